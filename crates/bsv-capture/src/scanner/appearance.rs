//! How a scan with a room looks in the colour render: the subject's skin tone, underwear and hair, the
//! floor and wall colours, and the lighting (two directional lights and ambient, Lambert, in one of four
//! set-ups and three colour temperatures). Chosen deterministically from the scan seed
//! ([`Appearance::from_seed`]), so that a segmentation front-end meets varied subjects under varied
//! lights in a room rather than one skin tone on grey under one lamp.

use super::mix_seed;
use super::room::SurfaceKind;
use bsv_core::{Segment, TriMesh};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Stream id of the appearance draws.
const STREAM_APPEARANCE: u64 = 0xA9;

/// Skin tones, light to dark (sRGB).
pub const SKIN_TONES: [[u8; 3]; 7] =
    [[255, 224, 196], [234, 192, 160], [224, 172, 140], [198, 140, 105], [160, 105, 72], [112, 72, 48], [80, 52, 36]];
const UNDERWEAR_COLOURS: [[u8; 3]; 6] =
    [[25, 25, 28], [30, 40, 80], [235, 235, 235], [120, 120, 125], [150, 30, 35], [40, 80, 150]];
const HAIR_COLOURS: [[u8; 3]; 6] =
    [[20, 18, 18], [55, 38, 28], [100, 70, 45], [200, 170, 110], [160, 160, 160], [140, 60, 30]];
const FLOOR_COLOURS: [[u8; 3]; 4] = [[150, 150, 145], [190, 175, 150], [150, 110, 70], [110, 120, 130]];
const WALL_COLOURS: [[u8; 3]; 4] = [[225, 222, 215], [200, 215, 200], [200, 210, 225], [215, 205, 185]];
/// Colour temperatures of the lights (per-channel factor): neutral, warm (tungsten-like), cool (daylight
/// through a window, cold LED panels).
const LIGHT_TINTS: [[f64; 3]; 3] = [[1.0, 1.0, 1.0], [1.0, 0.92, 0.78], [0.88, 0.95, 1.05]];

/// Where the two lights of a room hang ([`Appearance::from_seed`] draws one per scan). Directions are
/// world-frame (x: the subject's left, y: up, z: toward the front camera).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightSetup {
    /// A key light from the front left above and a fill from the back right above (the rig's lamp
    /// until round 2 session 17, still one scan in four).
    KeyFrontLeft,
    /// The same mirrored: key from the front right, fill from the back left.
    KeyFrontRight,
    /// Ceiling lights: both steeply from above (dim vertical surfaces, bright shoulders and feet).
    Overhead,
    /// A strong light from one side (a window): one half of the body bright, the other lit by the fill
    /// and the ambient only.
    Side,
}

impl LightSetup {
    /// The key and fill directions (unit vectors toward the lights).
    fn directions(self) -> [[f64; 3]; 2] {
        match self {
            LightSetup::KeyFrontLeft => [unit([0.5, 0.8, 0.7]), unit([-0.5, 0.7, -0.7])],
            LightSetup::KeyFrontRight => [unit([-0.5, 0.8, 0.7]), unit([0.5, 0.7, -0.7])],
            LightSetup::Overhead => [unit([0.15, 1.0, 0.35]), unit([-0.15, 1.0, -0.35])],
            LightSetup::Side => [unit([1.0, 0.35, 0.1]), unit([-1.0, 0.5, -0.2])],
        }
    }
}

/// Cut of the underwear.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnderwearStyle {
    /// Briefs: a band from just below the crotch to the waist.
    Briefs,
    /// Trunks: down over the upper thighs.
    Trunks,
}

/// A directional light.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Unit world-frame direction from the surface toward the light.
    pub toward: [f64; 3],
    /// Intensity (1 = full albedo on a surface facing it).
    pub intensity: f64,
}

/// How far long hair hangs below the top of the head at the back, metres ([`Look::long_hair`]): from
/// the shoulders' height to the shoulder blades'.
pub const LONG_HAIR_DOWN_M: (f64, f64) = (0.30, 0.45);
/// Half the width of long hair hanging over the neck and the upper back, metres (about a head's).
pub const LONG_HAIR_HALF_WIDTH_M: f64 = 0.10;

/// The band a top ([`Look::top`]) covers on the torso, as fractions of the height from the crotch to the
/// top of the head: from below the bust to above it (a sports top or a bra's band and cups).
pub const TOP_BAND: (f64, f64) = (0.38, 0.56);

/// Looks a scan can be asked for beyond what [`Appearance::from_seed`] draws (a cohort widened to a
/// failure class; every scan of a seed keeps its other draws). Default: none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Look {
    /// Long hair: a subject with hair hangs it down over the neck and the upper back, the back camera's
    /// view (to [`LONG_HAIR_DOWN_M`] below the top of the head, drawn from the seed; a bald subject stays
    /// bald).
    pub long_hair: bool,
    /// A top in the underwear's colour over the chest ([`TOP_BAND`] of the torso), front and back.
    pub top: bool,
    /// Smooth shading: the body is lit with normals interpolated across each triangle from the mesh's
    /// vertex normals, as skin looks and as most renderers draw a mesh, instead of each triangle's own
    /// flat normal (the rig's default, which shows the mesh's facets). Depth and labels are unchanged.
    pub smooth_shading: bool,
    /// The colour as a camera's sensor records it: the optics' blur ([`COLOUR_BLUR_PX`]) and shot and read
    /// noise ([`COLOUR_READ_NOISE`], [`COLOUR_SHOT_NOISE`]) instead of the render's exact pixels.
    pub colour_sensor: bool,
}

/// The colour sensor's blur ([`Look::colour_sensor`]): a Gaussian of this sigma, pixels (the optics and the
/// demosaicing of an RGB camera at its native resolution spread an edge over about two pixels).
pub const COLOUR_BLUR_PX: f32 = 0.7;
/// The colour sensor's read noise: sigma in 8-bit levels, at every level.
pub const COLOUR_READ_NOISE: f64 = 1.5;
/// The colour sensor's shot noise: the variance grows by this many squared levels per level of signal
/// (2.9 levels sd at mid-grey with the read noise; an indoor RGB camera's).
pub const COLOUR_SHOT_NOISE: f64 = 0.05;

/// The look of a scan with a room.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Appearance {
    /// Skin albedo (sRGB).
    pub skin: [u8; 3],
    /// Underwear colour (sRGB).
    pub underwear: [u8; 3],
    /// Underwear cut.
    pub underwear_style: UnderwearStyle,
    /// Height of the waistband above the crotch, metres.
    pub waist_rise_m: f64,
    /// Hair colour (sRGB).
    pub hair: [u8; 3],
    /// How far hair comes down from the top of the head, metres (0 = bald); at the back of the head
    /// it comes down 2.5 times as far.
    pub hair_length_m: f64,
    /// Long hair ([`Look::long_hair`]): how far it hangs below the top of the head at the back, over the
    /// head, the neck and the upper back, within [`LONG_HAIR_HALF_WIDTH_M`] of the head's middle; 0: not long.
    #[serde(default)]
    pub hair_down_m: f64,
    /// A top in the underwear's colour over the chest ([`Look::top`]).
    #[serde(default)]
    pub top: bool,
    /// The body lit with interpolated vertex normals ([`Look::smooth_shading`]).
    #[serde(default)]
    pub smooth_shading: bool,
    /// The colour blurred and noisy as a sensor records it ([`Look::colour_sensor`]).
    #[serde(default)]
    pub colour_sensor: bool,
    /// Floor albedo (sRGB).
    pub floor: [u8; 3],
    /// Floor tile size, metres.
    pub floor_tile_m: f64,
    /// Wall albedo (sRGB).
    pub wall: [u8; 3],
    /// Ambient light (fraction of the albedo everywhere).
    pub ambient: f64,
    /// Where the lights hang.
    pub light_setup: LightSetup,
    /// The two directional lights: the key, then the fill.
    pub lights: [Light; 2],
    /// Colour of the light (per-channel factor on every lit surface: ambient and directional alike).
    pub tint: [f64; 3],
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / n)
}

impl Appearance {
    /// The appearance of scan seed `seed`: a skin tone of [`SKIN_TONES`], underwear (briefs or
    /// trunks, six colours), hair (six colours, 1 in 8 bald), floor and wall colours, and the light: a
    /// set-up of [`LightSetup`], an ambient of 0.2-0.4 and two lights making the total 1.0-1.25 (1.2 before; the key
    /// 0.6-0.8 of the directional part, the fill the rest), and a colour of [`LIGHT_TINTS`].
    /// Deterministic; the subject's and the room's draws come first, as before the lights varied, so a
    /// seed dresses its subject as it always did.
    pub fn from_seed(seed: u64) -> Appearance {
        let mut rng = rand::rngs::StdRng::seed_from_u64(mix_seed(seed, STREAM_APPEARANCE, 0));
        let mut pick = |n: usize| rng.random_range(0..n);
        let skin = SKIN_TONES[pick(SKIN_TONES.len())];
        let underwear = UNDERWEAR_COLOURS[pick(UNDERWEAR_COLOURS.len())];
        let underwear_style = if pick(2) == 0 { UnderwearStyle::Briefs } else { UnderwearStyle::Trunks };
        let hair = HAIR_COLOURS[pick(HAIR_COLOURS.len())];
        let bald = pick(8) == 0;
        let floor = FLOOR_COLOURS[pick(FLOOR_COLOURS.len())];
        let wall = WALL_COLOURS[pick(WALL_COLOURS.len())];
        let tile = [0.3, 0.4, 0.5, 0.6][pick(4)];
        let waist_rise_m = rng.random_range(0.10..0.18);
        let hair_length_m = if bald { 0.0 } else { rng.random_range(0.04..0.08) };
        let key = rng.random_range(0.5..0.65);
        let light_setup = [LightSetup::KeyFrontLeft, LightSetup::KeyFrontRight, LightSetup::Overhead, LightSetup::Side]
            [rng.random_range(0..4)];
        let key_share = 0.6 + (key - 0.5) / 0.15 * 0.2; // the same draw, as the key's share: 0.6-0.8
        let ambient: f64 = rng.random_range(0.2..0.4);
        let directional = rng.random_range(1.0..1.25) - ambient;
        let (key, fill) = (key_share * directional, (1.0 - key_share) * directional);
        let tint = LIGHT_TINTS[rng.random_range(0..LIGHT_TINTS.len())];
        let [toward_key, toward_fill] = light_setup.directions();
        Appearance {
            skin,
            underwear,
            underwear_style,
            waist_rise_m,
            hair,
            hair_length_m,
            hair_down_m: 0.0,
            top: false,
            smooth_shading: false,
            colour_sensor: false,
            floor,
            floor_tile_m: tile,
            wall,
            ambient,
            light_setup,
            lights: [Light { toward: toward_key, intensity: key }, Light { toward: toward_fill, intensity: fill }],
            tint,
        }
    }
}

impl Appearance {
    /// [`Appearance::from_seed`] with `look` on top: its other draws are the seed's as always.
    pub fn from_seed_with(seed: u64, look: &Look) -> Appearance {
        let mut a = Appearance::from_seed(seed);
        if look.long_hair && a.hair_length_m > 0.0 {
            let (lo, hi) = LONG_HAIR_DOWN_M;
            a.hair_down_m = lo + (hi - lo) * hash01(seed as i64, 0x4A1);
        }
        a.top = look.top;
        a.smooth_shading = look.smooth_shading;
        a.colour_sensor = look.colour_sensor;
        a
    }
}

/// Heights of a body that place underwear and hair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyHeights {
    /// Height of the crotch: the lowest torso vertex, metres.
    pub crotch_y: f64,
    /// Height of the top of the head (the highest vertex), metres.
    pub top_y: f64,
    /// x of the head's middle (the mean of its vertices; 0 without head vertices), metres: where long hair
    /// hangs.
    #[serde(default)]
    pub head_x: f64,
}

impl BodyHeights {
    /// From the mesh and its face labels: the crotch is the lowest corner of a torso face (47 % of
    /// the height above the lowest vertex when nothing is labelled torso), the top the highest vertex.
    pub fn of(mesh: &TriMesh, face_labels: &[u8]) -> BodyHeights {
        let ys = || mesh.vertices.iter().map(|p| p[1]);
        let top_y = ys().fold(f64::NEG_INFINITY, f64::max);
        let low_y = ys().fold(f64::INFINITY, f64::min);
        let torso = Segment::Torso as u8;
        let crotch = mesh
            .triangles
            .iter()
            .zip(face_labels)
            .filter(|(_, &l)| l == torso)
            .flat_map(|(t, _)| t.iter().filter_map(|&i| mesh.vertices.get(i as usize).map(|p| p[1])))
            .fold(f64::INFINITY, f64::min);
        let crotch_y = if crotch.is_finite() { crotch } else { low_y + 0.47 * (top_y - low_y) };
        let head = Segment::Head as u8;
        let mut head_vertices = vec![false; mesh.vertices.len()];
        for (t, _) in mesh.triangles.iter().zip(face_labels).filter(|(_, &l)| l == head) {
            for &i in t {
                if let Some(v) = head_vertices.get_mut(i as usize) {
                    *v = true;
                }
            }
        }
        let (sum, n) = mesh
            .vertices
            .iter()
            .zip(&head_vertices)
            .filter(|(_, &h)| h)
            .fold((0.0, 0usize), |(s, n), (p, _)| (s + p[0], n + 1));
        let head_x = if n > 0 { sum / n as f64 } else { 0.0 };
        BodyHeights { crotch_y, top_y, head_x }
    }
}

/// One pixel's surface for the colour render.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePixel {
    /// What was hit.
    pub kind: SurfaceKind,
    /// Segment label (body pixels).
    pub label: u8,
    /// World hit point.
    pub point: [f64; 3],
    /// Unit world normal toward the camera.
    pub normal: [f64; 3],
}

/// A small deterministic hash of two integers into [0, 1).
fn hash01(a: i64, b: i64) -> f64 {
    (mix_seed(a as u64, 0x7113, b as u64) >> 11) as f64 / (1u64 << 53) as f64
}

impl Appearance {
    /// Albedo of a body pixel: hair on the top and back of the head (long hair also down the neck and the
    /// upper back), underwear over the pelvis (and with a top over the chest), skin elsewhere.
    fn body_albedo(&self, heights: &BodyHeights, label: u8, p: [f64; 3], n: [f64; 3]) -> [f64; 3] {
        let y = p[1];
        let hangs = label == Segment::Head as u8 || label == Segment::Torso as u8;
        if self.hair_down_m > 0.0
            && hangs
            && n[2] < -0.2
            && y > heights.top_y - self.hair_down_m
            && (p[0] - heights.head_x).abs() < LONG_HAIR_HALF_WIDTH_M
        {
            return self.hair.map(f64::from);
        }
        if label == Segment::Head as u8 && self.hair_length_m > 0.0 {
            let reach = if n[2] < -0.2 { 2.5 * self.hair_length_m } else { self.hair_length_m };
            if y > heights.top_y - reach {
                return self.hair.map(f64::from);
            }
        }
        let pelvis = [Segment::Torso as u8, Segment::ThighL as u8, Segment::ThighR as u8];
        let drop = match self.underwear_style {
            UnderwearStyle::Briefs => 0.02,
            UnderwearStyle::Trunks => 0.12,
        };
        if pelvis.contains(&label) && y >= heights.crotch_y - drop && y <= heights.crotch_y + self.waist_rise_m {
            return self.underwear.map(f64::from);
        }
        if self.top && label == Segment::Torso as u8 {
            let t = (y - heights.crotch_y) / (heights.top_y - heights.crotch_y);
            if (TOP_BAND.0..=TOP_BAND.1).contains(&t) {
                return self.underwear.map(f64::from);
            }
        }
        self.skin.map(f64::from)
    }

    /// Albedo of a floor pixel: tiles of `floor_tile_m` with +-5 % variation and darker grout lines.
    fn floor_albedo(&self, p: [f64; 3]) -> [f64; 3] {
        let (sx, sz) = (p[0] / self.floor_tile_m, p[2] / self.floor_tile_m);
        let (ix, iz) = (sx.floor(), sz.floor());
        let edge = (sx - ix).min(1.0 - (sx - ix)).min((sz - iz).min(1.0 - (sz - iz))) * self.floor_tile_m;
        let f = if edge < 0.006 { 0.7 } else { 0.95 + 0.1 * hash01(ix as i64, iz as i64) };
        self.floor.map(|c| f64::from(c) * f)
    }

    /// The sRGB colour of one pixel: albedo x (ambient + sum of the lights' Lambert terms) x the lights'
    /// colour.
    pub fn shade(&self, heights: &BodyHeights, px: &SurfacePixel) -> [u8; 3] {
        let albedo = match px.kind {
            SurfaceKind::None => return [0, 0, 0],
            SurfaceKind::Body => self.body_albedo(heights, px.label, px.point, px.normal),
            SurfaceKind::Floor => self.floor_albedo(px.point),
            SurfaceKind::Wall => self.wall.map(f64::from),
            SurfaceKind::Ceiling => [235.0, 235.0, 232.0],
            SurfaceKind::Block => [110.0, 80.0, 55.0],
            SurfaceKind::Person => [60.0, 75.0, 120.0],
        };
        let n = px.normal;
        // The lights hang below the ceiling: it is lit indirectly (ambient plus a fixed bounce).
        let bounce = if px.kind == SurfaceKind::Ceiling { 0.45 } else { 0.0 };
        let light: f64 = self.ambient
            + bounce
            + self
                .lights
                .iter()
                .map(|l| l.intensity * (n[0] * l.toward[0] + n[1] * l.toward[1] + n[2] * l.toward[2]).max(0.0))
                .sum::<f64>();
        let lit = |k: usize| (albedo[k] * light * self.tint[k]).round().clamp(0.0, 255.0) as u8;
        [lit(0), lit(1), lit(2)]
    }
}
