//! Starting values of a single-run fit, read off the data: direction from the net displacement,
//! the rolling decay from block velocities late in the run, v0 from the rolling velocity
//! extrapolated to the kick, and μ from how far the early (sliding) frames run ahead of that
//! rolling motion. Medians throughout, so outliers do not matter.

use super::model::{MU, NP, T0, TD, V0, Z0};
use crate::physics::{Groove, G_MPS2};
use crate::stats::median_in_place;

/// Start values [z0, t0, v0, 0, μ, T] for the frames `t_s`, `z_m` (at least 10) of a single run.
pub fn single_start(
    t_s: &[f64],
    z_m: &[f64],
    fps: f64,
    groove: Groove,
    scratch: &mut Vec<f64>,
) -> [f64; NP] {
    let n = t_s.len();
    let ks2 = groove.k * groove.s * groove.s;
    let head = median_of(&z_m[..n.min(5)], scratch);
    let tail = median_of(&z_m[n.saturating_sub(5)..], scratch);
    let dir = if tail >= head { 1.0 } else { -1.0 };
    let t_end = t_s[n - 1].max(1e-9);

    // robust mean velocity of equal blocks of frames, and their mid times
    let nb = (n / 40).clamp(4, 16);
    let mut late: [(f64, f64); 16] = [(0.0, 0.0); 16];
    let mut n_late = 0;
    let mut v_all = [0.0; 16];
    for (b, v_block) in v_all.iter_mut().enumerate().take(nb) {
        let (lo, hi) = (b * n / nb, (b + 1) * n / nb);
        let q = ((hi - lo) / 3).max(1);
        let tf = median_of(&t_s[lo..lo + q], scratch);
        let tl = median_of(&t_s[hi - q..hi], scratch);
        let yf = dir * median_of(&z_m[lo..lo + q], scratch);
        let yl = dir * median_of(&z_m[hi - q..hi], scratch);
        let v = if tl > tf { (yl - yf) / (tl - tf) } else { 0.0 };
        *v_block = v;
        let tb = 0.5 * (tf + tl);
        if tb >= 0.4 * t_end && v > 0.0 {
            late[n_late] = (tb, v.ln());
            n_late += 1;
        }
    }
    // ln v = a − t/Te on the late blocks
    let (mut ln_v0, mut te) = (f64::NAN, f64::NAN);
    if n_late >= 2 {
        let m = n_late as f64;
        let tm = late[..n_late].iter().map(|p| p.0).sum::<f64>() / m;
        let lm = late[..n_late].iter().map(|p| p.1).sum::<f64>() / m;
        let sxy: f64 = late[..n_late].iter().map(|p| (p.0 - tm) * (p.1 - lm)).sum();
        let sxx: f64 = late[..n_late].iter().map(|p| (p.0 - tm).powi(2)).sum();
        let slope = sxy / sxx;
        if slope < 0.0 {
            te = -1.0 / slope;
            ln_v0 = lm - slope * tm;
        }
    }
    if !(te.is_finite() && te > 1e-3) {
        te = (10.0 * t_end).max(1e-3);
        ln_v0 = median_of(&v_all[nb / 2..nb], scratch).max(1e-6).ln();
    }
    let te = te.min(2e3);
    let v1 = ln_v0.exp().min(20.0);
    // offset of the rolling motion extrapolated back to the first frame
    let amp = v1 * te;
    scratch.clear();
    for i in 0..n {
        if t_s[i] >= 0.4 * t_end {
            scratch.push(dir * (z_m[i] - head) - amp * -(-t_s[i] / te).exp_m1());
        }
    }
    let lead = if scratch.is_empty() {
        0.0
    } else {
        median_in_place(scratch)
    };
    let v0 = v1 * (1.0 + ks2) / ks2;
    // sliding runs ahead of the extrapolated rolling by (v0 − v1)·t1/2
    let t1 = (2.0 * lead / (v0 - v1)).clamp(1.0 / fps, 0.5 * t_end);
    let mu = (v1 / (groove.s * groove.k * G_MPS2 * t1)).clamp(0.1, 1.0);
    let mut x = [0.0; NP];
    x[Z0] = head;
    x[T0] = 0.5 / fps;
    x[V0] = dir * v0.max(1e-5);
    x[MU] = mu;
    x[TD] = (te * ks2 / (1.0 + ks2)).clamp(1e-3, 1e3);
    x
}

fn median_of(v: &[f64], scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend_from_slice(v);
    median_in_place(scratch)
}
