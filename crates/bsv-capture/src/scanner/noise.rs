//! L515 depth noise: flying pixels at depth discontinuities, then Gaussian depth noise
//! (the model is documented on [`DepthNoise`]). Deterministic per seed: one RNG per image row.

use super::rig::DepthNoise;
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// The depth of the 4-neighbour that differs most from `z` by more than the jump (a missing
/// neighbour counts as `z + silhouette_tail`), if any.
fn discontinuity_target(depth: &[f64], w: usize, h: usize, u: usize, v: usize, noise: &DepthNoise) -> Option<f64> {
    let z = depth[v * w + u];
    let mut best: Option<f64> = None;
    let mut consider = |other: f64| {
        let diff = (other - z).abs();
        if diff > noise.flying_jump && best.is_none_or(|b| diff > (b - z).abs()) {
            best = Some(other);
        }
    };
    let neighbours = [
        (u > 0).then(|| v * w + u - 1),
        (u + 1 < w).then(|| v * w + u + 1),
        (v > 0).then(|| (v - 1) * w + u),
        (v + 1 < h).then(|| (v + 1) * w + u),
    ];
    for j in neighbours.into_iter().flatten() {
        let zj = depth[j];
        if zj > 0.0 {
            consider(zj);
        } else if noise.silhouette_tail > 0.0 {
            consider(z + noise.silhouette_tail);
        }
    }
    best
}

/// The measured depth image from the true one (metres, 0 = no return).
pub(super) fn apply(depth: &[f64], width: u32, height: u32, noise: &DepthNoise, seed: u64) -> Vec<f64> {
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![0.0; depth.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(v, row)| {
        let mut rng = rand::rngs::StdRng::seed_from_u64(super::mix_seed(seed, super::STREAM_NOISE, v as u64));
        for (u, slot) in row.iter_mut().enumerate() {
            let z = depth[v * w + u];
            if z <= 0.0 {
                continue;
            }
            // Draw the same number of variates for every valid pixel so that draws do not shift.
            let fly: f64 = rng.random();
            let mix: f64 = rng.random();
            let n: f64 = rng.sample(StandardNormal);
            let mut zm = z;
            if fly < noise.flying_probability {
                if let Some(other) = discontinuity_target(depth, w, h, u, v, noise) {
                    zm = z + mix * (other - z);
                }
            }
            let zn = zm + n * noise.sigma(zm);
            *slot = if zn > 0.0 && zn.is_finite() { zn } else { 0.0 };
        }
    });
    out
}
