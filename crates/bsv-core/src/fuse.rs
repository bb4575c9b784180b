//! Cloud building from captured depth images (in progress).
