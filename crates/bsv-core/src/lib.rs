//! BSV core: the types every crate shares (triangle mesh, point cloud, segment ids), PLY/OBJ I/O,
//! mesh checks and repairs, geometry helpers, the camera model, point-cloud cleaning and the
//! virtual two-camera scanner. No registration or volume logic lives here.

pub mod camera;
pub mod check;
pub mod clean;
pub mod cloud;
pub mod fuse;
pub mod geometry;
pub mod io;
pub mod mesh;
pub mod scanner;
pub mod segment;
pub mod shapes;
pub mod template;
pub mod topology;

pub use cloud::PointCloud;
pub use mesh::TriMesh;
pub use segment::{Aggregate, Segment, EXTREMITIES, PALETTE, SEGMENT_COUNT, TRUNK_LIMBS};
