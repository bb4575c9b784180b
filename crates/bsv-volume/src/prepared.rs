//! Segment volumes of one mesh re-measured at many vertex positions: the topology work done once.
//!
//! [`crate::segment_volumes_with`] validates the mesh, builds its edge table, closes holes, picks and
//! island-merges the labels, finds the interface edges and chains them into pieces and junction
//! clusters, and only then reads the positions. When only the positions change (a calibration Monte
//! Carlo moves the vertices of one fitted mesh hundreds of times), [`PreparedSegments`] keeps the
//! first part and redoes only the second: the face tetrahedra, the apexes, hubs and hole centroids
//! (centroids of their vertices at the new positions), the volumes and the notes. Both use the same
//! functions of `segments`, so a prepared evaluation gives what `segment_volumes_with` gives on the
//! moved mesh, with the topology of the prepared one.
//!
//! What is fixed at preparation: the triangles, the labels after island merging, the pieces and the
//! clusters. Island merging ([`crate::merge_small_islands`]) reads positions only through its area
//! threshold (`IslandOptions::min_area_m2`, off in the default and in [`SegmentOptions::fitted`]):
//! with an area threshold the merged labels are those of the prepared (nominal) mesh, which is what a
//! re-measurement at positions moved by millimetres wants (a patch's area changes by far less than
//! any threshold margin), but may differ from `segment_volumes_with` on a mesh moved far enough to
//! carry a patch across the threshold.

use crate::closed::{hole_of, BoundaryLoop};
use crate::edges::check_finite;
use crate::labels::IslandReport;
use crate::report::{check_density, VolumeReport};
use crate::segments::{labelled, segment_volumes_at, Caps, LabelSource, SegmentOptions, SegmentVolumes};
use crate::VolumeError;
use bsv_core::TriMesh;
use rayon::prelude::*;
use std::borrow::Cow;

/// A labelled closed mesh prepared for re-measuring its segment volumes at new vertex positions
/// (same vertex count and order): [`PreparedSegments::evaluate`] on a vertex array gives the
/// [`SegmentVolumes`] that [`crate::segment_volumes_with`] gives on the mesh with those vertices.
/// See the module docs for what is fixed at preparation.
pub struct PreparedSegments {
    /// Vertex count of the input mesh (what every evaluation must pass).
    n_vertices: usize,
    /// Triangles of the closed mesh (hole fans appended, their apexes after the input's vertices).
    triangles: Vec<[u32; 3]>,
    /// One label per triangle of the closed mesh, islands merged when asked.
    labels: Vec<u8>,
    /// Where the labels came from.
    source: LabelSource,
    /// What island merging changed (at preparation).
    islands: Option<IslandReport>,
    /// Boundary loops closed by fans (only with `close_holes`).
    loops: Vec<BoundaryLoop>,
    /// The caps between segments.
    caps: Caps,
}

impl PreparedSegments {
    /// Prepares `mesh` with `opts`: validation, hole closing, labels and island merging, and the caps'
    /// topology. Fails as [`crate::segment_volumes_with`] fails on the same mesh.
    pub fn new(mesh: &TriMesh, opts: &SegmentOptions) -> Result<PreparedSegments, VolumeError> {
        let lab = labelled(mesh, opts)?;
        let caps = Caps::build(lab.closed.vertices.len(), &lab.table, &lab.labels);
        Ok(PreparedSegments {
            n_vertices: mesh.vertices.len(),
            triangles: lab.closed.triangles.clone(),
            labels: lab.labels,
            source: lab.source,
            islands: lab.islands,
            loops: lab.loops,
            caps,
        })
    }

    /// The vertex count every evaluation must pass (that of the prepared mesh).
    pub fn vertex_count(&self) -> usize {
        self.n_vertices
    }

    /// `Ok` when `n` is the prepared mesh's vertex count, else `VertexCountMismatch`.
    pub fn check_vertex_count(&self, n: usize) -> Result<(), VolumeError> {
        if n == self.n_vertices {
            Ok(())
        } else {
            Err(VolumeError::VertexCountMismatch { expected: self.n_vertices, got: n })
        }
    }

    /// The segment volumes with the vertices at `vertices` (the prepared mesh's vertices moved, same
    /// count and order). Errors: `VertexCountMismatch` for another count, `NonFiniteVertex` for a NaN
    /// or infinite coordinate.
    pub fn evaluate(&self, vertices: &[[f64; 3]]) -> Result<SegmentVolumes, VolumeError> {
        self.check_vertex_count(vertices.len())?;
        check_finite(vertices)?;
        let holes: Vec<_> = self.loops.iter().map(|l| hole_of(vertices, l)).collect();
        let closed: Cow<'_, [[f64; 3]]> = if holes.is_empty() {
            Cow::Borrowed(vertices)
        } else {
            Cow::Owned(vertices.iter().copied().chain(holes.iter().map(|h| h.centroid)).collect())
        };
        Ok(segment_volumes_at(&closed, &self.triangles, &self.labels, &self.caps, self.source, holes, self.islands))
    }

    /// [`PreparedSegments::evaluate`] on flat coordinates `x0 y0 z0 x1 y1 z1 ...` (one row of a C-ordered
    /// (N, 3) array). Errors: `CoordinatesNotTriples` for a length that is not a multiple of 3,
    /// `VertexCountMismatch` for another vertex count, and those of [`PreparedSegments::evaluate`].
    pub fn evaluate_coords(&self, coords: &[f64]) -> Result<SegmentVolumes, VolumeError> {
        if coords.len() % 3 != 0 {
            return Err(VolumeError::CoordinatesNotTriples { len: coords.len() });
        }
        self.check_vertex_count(coords.len() / 3)?;
        let vertices: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        self.evaluate(&vertices)
    }

    /// The volume report ([`VolumeReport::from_volumes`]) at a density (kg/m^3) with the vertices at
    /// `vertices`: what [`crate::report_with`] gives on the moved mesh.
    pub fn report(&self, vertices: &[[f64; 3]], density_kg_m3: f64) -> Result<VolumeReport, VolumeError> {
        check_density(density_kg_m3)?;
        VolumeReport::from_volumes(&self.evaluate(vertices)?, density_kg_m3)
    }

    /// [`PreparedSegments::evaluate`] on every vertex array of `draws`, in parallel (rayon); the results
    /// in the order of `draws`. On failure, the error of the first failing draw.
    pub fn evaluate_many<V: AsRef<[[f64; 3]]> + Sync>(&self, draws: &[V]) -> Result<Vec<SegmentVolumes>, VolumeError> {
        first_error(draws.par_iter().map(|v| self.evaluate(v.as_ref())).collect())
    }

    /// [`PreparedSegments::evaluate_coords`] on every coordinate array of `draws`, in parallel (rayon);
    /// the results in the order of `draws`. On failure, the error of the first failing draw.
    pub fn evaluate_many_coords<C: AsRef<[f64]> + Sync>(
        &self,
        draws: &[C],
    ) -> Result<Vec<SegmentVolumes>, VolumeError> {
        first_error(draws.par_iter().map(|c| self.evaluate_coords(c.as_ref())).collect())
    }

    /// The volume report ([`VolumeReport::from_volumes`]) at a density (kg/m^3) of every coordinate
    /// array of `draws` (as [`PreparedSegments::evaluate_coords`] takes them), in parallel, in order:
    /// per draw what [`crate::report_with`] gives on the moved mesh. An invalid density fails first.
    pub fn reports_many_coords<C: AsRef<[f64]> + Sync>(
        &self,
        draws: &[C],
        density_kg_m3: f64,
    ) -> Result<Vec<VolumeReport>, VolumeError> {
        check_density(density_kg_m3)?;
        first_error(
            draws
                .par_iter()
                .map(|c| VolumeReport::from_volumes(&self.evaluate_coords(c.as_ref())?, density_kg_m3))
                .collect(),
        )
    }

    /// [`PreparedSegments::reports_many_coords`] on a stack of `draws` vertex arrays of `vertices`
    /// vertices each, one after another in `coords` (a C-ordered (S, N, 3) array with S = `draws`,
    /// N = `vertices`). The vertex count is checked first, also for an empty stack
    /// (`VertexCountMismatch`), then the density, then the length (`StackLengthMismatch`).
    pub fn reports_stacked(
        &self,
        coords: &[f64],
        draws: usize,
        vertices: usize,
        density_kg_m3: f64,
    ) -> Result<Vec<VolumeReport>, VolumeError> {
        self.check_vertex_count(vertices)?;
        check_density(density_kg_m3)?;
        let per_draw = 3 * vertices;
        if draws.checked_mul(per_draw) != Some(coords.len()) {
            return Err(VolumeError::StackLengthMismatch { len: coords.len(), draws, vertices });
        }
        let rows: Vec<&[f64]> =
            if per_draw == 0 { vec![&[][..]; draws] } else { coords.chunks_exact(per_draw).collect() };
        self.reports_many_coords(&rows, density_kg_m3)
    }

    /// The [`QuantityTable`] of [`PreparedSegments::reports_stacked`]: per quantity
    /// ([`VolumeReport::quantities`]), its value in every draw.
    pub fn quantities_stacked(
        &self,
        coords: &[f64],
        draws: usize,
        vertices: usize,
        density_kg_m3: f64,
    ) -> Result<QuantityTable, VolumeError> {
        Ok(QuantityTable::of_reports(&self.reports_stacked(coords, draws, vertices, density_kg_m3)?))
    }
}

/// The quantities ([`VolumeReport::quantities`]) of many reports as columns: `names[j]`'s value in
/// report `i` is `columns[j][i]`, NaN where that report has no (finite) value for it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuantityTable {
    /// The quantity names, in first-seen order (report by report, each in its own order).
    pub names: Vec<String>,
    /// One column per name, one entry per report.
    pub columns: Vec<Vec<f64>>,
}

impl QuantityTable {
    /// The table of `reports` (no columns for none).
    pub fn of_reports(reports: &[VolumeReport]) -> QuantityTable {
        let mut table = QuantityTable::default();
        for (i, r) in reports.iter().enumerate() {
            for (k, v) in r.quantities() {
                let j = match table.names.iter().position(|n| n == k) {
                    Some(j) => j,
                    None => {
                        table.names.push(k.to_string());
                        table.columns.push(vec![f64::NAN; reports.len()]);
                        table.names.len() - 1
                    }
                };
                table.columns[j][i] = v;
            }
        }
        table
    }
}

/// The values, or the error of the first failing item (deterministic, whatever the threads did).
fn first_error<T>(results: Vec<Result<T, VolumeError>>) -> Result<Vec<T>, VolumeError> {
    results.into_iter().collect()
}
