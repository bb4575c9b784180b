//! Point-cloud operations of the shared type: dropping segments.

#![allow(clippy::unwrap_used)]

use bsv_core::{PointCloud, Segment};

#[test]
fn drop_segments_removes_extremities() {
    let mut c = PointCloud::new((0..6).map(|i| [i as f64, 0.0, 0.0]).collect());
    c.labels = Some(vec![1, 2, 7, 9, 13, 2]);
    c.colors = Some(vec![[1, 1, 1], [2, 2, 2], [7, 7, 7], [9, 9, 9], [13, 13, 13], [2, 2, 2]]);
    let removed = c.drop_segments(&bsv_core::EXTREMITIES);
    assert_eq!(removed, 3);
    assert_eq!(c.labels.as_ref().unwrap(), &vec![2, 9, 2]);
    assert_eq!(c.colors.as_ref().unwrap()[1], [9, 9, 9]);
    assert_eq!(c.points[1], [3.0, 0.0, 0.0]);
    let mut unlabelled = PointCloud::new(vec![[0.0; 3]]);
    assert_eq!(unlabelled.drop_segments(&[Segment::Head]), 0);
}
