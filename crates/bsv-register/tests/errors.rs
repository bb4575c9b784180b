//! Bad input gives typed errors, never a panic.

#![allow(clippy::unwrap_used)]
mod common;
use bsv_core::shapes::{cuboid, icosphere};
use bsv_core::PointCloud;
use bsv_register::{
    register, ArticulationParams, ControlFlow, EnergyParams, InputError, IterationLog, LabelSource, NumericError,
    OutlierParams, ParameterError, RegisterError, RegisterParams, Schedule,
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
    assert_eq!(Schedule::parse(" M2P:5, p2m:5 ,m2p:10").unwrap(), Schedule::default());

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
    assert_eq!(reg.outliers_removed, 1);
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
