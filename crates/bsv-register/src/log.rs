//! The per-iteration log of a registration: energies, distances, correspondences and timings.

use crate::schedule::CorrespondenceKind;
use serde::{Deserialize, Serialize};

/// Energy terms (m^2, see [`crate::EnergyParams`]) at one point of an iteration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    /// ARAP/affine term.
    pub arap: f64,
    /// Regularization term.
    pub reg: f64,
    /// Data term.
    pub data: f64,
    /// Sum of the three.
    pub total: f64,
}

/// Wall time of the parts of one iteration, seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    /// Correspondences (k-d tree queries, pruning, normals).
    pub correspond: f64,
    /// Local step (per-cell maps), with the numeric refactorization of the global system (when the
    /// data weights changed) running alongside it.
    pub local: f64,
    /// Global step: right-hand side and triangular solves.
    pub solve: f64,
}

/// What happened in one iteration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationLog {
    /// Index of the schedule stage (0-based).
    pub stage: usize,
    /// Global iteration index (0-based).
    pub iteration: usize,
    /// Correspondence kind of the stage.
    pub kind: CorrespondenceKind,
    /// Total energy with this iteration's correspondences and the previous maps (start of iteration).
    pub energy_start: f64,
    /// Total energy after the local step.
    pub energy_after_local: f64,
    /// Energy terms after the global step (end of iteration).
    pub energy: Energy,
    /// RMS distance from the vertices entering this iteration to their nearest cloud point, mm
    /// (before pruning).
    pub rms_mesh_to_points_mm: f64,
    /// RMS distance from the cloud points to their nearest vertex entering this iteration, mm
    /// (p2m iterations only: the query costs as much as the rest of an iteration).
    pub rms_points_to_mesh_mm: Option<f64>,
    /// RMS displacement of the vertices in this iteration's global step, mm (how far the fit still
    /// moves: the convergence measure of `stop_motion_mm`).
    pub motion_mm: f64,
    /// Correspondences kept after pruning (vertices with a data term).
    pub n_correspondences: usize,
    /// Whether the system was refactorized (the data weights changed).
    pub refactorized: bool,
    /// Time split.
    pub timings: Timings,
}
