//! Fit quality as data: a converged single-run fit whose parameters sit at a bound or have no
//! standard error, whose switch to rolling falls outside the recording, whose v0 is far from the
//! speed of the first frames, or whose residuals carry structure far above the run's noise is
//! `suspect`, with the reasons.

use super::model::{Prepared, MU, NP, T0, TD, V0};
use crate::lsq::dense::solve_spd;
use crate::physics::Groove;
use crate::stats::{ols_line, upper_median, Line, MAD_TO_SIGMA};

/// v0 further than this fraction from the first frames' speed is suspect.
const V0_TOLERANCE: f64 = 0.3;
/// Frames averaged to look for structure in the residuals.
const WINDOW: usize = 15;
/// Structure: the windowed mean residual's RMS this many times what white noise of the run's
/// frame-to-frame scatter would give. Calibrated on a null (tests/trackers.rs,
/// `the_structure_threshold_flags_under_one_percent_of_clean_runs`): of the right fits of 1500
/// clean synthesized runs (|v0| 5–100 mm/s), those with white noise of 1 or 3 µm stay below 2;
/// those with pixel-locked positions (1–4 µm, correlated from frame to frame, which the
/// frame-to-frame scatter understates) have a median of 1.4 and a tail: 16 of 467 above 20, 5
/// above 25, 1 above 30, none above 35. At 30 the false-suspect rate is 0.2 % with locked errors
/// and 0 with white noise (the bar: at most 1 % with each). Wrong-basin fits of pixel-locked slow
/// runs give 25–40; they also sit at a bound or switch to rolling after the recording.
pub const STRUCTURE_FACTOR: f64 = 30.0;

/// The reasons a fit of frames `t_s`, `z_m` with parameters `x` and standard errors `se` is
/// suspect (empty: none). `lo`, `hi` are the bounds the fit had.
pub fn suspect_reasons(
    t_s: &[f64],
    z_m: &[f64],
    x: &[f64; NP],
    se: &[Option<f64>; NP],
    lo: &[f64; NP],
    hi: &[f64; NP],
    groove: Groove,
) -> Vec<String> {
    let mut why = Vec::new();
    let near = |v: f64, b: f64| b.is_finite() && (v - b).abs() <= 1e-3 * b.abs().max(1e-6);
    let named = [(MU, "μ"), (TD, "T"), (V0, "v0")];
    for (i, name) in named {
        if near(x[i], lo[i]) || near(x[i], hi[i]) {
            why.push(format!("{name} = {:.4e} is at its bound", x[i]));
        }
    }
    // A parameter the frames do not determine (a singular curvature, as near a bound) has no
    // standard error; its value is whatever the iterations ended at.
    let lost: Vec<&str> = named
        .iter()
        .filter(|(i, _)| !se[*i].is_some_and(|s| s.is_finite()))
        .map(|(_, name)| *name)
        .collect();
    if !lost.is_empty() {
        why.push(format!(
            "no standard error for {}: these frames do not determine {}",
            lost.join(", "),
            if lost.len() == 1 { "it" } else { "them" }
        ));
    }
    let Some(m) = Prepared::new(x, groove) else {
        why.push("the fitted model cannot be evaluated".into());
        return why;
    };
    let n = t_s.len().min(z_m.len());
    if n < 3 {
        return why;
    }
    let t_end = t_s[n - 1] + x[T0];
    if !(m.t1_s.is_finite() && m.t1_s <= t_end) {
        why.push(format!(
            "the switch to rolling at {:.4} s falls after the recording ends ({t_end:.4} s)",
            m.t1_s
        ));
    }
    let r: Vec<f64> = (0..n).map(|i| z_m[i] - m.eval(t_s[i], 0.0)).collect();
    // The first frames' speed against the fitted model's over the same frames: the slope of the
    // residuals there, which a fit in the right basin keeps within its error.
    let w = (n / 10).clamp(10, 40).min(n);
    // (at least 4 frames, so that the slope's error has 2 degrees of freedom)
    let line = (w >= 4).then(|| ols_line(&t_s[..w], &r[..w])).flatten();
    if let Some(Line {
        slope,
        slope_se: se,
        ..
    }) = line
    {
        let model_speed = (m.eval(t_s[w - 1], 0.0) - m.eval(t_s[0], 0.0)) / (t_s[w - 1] - t_s[0]);
        if slope.abs() > V0_TOLERANCE * model_speed.abs() + 3.0 * se {
            why.push(format!(
                "v0 = {:.4} m/s is far from the first frames' speed: the model runs at {model_speed:.4} m/s over the first {w} frames, the data at {:.4} ± {se:.4} m/s",
                x[V0],
                model_speed + slope
            ));
        }
    }
    if let Some(ratio) = structure(&r) {
        if ratio > STRUCTURE_FACTOR {
            why.push(format!(
                "the residuals carry structure {ratio:.0} times the run's frame-to-frame noise"
            ));
        }
    }
    why
}

/// The residual-structure ratio of a fit (what [`STRUCTURE_FACTOR`] bounds): the RMS of the
/// residuals' windowed means over what white noise of their frame-to-frame scatter would give;
/// `None` for short runs, no scatter, or a model that cannot be evaluated.
pub fn structure_ratio(t_s: &[f64], z_m: &[f64], x: &[f64; NP], groove: Groove) -> Option<f64> {
    let m = Prepared::new(x, groove)?;
    let n = t_s.len().min(z_m.len());
    let r: Vec<f64> = (0..n).map(|i| z_m[i] - m.eval(t_s[i], 0.0)).collect();
    structure(&r)
}

/// The speed at the first frame from a quadratic through the first frames (a tenth of the run,
/// 10 to 40 frames), fitted by least squares; `None` if too few frames.
pub fn early_speed(t_s: &[f64], z_m: &[f64]) -> Option<f64> {
    early_speed_se(t_s, z_m).map(|(v, _)| v)
}

/// [`early_speed`] and its standard error from the quadratic's residuals.
pub fn early_speed_se(t_s: &[f64], z_m: &[f64]) -> Option<(f64, f64)> {
    let n = (t_s.len() / 10).clamp(10, 40).min(t_s.len());
    if n < 6 {
        return None;
    }
    let t0 = t_s[0];
    // normal equations of z = a + b τ + c τ²
    let mut s = [[0.0; 3]; 3];
    let mut y = [0.0; 3];
    for i in 0..n {
        let tau = t_s[i] - t0;
        let f = [1.0, tau, tau * tau];
        for a in 0..3 {
            y[a] += f[a] * z_m[i];
            for b in 0..3 {
                s[a][b] += f[a] * f[b];
            }
        }
    }
    let s: Vec<f64> = s.iter().flatten().copied().collect();
    let sol = solve_spd(&s, 3, &y)?;
    let rss: f64 = (0..n)
        .map(|i| {
            let tau = t_s[i] - t0;
            (z_m[i] - sol[0] - sol[1] * tau - sol[2] * tau * tau).powi(2)
        })
        .sum();
    let inv_bb = solve_spd(&s, 3, &[0.0, 1.0, 0.0])?[1];
    let se = (rss / (n - 3) as f64 * inv_bb.max(0.0)).sqrt();
    (sol[1].is_finite() && se.is_finite()).then_some((sol[1], se))
}

/// RMS of the residuals' windowed means over what white noise with the residuals' frame-to-frame
/// scatter (1.4826·MAD of first differences / √2) would give; `None` for short runs or no scatter.
fn structure(r: &[f64]) -> Option<f64> {
    if r.len() < 3 * WINDOW {
        return None;
    }
    let mut d: Vec<f64> = r.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let sigma = MAD_TO_SIGMA * upper_median(&mut d) / 2f64.sqrt();
    let means: Vec<f64> = r
        .chunks_exact(WINDOW)
        .map(|c| c.iter().sum::<f64>() / WINDOW as f64)
        .collect();
    let rms = (means.iter().map(|m| m * m).sum::<f64>() / means.len() as f64).sqrt();
    (sigma > 0.0).then(|| rms / (sigma / (WINDOW as f64).sqrt()))
}
