//! The rig with a room: room pixels carry depth but label 0, the oracle cloud holds the body only,
//! the colour render paints the subject and the room, and room parameters are checked.

#![allow(clippy::unwrap_used)]

use bsv_capture::distance::surface_distances;
use bsv_capture::scanner::{
    scan, write_capture, Appearance, BodyHeights, Condition, Look, Rig, Room, RoomObject, ScanError, SurfaceKind,
    SurfacePixel, LONG_HAIR_DOWN_M, LONG_HAIR_HALF_WIDTH_M, SKIN_TONES, TOP_BAND,
};
use bsv_core::{shapes, Segment};
use std::collections::HashSet;

fn kinds_seen(s: &bsv_capture::scanner::Scan, view: usize) -> HashSet<u8> {
    s.views[view].surface.as_ref().unwrap().kind.iter().copied().collect()
}

#[test]
fn room_pixels_have_depth_and_label_0_and_the_cloud_is_the_body() {
    let body = shapes::capsule_body(false, false);
    let plain = scan(&body, &Rig::paper_default(), Condition::NoEr, 3).unwrap();
    let roomed = scan(&body, &Rig::paper_default().with_room(Room::clinic()), Condition::NoEr, 3).unwrap();
    // No room point reaches the cloud: in noer it is exactly the body-only cloud.
    assert_eq!(roomed.cloud, plain.cloud);
    assert!(plain.appearance.is_none() && roomed.appearance.is_some());
    for (vi, v) in roomed.views.iter().enumerate() {
        let surf = v.surface.as_ref().unwrap();
        let seen = kinds_seen(&roomed, vi);
        assert!(seen.contains(&(SurfaceKind::Floor as u8)) && seen.contains(&(SurfaceKind::Wall as u8)), "{seen:?}");
        let mut room_px = 0;
        for (i, &k) in surf.kind.iter().enumerate() {
            if k != SurfaceKind::Body as u8 && k != SurfaceKind::None as u8 {
                assert_eq!(v.labels[i], 0);
                assert!(v.depth[i] > 0.0);
                room_px += 1;
            }
        }
        // The room fills most of the image; the empty-background scan had no depth there.
        assert!(room_px > 500_000, "{} room pixels {room_px}", v.name);
        assert!(plain.views[vi].depth.iter().filter(|&&z| z > 0.0).count() < 200_000);
        assert_eq!(v.pixels, plain.views[vi].pixels);
    }
}

#[test]
fn l515_with_a_room_flies_between_body_and_room_but_keeps_body_pixels_only() {
    let body = shapes::capsule_body(false, false);
    let s = scan(&body, &Rig::paper_default().with_room(Room::clinic()), Condition::L515, 5).unwrap();
    let d = surface_distances(&s.cloud.points, &body).unwrap();
    let far = d.iter().filter(|&&x| x > 0.1).count();
    // Flying pixels at the outline reach toward the wall (beyond the 0.3 m silhouette tail).
    assert!(far > 50 && far < d.len() / 50, "{far} of {} points > 10 cm", d.len());
    assert!(d.iter().any(|&x| x > 0.35));
    for v in &s.views {
        let surf = v.surface.as_ref().unwrap();
        assert!(v.pixels.iter().all(|&p| surf.kind[p as usize] == SurfaceKind::Body as u8));
    }
}

#[test]
fn objects_are_seen_by_the_front_camera_only_as_room() {
    let body = shapes::capsule_body(false, false);
    let s = scan(&body, &Rig::paper_default().with_room(Room::clinic_with_objects()), Condition::NoEr, 0).unwrap();
    let front = kinds_seen(&s, 0);
    assert!(front.contains(&(SurfaceKind::Block as u8)) && front.contains(&(SurfaceKind::Person as u8)), "{front:?}");
    let plain = scan(&body, &Rig::paper_default(), Condition::NoEr, 0).unwrap();
    assert_eq!(s.cloud.len(), plain.cloud.len());
}

#[test]
fn appearance_is_deterministic_and_varied() {
    assert_eq!(Appearance::from_seed(11), Appearance::from_seed(11));
    let all: Vec<Appearance> = (0..200).map(Appearance::from_seed).collect();
    let tones: HashSet<[u8; 3]> = all.iter().map(|a| a.skin).collect();
    assert_eq!(tones.len(), SKIN_TONES.len());
    assert!(all.iter().any(|a| a.hair_length_m == 0.0) && all.iter().any(|a| a.hair_length_m > 0.0));
    assert!(all.windows(2).any(|w| w[0] != w[1]));
    // Every light set-up and colour occurs; the light stays in the range the renders were made for.
    let setups: HashSet<String> = all.iter().map(|a| format!("{:?}", a.light_setup)).collect();
    assert_eq!(setups.len(), 4, "{setups:?}");
    let tints: HashSet<String> = all.iter().map(|a| format!("{:?}", a.tint)).collect();
    assert_eq!(tints.len(), 3, "{tints:?}");
    for a in &all {
        let total = a.ambient + a.lights.iter().map(|l| l.intensity).sum::<f64>();
        assert!((1.0..=1.25).contains(&total) && a.lights.iter().all(|l| l.intensity >= 0.1), "{a:?}");
    }
    // Room variation is deterministic and keeps the walls beyond the cameras.
    let r = Room::clinic().varied(4);
    assert_eq!(r, Room::clinic().varied(4));
    assert_ne!(r, Room::clinic().varied(5));
    assert!(r.back_wall_z < -2.3 && r.front_wall_z > 2.3);
}

#[test]
fn the_colour_render_shows_the_room_and_is_deterministic() {
    let body = shapes::capsule_body(false, false);
    let dir = std::env::temp_dir().join(format!("bsv-room-{}", std::process::id()));
    let rig = Rig::paper_default().with_room(Room::clinic());
    for (sub, r) in [("plain", Rig::paper_default()), ("room", rig.clone()), ("again", rig)] {
        write_capture(&scan(&body, &r, Condition::NoEr, 2).unwrap(), &dir.join(sub)).unwrap();
    }
    let read = |sub: &str| image::open(dir.join(sub).join("front/color.png")).unwrap().to_rgb8();
    let (plain, room, again) = (read("plain"), read("room"), read("again"));
    assert_eq!(room, again);
    // The plain render's background is uniform grey; the room's is not.
    let corner = |img: &image::RgbImage| *img.get_pixel(5, 1000);
    assert_eq!(corner(&plain).0, [128, 128, 128]);
    assert_ne!(corner(&room).0, [128, 128, 128]);
    let distinct: HashSet<[u8; 3]> = room.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 200, "{} colours", distinct.len());
    let depth = image::open(dir.join("room/front/depth.png")).unwrap().to_luma16();
    assert!(depth.pixels().filter(|p| p.0[0] > 0).count() > 900_000 * 3 / 4);
    // scan.json says how the room's render looks (a benchmark groups by it); the plain render has no look.
    let info = |sub: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(sub).join("scan.json")).unwrap()).unwrap()
    };
    let look: Appearance = serde_json::from_value(info("room")["appearance"].clone()).unwrap();
    assert_eq!(look, Appearance::from_seed(2));
    assert!(info("plain").get("appearance").is_none());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_room_parameters_name_the_parameter_and_the_remedy() {
    let body = shapes::capsule_body(false, false);
    let mut room = Room::clinic();
    room.back_wall_z = -1.5;
    let e = scan(&body, &Rig::paper_default().with_room(room), Condition::NoEr, 0).unwrap_err();
    assert!(matches!(e, ScanError::CameraOutsideRoom { param: "back_wall_z", .. }), "{e}");
    assert!(e.to_string().contains("back") && e.to_string().contains("smaller z"));
    let room = Room { wall_height: f64::NAN, ..Room::clinic() };
    let e = scan(&body, &Rig::paper_default().with_room(room), Condition::NoEr, 0).unwrap_err();
    assert!(e.to_string().contains("wall_height"), "{e}");
    let room = Room {
        objects: vec![RoomObject::Person { center_xz: [0.0, -1.0], height: 0.3, radius: 0.2 }],
        ..Room::clinic()
    };
    let e = scan(&body, &Rig::paper_default().with_room(room), Condition::NoEr, 0).unwrap_err();
    assert!(matches!(e, ScanError::BadRoom { param: "objects.person.height", .. }), "{e}");
    let json: Room = serde_json::from_str(r#"{"back_wall_z": -3.0}"#).unwrap();
    assert_eq!(json, Room { back_wall_z: -3.0, ..Room::clinic() });
    assert!(serde_json::from_str::<Room>(r#"{"bak_wall_z": -3.0}"#).is_err());
}

#[test]
fn long_hair_keeps_the_seeds_other_draws_and_hangs_over_the_upper_back() {
    let long = Look { long_hair: true, ..Look::default() };
    let mut seen_long = false;
    for seed in 0..64 {
        let plain = Appearance::from_seed(seed);
        let with = Appearance::from_seed_with(seed, &long);
        assert_eq!(plain.hair_down_m, 0.0);
        assert_eq!(Appearance { hair_down_m: 0.0, ..with.clone() }, plain, "seed {seed}: other draws changed");
        if plain.hair_length_m == 0.0 {
            assert_eq!(with.hair_down_m, 0.0, "seed {seed}: a bald subject stays bald");
        } else {
            let (lo, hi) = LONG_HAIR_DOWN_M;
            assert!((lo..=hi).contains(&with.hair_down_m), "seed {seed}: {}", with.hair_down_m);
            seen_long = true;
        }
        assert_eq!(Appearance::from_seed_with(seed, &Look::default()), plain);
    }
    assert!(seen_long);
    // A torso pixel on the upper back, seen by the back camera, is hair with long hair and skin without;
    // the same pixel seen from the front, or beside the hair's width, is skin either way.
    let seed = (0..64).find(|&s| Appearance::from_seed(s).hair_length_m > 0.0).unwrap();
    let (plain, with) = (Appearance::from_seed(seed), Appearance::from_seed_with(seed, &long));
    let heights = BodyHeights { crotch_y: 0.85, top_y: 1.75, head_x: 0.01 };
    let px = |x: f64, nz: f64| SurfacePixel {
        kind: SurfaceKind::Body,
        label: Segment::Torso as u8,
        point: [x, heights.top_y - 0.28, -0.1],
        normal: [0.0, 0.0, nz],
    };
    let hair_top =
        SurfacePixel { label: Segment::Head as u8, point: [0.0, heights.top_y - 0.01, -0.05], ..px(0.0, -1.0) };
    assert_eq!(with.shade(&heights, &px(0.01, -1.0)), with.shade(&heights, &hair_top));
    assert_ne!(plain.shade(&heights, &px(0.01, -1.0)), plain.shade(&heights, &hair_top));
    assert_eq!(with.shade(&heights, &px(0.01, 1.0)), plain.shade(&heights, &px(0.01, 1.0)));
    let beside = 0.01 + LONG_HAIR_HALF_WIDTH_M + 0.02;
    assert_eq!(with.shade(&heights, &px(beside, -1.0)), plain.shade(&heights, &px(beside, -1.0)));
}

#[test]
fn a_top_covers_the_chest_front_and_back_in_the_underwears_colour() {
    let seed = 5;
    let plain = Appearance::from_seed(seed);
    let with = Appearance::from_seed_with(seed, &Look { top: true, ..Look::default() });
    assert!(with.top && !plain.top);
    assert_eq!(Appearance { top: false, ..with.clone() }, plain);
    let heights = BodyHeights { crotch_y: 0.85, top_y: 1.75, head_x: 0.0 };
    let at = |t: f64, label: Segment, nz: f64| SurfacePixel {
        kind: SurfaceKind::Body,
        label: label as u8,
        point: [0.05, heights.crotch_y + t * (heights.top_y - heights.crotch_y), 0.1 * nz],
        normal: [0.0, 0.0, nz],
    };
    let mid = 0.5 * (TOP_BAND.0 + TOP_BAND.1);
    // On the chest, front and back: the underwear's albedo, as on the pelvis; the arm beside it and the
    // belly below it stay skin.
    let pelvis = at(0.05, Segment::Torso, 1.0);
    for nz in [1.0, -1.0] {
        let chest = at(mid, Segment::Torso, nz);
        assert_eq!(
            with.shade(&heights, &chest),
            with.shade(&heights, &SurfacePixel { normal: chest.normal, ..pelvis })
        );
        assert_ne!(plain.shade(&heights, &chest), with.shade(&heights, &chest));
    }
    assert_eq!(
        with.shade(&heights, &at(mid, Segment::UpperArmL, 1.0)),
        plain.shade(&heights, &at(mid, Segment::UpperArmL, 1.0))
    );
    let belly = at(TOP_BAND.0 - 0.05, Segment::Torso, 1.0);
    assert_eq!(with.shade(&heights, &belly), plain.shade(&heights, &belly));
}

/// The largest angle (radians) between the colour normals of two 4-neighbouring body pixels of a view, away
/// from the outline (both pixels and their neighbours on the body).
fn largest_normal_step(s: &bsv_capture::scanner::Scan, view: usize) -> f64 {
    let v = &s.views[view];
    let surf = v.surface.as_ref().unwrap();
    let w = v.intrinsics.width as usize;
    let body = |i: usize| surf.kind[i] == SurfaceKind::Body as u8;
    let mut worst: f64 = 0.0;
    for i in (w + 1)..(surf.kind.len() - w - 1) {
        if ![i, i - 1, i + 1, i - w, i + w, i + 1 + w].iter().all(|&j| body(j)) {
            continue;
        }
        let (a, b) = (surf.normal[i], surf.normal[i + 1]);
        let dot: f32 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        worst = worst.max(f64::from(dot.clamp(-1.0, 1.0)).acos());
    }
    worst
}

#[test]
fn smooth_shading_changes_the_colour_normals_only_and_hides_the_facets() {
    // A coarse ball (80 faces, about 25 deg between neighbouring face normals) in front of the rig.
    let mut ball = shapes::icosphere(0.3, 1);
    shapes::translate(&mut ball, [0.0, 1.0, 0.0]);
    ball.vertex_labels = Some(vec![Segment::Torso as u8; ball.n_vertices()]);
    let flat_rig = Rig::paper_default().with_room(Room::clinic());
    let smooth_rig = Rig { look: Look { smooth_shading: true, ..Look::default() }, ..flat_rig.clone() };
    let flat = scan(&ball, &flat_rig, Condition::L515, 2).unwrap();
    let smooth = scan(&ball, &smooth_rig, Condition::L515, 2).unwrap();
    assert_eq!(smooth.cloud, flat.cloud);
    assert!(
        smooth.appearance.as_ref().unwrap().0.smooth_shading && !flat.appearance.as_ref().unwrap().0.smooth_shading
    );
    assert_eq!(
        Appearance { smooth_shading: false, ..smooth.appearance.as_ref().unwrap().0.clone() },
        flat.appearance.as_ref().unwrap().0
    );
    for vi in 0..flat.views.len() {
        let (f, s) = (&flat.views[vi], &smooth.views[vi]);
        assert_eq!((&f.depth, &f.labels, &f.pixels), (&s.depth, &s.labels, &s.pixels));
        let (fs, ss) = (f.surface.as_ref().unwrap(), s.surface.as_ref().unwrap());
        assert_eq!(fs.kind, ss.kind);
        // Room pixels keep their normals; body pixels face the camera either way.
        for (i, &k) in fs.kind.iter().enumerate() {
            if k == SurfaceKind::Body as u8 {
                let n = ss.normal[i];
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-4, "pixel {i}: |n| = {len}");
            } else {
                assert_eq!(fs.normal[i], ss.normal[i]);
            }
        }
        // Flat: the normal jumps by a facet's angle between neighbouring pixels; smooth: by a pixel's worth.
        let (jf, js) = (largest_normal_step(&flat, vi), largest_normal_step(&smooth, vi));
        assert!(jf > 0.3, "{} flat step {jf}", f.name);
        assert!(js < 0.1, "{} smooth step {js}", f.name);
    }
}

#[test]
fn the_colour_sensor_blurs_and_adds_noise_that_grows_with_the_level() {
    let body = shapes::capsule_body(false, false);
    let dir = std::env::temp_dir().join(format!("bsv-sensor-{}", std::process::id()));
    let rig = Rig::paper_default().with_room(Room::clinic());
    let sensor = Rig { look: Look { colour_sensor: true, ..Look::default() }, ..rig.clone() };
    let read = |name: &str| -> Vec<image::RgbImage> {
        ["front", "back"]
            .iter()
            .map(|c| image::open(dir.join(name).join(c).join("color.png")).unwrap().to_rgb8())
            .collect()
    };
    for (name, r, seed) in [("exact", &rig, 3), ("sensor", &sensor, 3), ("again", &sensor, 3), ("other", &sensor, 4)] {
        let s = scan(&body, r, Condition::NoEr, seed).unwrap();
        assert_eq!(s.appearance.as_ref().unwrap().0.colour_sensor, name != "exact");
        write_capture(&s, &dir.join(name)).unwrap();
    }
    let (exact, noisy, again) = (read("exact"), read("sensor"), read("again"));
    assert_eq!(noisy, again, "deterministic for a seed");
    for (e, n) in exact.iter().zip(&noisy) {
        // The noise's sd per level: sqrt(READ^2 + SHOT x level) on flat regions (the
        // wall, the floor's tiles): 2.7 at level 96, 3.3 at 174.
        let (mut dark, mut bright) = (Vec::new(), Vec::new());
        let (w, h) = e.dimensions();
        for y in 2..h - 2 {
            for x in 2..w - 2 {
                let level = e.get_pixel(x, y)[1];
                // flat: the exact render is the same level 2 pixels around, so the blur leaves it as it is
                let flat = [(0, 2), (2, 0), (0, -2), (-2, 0), (2, 2), (-2, -2), (2, -2), (-2, 2)].iter().all(
                    |&(dx, dy): &(i32, i32)| {
                        e.get_pixel(x.saturating_add_signed(dx), y.saturating_add_signed(dy))[1] == level
                    },
                );
                if !flat {
                    continue;
                }
                let d = f64::from(n.get_pixel(x, y)[1]) - f64::from(level);
                if level < 100 {
                    dark.push(d)
                } else if level > 165 {
                    bright.push(d)
                }
            }
        }
        let sd = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        assert!(dark.len() > 10_000 && bright.len() > 10_000, "{} {}", dark.len(), bright.len());
        let (sd_dark, sd_bright) = (sd(&dark), sd(&bright));
        assert!(sd_dark > 2.2 && sd_bright > sd_dark + 0.3 && sd_bright < 4.0, "{sd_dark} {sd_bright}");
    }
    // The blur softens the render's hard edges: where the exact image steps by more than 40 levels from one
    // pixel to the next, the recorded one steps by a good deal less.
    for (e, n) in exact.iter().zip(&noisy) {
        let (mut before, mut after, mut count) = (0.0, 0.0, 0);
        for (x, y, p) in e.enumerate_pixels() {
            if x + 1 < e.width() {
                let step = (f64::from(e.get_pixel(x + 1, y)[1]) - f64::from(p[1])).abs();
                if step > 40.0 {
                    before += step;
                    after += (f64::from(n.get_pixel(x + 1, y)[1]) - f64::from(n.get_pixel(x, y)[1])).abs();
                    count += 1;
                }
            }
        }
        assert!(count > 100 && after < 0.8 * before, "{count} edges: {before} -> {after}");
    }
    // Another seed draws other noise.
    assert_ne!(read("other"), noisy);
    std::fs::remove_dir_all(&dir).ok();
}
