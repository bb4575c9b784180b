//! I/O benchmark (not a test): writes a 1M-point binary PLY cloud (as bsv writes it: double xyz,
//! palette colours, labels), the same cloud the way RealSense/Open3D tools write it (float xyz + uchar
//! rgb), and a ~100k-triangle labelled mesh, then times reading and writing them (median of 5, warm
//! page cache) and prints MB/s. Rows `parse` (decoding bytes already in memory) and `fsread` (just
//! reading the file into memory) split the read time into decoding and disk/page-cache copying. `benchmarks/io_bench.py` runs it and compares with trimesh and Open3D.
//!
//! Usage: `cargo run --release -p bsv-core --example io_bench -- [--out DIR] [--json FILE] [--runs N]`

use std::path::{Path, PathBuf};
use std::time::Instant;

use bsv_core::io::{read_mesh, read_point_cloud, write_mesh, write_point_cloud};
use bsv_core::shapes::subdivided_cuboid;
use bsv_core::{PointCloud, TriMesh};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let out = f();
        times.push(t.elapsed().as_secs_f64());
        last = Some(out);
    }
    (median(times), last.expect("at least one run"))
}

/// A deterministic 1M-point body-sized cloud with labels.
fn cloud(n: usize) -> PointCloud {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<[f64; 3]> = (0..n).map(|_| [rnd() * 0.6 - 0.3, rnd() * 1.8, rnd() * 0.3 - 0.15]).collect();
    let labels = points.iter().map(|p| (1 + (p[1] / 1.8 * 14.0) as u8).min(14)).collect();
    PointCloud { points, normals: None, colors: None, labels: Some(labels) }
}

/// The same points the way RealSense / Open3D write clouds: float x, y, z and uchar red, green, blue.
fn write_float_cloud(path: &Path, c: &PointCloud) -> std::io::Result<()> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment float cloud for the io benchmark\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        c.len()
    );
    let mut buf = Vec::with_capacity(header.len() + 15 * c.len());
    buf.extend_from_slice(header.as_bytes());
    for (i, p) in c.points.iter().enumerate() {
        for v in p {
            buf.extend_from_slice(&(*v as f32).to_le_bytes());
        }
        buf.extend_from_slice(&[(i % 251) as u8, 128, 64]);
    }
    std::fs::write(path, buf)
}

fn mesh() -> TriMesh {
    let mut m = subdivided_cuboid([0.5, 1.7, 0.3], 92);
    m.vertex_labels = Some(m.vertices.iter().map(|p| if p[1] > 0.0 { 2 } else { 9 }).collect());
    m
}

struct Row {
    name: &'static str,
    op: &'static str,
    path: PathBuf,
    bytes: u64,
    seconds: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut out = std::env::temp_dir().join("bsv_io_bench");
    let mut json: Option<PathBuf> = None;
    let mut runs = 5usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a directory")?),
            "--json" => json = Some(PathBuf::from(args.next().ok_or("--json needs a file")?)),
            "--runs" => runs = args.next().ok_or("--runs needs a number")?.parse()?,
            "-h" | "--help" => {
                println!("io_bench [--out DIR] [--json FILE] [--runs N]: PLY read/write throughput of bsv-core");
                return Ok(());
            }
            other => return Err(format!("unknown argument {other:?}; see --help").into()),
        }
    }
    std::fs::create_dir_all(&out)?;
    let runs = runs.max(1);
    let c = cloud(1_000_000);
    let m = mesh();
    let cloud_path = out.join("cloud_1m.ply");
    let float_path = out.join("cloud_1m_float.ply");
    let mesh_path = out.join("mesh_100k.ply");
    write_float_cloud(&float_path, &c)?;

    let size = |p: &Path| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
    let mut rows = Vec::new();
    let (t, r) = time(runs, || write_point_cloud(&cloud_path, &c));
    r?;
    rows.push(Row { name: "cloud_1m", op: "write", path: cloud_path.clone(), bytes: size(&cloud_path), seconds: t });
    let (t, r) = time(runs, || read_point_cloud(&cloud_path));
    let back = r?;
    assert_eq!(back.points, c.points, "round trip must be exact");
    rows.push(Row { name: "cloud_1m", op: "read", path: cloud_path.clone(), bytes: size(&cloud_path), seconds: t });
    let bytes = std::fs::read(&cloud_path)?;
    let (t, r) = time(runs, || bsv_core::io::ply::parse_cloud(&bytes));
    assert_eq!(r?.len(), c.len());
    rows.push(Row { name: "cloud_1m", op: "parse", path: cloud_path.clone(), bytes: size(&cloud_path), seconds: t });
    let (t, r) = time(runs, || std::fs::read(&cloud_path));
    r?;
    rows.push(Row { name: "cloud_1m", op: "fsread", path: cloud_path.clone(), bytes: size(&cloud_path), seconds: t });
    let (t, r) = time(runs, || read_point_cloud(&float_path));
    assert_eq!(r?.len(), c.len());
    rows.push(Row {
        name: "cloud_1m_float",
        op: "read",
        path: float_path.clone(),
        bytes: size(&float_path),
        seconds: t,
    });
    let (t, r) = time(runs, || write_mesh(&mesh_path, &m));
    r?;
    rows.push(Row { name: "mesh_100k", op: "write", path: mesh_path.clone(), bytes: size(&mesh_path), seconds: t });
    let (t, r) = time(runs, || read_mesh(&mesh_path));
    assert_eq!(r?, m, "round trip must be exact");
    rows.push(Row { name: "mesh_100k", op: "read", path: mesh_path.clone(), bytes: size(&mesh_path), seconds: t });

    println!(
        "bsv-core PLY I/O, median of {runs} (warm page cache, {} rayon threads); mesh: {} vertices, {} triangles",
        rayon::current_num_threads(),
        m.n_vertices(),
        m.n_triangles()
    );
    println!("{:<16} {:<6} {:>10} {:>10} {:>10}", "file", "op", "MB", "ms", "MB/s");
    let mut entries = Vec::new();
    for r in &rows {
        let mb = r.bytes as f64 / 1e6;
        println!("{:<16} {:<6} {:>10.2} {:>10.2} {:>10.0}", r.name, r.op, mb, r.seconds * 1e3, mb / r.seconds);
        entries.push(serde_json::json!({
            "file": r.name, "op": r.op, "path": r.path, "bytes": r.bytes, "seconds": r.seconds,
            "mb_per_s": mb / r.seconds,
        }));
    }
    if let Some(j) = json {
        let doc = serde_json::json!({
            "runs": runs, "threads": rayon::current_num_threads(),
            "mesh_vertices": m.n_vertices(), "mesh_triangles": m.n_triangles(), "results": entries,
        });
        std::fs::write(&j, serde_json::to_string_pretty(&doc)?)?;
    }
    Ok(())
}
