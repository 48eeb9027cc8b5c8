//! `ygg-bench ladder`: the paper's ablation ladder (dsg, vanilla, chocolate, mint,
//! saffron) on the office workload, with answers checked identical before timing.

pub mod flat_dsg;
pub mod workload;

use ygg_store::Point;

/// Sorted object ids answering one query.
pub type Answer = Vec<u64>;

/// The cone test of Q2, as the workload defines it: `|v - eye| <= range` and the angle
/// between `v - eye` and the unit `dir` at most the half-angle (`cos_half` is its
/// cosine); a point at the eye is visible.
pub fn cone_contains(eye: &Point, dir: &Point, cos_half: f32, range: f32, v: &Point) -> bool {
    let d = [v[0] - eye[0], v[1] - eye[1], v[2] - eye[2]];
    let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if len2 > range * range {
        return false;
    }
    let along = d[0] * dir[0] + d[1] * dir[1] + d[2] * dir[2];
    len2 == 0.0 || along >= len2.sqrt() * cos_half
}
