//! The room around the subject: a finite floor at y = 0, walls, an optional ceiling and optional
//! objects (a chair-like block, a second standing person), so that the virtual cameras see what real
//! clinic cameras see around the subject (DESIGN.md, "Facts from round 2": the floor around the feet and
//! a wall behind the subject are inside the L515's range).
//!
//! World frame as everywhere (DESIGN.md "Conventions"): Y up, floor at y = 0, the subject at the origin
//! facing +Z toward the front camera (z = +2 m), the back camera at z = -2 m. The room is rendered by
//! its own ray-casting structure ([`RoomScene`]); its pixels carry depth but segment label 0.

use super::{mix_seed, ScanError};
use bsv_core::shapes;
use bsv_core::TriMesh;
use parry3d_f64::math::Vector;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Stream id of the room's per-seed variation.
const STREAM_ROOM: u64 = 0x0800;

/// What a pixel's ray hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum SurfaceKind {
    /// Nothing within range.
    None = 0,
    /// The scanned body.
    Body = 1,
    /// The floor (y = 0).
    Floor = 2,
    /// A wall.
    Wall = 3,
    /// The ceiling.
    Ceiling = 4,
    /// A block object ([`RoomObject::Block`]).
    Block = 5,
    /// Another person ([`RoomObject::Person`]).
    Person = 6,
}

impl SurfaceKind {
    /// The kind of a stored code (unknown codes are [`SurfaceKind::None`]).
    pub fn from_code(code: u8) -> SurfaceKind {
        match code {
            1 => SurfaceKind::Body,
            2 => SurfaceKind::Floor,
            3 => SurfaceKind::Wall,
            4 => SurfaceKind::Ceiling,
            5 => SurfaceKind::Block,
            6 => SurfaceKind::Person,
            _ => SurfaceKind::None,
        }
    }
}

/// An object standing on the floor of the room (off by default; useful for isolation tests).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RoomObject {
    /// A box standing on the floor (a chair, a cabinet), rotated about the vertical.
    Block {
        /// Centre of its footprint (x, z), metres.
        center_xz: [f64; 2],
        /// Width (x), height (y), depth (z) before the rotation, metres.
        size: [f64; 3],
        /// Rotation about +Y, degrees.
        yaw_deg: f64,
    },
    /// A standing person-like capsule (a second person partly in view).
    Person {
        /// Centre of its footprint (x, z), metres.
        center_xz: [f64; 2],
        /// Height from the floor to the top, metres.
        height: f64,
        /// Radius, metres.
        radius: f64,
    },
}

/// A room: the floor, walls, ceiling and objects around the subject. Defaults are [`Room::clinic`]
/// (missing keys in a serialized room take the clinic's values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Room {
    /// A floor at y = 0 (false: nothing below the subject returns depth).
    pub floor: bool,
    /// The front, back and side walls (false: none; the ceiling is [`Room::ceiling`]).
    pub walls: bool,
    /// Floor extent along x, metres, centred on x = 0.
    pub floor_width: f64,
    /// Floor extent along z, metres, centred on z = 0.
    pub floor_length: f64,
    /// z of the wall behind the subject as seen from the front camera (beyond the back camera), metres (< 0).
    pub back_wall_z: f64,
    /// z of the wall behind the front camera, metres (> 0).
    pub front_wall_z: f64,
    /// Side walls at x = +-`side_wall_x` metres; `None`: no side walls.
    pub side_wall_x: Option<f64>,
    /// Height of the walls (and of the ceiling), metres.
    pub wall_height: f64,
    /// A ceiling at `wall_height`.
    pub ceiling: bool,
    /// Objects standing on the floor.
    pub objects: Vec<RoomObject>,
}

impl Default for Room {
    fn default() -> Self {
        Room::clinic()
    }
}

impl Room {
    /// A small clinic room: a 6 x 8 m floor, walls 0.6 m behind each camera (z = -2.6 and +2.6 m),
    /// side walls at x = +-2.4 m (inside the front camera's view of the back wall), 2.7 m high with a
    /// ceiling, no objects.
    pub fn clinic() -> Room {
        Room {
            floor: true,
            walls: true,
            floor_width: 6.0,
            floor_length: 8.0,
            back_wall_z: -2.6,
            front_wall_z: 2.6,
            side_wall_x: Some(2.4),
            wall_height: 2.7,
            ceiling: true,
            objects: Vec::new(),
        }
    }

    /// [`Room::clinic`] with two objects partly in the front camera's view: a chair-sized block behind
    /// the subject to its left and a second person behind it to its right.
    pub fn clinic_with_objects() -> Room {
        Room {
            objects: vec![
                RoomObject::Block { center_xz: [0.9, -1.2], size: [0.5, 0.9, 0.5], yaw_deg: 20.0 },
                RoomObject::Person { center_xz: [-1.3, -1.6], height: 1.7, radius: 0.2 },
            ],
            ..Room::clinic()
        }
    }

    /// A studio: no floor, walls, ceiling or object returns depth (the background is empty, as in the
    /// rig without a room), but the colour render still dresses and lights the subject like a room's
    /// ([`crate::scanner::Appearance`]). Compared with [`Room::clinic`] it isolates what the floor and
    /// walls do from what the subject's appearance does.
    pub fn studio() -> Room {
        Room { floor: false, walls: false, ceiling: false, ..Room::clinic() }
    }

    /// This room with its distances varied deterministically for `seed`: each wall moved by up to
    /// -0.2 .. +0.6 m away from the subject, the wall height by -0.1 .. +0.4 m (objects stay).
    pub fn varied(&self, seed: u64) -> Room {
        let mut rng = rand::rngs::StdRng::seed_from_u64(mix_seed(seed, STREAM_ROOM, 0));
        let mut away = || rng.random_range(-0.2..0.6);
        let mut r = self.clone();
        r.back_wall_z -= away();
        r.front_wall_z += away();
        r.side_wall_x = r.side_wall_x.map(|x| x + away());
        r.wall_height += rng.random_range(-0.1..0.4);
        r
    }

    /// Checks every value: finite, positive sizes, walls on their side of the subject, objects on
    /// the floor. The error names the parameter and the remedy.
    pub fn validate(&self) -> Result<(), ScanError> {
        let bad = |param: &'static str, value: f64, remedy: &'static str| ScanError::BadRoom { param, value, remedy };
        for (p, v) in
            [("floor_width", self.floor_width), ("floor_length", self.floor_length), ("wall_height", self.wall_height)]
        {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(p, v, "use a finite size > 0 metres"));
            }
        }
        if !(self.back_wall_z.is_finite() && self.back_wall_z < 0.0) {
            return Err(bad("back_wall_z", self.back_wall_z, "use a finite z < 0 (behind the subject), e.g. -2.6"));
        }
        if !(self.front_wall_z.is_finite() && self.front_wall_z > 0.0) {
            return Err(bad(
                "front_wall_z",
                self.front_wall_z,
                "use a finite z > 0 (in front of the subject), e.g. 2.6",
            ));
        }
        if let Some(x) = self.side_wall_x {
            if !(x.is_finite() && x > 0.0) {
                return Err(bad("side_wall_x", x, "use a finite half-width > 0 metres, or none for no side walls"));
            }
        }
        self.objects.iter().try_for_each(RoomObject::validate)
    }

    /// Checks that a camera centre lies inside the room (between the walls, above the floor, below
    /// the ceiling; anywhere in a room without walls); `camera` names it in the error.
    pub fn check_inside(&self, camera: &str, centre: [f64; 3]) -> Result<(), ScanError> {
        if !self.walls {
            return Ok(());
        }
        let [x, y, z] = centre;
        let side = self.side_wall_x.unwrap_or(f64::INFINITY);
        let (param, remedy) = if z <= self.back_wall_z {
            ("back_wall_z", "move the back wall behind the camera (a smaller z)")
        } else if z >= self.front_wall_z {
            ("front_wall_z", "move the front wall behind the camera (a larger z)")
        } else if x.abs() >= side {
            ("side_wall_x", "widen the room (a larger side_wall_x)")
        } else if y <= 0.0 || y >= self.wall_height {
            ("wall_height", "put the camera above the floor and below the ceiling (raise wall_height)")
        } else {
            return Ok(());
        };
        Err(ScanError::CameraOutsideRoom { camera: camera.to_string(), param, remedy })
    }
}

impl RoomObject {
    fn validate(&self) -> Result<(), ScanError> {
        let bad = |param: &'static str, value: f64, remedy: &'static str| ScanError::BadRoom { param, value, remedy };
        match self {
            RoomObject::Block { center_xz, size, yaw_deg } => {
                if let Some(v) = center_xz.iter().chain([yaw_deg]).find(|v| !v.is_finite()) {
                    return Err(bad("objects.block", *v, "use finite centre_xz and yaw_deg"));
                }
                if let Some(v) = size.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                    return Err(bad("objects.block.size", *v, "use three finite sizes > 0 metres"));
                }
            }
            RoomObject::Person { center_xz, height, radius } => {
                if let Some(v) = center_xz.iter().find(|v| !v.is_finite()) {
                    return Err(bad("objects.person.center_xz", *v, "use a finite (x, z) in metres"));
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(bad("objects.person.radius", *radius, "use a finite radius > 0 metres"));
                }
                if !(height.is_finite() && *height > 2.0 * radius) {
                    return Err(bad("objects.person.height", *height, "use a finite height > 2 x radius"));
                }
            }
        }
        Ok(())
    }

    /// The object's closed triangle mesh and its kind.
    fn mesh(&self) -> (TriMesh, SurfaceKind) {
        match self {
            RoomObject::Block { center_xz, size, yaw_deg } => {
                let mut m = shapes::cuboid(*size);
                shapes::translate(&mut m, [0.0, size[1] / 2.0, 0.0]);
                shapes::rotate_y(&mut m, yaw_deg.to_radians());
                shapes::translate(&mut m, [center_xz[0], 0.0, center_xz[1]]);
                (m, SurfaceKind::Block)
            }
            RoomObject::Person { center_xz, height, radius } => {
                let mut m = shapes::capsule(*radius, height - 2.0 * radius, 24, 6, 8);
                shapes::translate(&mut m, [center_xz[0], *radius, center_xz[1]]);
                (m, SurfaceKind::Person)
            }
        }
    }
}

/// The room as one ray-casting structure (parry BVH) with the kind of every triangle.
pub(crate) struct RoomScene {
    /// The BVH of every room triangle (`None` for a room with nothing in it, [`Room::studio`]).
    pub bvh: Option<parry3d_f64::shape::TriMesh>,
    /// [`SurfaceKind`] of each triangle.
    pub kinds: Vec<SurfaceKind>,
}

/// Appends the rectangle with corner `o` and edges `a`, `b` (two triangles) to `m` and `kinds`.
fn push_quad(m: &mut TriMesh, kinds: &mut Vec<SurfaceKind>, o: [f64; 3], a: [f64; 3], b: [f64; 3], kind: SurfaceKind) {
    let i = m.vertices.len() as u32;
    let p = |s: f64, t: f64| [o[0] + s * a[0] + t * b[0], o[1] + s * a[1] + t * b[1], o[2] + s * a[2] + t * b[2]];
    m.vertices.extend([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
    m.triangles.extend([[i, i + 1, i + 2], [i, i + 2, i + 3]]);
    kinds.extend([kind, kind]);
}

impl RoomScene {
    /// Builds the room's triangles (the floor, the walls, the ceiling, the objects) and their BVH.
    pub fn build(room: &Room) -> Result<RoomScene, ScanError> {
        room.validate()?;
        let mut m = TriMesh::default();
        let mut kinds = Vec::new();
        let (hw, hl, h) = (room.floor_width / 2.0, room.floor_length / 2.0, room.wall_height);
        let xw = room.side_wall_x.unwrap_or(hw).max(hw);
        let (zb, zf) = (room.back_wall_z, room.front_wall_z);
        if room.floor {
            let (o, a, b) = ([-hw, 0.0, -hl], [2.0 * hw, 0.0, 0.0], [0.0, 0.0, 2.0 * hl]);
            push_quad(&mut m, &mut kinds, o, a, b, SurfaceKind::Floor);
        }
        if room.walls {
            for z in [zb, zf] {
                push_quad(&mut m, &mut kinds, [-xw, 0.0, z], [2.0 * xw, 0.0, 0.0], [0.0, h, 0.0], SurfaceKind::Wall);
            }
        }
        if let Some(x) = room.side_wall_x.filter(|_| room.walls) {
            for sx in [-x, x] {
                push_quad(&mut m, &mut kinds, [sx, 0.0, zb], [0.0, 0.0, zf - zb], [0.0, h, 0.0], SurfaceKind::Wall);
            }
        }
        if room.ceiling {
            push_quad(
                &mut m,
                &mut kinds,
                [-xw, h, zb],
                [2.0 * xw, 0.0, 0.0],
                [0.0, 0.0, zf - zb],
                SurfaceKind::Ceiling,
            );
        }
        for o in &room.objects {
            let (part, kind) = o.mesh();
            kinds.extend(std::iter::repeat_n(kind, part.triangles.len()));
            let off = m.vertices.len() as u32;
            m.vertices.extend(part.vertices);
            m.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + off)));
        }
        if m.triangles.is_empty() {
            return Ok(RoomScene { bvh: None, kinds });
        }
        let verts: Vec<Vector> = m.vertices.iter().map(|p| Vector::new(p[0], p[1], p[2])).collect();
        let bvh =
            parry3d_f64::shape::TriMesh::new(verts, m.triangles).map_err(|e| ScanError::Parry(format!("room: {e}")))?;
        Ok(RoomScene { bvh: Some(bvh), kinds })
    }
}
