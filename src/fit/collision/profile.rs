//! Profile likelihood of μ_pp: the whole-run fit's deviance with μ_pp held at each value of a
//! grid (every other parameter refitted), and what it implies — an interval when the profile has
//! a minimum inside the grid, a one-sided bound when it is flat towards one end.

use super::wholerun::{fit_group, residuals, FitSpec, GroupFit, PairRun, MU_PP};
use crate::artifacts::collision_summary::{
    MuPpProfile, ProfilePoint, ProfileVerdict, STOP_DEVIANCE,
};

/// Rise of the deviance that bounds a 95 % interval of one parameter (χ²₁ quantile).
pub const DELTA_95: f64 = 3.841_458_820_694_124;

/// Huber threshold of the whole-run fits (whitened residuals): residuals enter the serial
/// correlation clipped here, as they enter the fit.
const HUBER_K: f64 = 3.0;

/// Largest lag-1 autocorrelation used for the variance inflation (factor 39).
const RHO_MAX: f64 = 0.95;

/// What the best fit's residuals say about the deviance's noise model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualChecks {
    /// Lag-1 autocorrelation of the whitened residuals.
    pub lag1: f64,
    /// Lag-1 autocorrelation of their contributions to the μ_pp score.
    pub score_lag1: f64,
    /// mean ψ² / mean ψ′ (the Huber deviance's scale).
    pub scale: f64,
}

/// Pooled lag-1 autocorrelations at the best fit `fit`, over consecutive samples of every track
/// of every run: of the whitened residuals ψ_k (clipped at the Huber threshold, as in the fit;
/// not centred: a track's offset is correlation too), and of the residuals' contributions to
/// the μ_pp score, g_k = ψ_k ∂r_k/∂ln μ_pp (the samples μ_pp depends on: sliding and impacts).
/// Each is Σ x_k x_{k+1} / Σ x_k². And the deviance's scale mean ψ² / mean ψ′: a Huber
/// deviance rises at the true parameter by this much on average (the robust analogue of
/// the residual variance; 1 when the whitening noise is right).
pub fn residual_checks(runs: &[PairRun], fit: &GroupFit) -> ResidualChecks {
    const H: f64 = 1e-3;
    let (mut lag, mut var, mut glag, mut gvar) = (0.0, 0.0, 0.0, 0.0);
    let mut inside = 0usize;
    let shifted = |k: f64| {
        let mut p = fit.result.shared.clone();
        p[MU_PP] *= (k * H).exp();
        p
    };
    let (up, down) = (shifted(1.0), shifted(-1.0));
    for (run, own) in runs.iter().zip(&fit.result.own) {
        let n = run.n_samples();
        let (mut r, mut rp, mut rm) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        residuals(run, &fit.spec, &fit.result.shared, own, &mut r);
        residuals(run, &fit.spec, &up, own, &mut rp);
        residuals(run, &fit.spec, &down, own, &mut rm);
        let psi: Vec<f64> = r.iter().map(|x| x.clamp(-HUBER_K, HUBER_K)).collect();
        inside += r.iter().filter(|x| x.abs() <= HUBER_K).count();
        let g: Vec<f64> = (0..n)
            .map(|k| {
                let d = (rp[k] - rm[k]) / (2.0 * H);
                if rp[k].abs() < 1e5 && rm[k].abs() < 1e5 && d.is_finite() {
                    psi[k] * d
                } else {
                    0.0
                }
            })
            .collect();
        let n0 = run.samples[0].len();
        for (lo, hi) in [(0, n0), (n0, n)] {
            let (x, y) = (&psi[lo..hi], &g[lo..hi]);
            var += x.iter().map(|v| v * v).sum::<f64>();
            lag += x.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
            gvar += y.iter().map(|v| v * v).sum::<f64>();
            glag += y.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
        }
    }
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    let scale = if inside > 0 { var / inside as f64 } else { 1.0 };
    ResidualChecks {
        lag1: ratio(lag, var),
        score_lag1: ratio(glag, gvar),
        scale: if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        },
    }
}

/// Variance inflation (1 + ρ)/(1 − ρ) of the mean of AR(1) residuals with lag-1
/// autocorrelation ρ (ρ clipped to [0, 0.95]).
pub fn ar1_inflation(rho: f64) -> f64 {
    let rho = if rho.is_finite() {
        rho.clamp(0.0, RHO_MAX)
    } else {
        0.0
    };
    (1.0 + rho) / (1.0 - rho)
}

/// The grid: log-spaced from 0.05 to 5 (13 values).
pub fn default_grid() -> Vec<f64> {
    (0..=12)
        .map(|i| 0.05 * 10f64.powf(i as f64 / 6.0))
        .collect()
}

/// The pair fit of `runs` with μ_pp held at `mu`, started from `from`.
fn fit_held(
    runs: &[PairRun],
    best: &GroupFit,
    mu: f64,
    from: &GroupFit,
    max_iter: usize,
) -> GroupFit {
    let spec = FitSpec {
        mu_pp_held: Some(mu),
        ..best.spec.clone()
    };
    fit_group(runs, &spec, Some(from), max_iter)
}

/// The fits at the grid values, walking outward from the value nearest the estimate, each from
/// its neighbour's solution, and the grid values the walk did not reach.
fn walk_grid(
    runs: &[PairRun],
    best: &GroupFit,
    grid: &[f64],
    max_iter: usize,
) -> (Vec<(f64, GroupFit)>, Vec<f64>) {
    let mu_best = best.result.shared[MU_PP];
    let n = grid.len();
    let centre = (0..n)
        .min_by(|&a, &b| {
            (grid[a].ln() - mu_best.ln())
                .abs()
                .total_cmp(&(grid[b].ln() - mu_best.ln()).abs())
        })
        .unwrap_or(0);
    let mut fits: Vec<Option<GroupFit>> = vec![None; n];
    let solve = |mu: f64, from: &GroupFit| fit_held(runs, best, mu, from, max_iter);
    if n > 0 {
        fits[centre] = Some(solve(grid[centre], best));
    }
    // past the stop level on the far side of the estimate: the walk goes no further
    let stop = |mu: f64, f: &GroupFit, down: bool| {
        (if down { mu < mu_best } else { mu > mu_best }) && f.cost() - best.cost() > STOP_DEVIANCE
    };
    for i in (0..centre).rev() {
        let from = fits[i + 1].as_ref().unwrap();
        if stop(grid[i + 1], from, true) {
            break;
        }
        fits[i] = Some(solve(grid[i], from));
    }
    for i in centre + 1..n {
        let from = fits[i - 1].as_ref().unwrap();
        if stop(grid[i - 1], from, false) {
            break;
        }
        fits[i] = Some(solve(grid[i], from));
    }
    let not_fitted: Vec<f64> = grid
        .iter()
        .zip(&fits)
        .filter(|(_, f)| f.is_none())
        .map(|(mu, _)| *mu)
        .collect();
    let fits: Vec<(f64, GroupFit)> = grid
        .iter()
        .copied()
        .zip(fits)
        .filter_map(|(mu, f)| f.map(|f| (mu, f)))
        .collect();
    (fits, not_fitted)
}

/// Adds fits at ±1 and ±2 half-widths of the covariance interval (in ln μ_pp) around the
/// estimate (the grid may be coarser than the interval) and returns the runs' dispersion of the
/// deviance's slope against its curvature (1 when the interval is unknown).
fn refine_near_estimate(
    runs: &[PairRun],
    best: &GroupFit,
    fits: &mut Vec<(f64, GroupFit)>,
    max_iter: usize,
) -> f64 {
    let mu_best = best.result.shared[MU_PP];
    let se_ln = best.result.shared_se(MU_PP) / mu_best;
    let mut dispersion = 1.0;
    if se_ln.is_finite() && se_ln > 0.0 {
        let h = (1.96 * se_ln).max(1e-4);
        for k in [-2.0, -1.0, 1.0, 2.0] {
            let mu = mu_best * (k * h).exp();
            let from = if k.abs() > 1.5 {
                fits.iter()
                    .min_by(|a, b| {
                        (a.0.ln() - mu.ln())
                            .abs()
                            .total_cmp(&(b.0.ln() - mu.ln()).abs())
                    })
                    .map(|f| f.1.clone())
                    .unwrap_or_else(|| best.clone())
            } else {
                best.clone()
            };
            fits.push((mu, fit_held(runs, best, mu, &from, max_iter)));
        }
        // runs are the independent units: per-run slopes of the deviance at the estimate
        // against its curvature (sandwich / model variance of ln μ_pp)
        let n = fits.len();
        let (minus, plus) = (&fits[n - 3].1, &fits[n - 2].1);
        let c0 = &best.result.block_cost;
        let (cm, cp) = (&minus.result.block_cost, &plus.result.block_cost);
        let curv: f64 = (0..c0.len())
            .map(|r| (cp[r] + cm[r] - 2.0 * c0[r]) / (h * h))
            .sum();
        let spread: f64 = (0..c0.len())
            .map(|r| ((cp[r] - cm[r]) / (2.0 * h)).powi(2))
            .sum();
        if curv > 0.0 && spread.is_finite() {
            dispersion = (spread / (2.0 * curv)).max(1.0);
        }
    }
    dispersion
}

/// Profile μ_pp over `grid` starting from the best fit `best` (μ_pp free). Fits walk outward
/// from the grid value nearest the best estimate, each starting from its neighbour's solution,
/// and stop in a direction after a fit beyond the estimate whose deviance passes
/// `STOP_DEVIANCE`.
pub fn profile_mu_pp(
    runs: &[PairRun],
    best: &GroupFit,
    grid: &[f64],
    max_iter: usize,
) -> MuPpProfile {
    profile_and_lowest(runs, best, grid, max_iter).0
}

/// `profile_mu_pp`, with the profile's lowest fit when it ended below `best` (μ_pp held there):
/// then `best` is not the joint fit's minimum, and that fit is where to start it again.
pub fn profile_and_lowest(
    runs: &[PairRun],
    best: &GroupFit,
    grid: &[f64],
    max_iter: usize,
) -> (MuPpProfile, Option<GroupFit>) {
    let mu_best = best.result.shared[MU_PP];
    let (mut fits, not_fitted) = walk_grid(runs, best, grid, max_iter);
    let dispersion = refine_near_estimate(runs, best, &mut fits, max_iter);
    let checks = residual_checks(runs, best);
    let serial_factor = ar1_inflation(checks.score_lag1);
    let inflation = dispersion.max(checks.scale * serial_factor);
    fits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let c_min = fits.iter().map(|f| f.1.cost()).fold(best.cost(), f64::min);
    let points: Vec<ProfilePoint> = fits
        .iter()
        .map(|(mu_pp, f)| ProfilePoint {
            mu_pp: *mu_pp,
            deviance: (f.cost() - c_min).max(0.0) / inflation,
            converged: f.converged(),
        })
        .collect();
    let estimate = if best.cost() <= c_min + 1e-9 {
        mu_best
    } else {
        points
            .iter()
            .min_by(|a, b| a.deviance.total_cmp(&b.deviance))
            .map(|p| p.mu_pp)
            .unwrap_or(mu_best)
    };
    let lowest = fits
        .iter()
        .map(|f| &f.1)
        .filter(|f| f.cost() < best.cost())
        .min_by(|a, b| a.cost().total_cmp(&b.cost()))
        .cloned();
    let profile = MuPpProfile {
        verdict: verdict(&points, estimate, DELTA_95),
        points,
        not_fitted,
        threshold: DELTA_95,
        dispersion,
        lag1_autocorrelation: checks.lag1,
        score_lag1_autocorrelation: checks.score_lag1,
        serial_factor,
        scale_factor: checks.scale,
        inflation,
    };
    (profile, lowest)
}

/// Where the deviance crosses `delta` on either side of the estimate (its square root
/// interpolated linearly in ln μ_pp between profile values), or a one-sided bound when it never does on one side.
pub fn verdict(points: &[ProfilePoint], estimate: f64, delta: f64) -> ProfileVerdict {
    // the estimate itself is the profile's minimum (deviance 0)
    let mut all: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| (p.mu_pp.ln() - estimate.ln()).abs() > 1e-9)
        .map(|p| (p.mu_pp.ln(), p.deviance))
        .collect();
    all.push((estimate.ln(), 0.0));
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let c = all.iter().position(|p| p.0 == estimate.ln()).unwrap_or(0);
    // the signed root of the deviance is linear in the parameter near a quadratic minimum
    let cross = |a: (f64, f64), b: (f64, f64)| {
        let (ra, rb) = (a.1.max(0.0).sqrt(), b.1.max(0.0).sqrt());
        let f = (delta.sqrt() - ra) / (rb - ra);
        (a.0 + f * (b.0 - a.0)).exp()
    };
    let lo = (0..c)
        .rev()
        .find(|&i| all[i].1 > delta)
        .map(|i| cross(all[i + 1], all[i]));
    let hi = (c + 1..all.len())
        .find(|&i| all[i].1 > delta)
        .map(|i| cross(all[i - 1], all[i]));
    match (lo, hi) {
        (Some(lo), Some(hi)) => ProfileVerdict::Interval { estimate, lo, hi },
        (Some(lo), None) => ProfileVerdict::LowerBound { lo },
        (None, Some(hi)) => ProfileVerdict::UpperBound { hi },
        (None, None) => ProfileVerdict::Unconstrained,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(f: impl Fn(f64) -> f64) -> Vec<ProfilePoint> {
        default_grid()
            .into_iter()
            .map(|mu| ProfilePoint {
                mu_pp: mu,
                deviance: f(mu),
                converged: true,
            })
            .collect()
    }

    #[test]
    fn a_parabola_in_ln_mu_gives_its_interval() {
        // D = ((ln μ − ln 0.3)/0.1)²: crosses 3.84 at ln μ = ln 0.3 ± 0.196
        let p = pts(|mu| ((mu.ln() - 0.3f64.ln()) / 0.1).powi(2));
        let ProfileVerdict::Interval { lo, hi, .. } = verdict(&p, 0.3, DELTA_95) else {
            panic!("no interval");
        };
        assert!((lo / 0.3 - (-0.196f64).exp()).abs() < 0.06, "{lo}");
        assert!((hi / 0.3 - 0.196f64.exp()).abs() < 0.06, "{hi}");
    }

    #[test]
    fn ar1_inflation_follows_the_effective_sample_size() {
        assert_eq!(ar1_inflation(0.0), 1.0);
        assert_eq!(ar1_inflation(-0.4), 1.0);
        assert!((ar1_inflation(0.7) - 1.7 / 0.3).abs() < 1e-12);
        assert!((ar1_inflation(0.99) - 1.95 / 0.05).abs() < 1e-9);
        assert_eq!(ar1_inflation(f64::NAN), 1.0);
    }

    #[test]
    fn a_profile_flat_above_gives_a_lower_bound() {
        // rises steeply below 0.8, flat above
        let p = pts(|mu| if mu < 0.8 { 50.0 * (0.8 - mu) } else { 0.0 });
        match verdict(&p, 2.0, DELTA_95) {
            ProfileVerdict::LowerBound { lo } => assert!(lo > 0.5 && lo < 0.8, "{lo}"),
            v => panic!("{v:?}"),
        }
        assert!(verdict(&pts(|_| 0.0), 1.0, DELTA_95) == ProfileVerdict::Unconstrained);
    }
}
