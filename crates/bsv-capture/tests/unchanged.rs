//! A scan without a room is bit-identical to the scanner before rooms existed: fingerprints of the
//! cloud, the depth, label and shade images and the colour render, recorded on the previous scanner.

#![allow(clippy::unwrap_used)]

use bsv_capture::scanner::{scan, write_capture, Condition, Rig};
use bsv_core::shapes;

/// FNV-1a over 64-bit words.
fn fnv(words: impl Iterator<Item = u64>) -> u64 {
    words.fold(0xcbf2_9ce4_8422_2325, |h, w| (h ^ w).wrapping_mul(0x0100_0000_01b3))
}

#[test]
fn a_scan_without_a_room_is_unchanged() {
    let body = shapes::capsule_body(false, true);
    let s = scan(&body, &Rig::paper_default(), Condition::L5Ca, 3).unwrap();
    let cloud = fnv(s
        .cloud
        .points
        .iter()
        .flat_map(|p| p.map(f64::to_bits))
        .chain(s.cloud.labels.as_ref().unwrap().iter().map(|&l| u64::from(l))));
    let views = fnv(s.views.iter().flat_map(|v| {
        v.depth
            .iter()
            .map(|z| u64::from(z.to_bits()))
            .chain(v.labels.iter().map(|&l| u64::from(l)))
            .chain(v.shade.iter().map(|x| u64::from(x.to_bits())))
            .chain(v.pixels.iter().map(|&p| u64::from(p)))
    }));
    let dir = std::env::temp_dir().join(format!("bsv-unchanged-{}", std::process::id()));
    write_capture(&s, &dir).unwrap();
    let rgb = image::open(dir.join("back/color.png")).unwrap().to_rgb8();
    let colour = fnv(rgb.as_raw().iter().map(|&b| u64::from(b)));
    std::fs::remove_dir_all(&dir).ok();
    // Recorded on commit f2dfe13 (the scanner without rooms) with this very test.
    assert_eq!(s.cloud.len(), 157_956);
    assert_eq!(cloud, 0x267e_d5b9_60f4_fa52, "cloud");
    assert_eq!(views, 0xd91c_319f_2b6c_2b6f, "views");
    assert_eq!(colour, 0xddd2_9e88_ad97_40db, "colour render");
}
