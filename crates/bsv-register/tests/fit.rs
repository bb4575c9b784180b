//! Known deformations with full clouds: the fit must land on the true surface and keep the volume.

mod common;
use bsv_core::shapes::{capsule, ellipsoid, icosphere};
use bsv_register::{EnergyParams, PrealignMode, PrealignParams, RegisterParams};
use common::*;

#[test]
fn template_registered_to_itself_stays_put() {
    let template = icosphere(0.25, 4);
    let cloud = cloud_of(&template, 100_000, 1);
    // The surface correction moves vertices off the sampled surface by design (h^2 H / 8,
    // ~0.1 mm here): this test checks that the fit itself stays put. With the paper's schedule (m2p
    // last: each vertex's nearest sample is the vertex itself) it does to 0.1 mm; the default's p2m
    // tail moves a vertex to the mean of its samples, which lie on the flat faces around it, lifted by
    // the curvature correction that assumes a smooth surface: 0.15 mm at most here.
    for (schedule, limit_mm) in [("m2p:5,p2m:5,m2p:10", 0.1), (bsv_register::DEFAULT_SCHEDULE, 0.2)] {
        let params = RegisterParams {
            surface_correction: false,
            schedule: bsv_register::Schedule::parse(schedule).expect("a valid schedule"),
            ..Default::default()
        };
        let reg = run(&template, &cloud, &params);
        let max = template
            .vertices
            .iter()
            .zip(&reg.mesh.vertices)
            .map(|(a, b)| bsv_core::geometry::dist2(*a, *b).sqrt())
            .fold(0.0, f64::max);
        println!(
            "self-registration ({schedule}): max vertex displacement {:.4} mm, prealign {:?}",
            max * 1e3,
            reg.prealign
        );
        assert!(max * 1e3 < limit_mm, "{schedule}: max displacement {:.4} mm", max * 1e3);
    }
}

#[test]
fn sphere_to_ellipsoid_stretched_15_percent() {
    // The cloud samples a much finer mesh than the template, so it is (nearly) the smooth surface;
    // the reference volume is the template mapped exactly onto that surface (what a perfect fit
    // with this template's resolution would give).
    let template = icosphere(0.2, 4);
    let radii = [0.23, 0.2, 0.2];
    let cloud = cloud_of(&ellipsoid(radii, 6), 100_000, 2);
    let mut ideal = template.clone();
    for p in &mut ideal.vertices {
        p[0] *= 1.15;
    }
    let params = RegisterParams {
        prealignment: PrealignParams { prealign: PrealignMode::Isotropic, ..Default::default() },
        ..Default::default()
    };
    let reg = run(&template, &cloud, &params);
    let max = reg.mesh.vertices.iter().map(|&p| ellipsoid_distance(p, radii)).fold(0.0, f64::max);
    let err = rel_pct(volume(&reg.mesh), volume(&ideal));
    let analytic = 4.0 / 3.0 * std::f64::consts::PI * radii.iter().product::<f64>();
    println!(
        "ellipsoid: max vertex error {:.3} mm, volume error {:.3} % (vs analytic {:.3} %)",
        max * 1e3,
        err,
        rel_pct(volume(&reg.mesh), analytic)
    );
    assert!(max < 2e-3, "max vertex error {:.3} mm", max * 1e3);
    assert!(err.abs() < 0.5);
}

#[test]
fn straight_capsule_to_bent_capsule() {
    // Bend a 0.4 m capsule (r = 6 cm) along an arc of radius 1 m (23 degrees); the reference is the
    // template bent analytically (vertices exactly on the true surface).
    let (r, length, radius) = (0.06, 0.4, 1.0);
    let template = capsule(r, length, 48, 12, 24);
    let mut ideal = template.clone();
    let mut truth = capsule(r, length, 128, 32, 96);
    for p in ideal.vertices.iter_mut().chain(truth.vertices.iter_mut()) {
        *p = bend(*p, radius, length);
    }
    let cloud = cloud_of(&truth, 100_000, 3);
    // A pose change, not a change of proportions: the paper's isotropic pre-alignment.
    // Bending stretches the outer side and compresses the inner one: vertices need the p2m
    // tangential (Lloyd) pull to spread evenly again (with 0: -0.57 % volume, same surface error).
    let params = RegisterParams {
        prealignment: PrealignParams { prealign: PrealignMode::Isotropic, ..Default::default() },
        energy: EnergyParams { tangential_weight_p2m: 1.0, ..Default::default() },
        ..Default::default()
    };
    let reg = run(&template, &cloud, &params);
    let max = reg.mesh.vertices.iter().map(|&p| bent_capsule_distance(p, r, length, radius)).fold(0.0, f64::max);
    let err = rel_pct(volume(&reg.mesh), volume(&ideal));
    println!("bent capsule: max vertex error {:.3} mm, volume error {:.3} %", max * 1e3, err);
    // The bound was 2 mm with the paper's schedule; the default's p2m tail leaves the worst vertex at
    // 2.3 mm, the volume within 0.07 %.
    assert!(max < 2.5e-3, "max vertex error {:.3} mm", max * 1e3);
    assert!(err.abs() < 0.5);
}

#[test]
fn template_rescaled_per_axis() {
    let template = ellipsoid([0.12, 0.3, 0.09], 4);
    let s = [1.2, 0.85, 1.1];
    let mut truth = template.clone();
    for p in &mut truth.vertices {
        *p = [p[0] * s[0] + 0.1, p[1] * s[1] + 1.0, p[2] * s[2] - 0.05];
    }
    let cloud = cloud_of(&truth, 100_000, 4);
    for mode in [PrealignMode::PerAxis, PrealignMode::Isotropic] {
        let params = RegisterParams {
            prealignment: PrealignParams { prealign: mode, ..Default::default() },
            ..Default::default()
        };
        let reg = run(&template, &cloud, &params);
        let radii = [0.12 * s[0], 0.3 * s[1], 0.09 * s[2]];
        let max_surface = reg
            .mesh
            .vertices
            .iter()
            .map(|&p| ellipsoid_distance([p[0] - 0.1, p[1] - 1.0, p[2] + 0.05], radii))
            .fold(0.0, f64::max);
        let max_vertex = reg
            .mesh
            .vertices
            .iter()
            .zip(&truth.vertices)
            .map(|(a, b)| bsv_core::geometry::dist2(*a, *b).sqrt())
            .fold(0.0, f64::max);
        let v = volume(&reg.mesh);
        let vt = volume(&truth);
        println!(
            "per-axis {:?} (used {:?}): max surface error {:.3} mm, max vertex error {:.3} mm, volume {:.3} %",
            mode,
            reg.prealign.mode,
            max_surface * 1e3,
            max_vertex * 1e3,
            rel_pct(v, vt)
        );
        assert!(max_surface < 2e-3);
        if mode == PrealignMode::PerAxis {
            assert_eq!(reg.prealign.mode, PrealignMode::PerAxis);
            assert!(max_vertex < 2e-3, "corresponding-vertex error {:.3} mm", max_vertex * 1e3);
        }
        assert!(rel_pct(v, vt).abs() < 0.5);
    }
}
