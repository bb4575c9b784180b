//! Fuzz-style tests of the parameter parsers (issue 14): random and mutated schedule strings and
//! parameter maps (JSON, the serde form every front end uses) never panic or abort: they parse and
//! validate, or fail with a typed error that names the parameter. Parameters that validate are
//! then run through one iteration of a small fit, which must succeed or fail with a typed error
//! (a huge count must not allocate or loop without end). Seeded (proptest's default RNG), a few
//! thousand cases in all, a few seconds.
#![allow(clippy::unwrap_used)]

use bsv_core::shapes::icosphere;
use bsv_core::PointCloud;
use bsv_register::{register, ControlFlow, RegisterParams, Schedule, PARAMETER_NAMES};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use serde_json::{json, Value};

/// Numbers a user (or a typo) might give: edge values, huge, tiny, negative, NaN/inf as strings.
fn number() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(json!(0)),
        Just(json!(-1)),
        Just(json!(1)),
        Just(json!(u64::MAX)),
        Just(json!(i64::MIN)),
        Just(json!(1e300)),
        Just(json!(-1e300)),
        Just(json!(5e-324)),
        Just(json!(1_000_000_000_000_000u64)),
        Just(json!("nan")),
        Just(json!("inf")),
        Just(json!(true)),
        Just(json!(null)),
        Just(json!([1, 2])),
        Just(json!("m2p:5")),
        any::<i64>().prop_map(|v| json!(v)),
        any::<u32>().prop_map(|v| json!(v)),
        (-1e9f64..1e9).prop_map(|v| json!(v)),
        (0.0f64..2.0).prop_map(|v| json!(v)),
        "[a-z_:,0-9.-]{0,12}".prop_map(|v| json!(v)),
    ]
}

/// Schedule strings: well-formed with any counts, and mutated ones.
fn schedule() -> impl Strategy<Value = String> {
    let count = prop_oneof![
        Just("18446744073709551615".to_string()),
        Just("1000000000000000".to_string()),
        Just("-1".to_string()),
        Just("0".to_string()),
        Just("1e3".to_string()),
        Just(String::new()),
        any::<u64>().prop_map(|v| v.to_string()),
        (0u32..30).prop_map(|v| v.to_string()),
    ];
    let kind = prop_oneof![Just("m2p"), Just("p2m"), Just("M2P"), Just(" p2m "), Just("x"), Just("")];
    let stage = (kind, count, prop_oneof![Just(":"), Just("="), Just("")]).prop_map(|(k, c, s)| format!("{k}{s}{c}"));
    prop_oneof![
        prop::collection::vec(stage, 0..5).prop_map(|v| v.join(",")),
        "\\PC{0,20}",
        prop::collection::vec(any::<u8>(), 0..20).prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
    ]
}

fn runner(cases: u32) -> TestRunner {
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha))
}

#[test]
fn random_schedules_parse_or_fail_with_a_message() {
    runner(3000)
        .run(&schedule(), |text| {
            match text.parse::<Schedule>() {
                Ok(s) => {
                    let p = RegisterParams { schedule: s, ..RegisterParams::default() };
                    if let Err(e) = p.validate() {
                        prop_assert!(e.to_string().contains("schedule"), "{e}");
                    }
                }
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_parameter_maps_validate_or_name_the_parameter_and_a_valid_one_fits_or_fails_typed() {
    let sphere = icosphere(0.3, 2);
    let cloud = PointCloud::new(bsv_capture::sample::sample_surface(&icosphere(0.31, 3), 600, 3).0);
    let names: Vec<&str> = PARAMETER_NAMES.iter().copied().chain(["alpah", ""]).collect();
    let entry = (prop::sample::select(names), prop_oneof![number(), schedule().prop_map(Value::from)]);
    let (valid, fitted) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    runner(2500)
        .run(&prop::collection::vec(entry, 1..4), |entries| {
            let map: serde_json::Map<String, Value> = entries.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
            let text = Value::Object(map).to_string();
            let params = match serde_json::from_str::<RegisterParams>(&text) {
                Ok(p) => p,
                Err(e) => {
                    prop_assert!(!e.to_string().is_empty());
                    return Ok(());
                }
            };
            if let Err(e) = params.validate() {
                prop_assert!(PARAMETER_NAMES.iter().any(|n| e.to_string().contains(n)), "{e}");
                return Ok(());
            }
            valid.set(valid.get() + 1);
            // One iteration with what the parameters say otherwise, one thread.
            let p = RegisterParams { schedule: "m2p:1".parse().unwrap(), threads: 1, ..params };
            let mut sink = |_: &bsv_register::IterationLog| ControlFlow::Continue(());
            match register(&sphere, &cloud, &p, &mut sink) {
                Ok(_) => fitted.set(fitted.get() + 1),
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
            Ok(())
        })
        .unwrap();
    let (valid, fitted) = (valid.get(), fitted.get());
    assert!(valid > 50 && fitted > 30, "too few valid cases: {valid} valid, {fitted} fitted");
}
