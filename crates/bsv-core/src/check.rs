//! Mesh checks (a report for `bsv-cli info` and a gate for volume computations) and repairs:
//! degenerate, duplicate and unreferenced elements removed, faces oriented consistently and outward.

use std::collections::{HashMap, HashSet, VecDeque};
use std::fmt;

use serde::Serialize;
use thiserror::Error;

use crate::geometry::{cross, dist2, norm, signed_volume, sub};
use crate::topology::{boundary_loops, edge_map, face_components};
use crate::TriMesh;

/// Relative area below which a triangle counts as degenerate: |cross| <= EPS * (longest edge)^2.
const DEGENERATE_EPS: f64 = 1e-12;

/// Counts and flags describing a mesh's validity as a closed, oriented surface.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub faces: usize,
    /// Triangles referring to a vertex that does not exist.
    pub invalid_faces: usize,
    /// Triangles with a repeated vertex index or (numerically) zero area.
    pub degenerate_faces: usize,
    /// Triangles using the same vertex set as an earlier triangle.
    pub duplicate_faces: usize,
    /// Vertices used by no triangle.
    pub unreferenced_vertices: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Closed chains of boundary edges (holes).
    pub boundary_loops: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles form more than one fan (e.g. two cones touching at a tip).
    pub non_manifold_vertices: usize,
    /// Edges shared by two triangles that run it in the same direction.
    pub inconsistent_edges: usize,
    /// Edge-connected components of triangles.
    pub components: usize,
    /// Total surface area, m^2.
    pub area: f64,
    /// No boundary and no non-manifold edge (and at least one valid triangle).
    pub is_watertight: bool,
    /// Every two-triangle edge is run in opposite directions by its triangles.
    pub is_consistently_oriented: bool,
    /// Enclosed signed volume, m^3, when watertight and consistently oriented (positive = outward).
    pub signed_volume: Option<f64>,
}

/// Why a mesh is not a closed, consistently oriented, outward 2-manifold. Each message says how to fix it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshCheckError {
    /// No triangles.
    #[error("{what} has no triangles ({vertices} vertices); pass a triangle mesh, not a point cloud")]
    Empty {
        /// The mesh's role (e.g. "template").
        what: String,
        /// Vertex count.
        vertices: usize,
    },
    /// Triangles refer to missing vertices.
    #[error("{what} has {count} triangle(s) referring to missing vertices; repair the mesh (`repair_mesh` drops them) or export it again")]
    InvalidFaces {
        /// The mesh's role.
        what: String,
        /// Invalid triangles.
        count: usize,
    },
    /// Edges with more than two triangles (or pinched vertices).
    #[error("{what} is not manifold: {edges} edge(s) shared by more than two triangles, {vertices} pinched vertex/vertices; remove duplicate faces (`repair_mesh`), otherwise fix the mesh in a modeller (e.g. MeshLab 'Repair non Manifold Edges')")]
    NonManifold {
        /// The mesh's role.
        what: String,
        /// Non-manifold edges.
        edges: usize,
        /// Non-manifold vertices.
        vertices: usize,
    },
    /// Holes.
    #[error("{what} is open: {edges} boundary edge(s) in {loops} hole(s); close the holes (e.g. MeshLab 'Close Holes', or let the volume step cap them) before computing a volume")]
    Open {
        /// The mesh's role.
        what: String,
        /// Boundary edges.
        edges: usize,
        /// Boundary loops.
        loops: usize,
    },
    /// Neighbouring triangles disagree on orientation.
    #[error("{what} is inconsistently oriented: {edges} edge(s) run the same way by both their triangles; repair the mesh (`repair_mesh` orients it)")]
    Inconsistent {
        /// The mesh's role.
        what: String,
        /// Inconsistent edges.
        edges: usize,
    },
    /// Closed and consistent but inside-out.
    #[error(
        "{what} is inside-out (signed volume {volume:.6} m^3 <= 0); repair the mesh (`repair_mesh` orients it outward)"
    )]
    Inward {
        /// The mesh's role.
        what: String,
        /// Signed volume, m^3.
        volume: f64,
    },
}

impl MeshReport {
    /// Ok when the mesh is a closed, consistently and outward oriented 2-manifold; `what` names the
    /// mesh in the error (e.g. "the template").
    pub fn require_closed_manifold(&self, what: &str) -> Result<(), MeshCheckError> {
        let what = what.to_string();
        if self.faces == 0 {
            return Err(MeshCheckError::Empty { what, vertices: self.vertices });
        }
        if self.invalid_faces > 0 {
            return Err(MeshCheckError::InvalidFaces { what, count: self.invalid_faces });
        }
        if self.non_manifold_edges > 0 || self.non_manifold_vertices > 0 {
            return Err(MeshCheckError::NonManifold {
                what,
                edges: self.non_manifold_edges,
                vertices: self.non_manifold_vertices,
            });
        }
        if self.boundary_edges > 0 {
            return Err(MeshCheckError::Open { what, edges: self.boundary_edges, loops: self.boundary_loops });
        }
        if self.inconsistent_edges > 0 {
            return Err(MeshCheckError::Inconsistent { what, edges: self.inconsistent_edges });
        }
        match self.signed_volume {
            Some(v) if v > 0.0 => Ok(()),
            Some(volume) => Err(MeshCheckError::Inward { what, volume }),
            None => Err(MeshCheckError::Inconsistent { what, edges: self.inconsistent_edges }),
        }
    }
}

impl fmt::Display for MeshReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let yes = |b: bool| if b { "yes" } else { "no" };
        writeln!(f, "vertices:               {}", self.vertices)?;
        writeln!(f, "triangles:              {}", self.faces)?;
        writeln!(f, "components:             {}", self.components)?;
        writeln!(f, "surface area:           {:.6} m^2", self.area)?;
        writeln!(f, "watertight:             {}", yes(self.is_watertight))?;
        writeln!(f, "consistently oriented:  {}", yes(self.is_consistently_oriented))?;
        match self.signed_volume {
            Some(v) => writeln!(
                f,
                "signed volume:          {:.6} m^3 ({:.3} L){}",
                v,
                v * 1000.0,
                if v < 0.0 { " (inside-out)" } else { "" }
            )?,
            None => writeln!(f, "signed volume:          n/a (not closed and consistently oriented)")?,
        }
        writeln!(f, "boundary edges:         {} in {} loop(s)", self.boundary_edges, self.boundary_loops)?;
        writeln!(f, "non-manifold edges:     {}", self.non_manifold_edges)?;
        writeln!(f, "non-manifold vertices:  {}", self.non_manifold_vertices)?;
        writeln!(f, "inconsistent edges:     {}", self.inconsistent_edges)?;
        writeln!(f, "degenerate triangles:   {}", self.degenerate_faces)?;
        writeln!(f, "duplicate triangles:    {}", self.duplicate_faces)?;
        writeln!(f, "unreferenced vertices:  {}", self.unreferenced_vertices)?;
        write!(f, "invalid triangles:      {}", self.invalid_faces)
    }
}

fn is_valid(t: &[u32; 3], n: usize) -> bool {
    t.iter().all(|&i| (i as usize) < n)
}

/// Repeated index, or area negligible relative to the longest edge (valid indices assumed).
fn is_degenerate(vertices: &[[f64; 3]], t: &[u32; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return true;
    }
    let [a, b, c] = t.map(|i| vertices[i as usize]);
    let longest = dist2(a, b).max(dist2(b, c)).max(dist2(c, a));
    norm(cross(sub(b, a), sub(c, a))) <= DEGENERATE_EPS * longest
}

fn sorted(t: &[u32; 3]) -> [u32; 3] {
    let mut s = *t;
    s.sort_unstable();
    s
}

/// Counts vertices whose incident triangles form more than one edge-connected fan.
fn count_non_manifold_vertices(n_vertices: usize, triangles: &[[u32; 3]]) -> usize {
    // CSR incidence: vertex -> (other two corners) of each incident triangle.
    let mut start = vec![0usize; n_vertices + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..n_vertices {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut pairs = vec![(0u32, 0u32); start[n_vertices]];
    for t in triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            pairs[fill[v]] = (t[(k + 1) % 3], t[(k + 2) % 3]);
            fill[v] += 1;
        }
    }
    let mut count = 0;
    let mut local: Vec<u32> = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    for v in 0..n_vertices {
        let fan = &pairs[start[v]..start[v + 1]];
        if fan.is_empty() {
            continue;
        }
        local.clear();
        local.extend(fan.iter().flat_map(|&(a, b)| [a, b]));
        local.sort_unstable();
        local.dedup();
        parent.clear();
        parent.extend(0..local.len());
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut groups = local.len();
        for &(a, b) in fan {
            let (Ok(ia), Ok(ib)) = (local.binary_search(&a), local.binary_search(&b)) else { continue };
            let (ra, rb) = (find(&mut parent, ia), find(&mut parent, ib));
            if ra != rb {
                parent[ra.max(rb)] = ra.min(rb);
                groups -= 1;
            }
        }
        if groups > 1 {
            count += 1;
        }
    }
    count
}

/// Checks a mesh; never panics, whatever the indices.
pub fn check_mesh(mesh: &TriMesh) -> MeshReport {
    let n = mesh.n_vertices();
    let valid: Vec<[u32; 3]> = mesh.triangles.iter().copied().filter(|t| is_valid(t, n)).collect();
    let invalid_faces = mesh.n_triangles() - valid.len();
    let degenerate_faces = valid.iter().filter(|t| is_degenerate(&mesh.vertices, t)).count();
    let mut seen = HashSet::with_capacity(valid.len());
    let duplicate_faces = valid
        .iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .filter(|t| !seen.insert(sorted(t)))
        .count();
    let mut used = vec![false; n];
    for t in &valid {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let unreferenced_vertices = used.iter().filter(|&&u| !u).count();
    // Edges of the valid triangles without repeated indices (a repeated index has no proper edges).
    let proper: Vec<[u32; 3]> =
        valid.iter().copied().filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).collect();
    let edges = edge_map(&proper);
    let mut boundary_edges = 0;
    let mut non_manifold_edges = 0;
    let mut inconsistent_edges = 0;
    for e in edges.values() {
        match e.faces.len() {
            1 => boundary_edges += 1,
            2 if e.faces[0].1 == e.faces[1].1 => inconsistent_edges += 1,
            2 => {}
            _ => non_manifold_edges += 1,
        }
    }
    let loops = if boundary_edges > 0 { boundary_loops(&proper).len() } else { 0 };
    let non_manifold_vertices = count_non_manifold_vertices(n, &proper);
    let components = face_components(&valid).1;
    let area = valid
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (mesh.vertices[a as usize], mesh.vertices[b as usize], mesh.vertices[c as usize]);
            0.5 * norm(cross(sub(b, a), sub(c, a)))
        })
        .sum();
    let is_watertight = !proper.is_empty() && invalid_faces == 0 && boundary_edges == 0 && non_manifold_edges == 0;
    let is_consistently_oriented = inconsistent_edges == 0;
    let signed_volume = (is_watertight && is_consistently_oriented).then(|| signed_volume(&mesh.vertices, &valid));
    MeshReport {
        vertices: n,
        faces: mesh.n_triangles(),
        invalid_faces,
        degenerate_faces,
        duplicate_faces,
        unreferenced_vertices,
        boundary_edges,
        boundary_loops: loops,
        non_manifold_edges,
        non_manifold_vertices,
        inconsistent_edges,
        components,
        area,
        is_watertight,
        is_consistently_oriented,
        signed_volume,
    }
}

/// What [`repair_mesh`] changed.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct RepairLog {
    /// Triangles removed because they referred to missing vertices.
    pub removed_invalid_faces: usize,
    /// Degenerate triangles removed.
    pub removed_degenerate_faces: usize,
    /// Duplicate triangles removed (the first of each vertex set is kept).
    pub removed_duplicate_faces: usize,
    /// Unreferenced vertices removed (indices compacted).
    pub removed_unreferenced_vertices: usize,
    /// Triangles flipped to agree with their neighbours.
    pub flipped_for_consistency: usize,
    /// Closed components turned outward (all their triangles flipped).
    pub components_turned_outward: usize,
    /// Edges still inconsistent after orienting (non-orientable surfaces, non-manifold edges).
    pub remaining_inconsistent_edges: usize,
    /// Label arrays dropped because their length did not match the mesh.
    pub dropped_label_arrays: usize,
}

impl fmt::Display for RepairLog {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "removed invalid triangles:     {}", self.removed_invalid_faces)?;
        writeln!(f, "removed degenerate triangles:  {}", self.removed_degenerate_faces)?;
        writeln!(f, "removed duplicate triangles:   {}", self.removed_duplicate_faces)?;
        writeln!(f, "removed unreferenced vertices: {}", self.removed_unreferenced_vertices)?;
        writeln!(f, "flipped for consistency:       {}", self.flipped_for_consistency)?;
        writeln!(f, "components turned outward:     {}", self.components_turned_outward)?;
        writeln!(f, "remaining inconsistent edges:  {}", self.remaining_inconsistent_edges)?;
        write!(f, "dropped mismatched labels:     {}", self.dropped_label_arrays)
    }
}

fn flip(t: &mut [u32; 3]) {
    t.swap(1, 2);
}

/// Repairs a mesh in place: removes invalid, degenerate and duplicate triangles and unreferenced
/// vertices (keeping label arrays in sync), orients every component consistently (breadth-first over
/// manifold edges, keeping the orientation most of its triangles had) and turns closed components
/// outward (positive signed volume).
pub fn repair_mesh(mesh: &mut TriMesh) -> RepairLog {
    let mut log = RepairLog::default();
    drop_mismatched_labels(mesh, &mut log);
    remove_bad_triangles(mesh, &mut log);
    remove_unreferenced_vertices(mesh, &mut log);
    orient_consistently(mesh, &mut log);
    turn_closed_components_outward(mesh, &mut log);
    log
}

/// Drops label arrays whose length does not match the vertices or triangles.
fn drop_mismatched_labels(mesh: &mut TriMesh, log: &mut RepairLog) {
    if mesh.vertex_labels.as_ref().is_some_and(|l| l.len() != mesh.n_vertices()) {
        mesh.vertex_labels = None;
        log.dropped_label_arrays += 1;
    }
    if mesh.face_labels.as_ref().is_some_and(|l| l.len() != mesh.n_triangles()) {
        mesh.face_labels = None;
        log.dropped_label_arrays += 1;
    }
}

/// Step 1: removes invalid, degenerate and duplicate triangles (and their face labels).
fn remove_bad_triangles(mesh: &mut TriMesh, log: &mut RepairLog) {
    let n = mesh.n_vertices();
    let mut seen = HashSet::with_capacity(mesh.n_triangles());
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| {
            if !is_valid(t, n) {
                log.removed_invalid_faces += 1;
                false
            } else if is_degenerate(&mesh.vertices, t) {
                log.removed_degenerate_faces += 1;
                false
            } else if !seen.insert(sorted(t)) {
                log.removed_duplicate_faces += 1;
                false
            } else {
                true
            }
        })
        .collect();
    let mut k = keep.iter();
    mesh.triangles.retain(|_| *k.next().unwrap_or(&false));
    if let Some(l) = mesh.face_labels.as_mut() {
        let mut k = keep.iter();
        l.retain(|_| *k.next().unwrap_or(&false));
    }
}

/// Step 2: removes vertices no triangle uses (and their labels), compacting the indices.
fn remove_unreferenced_vertices(mesh: &mut TriMesh, log: &mut RepairLog) {
    let n = mesh.n_vertices();
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut remap = vec![u32::MAX; n];
    let mut next = 0u32;
    for (v, &u) in used.iter().enumerate() {
        if u {
            remap[v] = next;
            next += 1;
        }
    }
    log.removed_unreferenced_vertices = n - next as usize;
    if log.removed_unreferenced_vertices > 0 {
        let mut i = 0;
        mesh.vertices.retain(|_| {
            i += 1;
            used[i - 1]
        });
        if let Some(l) = mesh.vertex_labels.as_mut() {
            let mut i = 0;
            l.retain(|_| {
                i += 1;
                used[i - 1]
            });
        }
        for t in &mut mesh.triangles {
            *t = t.map(|v| remap[v as usize]);
        }
    }
}

/// Triangles across each manifold edge, with whether both run the edge the same way.
fn manifold_neighbours(triangles: &[[u32; 3]]) -> HashMap<u32, Vec<(u32, bool)>> {
    let edges = edge_map(triangles);
    let mut neighbours: HashMap<u32, Vec<(u32, bool)>> = HashMap::new();
    for e in edges.values() {
        if let [(f, df), (g, dg)] = e.faces[..] {
            // `same` = both triangles run the edge in the same direction (one must flip).
            neighbours.entry(f).or_default().push((g, df == dg));
            neighbours.entry(g).or_default().push((f, df == dg));
        }
    }
    neighbours
}

/// Step 3: consistent orientation per component, breadth-first across manifold edges.
fn orient_consistently(mesh: &mut TriMesh, log: &mut RepairLog) {
    let neighbours = manifold_neighbours(&mesh.triangles);
    let nf = mesh.n_triangles();
    let mut flipped = vec![false; nf];
    let mut visited = vec![false; nf];
    let mut queue = VecDeque::new();
    for seed in 0..nf {
        if visited[seed] {
            continue;
        }
        let mut members = vec![seed];
        visited[seed] = true;
        queue.push_back(seed as u32);
        while let Some(f) = queue.pop_front() {
            for &(g, same) in neighbours.get(&f).map(Vec::as_slice).unwrap_or(&[]) {
                if !visited[g as usize] {
                    visited[g as usize] = true;
                    // g must flip relative to f when they run the edge the same way.
                    flipped[g as usize] = flipped[f as usize] ^ same;
                    members.push(g as usize);
                    queue.push_back(g);
                }
            }
        }
        // Keep the orientation the majority of the component had.
        let n_flipped = members.iter().filter(|&&f| flipped[f]).count();
        if 2 * n_flipped > members.len() {
            for &f in &members {
                flipped[f] = !flipped[f];
            }
        }
    }
    for (t, &fl) in mesh.triangles.iter_mut().zip(&flipped) {
        if fl {
            flip(t);
            log.flipped_for_consistency += 1;
        }
    }
}

/// Step 4: flips every closed component whose signed volume is negative; also counts the edges
/// still inconsistent.
fn turn_closed_components_outward(mesh: &mut TriMesh, log: &mut RepairLog) {
    let edges = edge_map(&mesh.triangles);
    let (comp, n_comp) = face_components(&mesh.triangles);
    let mut closed = vec![true; n_comp];
    for e in edges.values() {
        let ok = e.faces.len() == 2 && e.faces[0].1 != e.faces[1].1;
        if !ok {
            for &(f, _) in &e.faces {
                closed[comp[f as usize] as usize] = false;
            }
        }
        if e.faces.len() == 2 && e.faces[0].1 == e.faces[1].1 {
            log.remaining_inconsistent_edges += 1;
        }
    }
    let mut volume = vec![0.0; n_comp];
    for (t, &c) in mesh.triangles.iter().zip(&comp) {
        volume[c as usize] += signed_volume(&mesh.vertices, std::slice::from_ref(t));
    }
    for c in 0..n_comp {
        if closed[c] && volume[c] < 0.0 {
            log.components_turned_outward += 1;
        }
    }
    if log.components_turned_outward > 0 {
        for (t, &c) in mesh.triangles.iter_mut().zip(&comp) {
            if closed[c as usize] && volume[c as usize] < 0.0 {
                flip(t);
            }
        }
    }
}
