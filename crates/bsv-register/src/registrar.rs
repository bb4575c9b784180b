//! Stages 2 and 3 of a registration: the [`Registrar`], built once per prepared template + cloud
//! (like libigl's `arap_precomputation` or faer's symbolic analysis: the cotangent weights, the
//! symbolic Cholesky factorization, the constant per-cell data of the local step and the k-d tree
//! over the cloud), and its [`Registrar::step`], one iteration of the schedule each
//! (correspondences, local step, global step; like `arap_solve`). [`Registrar::finish`] (in
//! `registrar/finish.rs`) turns the fit into a [`crate::Registration`].
//!
//! Parallel parts run in the caller's rayon pool. No floating-point sum depends on how rayon splits
//! the work: per-item results are collected in index order, the energy sums go over fixed chunks
//! added in chunk order and the p2m sums per vertex run in point order, so a fit is bit-identical
//! for any thread count and from run to run (`tests/reproducible.rs`).

mod finish;

use crate::correspond::{CloudIndex, LabelTrees, Pruning, Targets};
use crate::cotan::CotanWeights;
use crate::curvature::shapes;
use crate::error::{NumericError, RegisterError};
use crate::local::{CellMaps, LocalModel};
use crate::log::{Energy, IterationLog, Timings};
use crate::params::{PruningParams, RegisterParams, MIN_FINAL_ITERATIONS};
use crate::prepare::Prepared;
use crate::schedule::{CorrespondenceKind, Schedule};
use crate::solver::GlobalSolver;
use bsv_core::geometry::{add, dot, scale, sub, total_area, vertex_normals};
use bsv_core::TriMesh;
use std::time::Instant;

/// A registration being fitted: the set-up built once and the state of the iterations.
pub struct Registrar<'a> {
    pool: &'a rayon::ThreadPool,
    params: &'a RegisterParams,
    /// The prepared input (its rest shape moved into `model` and `fit`).
    input: Prepared<'a>,
    solver: GlobalSolver,
    index: CloudIndex,
    model: LocalModel,
    pruning: Pruning,
    /// The template's vertex labels when label-aware matching is on.
    match_labels: Option<&'a [u8]>,
    setup_seconds: f64,
    fit: FitState,
    log: Vec<IterationLog>,
    cursor: Cursor,
}

impl std::fmt::Debug for Registrar<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Registrar")
            .field("vertices", &self.fit.cur.len())
            .field("index", &self.index)
            .field("solver", &self.solver)
            .field("iterations_done", &self.log.len())
            .finish()
    }
}

/// The per-iteration state and buffers (allocated once).
struct FitState {
    /// The current mesh (for the vertex normals).
    work: TriMesh,
    /// Current vertex positions.
    cur: Vec<[f64; 3]>,
    /// Cell maps of the local step.
    maps: CellMaps,
    /// Data weights (0 without correspondence).
    d: Vec<f64>,
    /// Correspondence targets.
    q: Vec<[f64; 3]>,
    /// ARAP part of the global right-hand side.
    rhs: Vec<[f64; 3]>,
    /// The global system's right-hand side / solution, n x 3.
    sol: faer::Mat<f64>,
    /// Every cloud point's vertex in the last p2m iteration (empty before one): the warm start of
    /// the next.
    p2m_vertex: Vec<u32>,
    /// ARAP and regularization energies at the end of the last iteration.
    arap: f64,
    reg: f64,
}

impl FitState {
    fn new(rest: Vec<[f64; 3]>, template: &TriMesh) -> FitState {
        let n = rest.len();
        let work = TriMesh::new(rest, template.triangles.clone());
        let cur = work.vertices.clone();
        FitState {
            work,
            cur,
            maps: CellMaps::identity(n),
            d: vec![0.0; n],
            q: vec![[0.0; 3]; n],
            rhs: vec![[0.0; 3]; n],
            sol: faer::Mat::<f64>::zeros(n, 3),
            p2m_vertex: Vec::new(),
            arap: 0.0,
            reg: 0.0,
        }
    }
}

/// Position in the schedule: the stage and the iterations done in it.
#[derive(Debug, Clone, Copy, Default)]
struct Cursor {
    stage: usize,
    done: usize,
}

impl Cursor {
    /// Moves past the schedule's end: no iteration is left.
    fn finish(&mut self, schedule: &Schedule) {
        (self.stage, self.done) = (schedule.0.len(), 0);
    }

    /// The stage of the next iteration (skipping stages of 0 iterations), `None` at the end.
    fn next(&mut self, schedule: &Schedule) -> Option<(usize, CorrespondenceKind)> {
        while let Some(stage) = schedule.0.get(self.stage) {
            if self.done < stage.iterations {
                return Some((self.stage, stage.kind));
            }
            self.stage += 1;
            self.done = 0;
        }
        None
    }
}

impl Pruning {
    /// The pruning settings of the parameters.
    fn of(p: &PruningParams) -> Pruning {
        Pruning {
            distance_factor: p.prune_distance_factor,
            torso_distance_factor: p.prune_distance_factor_torso,
            distance_floor: p.prune_distance_floor_m,
            min_cos: if p.prune_normal_angle_deg >= 180.0 { -1.0 } else { p.prune_normal_angle_deg.to_radians().cos() },
        }
    }
}

/// Data energy `sum_i d_i |p_i - q_i|^2`.
fn data_energy(cur: &[[f64; 3]], d: &[f64], q: &[[f64; 3]]) -> f64 {
    cur.iter()
        .zip(d)
        .zip(q)
        .filter(|((_, &di), _)| di > 0.0)
        .map(|((p, &di), t)| {
            let e = sub(*p, *t);
            di * dot(e, e)
        })
        .sum()
}

/// Sets the data weights `d` and targets `q` from the correspondences: the normal part of each
/// residual and the fraction `tangential_weight` of the tangential part. Returns the number of
/// vertices with a target.
fn set_targets(
    targets: &Targets,
    tangential_weight: f64,
    data_weight: f64,
    cur: &[[f64; 3]],
    d: &mut [f64],
    q: &mut [[f64; 3]],
) -> usize {
    let mut n_corr = 0;
    for (v, t) in targets.iter().enumerate() {
        match t {
            Some(res) => {
                // Keep the normal part of the residual and a fraction of the tangential one.
                let tangential = sub(res.offset, res.normal_part);
                q[v] = add(cur[v], add(res.normal_part, scale(tangential, tangential_weight)));
                d[v] = data_weight;
                n_corr += 1;
            }
            None => {
                d[v] = 0.0;
                q[v] = cur[v];
            }
        }
    }
    n_corr
}

impl<'a> Registrar<'a> {
    /// The set-up of the fit of `prepared` with `params` (the same parameters it was prepared
    /// with): cotangent weights of the rest shape, the symbolic factorization of the global
    /// system, the k-d tree over the cloud and the per-segment trees (the three in parallel), the
    /// local model.
    pub fn new(
        pool: &'a rayon::ThreadPool,
        mut prepared: Prepared<'a>,
        params: &'a RegisterParams,
    ) -> Result<Registrar<'a>, RegisterError> {
        let template = prepared.template;
        let rest = std::mem::take(&mut prepared.rest);
        let n = rest.len();
        let e = &params.energy;
        let area = total_area(&TriMesh::new(rest.clone(), template.triangles.clone()));
        let lambda = e.alpha * 1e-6 * e.cell_weight * area / n as f64;
        let weights = CotanWeights::new(&rest, &template.triangles);
        let cloud = &*prepared.cloud;
        // Label-aware matching when both sides are labelled: the per-segment trees are built
        // alongside the cloud's tree and the symbolic factorization.
        let labelled: Option<(&[u8], &'a [u8])> = match (&cloud.labels, &template.vertex_labels) {
            (Some(cl), Some(tl)) if params.pruning.label_aware => Some((cl.as_slice(), tl.as_slice())),
            _ => None,
        };
        let (solver, (index, trees)) = pool.install(|| {
            rayon::join(
                || GlobalSolver::new(&weights, e.cell_weight),
                || {
                    rayon::join(
                        || CloudIndex::new(&cloud.points, cloud.normals.as_deref(), params.pruning.estimate_normals_k),
                        || labelled.map(|(cl, tl)| LabelTrees::build(&cloud.points, cl, tl)).transpose(),
                    )
                },
            )
        });
        let solver = solver.map_err(NumericError::solver)?;
        let mut index = index.map_err(NumericError::index)?;
        let trees = trees.map_err(NumericError::index)?;
        let match_labels: Option<&'a [u8]> = match (trees, labelled) {
            (Some(trees), Some((_, tl))) => (index.set_label_trees(trees) > 0).then_some(tl),
            _ => None,
        };
        let model = pool.install(|| LocalModel::new(rest.clone(), weights, e.cell_weight, lambda));
        let setup_seconds = prepared.started.elapsed().as_secs_f64();
        Ok(Registrar {
            pool,
            params,
            solver,
            index,
            model,
            pruning: Pruning::of(&params.pruning),
            match_labels,
            setup_seconds,
            fit: FitState::new(rest, template),
            log: Vec::with_capacity(params.schedule.total_iterations().min(crate::schedule::MAX_ITERATIONS)),
            cursor: Cursor::default(),
            input: prepared,
        })
    }

    /// Runs the next iteration of the schedule: correspondences, local step, global step.
    /// Returns its log entry, or `None` when the schedule is done.
    pub fn step(&mut self) -> Result<Option<&IterationLog>, RegisterError> {
        let Some((stage, kind)) = self.cursor.next(&self.params.schedule) else {
            return Ok(None);
        };
        let iteration = self.log.len();
        let t0 = Instant::now();
        let (n_correspondences, rms_m2p, rms_p2m) = self.correspond(kind, iteration)?;
        let f = &self.fit;
        let energy_start = f.arap + f.reg + data_energy(&f.cur, &f.d, &f.q);
        let t1 = Instant::now();
        let (energy_after_local, refactorized) = self.local_step_and_factorization()?;
        let t2 = Instant::now();
        let motion = self.global_solve(iteration)?;
        let t3 = Instant::now();
        let (model, f) = (&self.model, &mut self.fit);
        (f.arap, f.reg) = self.pool.install(|| model.energy(&f.cur, &f.maps));
        let data = data_energy(&f.cur, &f.d, &f.q);
        self.log.push(IterationLog {
            stage,
            iteration,
            kind,
            energy_start,
            energy_after_local,
            energy: Energy { arap: f.arap, reg: f.reg, data, total: f.arap + f.reg + data },
            rms_mesh_to_points_mm: rms_m2p * 1e3,
            rms_points_to_mesh_mm: rms_p2m.map(|r| r * 1e3),
            motion_mm: motion * 1e3,
            n_correspondences,
            refactorized,
            timings: Timings {
                correspond: (t1 - t0).as_secs_f64(),
                local: (t2 - t1).as_secs_f64(),
                solve: (t3 - t2).as_secs_f64(),
            },
        });
        self.cursor.done += 1;
        if self.converged(stage, motion) {
            self.cursor.finish(&self.params.schedule);
        }
        Ok(self.log.last())
    }

    /// The correspondences of this iteration into the data weights and targets. Returns the number
    /// of correspondences and the RMS distances (m) mesh-to-points and (p2m only) points-to-mesh.
    fn correspond(
        &mut self,
        kind: CorrespondenceKind,
        iteration: usize,
    ) -> Result<(usize, f64, Option<f64>), RegisterError> {
        let f = &mut self.fit;
        f.work.vertices.copy_from_slice(&f.cur);
        let normals = vertex_normals(&f.work);
        let e = &self.params.energy;
        let h = e.curvature_correction.then(|| self.pool.install(|| shapes(&self.model.weights, &f.cur, &normals)));
        let (index, pruning, labels, cur) = (&self.index, &self.pruning, self.match_labels, &f.cur);
        let (targets, rms_m2p, rms_p2m) = match kind {
            CorrespondenceKind::M2p => {
                let (t, rms) = self.pool.install(|| index.m2p(cur, &normals, pruning, labels, h.as_deref()));
                (t, rms, None)
            }
            CorrespondenceKind::P2m => {
                // Warm start from the previous iteration when it was p2m too.
                let after_p2m = self.log.last().is_some_and(|l| l.kind == CorrespondenceKind::P2m);
                let warm =
                    (self.params.p2m_warm_start && after_p2m).then_some((&self.model.weights, f.p2m_vertex.as_slice()));
                let (t, rms, assigned) = self
                    .pool
                    .install(|| index.p2m(cur, &normals, pruning, labels, h.as_deref(), warm))
                    .map_err(NumericError::index)?;
                f.p2m_vertex = assigned;
                let m2p = self.pool.install(|| index.nearest(cur));
                let rms_m2p = (m2p.iter().map(|r| r.1).sum::<f64>() / cur.len() as f64).sqrt();
                (t, rms_m2p, Some(rms))
            }
        };
        let tw = match kind {
            CorrespondenceKind::M2p => e.tangential_weight,
            CorrespondenceKind::P2m => e.tangential_weight_p2m,
        };
        let n_corr = set_targets(&targets, tw, e.data_weight, &f.cur, &mut f.d, &mut f.q);
        if n_corr == 0 {
            return Err(NumericError::NoCorrespondences { iteration }.into());
        }
        if iteration < e.keypoint_iterations {
            self.input.keypoints.apply(
                &f.cur,
                e.keypoint_weight * e.data_weight,
                e.keypoint_robust_m,
                e.keypoint_axial,
                &mut f.d,
                &mut f.q,
            );
        }
        Ok((n_corr, rms_m2p, rms_p2m))
    }

    /// The local step (new cell maps) and, alongside it on the pool's other threads, the numeric
    /// refactorization of the global system for this iteration's data weights (it depends on the
    /// weights only, which the correspondences have set; the solver is sequential, so the two overlap
    /// without changing a bit of either). Returns the total energy after the local step and whether
    /// the system was refactorized.
    fn local_step_and_factorization(&mut self) -> Result<(f64, bool), RegisterError> {
        let (model, f, solver) = (&self.model, &mut self.fit, &mut self.solver);
        let (maps, cur, d) = (&mut f.maps, &f.cur, &f.d);
        let ((a_loc, r_loc), refactorized) =
            self.pool.install(|| rayon::join(|| model.local_step(cur, maps), || solver.set_data_weights(d)));
        let refactorized = refactorized.map_err(NumericError::solver)?;
        Ok((a_loc + r_loc + data_energy(&f.cur, &f.d, &f.q), refactorized))
    }

    /// The global solve for the new vertex positions (the system factorized for this iteration's
    /// data weights by [`Self::local_step_and_factorization`]). Returns the RMS displacement of the
    /// vertices (m).
    fn global_solve(&mut self, iteration: usize) -> Result<f64, RegisterError> {
        let (model, f) = (&self.model, &mut self.fit);
        self.pool.install(|| model.rhs(&f.maps, &mut f.rhs));
        for v in 0..f.cur.len() {
            for k in 0..3 {
                f.sol[(v, k)] = f.rhs[v][k] + f.d[v] * f.q[v][k];
            }
        }
        self.solver.solve_in_place(f.sol.as_mut()).map_err(NumericError::solver)?;
        let mut moved2 = 0.0;
        for (v, p) in f.cur.iter_mut().enumerate() {
            let new = [f.sol[(v, 0)], f.sol[(v, 1)], f.sol[(v, 2)]];
            let d = sub(new, *p);
            moved2 += dot(d, d);
            *p = new;
        }
        if f.cur.iter().any(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(NumericError::Diverged { iteration }.into());
        }
        Ok((moved2 / f.cur.len().max(1) as f64).sqrt())
    }

    /// Whether the fit has converged after an iteration of `stage` that moved the vertices by
    /// `motion` (RMS, m): in the schedule's last stage, after at least [`MIN_FINAL_ITERATIONS`] of
    /// its iterations, less than `stop_motion_mm`.
    fn converged(&self, stage: usize, motion: f64) -> bool {
        let last = self.params.schedule.0.len().saturating_sub(1);
        stage == last && self.cursor.done >= MIN_FINAL_ITERATIONS && motion * 1e3 < self.params.stop_motion_mm
    }

    /// The current vertex positions (the rest shape before the first step), metres.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.fit.cur
    }

    /// The log of the iterations run so far.
    pub fn log(&self) -> &[IterationLog] {
        &self.log
    }

    /// Whether every iteration of the schedule has run.
    pub fn is_done(&self) -> bool {
        let mut cursor = self.cursor;
        cursor.next(&self.params.schedule).is_none()
    }

    /// The prepared input being fitted.
    pub fn prepared(&self) -> &Prepared<'a> {
        &self.input
    }
}
