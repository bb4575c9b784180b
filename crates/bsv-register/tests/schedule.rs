//! Schedules with absurd iteration counts are parameter errors, never an overflow panic or an
//! allocation abort (issue 14: `m2p:18446744073709551615,m2p:1` panicked, `m2p:1000000000000000` aborted).
//! The last stage stops on convergence (`stop_motion_mm`), never before its minimum.

#![allow(clippy::unwrap_used)]
mod common;
use bsv_core::shapes::{ellipsoid, icosphere};
use bsv_register::{ControlFlow, IterationLog, ParameterError, RegisterParams, Schedule, MAX_ITERATIONS};
use common::*;

/// The iteration logs of a fit of a sphere to an ellipsoid's two-view cloud with `params`.
fn logs(params: &RegisterParams) -> Vec<IterationLog> {
    let template = icosphere(0.2, 3);
    let mut cloud = cloud_of(&ellipsoid([0.24, 0.2, 0.17], 5), 50_000, 5);
    drop_sides(&mut cloud, 0.85);
    let mut out = Vec::new();
    let mut cb = |l: &IterationLog| {
        out.push(l.clone());
        ControlFlow::Continue(())
    };
    bsv_register::register(&template, &cloud, params, &mut cb).unwrap();
    out
}

#[test]
fn the_last_stage_stops_once_the_fit_stops_moving() {
    let schedule = Schedule::parse("m2p:5,p2m:5,m2p:30").unwrap();
    let all = logs(&RegisterParams { schedule: schedule.clone(), stop_motion_mm: 0.0, ..Default::default() });
    assert_eq!(all.len(), 40, "0 = every iteration");
    let p = RegisterParams { schedule, ..Default::default() };
    let stopped = logs(&p);
    let last = stopped.last().unwrap();
    assert!(stopped.len() < 40, "a converged fit stops early: {} iterations", stopped.len());
    assert!(stopped.len() >= 10 + bsv_register::MIN_FINAL_ITERATIONS, "never before the last stage's minimum");
    assert!(last.motion_mm < p.stop_motion_mm, "it stopped at a still iteration: {last:?}");
    for l in &stopped[10 + bsv_register::MIN_FINAL_ITERATIONS - 1..stopped.len() - 1] {
        assert!(l.motion_mm >= p.stop_motion_mm, "it ran past a still iteration: {l:?}");
    }
    // The same iterations as the full run up to the stop.
    for (a, b) in stopped.iter().zip(&all) {
        assert_eq!(a.motion_mm, b.motion_mm);
    }
    let e = serde_json::from_str::<RegisterParams>(r#"{"stop_motion_mm": -1}"#).map(|p| p.validate());
    assert!(matches!(e, Ok(Err(ParameterError::BadParameter { name: "stop_motion_mm", .. }))), "{e:?}");
}

#[test]
fn huge_or_overflowing_schedules_are_refused() {
    for text in ["m2p:18446744073709551615,m2p:1", "m2p:1000000000000000", &format!("p2m:{}", MAX_ITERATIONS + 1)] {
        let e = Schedule::parse(text).unwrap_err();
        assert!(matches!(e, ParameterError::BadSchedule { .. }), "{text}: {e:?}");
        assert!(e.to_string().contains("iterations in total"), "{e}");
    }
    assert_eq!(Schedule::parse(&format!("m2p:{MAX_ITERATIONS}")).unwrap().total_iterations(), MAX_ITERATIONS);
    // The list form goes through the same check, inside the parameters too.
    let list =
        r#"{"schedule": [{"kind": "m2p", "iterations": 18446744073709551615}, {"kind": "p2m", "iterations": 1}]}"#;
    let e = serde_json::from_str::<RegisterParams>(list).unwrap_err().to_string();
    assert!(e.contains("iterations in total"), "{e}");
    let e = serde_json::from_str::<RegisterParams>(r#"{"schedule": "m2p:0"}"#).unwrap_err().to_string();
    assert!(e.contains("no iteration"), "{e}");
}
