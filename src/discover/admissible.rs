//! Whether a fitted term is physics: a search that ended at its bound resolves nothing, a size
//! that ended at the edge of what its form can mean (μ varying by 90 % of itself) is a form bent
//! to absorb something else, and a dissipation that pushes the particle forward is no
//! dissipation.
//!
//! The groove and the air are passive: every acceleration that depends on the particle's speed
//! alone (the drag in any of its forms, a rolling resistance, a smooth force in v) takes energy
//! out, so their sum opposes the motion, `a_v(v)·v ≤ 0`, at every speed the runs reach. A fitted
//! quadratic drag with a negative coefficient is allowed where the total drag still opposes the
//! motion (a drag that grows more slowly than linearly); where it reverses (above
//! `v = 1/(T·|c|)`) the fit has bent the form to absorb something else, and the term is refused
//! in words instead of reported as a propulsion. Forces that depend on position (a potential) or
//! on time (a drive) carry no sign rule.

use super::estimates::{scale_at_bound, side_of_bound};
use super::model::Model;
use super::sim::{Drag, SimModel};
use super::G_MPS2;
use crate::physics::{Term, Variable};

/// Points of the speed grid the sign is checked on, from 2 % of the fastest run's speed up to it.
const SPEED_POINTS: usize = 64;

/// Why the last term of `m` is no physical finding, or None when it is admissible.
pub fn refusal(m: &Model) -> Option<String> {
    scale_at_bound(m)
        .or_else(|| size_at_bound(m))
        .or_else(|| not_passive(m))
}

/// The refusal of a last term whose size ended at a bound its form marks as no physical limit
/// (`Form::refused_at_bound`), or None.
fn size_at_bound(m: &Model) -> Option<String> {
    let i = m.spec.extras.len().checked_sub(1)?;
    let off = m.spec.extra_offset(i);
    let e = &m.spec.extras[i];
    let n = e.params().len();
    (0..n).find_map(|j| {
        let info = &m.params[off + j];
        let x = m.fit.global[off + j];
        side_of_bound(x, info, 1e-2)
            .is_some_and(|lower| e.refused_at_bound(j, lower))
            .then(|| {
            format!(
                "rejected: its {} ended at its bound ({x:.3}): {} this large is a form bent to absorb something else, not physics",
                info.name,
                e.size_name()
            )
        })
    })
}

/// The acceleration of `sim` that depends on the signed speed `v` alone (m/s²).
pub fn speed_acceleration(sim: &SimModel, v: f64) -> f64 {
    let drag = match sim.drag {
        Drag::Quadratic { t_s, c_per_m } => -v / t_s - c_per_m * v * v.abs(),
        Drag::Saturating { t0_s, tp_s_per_mps } => -v / (t0_s + tp_s_per_mps * v.abs()),
    };
    let resistance = -sim.roll_c * G_MPS2 * v.signum();
    let splines: f64 = sim
        .terms
        .iter()
        .filter_map(|t| match t {
            Term::Spline(sp) if sp.variable == Variable::V => Some(sp.at(v)),
            _ => None,
        })
        .sum();
    drag + resistance + splines
}

/// The refusal of a model whose speed-dependent acceleration pushes a particle forward somewhere
/// in the speed range the runs cover (per material), or None.
fn not_passive(m: &Model) -> Option<String> {
    // the baseline's linear drag is passive: only a speed term can make the sum push
    let speed_term = m.spec.extras.iter().any(|e| e.speed_dependent());
    if !speed_term {
        return None;
    }
    let v_max = m
        .fit
        .local
        .iter()
        .map(|l| l[2].abs())
        .fold(0.0f64, f64::max);
    if !(v_max > 0.0) {
        return None;
    }
    for material in 0..m.spec.n_materials {
        let sim = m.spec.sim_model(&m.fit.global, material, v_max);
        for j in 0..SPEED_POINTS {
            let speed = v_max * (0.02 + 0.98 * j as f64 / (SPEED_POINTS - 1) as f64);
            for v in [speed, -speed] {
                let push = speed_acceleration(&sim, v) * v.signum();
                if push > 0.0 {
                    return Some(format!(
                        "refused: with it the speed-dependent forces push the particle forward at \
                         |v| = {:.1} mm/s (by {:.3} m/s²), inside the speeds the runs reach; a \
                         dissipation that accelerates is no physics, so the fit bent this form \
                         to absorb something else",
                        1e3 * speed,
                        push
                    ));
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sim(drag: Drag) -> SimModel {
        SimModel {
            drag,
            ..SimModel::baseline(0.5779, 2.5, 0.3, 0.05)
        }
    }

    #[test]
    fn a_negative_quadratic_drag_pushes_only_above_its_reversal_speed() {
        // −v/T − c v|v| with T = 0.05 s, c = −178 /m reverses at 1/(T|c|) = 0.112 m/s
        let s = sim(Drag::Quadratic {
            t_s: 0.05,
            c_per_m: -178.0,
        });
        assert!(speed_acceleration(&s, 0.1) < 0.0);
        assert!(speed_acceleration(&s, 0.12) > 0.0);
        assert!(speed_acceleration(&s, -0.12) < 0.0);
    }

    #[test]
    fn a_saturating_drag_and_a_resistance_always_oppose_the_motion() {
        let mut s = sim(Drag::Saturating {
            t0_s: 0.05,
            tp_s_per_mps: 1.1,
        });
        s.roll_c = 0.004;
        for v in [1e-4, 0.01, 0.3, 3.0] {
            assert!(speed_acceleration(&s, v) < 0.0);
            assert!(speed_acceleration(&s, -v) > 0.0);
        }
    }
}
