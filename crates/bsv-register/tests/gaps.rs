//! Front/back clouds with lateral gaps: boxes of the paper's sizes at 45 degrees and a torso-like
//! ellipsoid; an alpha sweep on the gap torso (the issue expected alpha = 0 to degrade; in this
//! engine it does not, see `alpha_sweep_on_the_gap_torso` and the table in benchmarks/BENCH.md, section Registration).

mod common;
use bsv_core::shapes::{ellipsoid, rotate_y, subdivided_cuboid};
use bsv_core::TriMesh;
use bsv_register::{EnergyParams, RegisterParams};
use common::*;

/// Registers `template` to the gappy sampling of `truth` and returns the volume error in percent.
fn gap_case(name: &str, template: &TriMesh, truth: &TriMesh, params: &RegisterParams, band: f64) -> f64 {
    let before = 100_000;
    let cloud = gappy_cloud(truth, band);
    let reg = run(template, &cloud, params);
    let err = rel_pct(volume(&reg.mesh), volume(truth));
    println!(
        "{name}: alpha {:e}: {} of {} points kept, prealign {:?} {:?} yaw {:.2} deg, volume error {:.3} %, rms m2p {:.2} mm p2m {:.2} mm",
        params.energy.alpha,
        cloud.len(),
        before,
        reg.prealign.mode,
        reg.prealign.scale,
        reg.prealign.yaw_deg,
        err,
        reg.rms_mesh_to_points_mm,
        reg.rms_points_to_mesh_mm
    );
    err
}

/// 100k samples of `truth` without the sides no front/back camera sees (normals within ~32
/// degrees of +-x) and without the outer `band` of each lateral half (|x - centre| > (1 - band)
/// x the half-width: for a box at 45 degrees, whose four faces both cameras see at 45 degrees,
/// this removes the two side corners).
fn gappy_cloud(truth: &TriMesh, band: f64) -> bsv_core::PointCloud {
    let mut cloud = cloud_of(truth, 100_000, 11);
    drop_sides(&mut cloud, 0.85);
    let (lo, hi) = cloud.points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[0]), b.max(p[0])));
    let (c, h) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
    let pts = cloud.points.clone();
    cloud.retain_indices(|i| (pts[i][0] - c).abs() <= (1.0 - band) * h);
    cloud
}

/// Lateral band removed from the 45-degree boxes.
const BOX_BAND: f64 = 0.1;

fn box_at_45(size: [f64; 3]) -> TriMesh {
    let mut b = subdivided_cuboid(size, 24);
    rotate_y(&mut b, std::f64::consts::FRAC_PI_4);
    b
}

#[test]
fn paper_boxes_at_45_degrees() {
    // An AXIS-ALIGNED cube template: the pre-alignment's yaw search turns it onto the boxes
    // (without it, box A reaches only 2.5 %: the cube must fold its corners onto the box faces).
    let template = subdivided_cuboid([1.0, 1.0, 1.0], 12);
    // Paper sizes; the second box stands 1.038 m tall.
    for (name, size) in [("box A", [0.558, 0.520, 0.589]), ("box B", [0.208, 1.038, 0.204])] {
        let truth = box_at_45(size);
        let params = RegisterParams::default();
        let err = gap_case(name, &template, &truth, &params, BOX_BAND);
        let yaw = run(&template, &gappy_cloud(&truth, BOX_BAND), &params).prealign.yaw_deg;
        // Any multiple of 90 degrees from 45 fits a box.
        let off = (yaw - 45.0).rem_euclid(90.0);
        assert!(off.min(90.0 - off) < 2.0, "{name}: yaw {yaw:.2} deg, expected 45 (mod 90)");
        assert!(err.abs() < 1.0, "{name}: volume error {err:.3} %");
    }
}

#[test]
fn torso_ellipsoid_with_gaps() {
    let template = ellipsoid([0.15, 0.28, 0.11], 4);
    let truth = ellipsoid([0.17, 0.30, 0.12], 6);
    let good = gap_case("torso", &template, &truth, &RegisterParams::default(), 0.0);
    assert!(good.abs() < 1.0, "torso: volume error {good:.3} %");
    // alpha = 0 (free affine cells): with the point-to-plane data term of the defaults the cells
    // have nothing pulling them together, and the result stays close; the numbers are printed.
    let free = gap_case(
        "torso",
        &template,
        &truth,
        &RegisterParams { energy: EnergyParams { alpha: 0.0, ..Default::default() }, ..Default::default() },
        0.0,
    );
    assert!(free.is_finite());
}

/// The issue asked for "alpha = 0 degrades measurably on the gap case". Measured here it does not,
/// in any data-term mode (point-to-plane default, the paper's point-to-point, with or without the
/// p2m Lloyd pull, data weights 1 / 0.1 / 0.01, 85 % or 50 % side limits): with free affine cells
/// the ARAP term is still an affine-invariant Laplacian smoothness term and m2p gives every vertex
/// a target, so nothing collapses; the regularization only adds stiffness, and a stiffer fit
/// shrinks the gap sides more. This test pins that behaviour (no collapse at alpha = 0, and the
/// practically rigid-cell alpha = 1e8 measurably more biased than alpha = 0 in point-to-point
/// mode) and prints the table of benchmarks/BENCH.md, section Registration.
#[test]
fn alpha_sweep_on_the_gap_torso() {
    let template = ellipsoid([0.15, 0.28, 0.11], 4);
    let radii = [0.17, 0.30, 0.12];
    let truth = ellipsoid(radii, 6);
    let cloud = gappy_cloud(&truth, 0.0);
    let mut p2p = Vec::new();
    for (mode, tw) in [("point-to-plane", 0.0), ("point-to-point", 1.0)] {
        for alpha in [0.0, 1e4, 1e6, 1e8] {
            let params = RegisterParams {
                energy: EnergyParams { alpha, tangential_weight: tw, ..Default::default() },
                ..Default::default()
            };
            let reg = run(&template, &cloud, &params);
            let err = rel_pct(volume(&reg.mesh), volume(&truth));
            let max = reg.mesh.vertices.iter().map(|&p| ellipsoid_distance(p, radii)).fold(0.0, f64::max);
            println!(
                "| {mode} | {alpha:.0e} | {err:+.3} % | {:.2} mm | {:.2} mm | {:.1} mm |",
                reg.rms_mesh_to_points_mm,
                reg.rms_points_to_mesh_mm,
                max * 1e3
            );
            // No collapse at any alpha.
            assert!(err.abs() < 2.0 && max < 0.02, "{mode} alpha {alpha:e}: {err:.3} %, max {:.1} mm", max * 1e3);
            if tw == 1.0 {
                p2p.push(err);
            }
        }
    }
    assert!(p2p[3].abs() > p2p[0].abs() + 0.2, "point-to-point: alpha 1e8 {:.3} % vs alpha 0 {:.3} %", p2p[3], p2p[0]);
}
