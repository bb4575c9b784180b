//! "Only the person" for one view: the floor fit and check ([`super::floor`]), floor removal, and
//! the rejection of depth-edge, far and separate pixels ([`super::isolate`]), with their report.

use super::deproject::{depth_filter, floor_samples, ViewPoints};
use super::floor::{fit_floor, quantile, FloorSearch, PERSON_LOW_QUANTILE};
use super::isolate::{choose_person, depth_edges, far_from_person, voxel_components};
use super::report::{CleaningReport, FloorReport};
use super::{DepthView, FuseError, FuseParams};
use std::time::Instant;

/// Fits and checks this view's floor, then removes the floor and the non-person points from `vp`
/// as the parameters ask; the floor and cleaning reports.
pub(super) fn clean_view(
    view: &DepthView,
    params: &FuseParams,
    vp: &mut ViewPoints,
) -> Result<(FloorReport, CleaningReport), FuseError> {
    let t = Instant::now();
    let deprojected = vp.len();
    let mut rep = CleaningReport::default();
    let subject_xz = [
        quantile(vp.points.iter().map(|p| p[0]).collect(), 0.5),
        quantile(vp.points.iter().map(|p| p[2]).collect(), 0.5),
    ];
    let low = quantile(vp.points.iter().map(|p| p[1]).collect(), PERSON_LOW_QUANTILE);
    let search = FloorSearch {
        inlier_m: params.floor_inlier_m,
        max_tilt_deg: params.floor_max_tilt_deg,
        min_pixels: params.floor_min_pixels,
    };
    let fit = fit_floor(&floor_samples(view, params), low, subject_xz, &search);
    let floor = FloorReport::new(fit.as_ref(), subject_xz);
    if let (true, Some(f)) = (params.remove_floor, &fit) {
        let keep: Vec<bool> = vp.points.iter().map(|&p| f.plane.distance(p) >= params.floor_margin_m).collect();
        rep.floor_removed = vp.retain(&keep);
    }
    if params.isolate_person && vp.len() > 0 {
        isolate(view, params, vp, &mut rep)?;
    }
    if vp.len() == 0 {
        return Err(FuseError::NothingLeft {
            camera: view.name.clone(),
            deprojected,
            floor: rep.floor_removed,
            edges: rep.edge_removed,
            far: rep.far_removed,
        });
    }
    rep.seconds = t.elapsed().as_secs_f64();
    Ok((floor, rep))
}

/// Removes depth-edge pixels, far pixels and the parts separate from the person.
fn isolate(
    view: &DepthView,
    params: &FuseParams,
    vp: &mut ViewPoints,
    rep: &mut CleaningReport,
) -> Result<(), FuseError> {
    let ok = depth_filter(params);
    let depth = |i: usize| {
        let z = view.depth.metres(i);
        if ok(z) {
            z
        } else {
            0.0
        }
    };
    let (w, h) = (view.intrinsics.width as usize, view.intrinsics.height as usize);
    let edges = depth_edges(&depth, w, h, &vp.pixels, params.edge_step_m);
    rep.edge_removed = vp.retain(&edges.iter().map(|&e| !e).collect::<Vec<_>>());
    let depths: Vec<f64> = vp.pixels.iter().map(|&i| depth(i as usize)).collect();
    let (far, median) = far_from_person(&depths, params.far_m);
    rep.median_depth_m = median.is_finite().then_some(median);
    rep.far_removed = vp.retain(&far.iter().map(|&f| !f).collect::<Vec<_>>());
    if vp.len() == 0 {
        return Ok(());
    }
    let comps = voxel_components(&vp.points, params.link_m);
    rep.parts = comps.sizes.len();
    let choice =
        choose_person(&vp.points, &comps, params.second_part_ratio).map_err(|c| FuseError::PersonNotIsolated {
            camera: view.name.clone(),
            person_points: c.main,
            other_points: c.second,
            distance_m: c.second_distance_m,
            ratio: params.second_part_ratio,
        })?;
    rep.person_points = choice.main;
    rep.largest_other_points = choice.second;
    rep.separate_removed = vp.retain(&choice.keep);
    Ok(())
}
