//! Bad input gives typed errors, never a panic.

#![allow(clippy::unwrap_used)]
mod common;
use bsv_core::shapes::{cuboid, icosphere};
use bsv_core::{MeshInvariant, PointCloud};
use bsv_register::{
    prepare, register, register_in, ArticulationParams, ControlFlow, EnergyParams, InputError, IterationLog,
    LabelSource, NumericError, OutlierParams, ParameterError, RegisterError, RegisterParams, Registrar, ResourceError,
    Schedule, PARAMETER_NAMES,
};
use common::*;

fn try_register(t: &bsv_core::TriMesh, c: &PointCloud, p: &RegisterParams) -> Result<(), RegisterError> {
    let mut sink = |_: &IterationLog| ControlFlow::Continue(());
    register(t, c, p, &mut sink).map(|_| ())
}

#[test]
fn bad_inputs_are_typed_errors() {
    let template = icosphere(0.2, 3);
    let good = cloud_of(&template, 5_000, 1);
    let p = RegisterParams::default();

    let e = try_register(&template, &PointCloud::default(), &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::EmptyCloud { .. })), "{e}");

    let nan = PointCloud::new(vec![[f64::NAN; 3]; 1000]);
    let e = try_register(&template, &nan, &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::NonFinitePoint { index: 0, .. })), "{e}");

    let mut one_bad = good.clone();
    one_bad.points[17][1] = f64::INFINITY;
    let e = try_register(&template, &one_bad, &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::NonFinitePoint { index: 17, .. })), "{e}");

    let mut mm = good.clone();
    for q in &mut mm.points {
        *q = q.map(|v| v * 1000.0);
    }
    let e = try_register(&template, &mm, &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::CloudLooksLikeMillimetres { .. })), "{e}");
    assert!(e.to_string().contains("millimetres"));

    let tiny = PointCloud::new(good.points.iter().map(|q| q.map(|v| v * 1e-3)).collect());
    assert!(matches!(
        try_register(&template, &tiny, &p).unwrap_err(),
        RegisterError::Input(InputError::CloudTooSmall { .. })
    ));

    let few = PointCloud::new(good.points[..10].to_vec());
    assert!(matches!(
        try_register(&template, &few, &p).unwrap_err(),
        RegisterError::Input(InputError::TooFewPoints { n: 10, .. })
    ));

    // Non-manifold: a box with one face missing (open), and one with a duplicated face.
    let mut open = cuboid([0.3, 0.3, 0.3]);
    open.triangles.pop();
    let e = try_register(&open, &good, &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::NonManifoldTemplate { faces: 1, .. })), "{e}");
    let mut dup = cuboid([0.3, 0.3, 0.3]);
    dup.triangles.push(dup.triangles[0]);
    let e = try_register(&dup, &good, &p).unwrap_err();
    assert!(matches!(e, RegisterError::Input(InputError::NonManifoldTemplate { faces: 3, .. })), "{e}");

    let mut degenerate = template.clone();
    let [a, b, _] = degenerate.triangles[0];
    degenerate.vertices[b as usize] = degenerate.vertices[a as usize];
    assert!(matches!(
        try_register(&degenerate, &good, &p).unwrap_err(),
        RegisterError::Input(InputError::DegenerateTemplate { .. })
    ));

    let labels = RegisterParams { labels: LabelSource::Template, ..Default::default() };
    assert_eq!(
        try_register(&template, &good, &labels).unwrap_err(),
        RegisterError::Input(InputError::TemplateWithoutLabels)
    );

    assert!(matches!(Schedule::parse("m2p:5,p2x:3").unwrap_err(), ParameterError::BadSchedule { .. }));
    assert!(matches!(Schedule::parse("m2p5").unwrap_err(), ParameterError::BadSchedule { .. }));
    assert!(matches!(Schedule::parse("m2p:-1").unwrap_err(), ParameterError::BadSchedule { .. }));
    assert!(matches!(Schedule::parse("").unwrap_err(), ParameterError::BadSchedule { .. }));
    assert_eq!(Schedule::parse(" M2P:5, p2m:5 ,m2p:4, P2M:2").unwrap(), Schedule::default());

    let neg = RegisterParams { energy: EnergyParams { alpha: -1.0, ..Default::default() }, ..Default::default() };
    assert!(matches!(
        try_register(&template, &good, &neg).unwrap_err(),
        RegisterError::Parameter(ParameterError::BadParameter { name: "alpha", .. })
    ));
}

#[test]
fn hints_name_real_parameters() {
    let fields = serde_json::to_value(RegisterParams::default()).unwrap();
    let msgs = [
        NumericError::NoCorrespondences { iteration: 3 }.to_string(),
        NumericError::Diverged { iteration: 3 }.to_string(),
    ];
    for (msg, names) in
        msgs.iter().zip([&["prune_distance_factor", "prune_normal_angle_deg"][..], &["data_weight", "alpha"][..]])
    {
        assert!(!msg.contains("--prune") && !msg.contains("data weight"), "{msg}");
        for name in names {
            assert!(msg.contains(name), "{msg} lacks {name}");
            assert!(fields.get(name).is_some(), "{name} is not a RegisterParams field");
        }
    }
    assert!(NumericError::Index { reason: "x".into() }.to_string().contains("k-d tree"));
}

#[test]
fn a_far_finite_outlier_never_panics() {
    // One point 1e19 m away (finite, beyond any i64 voxel key) in a good cloud: with the default
    // sparse-point removal it is dropped and the fit succeeds; without it the registration still
    // returns (a fit or a typed error), never a panic.
    let template = icosphere(0.2, 3);
    let mut cloud = cloud_of(&icosphere(0.2, 5), 5_000, 1);
    cloud.points[123] = [1e19, 0.0, 0.0];
    cloud.normals = None;
    let reg = run(&template, &cloud, &RegisterParams::default());
    assert_eq!(reg.detached_removed + reg.outliers_removed, 1);
    assert!(reg.mesh.vertices.iter().all(|p| p.iter().all(|x| x.abs() < 1.0)));
    for far in [[1e19, 0.0, 0.0], [-1e300, 1e300, 0.0], [f64::MAX, 0.0, 0.0]] {
        cloud.points[123] = far;
        let p = RegisterParams {
            outliers: OutlierParams { outlier_voxel_m: 0.0, ..Default::default() },
            ..Default::default()
        };
        let _ = try_register(&template, &cloud, &p);
        let p = RegisterParams {
            outliers: OutlierParams { outlier_voxel_m: 1e-300, ..Default::default() },
            ..Default::default()
        };
        let _ = try_register(&template, &cloud, &p);
    }
}

#[test]
fn extremities_are_dropped_by_the_library() {
    let template = icosphere(0.2, 3);
    let mut cloud = cloud_of(&icosphere(0.2, 5), 5_000, 2);
    // Head (1) above y = 0.15, foot (13) below y = -0.15, trunk (2) between.
    let labels: Vec<u8> = cloud
        .points
        .iter()
        .map(|p| {
            if p[1] > 0.15 {
                1
            } else if p[1] < -0.15 {
                13
            } else {
                2
            }
        })
        .collect();
    let expected = labels.iter().filter(|&&l| l != 2).count();
    assert!(expected > 100);
    cloud.labels = Some(labels);
    let p = RegisterParams {
        articulation: ArticulationParams { articulate: false, ..Default::default() },
        ..Default::default()
    };
    let reg = run(&template, &cloud, &p);
    assert_eq!(reg.extremities_dropped, expected);
    let mut keep = p.clone();
    keep.outliers.drop_extremities = false;
    assert_eq!(run(&template, &cloud, &keep).extremities_dropped, 0);

    let mut all = cloud.clone();
    all.labels = Some(vec![7; all.points.len()]);
    let e = try_register(&template, &all, &p).unwrap_err();
    assert_eq!(e, RegisterError::Input(InputError::OnlyExtremities { n: 5_000 }));
    assert!(e.to_string().contains("head/hand/foot"), "{e}");
    let mut short = cloud.clone();
    short.labels = Some(vec![2; 10]);
    assert!(matches!(
        try_register(&template, &short, &p).unwrap_err(),
        RegisterError::Input(InputError::LengthMismatch { got: 10, .. })
    ));
}

#[test]
fn labels_come_from_the_cloud_or_the_template() {
    let mut template = icosphere(0.2, 3);
    template.vertex_labels = Some(template.vertices.iter().map(|p| if p[1] > 0.0 { 2 } else { 9 }).collect());
    let mut cloud = cloud_of(&icosphere(0.2, 5), 20_000, 3);
    cloud.labels = Some(cloud.points.iter().map(|p| if p[0] > 0.0 { 3 } else { 4 }).collect());
    let reg = run(&template, &cloud, &RegisterParams::default());
    let l = reg.mesh.vertex_labels.as_ref().unwrap();
    for (p, &lab) in reg.mesh.vertices.iter().zip(l) {
        if p[0].abs() > 0.01 {
            assert_eq!(lab, if p[0] > 0.0 { 3 } else { 4 });
        }
    }
    assert!(reg.mesh.face_labels.is_none());
    let reg = run(&template, &cloud, &RegisterParams { labels: LabelSource::Template, ..Default::default() });
    assert_eq!(reg.mesh.vertex_labels, template.vertex_labels);
}

#[test]
fn the_progress_callback_can_stop_the_fit() {
    let template = icosphere(0.2, 3);
    let cloud = cloud_of(&icosphere(0.2, 5), 5_000, 4);
    let mut seen = 0;
    let mut stop_after_three = |l: &IterationLog| {
        seen += 1;
        if l.iteration == 2 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let e = register(&template, &cloud, &RegisterParams::default(), &mut stop_after_three).unwrap_err();
    assert_eq!(e, RegisterError::Stopped { iteration: 2 });
    assert_eq!(seen, 3);
    assert_eq!(e.parameter(), None);
}

#[test]
fn the_stages_compose_to_register_in_the_callers_pool() {
    let template = icosphere(0.2, 3);
    let cloud = cloud_of(&icosphere(0.21, 5), 5_000, 6);
    let params = RegisterParams { threads: 1, ..Default::default() };
    let whole = run(&template, &cloud, &params);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut sink = |_: &IterationLog| ControlFlow::Continue(());
    let inside = register_in(&pool, &template, &cloud, &params, &mut sink).unwrap();
    assert_eq!(inside.mesh.vertices, whole.mesh.vertices);
    // By hand: prepare, build the registrar once, step to the end, finish.
    let prepared = prepare(&template, &cloud, &params).unwrap();
    assert_eq!(prepared.rest().len(), template.vertices.len());
    let mut fit = Registrar::new(&pool, prepared, &params).unwrap();
    let mut steps = 0;
    while let Some(entry) = fit.step().unwrap() {
        assert_eq!(entry.iteration, steps);
        steps += 1;
    }
    // The last stage may stop early on convergence (`stop_motion_mm`), as in the whole run.
    assert!(fit.is_done() && steps <= params.schedule.total_iterations() && fit.log().len() == steps);
    assert_eq!(steps, whole.log.len());
    let staged = fit.finish().unwrap();
    assert_eq!(staged.mesh.vertices, whole.mesh.vertices);
    assert_eq!(staged.rms_points_to_mesh_mm, whole.rms_points_to_mesh_mm);
}

#[test]
fn remedies_name_parameters_never_front_ends() {
    let names = PARAMETER_NAMES;
    let errors: Vec<RegisterError> = vec![
        InputError::EmptyCloud { min: 100 }.into(),
        InputError::OnlyExtremities { n: 5 }.into(),
        InputError::TooFewPoints { n: 5, min: 100 }.into(),
        InputError::NonFinitePoint { index: 0, point: [f64::NAN; 3] }.into(),
        InputError::CloudLooksLikeMillimetres { extent_m: 1800.0, limit_m: 5.0 }.into(),
        InputError::CloudTooSmall { extent_m: 0.001, limit_m: 0.05 }.into(),
        InputError::EmptyTemplate { vertices: 0, triangles: 0 }.into(),
        InputError::BadTriangleIndex(MeshInvariant::IndexOutOfRange { face: 0, index: 9, n_vertices: 4 }).into(),
        InputError::NonFiniteTemplateVertex { index: 0, point: [f64::NAN; 3] }.into(),
        InputError::NonManifoldTemplate { a: 0, b: 1, faces: 1, count: 3 }.into(),
        InputError::DegenerateTemplate { triangle: 0, count: 1 }.into(),
        InputError::TemplateWithoutLabels.into(),
        InputError::CloudWithoutLabels.into(),
        InputError::LengthMismatch { what: "cloud labels", got: 1, expected: 2 }.into(),
        ParameterError::BadSchedule { text: "x".into(), reason: "y".into() }.into(),
        ParameterError::BadParameter { name: "cell_weight", value: -1.0, hint: "must be > 0" }.into(),
        NumericError::NoCorrespondences { iteration: 1 }.into(),
        NumericError::Solver { reason: "x".into() }.into(),
        NumericError::Diverged { iteration: 1 }.into(),
        NumericError::Index { reason: "x".into() }.into(),
        ResourceError::ThreadPool { threads: 3, reason: "x".into() }.into(),
        RegisterError::Stopped { iteration: 1 },
    ];
    for e in &errors {
        let msg = e.to_string();
        assert!(!msg.contains("--") && !msg.contains("bsv.") && !msg.contains("Python"), "{msg}");
        for p in e.parameters() {
            assert!(names.contains(p), "{p} is not a registration parameter");
            assert!(msg.contains(p), "{msg} does not name {p}");
        }
        assert_eq!(e.parameter(), e.parameters().first().copied());
    }
    let params = |i: usize| errors[i].parameters();
    assert_eq!(params(1), ["drop_extremities"]);
    assert_eq!(params(15), ["cell_weight"]);
    assert_eq!(params(16), ["prune_distance_factor", "prune_normal_angle_deg"]);
    assert_eq!(params(18), ["data_weight", "alpha"]);
    assert_eq!(params(20), ["threads"]);
}
