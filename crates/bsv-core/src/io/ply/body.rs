//! PLY body decoding: a fast fixed-stride path for binary vertex elements (parallel, no per-record
//! allocation) and a streaming record reader shared by ascii and binary bodies for everything else.

use rayon::prelude::*;

use super::header::{Element, Header, PropKind, Scalar};
use super::{PlyData, PlyEncoding, PlyError};
use crate::segment::SEGMENT_COUNT;

/// Records above which the binary vertex path runs in parallel.
const PAR_MIN_RECORDS: usize = 1 << 16;

/// Decodes one binary scalar (the slice holds at least `ty.size()` bytes).
#[inline(always)]
fn decode(b: &[u8], ty: Scalar, big: bool) -> f64 {
    macro_rules! rd {
        ($t:ty, $n:expr) => {{
            let mut a = [0u8; $n];
            a.copy_from_slice(&b[..$n]);
            (if big { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
        }};
    }
    match ty {
        Scalar::I8 => f64::from(b[0] as i8),
        Scalar::U8 => f64::from(b[0]),
        Scalar::I16 => rd!(i16, 2),
        Scalar::U16 => rd!(u16, 2),
        Scalar::I32 => rd!(i32, 4),
        Scalar::U32 => rd!(u32, 4),
        Scalar::F32 => rd!(f32, 4),
        Scalar::F64 => rd!(f64, 8),
    }
}

/// A source of record values: a binary cursor or an ascii line tokenizer.
trait Source<'a> {
    /// Starts record `index` of `element`.
    fn begin(&mut self, element: &'a Element, index: usize) -> Result<(), PlyError>;
    /// The next value of the current record.
    fn value(&mut self, ty: Scalar) -> Result<f64, PlyError>;
    /// Ends the current record.
    fn end(&mut self) -> Result<(), PlyError>;
}

/// Binary cursor over the body.
struct Binary<'a> {
    body: &'a [u8],
    pos: usize,
    big: bool,
    element: &'a str,
    count: usize,
    index: usize,
    record_start: usize,
}

impl<'a> Source<'a> for Binary<'a> {
    #[inline]
    fn begin(&mut self, element: &'a Element, index: usize) -> Result<(), PlyError> {
        self.element = &element.name;
        self.count = element.count;
        self.index = index;
        self.record_start = self.pos;
        Ok(())
    }

    #[inline]
    fn value(&mut self, ty: Scalar) -> Result<f64, PlyError> {
        let n = ty.size();
        match self.body.get(self.pos..self.pos + n) {
            Some(b) => {
                self.pos += n;
                Ok(decode(b, ty, self.big))
            }
            None => Err(PlyError::Truncated {
                element: self.element.to_string(),
                index: self.index,
                count: self.count,
                offset: self.record_start,
                needed: self.pos + n - self.record_start,
                available: self.body.len() - self.record_start,
            }),
        }
    }

    #[inline]
    fn end(&mut self) -> Result<(), PlyError> {
        Ok(())
    }
}

/// Ascii tokenizer: one record per non-empty line.
struct Ascii<'a> {
    text: &'a [u8],
    /// Start of the next unread line.
    pos: usize,
    /// Line number of the line after `pos`'s previous line (1-based numbering of the whole file).
    line_no: usize,
    /// The current record's line and the cursor within it.
    line: &'a [u8],
    cursor: usize,
    element: &'a str,
    index: usize,
}

impl<'a> Ascii<'a> {
    fn record_error(&self, message: String) -> PlyError {
        PlyError::AsciiRecord { line: self.line_no, element: self.element.to_string(), index: self.index, message }
    }

    /// The next non-empty line, advancing the line counter.
    fn next_line(&mut self) -> Option<&'a [u8]> {
        while self.pos < self.text.len() {
            let rest = &self.text[self.pos..];
            let (line, adv) = super::header::next_line(rest);
            self.pos += adv;
            self.line_no += 1;
            if line.iter().any(|b| !b.is_ascii_whitespace()) {
                return Some(line);
            }
        }
        None
    }

    fn token(&mut self) -> Option<&'a [u8]> {
        let line = self.line;
        let mut i = self.cursor;
        while i < line.len() && line[i].is_ascii_whitespace() {
            i += 1;
        }
        if i == line.len() {
            self.cursor = i;
            return None;
        }
        let start = i;
        while i < line.len() && !line[i].is_ascii_whitespace() {
            i += 1;
        }
        self.cursor = i;
        Some(&line[start..i])
    }
}

impl<'a> Source<'a> for Ascii<'a> {
    fn begin(&mut self, element: &'a Element, index: usize) -> Result<(), PlyError> {
        self.element = &element.name;
        self.index = index;
        match self.next_line() {
            Some(line) => {
                self.line = line;
                self.cursor = 0;
                Ok(())
            }
            None => Err(PlyError::EndsEarly { element: element.name.clone(), index, count: element.count }),
        }
    }

    fn value(&mut self, _ty: Scalar) -> Result<f64, PlyError> {
        let Some(tok) = self.token() else {
            return Err(self.record_error("the line has fewer values than the header's properties".into()));
        };
        match std::str::from_utf8(tok).ok().and_then(|s| s.parse::<f64>().ok()) {
            Some(v) => Ok(v),
            None => Err(self.record_error(format!("{:?} is not a number", String::from_utf8_lossy(tok)))),
        }
    }

    fn end(&mut self) -> Result<(), PlyError> {
        if self.token().is_some() {
            return Err(self.record_error("the line has more values than the header's properties".into()));
        }
        Ok(())
    }
}

/// Slots of the vertex values BSV keeps.
const X: usize = 0;
const NX: usize = 3;
const RED: usize = 6;
const LABEL: usize = 9;
const N_SLOTS: usize = 10;

/// Where each vertex property goes (`None` = skipped) and the types of the kept ones.
struct VertexPlan {
    slot_of_prop: Vec<Option<usize>>,
    types: [Scalar; N_SLOTS],
    has_normals: bool,
    has_colors: bool,
    has_label: bool,
}

fn scalar_prop(el: &Element, name: &str) -> Option<(usize, Scalar)> {
    let i = el.find(name)?;
    match el.props[i].kind {
        PropKind::Scalar(s) => Some((i, s)),
        PropKind::List { .. } => None,
    }
}

fn vertex_plan(el: &Element) -> Result<VertexPlan, PlyError> {
    let mut slot_of_prop = vec![None; el.props.len()];
    let mut types = [Scalar::F64; N_SLOTS];
    let mut assign = |slot: usize, (p, ty): (usize, Scalar)| {
        slot_of_prop[p] = Some(slot);
        types[slot] = ty;
    };
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let found = scalar_prop(el, name).ok_or_else(|| PlyError::MissingProperty {
            element: el.name.clone(),
            property: (*name).to_string(),
            hint: "vertices need x, y and z (float or double); export the cloud with its coordinates",
        })?;
        assign(X + k, found);
    }
    let normals = ["nx", "ny", "nz"].map(|n| scalar_prop(el, n));
    let has_normals = normals.iter().all(Option::is_some);
    if has_normals {
        for (k, f) in normals.into_iter().enumerate() {
            if let Some(f) = f {
                assign(NX + k, f);
            }
        }
    }
    let mut colors = ["red", "green", "blue"].map(|n| scalar_prop(el, n));
    if !colors.iter().all(Option::is_some) {
        colors = ["diffuse_red", "diffuse_green", "diffuse_blue"].map(|n| scalar_prop(el, n));
    }
    let has_colors = colors.iter().all(Option::is_some);
    if has_colors {
        for (k, f) in colors.into_iter().enumerate() {
            if let Some(f) = f {
                assign(RED + k, f);
            }
        }
    }
    let label = scalar_prop(el, "label");
    let has_label = label.is_some();
    if let Some(f) = label {
        assign(LABEL, f);
    }
    Ok(VertexPlan { slot_of_prop, types, has_normals, has_colors, has_label })
}

/// Columns being filled for the vertex element.
#[derive(Default)]
struct VertexCols {
    points: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    colors: Option<Vec<[u8; 3]>>,
    labels: Option<Vec<u8>>,
}

#[inline]
fn to_color(v: f64, ty: Scalar) -> u8 {
    let v = if ty.is_float() { (v * 255.0).round() } else { v };
    // NaN maps to 0 through the saturating cast.
    v.clamp(0.0, 255.0) as u8
}

/// A label value as a segment id, or `None` when it is not one.
#[inline]
fn to_label(v: f64) -> Option<u8> {
    // `v as u8 as f64 == v` holds exactly for integral 0..=255 (NaN and negatives fail it).
    if v < SEGMENT_COUNT as f64 && f64::from(v as u8) == v {
        Some(v as u8)
    } else {
        None
    }
}

/// A binary scalar reader monomorphized on type and endianness (keeps the hot loops free of matches).
trait Rd {
    fn rd(b: &[u8]) -> f64;
}

macro_rules! readers {
    ($($name:ident: $t:ty, $n:expr, $from:ident;)*) => {$(
        struct $name;
        impl Rd for $name {
            #[inline(always)]
            fn rd(b: &[u8]) -> f64 {
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                <$t>::$from(a) as f64
            }
        }
    )*};
}

readers! {
    LeI8: i8, 1, from_le_bytes; LeU8: u8, 1, from_le_bytes;
    LeI16: i16, 2, from_le_bytes; BeI16: i16, 2, from_be_bytes;
    LeU16: u16, 2, from_le_bytes; BeU16: u16, 2, from_be_bytes;
    LeI32: i32, 4, from_le_bytes; BeI32: i32, 4, from_be_bytes;
    LeU32: u32, 4, from_le_bytes; BeU32: u32, 4, from_be_bytes;
    LeF32: f32, 4, from_le_bytes; BeF32: f32, 4, from_be_bytes;
    LeF64: f64, 8, from_le_bytes; BeF64: f64, 8, from_be_bytes;
}

/// Calls `$f::<Reader>($args)` with the reader for `($ty, $big)`.
macro_rules! dispatch {
    ($ty:expr, $big:expr, $f:ident($($arg:expr),*)) => {
        match ($ty, $big) {
            (Scalar::I8, _) => $f::<LeI8>($($arg),*),
            (Scalar::U8, _) => $f::<LeU8>($($arg),*),
            (Scalar::I16, false) => $f::<LeI16>($($arg),*),
            (Scalar::I16, true) => $f::<BeI16>($($arg),*),
            (Scalar::U16, false) => $f::<LeU16>($($arg),*),
            (Scalar::U16, true) => $f::<BeU16>($($arg),*),
            (Scalar::I32, false) => $f::<LeI32>($($arg),*),
            (Scalar::I32, true) => $f::<BeI32>($($arg),*),
            (Scalar::U32, false) => $f::<LeU32>($($arg),*),
            (Scalar::U32, true) => $f::<BeU32>($($arg),*),
            (Scalar::F32, false) => $f::<LeF32>($($arg),*),
            (Scalar::F32, true) => $f::<BeF32>($($arg),*),
            (Scalar::F64, false) => $f::<LeF64>($($arg),*),
            (Scalar::F64, true) => $f::<BeF64>($($arg),*),
        }
    };
}

/// Fills a triple column from records when its three fields share a type.
fn fill3<R: Rd>(data: &[u8], stride: usize, o: [usize; 3], out: &mut [[f64; 3]]) {
    for (r, p) in data.chunks_exact(stride).zip(out) {
        *p = [R::rd(&r[o[0]..]), R::rd(&r[o[1]..]), R::rd(&r[o[2]..])];
    }
}

/// Fills a triple column whatever its fields' types.
fn triple_column(data: &[u8], stride: usize, o: [usize; 3], t: [Scalar; 3], big: bool, out: &mut [[f64; 3]]) {
    if t[0] == t[1] && t[1] == t[2] {
        dispatch!(t[0], big, fill3(data, stride, o, out));
    } else {
        for (r, p) in data.chunks_exact(stride).zip(out) {
            *p = [decode(&r[o[0]..], t[0], big), decode(&r[o[1]..], t[1], big), decode(&r[o[2]..], t[2], big)];
        }
    }
}

/// Records per parallel block of the binary vertex path.
const BLOCK: usize = 1 << 14;

/// One block of the binary vertex path: its records and its slices of every output column.
struct Block<'a> {
    first: usize,
    data: &'a [u8],
    points: &'a mut [[f64; 3]],
    normals: Option<&'a mut [[f64; 3]]>,
    colors: Option<&'a mut [[u8; 3]]>,
    labels: Option<&'a mut [u8]>,
}

/// Per-block problems: first non-finite point and first bad label (absolute indices).
#[derive(Clone, Copy, Default)]
struct BlockIssues {
    non_finite: Option<usize>,
    bad_label: Option<usize>,
}

impl BlockIssues {
    fn merge(a: BlockIssues, b: BlockIssues) -> BlockIssues {
        let min = |x: Option<usize>, y: Option<usize>| match (x, y) {
            (Some(x), Some(y)) => Some(x.min(y)),
            (x, y) => x.or(y),
        };
        BlockIssues { non_finite: min(a.non_finite, b.non_finite), bad_label: min(a.bad_label, b.bad_label) }
    }
}

/// Byte offset within a record of each kept vertex slot.
fn slot_offsets(el: &Element, plan: &VertexPlan) -> [usize; N_SLOTS] {
    let mut offsets = [0usize; N_SLOTS];
    let mut off = 0;
    for (p, prop) in el.props.iter().enumerate() {
        if let Some(slot) = plan.slot_of_prop[p] {
            offsets[slot] = off;
        }
        if let PropKind::Scalar(s) = prop.kind {
            off += s.size();
        }
    }
    offsets
}

/// Record layout of a fixed-stride binary vertex element: what each block decoder needs.
#[derive(Clone, Copy)]
struct FixedVertexLayout {
    stride: usize,
    offsets: [usize; N_SLOTS],
    types: [Scalar; N_SLOTS],
    big: bool,
}

impl FixedVertexLayout {
    fn offsets3(&self, base: usize) -> [usize; 3] {
        [self.offsets[base], self.offsets[base + 1], self.offsets[base + 2]]
    }

    fn types3(&self, base: usize) -> [Scalar; 3] {
        [self.types[base], self.types[base + 1], self.types[base + 2]]
    }

    /// Decodes every column of one block and reports its problems.
    fn read_block(&self, b: Block<'_>) -> BlockIssues {
        let mut issues = BlockIssues::default();
        triple_column(b.data, self.stride, self.offsets3(X), self.types3(X), self.big, b.points);
        issues.non_finite = b
            .points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()))
            .map(|i| b.first + i);
        if let Some(nrm) = b.normals {
            triple_column(b.data, self.stride, self.offsets3(NX), self.types3(NX), self.big, nrm);
        }
        if let Some(col) = b.colors {
            self.read_colors(b.data, col);
        }
        if let Some(col) = b.labels {
            if let Some(i) = self.read_labels(b.data, col) {
                issues.bad_label = Some(b.first + i);
            }
        }
        issues
    }

    /// Colour column of one block (a plain byte copy when all three channels are `uchar`).
    fn read_colors(&self, data: &[u8], col: &mut [[u8; 3]]) {
        let (o, tt, big) = (self.offsets3(RED), self.types3(RED), self.big);
        if tt.iter().all(|&x| x == Scalar::U8) {
            for (r, c) in data.chunks_exact(self.stride).zip(col.iter_mut()) {
                *c = [r[o[0]], r[o[1]], r[o[2]]];
            }
        } else {
            for (r, c) in data.chunks_exact(self.stride).zip(col.iter_mut()) {
                *c = [0, 1, 2].map(|k| to_color(decode(&r[o[k]..], tt[k], big), tt[k]));
            }
        }
    }

    /// Label column of one block; the block-relative index of the first invalid label, if any.
    fn read_labels(&self, data: &[u8], col: &mut [u8]) -> Option<usize> {
        let mut bad_label = None;
        let (o, ty, big) = (self.offsets[LABEL], self.types[LABEL], self.big);
        for (i, (r, l)) in data.chunks_exact(self.stride).zip(col.iter_mut()).enumerate() {
            let label = if ty == Scalar::U8 {
                Some(r[o]).filter(|&l| usize::from(l) < SEGMENT_COUNT)
            } else {
                to_label(decode(&r[o..], ty, big))
            };
            match label {
                Some(x) => *l = x,
                None => {
                    bad_label.get_or_insert(i);
                }
            }
        }
        bad_label
    }
}

/// Cuts the records and every output column into aligned blocks of `BLOCK` records.
fn split_blocks<'a>(data: &'a [u8], stride: usize, cols: &'a mut VertexCols) -> Vec<Block<'a>> {
    let mut blocks = Vec::with_capacity(cols.points.len() / BLOCK + 1);
    let mut pc = cols.points.chunks_mut(BLOCK);
    let mut nc = cols.normals.as_mut().map(|v| v.chunks_mut(BLOCK));
    let mut cc = cols.colors.as_mut().map(|v| v.chunks_mut(BLOCK));
    let mut lc = cols.labels.as_mut().map(|v| v.chunks_mut(BLOCK));
    for (k, d) in data.chunks(BLOCK * stride).enumerate() {
        let Some(p) = pc.next() else { break };
        blocks.push(Block {
            first: k * BLOCK,
            data: d,
            points: p,
            normals: nc.as_mut().and_then(Iterator::next),
            colors: cc.as_mut().and_then(Iterator::next),
            labels: lc.as_mut().and_then(Iterator::next),
        });
    }
    blocks
}

/// Reads the vertex element from a fixed-stride binary body slice in one fused pass over blocks
/// (parallel for large clouds), with readers specialised per type and endianness.
fn vertices_fixed(
    data: &[u8],
    stride: usize,
    el: &Element,
    plan: &VertexPlan,
    big: bool,
) -> Result<VertexCols, PlyError> {
    let layout = FixedVertexLayout { stride, offsets: slot_offsets(el, plan), types: plan.types, big };
    let n = el.count;
    let mut cols = VertexCols {
        points: vec![[0.0f64; 3]; n],
        normals: plan.has_normals.then(|| vec![[0.0f64; 3]; n]),
        colors: plan.has_colors.then(|| vec![[0u8; 3]; n]),
        labels: plan.has_label.then(|| vec![0u8; n]),
    };
    let blocks = split_blocks(data, stride, &mut cols);
    let run = |b: Block<'_>| layout.read_block(b);
    let issues = if n >= PAR_MIN_RECORDS {
        blocks.into_par_iter().map(run).reduce(BlockIssues::default, BlockIssues::merge)
    } else {
        blocks.into_iter().map(run).fold(BlockIssues::default(), BlockIssues::merge)
    };
    if let Some(index) = issues.bad_label {
        let value = decode(&data[index * stride + layout.offsets[LABEL]..], layout.types[LABEL], big);
        return Err(PlyError::LabelOutOfRange { element: el.name.clone(), index, value });
    }
    if let Some(vertex) = issues.non_finite {
        let value = cols.points[vertex].iter().copied().find(|c| !c.is_finite()).unwrap_or(f64::NAN);
        return Err(PlyError::NonFinite { vertex, value });
    }
    Ok(cols)
}

/// Reads one record's list or scalar that BSV does not keep.
#[inline]
fn skip_prop<'a, S: Source<'a>>(src: &mut S, kind: PropKind, el: &Element, index: usize) -> Result<(), PlyError> {
    match kind {
        PropKind::Scalar(s) => {
            src.value(s)?;
        }
        PropKind::List { count, item } => {
            let n = list_len(src.value(count)?, el, index)?;
            for _ in 0..n {
                src.value(item)?;
            }
        }
    }
    Ok(())
}

fn list_len(v: f64, el: &Element, index: usize) -> Result<usize, PlyError> {
    if v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64 {
        Ok(v as usize)
    } else {
        Err(PlyError::BadListCount { element: el.name.clone(), index, value: v })
    }
}

/// Capacity hint bounded by what the remaining body could hold (never trusts a header count blindly).
fn capacity(count: usize, remaining: usize, min_record: usize) -> usize {
    count.min(remaining / min_record.max(1) + 1)
}

/// Reads the vertex element record by record (ascii, or binary with list properties).
fn vertices_stream<'a, S: Source<'a>>(
    src: &mut S,
    el: &'a Element,
    plan: &VertexPlan,
    remaining: usize,
) -> Result<VertexCols, PlyError> {
    let cap = capacity(el.count, remaining, el.min_size());
    let mut cols = VertexCols {
        points: Vec::with_capacity(cap),
        normals: plan.has_normals.then(|| Vec::with_capacity(cap)),
        colors: plan.has_colors.then(|| Vec::with_capacity(cap)),
        labels: plan.has_label.then(|| Vec::with_capacity(cap)),
    };
    let t = plan.types;
    for index in 0..el.count {
        src.begin(el, index)?;
        let mut v = [0.0f64; N_SLOTS];
        for (p, prop) in el.props.iter().enumerate() {
            match (plan.slot_of_prop[p], prop.kind) {
                (Some(slot), PropKind::Scalar(s)) => v[slot] = src.value(s)?,
                (_, kind) => skip_prop(src, kind, el, index)?,
            }
        }
        src.end()?;
        cols.points.push([v[X], v[X + 1], v[X + 2]]);
        if let Some(n) = cols.normals.as_mut() {
            n.push([v[NX], v[NX + 1], v[NX + 2]]);
        }
        if let Some(c) = cols.colors.as_mut() {
            c.push([to_color(v[RED], t[RED]), to_color(v[RED + 1], t[RED + 1]), to_color(v[RED + 2], t[RED + 2])]);
        }
        if let Some(l) = cols.labels.as_mut() {
            let value = v[LABEL];
            l.push(to_label(value).ok_or_else(|| PlyError::LabelOutOfRange {
                element: el.name.clone(),
                index,
                value,
            })?);
        }
    }
    Ok(cols)
}

/// Triangles and optional labels of the face element.
struct FaceCols {
    triangles: Vec<[u32; 3]>,
    labels: Option<Vec<u8>>,
}

/// Layout of a binary face element whose records would all be triangles: every property a scalar
/// except the index list, read as if each list held 3 items.
struct TriLayout {
    stride: usize,
    count_off: usize,
    count_ty: Scalar,
    idx_off: usize,
    idx_ty: Scalar,
    label: Option<(usize, Scalar)>,
}

fn tri_layout(el: &Element, list: usize) -> Option<TriLayout> {
    let mut off = 0;
    let mut layout =
        TriLayout { stride: 0, count_off: 0, count_ty: Scalar::U8, idx_off: 0, idx_ty: Scalar::U8, label: None };
    for (p, prop) in el.props.iter().enumerate() {
        match prop.kind {
            PropKind::List { count, item } if p == list => {
                layout.count_off = off;
                layout.count_ty = count;
                layout.idx_off = off + count.size();
                layout.idx_ty = item;
                off += count.size() + 3 * item.size();
            }
            PropKind::List { .. } => return None,
            PropKind::Scalar(s) => {
                if prop.name == "label" {
                    layout.label = Some((off, s));
                }
                off += s.size();
            }
        }
    }
    layout.stride = off;
    Some(layout)
}

/// Decodes triangle records; false when a record is not a triangle or an index is invalid (the
/// streaming reader then re-reads the element and reports the exact problem).
fn fill_tris<R: Rd>(data: &[u8], l: &TriLayout, big: bool, n_vertices: usize, out: &mut [[u32; 3]]) -> bool {
    let isz = l.idx_ty.size();
    let nv = n_vertices as f64;
    let valid = |v: f64| v < nv && f64::from(v as u32) == v;
    for (r, t) in data.chunks_exact(l.stride).zip(out) {
        let n = if l.count_ty == Scalar::U8 {
            f64::from(r[l.count_off])
        } else {
            decode(&r[l.count_off..], l.count_ty, big)
        };
        let o = l.idx_off;
        let (a, b, c) = (R::rd(&r[o..]), R::rd(&r[o + isz..]), R::rd(&r[o + 2 * isz..]));
        if n != 3.0 || !(valid(a) && valid(b) && valid(c)) {
            return false;
        }
        *t = [a as u32, b as u32, c as u32];
    }
    true
}

/// Fast path for binary face elements made only of triangles: fixed stride, parallel blocks.
/// `None` when the element does not fit that shape (the caller streams it instead).
fn faces_fixed(body: &[u8], el: &Element, list: usize, n_vertices: usize, big: bool) -> Option<FaceCols> {
    let l = tri_layout(el, list)?;
    let n = el.count;
    let data = body.get(..l.stride.checked_mul(n)?)?;
    let mut triangles = vec![[0u32; 3]; n];
    let mut labels = l.label.map(|_| vec![0u8; n]);
    type Job<'a> = (&'a [u8], (&'a mut [[u32; 3]], Option<&'a mut [u8]>));
    let run = |(d, (t, lab)): Job<'_>| -> bool {
        if !dispatch!(l.idx_ty, big, fill_tris(d, &l, big, n_vertices, t)) {
            return false;
        }
        if let (Some(lab), Some((o, ty))) = (lab, l.label) {
            for (r, x) in d.chunks_exact(l.stride).zip(lab.iter_mut()) {
                match to_label(decode(&r[o..], ty, big)) {
                    Some(v) => *x = v,
                    None => return false,
                }
            }
        }
        true
    };
    let mut jobs = Vec::with_capacity(n / BLOCK + 1);
    {
        let mut lc = labels.as_mut().map(|v| v.chunks_mut(BLOCK));
        for (d, t) in data.chunks(BLOCK * l.stride).zip(triangles.chunks_mut(BLOCK)) {
            jobs.push((d, (t, lc.as_mut().and_then(Iterator::next))));
        }
    }
    let ok = if n >= PAR_MIN_RECORDS { jobs.into_par_iter().all(run) } else { jobs.into_iter().all(run) };
    ok.then_some(FaceCols { triangles, labels })
}

fn face_list_prop(el: &Element) -> Result<usize, PlyError> {
    ["vertex_indices", "vertex_index"]
        .iter()
        .find_map(|n| el.find(n).filter(|&i| matches!(el.props[i].kind, PropKind::List { .. })))
        .ok_or_else(|| PlyError::MissingProperty {
            element: el.name.clone(),
            property: "vertex_indices (or vertex_index) list".into(),
            hint: "faces need a list of vertex indices; export the mesh with its faces, or drop the face element",
        })
}

fn faces_stream<'a, S: Source<'a>>(
    src: &mut S,
    el: &'a Element,
    n_vertices: usize,
    remaining: usize,
) -> Result<FaceCols, PlyError> {
    let list = face_list_prop(el)?;
    let label = scalar_prop(el, "label").map(|(i, _)| i);
    let cap = capacity(el.count, remaining, el.min_size());
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(cap);
    let mut labels: Option<Vec<u8>> = label.map(|_| Vec::with_capacity(cap));
    let index_of = |v: f64, face: usize| -> Result<u32, PlyError> {
        if v >= 0.0 && v < n_vertices as f64 && v.fract() == 0.0 {
            Ok(v as u32)
        } else {
            Err(PlyError::FaceIndexOutOfRange { face, index: v, vertex_count: n_vertices })
        }
    };
    for face in 0..el.count {
        src.begin(el, face)?;
        let before = triangles.len();
        let mut face_label = 0u8;
        for (p, prop) in el.props.iter().enumerate() {
            match prop.kind {
                PropKind::List { count, item } if p == list => {
                    let n = list_len(src.value(count)?, el, face)?;
                    if n < 3 {
                        return Err(PlyError::FaceTooSmall { face, n });
                    }
                    let a = index_of(src.value(item)?, face)?;
                    let mut b = index_of(src.value(item)?, face)?;
                    for _ in 2..n {
                        let c = index_of(src.value(item)?, face)?;
                        triangles.push([a, b, c]);
                        b = c;
                    }
                }
                PropKind::Scalar(s) if Some(p) == label => {
                    let value = src.value(s)?;
                    face_label = to_label(value).ok_or_else(|| PlyError::LabelOutOfRange {
                        element: el.name.clone(),
                        index: face,
                        value,
                    })?;
                }
                kind => skip_prop(src, kind, el, face)?,
            }
        }
        src.end()?;
        if let Some(l) = labels.as_mut() {
            l.resize(l.len() + triangles.len() - before, face_label);
        }
    }
    Ok(FaceCols { triangles, labels })
}

fn skip_stream<'a, S: Source<'a>>(src: &mut S, el: &'a Element) -> Result<(), PlyError> {
    if el.props.is_empty() {
        // Records without properties hold no data in either encoding.
        return Ok(());
    }
    for index in 0..el.count {
        src.begin(el, index)?;
        for prop in &el.props {
            skip_prop(src, prop.kind, el, index)?;
        }
        src.end()?;
    }
    Ok(())
}

/// First non-finite coordinate, as a typed error (the binary fixed-stride path checks while decoding).
fn check_finite(points: &[[f64; 3]]) -> Result<(), PlyError> {
    match points.iter().position(|p| !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite())) {
        Some(vertex) => {
            let value = points[vertex].iter().copied().find(|c| !c.is_finite()).unwrap_or(f64::NAN);
            Err(PlyError::NonFinite { vertex, value })
        }
        None => Ok(()),
    }
}

/// The columns decoded from a body (each element is optional in the file).
#[derive(Default)]
struct BodyCols {
    vertices: Option<VertexCols>,
    faces: Option<FaceCols>,
}

/// Decodes the body that follows `header` in `bytes`.
pub(super) fn read_body(bytes: &[u8], header: &Header) -> Result<PlyData, PlyError> {
    let body = bytes.get(header.body_offset..).unwrap_or(&[]);
    let vertex_el = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| PlyError::MissingElement { element: "vertex".into() })?;
    let plan = vertex_plan(vertex_el)?;
    let n_vertices = vertex_el.count;
    let data = PlyData { encoding: header.encoding, comments: header.comments.clone(), ..PlyData::default() };
    let cols = match header.encoding {
        PlyEncoding::Ascii => read_ascii_body(body, header, &plan, n_vertices)?,
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let big = header.encoding == PlyEncoding::BinaryBigEndian;
            read_binary_body(body, header, &plan, n_vertices, big)?
        }
    };
    Ok(with_columns(data, cols))
}

/// Moves the decoded columns into `data`.
fn with_columns(mut data: PlyData, cols: BodyCols) -> PlyData {
    let v = cols.vertices.unwrap_or_default();
    data.points = v.points;
    data.normals = v.normals;
    data.colors = v.colors;
    data.vertex_labels = v.labels;
    if let Some(f) = cols.faces {
        data.triangles = Some(f.triangles);
        data.face_labels = f.labels;
    }
    data
}

/// Decodes an ascii body: every element streamed line by line, then no non-empty line may follow.
fn read_ascii_body(body: &[u8], header: &Header, plan: &VertexPlan, n_vertices: usize) -> Result<BodyCols, PlyError> {
    let mut cols = BodyCols::default();
    let mut src = Ascii { text: body, pos: 0, line_no: header.lines, line: &[], cursor: 0, element: "", index: 0 };
    for el in &header.elements {
        let remaining = body.len() - src.pos.min(body.len());
        match el.name.as_str() {
            "vertex" => {
                let v = vertices_stream(&mut src, el, plan, remaining)?;
                check_finite(&v.points)?;
                cols.vertices = Some(v);
            }
            "face" => cols.faces = Some(faces_stream(&mut src, el, n_vertices, remaining)?),
            _ => skip_stream(&mut src, el)?,
        }
    }
    let mut extra_lines = 0usize;
    let first_extra = src.line_no + 1;
    while src.next_line().is_some() {
        extra_lines += 1;
    }
    if extra_lines > 0 {
        return Err(extra_data(header, format!("{extra_lines} extra non-empty line(s) from line {first_extra}")));
    }
    Ok(cols)
}

/// Decodes a binary body: fixed-stride fast paths where the element allows, streaming otherwise;
/// only zero or whitespace padding may follow.
fn read_binary_body(
    body: &[u8],
    header: &Header,
    plan: &VertexPlan,
    n_vertices: usize,
    big: bool,
) -> Result<BodyCols, PlyError> {
    let mut cols = BodyCols::default();
    let mut src = Binary { body, pos: 0, big, element: "", count: 0, index: 0, record_start: 0 };
    for el in &header.elements {
        let remaining = body.len() - src.pos;
        match (el.name.as_str(), el.fixed_size()) {
            ("face", _) => cols.faces = Some(read_binary_faces(&mut src, el, n_vertices, remaining)?),
            (name, Some(stride)) if stride > 0 => {
                let span = fixed_span(&src, el, stride, remaining)?;
                if name == "vertex" {
                    cols.vertices = Some(vertices_fixed(span, stride, el, plan, big)?);
                }
                src.pos += span.len();
            }
            ("vertex", _) => {
                let v = vertices_stream(&mut src, el, plan, remaining)?;
                check_finite(&v.points)?;
                cols.vertices = Some(v);
            }
            _ => skip_stream(&mut src, el)?,
        }
    }
    let extra = &body[src.pos..];
    if extra.iter().any(|&b| b != 0 && !b.is_ascii_whitespace()) {
        return Err(extra_data(header, format!("{} extra byte(s) at body offset {}", extra.len(), src.pos)));
    }
    Ok(cols)
}

/// The face element of a binary body: the all-triangles fast path, else the streaming reader
/// (which also reports the exact problem when the fast path rejects the element).
fn read_binary_faces<'a>(
    src: &mut Binary<'a>,
    el: &'a Element,
    n_vertices: usize,
    remaining: usize,
) -> Result<FaceCols, PlyError> {
    let list = face_list_prop(el)?;
    match faces_fixed(&src.body[src.pos..], el, list, n_vertices, src.big) {
        Some(f) => {
            src.pos += f.triangles.len() * tri_layout(el, list).map_or(0, |l| l.stride);
            Ok(f)
        }
        None => faces_stream(src, el, n_vertices, remaining),
    }
}

/// The bytes of a fixed-stride element at the cursor, or `Truncated` when the body is too short.
fn fixed_span<'a>(src: &Binary<'a>, el: &Element, stride: usize, remaining: usize) -> Result<&'a [u8], PlyError> {
    let needed = stride.saturating_mul(el.count);
    if needed > remaining {
        return Err(PlyError::Truncated {
            element: el.name.clone(),
            index: remaining / stride,
            count: el.count,
            offset: src.pos,
            needed,
            available: remaining,
        });
    }
    Ok(&src.body[src.pos..src.pos + needed])
}

fn extra_data(header: &Header, extra: String) -> PlyError {
    let (element, count) = header.elements.last().map(|e| (e.name.clone(), e.count)).unwrap_or_default();
    PlyError::ExtraData { element, count, extra }
}
