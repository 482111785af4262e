//! One range for the force between the particles of every material: when each material's pairs
//! accept an exponential force, the ranges fitted apart are tested against one range for all.
//!
//! The pairs can fix a force's work W = Aλ, or its amplitude at contact, far better than A and
//! λ apart, and one material's fit can stop along that ridge: a bench attraction of 0.10 m/s²
//! was fitted at 0.014 m/s² over 1.3 mm in one material (a local minimum: at the other's range
//! its χ² was 98 lower) and at 0.11 m/s² over 176 µm in the other. The range is what a cause sets
//! (a screening length, a bridge's size), the amplitude what each material's charge or
//! magnetization sets, so one range is the simpler model:
//! - each material's profile cost C_m(ln λ) (its amplitude, μ_pp, the restitution laws and every
//!   run's kick refitted with λ held) is found at each range fitted apart and midway between
//!   them, where the sum's minimum lies when each profile falls towards its own range; the
//!   joint range is the vertex of the parabola through the sum, kept within the points;
//! - the range is shared when what sharing costs, Σ_m ΔC_m over each material's inflation, is
//!   below χ² with (materials − 1) degrees of freedom at 0.99 (the two models tie, and the
//!   simpler is the model), and no amplitude ends at its bound;
//! - each amplitude is then the one fitted at the shared range. The range's error sums each
//!   material's information on ln λ there (its covariance at the shared fit with λ freed,
//!   inflated); an amplitude's error adds, to its error at that range, the range's error times
//!   how the amplitude moves with the range in that covariance.

use crate::fit::collision::wholerun::{fit_group_with, GroupFit, PairRun, PF_AMP, PF_LN_RANGE};
use crate::stats::dist::chi2_sf;
use rayon::prelude::*;

/// Sharing is refused when what it costs is this unlikely by chance.
const REFUSE_P: f64 = 0.01;

/// The range the materials share, as each material's test keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct SharedRange {
    /// ln λ shared, and its standard error from the profile's curvature.
    pub ln_range: f64,
    pub ln_range_se: f64,
    /// Each material's range fitted apart (m), in the materials' order.
    pub apart_m: Vec<(String, f64)>,
    /// What sharing costs (Σ ΔC over the inflations; below zero when a fit apart had stopped in
    /// a worse minimum than the one at the shared range), its degrees of freedom and p-value.
    pub chi2: f64,
    pub dof: usize,
    pub p: f64,
    /// How this material's amplitude moves with ln λ along its profile (m/s² per unit ln λ).
    pub amp_slope: f64,
}

/// The joint minimum of a profile `total` (χ² units) evaluated at sorted `xs`: the vertex of
/// the parabola through the best point and its neighbours (the three nearest the best at an
/// end), kept within the points, and the parabola's curvature a (total ≈ a (x − x*)² + c);
/// with a curvature not above zero, the best point itself and NaN.
pub fn joint_minimum(xs: &[f64], total: &[f64]) -> (f64, f64) {
    let best = (0..xs.len())
        .min_by(|&a, &b| total[a].total_cmp(&total[b]))
        .expect("at least one point");
    if xs.len() < 3 {
        return (xs[best], f64::NAN);
    }
    let mid = best.clamp(1, xs.len() - 2);
    let (x0, x1, x2) = (xs[mid - 1], xs[mid], xs[mid + 1]);
    let (y0, y1, y2) = (total[mid - 1], total[mid], total[mid + 1]);
    // divided differences: y = y0 + d01 (x − x0) + a (x − x0)(x − x1)
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let a = (d12 - d01) / (x2 - x0);
    if a.is_nan() || a <= 0.0 {
        return (xs[best], f64::NAN);
    }
    let vertex = 0.5 * (x0 + x1) - d01 / (2.0 * a);
    (vertex.clamp(xs[0], xs[xs.len() - 1]), a)
}

/// The fit of `runs` from `fit` with ln λ held at `x`, the amplitude started where the work
/// stays the same.
fn at_range(
    runs: &[PairRun],
    fit: &GroupFit,
    free: &(dyn Fn(usize) -> bool + Sync),
    x: f64,
    max_iter: usize,
) -> GroupFit {
    let mut shared = fit.result.shared.clone();
    shared[PF_AMP] *= (shared[PF_LN_RANGE] - x).exp();
    shared[PF_LN_RANGE] = x;
    fit_group_with(
        runs,
        &fit.spec,
        &shared,
        Some(fit.result.own.as_slice()),
        &|i| i == PF_AMP || (free(i) && i != PF_LN_RANGE),
        max_iter,
    )
}

/// One material's accepted exponential force as the test of one range takes it.
pub struct Member<'a> {
    pub material: &'a str,
    pub fit: &'a GroupFit,
    pub inflate: f64,
    pub runs: &'a [PairRun],
}

/// Tests one range for the `members` (`free` the shared slots the held fit frees): when it is a
/// tie with the ranges apart, what each member keeps of it and its fit at that range, in the
/// members' order. None for fewer than two members or when sharing costs too much.
pub fn share_range(
    members: &[Member],
    free: &(dyn Fn(usize) -> bool + Sync),
    max_iter: usize,
) -> Option<Vec<(SharedRange, GroupFit)>> {
    if members.len() < 2 {
        return None;
    }
    let own: Vec<f64> = members
        .iter()
        .map(|m| m.fit.result.shared[PF_LN_RANGE])
        .collect();
    let mut xs = own.clone();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let between: Vec<f64> = xs.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    xs.extend(between);
    xs.sort_by(f64::total_cmp);
    let global = profile(members, &xs, free, max_iter);
    let total =
        |prof: &[Vec<(f64, GroupFit)>], j: usize| -> f64 { prof.iter().map(|p| p[j].0).sum() };
    let (x, _) = joint_minimum(
        &xs,
        &(0..xs.len()).map(|j| total(&global, j)).collect::<Vec<_>>(),
    );
    let mut at_x = profile(members, &[x], free, max_iter);
    let chi2 = total(&at_x, 0);
    let dof = members.len() - 1;
    let p = chi2_sf(chi2.max(0.0), dof as f64);
    if p < REFUSE_P {
        return None;
    }
    // the range's error: each member's information on ln λ where it is shared (its covariance
    // there with λ free, inflated), summed; and how its amplitude moves with ln λ
    let local: Vec<(f64, f64)> = members
        .par_iter()
        .zip(&at_x)
        .map(|(m, prof)| {
            let fit = &prof[0].1;
            let at = fit_group_with(
                m.runs,
                &fit.spec,
                &fit.result.shared,
                Some(fit.result.own.as_slice()),
                &|i| free(i) || i == PF_AMP || i == PF_LN_RANGE,
                0,
            );
            let cov = &at.result.shared_cov;
            let var = cov[PF_LN_RANGE][PF_LN_RANGE];
            // a range the material does not determine leaves the error unknown, not zero
            if !(var > 0.0 && var.is_finite()) {
                return (f64::NAN, 0.0);
            }
            (1.0 / (var * m.inflate), cov[PF_AMP][PF_LN_RANGE] / var)
        })
        .collect();
    let information: f64 = local.iter().map(|l| l.0).sum();
    let apart_m: Vec<(String, f64)> = members
        .iter()
        .zip(&own)
        .map(|(m, x)| (m.material.to_string(), x.exp()))
        .collect();
    Some(
        at_x.iter_mut()
            .zip(&local)
            .map(|(prof, &(_, amp_slope))| {
                let shared = SharedRange {
                    ln_range: x,
                    ln_range_se: (1.0 / information).sqrt(),
                    apart_m: apart_m.clone(),
                    chi2,
                    dof,
                    p,
                    amp_slope,
                };
                (shared, prof.swap_remove(0).1)
            })
            .collect(),
    )
}

/// Each member's fit with ln λ held at each of `xs`, with its cost beyond its own fit over its
/// inflation (ΔC); at a member's own range, its own fit.
fn profile(
    members: &[Member],
    xs: &[f64],
    free: &(dyn Fn(usize) -> bool + Sync),
    max_iter: usize,
) -> Vec<Vec<(f64, GroupFit)>> {
    let tasks: Vec<(usize, usize)> = (0..members.len())
        .flat_map(|m| (0..xs.len()).map(move |j| (m, j)))
        .collect();
    let mut fits: Vec<(f64, GroupFit)> = tasks
        .par_iter()
        .map(|&(m, j)| {
            let member = &members[m];
            if xs[j] == member.fit.result.shared[PF_LN_RANGE] {
                return (0.0, member.fit.clone());
            }
            let f = at_range(member.runs, member.fit, free, xs[j], max_iter);
            ((f.cost() - member.fit.cost()) / member.inflate, f)
        })
        .collect();
    let mut out = Vec::with_capacity(members.len());
    for _ in 0..members.len() {
        let rest = fits.split_off(xs.len());
        out.push(std::mem::replace(&mut fits, rest));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_joint_minimum_is_the_vertex_of_the_profile_within_its_points() {
        // 2 (x − 0.3)² + 1 at three points: its vertex and curvature exactly
        let f = |x: f64| 2.0 * (x - 0.3) * (x - 0.3) + 1.0;
        let xs = [-1.0, 0.0, 1.0];
        let (x, a) = joint_minimum(&xs, &xs.map(f));
        assert!(
            (x - 0.3).abs() < 1e-12 && (a - 2.0).abs() < 1e-12,
            "{x} {a}"
        );
        // at five points, from the best point's neighbours
        let xs = [-2.0, -1.0, 0.0, 1.0, 2.0];
        let (x, a) = joint_minimum(&xs, &xs.map(f));
        assert!(
            (x - 0.3).abs() < 1e-12 && (a - 2.0).abs() < 1e-12,
            "{x} {a}"
        );
        // a vertex outside the points is kept at the nearest end
        let g = |x: f64| (x - 5.0) * (x - 5.0);
        let xs = [0.0, 1.0, 2.0];
        assert_eq!(joint_minimum(&xs, &xs.map(g)).0, 2.0);
        // a profile that is not convex: its best point, and no curvature
        let h = |x: f64| -(x * x);
        let (x, a) = joint_minimum(&xs, &xs.map(h));
        assert_eq!(x, 2.0);
        assert!(a.is_nan());
    }
}
