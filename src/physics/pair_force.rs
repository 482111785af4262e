//! A force between the two particles of a pair that acts before they touch (adhesion, a liquid
//! bridge, magnetization, charge), as a function of their separation s = centre distance − 2R.
//!
//! Each particle feels `a(s)` along the line of centres (per unit mass, m/s²), pushing the two
//! apart when `a > 0` and pulling them together when `a < 0`. Two named shapes:
//! - exponential, `a(s) = A e^{−s/λ}` (a screened interaction, a bridge that thins);
//! - power law, `a(s) = A (1 + s/λ)^{−n}`, n > 1 (van der Waals–like at λ ≪ R, a dipole's
//!   r⁻⁴ at λ = 2R, n = 4); its large-n limit at fixed λ/n is the exponential.
//!
//! The size the data fix best for a short range is the work the force does per unit mass over
//! its whole range, `W = ∫₀^∞ a(s) ds` (m²/s²): `Aλ` and `Aλ/(n − 1)`; an attraction of work W
//! raises an approach speed v to √(v² + 2·2W) at contact (both particles are pulled).
//!
//! While the particles touch, an attraction is held by the contact itself (the normal force
//! balances it; see `on_particle`); a pair that has come to move together under an attraction is
//! held as one body until the contact would pull (`pair`), and the contact's friction brakes both
//! spins while they turn the same way (`pair::PairParams::contact_friction`): a pair held together
//! rolls to rest.

use serde::{Deserialize, Serialize};

/// The force between the two particles of a pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairForce {
    /// `A e^{−s/λ}`.
    Exponential { amp_mps2: f64, range_m: f64 },
    /// `A (1 + s/λ)^{−n}`.
    PowerLaw {
        amp_mps2: f64,
        range_m: f64,
        exponent: f64,
    },
}

impl PairForce {
    /// The acceleration of each particle at separation `gap_m` (> 0 apart, < 0 together); at a
    /// negative gap (rounding at contact) the contact value.
    pub fn accel(&self, gap_m: f64) -> f64 {
        let s = gap_m.max(0.0);
        match *self {
            PairForce::Exponential { amp_mps2, range_m } => amp_mps2 * (-s / range_m).exp(),
            PairForce::PowerLaw {
                amp_mps2,
                range_m,
                exponent,
            } => amp_mps2 * (1.0 + s / range_m).powf(-exponent),
        }
    }

    /// The force's amplitude at contact, A (m/s²).
    pub fn amplitude_mps2(&self) -> f64 {
        match *self {
            PairForce::Exponential { amp_mps2, .. } | PairForce::PowerLaw { amp_mps2, .. } => {
                amp_mps2
            }
        }
    }

    /// The work per unit mass over the whole range, ∫₀^∞ a(s) ds (m²/s²; infinite for a power
    /// law with n ≤ 1).
    pub fn work_m2ps2(&self) -> f64 {
        match *self {
            PairForce::Exponential { amp_mps2, range_m } => amp_mps2 * range_m,
            PairForce::PowerLaw {
                amp_mps2,
                range_m,
                exponent,
            } if exponent > 1.0 => amp_mps2 * range_m / (exponent - 1.0),
            PairForce::PowerLaw { amp_mps2, .. } => amp_mps2.signum() * f64::INFINITY,
        }
    }

    /// The separation within which the force does all but a fraction `1/e³` (5 %) of its
    /// work: 3λ, and λ(e^{3/(n−1)} − 1) for the power law.
    pub fn reach_m(&self) -> f64 {
        match *self {
            PairForce::Exponential { range_m, .. } => 3.0 * range_m,
            PairForce::PowerLaw {
                range_m, exponent, ..
            } => range_m * ((3.0 / (exponent - 1.0).max(1e-3)).exp() - 1.0),
        }
    }

    /// The accelerations of the lower-z and the upper-z particle at separation `gap_m`: while
    /// they touch an attraction is held by the contact (both 0), whichever way they move. Had it
    /// been released as soon as they separate, the right-hand side would jump each time a
    /// touching pair's relative speed crossed zero, and the integrator crawled there (minutes per
    /// simulation of an attracted pair under a waviness); what the rule leaves out is the
    /// attraction over the contact's rounding slack, 10⁻¹³ m.
    pub fn on_particle(&self, gap_m: f64, touching: bool) -> [f64; 2] {
        let a = self.accel(gap_m);
        if touching && a < 0.0 {
            return [0.0, 0.0];
        }
        [-a, a]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_work_is_the_integral_of_the_force_over_its_range() {
        let forms = [
            PairForce::Exponential {
                amp_mps2: -0.8,
                range_m: 30e-6,
            },
            PairForce::PowerLaw {
                amp_mps2: 0.5,
                range_m: 20e-6,
                exponent: 3.0,
            },
        ];
        for f in forms {
            // trapezoids on a log grid out to 1e4 ranges
            let (mut sum, mut prev) = (0.0, (0.0, f.accel(0.0)));
            for k in 1..=20_000 {
                let s = 1e-9 * (1e-1f64 / 1e-9).powf(k as f64 / 20_000.0);
                let a = f.accel(s);
                sum += 0.5 * (a + prev.1) * (s - prev.0);
                prev = (s, a);
            }
            let w = f.work_m2ps2();
            assert!((sum - w).abs() < 2e-3 * w.abs(), "{f:?}: {sum} vs {w}");
            // the reach holds 95 % of the work
            let (mut inside, mut prev) = (0.0, (0.0, f.accel(0.0)));
            for k in 1..=20_000 {
                let s = f.reach_m() * k as f64 / 20_000.0;
                let a = f.accel(s);
                inside += 0.5 * (a + prev.1) * (s - prev.0);
                prev = (s, a);
            }
            let share = inside / w;
            assert!((share - 0.9502).abs() < 2e-3, "{f:?}: {share}");
        }
    }

    #[test]
    fn an_attraction_at_contact_is_held_by_the_contact_but_not_a_repulsion() {
        let pull = PairForce::Exponential {
            amp_mps2: -1.0,
            range_m: 1e-5,
        };
        assert_eq!(pull.on_particle(0.0, true), [0.0, 0.0]);
        assert_eq!(pull.on_particle(1e-5, false)[1], -(-1.0f64).exp());
        let push = PairForce::Exponential {
            amp_mps2: 1.0,
            range_m: 1e-5,
        };
        assert_eq!(push.on_particle(0.0, true), [-1.0, 1.0]);
    }
}
