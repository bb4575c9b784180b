//! Image-plane geometry of the camera segmentation: the distance from every labelled pixel to the
//! nearest of a group of 2-D line segments (the "bones" between MediaPipe landmarks, or a polygon's
//! edges). `bsv.frontend.segment.label_pixels` assigns each pixel of the person to the nearest bone
//! group; this is the exact distance it compares, computed for ~70k pixels and ~60 bones per image.

use rayon::prelude::*;

/// Below this squared length (pixels²) a segment is its first end point.
const DEGENERATE_LEN2: f64 = 1e-12;

/// Points per parallel task.
const CHUNK: usize = 4096;

/// Distance from `p` to the line segment `[ax, ay, bx, by]`: to the nearest point of the segment, its
/// parameter along a→b clamped to [0, 1] (a segment shorter than 1e-6 px is its point `a`).
pub fn segment_distance(p: [f64; 2], s: [f64; 4]) -> f64 {
    let (ax, ay) = (s[0], s[1]);
    let (abx, aby) = (s[2] - ax, s[3] - ay);
    let den = abx * abx + aby * aby;
    let t = if den <= DEGENERATE_LEN2 { 0.0 } else { (((p[0] - ax) * abx + (p[1] - ay) * aby) / den).clamp(0.0, 1.0) };
    (p[0] - (ax + t * abx)).hypot(p[1] - (ay + t * aby))
}

/// For every point, the distance to the nearest of `segments` (each `[ax, ay, bx, by]`); infinity when
/// there are none. Parallel over the points; the result does not depend on the number of threads. A
/// segment with a NaN coordinate is never the nearest (`f64::min` skips NaN), and a NaN point gets
/// infinity: the callers pass finite landmarks and pixel centres.
pub fn nearest_segment_distances(points: &[[f64; 2]], segments: &[[f64; 4]]) -> Vec<f64> {
    let mut out = vec![f64::INFINITY; points.len()];
    out.par_chunks_mut(CHUNK).zip(points.par_chunks(CHUNK)).for_each(|(d, p)| {
        for (di, &pi) in d.iter_mut().zip(p) {
            for &s in segments {
                *di = di.min(segment_distance(pi, s));
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_a_segment_its_ends_and_a_point() {
        let s = [0.0, 0.0, 10.0, 0.0];
        assert_eq!(segment_distance([5.0, 3.0], s), 3.0); // beside the middle
        assert_eq!(segment_distance([-3.0, 4.0], s), 5.0); // past a: to a
        assert_eq!(segment_distance([13.0, -4.0], s), 5.0); // past b: to b
        assert_eq!(segment_distance([4.0, 3.0], [1.0, -1.0, 1.0, -1.0]), 5.0); // a point
    }

    #[test]
    fn the_nearest_of_several_and_none() {
        let segs = [[0.0, 0.0, 0.0, 10.0], [10.0, 0.0, 10.0, 10.0]];
        let pts: Vec<[f64; 2]> = (0..10_000).map(|i| [f64::from(i % 11), f64::from(i % 7)]).collect();
        let d = nearest_segment_distances(&pts, &segs);
        for (p, d) in pts.iter().zip(&d) {
            assert_eq!(*d, p[0].min(10.0 - p[0]));
        }
        assert!(nearest_segment_distances(&[[1.0, 2.0]], &[]).iter().all(|d| d.is_infinite()));
    }
}
