//! Per-material aggregates of single-run fits: μ (weighted, and the chapter's mean over fast runs),
//! the T-vs-v0 and μ-vs-v0 lines, each with a seeded bootstrap interval over whole runs. Only
//! `converged` fits enter (a `suspect` or unfinished one is listed in `left_out`), and every
//! estimate is one that a single wild run cannot capture: the robust weighted mean of μ and
//! Theil–Sen lines.

use super::bootstrap::percentile_intervals_in_groups;
use super::options::OptionError;
use super::regression::{kept_table, mean_kept, mean_where, RobustMean};
use super::single::SingleFit;
use crate::artifacts::run_fit::FitStatus;
use crate::artifacts::summary::{
    DragLine, Estimate, FrictionLine, LeftOut, MaterialSummary, SingleSummary,
};
use crate::stats::{theil_sen_intercept, theil_sen_many, InterceptOrder, SlopeOrder, SLOPE_LANES};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Params of the `aggregate` stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AggregateOptions {
    pub bootstrap_resamples: usize,
    pub level: f64,
    /// The chapter averages μ over runs faster than this.
    pub fast_min_speed_mps: f64,
    /// k = m R² / I of the particles (for μ_pp from the collisions); keep it equal to the fit
    /// stage's `k` (`[project] params` sets both).
    pub k: f64,
    /// Opening angle of the groove, degrees, for the whole-run collision fits (the chapter's
    /// 70.6 by default; `[project] params` sets it for every stage).
    pub groove_angle_deg: f64,
}

impl Default for AggregateOptions {
    fn default() -> Self {
        AggregateOptions {
            bootstrap_resamples: 2000,
            level: 0.95,
            fast_min_speed_mps: 0.03,
            k: 2.5,
            groove_angle_deg: 70.6,
        }
    }
}

impl AggregateOptions {
    /// Check ranges; the error names the key and a valid range.
    pub fn validate(&self) -> Result<(), OptionError> {
        let bad = |key, message| Err(OptionError { key, message });
        if !(100..=1_000_000).contains(&self.bootstrap_resamples) {
            return bad(
                "bootstrap_resamples",
                "must be between 100 and 1000000, e.g. 2000",
            );
        }
        if !(self.level > 0.5 && self.level < 1.0) {
            return bad("level", "must be between 0.5 and 1, e.g. 0.95");
        }
        if !(self.fast_min_speed_mps >= 0.0 && self.fast_min_speed_mps.is_finite()) {
            return bad(
                "fast_min_speed_mps",
                "must be a speed ≥ 0 in m/s, e.g. 0.03",
            );
        }
        super::options::check_groove(self.groove_angle_deg, self.k)?;
        Ok(())
    }
}

/// Aggregate the single-run fits (any order) per material and pooled. `seed` drives the bootstrap.
pub fn aggregate_single(fits: &[SingleFit], opts: &AggregateOptions, seed: u64) -> SingleSummary {
    aggregate_single_memo(fits, opts, seed, None)
}

/// Material summaries an earlier run made, by a key of everything a summary is made of: the
/// options, its seed and the digests of its fits (`aggregate_single_memo`).
pub trait SummaryMemo: Sync {
    fn get(&self, key: &[u8; 32]) -> Option<MaterialSummary>;
    fn put(&self, key: [u8; 32], summary: &MaterialSummary);
}

/// `aggregate_single`, taking from `memo` each summary whose fits did not change (after an edit
/// of one recording, every material but the edited run's) and giving it those it made;
/// `digests[i]` is a digest of `fits[i]` (the stage's: of its item's bytes). The same summaries
/// as without a memo.
pub fn aggregate_single_memo(
    fits: &[SingleFit],
    opts: &AggregateOptions,
    seed: u64,
    memo: Option<(&[[u8; 32]], &dyn SummaryMemo)>,
) -> SingleSummary {
    let mut by_material: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    let mut order: Vec<usize> = (0..fits.len()).collect();
    order.sort_by(|&a, &b| fits[a].run.cmp(&fits[b].run));
    for &i in &order {
        by_material
            .entry(fits[i].material.as_str())
            .or_default()
            .push(i);
    }
    let summary = |picked: &[usize], seed: u64| {
        let fs: Vec<&SingleFit> = picked.iter().map(|&i| &fits[i]).collect();
        let Some((digests, memo)) = memo else {
            return material_summary(&fs, opts, seed);
        };
        let mut h = blake3::Hasher::new();
        h.update(b"groove material summary v1\0");
        h.update(&serde_json::to_vec(opts).expect("options serialize"));
        h.update(&seed.to_le_bytes());
        h.update(&(picked.len() as u64).to_le_bytes());
        for &i in picked {
            h.update(&digests[i]);
        }
        let key = *h.finalize().as_bytes();
        memo.get(&key).unwrap_or_else(|| {
            let made = material_summary(&fs, opts, seed);
            memo.put(key, &made);
            made
        })
    };
    // Each summary's bootstrap is parallel, but its draws and its estimate are not: the
    // summaries run side by side so that those serial parts overlap.
    let (materials, pooled) = rayon::join(
        || {
            by_material
                .par_iter()
                .map(|(m, picked)| (m.to_string(), summary(picked, seed ^ fnv1a(m))))
                .collect()
        },
        || summary(&order, seed ^ fnv1a("\0pooled")),
    );
    SingleSummary {
        n_runs: fits.len(),
        n_converged: pooled.n_converged,
        fast_min_speed_mps: opts.fast_min_speed_mps,
        materials,
        pooled,
    }
}

/// Run pairs behind the Theil–Sen slope of the estimate: every pair up to this count (about
/// 2,000 runs), a uniform draw of this many above (`stats::line`).
const POINT_PAIRS: usize = 2_000_000;
/// Run pairs behind the slopes of the bootstrap resamples (`stats::SlopeOrder`): every pair up to
/// `max(RESAMPLE_PAIRS, RESAMPLE_PAIRS_PER_RUN · n)` (every pair up to about 320 runs), a fixed
/// uniform draw of that many above, so each run sits in at least about 40 drawn pairs; the
/// draw then widens the line intervals by at most about 15 % (never narrows them), against
/// ≈ 35 % at 10,000 runs for the 20,000 pairs drawn anew for each resample before.
const RESAMPLE_PAIRS: usize = 50_000;
const RESAMPLE_PAIRS_PER_RUN: usize = 20;

fn material_summary(fits: &[&SingleFit], opts: &AggregateOptions, seed: u64) -> MaterialSummary {
    let ok: Vec<&&SingleFit> = fits
        .iter()
        .filter(|f| f.status == FitStatus::Converged)
        .collect();
    let speed: Vec<f64> = ok.iter().map(|f| f.v0_mps.abs()).collect();
    let mu: Vec<f64> = ok.iter().map(|f| f.mu).collect();
    let mu_se: Vec<f64> = ok.iter().map(|f| f.mu_se.unwrap_or(f64::NAN)).collect();
    let t: Vec<f64> = ok.iter().map(|f| f.t_drag_s).collect();
    let fast = |i: usize| speed[i] > opts.fast_min_speed_mps;
    let all: Vec<usize> = (0..ok.len()).collect();
    let (b1, b2) = (&mut Vec::new(), &mut Vec::new());
    let [(ta, tb), (ma, mb)] = theil_sen_many(&speed, [&t, &mu], &all, [b1, b2], POINT_PAIRS);
    let robust_mean = RobustMean::new(&mu, &mu_se);
    let mu_if_fast = kept_table(&mu, fast);
    let point = [
        robust_mean.of(&vec![1; ok.len()]),
        mean_where(&mu, &all, fast),
        ta,
        tb,
        ma,
        mb,
    ];
    // The resamples' slopes from one slope order of the runs' pairs (weighted by how often
    // each run was drawn); a drawn order's own slope may differ a little from the estimate's,
    // so its resamples are moved by that difference (the interval is the estimate's).
    let max_pairs = RESAMPLE_PAIRS.max(RESAMPLE_PAIRS_PER_RUN * ok.len());
    let order = SlopeOrder::new(&speed, [&t, &mu], max_pairs, seed);
    let shift: [f64; 2] = std::array::from_fn(|k| match order.every_pair {
        true => 0.0,
        false => point[3 + 2 * k] - order.slope(k, &vec![1; ok.len()]),
    });
    // The resamples' intercepts, read near the estimate's line where they can be.
    let intercepts = [
        InterceptOrder::new(&speed, &t, point[3]),
        InterceptOrder::new(&speed, &mu, point[5]),
    ];
    // Resamples in groups of SLOPE_LANES, whose slopes share one pass over the slope order.
    let ci = percentile_intervals_in_groups(
        ok.len(),
        opts.bootstrap_resamples,
        seed,
        opts.level,
        SLOPE_LANES,
        |group| {
            let n = ok.len();
            let mut weights = vec![vec![0u16; n]; group.len()];
            for (idx, w) in group.iter().zip(&mut weights) {
                for &i in idx {
                    w[i] = w[i].saturating_add(1);
                }
            }
            let slopes = order.slopes_many(&weights);
            let (mut buf, mut near) = (Vec::new(), Vec::new());
            group
                .iter()
                .zip(&weights)
                .zip(slopes)
                .map(|((idx, w), slopes)| {
                    let mut line = |k: usize, y: &[f64]| {
                        let b = slopes[k] + shift[k];
                        if b.is_nan() {
                            return (f64::NAN, f64::NAN);
                        }
                        let a = intercepts[k]
                            .median((&speed, y), w, idx.len(), b, &mut near)
                            .unwrap_or_else(|| theil_sen_intercept(&speed, y, idx, b, &mut buf));
                        (a, b)
                    };
                    let ((ta, tb), (ma, mb)) = (line(0, &t), line(1, &mu));
                    [
                        robust_mean.of(w),
                        mean_kept(&mu_if_fast, idx),
                        ta,
                        tb,
                        ma,
                        mb,
                    ]
                })
                .collect()
        },
    );
    let est = |k: usize| {
        Estimate::with_interval(point[k], if point[k].is_finite() { ci[k] } else { None })
    };
    let speed_range_mps = (!speed.is_empty()).then(|| {
        [
            speed.iter().copied().fold(f64::INFINITY, f64::min),
            speed.iter().copied().fold(0.0, f64::max),
        ]
    });
    MaterialSummary {
        n_runs: fits.len(),
        n_converged: ok.len(),
        mu_weighted: est(0),
        mu_fast: est(1),
        n_fast: (0..ok.len()).filter(|&i| fast(i)).count(),
        t_vs_v0: DragLine {
            intercept_s: est(2),
            slope_s_per_mps: est(3),
        },
        mu_vs_v0: FrictionLine {
            intercept: est(4),
            slope_per_mps: est(5),
        },
        speed_range_mps,
        left_out: fits
            .iter()
            .filter(|f| f.status != FitStatus::Converged)
            .map(|f| LeftOut {
                run: f.run.clone(),
                status: f.status.to_string(),
                why: match f.suspect.is_empty() {
                    true => format!("the fit ended with {:?}", f.termination),
                    false => f.suspect.join("; "),
                },
            })
            .collect(),
    }
}

/// What the restarts of the single-run fits did, in words for summary.json's notes and the report:
/// how many runs whose first fit was suspect (the signature of a fit that settled in a wrong basin,
/// as pixel-locked tracker positions cause) a restart from other start values recovered, and how
/// many stay suspect and are left out. `None` when every first fit passed its checks.
pub fn restart_note(fits: &[SingleFit]) -> Option<String> {
    let recovered = fits.iter().filter(|f| f.restarted).count();
    let still = fits
        .iter()
        .filter(|f| f.status == FitStatus::Suspect)
        .count();
    let n = recovered + still;
    (n > 0).then(|| {
        format!(
            "{recovered} of {n} single runs whose first fit looked wrong (a parameter at a bound, the switch to rolling after the recording, v0 off the first frames' speed or structured residuals, as pixel-locked tracker positions cause) were recovered by a restart from other start values; {still} stay suspect and are left out of the aggregates"
        )
    })
}

/// FNV-1a of a name: a fixed, platform-independent way to give each material its own stream.
fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}
