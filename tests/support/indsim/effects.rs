//! Drag laws, extra forces (fixed in the lab, in time, in velocity) and friction laws.

use super::model::G;

/// The drag on the particle.
#[derive(Clone, Debug)]
pub enum Drag {
    /// a = −v/T.
    Linear { t_s: f64 },
    /// a = −v/T − c v|v|.
    Quadratic { t_s: f64, c_per_m: f64 },
    /// a = −v/(T0 + T'|v|).
    Saturating { t0_s: f64, tp_s_per_mps: f64 },
}

impl Drag {
    pub fn accel(&self, v: f64) -> f64 {
        match *self {
            Drag::Linear { t_s } => -v / t_s,
            Drag::Quadratic { t_s, c_per_m } => -v / t_s - c_per_m * v * v.abs(),
            Drag::Saturating { t0_s, tp_s_per_mps } => -v / (t0_s + tp_s_per_mps * v.abs()),
        }
    }

    /// The linear time constant (T or T0).
    pub fn t_s(&self) -> f64 {
        match *self {
            Drag::Linear { t_s } | Drag::Quadratic { t_s, .. } => t_s,
            Drag::Saturating { t0_s, .. } => t0_s,
        }
    }

    /// The same law with its linear time constant replaced.
    pub fn with_t_s(&self, t: f64) -> Drag {
        match *self {
            Drag::Linear { .. } => Drag::Linear { t_s: t },
            Drag::Quadratic { c_per_m, .. } => Drag::Quadratic { t_s: t, c_per_m },
            Drag::Saturating { tp_s_per_mps, .. } => Drag::Saturating {
                t0_s: t,
                tp_s_per_mps,
            },
        }
    }
}

/// An extra acceleration along the groove (z in the lab, t since the kick).
#[derive(Clone, Debug)]
pub enum Force {
    /// a = −c g sign(v): a resistance against motion.
    Resistance { c: f64 },
    /// a = −g sin α.
    Tilt { alpha_rad: f64 },
    /// a = A sin(2π z/λ + φ).
    Periodic {
        amp: f64,
        wavelength_m: f64,
        phase: f64,
    },
    /// a = A exp(−(z − z_c)²/(2w²)).
    Localized {
        amp: f64,
        centre_m: f64,
        width_m: f64,
    },
    /// a = A (1 + tanh((z − z_s)/w))/2: a force that switches on past z_s.
    Step { amp: f64, z_m: f64, width_m: f64 },
    /// a = Σ A_i sin(k_i z + φ_i): a smooth random field in z.
    Field { modes: Vec<(f64, f64, f64)> },
    /// a = A sin(2π f t + φ).
    Time { amp: f64, freq_hz: f64, phase: f64 },
    /// a = −A sign(v) exp(−(|v| − v_c)²/(2w²)): a resistance only in a band of speeds.
    SpeedBump { amp: f64, v_c: f64, width: f64 },
}

impl Force {
    /// Acceleration at `z`, `v`, `t`; `dir` is the direction of motion (sign of v, or the trial
    /// direction at rest).
    pub fn accel(&self, z: f64, v: f64, t: f64, dir: f64) -> f64 {
        use std::f64::consts::TAU;
        match self {
            Force::Resistance { c } => -c * G * dir,
            Force::Tilt { alpha_rad } => -G * alpha_rad.sin(),
            Force::Periodic {
                amp,
                wavelength_m,
                phase,
            } => amp * (TAU * z / wavelength_m + phase).sin(),
            Force::Localized {
                amp,
                centre_m,
                width_m,
            } => {
                let x = (z - centre_m) / width_m;
                amp * (-0.5 * x * x).exp()
            }
            Force::Step { amp, z_m, width_m } => 0.5 * amp * (1.0 + ((z - z_m) / width_m).tanh()),
            Force::Field { modes } => modes.iter().map(|(a, k, p)| a * (k * z + p).sin()).sum(),
            Force::Time {
                amp,
                freq_hz,
                phase,
            } => amp * (TAU * freq_hz * t + phase).sin(),
            Force::SpeedBump { amp, v_c, width } => {
                let x = (v.abs() - v_c) / width;
                -amp * dir * (-0.5 * x * x).exp()
            }
        }
    }
}

/// How the particle–groove friction coefficient varies around its base value μ.
#[derive(Clone, Debug)]
pub enum FrictionLaw {
    Constant,
    /// μ (1 + δ sin(2π z/λ + φ)), z in the lab.
    Position {
        delta: f64,
        wavelength_m: f64,
        phase: f64,
    },
    /// μ + Δμ between z_a and z_b in the lab (edges smoothed over `edge_m`).
    Patch {
        delta_mu: f64,
        z_a: f64,
        z_b: f64,
        edge_m: f64,
    },
    /// μ (1 − exp(−|u|/v_c)): rising with slip speed; the hold uses μ.
    SlipRising {
        v_c: f64,
    },
    /// μ (1 + δ exp(−|u|/v_c)): falling with slip speed; the hold uses μ (1 + δ).
    SlipFalling {
        delta: f64,
        v_c: f64,
    },
    /// μ (1 + δ sign(v)): different for motion towards +z and −z.
    Direction {
        delta: f64,
    },
}

impl FrictionLaw {
    /// The coefficient at `z` for slip speed `slip` (None: the static hold), moving in `dir`.
    pub fn mu(&self, mu: f64, z: f64, slip: Option<f64>, dir: f64) -> f64 {
        use std::f64::consts::TAU;
        match *self {
            FrictionLaw::Constant => mu,
            FrictionLaw::Position {
                delta,
                wavelength_m,
                phase,
            } => mu * (1.0 + delta * (TAU * z / wavelength_m + phase).sin()),
            FrictionLaw::Patch {
                delta_mu,
                z_a,
                z_b,
                edge_m,
            } => {
                let on = 0.25
                    * (1.0 + ((z - z_a) / edge_m).tanh())
                    * (1.0 + ((z_b - z) / edge_m).tanh());
                mu + delta_mu * on
            }
            FrictionLaw::SlipRising { v_c } => match slip {
                Some(u) => mu * (1.0 - (-u / v_c).exp()),
                None => mu,
            },
            FrictionLaw::SlipFalling { delta, v_c } => {
                mu * (1.0 + delta * (-slip.unwrap_or(0.0) / v_c).exp())
            }
            FrictionLaw::Direction { delta } => mu * (1.0 + delta * dir),
        }
    }
}
