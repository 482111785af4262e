//! The impact-specific test of the collision runs: the whole-run pair fit's residuals split by
//! time since the last impact, a misfit concentrated in the milliseconds after impacts beyond what
//! the tracker's noise there gives (isolated tracking outliers left out; Student's t over the
//! runs' log ratios) and its decision in words.

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
    /// elsewhere (isolated tracking outliers left out) carried to the near side's speeds by the
    /// noise's growth with speed (`split_by_impact`), in the typical run: the geometric mean
    /// of the runs' ratios (pooled when no run has samples on both sides). One run fitted badly
    /// at its start (−13σ for 5 ms) made the pooled ratio 1.59× on a null.
    pub(super) ratio: f64,
    /// The run with the largest ratio, and that ratio.
    pub(super) worst: Option<(String, f64)>,
    /// Samples within the window.
    pub(super) n_near: usize,
    /// ln(near / expected near) of each run with at least `MIN_SAMPLES` samples on both sides:
    /// the runs are the independent units (residuals within a run are correlated by any misfit).
    pub(super) log_ratios: Vec<f64>,
    /// Lag-1 autocorrelation of the whitened residuals, pooled over the tracks (each residual
    /// clipped at 10σ).
    pub(super) lag1: f64,
}

/// Samples a run needs on each side of the split to give its own ratio.
const MIN_SAMPLES: usize = 4;

/// A squared whitened residual, or a squared second difference in units of its white-noise
/// variance (6), counts at most this much: ten standard deviations.
const CAP: f64 = 100.0;

/// Sums of a side of the split: squared residuals and squared speeds.
#[derive(Clone, Copy, Default)]
struct Side {
    u: f64,
    v2: f64,
    n: usize,
}

impl Side {
    fn add(&mut self, u: f64, v2: f64) {
        self.u += u;
        self.v2 += v2;
        self.n += 1;
    }
    fn merge(&mut self, o: &Side) {
        self.u += o.u;
        self.v2 += o.v2;
        self.n += o.n;
    }
    fn mean(&self) -> f64 {
        self.u / self.n.max(1) as f64
    }
    fn mean_v2(&self) -> f64 {
        self.v2 / self.n.max(1) as f64
    }
}

/// Least-squares sums of the second differences' squares y against the squared speed x, away
/// from impacts: the noise's growth with speed.
#[derive(Clone, Copy, Default)]
struct Growth {
    n: f64,
    x: f64,
    y: f64,
    xx: f64,
    xy: f64,
}

impl Growth {
    fn add(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.x += x;
        self.y += y;
        self.xx += x * x;
        self.xy += x * y;
    }
    fn merge(&mut self, o: &Growth) {
        self.n += o.n;
        self.x += o.x;
        self.y += o.y;
        self.xx += o.xx;
        self.xy += o.xy;
    }
    /// The slope of the noise's variance in v² (whitened units per (m/s)²), never below 0.
    fn slope(&self) -> f64 {
        let var = self.xx - self.x * self.x / self.n.max(1.0);
        if self.n < MIN_SAMPLES as f64 || !(var > 0.0) {
            return 0.0;
        }
        ((self.xy - self.x * self.y / self.n) / var).max(0.0)
    }
}

/// One run's (or the pooled runs') sums.
#[derive(Clone, Copy, Default)]
struct Bins {
    near: Side,
    far: Side,
    growth: Growth,
}

impl Bins {
    fn merge(&mut self, o: &Bins) {
        self.near.merge(&o.near);
        self.far.merge(&o.far);
        self.growth.merge(&o.growth);
    }

    /// ln of the mean square after impacts over what the noise gives there: the far side's mean
    /// square carried to the near side's speeds by the noise's growth with speed (its level
    /// elsewhere kept at least a tenth of the far mean square). None without enough samples.
    fn log_ratio(&self) -> Option<f64> {
        let enough = |s: &Side| s.n >= MIN_SAMPLES && s.u > 0.0;
        if !(enough(&self.near) && enough(&self.far)) {
            return None;
        }
        let b = self.growth.slope();
        let far = self.far.mean();
        let base = (far - b * self.far.mean_v2()).max(0.1 * far);
        let expected = base + b * self.near.mean_v2();
        Some((self.near.mean() / expected).ln())
    }
}

/// The split of the whole-run fit `fit`'s residuals (whitened by each run's σ) by time since the
/// last impact, the mean square after impacts measured against what the tracker's noise gives
/// there.
///
/// Motion blur makes the tracks noisier where the particles are fast, which is just after
/// impacts: whitened by one σ per run, a null with blur and correlated noise read 1.9× (one
/// material of ten null seeds). So the noise's growth with speed is learned in each run away
/// from its impacts, from the residuals' second differences r[k−1] − 2r[k] + r[k+1] over
/// consecutive frames (a smooth misfit hardly bends them, while white noise fills them) against
/// the model's squared speed; the far side's mean square, carried to the near side's speeds by
/// that growth, is what the noise alone gives after the impacts. A misfit after impacts, even
/// one as quick as a ringing, is not in what the noise is learned from. Second differences across
/// an impact or the kick (where the model's kink and the data's need not fall in the same frame)
/// or through an isolated outlier are left out.
pub(super) fn split_by_impact(runs: &[PairRun], fit: &GroupFit) -> ImpactSplit {
    let mut pooled = Bins::default();
    let mut log_ratios = Vec::new();
    let mut worst: Option<(String, f64)> = None;
    let (mut cross, mut square) = (0.0, 0.0);
    for (run, own) in runs.iter().zip(&fit.result.own) {
        let (rel, traj) = simulate_run(run, &fit.spec, &fit.result.shared, own);
        let mut bins = Bins::default();
        let close = |t: f64| {
            traj.impacts
                .iter()
                .any(|im| !im.joined && t >= im.t_s && t - im.t_s < IMPACT_WINDOW_S)
        };
        // a kink of the model between two times: an impact, or the kick (rel leaves 0)
        let kink = |a: f64, b: f64| {
            a <= 0.0 && b > 0.0 || traj.impacts.iter().any(|im| a < im.t_s && im.t_s <= b)
        };
        for p in 0..2 {
            let s = &run.samples[p];
            let track = &traj.particles[p];
            let r: Vec<f64> = s
                .iter()
                .map(|&(i, zd)| (track.z_m[i] - zd) / run.sigma_m)
                .collect();
            let clipped: Vec<f64> = r.iter().map(|x| x.clamp(-10.0, 10.0)).collect();
            cross += clipped.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
            square += clipped.iter().map(|x| x * x).sum::<f64>();
            let calm = |j: Option<usize>| {
                j.and_then(|j| r.get(j))
                    .is_none_or(|x| x.abs() < NEIGHBOUR_SIGMA)
            };
            let outlier: Vec<bool> = (0..r.len())
                .map(|k| r[k].abs() > OUTLIER_SIGMA && calm(k.checked_sub(1)) && calm(Some(k + 1)))
                .collect();
            for (k, &(i, _)) in s.iter().enumerate() {
                if outlier[k] {
                    continue;
                }
                let u = (r[k] * r[k]).min(CAP);
                let v2 = track.v_mps[i] * track.v_mps[i];
                let side = if close(rel[i]) {
                    &mut bins.near
                } else {
                    &mut bins.far
                };
                side.add(u, v2);
            }
            for k in 1..s.len().saturating_sub(1) {
                let (a, i, b) = (s[k - 1].0, s[k].0, s[k + 1].0);
                let consecutive = a + 1 == i && i + 1 == b;
                if !consecutive
                    || close(rel[i])
                    || outlier[k - 1..=k + 1].iter().any(|&o| o)
                    || kink(rel[a], rel[b])
                {
                    continue;
                }
                let d2 = r[k - 1] - 2.0 * r[k] + r[k + 1];
                bins.growth
                    .add(track.v_mps[i] * track.v_mps[i], (d2 * d2 / 6.0).min(CAP));
            }
        }
        if let Some(l) = bins.log_ratio() {
            if worst.as_ref().is_none_or(|(_, w)| l > *w) {
                worst = Some((run.run.clone(), l));
            }
            log_ratios.push(l);
        }
        pooled.merge(&bins);
    }
    let ratio = if log_ratios.is_empty() {
        // no run has enough samples on both sides: the pooled samples, or none (NaN, said as
        // too few samples by `impact_decision`)
        pooled.log_ratio().map_or(f64::NAN, f64::exp)
    } else {
        (log_ratios.iter().sum::<f64>() / log_ratios.len() as f64).exp()
    };
    ImpactSplit {
        ratio,
        worst: worst.map(|(r, l)| (r, l.exp())),
        n_near: pooled.near.n,
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
    if !ratio.is_finite() {
        return (
            false,
            format!("too few samples after impacts (under {MIN_SAMPLES} on a side) to compare them with the tracking noise there: not tested"),
        );
    }
    let significant = p_holm < ALPHA;
    let large = ratio > MIN_RATIO;
    let words = match (significant, large) {
        (true, true) => format!(
            "the misfit concentrates after impacts (mean square {ratio:.2}× what the tracking noise gives there, in the typical run): the impact model misses something"
        ),
        (true, false) => format!(
            "a significant but small excess after impacts: the mean square within 5 ms is {ratio:.2}× what the tracking noise gives there in the typical run (p Holm {p_holm:.1e}), below the {MIN_RATIO}× that counts as an impact-model misfit"
        ),
        (false, _) => format!(
            "no significant misfit specific to impacts (mean square {ratio:.2}× what the tracking noise gives there in the typical run, p Holm {p_holm:.2})"
        ),
    };
    (significant && large, words)
}
