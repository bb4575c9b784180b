//! BSV registration: warps a template mesh onto a (front + back, gappy) point cloud.
//!
//! [`register`] is a composition of four named stages (after libigl's `arap_precomputation` /
//! `arap_solve` and faer's symbolic / numeric split):
//!
//! 1. [`prepare`] -> [`Prepared`]: input checks, head/hand/foot removal
//!    ([`OutlierParams::drop_extremities`]), sparse-point (flying pixel) removal (`outliers.rs`),
//!    detached-piece removal (floor and wall spill labelled like a limb, `detached.rs`),
//!    the similarity pre-alignment (`prealign.rs`) and the articulated initialisation of the limbs
//!    when the template and the cloud are labelled (`articulate.rs`; the articulated template is
//!    the rest shape).
//! 2. [`Registrar::new`]: built once per prepared input, owns the cotangent weights (`cotan.rs`),
//!    the symbolic Cholesky analysis of the global system (`solver.rs`), the constant per-cell data
//!    of the local step (`local.rs`), the k-d trees over the cloud (`correspond.rs`) and the
//!    buffers of the iterations.
//! 3. [`Registrar::step`], once per iteration of the schedule: correspondences (label-aware when
//!    both sides are labelled), the local step (exact per-cell minimiser of the regularized ARAP
//!    energy) and the global step (one sparse solve with the three coordinates at once).
//! 4. [`Registrar::finish`] -> [`Registration`]: the inscribed-mesh [`surface_correction`], the
//!    final distances and the labels.
//!
//! Energies, weights and units are documented on [`EnergyParams`] and in
//! `local.rs`. Errors are typed per stage ([`RegisterError`]). What each stage of the pipeline
//! gains on the synthetic cohort: (measured: benchmarks/BENCH.md, section Registration).

mod articulate;
mod correspond;
mod cotan;
mod curvature;
mod detached;
mod error;
mod keypoints;
mod local;
mod log;
mod outliers;
mod params;
mod plausible;
mod prealign;
mod prepare;
mod quality;
mod raytrail;
mod registrar;
mod result;
mod schedule;
mod section;
mod solver;
mod surface;
mod sym3;
#[cfg(test)]
mod testshapes;
mod voxels;
mod walk;

pub use error::{ImplausibleError, InputError, NumericError, ParameterError, RegisterError, ResourceError};
pub use keypoints::{Keypoint, KeypointResidual, Keypoints};
pub use log::{Energy, IterationLog, Timings};
pub use params::{
    ArticulationParams, CheckParams, EnergyParams, LabelSource, OutlierParams, PrealignMode, PrealignParams,
    PruningParams, RegisterParams, YawMode, MIN_FINAL_ITERATIONS, PARAMETER_NAMES,
};
pub use plausible::{check_person, is_human_template};
pub use prealign::Similarity;
pub use prepare::{prepare, Prepared};
pub use quality::{SegmentQuality, DOUBT_COVERAGE, DOUBT_EXPOSED, DOUBT_FOLDED, DOUBT_FOLDED_TORSO, DOUBT_RMS_MM};
pub use registrar::Registrar;
pub use result::{LimbAlignment, Registration};
pub use schedule::{CorrespondenceKind, Schedule, Stage, DEFAULT_SCHEDULE, MAX_ITERATIONS};
pub use std::ops::ControlFlow;
pub use surface::surface_correction;

use bsv_core::{PointCloud, TriMesh};

/// Registers `template` onto `cloud` (metres, shared world frame) in a new rayon pool of
/// `params.threads` threads. Calls `progress` after every iteration; `ControlFlow::Break(())`
/// stops the fit with [`RegisterError::Stopped`]. Never panics on user data: every failure is a
/// [`RegisterError`].
pub fn register(
    template: &TriMesh,
    cloud: &PointCloud,
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog) -> ControlFlow<()>,
) -> Result<Registration, RegisterError> {
    register_with_keypoints(template, &[], cloud, &[], params, progress)
}

/// [`register`] in the caller's rayon `pool` (`params.threads` is ignored): the parallel parts of
/// the fit run in `pool`, `progress` is called on this thread.
pub fn register_in(
    pool: &rayon::ThreadPool,
    template: &TriMesh,
    cloud: &PointCloud,
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog) -> ControlFlow<()>,
) -> Result<Registration, RegisterError> {
    register_in_with_keypoints(pool, template, &[], cloud, &[], params, progress)
}

/// [`register`] with the keypoint term: see [`register_in_with_keypoints`].
pub fn register_with_keypoints(
    template: &TriMesh,
    rings: &[bsv_core::template::JointRing],
    cloud: &PointCloud,
    measured: &[Keypoint],
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog) -> ControlFlow<()>,
) -> Result<Registration, RegisterError> {
    params.validate()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(params.threads)
        .build()
        .map_err(|e| ResourceError::ThreadPool { threads: params.threads, reason: e.to_string() })?;
    register_in_with_keypoints(&pool, template, rings, cloud, measured, params, progress)
}

/// [`register_in`] with the keypoint term (`keypoints.rs`): the `measured` joint centres pull the
/// template's joints, defined by `rings` (made for this template; the embedded templates carry
/// theirs: `bsv_core::template::template_joints`). With no measured joint it is [`register_in`].
pub fn register_in_with_keypoints(
    pool: &rayon::ThreadPool,
    template: &TriMesh,
    rings: &[bsv_core::template::JointRing],
    cloud: &PointCloud,
    measured: &[Keypoint],
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog) -> ControlFlow<()>,
) -> Result<Registration, RegisterError> {
    let prepared = prepare(template, cloud, params)?.with_keypoints(rings, measured)?;
    let mut fit = Registrar::new(pool, prepared, params)?;
    while let Some(entry) = fit.step()? {
        if progress(entry).is_break() {
            return Err(RegisterError::Stopped { iteration: entry.iteration });
        }
    }
    fit.finish()
}
