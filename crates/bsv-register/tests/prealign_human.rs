//! The automatic pre-alignment of a labelled human template is isotropic (the paper's): trails of
//! flying pixels behind the silhouettes stretch a body cloud's depth, and a box comparison would
//! then scale the template 1.5 times in depth (`PrealignParams::for_template`). A box keeps Auto.
#![allow(clippy::unwrap_used)]

use bsv_capture::sample::sample_surface;
use bsv_core::template::{template, TemplateKind};
use bsv_core::{shapes, PointCloud};
use bsv_register::{register, ControlFlow, PrealignMode, RegisterParams};

/// A labelled cloud of the default template's surface with trails of points every centimetre up to
/// 30 cm behind 1 % of its points along the depth axis, as a depth camera's silhouette pixels leave.
fn person_with_trails() -> PointCloud {
    let t = template(TemplateKind::Default).unwrap();
    let (mut points, faces) = sample_surface(&t, 20_000, 7);
    let vl = t.vertex_labels.clone().unwrap();
    let mut labels: Vec<u8> = faces.iter().map(|&f| vl[t.triangles[f as usize][0] as usize]).collect();
    let n = points.len();
    for i in (0..n).step_by(100) {
        let p = points[i];
        for k in 1..=30 {
            points.push([p[0], p[1], p[2] + 0.01 * k as f64 * p[2].signum()]);
            labels.push(labels[i]);
        }
    }
    let mut c = PointCloud::new(points);
    c.labels = Some(labels);
    c
}

fn fit_mode(template: &bsv_core::TriMesh, cloud: &PointCloud) -> (PrealignMode, [f64; 3]) {
    let mut params = RegisterParams { schedule: bsv_register::Schedule::parse("m2p:1").unwrap(), ..Default::default() };
    params.outliers.ray_parallel_max_cos = 0.0; // keep the trails: the box sees them
    params.outliers.outlier_voxel_m = 0.0;
    params.outliers.detached_voxel_m = 0.0;
    let mut sink = |_: &bsv_register::IterationLog| ControlFlow::Continue(());
    let reg = register(template, cloud, &params, &mut sink).unwrap();
    (reg.prealign.mode, reg.prealign.scale)
}

#[test]
fn a_human_template_is_scaled_isotropically_whatever_the_depth_trails() {
    let t = template(TemplateKind::Default).unwrap();
    let (mode, scale) = fit_mode(&t, &person_with_trails());
    assert_eq!(mode, PrealignMode::Isotropic, "scale {scale:?}");
    assert!((scale[2] / scale[1] - 1.0).abs() < 1e-12);
}

#[test]
fn a_box_template_keeps_the_automatic_per_axis_scaling() {
    // A unit cube template and a 1.04 x 0.2 x 0.2 m box (the paper's box A): per-axis.
    let cube = shapes::subdivided_cuboid([1.0, 1.0, 1.0], 6);
    let target = shapes::subdivided_cuboid([0.2, 1.04, 0.2], 12);
    let (points, _) = sample_surface(&target, 20_000, 3);
    let (mode, _) = fit_mode(&cube, &PointCloud::new(points));
    assert_eq!(mode, PrealignMode::PerAxis);
}
