//! The one rule each for moving segment labels between faces and vertices (every crate and the
//! Python package call these; no other copy exists).
//!
//! Tie rules (deterministic, independent of hash order or threads):
//! - face from vertices: the label shared by at least two corners; when the three corners all differ,
//!   the label of the corner with the smallest vertex index;
//! - vertex from faces: the most common label among the incident faces; ties go to the smallest id
//!   ([`most_common`], also the vote of the hole caps in `bsv-volume`).

/// Label of a face from its three corners' labels: the label shared by at least two corners; when
/// all three differ, the FIRST corner's label. On a mesh, pass the corners starting at the one with
/// the smallest vertex index (as [`face_labels_from_vertices`] does), so that the tie goes to that
/// corner whatever the triangle's rotation.
pub fn face_label_from_corners(l: [u8; 3]) -> u8 {
    if l[0] == l[1] || l[0] == l[2] {
        l[0]
    } else if l[1] == l[2] {
        l[1]
    } else {
        l[0]
    }
}

/// Face labels from vertex labels: majority of the three corners (see the module's tie rule).
/// Triangles with an out-of-range corner get label 0.
pub fn face_labels_from_vertices(triangles: &[[u32; 3]], vertex_labels: &[u8]) -> Vec<u8> {
    triangles
        .iter()
        .map(|t| {
            // Rotate (orientation kept) so that the smallest vertex index comes first.
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            let l = |j: usize| vertex_labels.get(t[(k + j) % 3] as usize).copied();
            let (Some(a), Some(b), Some(c)) = (l(0), l(1), l(2)) else { return 0 };
            face_label_from_corners([a, b, c])
        })
        .collect()
}

/// Vertex labels from face labels: the most common label of the incident faces (ties: smallest id);
/// vertices used by no face get 0. Out-of-range corners are ignored.
pub fn vertex_labels_from_faces(n_vertices: usize, triangles: &[[u32; 3]], face_labels: &[u8]) -> Vec<u8> {
    let mut pairs: Vec<(u32, u8)> = Vec::with_capacity(triangles.len() * 3);
    for (t, &l) in triangles.iter().zip(face_labels) {
        for &v in t {
            if (v as usize) < n_vertices {
                pairs.push((v, l));
            }
        }
    }
    pairs.sort_unstable();
    let mut out = vec![0u8; n_vertices];
    let mut i = 0;
    while i < pairs.len() {
        let v = pairs[i].0;
        let (mut best, mut best_count) = (0u8, 0usize);
        while i < pairs.len() && pairs[i].0 == v {
            let l = pairs[i].1;
            let mut j = i;
            while j < pairs.len() && pairs[j] == (v, l) {
                j += 1;
            }
            // Labels come in increasing order, so `>` keeps the smallest id on ties.
            if j - i > best_count {
                best = l;
                best_count = j - i;
            }
            i = j;
        }
        out[v as usize] = best;
    }
    out
}

/// The most common label of `labels` (ties: the smallest id; 0 for none): the vertex rule's vote,
/// also used for the labels of hole caps (`bsv-volume`).
pub fn most_common(labels: &[u8]) -> u8 {
    let mut counts = [0usize; 256];
    for &l in labels {
        counts[usize::from(l)] += 1;
    }
    let mut best = 0usize;
    for (l, &c) in counts.iter().enumerate() {
        if c > counts[best] {
            best = l;
        }
    }
    best as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn majority_and_ties() {
        assert_eq!(face_label_from_corners([3, 3, 5]), 3);
        assert_eq!(face_label_from_corners([5, 3, 3]), 3);
        assert_eq!(face_label_from_corners([3, 5, 3]), 3);
        assert_eq!(face_label_from_corners([9, 3, 5]), 9);
        // All differ: the corner with the smallest vertex index, whatever the rotation.
        let vl = [7, 2, 4];
        for t in [[0, 1, 2], [1, 2, 0], [2, 0, 1]] {
            assert_eq!(face_labels_from_vertices(&[t], &vl), vec![7]);
        }
        assert_eq!(face_labels_from_vertices(&[[0, 1, 9]], &vl), vec![0]);
        // Vertex 0: faces 1, 2, 2 -> 2; vertex 1: faces 1, 2 -> tie -> 1; vertex 3: unused -> 0.
        let tris = [[0, 1, 2], [0, 2, 1], [0, 2, 1]];
        assert_eq!(vertex_labels_from_faces(4, &tris, &[1, 2, 2]), vec![2, 2, 2, 0]);
        assert_eq!(vertex_labels_from_faces(3, &tris[..2], &[2, 1]), vec![1, 1, 1]);
        assert_eq!(most_common(&[4, 2, 4, 2]), 2);
        assert_eq!(most_common(&[5, 5, 1]), 5);
        assert_eq!(most_common(&[]), 0);
    }
}
