//! Schedules with absurd iteration counts are parameter errors, never an overflow panic or an
//! allocation abort (issue 14: `m2p:18446744073709551615,m2p:1` panicked, `m2p:1000000000000000` aborted).

#![allow(clippy::unwrap_used)]

use bsv_register::{ParameterError, RegisterParams, Schedule, MAX_ITERATIONS};

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
