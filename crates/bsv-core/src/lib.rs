//! BSV core: the types every crate shares (triangle mesh, point cloud, segment ids), PLY/OBJ I/O,
//! mesh checks and repairs, geometry helpers, topology, templates, the one face/vertex label rule and
//! analytic test shapes. No capture (camera, scanner, cloud building, cleaning: `bsv_capture`),
//! registration or volume logic lives here.

pub mod check;
pub mod cloud;
pub mod geometry;
pub mod io;
pub mod labels;
pub mod mesh;
pub mod segment;
pub mod shapes;
pub mod template;
pub mod topology;

pub use cloud::PointCloud;
pub use mesh::{MeshInvariant, TriMesh};
pub use segment::{Aggregate, Segment, EXTREMITIES, PALETTE, SEGMENT_COUNT, TRUNK_LIMBS};
