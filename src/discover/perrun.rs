//! Per-run fits: each run alone with its own μ and T (extra terms held at given values), which
//! measure the run's noise, flag its tracking outliers and give the drift of fitted T and μ.

use super::candidate::predict;
use super::candidate::{ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::joint::{fit_joint, FitControl, USUAL_DAMPING};
use super::noise_model::Slow;
use super::slow_noise::Series;
use rayon::prelude::*;

/// One run's own fit.
#[derive(Clone, Debug)]
pub struct PerRunFit {
    pub mu: f64,
    pub t_s: f64,
    pub local: [f64; N_LOCAL],
    pub rms_m: f64,
    pub converged: bool,
}

/// Starting values of z0, t0, v0 from the first frames: a parabola through the first ~20 samples.
pub fn local_start(run: &RunData) -> [f64; N_LOCAL] {
    let n = run.t_s.len().min(20);
    let t = &run.t_s[..n];
    let z = &run.z_m[..n];
    // least squares z = a + b t + c t² (normal equations, centred for conditioning)
    let tm = t.iter().sum::<f64>() / n as f64;
    let mut m = [0.0; 9];
    let mut rhs = [0.0; 3];
    for (ti, zi) in t.iter().zip(z) {
        let u = ti - tm;
        let phi = [1.0, u, u * u];
        for a in 0..3 {
            for b in 0..3 {
                m[a * 3 + b] += phi[a] * phi[b];
            }
            rhs[a] += phi[a] * zi;
        }
    }
    let t0 = 0.5 / run.fps.max(1.0);
    let Some(l) = crate::lsq::dense::cholesky_jittered(&m, 3) else {
        // no frames: nothing to start from but the first sample, if any
        return [run.z_m.first().copied().unwrap_or(0.0), t0, 1e-6];
    };
    crate::lsq::dense::chol_solve(&l, 3, &mut rhs);
    // value and slope at t = −t0 (the kick)
    let u = -t0 - tm;
    let v0 = rhs[1] + 2.0 * rhs[2] * u;
    let z0 = rhs[0] + rhs[1] * u + rhs[2] * u * u;
    [z0, t0, if v0.abs() > 1e-6 { v0 } else { 1e-6 }]
}

/// A one-material spec holding `base`'s extra terms fixed at `extra_values`.
fn single_spec(
    base: &Spec,
    base_params: &[ParamInfo],
    extra_values: &[f64],
) -> (Spec, Vec<ParamInfo>) {
    let spec = Spec {
        n_materials: 1,
        ..base.clone()
    };
    let mut params = vec![
        base_params[0].clone(),
        base_params[base.n_materials].clone(),
    ];
    let off = 2 * base.n_materials;
    for (i, p) in base_params[off..].iter().enumerate() {
        let mut p = p.clone();
        p.start = extra_values[i];
        p.lo = extra_values[i];
        p.hi = extra_values[i];
        params.push(p);
    }
    (spec, params)
}

/// Fit every run alone (μ and T free, extras fixed), from `starts` (μ, T, locals) when given.
pub fn fit_each_run(
    runs: &[RunData],
    base: &Spec,
    base_params: &[ParamInfo],
    extra_values: &[f64],
    starts: Option<&[PerRunFit]>,
) -> Vec<PerRunFit> {
    let (spec, params) = single_spec(base, base_params, extra_values);
    runs.par_iter()
        .enumerate()
        .map(|(i, run)| {
            let mut r = run.clone();
            r.material = 0;
            let (mu, t, l) = match starts {
                Some(s) => (s[i].mu, s[i].t_s, s[i].local),
                None => (0.3, 0.08, local_start(run)),
            };
            let mut g = vec![mu, t];
            g.extend_from_slice(extra_values);
            let ctl = FitControl {
                max_iter: 60,
                free_global: true,
                covariance: true,
                damping: USUAL_DAMPING,
            };
            let f = fit_joint(&spec, &params, std::slice::from_ref(&r), &g, &[l], ctl);
            let n = r.n_used().max(1) as f64;
            PerRunFit {
                mu: f.global[0],
                t_s: f.global[1],
                local: f.local[0],
                rms_m: (f.chi2 / n).sqrt() * r.sigma_m,
                converged: f.converged,
            }
        })
        .collect()
}

/// Residuals (observed − fitted) of a per-run fit at every sample.
pub fn residuals(
    run: &RunData,
    base: &Spec,
    base_params: &[ParamInfo],
    extra_values: &[f64],
    fit: &PerRunFit,
) -> Vec<f64> {
    let (spec, _) = single_spec(base, base_params, extra_values);
    let mut r = run.clone();
    r.material = 0;
    let mut g = vec![fit.mu, fit.t_s];
    g.extend_from_slice(extra_values);
    let mut z = vec![0.0; run.t_s.len()];
    predict(&spec, &g, &fit.local, &r, &mut z);
    run.z_m.iter().zip(&z).map(|(a, b)| a - b).collect()
}

/// Measure each run's noise and flag its outliers from its baseline fit, twice (`noise::measure`:
/// what a local cubic leaves of the residuals, so a slow misfit of the baseline is not noise),
/// then the dataset's noise growing with speed (`blur.rs`, returned when seen) and slow drift.
pub fn measure_noise(
    runs: &mut [RunData],
    base: &Spec,
    base_params: &[ParamInfo],
) -> (Vec<PerRunFit>, Option<super::blur::Blur>) {
    let mut fits = fit_each_run(runs, base, base_params, &[], None);
    let mut noises = Vec::new();
    for pass in 0..2 {
        noises = runs
            .par_iter_mut()
            .zip(&fits)
            .map(|(run, fit)| {
                let res = residuals(run, base, base_params, &[], fit);
                let noise = super::noise::measure(&run.t_s, &res, &mut run.keep);
                (run.sigma_m, run.fast) = (noise.sigma_m, noise.fast);
                noise
            })
            .collect();
        if pass == 0 {
            fits = fit_each_run(runs, base, base_params, &[], Some(&fits));
        }
    }
    let mixed = super::noise::mixed_wanted(&noises);
    for (run, noise) in runs.iter_mut().zip(&noises) {
        (run.sigma_m, run.fast) = noise.taken(mixed);
    }
    let res: Vec<Vec<f64>> = runs
        .par_iter()
        .zip(&fits)
        .map(|(run, fit)| residuals(run, base, base_params, &[], fit))
        .collect();
    let blur = super::blur::measure(runs, &res);
    let slow = slow_of(runs, base, base_params, &[], &fits);
    runs.iter_mut().for_each(|r| r.slow = slow);
    (fits, blur)
}

/// The dataset's slow tracking noise read from each run's own fit under a joint model
/// (`fits_under`).
pub fn slow_noise_under(
    runs: &[RunData],
    spec: &Spec,
    params: &[ParamInfo],
    global: &[f64],
    local: &[[f64; N_LOCAL]],
) -> Slow {
    let fits = fits_under(runs, spec, params, global, local);
    slow_of(runs, spec, params, &global[2 * spec.n_materials..], &fits)
}

/// Each run's own fit under a joint model: `spec` with its extra terms held at `global`'s
/// values, each run's μ and T started from its material's and its z0, t0, v0 from `local`.
pub fn fits_under(
    runs: &[RunData],
    spec: &Spec,
    params: &[ParamInfo],
    global: &[f64],
    local: &[[f64; N_LOCAL]],
) -> Vec<PerRunFit> {
    let nm = spec.n_materials;
    let starts: Vec<PerRunFit> = runs
        .iter()
        .zip(local)
        .map(|(r, l)| PerRunFit {
            mu: global[r.material],
            t_s: global[nm + r.material],
            local: *l,
            rms_m: 0.0,
            converged: true,
        })
        .collect();
    fit_each_run(runs, spec, params, &global[2 * nm..], Some(&starts))
}

/// The slow noise of the runs' own fits `fits`.
fn slow_of(
    runs: &[RunData],
    base: &Spec,
    base_params: &[ParamInfo],
    extra_values: &[f64],
    fits: &[PerRunFit],
) -> Slow {
    let series: Vec<Series> = runs
        .par_iter()
        .zip(fits)
        .map(|(run, fit)| slow_series(run, base, base_params, extra_values, fit))
        .collect();
    super::slow_noise::estimate(&series).0
}

/// A run's own fit as the slow-noise estimate reads it: the residual at its kept samples in
/// noise units and the fit's five columns there (each parameter stepped).
fn slow_series(
    run: &RunData,
    base: &Spec,
    base_params: &[ParamInfo],
    extra_values: &[f64],
    fit: &PerRunFit,
) -> Series {
    let kept = |v: Vec<f64>| -> Vec<f64> {
        v.into_iter()
            .zip(&run.keep)
            .filter(|p| *p.1)
            .map(|p| p.0 / run.sigma_m)
            .collect()
    };
    let res = residuals(run, base, base_params, extra_values, fit);
    let steps: [(usize, f64); 5] = [
        (0, 1e-4 * fit.mu.abs().max(1e-3)),
        (1, 1e-4 * fit.t_s.abs().max(1e-4)),
        (2, 1e-7),
        (3, 1e-7),
        (4, 1e-6 * fit.local[2].abs().max(1e-3)),
    ];
    let cols = steps
        .iter()
        .map(|&(j, h)| {
            let mut f = fit.clone();
            match j {
                0 => f.mu += h,
                1 => f.t_s += h,
                _ => f.local[j - 2] += h,
            }
            let moved = residuals(run, base, base_params, extra_values, &f);
            kept(moved.iter().zip(&res).map(|(a, b)| a - b).collect())
        })
        .collect();
    Series {
        y: kept(res),
        cols,
        fast: run.fast,
        scale: run.scale.clone(),
    }
}
