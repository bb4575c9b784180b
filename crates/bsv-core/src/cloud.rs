//! The point cloud type shared by every crate.

use crate::Segment;

/// A point cloud in metres with optional normals, colours and segment labels.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// Point positions, metres, world frame.
    pub points: Vec<[f64; 3]>,
    /// Optional unit normals (same length as `points`).
    pub normals: Option<Vec<[f64; 3]>>,
    /// Optional sRGB colours (same length as `points`).
    pub colors: Option<Vec<[u8; 3]>>,
    /// Optional segment ids (same length as `points`).
    pub labels: Option<Vec<u8>>,
}

impl PointCloud {
    /// A cloud of bare points.
    pub fn new(points: Vec<[f64; 3]>) -> Self {
        PointCloud { points, normals: None, colors: None, labels: None }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud has no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Keeps the points for which `keep(i)` is true, with their attributes.
    pub fn retain_indices(&mut self, mut keep: impl FnMut(usize) -> bool) {
        let mask: Vec<bool> = (0..self.points.len()).map(&mut keep).collect();
        fn filter<T: Copy>(v: &mut Vec<T>, mask: &[bool]) {
            let mut i = 0;
            v.retain(|_| {
                let k = mask[i];
                i += 1;
                k
            });
        }
        filter(&mut self.points, &mask);
        if let Some(n) = self.normals.as_mut() {
            filter(n, &mask);
        }
        if let Some(c) = self.colors.as_mut() {
            filter(c, &mask);
        }
        if let Some(l) = self.labels.as_mut() {
            filter(l, &mask);
        }
    }

    /// Removes the points whose label is one of `segments` (no-op for an unlabelled cloud), with their
    /// attributes; returns the number removed.
    pub fn drop_segments(&mut self, segments: &[Segment]) -> usize {
        let Some(labels) = self.labels.clone() else {
            return 0;
        };
        let before = self.len();
        self.retain_indices(|i| !segments.iter().any(|s| s.id() == labels[i]));
        before - self.len()
    }
}
