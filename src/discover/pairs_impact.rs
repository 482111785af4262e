//! The impact-specific test of the collision runs: the whole-run pair fit's residuals split by
//! time since the last impact, a misfit concentrated in the milliseconds after impacts (isolated
//! tracking outliers left out; Student's t over the runs' log ratios) and its decision in words.

use crate::fit::collision::wholerun::{simulate_run, GroupFit, PairRun};
use crate::stats::dist::t_sf;

/// Significance of both tests of the pairs (this one and the physics test of `pairs`).
pub const ALPHA: f64 = 0.01;

/// Window after an impact that counts as "at the impact" (s).
pub const IMPACT_WINDOW_S: f64 = 5e-3;
/// An impact-specific misfit must also raise the mean squared residual by this factor.
pub(super) const MIN_RATIO: f64 = 1.3;
/// A whitened residual beyond this many σ whose neighbours in time are both within
/// `NEIGHBOUR_SIGMA` is a tracking outlier (one bad frame), not a misfit, which spans frames: the
/// impact test leaves it out. Kept in, a handful of 30 µm outliers among the few samples after
/// impacts read as an impact misfit (1.52× on a 2 kHz null with 0.5 % outliers).
const OUTLIER_SIGMA: f64 = 4.0;
const NEIGHBOUR_SIGMA: f64 = 2.0;

/// The residuals after impacts against the rest, pooled and run by run.
pub(super) struct ImpactSplit {
    /// Mean squared whitened residual within `IMPACT_WINDOW_S` after an impact over that
    /// elsewhere (isolated tracking outliers left out), in the typical run: the geometric mean
    /// of the runs' ratios (pooled when no run has samples on both sides). One run fitted badly
    /// at its start (−13σ for 5 ms) made the pooled ratio 1.59× on a null.
    pub(super) ratio: f64,
    /// The run with the largest ratio, and that ratio.
    pub(super) worst: Option<(String, f64)>,
    /// Samples within the window.
    pub(super) n_near: usize,
    /// ln(near / far) of each run with at least `MIN_SAMPLES` samples on both sides: the runs
    /// are the independent units (residuals within a run are correlated by any misfit).
    pub(super) log_ratios: Vec<f64>,
    /// Lag-1 autocorrelation of the whitened residuals, pooled over the tracks (each residual
    /// clipped at 10σ).
    pub(super) lag1: f64,
}

/// Samples a run needs on each side of the split to give its own ratio.
const MIN_SAMPLES: usize = 4;

/// Split the free fit's residuals by time since the last impact.
/// Each sample's noise scale over the track's mean, when the tracking noise grows with speed as
/// σ² = σ₀² + (c·v)² (c = `blur_s`, the single runs' `blur.rs`): fast particles just after an
/// impact have a larger noise, which is no misfit. Empty when c = 0.
fn speed_scale(v: &[f64], sigma_m: f64, blur_s: f64) -> Vec<f64> {
    if !(blur_s > 0.0) || v.is_empty() {
        return Vec::new();
    }
    let c2 = blur_s * blur_s;
    let mean_v2 = v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
    // the run's σ is its noise's mean over the track: what the speeds leave of it is σ₀²
    let base = (sigma_m * sigma_m - c2 * mean_v2).max(0.05 * sigma_m * sigma_m);
    let var: Vec<f64> = v.iter().map(|x| base + c2 * x * x).collect();
    super::blur::relative(&var)
}

/// The split of the whole-run fit `fit`'s residuals, each sample whitened by its noise (the
/// run's σ, grown with speed by `blur_s` where the single runs measured that).
pub(super) fn split_by_impact(runs: &[PairRun], fit: &GroupFit, blur_s: f64) -> ImpactSplit {
    let (mut near, mut far) = ((0.0, 0usize), (0.0, 0usize));
    let mut log_ratios = Vec::new();
    let mut worst: Option<(String, f64)> = None;
    let (mut cross, mut square) = (0.0, 0.0);
    for (run, own) in runs.iter().zip(&fit.result.own) {
        let (rel, traj) = simulate_run(run, &fit.spec, &fit.result.shared, own);
        let (mut rn, mut rf) = ((0.0, 0usize), (0.0, 0usize));
        for p in 0..2 {
            let v: Vec<f64> = run.samples[p]
                .iter()
                .map(|&(i, _)| traj.particles[p].v_mps[i])
                .collect();
            let scale = speed_scale(&v, run.sigma_m, blur_s);
            let r: Vec<f64> = run.samples[p]
                .iter()
                .enumerate()
                .map(|(k, &(i, zd))| {
                    (traj.particles[p].z_m[i] - zd) / run.sigma_m / scale.get(k).unwrap_or(&1.0)
                })
                .collect();
            let clipped: Vec<f64> = r.iter().map(|x| x.clamp(-10.0, 10.0)).collect();
            cross += clipped.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
            square += clipped.iter().map(|x| x * x).sum::<f64>();
            for (k, &(i, _)) in run.samples[p].iter().enumerate() {
                let calm = |j: Option<usize>| {
                    j.and_then(|j| r.get(j))
                        .is_none_or(|x| x.abs() < NEIGHBOUR_SIGMA)
                };
                if r[k].abs() > OUTLIER_SIGMA && calm(k.checked_sub(1)) && calm(Some(k + 1)) {
                    continue;
                }
                let u = (r[k] * r[k]).min(100.0);
                let close = traj
                    .impacts
                    .iter()
                    .any(|im| !im.joined && rel[i] >= im.t_s && rel[i] - im.t_s < IMPACT_WINDOW_S);
                let bin = if close { &mut rn } else { &mut rf };
                bin.0 += u;
                bin.1 += 1;
            }
        }
        if rn.1 >= MIN_SAMPLES && rf.1 >= MIN_SAMPLES && rn.0 > 0.0 && rf.0 > 0.0 {
            let l = (rn.0 / rn.1 as f64 / (rf.0 / rf.1 as f64)).ln();
            if worst.as_ref().is_none_or(|(_, w)| l > *w) {
                worst = Some((run.run.clone(), l));
            }
            log_ratios.push(l);
        }
        near = (near.0 + rn.0, near.1 + rn.1);
        far = (far.0 + rf.0, far.1 + rf.1);
    }
    let mean = |b: (f64, usize)| b.0 / b.1.max(1) as f64;
    let ratio = if log_ratios.is_empty() {
        mean(near) / mean(far).max(1e-12)
    } else {
        (log_ratios.iter().sum::<f64>() / log_ratios.len() as f64).exp()
    };
    ImpactSplit {
        ratio,
        worst: worst.map(|(r, l)| (r, l.exp())),
        n_near: near.1,
        log_ratios,
        lag1: if square > 0.0 { cross / square } else { 0.0 },
    }
}

impl ImpactSplit {
    /// Standard error of the ratio from the spread of the runs' log ratios (pooled samples when
    /// fewer than two runs give one).
    pub(super) fn ratio_se(&self) -> f64 {
        let n = self.log_ratios.len();
        if n < 2 {
            return self.ratio * (2.0 / self.n_near.max(1) as f64).sqrt();
        }
        let mean = self.log_ratios.iter().sum::<f64>() / n as f64;
        let var = self
            .log_ratios
            .iter()
            .map(|l| (l - mean).powi(2))
            .sum::<f64>()
            / (n - 1) as f64;
        self.ratio * (var / n as f64).sqrt()
    }
}

/// One-sided p-value that the runs' ln(near/far) have a positive mean: Student's t over the
/// runs. 1 (no evidence) with fewer than 3 runs.
pub(super) fn impact_p_value(log_ratios: &[f64]) -> f64 {
    let n = log_ratios.len();
    if n < 3 {
        return 1.0;
    }
    let mean = log_ratios.iter().sum::<f64>() / n as f64;
    let var = log_ratios.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    if var <= 0.0 {
        return if mean > 0.0 { 0.0 } else { 1.0 };
    }
    t_sf(mean / (var / n as f64).sqrt(), (n - 1) as f64)
}

/// The impact-specific test's decision and its words from the mean-square ratio and its Holm
/// p-value: a misfit needs both significance (p < α) and size (ratio > `MIN_RATIO`); a
/// significant but small excess is said as such, not as "no misfit".
pub(super) fn impact_decision(ratio: f64, p_holm: f64) -> (bool, String) {
    let significant = p_holm < ALPHA;
    let large = ratio > MIN_RATIO;
    let words = match (significant, large) {
        (true, true) => format!(
            "the misfit concentrates after impacts (mean square {ratio:.2}× the rest in the typical run): the impact model misses something"
        ),
        (true, false) => format!(
            "a significant but small excess after impacts: the mean square within 5 ms is {ratio:.2}× the rest in the typical run (p Holm {p_holm:.1e}), below the {MIN_RATIO}× that counts as an impact-model misfit"
        ),
        (false, _) => format!(
            "no significant misfit specific to impacts (mean square {ratio:.2}× the rest in the typical run, p Holm {p_holm:.2})"
        ),
    };
    (significant && large, words)
}
