//! Mesh connectivity: undirected edges with their faces, boundary loops, vertex one-rings, components.

use std::collections::HashMap;

/// An undirected edge `(min, max)` and the faces that use it, with the direction each face runs it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdgeFaces {
    /// Faces using the edge, paired with `true` when the face runs it from `min` to `max`.
    pub faces: Vec<(u32, bool)>,
}

/// Per vertex (of `n_vertices`): whether it ends an edge shared by two faces `f`, `g` (face indices)
/// for which `crease(f, g)` holds, e.g. a sharp or folded edge judged by the faces' normals.
pub fn vertices_on_edges(
    n_vertices: usize,
    triangles: &[[u32; 3]],
    mut crease: impl FnMut(usize, usize) -> bool,
) -> Vec<bool> {
    let mut on = vec![false; n_vertices];
    for (&(a, b), e) in edge_map(triangles).iter() {
        if let [(f, _), (g, _)] = e.faces[..] {
            if crease(f as usize, g as usize) {
                on[a as usize] = true;
                on[b as usize] = true;
            }
        }
    }
    on
}

/// The undirected edge map of a triangle list: key `(min, max)` vertex ids.
pub fn edge_map(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), EdgeFaces> {
    let mut map: HashMap<(u32, u32), EdgeFaces> = HashMap::with_capacity(triangles.len() * 3 / 2 + 1);
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            map.entry(key).or_insert_with(|| EdgeFaces { faces: Vec::with_capacity(2) }).faces.push((f as u32, a < b));
        }
    }
    map
}

/// Boundary loops: closed chains of edges used by exactly one face, each in the direction its face runs
/// it (so a cap built on the loop with reversed winding closes the surface outward).
/// Edges that cannot be chained into loops (non-manifold boundary vertices) end their chain early.
pub fn boundary_loops(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let map = edge_map(triangles);
    // Directed boundary half-edges a -> b as the single face runs them.
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut edges: Vec<(u32, u32)> = map
        .iter()
        .filter(|(_, e)| e.faces.len() == 1)
        .map(|(&(lo, hi), e)| if e.faces[0].1 { (lo, hi) } else { (hi, lo) })
        .collect();
    edges.sort_unstable();
    for &(a, b) in &edges {
        next.entry(a).or_default().push(b);
    }
    let mut loops = Vec::new();
    for &(start, _) in &edges {
        while let Some(outs) = next.get_mut(&start) {
            let Some(first) = outs.pop() else { break };
            let mut chain = vec![start];
            let mut cur = first;
            while cur != start {
                chain.push(cur);
                match next.get_mut(&cur).and_then(|o| o.pop()) {
                    Some(n) => cur = n,
                    None => break,
                }
            }
            loops.push(chain);
        }
    }
    loops
}

/// Sorted, de-duplicated neighbour lists of every vertex (`n_vertices` entries).
pub fn vertex_neighbors(n_vertices: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n_vertices];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3]);
            if a < n_vertices && (b as usize) < n_vertices {
                nb[a].push(b);
                nb[b as usize].push(t[k]);
            }
        }
    }
    for l in &mut nb {
        l.sort_unstable();
        l.dedup();
    }
    nb
}

/// Connected components of faces (sharing an edge), as a component id per face and the count.
pub fn face_components(triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let map = edge_map(triangles);
    let mut parent: Vec<u32> = (0..triangles.len() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for e in map.values() {
        for w in e.faces.windows(2) {
            let (a, b) = (find(&mut parent, w[0].0), find(&mut parent, w[1].0));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut ids = HashMap::new();
    let comp: Vec<u32> = (0..triangles.len() as u32)
        .map(|f| {
            let r = find(&mut parent, f);
            let n = ids.len() as u32;
            *ids.entry(r).or_insert(n)
        })
        .collect();
    (comp, ids.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{cuboid, icosphere};

    #[test]
    fn closed_mesh_has_no_loops_and_one_component() {
        let m = icosphere(1.0, 2);
        assert!(boundary_loops(&m.triangles).is_empty());
        assert_eq!(face_components(&m.triangles).1, 1);
        assert!(edge_map(&m.triangles).values().all(|e| e.faces.len() == 2));
    }

    #[test]
    fn open_box_has_one_square_loop() {
        let mut m = cuboid([1.0, 1.0, 1.0]);
        m.triangles.truncate(10);
        let loops = boundary_loops(&m.triangles);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), 4);
        let nb = vertex_neighbors(m.n_vertices(), &m.triangles);
        assert!(nb.iter().all(|l| l.len() >= 3));
    }
}
