//! From a solved joint model to the `CollisionFit` record: segments with their phases, impacts
//! with velocities and spins before and after, C, Δv of the target, stick/slip, and standard
//! errors propagated from the fit's covariance.

use super::model::{Layout, MU, T_DRAG};
use crate::artifacts::collision_fit::{
    CollisionFit, Contact, Estimate, ImpactFit, Kin, PhaseKind, PhaseSpan, PreImpactSource,
    SegmentFit,
};
use crate::lsq::dense_fit::DenseFit as LmResult;
use crate::lsq::Termination;
use crate::recording::RunInfo;

/// A record for a run that could not be fitted.
pub fn failed_fit(info: &RunInfo, termination: Termination, message: &str) -> CollisionFit {
    let nan = Estimate {
        value: f64::NAN,
        se: None,
        interval: None,
    };
    CollisionFit {
        run: info.run.clone(),
        material: info.material.clone(),
        setup: info.setup,
        direction: 1,
        termination,
        status: termination.status_word().to_string(),
        message: message.to_string(),
        mu_pg: nan,
        t_drag_s: nan,
        segments: Vec::new(),
        impacts: Vec::new(),
        rms_m: f64::NAN,
        noise_m: f64::NAN,
        n_points: 0,
        n_outliers: 0,
        iterations: 0,
        fit_end_s: None,
    }
}

/// Standard error of a derived quantity f(p) by central differences along each fitted
/// parameter (steps of 1 % of its standard error) and the covariance.
fn propagate(res: &LmResult, f: &dyn Fn(&[f64]) -> f64) -> Estimate {
    let p = &res.params;
    let value = f(p);
    let m = p.len();
    let mut grad = vec![0.0; m];
    let mut q = p.clone();
    for j in 0..m {
        let se = res.se(j);
        if !(se > 0.0) || !se.is_finite() {
            continue;
        }
        let h = 0.01 * se;
        q[j] = p[j] + h;
        let up = f(&q);
        q[j] = p[j] - h;
        let down = f(&q);
        q[j] = p[j];
        grad[j] = (up - down) / (2.0 * h);
    }
    let mut var = 0.0;
    for i in 0..m {
        for j in 0..m {
            if grad[i] != 0.0 && grad[j] != 0.0 {
                var += grad[i] * res.covariance[i][j] * grad[j];
            }
        }
    }
    Estimate::new(value, var.max(0.0).sqrt())
}

/// Build the record of a solved run. `direction` is +1/−1 (lab sign of the striker's motion).
pub fn summarize_fit(
    info: &RunInfo,
    direction: f64,
    layout: &Layout,
    res: &LmResult,
) -> CollisionFit {
    let p = &res.params;
    let lab = |e: Estimate| Estimate {
        value: direction * e.value,
        ..e
    };
    let mut segments = Vec::new();
    for part in 0..2 {
        let track = &layout.tracks[part];
        let starts = layout.piece_starts(p, part);
        let t_last = *track.t_s.last().unwrap_or(&0.0);
        for (k, st) in starts.iter().enumerate() {
            let (t0, t1) = (st.t_s, starts.get(k + 1).map(|s| s.t_s).unwrap_or(t_last));
            let n_points = track.t_s.iter().filter(|&&t| t >= t0 && t < t1).count();
            let piece_v = |q: &[f64]| layout.piece_starts(q, part)[k].v_mps;
            let piece_va = |q: &[f64]| layout.piece_starts(q, part)[k].va_mps;
            let (v_est, va_est) = if st.rest {
                (Estimate::new(0.0, 0.0), Estimate::new(0.0, 0.0))
            } else {
                (propagate(res, &piece_v), propagate(res, &piece_va))
            };
            let motion = layout.motion(p, part, k);
            let t_drag = layout.drag[part][k];
            let t_sw = (!st.rest)
                .then(|| t0 + motion.switch_time_s(st.v_mps, st.va_mps))
                .filter(|&t| t <= t1);
            let phases = match (st.rest, t_sw) {
                (true, _) => vec![span(PhaseKind::Rest, t0, t1)],
                (false, Some(ts)) if ts <= t0 => vec![span(PhaseKind::Rolling, t0, t1)],
                (false, Some(ts)) => vec![
                    span(PhaseKind::Sliding, t0, ts),
                    span(PhaseKind::Rolling, ts, t1),
                ],
                (false, None) => vec![span(PhaseKind::Sliding, t0, t1)],
            };
            segments.push(SegmentFit {
                particle: part as u32,
                t_start_s: t0,
                t_end_s: t1,
                z_start_m: direction * st.z_m,
                v_start_mps: lab(v_est),
                va_start_mps: lab(va_est),
                t_drag_s: Estimate::new(p[t_drag].exp(), p[t_drag].exp() * res.se(t_drag)),
                t_switch_s: t_sw,
                spin_identified: resolved(va_est, v_est.value),
                phases,
                n_points,
            });
        }
    }
    let impacts = (0..layout.impacts.len())
        .map(|j| impact_record(layout, res, j, direction))
        .collect();
    let data = &res.residuals[..layout.n_data()];
    let rms = (data.iter().map(|r| r * r).sum::<f64>() / data.len().max(1) as f64).sqrt();
    CollisionFit {
        run: info.run.clone(),
        material: info.material.clone(),
        setup: info.setup,
        direction: direction as i32,
        termination: res.termination,
        status: res.termination.status_word().to_string(),
        message: String::new(),
        mu_pg: Estimate::new(p[MU], res.se(MU)),
        t_drag_s: Estimate::new(p[T_DRAG].exp(), p[T_DRAG].exp() * res.se(T_DRAG)),
        segments,
        impacts,
        rms_m: rms,
        noise_m: res.scale,
        n_points: data.len(),
        n_outliers: data.iter().filter(|r| r.abs() > 5.0 * res.scale).count(),
        iterations: res.iterations,
        fit_end_s: None,
    }
}

fn span(phase: PhaseKind, t_start_s: f64, t_end_s: f64) -> PhaseSpan {
    PhaseSpan {
        phase,
        t_start_s,
        t_end_s,
    }
}

/// Everything about impact `j` (striker-forward frame inside, lab frame for Kin).
fn impact_record(layout: &Layout, res: &LmResult, j: usize, direction: f64) -> ImpactFit {
    let momentum = layout.before_impact(&res.params, 0, j).is_none();
    // [v1, va1, v2, va2] before and after, as functions of the parameters
    let before = move |q: &[f64]| -> [f64; 4] {
        let tg = layout
            .before_impact(q, 1, j)
            .map(|k| (k.v_mps, k.va_mps))
            .unwrap_or((0.0, 0.0));
        let st = match layout.before_impact(q, 0, j) {
            Some(k) => (k.v_mps, k.va_mps),
            None => {
                // contact setup: no striker track before; momentum conservation, no spin
                let a1 = layout.after_impact(q, 0, j).unwrap_or((0.0, 0.0));
                let a2 = layout.after_impact(q, 1, j).unwrap_or((0.0, 0.0));
                (a1.0 + a2.0 - tg.0, 0.0)
            }
        };
        [st.0, st.1, tg.0, tg.1]
    };
    let after = move |q: &[f64]| -> [f64; 4] {
        let a1 = layout.after_impact(q, 0, j).unwrap_or((f64::NAN, f64::NAN));
        let a2 = layout.after_impact(q, 1, j).unwrap_or((f64::NAN, f64::NAN));
        [a1.0, a1.1, a2.0, a2.1]
    };
    let est = |f: &dyn Fn(&[f64]) -> f64| propagate(res, f);
    let lab = |e: Estimate| Estimate {
        value: direction * e.value,
        ..e
    };
    let kin = |g: &dyn Fn(&[f64]) -> [f64; 4], i: usize| Kin {
        v_mps: lab(est(&|q| g(q)[i])),
        va_mps: lab(est(&|q| g(q)[i + 1])),
    };
    let p = &res.params;
    let (b, a) = (before(p), after(p));
    let speed = est(&|q| before(q)[0] - before(q)[2]);
    let restitution = est(&|q| {
        let (b, a) = (before(q), after(q));
        (a[2] - a[0]) / (b[0] - b[2])
    });
    let sum_after = est(&|q| after(q)[1] + after(q)[3]);
    let sum_before = est(&|q| before(q)[1] + before(q)[3]);
    let contact = classify(sum_before, sum_after);
    ImpactFit {
        index: j,
        t_s: est(&|q| layout.impact_time(q, j)),
        striker_before: kin(&before, 0),
        striker_after: kin(&after, 0),
        target_before: kin(&before, 2),
        target_after: kin(&after, 2),
        striker_before_source: if momentum {
            PreImpactSource::MomentumConservation
        } else {
            PreImpactSource::Fitted
        },
        impact_speed_mps: speed,
        restitution,
        target_dvz_mps: est(&|q| after(q)[2] - before(q)[2]),
        target_dva_mps: est(&|q| after(q)[3] - before(q)[3]),
        striker_dva_mps: est(&|q| after(q)[1] - before(q)[1]),
        spin_sum_before_mps: sum_before.value,
        spin_sum_after_mps: sum_after,
        momentum_mismatch_mps: (b[0] + b[2]) - (a[0] + a[2]),
        contact,
    }
}

/// A spin is resolved when its standard error is small against the speed (or 1 mm/s).
fn resolved(va: Estimate, v_mps: f64) -> bool {
    va.se.is_some_and(|se| se <= 0.25 * v_mps.abs() + 1e-3)
}

/// Stick leaves v_a1' + v_a2' = 0; slip keeps the sign of the sum and a clearly nonzero value.
fn classify(sum_before: Estimate, sum_after: Estimate) -> Contact {
    let (Some(se_b), Some(se_a)) = (sum_before.se, sum_after.se) else {
        return Contact::Undetermined;
    };
    let s = sum_before.value;
    if se_a.max(se_b) > 0.25 * s.abs() + 1e-3 {
        return Contact::Undetermined;
    }
    let a = sum_after.value;
    if a.signum() == s.signum() && a.abs() > 3.0 * se_a && a.abs() > 0.05 * s.abs() {
        Contact::Slip
    } else {
        Contact::Stick
    }
}
