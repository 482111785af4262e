//! Where a model misses: residuals pooled by phase, speed, position, direction and material, and
//! the per-run runs test and lag-1 autocorrelation combined over runs.

use super::sim::Motion;
use crate::stats::dist::normal_sf;
use std::collections::BTreeMap;

/// Residuals of one run with what the model says at each kept sample.
pub struct RunResiduals {
    pub material: String,
    /// +1 or −1.
    pub direction: f64,
    pub sigma_m: f64,
    pub residual_m: Vec<f64>,
    pub speed_mps: Vec<f64>,
    pub z_m: Vec<f64>,
    pub phase: Vec<Motion>,
}

pub use crate::artifacts::diagnosis::{Bin, Structure};

#[derive(Default)]
struct Acc {
    per_run: BTreeMap<usize, (f64, usize)>,
    n: usize,
    s: f64,
    ss: f64,
    ssn: f64,
}

impl Acc {
    fn add(&mut self, run: usize, r: f64, sigma: f64) {
        let e = self.per_run.entry(run).or_insert((0.0, 0));
        e.0 += r;
        e.1 += 1;
        self.n += 1;
        self.s += r;
        self.ss += r * r;
        self.ssn += (r / sigma).powi(2);
    }
    fn bin(&self) -> Bin {
        let n = self.n.max(1) as f64;
        let mean = self.s / n;
        // standard error of the mean from the spread of per-run means (frames are not independent)
        let means: Vec<f64> = self.per_run.values().map(|(s, c)| s / *c as f64).collect();
        let k = means.len() as f64;
        let z = if means.len() > 1 {
            let mm = means.iter().sum::<f64>() / k;
            let sd = (means.iter().map(|m| (m - mm).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
            if sd > 0.0 {
                mm / (sd / k.sqrt())
            } else {
                0.0
            }
        } else {
            0.0
        };
        Bin {
            n: self.n,
            rms_m: (self.ss / n).sqrt(),
            mean_m: mean,
            mean_z: z,
            rms_over_noise: (self.ssn / n).sqrt(),
        }
    }
}

fn runs_test_z(r: &[f64]) -> Option<f64> {
    let signs: Vec<bool> = r.iter().filter(|x| **x != 0.0).map(|x| *x > 0.0).collect();
    let n1 = signs.iter().filter(|s| **s).count() as f64;
    let n2 = signs.len() as f64 - n1;
    if n1 < 2.0 || n2 < 2.0 {
        return None;
    }
    let runs = 1 + signs.windows(2).filter(|w| w[0] != w[1]).count();
    let n = n1 + n2;
    let mu = 2.0 * n1 * n2 / n + 1.0;
    let var = 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0));
    (var > 0.0).then(|| (runs as f64 - mu) / var.sqrt())
}

fn lag1(r: &[f64]) -> Option<f64> {
    if r.len() < 3 {
        return None;
    }
    let m = r.iter().sum::<f64>() / r.len() as f64;
    let den: f64 = r.iter().map(|x| (x - m).powi(2)).sum();
    let num: f64 = r.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum();
    (den > 0.0).then(|| num / den)
}

/// Lag-1 autocorrelation of one residual series (0 when undefined).
pub fn lag1_autocorrelation(r: &[f64]) -> f64 {
    lag1(r).unwrap_or(0.0)
}

fn edges_label(lo: f64, hi: f64, unit: &str, scale: f64) -> String {
    format!("{:.1}..{:.1} {unit}", lo * scale, hi * scale)
}

/// Pool the residuals of every run. Speed bins are quintiles of |v|, position bins 8 equal widths.
pub fn structure(runs: &[RunResiduals]) -> Structure {
    let mut speeds: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.speed_mps.iter().map(|v| v.abs()))
        .collect();
    speeds.sort_by(f64::total_cmp);
    let q = |p: f64| -> f64 {
        if speeds.is_empty() {
            0.0
        } else {
            crate::stats::quantile_nearest(&speeds, p)
        }
    };
    let sedges: Vec<f64> = (0..=5).map(|i| q(i as f64 / 5.0)).collect();
    let zmin = runs
        .iter()
        .flat_map(|r| r.z_m.iter().copied())
        .fold(f64::INFINITY, f64::min);
    let zmax = runs
        .iter()
        .flat_map(|r| r.z_m.iter().copied())
        .fold(f64::NEG_INFINITY, f64::max);
    let zw = ((zmax - zmin) / 8.0).max(1e-12);
    let mut phase: BTreeMap<String, Acc> = BTreeMap::new();
    let mut speed: BTreeMap<String, Acc> = BTreeMap::new();
    let mut pos: BTreeMap<String, Acc> = BTreeMap::new();
    let mut dir: BTreeMap<String, Acc> = BTreeMap::new();
    let mut mat: BTreeMap<String, Acc> = BTreeMap::new();
    let (mut zsum, mut zcount) = (0.0, 0usize);
    let (mut rho_sum, mut rho_z, mut rho_count) = (0.0, 0.0, 0usize);
    for (ri, run) in runs.iter().enumerate() {
        for i in 0..run.residual_m.len() {
            let r = run.residual_m[i];
            let s = run.sigma_m;
            let ph = match run.phase[i] {
                Motion::Sliding => "sliding",
                Motion::Rolling => "rolling",
                Motion::Rest => "rest",
            };
            phase.entry(ph.into()).or_default().add(ri, r, s);
            let v = run.speed_mps[i].abs();
            let b = (1..5).filter(|k| v >= sedges[*k]).count();
            let label = format!(
                "{b}: {}",
                edges_label(sedges[b], sedges[b + 1], "mm/s", 1e3)
            );
            speed.entry(label).or_default().add(ri, r, s);
            let pb = (((run.z_m[i] - zmin) / zw) as usize).min(7);
            let lo = zmin + pb as f64 * zw;
            let label = format!("{pb}: {}", edges_label(lo, lo + zw, "mm", 1e3));
            pos.entry(label).or_default().add(ri, r, s);
            let d = if run.direction > 0.0 { "+z" } else { "-z" };
            dir.entry(d.into()).or_default().add(ri, r, s);
            mat.entry(run.material.clone()).or_default().add(ri, r, s);
        }
        if let Some(z) = runs_test_z(&run.residual_m) {
            zsum += z;
            zcount += 1;
        }
        if let Some(rho) = lag1(&run.residual_m) {
            rho_sum += rho;
            rho_z += rho * (run.residual_m.len() as f64).sqrt();
            rho_count += 1;
        }
    }
    let done = |m: BTreeMap<String, Acc>| m.into_iter().map(|(k, a)| (k, a.bin())).collect();
    let runs_test_z = if zcount > 0 {
        zsum / (zcount as f64).sqrt()
    } else {
        0.0
    };
    let lag1_z = if rho_count > 0 {
        rho_z / (rho_count as f64).sqrt()
    } else {
        0.0
    };
    Structure {
        by_phase: done(phase),
        by_speed: done(speed),
        by_position: done(pos),
        by_direction: done(dir),
        by_material: done(mat),
        runs_test_z,
        runs_test_p: normal_sf(-runs_test_z).min(1.0),
        lag1_autocorrelation: if rho_count > 0 {
            rho_sum / rho_count as f64
        } else {
            0.0
        },
        lag1_z,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_test_sees_a_smooth_pattern() {
        let alternating: Vec<f64> = (0..100)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let blocks: Vec<f64> = (0..100)
            .map(|i| if (i / 25) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert!(runs_test_z(&alternating).unwrap() > 5.0);
        assert!(runs_test_z(&blocks).unwrap() < -5.0);
        assert!(lag1(&blocks).unwrap() > 0.9);
    }
}
