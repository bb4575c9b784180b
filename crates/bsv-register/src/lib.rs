//! BSV registration: warps a template mesh onto a (front + back, gappy) point cloud.
//!
//! Pipeline of [`register`]: input checks, head/hand/foot removal
//! ([`RegisterParams::drop_extremities`]), sparse-point (flying pixel) removal ([`outliers`]), the
//! similarity pre-alignment ([`prealign`]), the articulated initialisation of the limbs when the
//! template and the cloud are labelled ([`articulate`]; the articulated template is the rest
//! shape), the cotangent weights ([`cotan`]), the symbolic Cholesky analysis of the global system
//! ([`solver`]), then for each iteration of the schedule: correspondences ([`correspond`],
//! label-aware when both sides are labelled), the local step ([`local`], exact per-cell minimiser
//! of the regularized ARAP energy) and the global step (one sparse solve with the three coordinates
//! at once); finally the inscribed-mesh [`surface_correction`] and the labels. Energies, weights and
//! units are documented in [`params`] and [`local`].
//!
//! Accuracy on the synthetic cohort (benchmarks/tune_register.py, seed 5, subjects 0-5, oracle
//! labels, default 4,177-vertex template; mean signed / mean absolute volume error):
//!
//! | step                                  | noer trunk_limbs | noer worst segment | l515 trunk_limbs |
//! |---------------------------------------|------------------|--------------------|------------------|
//! | paper pipeline (before)               | -2.74 / 2.74 %   | forearm_l 26.2 %   | +6.38 / 6.85 %   |
//! | + label-aware correspondences         | -2.80 / 2.80 %   | forearm_l 26.9 %   | +5.85 / 6.46 %   |
//! | + articulated limbs (rigid)           | -2.13 / 2.13 %   | shin_l 8.8 %       | +9.78 / 10.3 %   |
//! | + sparse-point removal                | -2.19 / 2.19 %   | shin_l 9.0 %       | -1.16 / 1.16 %   |
//! | + limb ends aligned, surface correction | -0.46 / 0.46 % | forearm_l 1.87 %   | +0.03 / 0.63 %   |
//!
//! (Row 4 on subjects 0-3.) A gap-free sampling of the same bodies gave the same
//! -2 % before the last step: the lateral gaps were not the cause; short limb ends and the
//! inscribed-polygon bias of a coarse mesh were.

pub mod articulate;
pub mod correspond;
pub mod cotan;
pub mod error;
pub mod local;
pub mod outliers;
pub mod params;
pub mod prealign;
pub mod solver;

pub use error::RegisterError;
pub use params::{
    CorrespondenceKind, Energy, IterationLog, LabelSource, PrealignMode, RegisterParams, Schedule, Stage, Timings,
    YawMode, DEFAULT_SCHEDULE,
};
pub use prealign::Similarity;

use bsv_core::geometry::{add, dot, scale, sub, total_area, vertex_normals};
use bsv_core::{PointCloud, TriMesh};
use correspond::{CloudIndex, Pruning};
use local::{CellMaps, LocalModel};
use serde::Serialize;
use std::time::Instant;

/// The result of a registration.
#[derive(Debug, Clone, Serialize)]
pub struct Registration {
    /// The fitted mesh: fitted vertices, the template's triangles, vertex labels (from the cloud, or
    /// the template's), face labels only in template-label mode.
    #[serde(skip)]
    pub mesh: TriMesh,
    /// One entry per iteration.
    pub log: Vec<IterationLog>,
    /// The pre-alignment used.
    pub prealign: Similarity,
    /// Checks, pre-alignment, weights, k-d tree and symbolic factorization, seconds.
    pub setup_seconds: f64,
    /// Whole registration, seconds.
    pub total_seconds: f64,
    /// RMS distance from the fitted vertices to their nearest cloud point, mm.
    pub rms_mesh_to_points_mm: f64,
    /// RMS distance from the cloud points to their nearest fitted vertex, mm.
    pub rms_points_to_mesh_mm: f64,
    /// Where the vertex labels came from (`None` when the mesh has no labels).
    pub labels_from: Option<LabelSource>,
    /// Head/hand/foot cloud points dropped before the fit ([`RegisterParams::drop_extremities`]).
    pub extremities_dropped: usize,
    /// Cloud points dropped as sparse outliers (see [`outliers`]).
    pub outliers_removed: usize,
    /// The limbs moved by the articulated initialisation (empty when it did not run).
    pub articulation: Vec<LimbAlignment>,
}

/// One limb of the articulated initialisation (see [`articulate`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LimbAlignment {
    /// Segment id.
    pub label: u8,
    /// Angle between the template's and the cloud's limb axes, degrees.
    pub angle_deg: f64,
    /// Scale applied along the axis.
    pub axial_scale: f64,
    /// Distance between the template's and the cloud's segment centroids (after the global
    /// pre-alignment), mm.
    pub shift_mm: f64,
}

/// The inscribed-mesh correction: with its vertices on a smooth surface, a triangle mesh lies
/// inside the surface between its vertices, by `h^2 H / 8` on average over a face (edge length
/// `h`, mean curvature `H`; for a paraboloid over an equilateral triangle of circumradius `rho`
/// the mean gap is `3 rho^2 H / 8` with `rho^2 = h^2 / 3`), so its volume is biased low (-2 to -5 %
/// on a 4k-vertex body template's limbs). Moving each vertex out by that gap along its normal
/// makes the faces straddle the surface. With cotangent weights `w_ij`,
/// `sum_j w_ij (x_i - x_j) = 2 A_i H n_i` (`A_i` the vertex area, `sqrt(3)/2 h^2` on a regular mesh),
/// hence the displacement `sum_j w_ij (x_i - x_j) / (8 sqrt(3))`. Measured (unit test): icosphere
/// levels 2/3/4 and a 16-around capsule keep under 10 % of their inscribed volume deficit.
///
/// Vertices on a sharp edge (dihedral angle between face normals above 40 degrees: a box's edges,
/// the rims of the caps that close a template at the neck, wrists and ankles) are not moved: there
/// the surface itself has the edge and the vertices lie on it.
pub fn surface_correction(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let w = cotan::CotanWeights::new(vertices, triangles);
    let fnorm: Vec<[f64; 3]> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| vertices[v as usize]);
            bsv_core::geometry::normalize(bsv_core::geometry::cross(sub(b, a), sub(c, a)))
        })
        .collect();
    let min_cos = 40f64.to_radians().cos();
    let mut sharp = vec![false; vertices.len()];
    for (&(a, b), e) in bsv_core::topology::edge_map(triangles).iter() {
        if let [(f, _), (g, _)] = e.faces[..] {
            if dot(fnorm[f as usize], fnorm[g as usize]) < min_cos {
                sharp[a as usize] = true;
                sharp[b as usize] = true;
            }
        }
    }
    let c = 1.0 / (8.0 * 3f64.sqrt());
    (0..vertices.len())
        .map(|i| {
            if sharp[i] {
                return vertices[i];
            }
            let (nb, wij) = w.row(i);
            let mut d = [0.0; 3];
            for (&j, &x) in nb.iter().zip(wij) {
                let e = sub(vertices[i], vertices[j as usize]);
                for k in 0..3 {
                    d[k] += x * e[k];
                }
            }
            add(vertices[i], scale(d, c))
        })
        .collect()
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

/// Registers `template` onto `cloud` (metres, shared world frame). Calls `progress` after every
/// iteration. Never panics on user data: every failure is a [`RegisterError`].
pub fn register(
    template: &TriMesh,
    cloud: &PointCloud,
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Registration, RegisterError> {
    params.validate()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(params.threads)
        .build()
        .map_err(|e| RegisterError::ThreadPool { threads: params.threads, reason: e.to_string() })?;
    register_in_pool(&pool, template, cloud, params, progress)
}

/// The registration proper: parallel parts run in `pool`, `progress` is called on this thread.
fn register_in_pool(
    pool: &rayon::ThreadPool,
    template: &TriMesh,
    cloud: &PointCloud,
    params: &RegisterParams,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Registration, RegisterError> {
    let start = Instant::now();
    // Checks.
    let template_box = prealign::check_template(template)?;
    // Head/hand/foot points (the paper drops them: poorly captured, not measured).
    let without_extremities;
    let mut extremities_dropped = 0;
    let is_extremity = |l: &u8| bsv_core::EXTREMITIES.iter().any(|s| s.id() == *l);
    let cloud = match &cloud.labels {
        Some(labels) if params.drop_extremities && labels.len() != cloud.points.len() => {
            return Err(RegisterError::LengthMismatch {
                what: "cloud labels",
                got: labels.len(),
                expected: cloud.points.len(),
            });
        }
        Some(labels) if params.drop_extremities && labels.iter().any(is_extremity) => {
            let mut c = cloud.clone();
            extremities_dropped = c.drop_segments(&bsv_core::EXTREMITIES);
            if c.points.is_empty() {
                return Err(RegisterError::OnlyExtremities { n: extremities_dropped });
            }
            without_extremities = c;
            &without_extremities
        }
        _ => cloud,
    };
    let cloud_box = prealign::check_cloud(cloud, params)?;
    // Sparse-point removal (flying pixels trail behind the silhouettes, right where the
    // gaps are, and would attract the gap-side vertices).
    let filtered;
    let mut outliers_removed;
    let keep = outliers::sparse_points(&cloud.points, params.outlier_voxel_m, params.outlier_min_fraction);
    outliers_removed = keep.iter().filter(|&&k| !k).count();
    let cloud = if outliers_removed > 0 && cloud.points.len() - outliers_removed >= params.min_points.max(1) {
        let mut c = cloud.clone();
        c.retain_indices(|i| keep[i]);
        filtered = c;
        &filtered
    } else {
        outliers_removed = 0;
        cloud
    };
    if params.labels == LabelSource::Template && template.vertex_labels.is_none() {
        return Err(RegisterError::TemplateWithoutLabels);
    }
    // Pre-alignment.
    let sim = prealign::prealign(&template.vertices, &template_box, &cloud.points, &cloud_box, params)
        .map_err(RegisterError::Index)?;
    let mut rest: Vec<[f64; 3]> = template.vertices.iter().map(|&p| sim.apply(p)).collect();
    // Articulated initialisation (labelled template and cloud).
    let mut articulation = Vec::new();
    if let (true, Some(cl), Some(tl)) = (params.articulate, &cloud.labels, &template.vertex_labels) {
        let poses = articulate::segment_poses(&rest, tl, &cloud.points, cl, params.articulate_axial_scale);
        if !poses.is_empty() {
            let w0 = cotan::CotanWeights::new(&rest, &template.triangles);
            rest = articulate::articulate(&rest, tl, &poses, &w0, params.articulate_smooth_iterations);
            articulation = poses
                .iter()
                .map(|p| LimbAlignment {
                    label: p.label,
                    angle_deg: p.angle_deg,
                    axial_scale: p.axial_scale,
                    shift_mm: bsv_core::geometry::dist2(p.cloud_centroid, p.template_centroid).sqrt() * 1e3,
                })
                .collect();
        }
    }
    let n = rest.len();
    let area = total_area(&TriMesh::new(rest.clone(), template.triangles.clone()));
    let lambda = params.alpha * 1e-6 * params.cell_weight * area / n as f64;
    // Weights, solver, local model, cloud index.
    let weights = cotan::CotanWeights::new(&rest, &template.triangles);
    let (solver, index) = pool.install(|| {
        rayon::join(
            || solver::GlobalSolver::new(&weights, params.cell_weight),
            || CloudIndex::new(&cloud.points, cloud.normals.as_deref(), params.estimate_normals_k),
        )
    });
    let mut solver = solver.map_err(RegisterError::Solver)?;
    let mut index = index.map_err(RegisterError::Index)?;
    // Label-aware matching when both sides are labelled.
    let match_labels: Option<&[u8]> = match (&cloud.labels, &template.vertex_labels) {
        (Some(cl), Some(tl)) if params.label_aware => {
            let matched = index.with_labels(cl, tl).map_err(RegisterError::Index)?;
            (matched > 0).then_some(tl.as_slice())
        }
        _ => None,
    };
    let model = pool.install(|| LocalModel::new(rest.clone(), weights, params.cell_weight, lambda));
    let pruning = Pruning {
        distance_factor: params.prune_distance_factor,
        distance_floor: params.prune_distance_floor_m,
        min_cos: if params.prune_normal_angle_deg >= 180.0 {
            -1.0
        } else {
            params.prune_normal_angle_deg.to_radians().cos()
        },
    };
    let setup_seconds = start.elapsed().as_secs_f64();

    let mut work = TriMesh::new(rest, template.triangles.clone());
    let mut cur = work.vertices.clone();
    let mut maps = CellMaps::identity(n);
    let mut d = vec![0.0; n];
    let mut q = vec![[0.0; 3]; n];
    let mut rhs = vec![[0.0; 3]; n];
    let mut sol = faer::Mat::<f64>::zeros(n, 3);
    let (mut arap, mut reg) = (0.0, 0.0);
    let mut log = Vec::with_capacity(params.schedule.total_iterations());
    let mut iteration = 0;
    for (si, stage) in params.schedule.0.iter().enumerate() {
        for _ in 0..stage.iterations {
            let t0 = Instant::now();
            work.vertices.copy_from_slice(&cur);
            let normals = vertex_normals(&work);
            let (targets, rms_m2p, rms_p2m) = match stage.kind {
                CorrespondenceKind::M2p => {
                    let (t, rms) = pool.install(|| index.m2p(&cur, &normals, &pruning, match_labels));
                    (t, rms, None)
                }
                CorrespondenceKind::P2m => {
                    let (t, rms) = pool.install(|| index.p2m(&cur, &normals, &pruning, match_labels)).map_err(RegisterError::Index)?;
                    let m2p = pool.install(|| index.nearest(&cur));
                    let rms_m2p = (m2p.iter().map(|r| r.1).sum::<f64>() / n as f64).sqrt();
                    (t, rms_m2p, Some(rms))
                }
            };
            let tw = match stage.kind {
                CorrespondenceKind::M2p => params.tangential_weight,
                CorrespondenceKind::P2m => params.tangential_weight_p2m,
            };
            let mut n_corr = 0;
            for (v, t) in targets.iter().enumerate() {
                match t {
                    Some(res) => {
                        // Keep the normal part of the residual and a fraction of the tangential one.
                        let tangential = sub(res.offset, res.normal_part);
                        q[v] = add(cur[v], add(res.normal_part, scale(tangential, tw)));
                        d[v] = params.data_weight;
                        n_corr += 1;
                    }
                    None => {
                        d[v] = 0.0;
                        q[v] = cur[v];
                    }
                }
            }
            if n_corr == 0 {
                return Err(RegisterError::NoCorrespondences { iteration });
            }
            let energy_start = arap + reg + data_energy(&cur, &d, &q);
            let t1 = Instant::now();
            let (a_loc, r_loc) = pool.install(|| model.local_step(&cur, &mut maps));
            let energy_after_local = a_loc + r_loc + data_energy(&cur, &d, &q);
            let t2 = Instant::now();
            let refactorized = solver.set_data_weights(&d).map_err(RegisterError::Solver)?;
            pool.install(|| model.rhs(&maps, &mut rhs));
            for v in 0..n {
                for k in 0..3 {
                    sol[(v, k)] = rhs[v][k] + d[v] * q[v][k];
                }
            }
            solver.solve_in_place(sol.as_mut()).map_err(RegisterError::Solver)?;
            for (v, p) in cur.iter_mut().enumerate() {
                *p = [sol[(v, 0)], sol[(v, 1)], sol[(v, 2)]];
            }
            if cur.iter().any(|p| p.iter().any(|x| !x.is_finite())) {
                return Err(RegisterError::Diverged { iteration });
            }
            let t3 = Instant::now();
            (arap, reg) = pool.install(|| model.energy(&cur, &maps));
            let data = data_energy(&cur, &d, &q);
            let entry = IterationLog {
                stage: si,
                iteration,
                kind: stage.kind,
                energy_start,
                energy_after_local,
                energy: Energy { arap, reg, data, total: arap + reg + data },
                rms_mesh_to_points_mm: rms_m2p * 1e3,
                rms_points_to_mesh_mm: rms_p2m.map(|r| r * 1e3),
                n_correspondences: n_corr,
                refactorized,
                timings: Timings {
                    correspond: (t1 - t0).as_secs_f64(),
                    local: (t2 - t1).as_secs_f64(),
                    solve: (t3 - t2).as_secs_f64(),
                },
            };
            progress(&entry);
            log.push(entry);
            iteration += 1;
        }
    }

    // Discretisation correction (see [`surface_correction`]).
    if params.surface_correction {
        cur = surface_correction(&cur, &template.triangles);
    }
    // Final distances and labels.
    let nearest = pool.install(|| index.nearest(&cur));
    let rms_m2p = (nearest.iter().map(|r| r.1).sum::<f64>() / n as f64).sqrt();
    let rms_p2m = pool.install(|| index.rms_points_to_mesh(&cur)).map_err(RegisterError::Index)?;
    let mut mesh = TriMesh::new(cur, template.triangles.clone());
    let labels_from = match (params.labels, &cloud.labels) {
        (LabelSource::Cloud, Some(labels)) => {
            mesh.vertex_labels = Some(nearest.iter().map(|r| labels[r.0 as usize]).collect());
            Some(LabelSource::Cloud)
        }
        (LabelSource::Template, _) | (LabelSource::Cloud, None) => {
            mesh.vertex_labels = template.vertex_labels.clone();
            if params.labels == LabelSource::Template {
                mesh.face_labels = template.face_labels.clone();
            }
            mesh.vertex_labels.as_ref().map(|_| LabelSource::Template)
        }
    };
    Ok(Registration {
        mesh,
        log,
        prealign: sim,
        setup_seconds,
        total_seconds: start.elapsed().as_secs_f64(),
        rms_mesh_to_points_mm: rms_m2p * 1e3,
        rms_points_to_mesh_mm: rms_p2m * 1e3,
        labels_from,
        extremities_dropped,
        outliers_removed,
        articulation,
    })
}

#[cfg(test)]
mod tests {
    use bsv_core::geometry::signed_volume;
    use bsv_core::shapes::{capsule, icosphere};

    #[test]
    fn surface_correction_removes_the_inscribed_volume_deficit() {
        for level in [2, 3, 4] {
            let s = icosphere(1.0, level);
            let truth = 4.0 / 3.0 * std::f64::consts::PI;
            let before = signed_volume(&s.vertices, &s.triangles) / truth - 1.0;
            let v = super::surface_correction(&s.vertices, &s.triangles);
            let after = signed_volume(&v, &s.triangles) / truth - 1.0;
            println!("icosphere level {level}: {:.3} % -> {:.3} %", before * 100.0, after * 100.0);
            assert!(after.abs() < 0.1 * before.abs(), "{before} -> {after}");
        }
        // A capsule (cylinder + hemispheres) with 16 segments around.
        let (r, l) = (0.03, 0.25);
        let c = capsule(r, l, 16, 8, 24);
        let truth = std::f64::consts::PI * r * r * l + 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        let before = signed_volume(&c.vertices, &c.triangles) / truth - 1.0;
        let v = super::surface_correction(&c.vertices, &c.triangles);
        let after = signed_volume(&v, &c.triangles) / truth - 1.0;
        println!("capsule 16 around: {:.3} % -> {:.3} %", before * 100.0, after * 100.0);
        assert!(after.abs() < 0.5 * before.abs(), "{before} -> {after}");
    }
}
