//! BSV capture: everything between a depth camera and a labelled point cloud — the camera model,
//! the virtual two-camera scanner (optionally inside a room), cloud building from depth images (fuse),
//! point-cloud cleaning (statistical outlier removal, voxel down-sampling, k-NN distances), exact
//! distances to a true surface, uniform surface sampling and the image-plane distances of the camera
//! segmentation (`planar`).
//! The shared types (mesh, cloud, segment ids) and I/O live in `bsv_core`.

pub mod camera;
pub mod clean;
pub mod distance;
pub mod fuse;
pub mod planar;
pub mod sample;
pub mod scanner;
