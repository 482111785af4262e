//! A fitted term's parameters as reported: physical names and SI units, a value that ended at a
//! bound of its search said in words, a spline's size where the runs go.

use super::candidate::{Extra, ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::model::Model;
use super::timeforce;
use super::G_MPS2;
use crate::artifacts::diagnosis::Estimate;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// The parameters of extra term `i` of `m`, in SI units with physical names.
pub fn term_parameters(m: &Model, i: usize, materials: &[String]) -> BTreeMap<String, Estimate> {
    let off = m.spec.extra_offset(i);
    let g = &m.fit.global;
    let se = &m.fit.global_se;
    let est = Estimate::new;
    let mut out = BTreeMap::new();
    let nm = m.spec.n_materials;
    match &m.spec.extras[i] {
        Extra::QuadraticDrag => {
            out.insert("c_per_m".into(), est(g[off], se[off]));
            for (k, name) in materials.iter().enumerate() {
                out.insert(format!("t_s_{name}"), est(g[nm + k], se[nm + k]));
            }
        }
        Extra::SaturatingDrag => {
            out.insert("tp_s_per_mps".into(), est(g[off], se[off]));
            for (k, name) in materials.iter().enumerate() {
                out.insert(format!("t0_s_{name}"), est(g[nm + k], se[nm + k]));
            }
        }
        Extra::RollingResistance => {
            out.insert(
                "deceleration_mps2".into(),
                est(g[off] * G_MPS2, se[off] * G_MPS2),
            );
            out.insert("coefficient".into(), est(g[off], se[off]));
        }
        Extra::GrooveTilt => {
            out.insert("alpha_deg".into(), est(g[off], se[off]));
        }
        Extra::VelocityFriction { .. } => {
            for (k, name) in materials.iter().enumerate() {
                let vc = g[off + k].exp();
                out.insert(format!("v_c_mps_{name}"), est(vc, vc * se[off + k]));
                out.insert(format!("mu_inf_{name}"), est(g[k], se[k]));
            }
        }
        Extra::PositionForce {
            harmonics,
            z_min_m,
            span_m,
        } => {
            let mut peak: f64 = 0.0;
            for j in 0..=200 {
                let z = z_min_m + span_m * j as f64 / 200.0;
                let a: f64 = (0..*harmonics)
                    .map(|k| {
                        let u = std::f64::consts::PI * (k + 1) as f64 * (z - z_min_m) / span_m;
                        g[off + 2 * k] * u.sin() + g[off + 2 * k + 1] * u.cos()
                    })
                    .sum();
                peak = peak.max(a.abs());
            }
            out.insert("peak_accel_mps2".into(), est(peak, f64::NAN));
            out.insert("z_min_m".into(), est(*z_min_m, 0.0));
            out.insert("span_m".into(), est(*span_m, 0.0));
            for k in 0..2 * harmonics {
                out.insert(m.params[off + k].name.clone(), est(g[off + k], se[off + k]));
            }
        }
        Extra::PeriodicZ { z_ref_m, .. } => {
            let (k, a, b) = (g[off], g[off + 1], g[off + 2]);
            let (sk, sa, sb) = (se[off], se[off + 1], se[off + 2]);
            let amp = a.hypot(b).max(1e-300);
            let amp_se = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp;
            out.insert("amplitude_mps2".into(), est(amp, amp_se));
            out.insert("peak_accel_mps2".into(), est(amp, amp_se));
            out.insert(
                "wavelength_m".into(),
                est(
                    std::f64::consts::TAU / k,
                    std::f64::consts::TAU * sk / (k * k),
                ),
            );
            let phase = (b.atan2(a) - k * z_ref_m).rem_euclid(std::f64::consts::TAU);
            let phase_se =
                (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp)).hypot(z_ref_m * sk);
            out.insert("phase_rad".into(), est(phase, phase_se));
        }
        Extra::Localized { .. } => {
            out.insert("amplitude_mps2".into(), est(g[off], se[off]));
            out.insert("peak_accel_mps2".into(), est(g[off].abs(), se[off]));
            out.insert("centre_m".into(), est(g[off + 1], se[off + 1]));
            out.insert("width_m".into(), est(g[off + 2], se[off + 2]));
        }
        Extra::TimePeriodic { .. } => {
            out.insert("frequency_hz".into(), est(g[off], se[off]));
            out.insert("amplitude_mps2".into(), est(g[off + 1], se[off + 1]));
            out.insert("peak_accel_mps2".into(), est(g[off + 1], se[off + 1]));
        }
        Extra::Spline {
            variable,
            lo,
            dx,
            segments,
        } => {
            let sp = crate::physics::SplineForce {
                variable: *variable,
                lo_x: *lo,
                dx: *dx,
                coefs_mps2: g[off..off + segments + 3].to_vec(),
            };
            let hi = lo + dx * *segments as f64;
            let (mut peak, mut at, mut ss) = (0.0f64, *lo, 0.0);
            for j in 0..=200 {
                let x = lo + (hi - lo) * j as f64 / 200.0;
                let a = sp.at(x);
                ss += a * a;
                if a.abs() > peak {
                    peak = a.abs();
                    at = x;
                }
            }
            out.insert("peak_accel_mps2".into(), est(peak, f64::NAN));
            out.insert("rms_accel_mps2".into(), est((ss / 201.0).sqrt(), f64::NAN));
            out.insert("x_at_peak".into(), est(at, 0.0));
            out.insert("x_lo".into(), est(*lo, 0.0));
            out.insert("x_hi".into(), est(hi, 0.0));
        }
        Extra::FrictionDirection => {
            out.insert("delta_dir".into(), est(g[off], se[off]));
            for (k, name) in materials.iter().enumerate() {
                let mu = g[k];
                out.insert(
                    format!("mu_forward_{name}"),
                    est(mu * (1.0 + g[off]), f64::NAN),
                );
                out.insert(
                    format!("mu_backward_{name}"),
                    est(mu * (1.0 - g[off]), f64::NAN),
                );
            }
        }
        Extra::FrictionPosition {
            z_mid_m,
            half_span_m,
        } => {
            let (p1, p2) = (g[off], g[off + 1]);
            let (mut peak, mut at) = (0.0f64, *z_mid_m);
            for j in 0..=200 {
                let x = -1.0 + 2.0 * j as f64 / 200.0;
                let d = p1 * x + p2 * 0.5 * (3.0 * x * x - 1.0);
                if d.abs() > peak.abs() {
                    peak = d;
                    at = z_mid_m + half_span_m * x;
                }
            }
            out.insert("p1_rel".into(), est(p1, se[off]));
            out.insert("p2_rel".into(), est(p2, se[off + 1]));
            out.insert("peak_rel".into(), est(peak, f64::NAN));
            out.insert("z_at_peak_m".into(), est(at, 0.0));
            out.insert("z_lo_m".into(), est(z_mid_m - half_span_m, 0.0));
            out.insert("z_hi_m".into(), est(z_mid_m + half_span_m, 0.0));
        }
        Extra::FrictionSlip { u_ref_mps } => {
            out.insert("beta_rel".into(), est(g[off], se[off]));
            out.insert("u_ref_mps".into(), est(*u_ref_mps, 0.0));
            out.insert(
                "dmu_rel_per_mps".into(),
                est(g[off] / u_ref_mps, se[off] / u_ref_mps),
            );
        }
        Extra::Distortion {
            z_mid_m,
            half_span_m,
        } => {
            let d = super::sim::Distortion {
                z_mid_m: *z_mid_m,
                half_span_m: *half_span_m,
                a2_m: g[off],
                a3_m: g[off + 1],
            };
            let peak = (0..=200)
                .map(|j| {
                    let z = z_mid_m + half_span_m * (-1.0 + 2.0 * j as f64 / 200.0);
                    d.measured(z) - z
                })
                .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
            out.insert("a2_m".into(), est(g[off], se[off]));
            out.insert("a3_m".into(), est(g[off + 1], se[off + 1]));
            out.insert("peak_shift_m".into(), est(peak, f64::NAN));
        }
        Extra::SpeedDriftT { .. } | Extra::SpeedDriftMu { .. } | Extra::DirectionAsymmetry => {
            for (k, p) in m.spec.extras[i].params().iter().enumerate() {
                out.insert(p.name.clone(), est(g[off + k], se[off + k]));
            }
        }
    }
    out
}

/// The parameters of extra term `i` of `m` that ended at a bound of their search, in words: such a
/// value is a limit the data pushed against, not an estimate (a velocity-dependent friction
/// fitted to two materials of which one has none ends with that material's v_c at its floor).
pub fn bound_notes(m: &Model, i: usize, materials: &[String]) -> Vec<String> {
    let off = m.spec.extra_offset(i);
    let n = m.spec.extras[i].params().len();
    let mut notes = Vec::new();
    for k in 0..n {
        let (x, info) = (m.fit.global[off + k], &m.params[off + k]);
        let Some(lower) = side_of_bound(x, info, 1e-6) else {
            continue;
        };
        // a term that starts where it vanishes, at its bound, is not reported as pinned there
        if lower
            && info.start == info.lo
            && !matches!(m.spec.extras[i], Extra::VelocityFriction { .. })
        {
            continue;
        }
        notes.push(match &m.spec.extras[i] {
            Extra::VelocityFriction { .. } => {
                let name = materials.get(k).map_or("?", |s| s.as_str());
                if lower {
                    format!(
                        "v_c of {name} at the search's floor ({:.1e} m/s): no speed dependence of {name}'s friction is resolved (its μ is constant, mu_inf_{name})",
                        x.exp()
                    )
                } else {
                    format!(
                        "v_c of {name} at the search's ceiling ({:.2} m/s): {name}'s friction still rises at the highest slip speeds; no plateau is resolved",
                        x.exp()
                    )
                }
            }
            Extra::PeriodicZ { .. } if info.name == "k_per_m" => format!(
                "the wavelength ({:.3} mm) is the {} the search allows: the data resolve no {} period, so wavelength and amplitude describe the observed stretch rather than a period",
                1e3 * std::f64::consts::TAU / x,
                if lower { "longest" } else { "shortest" },
                if lower { "longer" } else { "shorter" }
            ),
            _ => format!(
                "{} = {x:.4e} at its {} bound: a limit the fit pushed against, not an estimate",
                info.name,
                if lower { "lower" } else { "upper" }
            ),
        });
    }
    notes
}

/// Which bound `x` sits at (`Some(true)` the lower), within `rel` of the parameter's range.
fn side_of_bound(x: f64, info: &ParamInfo, rel: f64) -> Option<bool> {
    let tol = rel * (info.hi - info.lo);
    if x <= info.lo + tol {
        Some(true)
    } else if x >= info.hi - tol {
        Some(false)
    } else {
        None
    }
}

/// Why a searched form's scale (a wavelength, a width, a frequency) fitted in full is not a
/// finding: it ran to the end of its search, so the data hold no such feature inside the range
/// the search can resolve (on two speed effects at once, a wave at the shortest wavelength
/// allowed soaked up what neither effect alone explained). `None` when the scale is inside.
pub fn scale_at_bound(m: &Model) -> Option<String> {
    let i = m.spec.extras.len().checked_sub(1)?;
    let off = m.spec.extra_offset(i);
    let (idx, what) = match m.spec.extras[i] {
        Extra::PeriodicZ { .. } => (0, "wavelength"),
        Extra::Localized { .. } => (2, "width"),
        Extra::TimePeriodic { .. } => (0, "frequency"),
        _ => return None,
    };
    let x = m.fit.global[off + idx];
    let lower = side_of_bound(x, &m.params[off + idx], 1e-2)?;
    // only the fine end: a wave longer, a bump wider or a vibration slower than the search
    // reaches is still a slow variation the data show (bound_notes says so in words)
    let text = match (&m.spec.extras[i], lower) {
        (Extra::PeriodicZ { .. }, false) => format!(
            "its wavelength ran to the shortest the search allows ({:.3} mm)",
            1e3 * std::f64::consts::TAU / x
        ),
        (Extra::Localized { .. }, true) => format!(
            "its width ran to the narrowest the search allows ({:.3} mm)",
            1e3 * x
        ),
        (Extra::TimePeriodic { .. }, false) => {
            format!("its frequency ran to the highest the search allows ({x:.1} Hz)")
        }
        _ => return None,
    };
    Some(format!(
        "rejected: {text}; a {what} at the end of the search is no feature the data resolve"
    ))
}

/// A spline force's size where the runs go: its peak (and where), RMS and the fraction of its
/// range that holds data, over the points of its range within half a knot spacing of a sample.
/// Over a gap between the runs the spline is held by its penalty alone and may swing far (13
/// m/s² at 6–7.4 mm on the shipped data, where no run went): that is no size of the data.
struct SplineSize {
    peak: f64,
    at: f64,
    rms: f64,
    covered: f64,
}

fn spline_size_where_runs_go(
    sp: &crate::physics::SplineForce,
    hi: f64,
    runs: &[RunData],
) -> SplineSize {
    use crate::physics::Variable;
    let mut xs: Vec<f64> = Vec::new();
    for r in runs {
        let kept = |j: usize| r.keep[j];
        match sp.variable {
            Variable::Z => xs.extend((0..r.z_m.len()).filter(|&j| kept(j)).map(|j| r.z_m[j])),
            Variable::T => xs.extend((0..r.t_s.len()).filter(|&j| kept(j)).map(|j| r.t_s[j])),
            Variable::V => {
                // a velocity over four frames: its noise is far below a knot spacing
                let h = 4;
                xs.extend((0..r.z_m.len().saturating_sub(h)).filter_map(|j| {
                    let dt = r.t_s[j + h] - r.t_s[j];
                    (kept(j) && kept(j + h) && dt > 0.0).then(|| (r.z_m[j + h] - r.z_m[j]) / dt)
                }))
            }
        }
    }
    xs.retain(|x| x.is_finite());
    xs.sort_by(f64::total_cmp);
    let near = |x: f64| {
        let k = xs.partition_point(|s| *s < x - 0.5 * sp.dx);
        k < xs.len() && xs[k] <= x + 0.5 * sp.dx
    };
    let (mut peak, mut at, mut ss, mut n) = (0.0f64, sp.lo_x, 0.0, 0usize);
    for j in 0..=200 {
        let x = sp.lo_x + (hi - sp.lo_x) * j as f64 / 200.0;
        if !near(x) {
            continue;
        }
        let a = sp.at(x);
        n += 1;
        ss += a * a;
        if a.abs() > peak {
            peak = a.abs();
            at = x;
        }
    }
    SplineSize {
        peak,
        at,
        rms: (ss / n.max(1) as f64).sqrt(),
        covered: n as f64 / 201.0,
    }
}

/// The parameters of extra term `i` of `m` as reported: `term_parameters`, with a force in
/// time's amplitude taken with each run's phase integrated out, not fitted (the fitted phases
/// also fit the noise and make it read high; timeforce.rs).
pub fn reported_parameters(
    m: &Model,
    i: usize,
    materials: &[String],
    runs: &[RunData],
) -> BTreeMap<String, Estimate> {
    let mut parameters = term_parameters(m, i, materials);
    if let Extra::Spline {
        variable,
        lo,
        dx,
        segments,
    } = m.spec.extras[i]
    {
        let off = m.spec.extra_offset(i);
        let sp = crate::physics::SplineForce {
            variable,
            lo_x: lo,
            dx,
            coefs_mps2: m.fit.global[off..off + segments + 3].to_vec(),
        };
        let size = spline_size_where_runs_go(&sp, lo + dx * segments as f64, runs);
        let est = |v: f64| Estimate::new(v, f64::NAN);
        parameters.insert("peak_accel_mps2".into(), est(size.peak));
        parameters.insert("rms_accel_mps2".into(), est(size.rms));
        parameters.insert("x_at_peak".into(), Estimate::new(size.at, 0.0));
        parameters.insert("covered_fraction".into(), Estimate::new(size.covered, 0.0));
    }
    if matches!(m.spec.extras[i], Extra::TimePeriodic { .. }) {
        if let Some(a) = amplitude_over_phases(&m.spec, &m.fit.global, &m.fit.local, runs) {
            for name in ["amplitude_mps2", "peak_accel_mps2"] {
                if let Some(p) = parameters.get_mut(name) {
                    p.value = a;
                }
            }
        }
    }
    parameters
}
/// The amplitude of a force periodic in time with each run's phase integrated out (uniform over
/// the circle) instead of fitted: the maximum of the marginal likelihood, at the joint fit's
/// frequency and locals. `None` without such a term.
///
/// The joint fit profiles a phase per run, and a phase chosen per run also fits that run's noise:
/// with n runs and the effect's total χ² X, the profiled amplitude comes out high by about
/// n/(2X) (the Rice bias: E|y| = √(A² + 2σ²) for a two-component projection; 6.5 % for 60 runs
/// at X = 460), and the excess does not fall with more runs, since every run brings its own
/// phase (Neyman and Scott's incidental parameters). Integrating the phases out leaves one
/// parameter for all runs, and its maximum-likelihood estimate is consistent.
fn amplitude_over_phases(
    spec: &Spec,
    global: &[f64],
    local: &[[f64; N_LOCAL]],
    runs: &[RunData],
) -> Option<f64> {
    let sums: Vec<([f64; 5], f64)> = runs
        .par_iter()
        .zip(local)
        .filter_map(|(run, l)| {
            let m = spec.sim_model(global, run.material, l[2]);
            let (idx, amp, _) = timeforce::time_term(&m)?;
            (amp != 0.0).then(|| {
                (
                    timeforce::run_sums(&m, idx, l, run),
                    run.sigma_m * run.sigma_m,
                )
            })
        })
        .collect();
    let amp = {
        let m = spec.sim_model(global, runs.first()?.material, local.first()?[2]);
        timeforce::time_term(&m)?.1
    };
    if sums.is_empty() || amp == 0.0 {
        return None;
    }
    let total = |scale: f64| -> f64 {
        sums.iter()
            .map(|(k, var)| timeforce::log_marginal(k, scale, *var))
            .sum()
    };
    // the scale in [0, 2] that maximises it (the profiled amplitude is scale 1, and above)
    Some(crate::lsq::golden::minimize(|x| -total(x), 0.0, 2.0, 50) * amp)
}
