//! Stage 4 of a registration: the fitted mesh and its report (surface correction, final
//! distances, labels).

use super::Registrar;
use crate::error::{NumericError, RegisterError};
use crate::params::LabelSource;
use crate::result::Registration;
use crate::surface::surface_correction;
use bsv_core::{PointCloud, TriMesh};

impl Registrar<'_> {
    /// The [`Registration`] of the fit as it stands (normally after the last [`Self::step`]):
    /// the inscribed-mesh correction ([`crate::surface_correction`], when the parameter
    /// `surface_correction` is on), the final RMS distances and the labels of the fitted mesh.
    pub fn finish(self) -> Result<Registration, RegisterError> {
        let (pool, params, template) = (self.pool, self.params, self.input.template);
        let keypoints = self.input.keypoints.residuals(&self.fit.cur);
        // The last p2m iteration's vertex of every point starts the final points-to-mesh walk.
        let p2m_vertex = self.fit.p2m_vertex;
        let warm =
            (params.p2m_warm_start && !p2m_vertex.is_empty()).then_some((&self.model.weights, p2m_vertex.as_slice()));
        let mut cur = self.fit.cur;
        // Discretisation correction (see [`surface_correction`]).
        if params.surface_correction {
            cur = surface_correction(&cur, &template.triangles);
        }
        // Final distances and labels.
        let index = &self.index;
        let nearest = pool.install(|| index.nearest(&cur));
        let rms_m2p = (nearest.iter().map(|r| r.1).sum::<f64>() / cur.len() as f64).sqrt();
        let rms_p2m = pool.install(|| index.rms_points_to_mesh(&cur, warm)).map_err(NumericError::index)?;
        let mut mesh = TriMesh::new(cur, template.triangles.clone());
        let labels_from = set_labels(&mut mesh, &nearest, params.labels, &self.input.cloud, template);
        let quality = crate::quality::segment_quality(&mesh, &nearest, template);
        let input = self.input;
        Ok(Registration {
            mesh,
            log: self.log,
            prealign: input.similarity,
            setup_seconds: self.setup_seconds,
            total_seconds: input.started.elapsed().as_secs_f64(),
            rms_mesh_to_points_mm: rms_m2p * 1e3,
            rms_points_to_mesh_mm: rms_p2m * 1e3,
            labels_from,
            extremities_dropped: input.extremities_dropped,
            detached_removed: input.detached_removed,
            outliers_removed: input.outliers_removed,
            articulation: input.articulation,
            quality,
            keypoints,
        })
    }
}

/// Labels the fitted `mesh`: from the nearest cloud point of each vertex (`nearest`) with
/// [`LabelSource::Cloud`] and a labelled cloud, else the template's (its face labels too with
/// [`LabelSource::Template`]). Returns where the labels came from (`None`: no labels).
fn set_labels(
    mesh: &mut TriMesh,
    nearest: &[(u32, f64)],
    source: LabelSource,
    cloud: &PointCloud,
    template: &TriMesh,
) -> Option<LabelSource> {
    match (source, &cloud.labels) {
        (LabelSource::Cloud, Some(labels)) => {
            mesh.vertex_labels = Some(nearest.iter().map(|r| labels[r.0 as usize]).collect());
            Some(LabelSource::Cloud)
        }
        (LabelSource::Template, _) | (LabelSource::Cloud, None) => {
            mesh.vertex_labels = template.vertex_labels.clone();
            if source == LabelSource::Template {
                mesh.face_labels = template.face_labels.clone();
            }
            mesh.vertex_labels.as_ref().map(|_| LabelSource::Template)
        }
    }
}
