//! Segment labels on a mesh: the merging of small label islands into their surroundings, and (re-
//! exported from [`bsv_core::labels`], the one rule each) face labels from vertex labels and vertex
//! labels from face labels.
//!
//! Tie rules (deterministic, independent of hash order or threads):
//! - face from vertices, vertex from faces: see [`bsv_core::labels`];
//! - island merging: an island takes the label it shares the most edges with; ties go to the smallest id.

pub use bsv_core::labels::{face_label_from_corners, face_labels_from_vertices, vertex_labels_from_faces};

use bsv_core::geometry::face_cross;
use bsv_core::TriMesh;

/// When a same-label connected patch of faces counts as a small island to merge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IslandOptions {
    /// Patches with fewer faces than this are islands (0 disables the face-count test).
    pub min_faces: usize,
    /// Patches with less area than this (m^2) are islands (0 disables the area test).
    pub min_area_m2: f64,
    /// Never merge the largest patch of each label (so a small but real segment such as a hand
    /// survives; only its stray fragments are merged).
    pub keep_largest: bool,
}

impl Default for IslandOptions {
    fn default() -> Self {
        IslandOptions { min_faces: 20, min_area_m2: 0.0, keep_largest: true }
    }
}

/// What `merge_small_islands` changed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IslandReport {
    /// Number of islands relabelled.
    pub merged_islands: usize,
    /// Number of faces whose label changed.
    pub relabelled_faces: usize,
    /// Passes run (components are recomputed after each pass).
    pub passes: usize,
}

/// Relabels small islands (connected same-label face patches below the thresholds) to the label they
/// share the most edges with, smallest islands first, repeating until none is left. An island with no
/// differently labelled neighbour (a whole component of the mesh) is left alone. Deterministic.
pub fn merge_small_islands(mesh: &TriMesh, face_labels: &mut [u8], opts: &IslandOptions) -> IslandReport {
    let mut report = IslandReport::default();
    let m = mesh.triangles.len().min(face_labels.len());
    if m == 0 || (opts.min_faces == 0 && opts.min_area_m2 <= 0.0) {
        return report;
    }
    let adj = FaceAdjacency::build(&mesh.triangles[..m]);
    let areas: Vec<f64> = (0..m)
        .map(|t| {
            if mesh.triangles[t].iter().all(|&v| (v as usize) < mesh.vertices.len()) {
                0.5 * bsv_core::geometry::norm(face_cross(mesh, t))
            } else {
                0.0
            }
        })
        .collect();
    // Each merge joins an island to a neighbour, so the number of patches falls: this terminates.
    loop {
        report.passes += 1;
        let patches = Patches::build(&adj, &face_labels[..m], &areas);
        let mut candidates: Vec<usize> = (0..patches.count())
            .filter(|&p| {
                let small = (opts.min_faces > 0 && patches.faces(p).len() < opts.min_faces)
                    || (opts.min_area_m2 > 0.0 && patches.area[p] < opts.min_area_m2);
                small && !(opts.keep_largest && patches.is_largest[p])
            })
            .collect();
        candidates.sort_by_key(|&p| (patches.faces(p).len(), patches.faces(p)[0]));
        let mut changed = false;
        for p in candidates {
            let faces = patches.faces(p);
            let own = face_labels[faces[0] as usize];
            if faces.iter().any(|&f| face_labels[f as usize] != own) {
                continue; // already absorbed in this pass through a neighbour's relabelling
            }
            let mut votes = [0usize; 256];
            for &f in faces {
                for &g in adj.neighbours(f as usize) {
                    let l = face_labels[g as usize];
                    if l != own {
                        votes[usize::from(l)] += 1;
                    }
                }
            }
            let mut best = own;
            let mut best_votes = 0;
            for (l, &v) in votes.iter().enumerate() {
                if v > best_votes {
                    best = l as u8;
                    best_votes = v;
                }
            }
            if best_votes == 0 {
                continue;
            }
            for &f in faces {
                face_labels[f as usize] = best;
            }
            report.merged_islands += 1;
            report.relabelled_faces += faces.len();
            changed = true;
        }
        if !changed {
            break;
        }
    }
    report
}

/// Face-to-face adjacency through shared edges (one entry per shared edge), in CSR form.
struct FaceAdjacency {
    start: Vec<usize>,
    list: Vec<u32>,
}

impl FaceAdjacency {
    fn build(triangles: &[[u32; 3]]) -> FaceAdjacency {
        let mut half: Vec<(u32, u32, u32)> = Vec::with_capacity(triangles.len() * 3);
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                half.push((a.min(b), a.max(b), f as u32));
            }
        }
        half.sort_unstable();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut i = 0;
        while i < half.len() {
            let mut j = i + 1;
            while j < half.len() && half[j].0 == half[i].0 && half[j].1 == half[i].1 {
                j += 1;
            }
            for w in half[i..j].windows(2) {
                if w[0].2 != w[1].2 {
                    pairs.push((w[0].2, w[1].2));
                    pairs.push((w[1].2, w[0].2));
                }
            }
            i = j;
        }
        pairs.sort_unstable();
        let mut start = vec![0usize; triangles.len() + 1];
        for &(a, _) in &pairs {
            start[a as usize + 1] += 1;
        }
        for k in 0..triangles.len() {
            start[k + 1] += start[k];
        }
        FaceAdjacency { start, list: pairs.into_iter().map(|p| p.1).collect() }
    }

    fn neighbours(&self, f: usize) -> &[u32] {
        &self.list[self.start[f]..self.start[f + 1]]
    }
}

/// Connected same-label patches of faces.
struct Patches {
    start: Vec<usize>,
    faces: Vec<u32>,
    area: Vec<f64>,
    is_largest: Vec<bool>,
}

impl Patches {
    fn build(adj: &FaceAdjacency, labels: &[u8], areas: &[f64]) -> Patches {
        let m = labels.len();
        let mut comp = vec![u32::MAX; m];
        let mut n = 0u32;
        let mut stack = Vec::new();
        let mut start = vec![0usize];
        let mut faces = Vec::with_capacity(m);
        let mut area = Vec::new();
        for seed in 0..m {
            if comp[seed] != u32::MAX {
                continue;
            }
            comp[seed] = n;
            stack.push(seed as u32);
            let first = faces.len();
            let mut a = 0.0;
            while let Some(f) = stack.pop() {
                faces.push(f);
                a += areas[f as usize];
                for &g in adj.neighbours(f as usize) {
                    if comp[g as usize] == u32::MAX && labels[g as usize] == labels[seed] {
                        comp[g as usize] = n;
                        stack.push(g);
                    }
                }
            }
            faces[first..].sort_unstable();
            start.push(faces.len());
            area.push(a);
            n += 1;
        }
        // Largest patch per label: most faces, then the smallest first face.
        let mut best: [Option<usize>; 256] = [None; 256];
        for p in 0..n as usize {
            let l = usize::from(labels[faces[start[p]] as usize]);
            let size = start[p + 1] - start[p];
            match best[l] {
                Some(q) if start[q + 1] - start[q] >= size => {}
                _ => best[l] = Some(p),
            }
        }
        let mut is_largest = vec![false; n as usize];
        for q in best.into_iter().flatten() {
            is_largest[q] = true;
        }
        Patches { start, faces, area, is_largest }
    }

    fn count(&self) -> usize {
        self.area.len()
    }

    fn faces(&self, p: usize) -> &[u32] {
        &self.faces[self.start[p]..self.start[p + 1]]
    }
}
