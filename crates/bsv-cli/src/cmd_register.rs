//! `bsv-cli register`: fit the template to a cloud, write the fitted mesh, report volumes.

use crate::output::{check_outputs, write_json, CliError, Output};
use bsv_core::template::{template, TemplateKind};
use bsv_core::{io, TriMesh};
use bsv_register::{
    register, ControlFlow, ImplausibleError, InputError, IterationLog, LabelSource, PrealignMode, RegisterError,
    RegisterParams, Registration, Schedule,
};
use bsv_volume::{report_with, SegmentOptions};
use std::path::PathBuf;

/// Arguments of `register`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The point cloud (PLY, metres, world frame), ideally labelled (`label` = segment id).
    cloud: PathBuf,
    /// Template mesh (PLY/OBJ, closed, labelled). Default: the embedded template (see --template-kind).
    template: Option<PathBuf>,
    /// Embedded template used when TEMPLATE is not given: default, fine, full, or female / male (the
    /// default mesh at MakeHuman's female or male end: the torso and thighs of that sex fit better).
    #[arg(long, default_value = "default", value_parser = TemplateKind::NAMES)]
    template_kind: String,
    /// Write the fitted mesh here (PLY with labels and palette colours, or OBJ with segment groups).
    #[arg(short, long, value_name = "FITTED")]
    output: Option<PathBuf>,
    /// Write the volumes JSON (with a "registration" section) here.
    #[arg(long, value_name = "OUT")]
    json: Option<PathBuf>,
    /// Correspondence schedule: comma-separated kind:iterations, kind = m2p (mesh to points) or p2m.
    #[arg(long, default_value = bsv_register::DEFAULT_SCHEDULE)]
    schedule: String,
    /// End the schedule's last stage once an iteration moves the vertices by less than this RMS
    /// distance, mm (0 = run every iteration of the schedule); only a last stage of more than 3
    /// iterations ends early (the default schedule's 2-iteration p2m tail always runs).
    #[arg(long, value_name = "MM")]
    stop_motion_mm: Option<f64>,
    /// Regularization strength: how much a cell may leave its nearest rotation (0 = free affine cells).
    #[arg(long)]
    alpha: Option<f64>,
    /// Labels of the fitted mesh: from the nearest cloud point (paper) or the template's own.
    #[arg(long, value_parser = ["cloud", "template"])]
    labels: Option<String>,
    /// Pre-alignment scaling: isotropic (paper), per_axis, or auto.
    #[arg(long, value_parser = ["isotropic", "per_axis", "auto"])]
    prealign: Option<String>,
    /// Units of the cloud file: m (default) or mm (divided by 1000 on reading).
    #[arg(long, default_value = "m", value_parser = ["m", "mm"])]
    units: String,
    /// The cloud's axis that points up (+x, -x, +y, -y, +z, -z): the cloud is rotated so that it
    /// becomes +y before the fit (the world frame: Y up, the subject facing +Z).
    #[arg(long, allow_hyphen_values = true, default_value = "+y", value_parser = ["+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"])]
    up: String,
    /// Do not refuse a cloud that does not look like a standing person in the world frame (flat,
    /// compact, not upright, not facing +Z, not of a person's size in metres).
    #[arg(long)]
    no_plausibility_check: bool,
    /// Keep head, hand and foot points (by default they are dropped, as in the paper).
    #[arg(long)]
    keep_extremities: bool,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Body density for the mass estimate, kg/m^3.
    #[arg(long, default_value_t = bsv_volume::DEFAULT_DENSITY_KG_M3)]
    density: f64,
    /// Print the time breakdown (setup, per iteration: correspondences, local step, solve).
    #[arg(long)]
    timings: bool,
    /// Do not print one line per iteration.
    #[arg(short, long)]
    quiet: bool,
    /// Overwrite outputs that exist.
    #[arg(long)]
    force: bool,
}

fn params_from(a: &Args, cloud_labelled: bool) -> Result<RegisterParams, CliError> {
    let schedule = a.schedule.parse::<Schedule>().map_err(|e| with_flags(&RegisterError::from(e)))?;
    let mut p = RegisterParams { schedule, threads: a.threads, ..Default::default() };
    p.outliers.drop_extremities = !a.keep_extremities;
    p.checks.check_plausible = !a.no_plausibility_check;
    if let Some(alpha) = a.alpha {
        p.energy.alpha = alpha;
    }
    if let Some(mm) = a.stop_motion_mm {
        p.stop_motion_mm = mm;
    }
    p.labels = match a.labels.as_deref() {
        Some("template") => LabelSource::Template,
        Some(_) => LabelSource::Cloud,
        None if cloud_labelled => LabelSource::Cloud,
        None => LabelSource::Template,
    };
    if let Some(mode) = a.prealign.as_deref() {
        p.prealignment.prealign = match mode {
            "isotropic" => PrealignMode::Isotropic,
            "per_axis" => PrealignMode::PerAxis,
            _ => PrealignMode::Auto,
        };
    }
    Ok(p)
}

/// The `bsv-cli register` flag that sets a registration parameter, where there is one.
fn flag_of(parameter: &str) -> Option<&'static str> {
    Some(match parameter {
        "alpha" => "--alpha",
        "schedule" => "--schedule",
        "stop_motion_mm" => "--stop-motion-mm",
        "labels" => "--labels",
        "prealign" => "--prealign",
        "threads" => "--threads",
        "drop_extremities" => "--keep-extremities",
        "check_plausible" => "--no-plausibility-check",
        _ => return None,
    })
}

/// The error's message with the flags of this command that carry out its remedy.
fn with_flags(e: &RegisterError) -> String {
    let mut flags: Vec<&str> = e.parameters().iter().filter_map(|p| flag_of(p)).collect();
    let up;
    match e {
        RegisterError::Input(InputError::CloudLooksLikeMillimetres { .. })
        | RegisterError::Implausible(ImplausibleError::Size { .. }) => flags.insert(0, "--units mm"),
        RegisterError::Implausible(ImplausibleError::WrongUp { up: axis, .. }) => {
            up = format!(
                "--up {}",
                if axis.len() == 1 { format!("+{axis} or --up -{axis}") } else { (*axis).to_string() }
            );
            flags.insert(0, &up);
        }
        _ => {}
    }
    if flags.is_empty() {
        e.to_string()
    } else {
        format!("{e} (bsv-cli: {})", flags.join(", "))
    }
}

fn print_iteration(it: &IterationLog, timings: bool) {
    let p2m = it.rms_points_to_mesh_mm.map_or_else(String::new, |v| format!("  p->m {v:6.2} mm"));
    say_inline!(
        "  [{}:{:<3} {:>2}] m->p {:6.2} mm{p2m}  E {:.4e}  corr {:>6}  moved {:5.2} mm",
        it.stage,
        format!("{:?}", it.kind).to_lowercase(),
        it.iteration,
        it.rms_mesh_to_points_mm,
        it.energy.total,
        it.n_correspondences,
        it.motion_mm
    );
    if timings {
        let t = &it.timings;
        say_inline!("  ({:.1} + {:.1} + {:.1} ms)", t.correspond * 1e3, t.local * 1e3, t.solve * 1e3);
    }
    say!();
}

/// The lines after the fit: dropped extremities, time and distances (and the time split).
fn print_summary(reg: &Registration, timings: bool) {
    if reg.extremities_dropped > 0 {
        say!(
            "dropped {} head/hand/foot points (labels 1, 7, 8, 13, 14); --keep-extremities keeps them",
            reg.extremities_dropped
        );
    }
    let iter_secs: f64 = reg.log.iter().map(|l| l.timings.correspond + l.timings.local + l.timings.solve).sum();
    say!(
        "done in {:.3} s (setup {:.0} ms, {} iterations, {:.1} ms/iteration): RMS mesh->points {:.2} mm, points->mesh {:.2} mm",
        reg.total_seconds,
        reg.setup_seconds * 1e3,
        reg.log.len(),
        iter_secs * 1e3 / reg.log.len().max(1) as f64,
        reg.rms_mesh_to_points_mm,
        reg.rms_points_to_mesh_mm
    );
    for (name, q) in reg.quality.iter().filter(|(_, q)| q.doubtful) {
        say!(
            "warning: the fit of {name} is doubtful (RMS {:.1} mm, covered {:.0} %, seen but uncovered {:.0} %, folded {:.0} %): check its cloud before using its volume",
            q.rms_mm,
            q.coverage * 100.0,
            q.exposed_uncovered * 100.0,
            q.folded * 100.0
        );
    }
    if timings {
        let sum = |f: fn(&IterationLog) -> f64| reg.log.iter().map(f).sum::<f64>() * 1e3;
        say!(
            "time split: setup {:.1} ms, correspondences {:.1} ms, local {:.1} ms, solve {:.1} ms",
            reg.setup_seconds * 1e3,
            sum(|l| l.timings.correspond),
            sum(|l| l.timings.local),
            sum(|l| l.timings.solve)
        );
    }
}

/// The template (TEMPLATE, or the embedded one of --template-kind) and how to name it.
fn read_template(a: &Args) -> Result<(TriMesh, String), CliError> {
    Ok(match &a.template {
        Some(p) => (io::read_mesh(p)?, p.display().to_string()),
        None => {
            let kind = TemplateKind::parse(&a.template_kind).unwrap_or_default();
            (template(kind)?, format!("embedded {kind:?} template"))
        }
    })
}

/// Rotates `cloud` so that its axis `up` (`+x`, `-x`, `+y`, `-y`, `+z`, `-z`; no sign = +) becomes
/// +y: a quarter turn about z (x up) or x (z up), or a half turn about x (-y up); normals follow.
fn turn_up(cloud: &mut bsv_core::PointCloud, up: &str) {
    let f: fn([f64; 3]) -> [f64; 3] = match up {
        "+x" | "x" => |[x, y, z]| [-y, x, z],
        "-x" => |[x, y, z]| [y, -x, z],
        "-y" => |[x, y, z]| [x, -y, -z],
        "+z" | "z" => |[x, y, z]| [x, z, -y],
        "-z" => |[x, y, z]| [x, -z, y],
        _ => return,
    };
    cloud.points.iter_mut().for_each(|p| *p = f(*p));
    if let Some(n) = &mut cloud.normals {
        n.iter_mut().for_each(|p| *p = f(*p));
    }
}

/// Runs `register`.
pub fn run(a: Args) -> Result<(), CliError> {
    let outputs: Vec<Output<'_>> = (a.output.iter().map(|p| Output::file("--output", p)))
        .chain(a.json.iter().map(|p| Output::file("--json", p)))
        .collect();
    check_outputs(&outputs, a.force)?;
    let mut cloud = io::read_point_cloud(&a.cloud)?;
    if a.units == "mm" {
        cloud.points.iter_mut().for_each(|p| *p = p.map(|v| v / 1000.0));
    }
    turn_up(&mut cloud, &a.up);
    let labelled = cloud.labels.as_ref().is_some_and(|l| l.iter().any(|&v| v != 0));
    if !labelled {
        say!("the cloud has no segment labels: volumes come from the template's labels");
        cloud.labels = None;
    }
    let (tmpl, tmpl_name) = read_template(&a)?;
    let params = params_from(&a, labelled)?;
    say!(
        "registering {} ({} points) with {tmpl_name} ({} vertices), schedule {}",
        a.cloud.display(),
        cloud.len(),
        tmpl.n_vertices(),
        params.schedule
    );
    let quiet = a.quiet;
    let timings = a.timings;
    let reg = register(&tmpl, &cloud, &params, &mut |it| {
        if !quiet {
            print_iteration(it, timings);
        }
        ControlFlow::Continue(())
    })
    .map_err(|e| format!("{}: {}", a.cloud.display(), with_flags(&e)))?;
    print_summary(&reg, timings);
    let opts = SegmentOptions::fitted();
    let mut report = report_with(&reg.mesh, a.density, &opts)?;
    let mut summary = serde_json::to_value(&reg)?;
    if let Some(obj) = summary.as_object_mut() {
        obj.insert("iterations".into(), reg.log.len().into());
        obj.insert("seconds".into(), reg.total_seconds.into());
        obj.insert("template".into(), tmpl_name.into());
        obj.insert("cloud".into(), a.cloud.display().to_string().into());
        obj.insert("params".into(), serde_json::to_value(&params)?);
    }
    report.registration = Some(summary);
    say!();
    say_inline!("{report}");
    if let Some(out) = &a.output {
        io::write_mesh(out, &reg.mesh)?;
        say!("fitted mesh written to {}", out.display());
    }
    if let Some(out) = &a.json {
        write_json(out, &serde_json::to_value(&report)?)?;
        say!("volumes written to {}", out.display());
    }
    Ok(())
}
