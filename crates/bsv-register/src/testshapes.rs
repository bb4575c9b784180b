//! Shapes the unit tests sample (test builds only).

/// Points on an elliptic tube about the unit `axis` (in the x-y plane) through the origin: one ring of
/// `around` points at each axial position of `along`, semi-axes `rw` across the axis in the x-y plane and
/// `rd` along z (the cameras' line of sight). Points whose normal's |z| is under `min_nz` are left out:
/// 0 keeps the whole ring, more drops the grazing band two cameras on z miss.
pub(crate) fn elliptic_tube(
    axis: [f64; 3],
    along: impl IntoIterator<Item = f64>,
    around: usize,
    rw: f64,
    rd: f64,
    min_nz: f64,
) -> Vec<[f64; 3]> {
    let w = [-axis[1], axis[0], 0.0];
    let mut out = Vec::new();
    for t in along {
        for j in 0..around {
            let phi = j as f64 / around as f64 * std::f64::consts::TAU;
            let (u, z) = (rw * phi.cos(), rd * phi.sin());
            let nz = phi.sin() / rd / ((phi.cos() / rw).powi(2) + (phi.sin() / rd).powi(2)).sqrt();
            if nz.abs() < min_nz {
                continue;
            }
            out.push([axis[0] * t + w[0] * u, axis[1] * t + w[1] * u, z]);
        }
    }
    out
}
