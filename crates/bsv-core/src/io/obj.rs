//! Wavefront OBJ reader and writer with segment groups.
//!
//! Reader: `v x y z` (an optional `w` or vertex colour after x, y, z is ignored), `f` in every index
//! form (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative = relative to the vertices read so far), polygons
//! fan-triangulated, `g`/`o` lines whose name is a segment name (DESIGN.md ids; exact, else
//! case-insensitive) label the faces that follow. Unknown group names leave faces unlabelled (0) and are
//! listed in [`ObjReport::unknown_groups`]. `vt`, `vn`, `s`, `usemtl`, `mtllib` and comments are ignored;
//! other statements (`l`, `p`, curves) are counted in [`ObjReport::ignored_statements`].
//! Face labels are present when at least one group name is a segment name. When every face is labelled
//! (no 0), vertex labels are derived too ([`crate::labels::vertex_labels_from_faces`]: each vertex takes
//! the label most of its faces carry, ties going to the smaller id, unreferenced vertices 0).
//!
//! Writer: `v` lines with the shortest decimal that parses back to the same f64 (exact round trip),
//! then, for a labelled mesh, one `g <segment name>` group per segment present (ascending segment id,
//! `unlabelled` for id 0) holding that segment's `f` lines in their original relative order; so the
//! faces of a file read back come grouped by segment (the same triangles and labels, in that order),
//! and Blender, MeshLab or trimesh show one object part per segment. An unlabelled mesh keeps its face
//! order and has no group. A mesh with
//! vertex labels but no face labels gets face labels by majority of its three corners
//! ([`crate::labels::face_labels_from_vertices`]: when all three differ, the corner with the smallest
//! vertex index), since OBJ cannot store vertex labels.

use std::borrow::Cow;
use std::fmt::Write as _;

use serde::Serialize;
use thiserror::Error;

use super::validate::{self, AttributeError};
use crate::labels::{face_labels_from_vertices, vertex_labels_from_faces};
use crate::segment::Segment;
use crate::TriMesh;

/// What the reader noticed besides the mesh itself.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct ObjReport {
    /// Group/object names that are not segment names (faces under them are unlabelled), in order.
    pub unknown_groups: Vec<String>,
    /// Faces with more than three vertices that were fan-triangulated.
    pub polygons_triangulated: usize,
    /// Statements skipped because BSV does not use them (`l`, `p`, curves, unknown keywords).
    pub ignored_statements: usize,
    /// True when vertex labels were derived from face labels (every face labelled).
    pub vertex_labels_derived: bool,
}

/// Why OBJ text could not be read. Every message names the line and says what to do.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ObjError {
    /// Zero bytes.
    #[error("the file is empty (0 bytes); check the path, or export the mesh again")]
    Empty,
    /// No `v` line at all.
    #[error("the file has no `v` (vertex) lines; it is not an OBJ mesh — check the file, or export it again")]
    NoVertices,
    /// A malformed `v` line.
    #[error("line {line}: bad vertex: {message}; a vertex line is `v x y z` with numbers — fix the line")]
    BadVertex {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A NaN or infinite coordinate.
    #[error(
        "line {line}: vertex {vertex} has a non-finite coordinate ({value}); remove NaN/inf vertices and export again"
    )]
    NonFinite {
        /// 1-based line number.
        line: usize,
        /// 0-based vertex index.
        vertex: usize,
        /// The value read.
        value: f64,
    },
    /// A malformed `f` line.
    #[error("line {line}: bad face: {message}; a face line is `f i j k ...` with 1-based (or negative) vertex indices — fix the line")]
    BadFace {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A face with fewer than three vertices.
    #[error("line {line}: face has {n} vertices; faces need at least 3 — remove the line or export again")]
    FaceTooSmall {
        /// 1-based line number.
        line: usize,
        /// Vertices on the line.
        n: usize,
    },
    /// A face with more corners than any real polygon has (bounds the memory of one line).
    #[error("line {line}: face has more than {max} vertices; real polygons have a few dozen at most — the file is corrupt, export it again")]
    FaceTooLarge {
        /// 1-based line number.
        line: usize,
        /// The largest number of corners read for one face.
        max: usize,
    },
    /// A face index outside the vertex list.
    #[error("line {line}: face index {index} is out of range: the file has {vertex_count} vertices (valid 1..={vertex_count} or -1..=-{vertex_count} relative); the file is corrupt or truncated — export it again")]
    IndexOutOfRange {
        /// 1-based line number.
        line: usize,
        /// The index as written in the file.
        index: i64,
        /// Vertices available (read so far for relative indices, in the file for absolute ones).
        vertex_count: usize,
    },
}

/// The segment a group/object name designates: exact name, else case-insensitive.
fn segment_of(name: &str) -> Option<Segment> {
    Segment::from_name(name).or_else(|| Segment::from_name(&name.to_ascii_lowercase()))
}

fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, Cow<'_, str>)> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, raw)| {
        let raw = raw.split(|&b| b == b'#').next().unwrap_or(&[]);
        (i + 1, String::from_utf8_lossy(raw))
    })
}

fn parse_vertex(
    line_no: usize,
    vertex: usize,
    mut words: std::str::SplitAsciiWhitespace<'_>,
) -> Result<[f64; 3], ObjError> {
    let mut p = [0.0; 3];
    for (k, c) in p.iter_mut().enumerate() {
        let w = words.next().ok_or_else(|| ObjError::BadVertex {
            line: line_no,
            message: format!("it has {k} coordinate(s), 3 are needed"),
        })?;
        let v: f64 =
            w.parse().map_err(|_| ObjError::BadVertex { line: line_no, message: format!("{w:?} is not a number") })?;
        if !v.is_finite() {
            return Err(ObjError::NonFinite { line: line_no, vertex, value: v });
        }
        *c = v;
    }
    Ok(p)
}

/// Reads only the `v` lines (for reading an OBJ as a point cloud).
pub fn parse_points(bytes: &[u8]) -> Result<Vec<[f64; 3]>, ObjError> {
    if bytes.is_empty() {
        return Err(ObjError::Empty);
    }
    let mut points = Vec::new();
    for (line_no, line) in lines(bytes) {
        let mut words = line.split_ascii_whitespace();
        if words.next() == Some("v") {
            points.push(parse_vertex(line_no, points.len(), words)?);
        }
    }
    if points.is_empty() {
        return Err(ObjError::NoVertices);
    }
    Ok(points)
}

/// Parses OBJ bytes into a triangle mesh with optional segment labels, and a report.
pub fn parse(bytes: &[u8]) -> Result<(TriMesh, ObjReport), ObjError> {
    if bytes.is_empty() {
        return Err(ObjError::Empty);
    }
    let mut state = ObjParser::default();
    for (line_no, line) in lines(bytes) {
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword {
            "v" => state.vertices.push(parse_vertex(line_no, state.vertices.len(), words)?),
            "f" => state.face(line_no, words)?,
            "g" | "o" => state.group(words),
            "vt" | "vn" | "vp" | "s" | "usemtl" | "mtllib" => {}
            _ => state.report.ignored_statements += 1,
        }
    }
    state.finish()
}

/// The most corners one `f` line may have: a bound on the work and memory of a single line (a corrupt
/// 100 MB face line would otherwise become tens of millions of fan triangles).
pub const MAX_FACE_CORNERS: usize = 1 << 16;

/// What [`parse`] accumulates line by line.
#[derive(Default)]
struct ObjParser {
    report: ObjReport,
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// One label per triangle: the segment of the group it was read under (0 outside segment groups).
    labels: Vec<u8>,
    any_segment_group: bool,
    current: u8,
    /// Absolute indices that pointed past the vertices read so far: checked at the end.
    forward: Vec<(usize, i64, u32)>,
    /// The current face's resolved indices (reused across lines).
    poly: Vec<u32>,
}

impl ObjParser {
    /// An `f` line: resolves its indices and fan-triangulates it under the current label.
    fn face(&mut self, line_no: usize, words: std::str::SplitAsciiWhitespace<'_>) -> Result<(), ObjError> {
        self.poly.clear();
        for w in words {
            if self.poly.len() == MAX_FACE_CORNERS {
                return Err(ObjError::FaceTooLarge { line: line_no, max: MAX_FACE_CORNERS });
            }
            let (i, resolved, r) = resolve_index(line_no, w, self.vertices.len())?;
            if resolved >= self.vertices.len() as i64 {
                self.forward.push((line_no, i, r));
            }
            self.poly.push(r);
        }
        let poly = &self.poly;
        if poly.len() < 3 {
            return Err(ObjError::FaceTooSmall { line: line_no, n: poly.len() });
        }
        if poly.len() > 3 {
            self.report.polygons_triangulated += 1;
        }
        for k in 1..poly.len() - 1 {
            self.triangles.push([poly[0], poly[k], poly[k + 1]]);
            self.labels.push(self.current);
        }
        Ok(())
    }

    /// A `g`/`o` line: the segment its names designate becomes the current label (else 0, and the
    /// name is recorded as unknown).
    fn group(&mut self, words: std::str::SplitAsciiWhitespace<'_>) {
        let names: Vec<&str> = words.collect();
        match names.iter().find_map(|n| segment_of(n)) {
            Some(s) => {
                self.current = s.id();
                self.any_segment_group = true;
            }
            None => {
                self.current = 0;
                let name = names.join(" ");
                if !name.is_empty() && name != "default" && !self.report.unknown_groups.contains(&name) {
                    self.report.unknown_groups.push(name);
                }
            }
        }
    }

    /// Checks forward references against the final vertex count and builds the mesh.
    fn finish(self) -> Result<(TriMesh, ObjReport), ObjError> {
        let ObjParser { mut report, vertices, triangles, labels, any_segment_group, forward, .. } = self;
        if vertices.is_empty() {
            return Err(ObjError::NoVertices);
        }
        if let Some(&(line, index, _)) = forward.iter().find(|f| f.2 as usize >= vertices.len()) {
            return Err(ObjError::IndexOutOfRange { line, index, vertex_count: vertices.len() });
        }
        let mut mesh = TriMesh::new(vertices, triangles);
        if any_segment_group {
            if !labels.is_empty() && labels.iter().all(|&l| l != 0) {
                mesh.vertex_labels = Some(vertex_labels_from_faces(mesh.n_vertices(), &mesh.triangles, &labels));
                report.vertex_labels_derived = true;
            }
            mesh.face_labels = Some(labels);
        }
        Ok((mesh, report))
    }
}

/// One face word (`v`, `v/vt`, `v//vn`, `v/vt/vn`) as `(index as written, resolved 0-based, as u32)`,
/// given the vertices read so far.
fn resolve_index(line_no: usize, w: &str, vertex_count: usize) -> Result<(i64, i64, u32), ObjError> {
    let head = w.split('/').next().unwrap_or("");
    let i: i64 = head.parse().map_err(|_| ObjError::BadFace {
        line: line_no,
        message: format!("{w:?} does not start with a vertex index"),
    })?;
    let n = vertex_count as i64;
    let resolved = match i {
        0 => return Err(ObjError::BadFace { line: line_no, message: "index 0 (OBJ indices start at 1)".into() }),
        i if i < 0 => {
            if n + i < 0 {
                return Err(ObjError::IndexOutOfRange { line: line_no, index: i, vertex_count });
            }
            n + i
        }
        i => i - 1,
    };
    let Ok(r) = u32::try_from(resolved) else {
        return Err(ObjError::IndexOutOfRange { line: line_no, index: i, vertex_count });
    };
    Ok((i, resolved, r))
}

/// Encodes a mesh as OBJ text (see the module docs for how labels become groups).
pub fn to_string(mesh: &TriMesh) -> Result<String, AttributeError> {
    let n = mesh.n_vertices();
    validate::length("vertex_labels", mesh.vertex_labels.as_deref(), n)?;
    validate::labels("vertex_labels", mesh.vertex_labels.as_deref())?;
    validate::length("face_labels", mesh.face_labels.as_deref(), mesh.n_triangles())?;
    validate::labels("face_labels", mesh.face_labels.as_deref())?;
    validate::finite(&mesh.vertices)?;
    validate::indices(&mesh.triangles, n)?;
    let mut s = String::with_capacity(n * 60 + mesh.n_triangles() * 30 + 64);
    let _ = writeln!(s, "# generated by bsv {}", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(s, "# {} vertices, {} triangles; groups are segment names", n, mesh.n_triangles());
    for p in &mesh.vertices {
        // `{:?}` is the shortest decimal that parses back to the same f64.
        let _ = writeln!(s, "v {:?} {:?} {:?}", p[0], p[1], p[2]);
    }
    let derived = match (&mesh.face_labels, &mesh.vertex_labels) {
        (None, Some(vl)) => Some(face_labels_from_vertices(&mesh.triangles, vl)),
        _ => None,
    };
    let face_labels = mesh.face_labels.as_ref().or(derived.as_ref());
    let mut order: Vec<usize> = (0..mesh.n_triangles()).collect();
    if let Some(fl) = face_labels {
        order.sort_by_key(|&t| fl[t]); // stable: original order within a segment
    }
    let mut group: Option<u8> = None;
    for t in order {
        if let Some(l) = face_labels.map(|fl| fl[t]) {
            if group != Some(l) {
                let name = Segment::from_id(l).unwrap_or(Segment::Unlabelled).name();
                let _ = writeln!(s, "g {name}");
                group = Some(l);
            }
        }
        let f = mesh.triangles[t];
        let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    Ok(s)
}
