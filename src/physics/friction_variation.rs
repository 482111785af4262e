//! How the groove's friction coefficient varies beyond its law in the slip speed: a factor on μ
//! by the direction of motion, by the position in the lab and by the slip speed.
//!
//! `μ_eff = μ(u) · (1 + δ_dir·dir) · (1 + p₁ P₁(x) + p₂ P₂(x)) · (1 + A sin(k z + φ))
//! · (1 + β (|u|/u_ref − 1)) · (1 + δ_s e^(−|u|/v_s))`, with `dir = ±1` the direction of motion, `x = (z − z_mid)/half_span`
//! held in [−1, 1] and P₁, P₂ the Legendre polynomials (a gradient and a curvature over the
//! observed stretch of groove), A, k, φ a periodic variation along the groove fixed in the lab
//! (a machining pattern, a texture), `u` the slip speed, δ_s and v_s a Stribeck rise of μ
//! towards zero slip (a static friction 1 + δ_s times the kinetic, falling off over v_s). The factor never goes below zero. It acts wherever friction acts: on the sliding
//! motion and on what friction can hold while rolling (at zero slip), and nowhere else, which is
//! what sets it apart from a force: a pure rolling phase does not feel it.

use serde::{Deserialize, Serialize};

/// The variation of μ beyond its law (every field 0: none).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionVariation {
    /// Relative difference by direction of motion: μ × (1 + by_direction · dir).
    pub by_direction: f64,
    /// Centre and half-length of the stretch the position variation is laid on (m; 0: none).
    pub z_mid_m: f64,
    pub half_span_m: f64,
    /// Relative gradient and curvature over that stretch (Legendre P₁, P₂ coefficients).
    pub by_position: [f64; 2],
    /// A periodic variation along the lab: relative amplitude A, wavenumber k (1/m), phase φ
    /// (rad); μ × (1 + A sin(k z + φ)). Zero amplitude: none.
    pub periodic: [f64; 3],
    /// Reference slip speed of the slip variation (m/s; 0: none).
    pub u_ref_mps: f64,
    /// Relative change of μ per u_ref of slip speed, about u_ref.
    pub by_slip: f64,
    /// A Stribeck rise at low slip: relative excess δ_s at zero slip and the slip speed v_s
    /// (m/s) over which it falls off; μ × (1 + δ_s e^(−|u|/v_s)). Zero v_s: none.
    pub stribeck: [f64; 2],
}

impl FrictionVariation {
    /// True when μ does not vary (the default).
    pub fn is_none(&self) -> bool {
        *self == FrictionVariation::default()
    }

    /// This variation with every part that `part` sets (its fields away from their defaults)
    /// taken from `part`: the parts of several forms, each setting its own, put together.
    pub fn with(self, part: FrictionVariation) -> FrictionVariation {
        let none = FrictionVariation::default();
        let take =
            |mine: f64, theirs: f64, default: f64| if theirs != default { theirs } else { mine };
        FrictionVariation {
            by_direction: take(self.by_direction, part.by_direction, none.by_direction),
            z_mid_m: take(self.z_mid_m, part.z_mid_m, none.z_mid_m),
            half_span_m: take(self.half_span_m, part.half_span_m, none.half_span_m),
            by_position: if part.by_position != none.by_position {
                part.by_position
            } else {
                self.by_position
            },
            periodic: if part.periodic != none.periodic {
                part.periodic
            } else {
                self.periodic
            },
            u_ref_mps: take(self.u_ref_mps, part.u_ref_mps, none.u_ref_mps),
            by_slip: take(self.by_slip, part.by_slip, none.by_slip),
            stribeck: if part.stribeck != none.stribeck {
                part.stribeck
            } else {
                self.stribeck
            },
        }
    }

    /// The factor on μ at lab position `z_m`, direction of motion `dir` and slip speed `slip_mps`.
    pub fn factor(&self, z_m: f64, dir: f64, slip_mps: f64) -> f64 {
        let mut f = 1.0 + self.by_direction * dir.signum();
        if self.half_span_m > 0.0 {
            let x = ((z_m - self.z_mid_m) / self.half_span_m).clamp(-1.0, 1.0);
            f *= 1.0 + self.by_position[0] * x + self.by_position[1] * 0.5 * (3.0 * x * x - 1.0);
        }
        let [amp, k, phase] = self.periodic;
        if amp != 0.0 {
            f *= 1.0 + amp * (k * z_m + phase).sin();
        }
        if self.u_ref_mps > 0.0 {
            f *= 1.0 + self.by_slip * (slip_mps.abs() / self.u_ref_mps - 1.0);
        }
        let [excess, v_s] = self.stribeck;
        if v_s > 0.0 {
            f *= 1.0 + excess * (-slip_mps.abs() / v_s).exp();
        }
        f.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::FrictionVariation;

    #[test]
    fn parts_set_by_different_forms_are_put_together() {
        let dir = FrictionVariation {
            by_direction: 0.1,
            ..FrictionVariation::default()
        };
        let texture = FrictionVariation {
            periodic: [0.05, 2000.0, 0.3],
            ..FrictionVariation::default()
        };
        let both = FrictionVariation::default().with(dir).with(texture);
        assert_eq!(both.by_direction, 0.1);
        assert_eq!(both.periodic, [0.05, 2000.0, 0.3]);
        let z: f64 = 0.004;
        let want = 1.1 * (1.0 + 0.05 * (2000.0 * z + 0.3).sin());
        assert!((both.factor(z, 1.0, 0.0) - want).abs() < 1e-12);
    }

    #[test]
    fn the_factor_is_one_without_variation_and_follows_each_part() {
        let none = FrictionVariation::default();
        assert_eq!(none.factor(0.003, -1.0, 0.02), 1.0);
        let dir = FrictionVariation {
            by_direction: 0.1,
            ..none
        };
        assert!((dir.factor(0.0, 1.0, 0.0) - 1.1).abs() < 1e-12);
        assert!((dir.factor(0.0, -1.0, 0.0) - 0.9).abs() < 1e-12);
        let pos = FrictionVariation {
            z_mid_m: 0.005,
            half_span_m: 0.005,
            by_position: [0.2, 0.0],
            ..none
        };
        assert!((pos.factor(0.010, 1.0, 0.0) - 1.2).abs() < 1e-12);
        assert!(
            (pos.factor(0.050, 1.0, 0.0) - 1.2).abs() < 1e-12,
            "held at the end"
        );
        let slip = FrictionVariation {
            u_ref_mps: 0.01,
            by_slip: -0.3,
            ..none
        };
        assert!((slip.factor(0.0, 1.0, 0.0) - 1.3).abs() < 1e-12);
        assert!((slip.factor(0.0, 1.0, 0.02) - 0.7).abs() < 1e-12);
        assert_eq!(slip.factor(0.0, 1.0, 0.1), 0.0, "never below zero");
        let stribeck = FrictionVariation {
            stribeck: [0.5, 0.01],
            ..none
        };
        assert!(
            (stribeck.factor(0.0, 1.0, 0.0) - 1.5).abs() < 1e-12,
            "static: 1 + δ_s"
        );
        assert!(
            (stribeck.factor(0.0, -1.0, -0.01) - (1.0 + 0.5 / std::f64::consts::E)).abs() < 1e-12
        );
        assert!(
            (stribeck.factor(0.0, 1.0, 1.0) - 1.0).abs() < 1e-12,
            "kinetic far above v_s"
        );
        let wave = FrictionVariation {
            periodic: [0.1, 1000.0, 0.5],
            ..none
        };
        let z = (std::f64::consts::FRAC_PI_2 - 0.5) / 1000.0;
        assert!((wave.factor(z, -1.0, 0.0) - 1.1).abs() < 1e-12, "the crest");
        assert!((wave.factor(z + std::f64::consts::PI / 1000.0, 1.0, 0.0) - 0.9).abs() < 1e-12);
    }
}
