//! Segment volumes whose sum is the whole volume by construction.
//!
//! Each segment S is closed by caps built on its boundary, and every cap triangle of S is also a cap
//! triangle of the neighbouring segment, with the opposite orientation. Summed over the segments the
//! caps cancel triangle by triangle (each pair contributes `+d` and `-d` of the same computed number),
//! so the segment volumes add up to the whole volume up to summation round-off, whatever the labels.
//!
//! Construction, on a closed, edge-manifold, consistently oriented mesh with one label per face:
//! 1. Interface edges are the edges whose two faces carry different labels S < T. They are chained into
//!    pieces through "regular" vertices (exactly two interface edges, same label pair); vertices where
//!    three or more segments meet (or two segments touch at a point) are junctions and end pieces. A
//!    piece is either a closed loop between two segments (the usual limb cut) or a path from junction
//!    to junction.
//! 2. Each piece gets one apex, the centroid of its vertices, shared by both sides: the cap is the fan of
//!    the piece's edges to that apex. For a closed loop this is exactly "fan the loop to its centroid".
//! 3. An open piece's fan leaves two spokes (junction to apex) unmatched. All pieces that touch each
//!    other through junctions form a junction cluster with one hub, the centroid of its junction
//!    vertices (a cluster has at least two); each spoke is closed by the triangle (apex, junction, hub),
//!    again shared by the two sides of the piece. At a junction the spokes of one segment come in and go
//!    out in equal numbers, and so do the hub edges, so every segment's surface is closed. The hub lies
//!    on the line where the cut surfaces meet when the junctions do (two triple points of a limb joint,
//!    the poles of a sphere cut in three sectors), so planar cuts stay planar and the parts are exact.
//!
//! Steps 1 and the topology of 2-3 depend on the labels only (`Caps::build`, once per labelling); the
//! positions enter in `Caps::integrals` alone, which [`crate::PreparedSegments`] reuses to re-measure a
//! mesh at many vertex positions.
//!
//! Because every segment surface is closed, its volume does not depend on the reference point of the
//! tetrahedra (the mesh centroid is used for round-off). Faces labelled 0 (unlabelled) are treated as a
//! segment of their own: they count in `whole` but produce no segment entry.

use crate::closed::{open_error, prepare_loops, BoundaryLoop, Hole};
use crate::edges::{det6, used_centroid, validate, EdgeTable};
use crate::labels::{face_labels_from_vertices, merge_small_islands, IslandOptions, IslandReport};
use crate::mass::Moments;
use crate::VolumeError;
use bsv_core::geometry::{add, scale};
use bsv_core::{Segment, TriMesh};
use std::collections::BTreeMap;
use std::ops::{AddAssign, Mul, SubAssign};

/// Where the face labels used for segment volumes came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabelSource {
    /// The mesh's face labels.
    Faces,
    /// Derived from the mesh's vertex labels (majority of the corners).
    Vertices,
    /// The mesh has no labels: only the whole volume is known.
    None,
}

/// Options of `segment_volumes_with`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SegmentOptions {
    /// Close holes by centroid fans instead of failing with `OpenMesh` (cap faces take the most common
    /// label along their loop).
    pub close_holes: bool,
    /// Merge small label islands into their surroundings before measuring (`None`: labels as given).
    pub islands: Option<IslandOptions>,
}

impl SegmentOptions {
    /// The volume policy for a fitted (registered) mesh, shared by `bsv-cli register` and the
    /// Python `bsv.register`: small label islands merged with the default [`IslandOptions`] (the
    /// nearest-point label transfer leaves stray patches of one segment inside another), no hole
    /// closing (a fitted template is closed).
    pub fn fitted() -> Self {
        SegmentOptions { close_holes: false, islands: Some(IslandOptions::default()) }
    }
}

/// Volumes of the segments of a labelled closed mesh, m^3.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentVolumes {
    /// Volume enclosed by the whole mesh, m^3 (= the sum of the segments and the unlabelled region).
    pub whole_m3: f64,
    /// Volume of every labelled segment present in the mesh, m^3 (absent segments are absent).
    pub segments: BTreeMap<Segment, f64>,
    /// Volume of the region of unlabelled faces when the mesh has both labelled and unlabelled faces.
    pub unlabelled_m3: Option<f64>,
    /// Where the labels came from.
    pub label_source: LabelSource,
    /// Holes closed before measuring (only with `close_holes`).
    pub holes: Vec<Hole>,
    /// True when the triangles faced inward and every volume was negated.
    pub inverted: bool,
    /// What island merging changed, when requested.
    pub islands: Option<IslandReport>,
    /// Statistics of the caps between segments.
    pub caps: CapStats,
    /// Human-readable remarks (missing labels, unlabelled faces, inverted mesh, ...).
    pub notes: Vec<String>,
}

impl SegmentVolumes {
    /// The volume of a segment, m^3, if present.
    pub fn get(&self, s: Segment) -> Option<f64> {
        self.segments.get(&s).copied()
    }
}

/// Counts describing the caps built between segments.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CapStats {
    /// Interface edges (edges between faces of different labels).
    pub interface_edges: usize,
    /// Interface pieces that are closed loops.
    pub closed_loops: usize,
    /// Interface pieces that run from junction to junction.
    pub open_pieces: usize,
    /// Vertices where three or more segments meet (or two touch at a point).
    pub junctions: usize,
    /// Junction clusters (each with one hub point).
    pub clusters: usize,
}

/// Volume of the whole mesh and of every label present, by the construction of the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelVolumes {
    /// Whole enclosed volume, m^3.
    pub whole_m3: f64,
    /// `(label, volume m^3, face count)` for every label that has faces, by label.
    pub by_label: Vec<(u8, f64, usize)>,
    /// Cap statistics.
    pub caps: CapStats,
}

/// Segment volumes with default options (labels as given, no hole closing).
/// Uses the face labels, or derives them from the vertex labels; with no labels only `whole` is given.
pub fn segment_volumes(mesh: &TriMesh) -> Result<SegmentVolumes, VolumeError> {
    segment_volumes_with(mesh, &SegmentOptions::default())
}

/// A closed mesh with its edge table and one label per face, as every per-segment measure uses it.
pub(crate) struct Labelled<'a> {
    /// The mesh, holes closed when asked.
    pub closed: std::borrow::Cow<'a, TriMesh>,
    /// Holes closed.
    pub holes: Vec<Hole>,
    /// Their boundary loops (the apex of loop `k` is vertex `n + k` of `closed`, n the input's count).
    pub loops: Vec<BoundaryLoop>,
    /// Edge table of `closed`.
    pub table: EdgeTable,
    /// One label per face of `closed` (islands merged when asked).
    pub labels: Vec<u8>,
    /// Where the labels came from.
    pub source: LabelSource,
    /// What island merging changed.
    pub islands: Option<IslandReport>,
}

/// Validates, closes holes when asked, and picks the face labels (faces, else vertices, else none)
/// with small islands merged when asked: the one labelling rule of volumes and mass properties.
pub(crate) fn labelled<'a>(mesh: &'a TriMesh, opts: &SegmentOptions) -> Result<Labelled<'a>, VolumeError> {
    let (closed, holes, loops, table) = prepare_loops(mesh, opts.close_holes)?;
    let (mut labels, source) = match (&closed.face_labels, &closed.vertex_labels) {
        (Some(f), _) => (f.clone(), LabelSource::Faces),
        (None, Some(v)) => (face_labels_from_vertices(&closed.triangles, v), LabelSource::Vertices),
        (None, None) => (vec![0u8; closed.triangles.len()], LabelSource::None),
    };
    let islands = match (opts.islands, source) {
        (Some(o), LabelSource::Faces | LabelSource::Vertices) => Some(merge_small_islands(&closed, &mut labels, &o)),
        _ => None,
    };
    Ok(Labelled { closed, holes, loops, table, labels, source, islands })
}

/// Segment volumes with options (hole closing, island merging).
pub fn segment_volumes_with(mesh: &TriMesh, opts: &SegmentOptions) -> Result<SegmentVolumes, VolumeError> {
    let Labelled { closed, holes, table, labels, source, islands, .. } = labelled(mesh, opts)?;
    let caps = Caps::build(closed.vertices.len(), &table, &labels);
    Ok(segment_volumes_at(&closed.vertices, &closed.triangles, &labels, &caps, source, holes, islands))
}

/// The part of `segment_volumes_with` that reads the positions: the volumes of the labelled closed
/// mesh (`triangles` labelled `labels`, caps `caps` built on them) at `vertices`, and the notes. Shared
/// with [`crate::PreparedSegments`], which fixes everything but `vertices` (and `holes`, redone at them).
pub(crate) fn segment_volumes_at(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    labels: &[u8],
    caps: &Caps,
    source: LabelSource,
    holes: Vec<Hole>,
    islands: Option<IslandReport>,
) -> SegmentVolumes {
    let mut notes = Vec::new();
    let lv = caps.volumes(used_centroid(vertices, triangles), vertices, triangles, labels);
    let inverted = lv.whole_m3 < 0.0;
    let sign = if inverted { -1.0 } else { 1.0 };
    let mut segments = BTreeMap::new();
    let mut unlabelled = None;
    let n_labelled: usize = lv.by_label.iter().filter(|l| l.0 != 0).map(|l| l.2).sum();
    for &(l, v, count) in &lv.by_label {
        match Segment::from_id(l) {
            Some(Segment::Unlabelled) | None => {
                if n_labelled > 0 {
                    unlabelled = Some(sign * v);
                    notes.push(format!(
                        "{count} of {} faces are unlabelled: their region ({:.3} L) counts in whole but in no segment",
                        labels.len(),
                        sign * v * 1e3
                    ));
                }
            }
            Some(s) => {
                segments.insert(s, sign * v);
            }
        }
    }
    if source == LabelSource::None {
        notes.push(
            "the mesh has no segment labels (neither face nor vertex labels): only the whole volume is given".into(),
        );
    } else if n_labelled == 0 {
        notes.push("every face is unlabelled (label 0): only the whole volume is given".into());
    }
    if inverted {
        notes.push(
            "the triangles face inward (negative enclosed volume): every volume was negated; orient the mesh outward"
                .into(),
        );
    }
    if !holes.is_empty() {
        notes.push(format!("{} hole(s) were closed by centroid fans before measuring", holes.len()));
    }
    for (s, v) in &segments {
        if *v <= 0.0 {
            notes.push(format!("segment {s} has a non-positive volume ({:.4} L): its labels are probably scattered; merge small islands", v * 1e3));
        }
    }
    SegmentVolumes {
        whole_m3: sign * lv.whole_m3,
        segments,
        unlabelled_m3: unlabelled,
        label_source: source,
        holes,
        inverted,
        islands,
        caps: lv.caps,
        notes,
    }
}

/// A six-fold tetrahedron integral summed per label: the volume (`f64`, `det6`) or the volume
/// moments of `mass` (`Moments`). The caps are built once and add the same integrand to both sides.
pub(crate) trait Integrand: Copy + Default + AddAssign + SubAssign + Mul<f64, Output = Self> {
    /// The six-fold integral over the signed tetrahedron (r, a, b, c).
    fn tetra(r: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Self;
}

impl Integrand for f64 {
    fn tetra(r: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
        det6(r, a, b, c)
    }
}

impl Integrand for Moments {
    fn tetra(r: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Moments {
        Moments::tetra(r, a, b, c)
    }
}

/// An interface between two segments: one piece of the caps (a closed loop, e.g. the elbow's, or a
/// path between junctions) and its apex, the centroid of its vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Interface {
    /// The smaller label of the two sides.
    pub lo: u8,
    /// The larger label of the two sides.
    pub hi: u8,
    /// Centroid of the piece's distinct vertices (the cap apex), metres.
    pub centroid: [f64; 3],
    /// Number of distinct vertices of the piece.
    pub vertices: usize,
    /// True for a closed loop, false for a path between junctions.
    pub closed: bool,
}

/// Six-fold integrals of the whole and of every label, from reference point `reference`.
pub(crate) struct LabelIntegrals<I> {
    /// The reference point of the tetrahedra.
    pub reference: [f64; 3],
    /// Whole mesh.
    pub whole: I,
    /// `(label, integral, face count)` for every label that has faces, by label.
    pub by_label: Vec<(u8, I, usize)>,
    /// Cap statistics.
    pub caps: CapStats,
    /// The cap pieces (interfaces).
    pub interfaces: Vec<Interface>,
}

/// Volumes (m^3, signed) of every label of a closed mesh, `face_labels` one per triangle. The caller
/// guarantees a validated mesh and its edge table (closed, manifold, consistently oriented).
pub(crate) fn label_volumes(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    table: &EdgeTable,
    face_labels: &[u8],
) -> LabelVolumes {
    label_volumes_at(used_centroid(vertices, triangles), vertices, triangles, table, face_labels)
}

/// Six-fold integrals of every label of a closed mesh from the centroid of its used vertices.
pub(crate) fn label_integrals<I: Integrand>(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    table: &EdgeTable,
    face_labels: &[u8],
) -> LabelIntegrals<I> {
    label_integrals_at(used_centroid(vertices, triangles), vertices, triangles, table, face_labels)
}

/// `label_volumes` with tetrahedra taken from the reference point `r` (any point gives the same
/// volumes for closed surfaces; the unit tests use this to prove every segment surface is closed).
fn label_volumes_at(
    r: [f64; 3],
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    table: &EdgeTable,
    face_labels: &[u8],
) -> LabelVolumes {
    Caps::build(vertices.len(), table, face_labels).volumes(r, vertices, triangles, face_labels)
}

/// The integrals of every label with the caps of the module docs, tetrahedra from `r`.
fn label_integrals_at<I: Integrand>(
    r: [f64; 3],
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    table: &EdgeTable,
    face_labels: &[u8],
) -> LabelIntegrals<I> {
    Caps::build(vertices.len(), table, face_labels).integrals(r, vertices, triangles, face_labels)
}

/// The caps between the segments of a labelling, without positions (step 1 of the module docs and the
/// topology of steps 2-3): the interface edges chained into pieces, the distinct vertices of each piece
/// (its apex is their centroid), the unmatched spokes and the junction clusters (each hub the centroid
/// of its junction vertices). Built once per labelling; [`Caps::integrals`] adds the positions, so a
/// mesh whose vertices move (same triangles and labels) is re-measured without redoing this.
pub(crate) struct Caps {
    /// The interface edges.
    iface: Vec<IEdge>,
    /// Their pieces.
    pieces: Pieces,
    /// Hub (junction cluster) of each spoke of `pieces.spokes`.
    spoke_hub: Vec<u32>,
    /// Junction vertices of each hub (CSR: hub `h`'s are `hub_vertices[hub_start[h]..hub_start[h + 1]]`).
    hub_start: Vec<usize>,
    /// See `hub_start`.
    hub_vertices: Vec<u32>,
    /// Cap statistics (topology only).
    stats: CapStats,
}

impl Caps {
    /// The caps of `face_labels` on a closed mesh of `n_vertices` vertices with edge table `table`.
    pub(crate) fn build(n_vertices: usize, table: &EdgeTable, face_labels: &[u8]) -> Caps {
        let iface = interface_edges(table, face_labels);
        let (piece, n_pieces) = chain_pieces(n_vertices, &iface);
        let pieces = Pieces::build(&iface, piece, n_pieces);
        // Junction clusters: pieces and junction vertices linked by spokes, one hub per cluster.
        let np = pieces.count;
        let mut open = vec![false; np];
        let mut junction_id = vec![u32::MAX; n_vertices];
        let mut junctions: Vec<u32> = Vec::new();
        for &(p, v, _) in &pieces.spokes {
            open[p as usize] = true;
            if junction_id[v as usize] == u32::MAX {
                junction_id[v as usize] = junctions.len() as u32;
                junctions.push(v);
            }
        }
        let mut cuf = UnionFind::new(np + junctions.len());
        for &(p, v, _) in &pieces.spokes {
            cuf.union(p as usize, np + junction_id[v as usize] as usize);
        }
        // Hubs numbered by their first junction; each lists its junctions in order.
        let mut hub_of_root = vec![u32::MAX; np + junctions.len()];
        let mut members: Vec<Vec<u32>> = Vec::new();
        let mut hub_of = |root: usize, members: &mut Vec<Vec<u32>>| {
            if hub_of_root[root] == u32::MAX {
                hub_of_root[root] = members.len() as u32;
                members.push(Vec::new());
            }
            hub_of_root[root] as usize
        };
        for (j, &v) in junctions.iter().enumerate() {
            let h = hub_of(cuf.find(np + j), &mut members);
            members[h].push(v);
        }
        let spoke_hub =
            pieces.spokes.iter().map(|&(p, _, _)| hub_of(cuf.find(p as usize), &mut members) as u32).collect();
        let mut hub_start = vec![0usize];
        let mut hub_vertices = Vec::with_capacity(junctions.len());
        for m in members {
            hub_vertices.extend(m);
            hub_start.push(hub_vertices.len());
        }
        let open_pieces = open.iter().filter(|&&o| o).count();
        let stats = CapStats {
            interface_edges: iface.len(),
            closed_loops: np - open_pieces,
            open_pieces,
            junctions: junctions.len(),
            clusters: (0..np + junctions.len()).filter(|&x| (x >= np || open[x]) && cuf.find(x) == x).count(),
        };
        Caps { iface, pieces, spoke_hub, hub_start, hub_vertices, stats }
    }

    /// Volumes (m^3, signed) of every label at `vertices`, tetrahedra from `r`.
    pub(crate) fn volumes(
        &self,
        r: [f64; 3],
        vertices: &[[f64; 3]],
        triangles: &[[u32; 3]],
        face_labels: &[u8],
    ) -> LabelVolumes {
        let li = self.integrals::<f64>(r, vertices, triangles, face_labels);
        let by_label = li.by_label.iter().map(|&(l, v, n)| (l, v / 6.0, n)).collect();
        LabelVolumes { whole_m3: li.whole / 6.0, by_label, caps: li.caps }
    }

    /// The six-fold integrals of every label at `vertices` (the caps' triangles and labels fixed),
    /// tetrahedra from `r`: faces, then the piece fans to their apexes, then the spokes closed at the
    /// hubs; apexes and hubs are the centroids of their vertices at `vertices`.
    pub(crate) fn integrals<I: Integrand>(
        &self,
        r: [f64; 3],
        vertices: &[[f64; 3]],
        triangles: &[[u32; 3]],
        face_labels: &[u8],
    ) -> LabelIntegrals<I> {
        let (mut acc, count, whole) = face_integrals::<I>(r, vertices, triangles, face_labels);
        if self.iface.is_empty() {
            return finish(r, acc, count, whole, self.stats, Vec::new());
        }
        // 2. One apex per piece, and the piece fans.
        let apex = group_centroids(&self.pieces.start, &self.pieces.members, vertices);
        self.pieces.add_fans(r, vertices, &self.iface, &apex, &mut acc);
        // 3. Each spoke closed by (apex, junction, hub) on both sides.
        let hubs = group_centroids(&self.hub_start, &self.hub_vertices, vertices);
        let pos = |v: u32| vertices[v as usize];
        for (&(p, v, d), &h) in self.pieces.spokes.iter().zip(&self.spoke_hub) {
            let w = I::tetra(r, apex[p as usize], pos(v), hubs[h as usize]) * f64::from(d);
            let (lo, hi) = self.pieces.pair[p as usize];
            acc[usize::from(lo)] += w;
            acc[usize::from(hi)] -= w;
        }
        let interfaces = self.pieces.interfaces(&apex);
        finish(r, acc, count, whole, self.stats, interfaces)
    }
}

/// Sums the six-fold tetrahedron integrals of the faces from `r`: per label, the face count per
/// label, and the whole.
fn face_integrals<I: Integrand>(
    r: [f64; 3],
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    face_labels: &[u8],
) -> (Vec<I>, [usize; 256], I) {
    let pos = |v: u32| vertices[v as usize];
    let mut acc = vec![I::default(); 256];
    let mut count = [0usize; 256];
    let mut whole = I::default();
    for (t, &l) in triangles.iter().zip(face_labels) {
        let d = I::tetra(r, pos(t[0]), pos(t[1]), pos(t[2]));
        acc[usize::from(l)] += d;
        count[usize::from(l)] += 1;
        whole += d;
    }
    (acc, count, whole)
}

/// An interface edge `a -> b`, oriented as the face with the smaller label `lo` runs it.
struct IEdge {
    a: u32,
    b: u32,
    lo: u8,
    hi: u8,
}

/// The edges whose two faces carry different labels.
fn interface_edges(table: &EdgeTable, face_labels: &[u8]) -> Vec<IEdge> {
    table
        .interior
        .iter()
        .filter_map(|e| {
            let (s, t) = (face_labels[e.face_fwd as usize], face_labels[e.face_back as usize]);
            match s.cmp(&t) {
                std::cmp::Ordering::Equal => None,
                std::cmp::Ordering::Less => Some(IEdge { a: e.from, b: e.to, lo: s, hi: t }),
                std::cmp::Ordering::Greater => Some(IEdge { a: e.to, b: e.from, lo: t, hi: s }),
            }
        })
        .collect()
}

/// Interface edges at each of the `n` vertices (CSR): vertex `v`'s edges are `at[start[v]..start[v + 1]]`.
fn edges_at_vertices(n: usize, iface: &[IEdge]) -> (Vec<usize>, Vec<u32>) {
    let mut start = vec![0usize; n + 1];
    for e in iface {
        start[e.a as usize + 1] += 1;
        start[e.b as usize + 1] += 1;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut at = vec![0u32; start[n]];
    for (k, e) in iface.iter().enumerate() {
        for v in [e.a, e.b] {
            at[fill[v as usize]] = k as u32;
            fill[v as usize] += 1;
        }
    }
    (start, at)
}

/// The piece of every interface edge (numbered 0.. in order of first edge) and the number of pieces:
/// edges are chained through regular vertices (exactly two interface edges with the same label pair).
fn chain_pieces(n: usize, iface: &[IEdge]) -> (Vec<u32>, usize) {
    let (start, at) = edges_at_vertices(n, iface);
    let mut uf = UnionFind::new(iface.len());
    for v in 0..n {
        let inc = &at[start[v]..start[v + 1]];
        if let [e0, e1] = inc {
            let (x, y) = (&iface[*e0 as usize], &iface[*e1 as usize]);
            if (x.lo, x.hi) == (y.lo, y.hi) {
                uf.union(*e0 as usize, *e1 as usize);
            }
        }
    }
    let mut piece_of_root = vec![u32::MAX; iface.len()];
    let mut piece = vec![0u32; iface.len()];
    let mut n_pieces = 0u32;
    for (k, pk) in piece.iter_mut().enumerate() {
        let root = uf.find(k);
        if piece_of_root[root] == u32::MAX {
            piece_of_root[root] = n_pieces;
            n_pieces += 1;
        }
        *pk = piece_of_root[root];
    }
    (piece, n_pieces as usize)
}

/// The centroid at `vertices` of each group of a CSR grouping (group `g` holds the vertex indices
/// `members[start[g]..start[g + 1]]`): a piece's apex, a junction cluster's hub.
fn group_centroids(start: &[usize], members: &[u32], vertices: &[[f64; 3]]) -> Vec<[f64; 3]> {
    start
        .windows(2)
        .map(|w| {
            let vs = &members[w[0]..w[1]];
            let sum = vs.iter().fold([0.0f64; 3], |s, &v| add(s, vertices[v as usize]));
            scale(sum, 1.0 / vs.len().max(1) as f64)
        })
        .collect()
}

/// The interface pieces: label pairs, distinct vertices and unmatched spokes (no positions).
struct Pieces {
    /// Piece of each interface edge.
    of_edge: Vec<u32>,
    /// Number of pieces.
    count: usize,
    /// `(smaller, larger)` label of each piece.
    pair: Vec<(u8, u8)>,
    /// `(piece, vertex, out - in)` on the smaller label's side, where non-zero: the ends of open pieces.
    spokes: Vec<(u32, u32, i32)>,
    /// Distinct vertices of each piece, ascending (CSR: piece `p`'s are `members[start[p]..start[p + 1]]`).
    start: Vec<usize>,
    /// See `start`.
    members: Vec<u32>,
}

impl Pieces {
    fn build(iface: &[IEdge], of_edge: Vec<u32>, np: usize) -> Pieces {
        let mut incid: Vec<(u32, u32, i32)> = Vec::with_capacity(iface.len() * 2);
        for (k, e) in iface.iter().enumerate() {
            incid.push((of_edge[k], e.a, 1));
            incid.push((of_edge[k], e.b, -1));
        }
        incid.sort_unstable_by_key(|x| (x.0, x.1));
        let mut start = vec![0usize; np + 1];
        let mut members = Vec::new();
        let mut spokes: Vec<(u32, u32, i32)> = Vec::new();
        let mut i = 0;
        while i < incid.len() {
            let (p, v, _) = incid[i];
            let mut d = 0;
            while i < incid.len() && incid[i].0 == p && incid[i].1 == v {
                d += incid[i].2;
                i += 1;
            }
            members.push(v);
            start[p as usize + 1] += 1;
            if d != 0 {
                spokes.push((p, v, d));
            }
        }
        for p in 0..np {
            start[p + 1] += start[p];
        }
        let mut pair = vec![(0u8, 0u8); np];
        for (k, e) in iface.iter().enumerate() {
            pair[of_edge[k] as usize] = (e.lo, e.hi);
        }
        Pieces { of_edge, count: np, pair, spokes, start, members }
    }

    /// The pieces as interfaces (label pair, apex, size, closed loop or not).
    fn interfaces(&self, apex: &[[f64; 3]]) -> Vec<Interface> {
        let mut open = vec![false; self.count];
        for &(p, _, _) in &self.spokes {
            open[p as usize] = true;
        }
        (0..self.count)
            .map(|p| Interface {
                lo: self.pair[p].0,
                hi: self.pair[p].1,
                centroid: apex[p],
                vertices: self.start[p + 1] - self.start[p],
                closed: !open[p],
            })
            .collect()
    }

    /// Piece fans: the smaller label gets (apex, b, a), the larger the same triangle reversed.
    fn add_fans<I: Integrand>(
        &self,
        r: [f64; 3],
        vertices: &[[f64; 3]],
        iface: &[IEdge],
        apex: &[[f64; 3]],
        acc: &mut [I],
    ) {
        let pos = |v: u32| vertices[v as usize];
        for (k, e) in iface.iter().enumerate() {
            let d = I::tetra(r, apex[self.of_edge[k] as usize], pos(e.b), pos(e.a));
            acc[usize::from(e.lo)] += d;
            acc[usize::from(e.hi)] -= d;
        }
    }
}

fn finish<I: Integrand>(
    reference: [f64; 3],
    acc: Vec<I>,
    count: [usize; 256],
    whole: I,
    caps: CapStats,
    interfaces: Vec<Interface>,
) -> LabelIntegrals<I> {
    let by_label = (0..256usize).filter(|&l| count[l] > 0).map(|l| (l as u8, acc[l], count[l])).collect();
    LabelIntegrals { reference, whole, by_label, caps, interfaces }
}

/// Volumes of every label of a mesh, m^3, signed: the whole and `(label, volume, faces)` per label.
/// The mesh must be closed, edge-manifold and consistently oriented; `face_labels` has one entry per
/// triangle (any u8). Exposed for callers with their own labels (e.g. a labelling under test).
pub fn volumes_by_label(mesh: &TriMesh, face_labels: &[u8]) -> Result<LabelVolumes, VolumeError> {
    if face_labels.len() != mesh.triangles.len() {
        return Err(VolumeError::LabelCountMismatch {
            what: "face",
            got: face_labels.len(),
            expected: mesh.triangles.len(),
        });
    }
    validate(mesh)?;
    let table = EdgeTable::build(&mesh.triangles);
    table.check_manifold(&mesh.vertices)?;
    if !table.boundary.is_empty() {
        return Err(open_error(&mesh.vertices, &table));
    }
    Ok(label_volumes(&mesh.vertices, &mesh.triangles, &table, face_labels))
}

/// Union-find with path halving; roots are the smallest member (deterministic).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect() }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let gp = self.parent[self.parent[x] as usize];
            self.parent[x] = gp;
            x = gp as usize;
        }
        x
    }

    fn union(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.parent[a.max(b)] = a.min(b) as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bsv_core::shapes::{icosphere, subdivided_cuboid};

    /// Every segment surface (faces + caps) is closed: its volume does not depend on the reference
    /// point, even with scattered random labels full of junctions.
    #[test]
    fn segment_surfaces_are_closed() {
        let mut state = 12345u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as u32
        };
        for mesh in [icosphere(1.0, 2), subdivided_cuboid([1.0, 0.5, 0.3], 4)] {
            let table = EdgeTable::build(&mesh.triangles);
            for round in 0..20 {
                let k = 2 + round % 5;
                let labels: Vec<u8> = (0..mesh.triangles.len()).map(|_| (next() % k) as u8).collect();
                let a = label_volumes_at([0.0; 3], &mesh.vertices, &mesh.triangles, &table, &labels);
                let b = label_volumes_at([3.0, -7.0, 5.0], &mesh.vertices, &mesh.triangles, &table, &labels);
                assert!(a.caps.junctions > 0);
                for (x, y) in a.by_label.iter().zip(&b.by_label) {
                    assert_eq!(x.0, y.0);
                    assert!((x.1 - y.1).abs() < 1e-12, "label {}: {} vs {}", x.0, x.1, y.1);
                }
                let sum: f64 = a.by_label.iter().map(|x| x.1).sum();
                assert!((sum - a.whole_m3).abs() < 1e-12);
            }
        }
    }
}
