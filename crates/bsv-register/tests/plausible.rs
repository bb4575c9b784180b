//! The plausibility checks before the fit (`plausible.rs`): a standing person in the world frame
//! passes, with and without labels; turned, upside-down, flat, compact and wrongly sized clouds are
//! refused with the error that names the problem; a non-human template is never checked.
#![allow(clippy::unwrap_used)]

use bsv_capture::sample::sample_surface;
use bsv_core::template::{template, TemplateKind};
use bsv_core::{shapes, PointCloud, TriMesh};
use bsv_register::{check_person, register, ControlFlow, ImplausibleError, RegisterError, RegisterParams};

/// A labelled cloud of the default template's surface (a standing person, Y up, facing +Z).
fn person(scale: f64) -> (TriMesh, PointCloud) {
    let t = template(TemplateKind::Default).unwrap();
    let (points, faces) = sample_surface(&t, 20_000, 7);
    let vl = t.vertex_labels.clone().unwrap();
    let mut c = PointCloud::new(points.iter().map(|p| p.map(|v| v * scale)).collect());
    c.labels = Some(faces.iter().map(|&f| vl[t.triangles[f as usize][0] as usize]).collect());
    (t, c)
}

fn map(c: &PointCloud, f: fn([f64; 3]) -> [f64; 3]) -> PointCloud {
    let mut out = c.clone();
    out.points.iter_mut().for_each(|p| *p = f(*p));
    out
}

fn unlabelled(c: &PointCloud) -> PointCloud {
    let mut out = c.clone();
    out.labels = None;
    out
}

#[test]
fn a_standing_person_passes_with_and_without_labels_at_any_plausible_size() {
    for scale in [0.6, 1.0, 1.3] {
        let (t, c) = person(scale);
        check_person(&c, &t).unwrap();
        check_person(&unlabelled(&c), &t).unwrap();
    }
}

#[test]
fn turned_and_upside_down_clouds_are_refused_naming_the_up_axis_or_the_facing() {
    let (t, c) = person(1.0);
    type Case = (&'static str, fn([f64; 3]) -> [f64; 3]);
    let cases: [Case; 5] = [
        ("90 about x", |[x, y, z]| [x, -z, y]),
        ("90 about y", |[x, y, z]| [z, y, -x]),
        ("90 about z", |[x, y, z]| [-y, x, z]),
        ("upside down", |[x, y, z]| [x, -y, -z]),
        ("180 about y", |[x, y, z]| [-x, y, -z]),
    ];
    for (name, f) in cases {
        let turned = map(&c, f);
        for (labels, cloud) in [(true, turned.clone()), (false, unlabelled(&turned))] {
            let r = check_person(&cloud, &t);
            let what = format!("{name}, labels {labels}: {r:?}");
            match name {
                "90 about x" => {
                    assert!(matches!(r, Err(ImplausibleError::WrongUp { up, .. }) if up.ends_with('z')), "{what}")
                }
                "90 about z" if labels => {
                    assert!(matches!(r, Err(ImplausibleError::WrongUp { up: "-x", .. })), "{what}")
                }
                "90 about z" => {
                    assert!(matches!(r, Err(ImplausibleError::WrongUp { up, .. }) if up.ends_with('x')), "{what}")
                }
                "upside down" => assert!(matches!(r, Err(ImplausibleError::WrongUp { up: "-y", .. })), "{what}"),
                "90 about y" => assert!(matches!(r, Err(ImplausibleError::Facing { .. })), "{what}"),
                // Without labels a person facing -Z cannot be told from one facing +Z.
                _ if labels => assert!(matches!(r, Err(ImplausibleError::Facing { .. })), "{what}"),
                _ => assert!(r.is_ok(), "{what}"),
            }
            if let Err(e) = r {
                let m = e.to_string();
                assert!(m.contains("rotate") || m.contains("turn"), "{m}");
                assert!(m.contains("check_plausible"), "{m}");
            }
        }
    }
}

#[test]
fn a_sphere_a_plane_and_a_doll_are_refused() {
    let (t, _) = person(1.0);
    // The sphere: 88 L.
    let r = (88e-3 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt();
    let mut sphere = shapes::icosphere(r, 4);
    shapes::translate(&mut sphere, [0.0, 1.0, 0.0]);
    let c = PointCloud::new(sample_surface(&sphere, 10_000, 1).0);
    assert!(matches!(check_person(&c, &t), Err(ImplausibleError::Compact { .. })), "{:?}", check_person(&c, &t));
    // A wall: a 1 x 1.5 m plane with 2 mm of noise.
    let plane: Vec<[f64; 3]> = (0..10_000)
        .map(|i| [(i % 100) as f64 / 100.0, (i / 100) as f64 * 0.015, 0.002 * ((i * 7919) % 3) as f64])
        .collect();
    let c = PointCloud::new(plane);
    assert!(matches!(check_person(&c, &t), Err(ImplausibleError::Flat { .. })), "{:?}", check_person(&c, &t));
    // A 40 cm doll (or a cloud in decimetres of a child): not a person's size in metres.
    let (_, doll) = person(0.25);
    let r = check_person(&doll, &t);
    assert!(matches!(r, Err(ImplausibleError::Size { .. })), "{r:?}");
    assert!(r.unwrap_err().to_string().contains("not in metres"));
}

#[test]
fn the_fit_refuses_with_a_typed_error_and_the_switch_turns_the_check_off() {
    let (t, c) = person(1.0);
    let upside_down = map(&c, |[x, y, z]| [x, -y, -z]);
    let mut sink = |_: &bsv_register::IterationLog| ControlFlow::Continue(());
    let e = register(&t, &upside_down, &RegisterParams::default(), &mut sink).unwrap_err();
    assert!(matches!(e, RegisterError::Implausible(ImplausibleError::WrongUp { .. })), "{e:?}");
    assert_eq!(e.parameter(), Some("check_plausible"));
    let mut p = RegisterParams::default();
    p.checks.check_plausible = false;
    p.schedule = "m2p:1".parse().unwrap();
    register(&t, &upside_down, &p, &mut sink).unwrap();
}

#[test]
fn a_template_that_is_not_a_labelled_human_is_not_checked() {
    // The boxes' template: a cube labelled torso only; analytic shapes: no labels.
    let mut cube = shapes::subdivided_cuboid([1.0, 1.0, 1.0], 4);
    cube.vertex_labels = Some(vec![2; cube.vertices.len()]);
    let sphere = shapes::icosphere(0.3, 3);
    let c = PointCloud::new(sample_surface(&sphere, 2_000, 1).0);
    assert!(!bsv_register::is_human_template(&cube));
    check_person(&c, &cube).unwrap();
    check_person(&c, &sphere).unwrap();
}
