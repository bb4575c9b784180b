//! Volume of a closed triangle mesh by the divergence theorem, and closing of holes by centroid fans.

use crate::edges::{det6, used_centroid, validate, EdgeTable};
use crate::VolumeError;
use bsv_core::geometry::{add, dist2, scale};
use bsv_core::labels::most_common;
use bsv_core::TriMesh;
use std::borrow::Cow;

/// How many loop centroids an `OpenMesh` error lists.
const LISTED_LOOPS: usize = 3;

/// A hole closed by a fan of triangles from its boundary loop to the loop's centroid.
#[derive(Debug, Clone, PartialEq)]
pub struct Hole {
    /// Centroid of the loop's vertices (the fan apex), metres.
    pub centroid: [f64; 3],
    /// Number of boundary edges in the loop.
    pub edges: usize,
    /// Loop length, metres.
    pub perimeter_m: f64,
}

/// The enclosed volume of a mesh and the holes closed to get it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshVolume {
    /// Signed enclosed volume, m^3 (positive for outward-facing triangles).
    pub volume_m3: f64,
    /// Holes that were closed (empty for a closed mesh).
    pub holes: Vec<Hole>,
}

/// Signed volume (m^3) of a closed, edge-manifold, consistently oriented mesh; an open mesh is an error.
pub fn closed_volume(mesh: &TriMesh) -> Result<f64, VolumeError> {
    Ok(mesh_volume(mesh, false)?.volume_m3)
}

/// Signed volume (m^3) of a mesh; with `close_holes` each boundary loop is first fanned to its centroid,
/// otherwise an open mesh is a `VolumeError::OpenMesh` saying how many loops it has and where.
pub fn mesh_volume(mesh: &TriMesh, close_holes: bool) -> Result<MeshVolume, VolumeError> {
    let (closed, holes, _) = prepare(mesh, close_holes)?;
    Ok(MeshVolume { volume_m3: tetra_sum(&closed.vertices, &closed.triangles), holes })
}

/// Divergence-theorem volume: signed tetrahedra summed relative to the centroid of the used vertices
/// (the result does not depend on that point for a closed mesh; it keeps round-off small).
pub fn tetra_sum(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    let r = used_centroid(vertices, triangles);
    triangles
        .iter()
        .map(|&[a, b, c]| det6(r, vertices[a as usize], vertices[b as usize], vertices[c as usize]))
        .sum::<f64>()
        / 6.0
}

/// A copy of the mesh with every hole closed by a fan to its loop centroid (one new vertex per loop),
/// and the holes closed. Cap faces take the most common face label along the loop, the new vertex the
/// most common vertex label of the loop (ties: smallest id). A closed mesh is returned unchanged.
pub fn close_holes(mesh: &TriMesh) -> Result<(TriMesh, Vec<Hole>), VolumeError> {
    let (closed, holes, _) = prepare(mesh, true)?;
    Ok((closed.into_owned(), holes))
}

/// A boundary loop: its half-edges `(from, to, face)` in walking order.
pub(crate) type BoundaryLoop = Vec<(u32, u32, u32)>;

/// Validates, checks manifoldness, closes holes when allowed; returns the closed mesh and its edges.
pub(crate) fn prepare(mesh: &TriMesh, close: bool) -> Result<(Cow<'_, TriMesh>, Vec<Hole>, EdgeTable), VolumeError> {
    let (closed, holes, _, table) = prepare_loops(mesh, close)?;
    Ok((closed, holes, table))
}

/// `prepare`, also returning the boundary loops that were closed: the fan apex of loop `k` is the
/// closed mesh's vertex `mesh.vertices.len() + k` (see [`hole_of`] to redo the holes at new positions).
pub(crate) fn prepare_loops(mesh: &TriMesh, close: bool) -> Closing<'_> {
    validate(mesh)?;
    check_labels(mesh)?;
    let table = EdgeTable::build(&mesh.triangles);
    table.check_manifold(&mesh.vertices)?;
    if table.boundary.is_empty() {
        return Ok((Cow::Borrowed(mesh), Vec::new(), Vec::new(), table));
    }
    if !close {
        return Err(open_error(&mesh.vertices, &table));
    }
    let loops = boundary_cycles(&table.boundary);
    let mut out = mesh.clone();
    let mut holes = Vec::with_capacity(loops.len());
    for l in &loops {
        let hole = hole_of(&mesh.vertices, l);
        let apex = out.vertices.len() as u32;
        out.vertices.push(hole.centroid);
        let n = l.len();
        let mut face_votes = Vec::with_capacity(n);
        let mut vertex_votes = Vec::with_capacity(n);
        for &(a, b, f) in l {
            out.triangles.push([apex, b, a]);
            if let Some(fl) = &mesh.face_labels {
                face_votes.push(fl[f as usize]);
            }
            if let Some(vl) = &mesh.vertex_labels {
                vertex_votes.push(vl[a as usize]);
            }
        }
        if let Some(fl) = &mut out.face_labels {
            let lab = most_common(&face_votes);
            fl.extend(std::iter::repeat_n(lab, n));
        }
        if let Some(vl) = &mut out.vertex_labels {
            vl.push(most_common(&vertex_votes));
        }
        holes.push(hole);
    }
    let table = EdgeTable::build(&out.triangles);
    table.check_manifold(&out.vertices)?;
    Ok((Cow::Owned(out), holes, loops, table))
}

/// What [`prepare_loops`] returns: the closed mesh, its holes, their loops and its edge table, or why not.
pub(crate) type Closing<'a> = Result<(Cow<'a, TriMesh>, Vec<Hole>, Vec<BoundaryLoop>, EdgeTable), VolumeError>;

/// The hole a boundary loop leaves at `vertices`: the loop centroid (the fan apex), its edge count
/// and perimeter. The one rule of hole closing and of re-measuring a prepared mesh at new positions.
pub(crate) fn hole_of(vertices: &[[f64; 3]], l: &[(u32, u32, u32)]) -> Hole {
    let perimeter_m = l.iter().fold(0.0, |p, &(a, b, _)| p + dist2(vertices[a as usize], vertices[b as usize]).sqrt());
    Hole { centroid: loop_centroid(vertices, l), edges: l.len(), perimeter_m }
}

/// The `OpenMesh` error of a mesh with boundary edges: loop count and the centroids of the largest loops.
pub(crate) fn open_error(vertices: &[[f64; 3]], table: &EdgeTable) -> VolumeError {
    let loops = boundary_cycles(&table.boundary);
    let mut described: Vec<(usize, [f64; 3])> = loops.iter().map(|l| (l.len(), loop_centroid(vertices, l))).collect();
    described.sort_by_key(|d| std::cmp::Reverse(d.0));
    VolumeError::OpenMesh {
        loops: loops.len(),
        boundary_edges: table.boundary.len(),
        loop_centroids: described.into_iter().take(LISTED_LOOPS).map(|d| d.1).collect(),
    }
}

/// Checks the lengths and values of the label arrays that are present.
pub(crate) fn check_labels(mesh: &TriMesh) -> Result<(), VolumeError> {
    let max = bsv_core::SEGMENT_COUNT as u8;
    for (what, labels, expected) in
        [("vertex", &mesh.vertex_labels, mesh.vertices.len()), ("face", &mesh.face_labels, mesh.triangles.len())]
    {
        let Some(l) = labels else { continue };
        if l.len() != expected {
            return Err(VolumeError::LabelCountMismatch { what, got: l.len(), expected });
        }
        if let Some((index, &label)) = l.iter().enumerate().find(|(_, &v)| v >= max) {
            return Err(VolumeError::UnknownLabel { what, index, label });
        }
    }
    Ok(())
}

fn loop_centroid(vertices: &[[f64; 3]], l: &[(u32, u32, u32)]) -> [f64; 3] {
    let acc = l.iter().fold([0.0; 3], |acc, &(a, _, _)| add(acc, vertices[a as usize]));
    scale(acc, 1.0 / l.len().max(1) as f64)
}

/// Splits directed boundary half-edges `(from, to, face)` into closed cycles (each a list of half-edges
/// in walking order). Deterministic: cycles start at the smallest unused half-edge, and at a vertex
/// with several exits the smallest unused one is taken. The boundary of an oriented edge-manifold
/// surface has as many exits as entries at every vertex, so every walk returns to its start; a walk
/// that passes a vertex twice (a pinch) is split there into simple cycles, so that every fan is manifold.
pub(crate) fn boundary_cycles(boundary: &[(u32, u32, u32)]) -> Vec<Vec<(u32, u32, u32)>> {
    let mut edges = boundary.to_vec();
    edges.sort_unstable();
    let mut used = vec![false; edges.len()];
    // Next unused exit per vertex: edges are sorted by `from`, so exits of v form a run.
    let first_exit = |v: u32| edges.partition_point(|e| e.0 < v);
    let mut cursor: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    let mut cycles = Vec::new();
    for s in 0..edges.len() {
        if used[s] {
            continue;
        }
        used[s] = true;
        let start = edges[s].0;
        let mut cycle = vec![edges[s]];
        let mut cur = edges[s].1;
        while cur != start {
            let pos = cursor.entry(cur).or_insert_with(|| first_exit(cur));
            while *pos < edges.len() && edges[*pos].0 == cur && used[*pos] {
                *pos += 1;
            }
            if *pos < edges.len() && edges[*pos].0 == cur {
                used[*pos] = true;
                cycle.push(edges[*pos]);
                cur = edges[*pos].1;
            } else {
                break; // unbalanced vertex (cannot happen after the manifold check): close the chain here
            }
        }
        split_simple(cycle, &mut cycles);
    }
    cycles
}

/// Splits a closed walk into simple cycles at repeated vertices (stack-based, linear time).
fn split_simple(walk: Vec<(u32, u32, u32)>, out: &mut Vec<Vec<(u32, u32, u32)>>) {
    let mut stack: Vec<(u32, u32, u32)> = Vec::with_capacity(walk.len());
    let mut at: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    for e in walk {
        at.entry(e.0).or_insert(stack.len());
        stack.push(e);
        if let Some(&i) = at.get(&e.1) {
            // The walk is back at e.1, first left at stack[i]: stack[i..] is a simple cycle.
            let cycle: Vec<_> = stack.drain(i..).collect();
            for c in &cycle {
                at.remove(&c.0);
            }
            out.push(cycle);
        }
    }
    if !stack.is_empty() {
        out.push(stack);
    }
}
