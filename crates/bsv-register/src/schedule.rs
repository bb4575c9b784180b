//! The correspondence schedule: which way nearest neighbours are taken in each iteration.

use crate::error::ParameterError;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Which way nearest neighbours are taken in an iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CorrespondenceKind {
    /// Mesh-to-point: each vertex to its nearest cloud point.
    M2p,
    /// Point-to-mesh: each cloud point to its nearest vertex; a vertex's target is the mean.
    P2m,
}

impl fmt::Display for CorrespondenceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CorrespondenceKind::M2p => "m2p",
            CorrespondenceKind::P2m => "p2m",
        })
    }
}

/// One stage of the schedule: `iterations` iterations with correspondences of `kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stage {
    /// Correspondence direction.
    pub kind: CorrespondenceKind,
    /// Number of iterations (correspondences + local + global step each).
    pub iterations: usize,
}

/// The correspondence schedule, e.g. `m2p:5,p2m:5,m2p:10` (the paper's).
///
/// Serialises as that string (so JSON/Python users write `"schedule": "m2p:10,p2m:5"`);
/// deserialises from the string or from the older list form
/// `[{"kind": "m2p", "iterations": 5}, ...]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Schedule(pub Vec<Stage>);

impl Serialize for Schedule {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

/// The accepted serialised forms of a [`Schedule`].
#[derive(Deserialize)]
#[serde(untagged)]
enum ScheduleRepr {
    /// `"m2p:5,p2m:5,m2p:10"`.
    Text(String),
    /// `[{"kind": "m2p", "iterations": 5}, ...]`.
    Stages(Vec<Stage>),
}

impl<'de> Deserialize<'de> for Schedule {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        match ScheduleRepr::deserialize(deserializer).map_err(|_| {
            serde::de::Error::custom(
                "schedule must be a string like \"m2p:5,p2m:5,m2p:10\" (or a list of {kind, iterations})",
            )
        })? {
            ScheduleRepr::Text(text) => Schedule::parse(&text).map_err(serde::de::Error::custom),
            ScheduleRepr::Stages(stages) => {
                let s = Schedule(stages);
                s.check().map_err(serde::de::Error::custom)?;
                Ok(s)
            }
        }
    }
}

/// The most iterations a schedule may have in total (a fit of this length takes hours; larger counts
/// are typing errors, and would overflow the iteration counter or the log's allocation).
pub const MAX_ITERATIONS: usize = 1_000_000;

/// The default schedule: the paper's 5 m2p, 5 p2m, then m2p, here 4 (the paper's 10 converged after 3-6
/// under the stopping rule), and a tail of 2 p2m. Why the tail: under depth noise a vertex's nearest
/// point exists anywhere inside the band of noise, so the last m2p stage hardly pulls a vertex back out
/// and the stiff fit settles inside the surface (L515-like clouds: limbs -1 to -2 %, trunk_limbs -0.4 to
/// -0.5 % signed); a p2m target is the mean of the vertex's points, whose noise averages out along the
/// normal. Measured on the oracle cohort (seeds 0 and 2, l515): trunk_limbs 0.43-0.51 -> 0.17-0.22 %,
/// the limbs' mean 1.12-1.29 -> 1.03-1.11 %, at the same cost (benchmarks/BENCH.md, round 2 session 12).
pub const DEFAULT_SCHEDULE: &str = "m2p:5,p2m:5,m2p:4,p2m:2";

impl Schedule {
    /// Parses `KIND:COUNT[,KIND:COUNT...]` (KIND `m2p` or `p2m`, case-insensitive, spaces allowed).
    pub fn parse(text: &str) -> Result<Schedule, ParameterError> {
        let bad = |reason: String| ParameterError::BadSchedule { text: text.to_string(), reason };
        let mut stages = Vec::new();
        for (k, part) in text.split(',').enumerate() {
            let part = part.trim();
            if part.is_empty() {
                return Err(bad(format!("stage {} is empty", k + 1)));
            }
            let (kind, count) = part.split_once(':').ok_or_else(|| bad(format!("stage {:?} has no ':'", part)))?;
            let kind = match kind.trim().to_ascii_lowercase().as_str() {
                "m2p" => CorrespondenceKind::M2p,
                "p2m" => CorrespondenceKind::P2m,
                other => return Err(bad(format!("unknown kind {:?}", other))),
            };
            let iterations: usize = count
                .trim()
                .parse()
                .map_err(|_| bad(format!("count {:?} is not a non-negative integer", count.trim())))?;
            stages.push(Stage { kind, iterations });
        }
        let schedule = Schedule(stages);
        schedule.check()?;
        Ok(schedule)
    }

    /// Checks that the schedule has at least one and at most [`MAX_ITERATIONS`] iterations.
    pub fn check(&self) -> Result<(), ParameterError> {
        let bad = |reason: String| ParameterError::BadSchedule { text: self.to_string(), reason };
        let total = self.0.iter().try_fold(0usize, |acc, s| acc.checked_add(s.iterations));
        match total {
            Some(0) => Err(bad("the schedule has no iteration".to_string())),
            Some(n) if n <= MAX_ITERATIONS => Ok(()),
            _ => Err(bad(format!(
                "it has more than {MAX_ITERATIONS} iterations in total; use fewer (the default has 20)"
            ))),
        }
    }

    /// Total number of iterations (saturating: [`Schedule::check`] bounds it).
    pub fn total_iterations(&self) -> usize {
        self.0.iter().fold(0usize, |acc, s| acc.saturating_add(s.iterations))
    }
}

impl Default for Schedule {
    /// [`DEFAULT_SCHEDULE`] (the one place that writes it down).
    fn default() -> Self {
        // A constant of this module, checked by the unit test `default_is_the_constant`: it parses.
        Schedule::parse(DEFAULT_SCHEDULE).expect("DEFAULT_SCHEDULE parses")
    }
}

impl fmt::Display for Schedule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self.0.iter().map(|s| format!("{}:{}", s.kind, s.iterations)).collect();
        f.write_str(&parts.join(","))
    }
}

impl std::str::FromStr for Schedule {
    type Err = ParameterError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Schedule::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_the_constant() {
        let d = Schedule::default();
        assert_eq!(d.to_string(), DEFAULT_SCHEDULE);
        assert!(d.check().is_ok());
        assert_eq!(d.0.last().map(|s| s.kind), Some(CorrespondenceKind::P2m));
    }
}
