//! BSV volumes: divergence-theorem volumes of closed meshes, segment labels on meshes, segment
//! volumes closed by shared caps (they add up to the whole exactly), aggregates, ratios, asymmetry,
//! mass, re-measurement of a prepared mesh at many vertex positions, and the volumes report (JSON of
//! DESIGN.md "Formats" and a readable table).
//!
//! Geometry is in metres and volumes in m^3 internally; reports are in litres.

pub mod closed;
mod edges;
pub mod error;
pub mod indices;
pub mod labels;
pub mod mass;
pub mod prepared;
pub mod report;
pub mod segments;

pub use closed::{close_holes, closed_volume, mesh_volume, tetra_sum, Hole, MeshVolume};
pub use error::VolumeError;
pub use indices::{aggregate, aggregates, asymmetries, asymmetry_pct, mass_kg, ratios, DEFAULT_DENSITY_KG_M3};
pub use labels::{
    face_label_from_corners, face_labels_from_vertices, merge_small_islands, vertex_labels_from_faces, IslandOptions,
    IslandReport,
};
pub use mass::{mass_properties, segment_mass_with, MassProperties, SegmentMass};
pub use prepared::{PreparedSegments, QuantityTable};
pub use report::{check_density, report, report_with, NamedValues, Units, VolumeReport};
pub use segments::{
    segment_volumes, segment_volumes_with, volumes_by_label, CapStats, Interface, LabelSource, LabelVolumes,
    SegmentOptions, SegmentVolumes,
};
