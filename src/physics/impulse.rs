//! The collision impulse between two equal spheres in the groove (the chapter's Eqs. 4.9–4.13).
//!
//! With J = (1 + C)/2 · (v_l − v_r) (l is the particle at lower z): `v_l' = v_l − J`,
//! `v_r' = v_r + J`. The contact slips when `|va_l + va_r| ≥ 2 μ_pp k J`, and then both spins
//! change by `−sign(va_l + va_r) μ_pp k J`; otherwise the surfaces stick at the contact and
//! `va_l' = (va_l − va_r)/2`, `va_r' = (va_r − va_l)/2`.

/// Velocities after an impact and whether the contact slipped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kick {
    pub v: [f64; 2],
    pub va: [f64; 2],
    pub slip: bool,
}

/// Apply the impulse to (v, va) of the lower-z particle `l` and the upper-z particle `r`.
pub fn collide(v: [f64; 2], va: [f64; 2], c: f64, mu_pp: f64, k: f64) -> Kick {
    let j = 0.5 * (1.0 + c) * (v[0] - v[1]);
    let sum = va[0] + va[1];
    let dva = mu_pp * k * j;
    let slip = sum.abs() >= 2.0 * dva;
    let va_new = if slip {
        [va[0] - sum.signum() * dva, va[1] - sum.signum() * dva]
    } else {
        [0.5 * (va[0] - va[1]), 0.5 * (va[1] - va[0])]
    };
    Kick {
        v: [v[0] - j, v[1] + j],
        va: va_new,
        slip,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elastic_impact_of_rolling_pair_exchanges_velocity_and_keeps_momentum() {
        let s = 0.5778576243835053;
        let k = 2.5;
        // striker rolling at 0.05 into a resting target: |va sum| = 0.05/s < 2 μ k J → stick
        let kick = collide([0.05, 0.0], [0.05 / s, 0.0], 1.0, 1.4, k);
        assert!(!kick.slip);
        assert!((kick.v[0]).abs() < 1e-17 && (kick.v[1] - 0.05).abs() < 1e-17);
        assert!((kick.va[0] - 0.025 / s).abs() < 1e-15 && (kick.va[1] + 0.025 / s).abs() < 1e-15);
        // weak friction: slip, both spins shift by μ k J (Eq. 4.14)
        let kick = collide([0.05, 0.0], [0.05 / s, 0.0], 1.0, 0.1, k);
        assert!(kick.slip);
        let dva = 0.1 * k * 0.05;
        assert!((kick.va[0] - (0.05 / s - dva)).abs() < 1e-15);
        assert!((kick.va[1] + dva).abs() < 1e-15);
    }
}
