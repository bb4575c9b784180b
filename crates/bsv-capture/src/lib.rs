//! BSV capture: everything between a depth camera and a labelled point cloud — the camera model,
//! the virtual two-camera scanner, cloud building from depth images (fuse), point-cloud cleaning
//! (statistical outlier removal, voxel down-sampling, k-NN distances) and uniform surface sampling.
//! The shared types (mesh, cloud, segment ids) and I/O live in `bsv_core`.

pub mod camera;
pub mod clean;
pub mod fuse;
pub mod sample;
pub mod scanner;
