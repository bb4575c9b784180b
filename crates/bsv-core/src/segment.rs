//! Segment ids, names, palette colours and the aggregates of DESIGN.md ("Conventions").

use std::fmt;

/// A body segment id (u8 on disk). `Unlabelled` is 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Segment {
    /// No segment (id 0).
    Unlabelled = 0,
    /// Head and neck (id 1).
    Head = 1,
    /// Torso, clavicles and shoulders (id 2).
    Torso = 2,
    /// Left upper arm (id 3).
    UpperArmL = 3,
    /// Right upper arm (id 4).
    UpperArmR = 4,
    /// Left forearm (id 5).
    ForearmL = 5,
    /// Right forearm (id 6).
    ForearmR = 6,
    /// Left hand (id 7).
    HandL = 7,
    /// Right hand (id 8).
    HandR = 8,
    /// Left thigh (id 9).
    ThighL = 9,
    /// Right thigh (id 10).
    ThighR = 10,
    /// Left shin (id 11).
    ShinL = 11,
    /// Right shin (id 12).
    ShinR = 12,
    /// Left foot (id 13).
    FootL = 13,
    /// Right foot (id 14).
    FootR = 14,
}

/// Number of segment ids including `Unlabelled` (ids 0..=14).
pub const SEGMENT_COUNT: usize = 15;

/// The nine segments of `trunk_limbs` (no head, hands, feet).
pub const TRUNK_LIMBS: [Segment; 9] = [
    Segment::Torso,
    Segment::UpperArmL,
    Segment::UpperArmR,
    Segment::ForearmL,
    Segment::ForearmR,
    Segment::ThighL,
    Segment::ThighR,
    Segment::ShinL,
    Segment::ShinR,
];

/// Segment ids that the cloud pipeline drops (head, hands, feet).
pub const EXTREMITIES: [Segment; 5] = [Segment::Head, Segment::HandL, Segment::HandR, Segment::FootL, Segment::FootR];

impl Segment {
    /// Every labelled segment (ids 1..=14), in id order.
    pub const ALL: [Segment; 14] = [
        Segment::Head,
        Segment::Torso,
        Segment::UpperArmL,
        Segment::UpperArmR,
        Segment::ForearmL,
        Segment::ForearmR,
        Segment::HandL,
        Segment::HandR,
        Segment::ThighL,
        Segment::ThighR,
        Segment::ShinL,
        Segment::ShinR,
        Segment::FootL,
        Segment::FootR,
    ];

    /// The segment with this id, or `None` for ids above 14.
    pub fn from_id(id: u8) -> Option<Segment> {
        if id == 0 {
            return Some(Segment::Unlabelled);
        }
        Segment::ALL.get(usize::from(id) - 1).copied()
    }

    /// The numeric id (0..=14).
    pub fn id(self) -> u8 {
        self as u8
    }

    /// The canonical name used as key everywhere (JSON, OBJ groups, Python).
    pub fn name(self) -> &'static str {
        match self {
            Segment::Unlabelled => "unlabelled",
            Segment::Head => "head",
            Segment::Torso => "torso",
            Segment::UpperArmL => "upper_arm_l",
            Segment::UpperArmR => "upper_arm_r",
            Segment::ForearmL => "forearm_l",
            Segment::ForearmR => "forearm_r",
            Segment::HandL => "hand_l",
            Segment::HandR => "hand_r",
            Segment::ThighL => "thigh_l",
            Segment::ThighR => "thigh_r",
            Segment::ShinL => "shin_l",
            Segment::ShinR => "shin_r",
            Segment::FootL => "foot_l",
            Segment::FootR => "foot_r",
        }
    }

    /// The segment whose canonical name is `name` (exact, lower case).
    pub fn from_name(name: &str) -> Option<Segment> {
        std::iter::once(Segment::Unlabelled).chain(Segment::ALL).find(|s| s.name() == name)
    }

    /// The palette colour (sRGB) used when writing labelled PLY files.
    pub fn color(self) -> [u8; 3] {
        PALETTE[usize::from(self.id())]
    }

    /// The mirror segment (left <-> right); central segments map to themselves.
    pub fn mirrored(self) -> Segment {
        match self {
            Segment::UpperArmL => Segment::UpperArmR,
            Segment::UpperArmR => Segment::UpperArmL,
            Segment::ForearmL => Segment::ForearmR,
            Segment::ForearmR => Segment::ForearmL,
            Segment::HandL => Segment::HandR,
            Segment::HandR => Segment::HandL,
            Segment::ThighL => Segment::ThighR,
            Segment::ThighR => Segment::ThighL,
            Segment::ShinL => Segment::ShinR,
            Segment::ShinR => Segment::ShinL,
            Segment::FootL => Segment::FootR,
            Segment::FootR => Segment::FootL,
            s => s,
        }
    }

    /// True for head, hands and feet (dropped from clouds by the pipeline).
    pub fn is_extremity(self) -> bool {
        EXTREMITIES.contains(&self)
    }
}

impl fmt::Display for Segment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Palette colours by segment id (index 0 = unlabelled, light grey): the one segment palette of every
/// figure, legend and labelled PLY file. Drawn from Okabe & Ito's and Paul Tol's colour-blind-safe sets
/// (hex codes in the comments) so that every pair differs by at least 10 CAM02-UCS units for normal
/// vision and under deuteranopia and protanopia simulation (`tests/python/test_palette.py`). The left
/// segment of a limb is the darker or more saturated of its pair.
pub const PALETTE: [[u8; 3]; SEGMENT_COUNT] = [
    [0xDD, 0xDD, 0xDD], // unlabelled: pale grey
    [0xDD, 0xCC, 0x77], // head: Tol muted sand
    [0x99, 0xDD, 0xFF], // torso: Tol light cyan
    [0x00, 0x77, 0xBB], // upper_arm_l: Tol vibrant blue
    [0x56, 0xB4, 0xE9], // upper_arm_r: Okabe-Ito sky blue
    [0x33, 0x22, 0x88], // forearm_l: Tol muted indigo
    [0xCC, 0x79, 0xA7], // forearm_r: Okabe-Ito reddish purple
    [0x88, 0x22, 0x55], // hand_l: Tol muted wine
    [0xAA, 0x33, 0x77], // hand_r: Tol bright purple
    [0xD5, 0x5E, 0x00], // thigh_l: Okabe-Ito vermillion
    [0xE6, 0x9F, 0x00], // thigh_r: Okabe-Ito orange
    [0xBB, 0x55, 0x66], // shin_l: Tol high-contrast red
    [0xEE, 0x88, 0x66], // shin_r: Tol light orange
    [0x44, 0xBB, 0x99], // foot_l: Tol light mint
    [0xF0, 0xE4, 0x42], // foot_r: Okabe-Ito yellow
];

/// A named sum of segments reported next to the segments (DESIGN.md "Aggregates").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aggregate {
    /// Torso + left/right upper arm, forearm, thigh, shin.
    TrunkLimbs,
    /// Every segment present.
    Whole,
    /// Left upper arm + left forearm.
    ArmL,
    /// Right upper arm + right forearm.
    ArmR,
    /// Left thigh + left shin.
    LegL,
    /// Right thigh + right shin.
    LegR,
}

impl Aggregate {
    /// Every aggregate, in report order.
    pub const ALL: [Aggregate; 6] =
        [Aggregate::TrunkLimbs, Aggregate::Whole, Aggregate::ArmL, Aggregate::ArmR, Aggregate::LegL, Aggregate::LegR];

    /// The key used in JSON and Python.
    pub fn name(self) -> &'static str {
        match self {
            Aggregate::TrunkLimbs => "trunk_limbs",
            Aggregate::Whole => "whole",
            Aggregate::ArmL => "arm_l",
            Aggregate::ArmR => "arm_r",
            Aggregate::LegL => "leg_l",
            Aggregate::LegR => "leg_r",
        }
    }

    /// The segments summed; `None` for `Whole` (every segment present).
    pub fn members(self) -> Option<&'static [Segment]> {
        match self {
            Aggregate::TrunkLimbs => Some(&TRUNK_LIMBS),
            Aggregate::Whole => None,
            Aggregate::ArmL => Some(&[Segment::UpperArmL, Segment::ForearmL]),
            Aggregate::ArmR => Some(&[Segment::UpperArmR, Segment::ForearmR]),
            Aggregate::LegL => Some(&[Segment::ThighL, Segment::ShinL]),
            Aggregate::LegR => Some(&[Segment::ThighR, Segment::ShinR]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_and_names_round_trip() {
        for s in Segment::ALL {
            assert_eq!(Segment::from_id(s.id()), Some(s));
            assert_eq!(Segment::from_name(s.name()), Some(s));
            assert_eq!(s.mirrored().mirrored(), s);
        }
        assert_eq!(Segment::from_id(15), None);
        assert_eq!(Segment::from_name("Torso"), None);
        assert_eq!(Segment::ThighL.id(), 9);
    }
}
