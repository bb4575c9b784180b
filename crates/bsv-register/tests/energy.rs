//! The energy never increases within an iteration (fixed correspondences): the local step and the
//! global step each minimise their own block exactly.

#![allow(clippy::unwrap_used)]
mod common;
use bsv_core::shapes::{ellipsoid, icosphere};
use bsv_register::{ControlFlow, EnergyParams, IterationLog, RegisterParams, Schedule};
use common::*;

#[test]
fn energy_monotone_within_every_iteration() {
    let template = icosphere(0.2, 3);
    let mut cloud = cloud_of(&ellipsoid([0.24, 0.2, 0.17], 5), 50_000, 5);
    drop_sides(&mut cloud, 0.85);
    for alpha in [1e6, 1e4, 1e8] {
        for tw in [0.0, 1.0] {
            let params = RegisterParams {
                energy: EnergyParams { alpha, tangential_weight: tw, tangential_weight_p2m: tw, ..Default::default() },
                schedule: Schedule::parse("m2p:4,p2m:4,m2p:4").unwrap(),
                stop_motion_mm: 0.0,
                ..Default::default()
            };
            let mut logs: Vec<IterationLog> = Vec::new();
            let mut cb = |l: &IterationLog| {
                logs.push(l.clone());
                ControlFlow::Continue(())
            };
            bsv_register::register(&template, &cloud, &params, &mut cb).unwrap();
            assert_eq!(logs.len(), 12);
            for l in &logs {
                let tol = 1e-9 * l.energy_start.abs().max(1e-12);
                assert!(l.energy_after_local <= l.energy_start + tol, "local step raised the energy: {l:?}");
                assert!(l.energy.total <= l.energy_after_local + tol, "global step raised the energy: {l:?}");
                assert!((l.energy.arap + l.energy.reg + l.energy.data - l.energy.total).abs() <= tol);
            }
            // The energy does move: a no-op solver would also pass the inequalities.
            assert!(logs[0].energy.total < 0.5 * logs[0].energy_start, "{:?}", logs[0]);
        }
    }
}
