//! The impulse model of one impact between equal spheres (see `physics`): normal impulse
//! J = (1 + C)/2 · (v1 − v2), then friction at the contact either slips (both spins change by
//! μ_pp k J against the sliding) or sticks (the contact surfaces end up moving together).
//!
//! Both cases in one line: Δv_a1 = Δv_a2 = −sign(S)·min(μ_pp k J, |S|/2), S = v_a1 + v_a2.

use crate::physics::impulse::collide;

/// Velocity and spin (v, v_a) of both particles after an impact, and whether it slipped: the
/// physics' own impulse rule ([`crate::physics::impulse::collide`]) in the fit's (v, v_a) pairs.
pub fn after_impact(
    pre: [(f64, f64); 2],
    restitution: f64,
    mu_pp: f64,
    k: f64,
) -> ([(f64, f64); 2], bool) {
    let [(v1, va1), (v2, va2)] = pre;
    let kick = collide([v1, v2], [va1, va2], restitution, mu_pp, k);
    (
        [(kick.v[0], kick.va[0]), (kick.v[1], kick.va[1])],
        kick.slip,
    )
}

/// The spin change alone, for fitting μ_pp to measured spin changes (the slip rule of
/// [`crate::physics::impulse::collide`] as a function of the spin sum and the impulse).
/// Each spin changes by this for spin sum `s_mps` and normal impulse (per mass) `j_mps` ≥ 0.
pub fn spin_change(s_mps: f64, j_mps: f64, mu_pp: f64, k: f64) -> (f64, bool) {
    let slip_limit = mu_pp * k * j_mps.abs();
    if s_mps.abs() >= 2.0 * slip_limit {
        (-s_mps.signum() * slip_limit, true)
    } else {
        (-0.5 * s_mps, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stick_leaves_equal_and_opposite_spins() {
        // a rolling striker (v_a = v/s) into a resting target sticks for μ_pp = 1.4
        let s = 0.5779;
        let ([(_, va1), (v2, va2)], slip) =
            after_impact([(0.1, 0.1 / s), (0.0, 0.0)], 0.9, 1.4, 2.5);
        assert!(!slip);
        assert!((va1 + va2).abs() < 1e-15);
        assert!((v2 - 0.095).abs() < 1e-12);
    }

    #[test]
    fn slip_changes_both_spins_by_mu_k_j() {
        let ([(v1, va1), (v2, va2)], slip) = after_impact([(0.01, 0.5), (0.0, 0.3)], 1.0, 1.4, 2.5);
        assert!(slip);
        let j = 0.01;
        assert!((v1 - 0.0).abs() < 1e-15 && (v2 - j).abs() < 1e-15);
        assert!((va1 - (0.5 - 1.4 * 2.5 * j)).abs() < 1e-12);
        assert!((va2 - (0.3 - 1.4 * 2.5 * j)).abs() < 1e-12);
    }
}
