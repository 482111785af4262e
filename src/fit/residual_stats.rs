//! Pooled statistics of re-simulation residuals, grouped by phase, speed, position, direction,
//! material, experiment and run: what is left for the discovery to explain; the collision runs'
//! frames also by phase and by time since the last impact. Outlier frames are left out.
//!
//! Per group: count, mean, RMS, lag-1 autocorrelation (about zero, over consecutive frames of the
//! same run in the same group) and the Wald–Wolfowitz runs test of the residual signs (runs summed
//! over the runs' stretches, `z = (R − E[R])/sd[R]`; strongly negative z = long same-sign stretches,
//! i.e. structure the model misses).

use super::residuals::RunResiduals;
use crate::artifacts::residuals::Phase;
use crate::recording::Experiment;
use std::collections::BTreeMap;

/// Upper edges (m/s) of the speed bins of |v_fit|; the last bin is open.
pub const SPEED_EDGES_MPS: [f64; 7] = [0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2];
/// Number of equal-width position bins over the pooled range of z_obs.
pub const POSITION_BINS: usize = 10;

pub use crate::artifacts::comparison::{Bin, Comparison, GroupStats, PairResiduals};

/// Upper edges (s) of the bins of time since the last impact (collision runs); the last is open.
pub const SINCE_IMPACT_EDGES_S: [f64; 3] = [1e-3, 5e-3, 20e-3];

/// The bin of time since the last impact at `t_s` (0 before the first impact, then 1 + the
/// index of the edge bin), for impact times `impacts_s` in time order.
pub fn since_impact_bin(t_s: f64, impacts_s: &[f64]) -> usize {
    match impacts_s.iter().rev().find(|&&ti| ti <= t_s) {
        None => 0,
        Some(ti) => {
            1 + SINCE_IMPACT_EDGES_S
                .iter()
                .position(|&e| t_s - ti < e)
                .unwrap_or(SINCE_IMPACT_EDGES_S.len())
        }
    }
}

/// Running sums of one group; `last` marks where the current stretch of a run stopped.
#[derive(Default, Clone)]
struct Acc {
    n: usize,
    sum: f64,
    sum_sq: f64,
    lag_num: f64,
    lag_den: f64,
    runs: f64,
    runs_mean: f64,
    runs_var: f64,
}

impl Acc {
    fn stats(&self) -> GroupStats {
        if self.n == 0 {
            return GroupStats::default();
        }
        let n = self.n as f64;
        GroupStats {
            n: self.n,
            mean_m: self.sum / n,
            rms_m: (self.sum_sq / n).sqrt(),
            lag1_autocorr: (self.lag_den > 0.0).then(|| self.lag_num / self.lag_den),
            runs_test_z: (self.runs_var > 0.0)
                .then(|| (self.runs - self.runs_mean) / self.runs_var.sqrt()),
        }
    }

    /// Add one stretch: consecutive included frames of one run in this group.
    fn add_stretch(&mut self, r: &[f64]) {
        let (mut plus, mut minus, mut runs, mut prev) = (0.0, 0.0, 0.0, 0.0f64);
        for (i, &x) in r.iter().enumerate() {
            self.n += 1;
            self.sum += x;
            self.sum_sq += x * x;
            if i + 1 < r.len() {
                self.lag_num += x * r[i + 1];
                self.lag_den += x * x;
            }
            if x != 0.0 {
                if x > 0.0 {
                    plus += 1.0
                } else {
                    minus += 1.0
                }
                if prev == 0.0 || x.signum() != prev.signum() {
                    runs += 1.0;
                }
                prev = x;
            }
        }
        let m = plus + minus;
        if plus > 0.0 && minus > 0.0 && m > 1.0 {
            self.runs += runs;
            self.runs_mean += 1.0 + 2.0 * plus * minus / m;
            self.runs_var += 2.0 * plus * minus * (2.0 * plus * minus - m) / (m * m * (m - 1.0));
        }
    }
}

/// Feed a run's frames into the accumulator of each frame's group (`key` gives it; None skips the
/// frame), cutting stretches where the group or the particle changes or an outlier intervenes.
fn feed<K: Ord + Clone>(
    accs: &mut BTreeMap<K, Acc>,
    res: &RunResiduals,
    key: impl Fn(usize) -> Option<K>,
    buf: &mut Vec<f64>,
) {
    let mut cur: Option<K> = None;
    buf.clear();
    for i in 0..res.residual_m.len() {
        let k = if res.outlier[i] { None } else { key(i) };
        let new_particle = i > 0 && res.particle[i] != res.particle[i - 1];
        if k != cur || new_particle {
            if let Some(c) = cur.take() {
                accs.entry(c).or_default().add_stretch(buf);
            }
            buf.clear();
            cur = k;
        }
        if cur.is_some() {
            buf.push(res.residual_m[i]);
        }
    }
    if let Some(c) = cur {
        accs.entry(c).or_default().add_stretch(buf);
    }
}

fn finish<K: Ord>(m: BTreeMap<K, Acc>) -> BTreeMap<K, GroupStats> {
    m.into_iter().map(|(k, a)| (k, a.stats())).collect()
}

fn speed_bin(v: f64) -> usize {
    SPEED_EDGES_MPS
        .iter()
        .position(|&e| v.abs() < e)
        .unwrap_or(SPEED_EDGES_MPS.len())
}

/// The runs whose residuals are usable (status ok), sorted by id, and the others with their status.
fn usable_runs(all: &[RunResiduals]) -> (Vec<&RunResiduals>, BTreeMap<String, String>) {
    let mut runs: Vec<&RunResiduals> = all.iter().collect();
    runs.sort_by(|a, b| a.run.cmp(&b.run));
    let mut skipped = BTreeMap::new();
    let used: Vec<&RunResiduals> = runs
        .iter()
        .copied()
        .filter(|r| {
            let ok = r.status == "ok";
            if !ok {
                skipped.insert(r.run.clone(), r.status.clone());
            }
            ok
        })
        .collect();
    (used, skipped)
}

/// The lowest and highest observed position over the frames that are not outliers.
fn position_range(used: &[&RunResiduals]) -> (f64, f64) {
    let (mut z_lo, mut z_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for r in used {
        for (i, &z) in r.z_obs_m.iter().enumerate() {
            if !r.outlier[i] {
                z_lo = z_lo.min(z);
                z_hi = z_hi.max(z);
            }
        }
    }
    (z_lo, z_hi)
}

/// The collision runs' pools by phase and by time since the last impact (bin 0: before the first).
fn pair_residuals(
    n_pair_runs: usize,
    pair_phase: BTreeMap<Phase, Acc>,
    pair_time: BTreeMap<usize, Acc>,
) -> Option<PairResiduals> {
    (n_pair_runs > 0).then(|| PairResiduals {
        n_runs: n_pair_runs,
        by_phase: finish(pair_phase),
        before_first_impact: pair_time.get(&0).map(Acc::stats).unwrap_or_default(),
        by_time_since_impact: pair_time
            .iter()
            .filter(|(b, _)| **b > 0)
            .map(|(&b, a)| Bin {
                lo: if b == 1 {
                    0.0
                } else {
                    SINCE_IMPACT_EDGES_S[b - 2]
                },
                hi: SINCE_IMPACT_EDGES_S.get(b - 1).copied(),
                stats: a.stats(),
            })
            .collect(),
    })
}

/// Pool the residuals of many runs (any order; runs are taken sorted by id).
pub fn compare(all: &[RunResiduals]) -> Comparison {
    let (used, skipped) = usable_runs(all);
    let (z_lo, z_hi) = position_range(&used);
    let width = (z_hi - z_lo) / POSITION_BINS as f64;
    let pos_bin = |z: f64| {
        ((z - z_lo) / width)
            .floor()
            .clamp(0.0, (POSITION_BINS - 1) as f64) as usize
    };

    let mut overall = BTreeMap::new();
    let mut by_phase = BTreeMap::new();
    let mut by_speed = BTreeMap::new();
    let mut by_position = BTreeMap::new();
    let mut by_direction = BTreeMap::new();
    let mut by_material = BTreeMap::new();
    let mut by_experiment = BTreeMap::new();
    let mut by_run = BTreeMap::new();
    let (mut pair_phase, mut pair_time) = (BTreeMap::new(), BTreeMap::new());
    let mut n_pair_runs = 0;
    let mut buf = Vec::new();
    let (mut n_frames, mut n_outliers) = (0, 0);
    for r in &used {
        n_frames += r.residual_m.len();
        n_outliers += r.outlier.iter().filter(|&&o| o).count();
        let dir = if r.direction >= 0 { "+z" } else { "-z" };
        feed(&mut overall, r, |_| Some(()), &mut buf);
        feed(&mut by_phase, r, |i| Some(r.phase[i]), &mut buf);
        feed(
            &mut by_speed,
            r,
            |i| Some(speed_bin(r.v_fit_mps[i])),
            &mut buf,
        );
        if width > 0.0 {
            feed(
                &mut by_position,
                r,
                |i| Some(pos_bin(r.z_obs_m[i])),
                &mut buf,
            );
        }
        feed(&mut by_direction, r, |_| Some(dir.to_string()), &mut buf);
        feed(&mut by_material, r, |_| Some(r.material.clone()), &mut buf);
        let experiment = match r.experiment {
            Experiment::Single => "single",
            Experiment::Collision => "collision",
        };
        feed(
            &mut by_experiment,
            r,
            |_| Some(experiment.to_string()),
            &mut buf,
        );
        feed(&mut by_run, r, |_| Some(r.run.clone()), &mut buf);
        if r.experiment == Experiment::Collision {
            n_pair_runs += 1;
            feed(&mut pair_phase, r, |i| Some(r.phase[i]), &mut buf);
            feed(
                &mut pair_time,
                r,
                |i| Some(since_impact_bin(r.t_s[i], &r.impacts_s)),
                &mut buf,
            );
        }
    }
    let pairs = pair_residuals(n_pair_runs, pair_phase, pair_time);
    Comparison {
        n_runs: used.len(),
        skipped,
        n_frames,
        n_outliers,
        overall: overall.get(&()).map(Acc::stats).unwrap_or_default(),
        by_phase: finish(by_phase),
        by_speed: by_speed
            .into_iter()
            .map(|(b, a)| Bin {
                lo: if b == 0 { 0.0 } else { SPEED_EDGES_MPS[b - 1] },
                hi: SPEED_EDGES_MPS.get(b).copied(),
                stats: a.stats(),
            })
            .collect(),
        by_position: by_position
            .into_iter()
            .map(|(b, a)| Bin {
                lo: z_lo + b as f64 * width,
                hi: Some(z_lo + (b + 1) as f64 * width),
                stats: a.stats(),
            })
            .collect(),
        by_direction: finish(by_direction),
        by_material: finish(by_material),
        by_experiment: finish(by_experiment),
        by_run: finish(by_run),
        pairs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::residuals::Phase;

    fn run(id: &str, r: Vec<f64>) -> RunResiduals {
        let n = r.len();
        RunResiduals {
            run: id.into(),
            material: "316".into(),
            experiment: Experiment::Single,
            direction: 1,
            status: "ok".into(),
            particle: vec![0; n],
            t_s: (0..n).map(|i| i as f64 * 1e-4).collect(),
            z_obs_m: (0..n).map(|i| i as f64 * 1e-6).collect(),
            z_fit_m: vec![0.0; n],
            residual_m: r,
            v_fit_mps: vec![0.01; n],
            phase: vec![Phase::Rolling; n],
            outlier: vec![false; n],
            impacts_s: vec![],
        }
    }

    #[test]
    fn alternating_signs_give_negative_autocorrelation_and_many_runs() {
        let alt: Vec<f64> = (0..200)
            .map(|i| if i % 2 == 0 { 1e-6 } else { -1e-6 })
            .collect();
        let c = compare(&[run("a", alt)]);
        let s = c.overall;
        assert_eq!(s.n, 200);
        assert!((s.rms_m - 1e-6).abs() < 1e-15 && s.mean_m.abs() < 1e-15);
        assert!((s.lag1_autocorr.unwrap() + 1.0).abs() < 0.01);
        // 200 runs where ~101 are expected: z ≈ +14
        assert!(s.runs_test_z.unwrap() > 10.0);
    }

    #[test]
    fn a_smooth_bump_gives_positive_autocorrelation_and_few_runs() {
        let bump: Vec<f64> = (0..200).map(|i| 1e-6 * (i as f64 * 0.05).sin()).collect();
        let c = compare(&[run("b", bump)]);
        assert!(c.overall.lag1_autocorr.unwrap() > 0.95);
        assert!(c.overall.runs_test_z.unwrap() < -10.0);
        assert_eq!(c.by_position.len(), POSITION_BINS);
        assert_eq!(c.by_speed.len(), 1);
        assert_eq!(c.by_speed[0].lo, 0.01);
    }

    #[test]
    fn collision_frames_are_binned_by_time_since_the_last_impact() {
        // frames every 0.1 ms from t = 0; impacts at 2 ms and 10 ms; residuals mark the bin
        // they belong in, so each bin's mean says which frames it got
        let mut pair = run("c", vec![0.0; 300]);
        pair.experiment = Experiment::Collision;
        pair.impacts_s = vec![2e-3, 10e-3];
        let want = |t: f64| -> f64 {
            let since = if t < 2e-3 {
                return 1.0;
            } else if t < 10e-3 {
                t - 2e-3
            } else {
                t - 10e-3
            };
            if since < 1e-3 {
                2.0
            } else if since < 5e-3 {
                3.0
            } else if since < 20e-3 {
                4.0
            } else {
                5.0
            }
        };
        pair.residual_m = pair.t_s.iter().map(|&t| want(t + 1e-9) * 1e-6).collect();
        pair.t_s.iter_mut().for_each(|t| *t += 1e-9);
        pair.phase[..100].fill(Phase::Sliding);
        let c = compare(&[run("s", vec![1e-6; 50]), pair]);
        let p = c.pairs.expect("a collision run gives pair residuals");
        assert_eq!(p.n_runs, 1);
        assert_eq!(p.before_first_impact.n, 20);
        assert!((p.before_first_impact.mean_m - 1e-6).abs() < 1e-15);
        // [0, 1 ms): 10 frames after each impact; [1, 5 ms): 40 + 40; [5, 20 ms): 30 + 150
        let bins: Vec<(f64, Option<f64>, usize, f64)> = p
            .by_time_since_impact
            .iter()
            .map(|b| (b.lo, b.hi, b.stats.n, b.stats.mean_m))
            .collect();
        assert_eq!(
            bins.iter().map(|b| (b.0, b.1, b.2)).collect::<Vec<_>>(),
            vec![
                (0.0, Some(1e-3), 20),
                (1e-3, Some(5e-3), 80),
                (5e-3, Some(20e-3), 180)
            ]
        );
        for (k, b) in bins.iter().enumerate() {
            assert!(
                (b.3 - (k as f64 + 2.0) * 1e-6).abs() < 1e-15,
                "bin {k}: {b:?}"
            );
        }
        assert_eq!(p.by_phase[&Phase::Sliding].n, 100);
        assert_eq!(p.by_phase[&Phase::Rolling].n, 200);
        // a dataset of single runs has none
        assert!(compare(&[run("s", vec![1e-6; 50])]).pairs.is_none());
    }
}
