//! One-particle trajectories for the discovery fits: baseline friction plus any candidate terms.
//!
//! `SimModel` is the flat, per-run physics a candidate model expands to; `simulate` samples it with
//! `physics::simulate`. The tests hold that integrator to an independent fixed-step reference
//! (`tests/discover_data/reference.rs`).

use super::G_MPS2;

/// How the drag depends on speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Drag {
    /// a = −v/T − c·v|v| (c = 0: the baseline linear drag).
    Quadratic { t_s: f64, c_per_m: f64 },
    /// a = −v/(T0 + T'|v|).
    Saturating { t0_s: f64, tp_s_per_mps: f64 },
}

/// The physics of one run, flattened.
#[derive(Clone, Debug, PartialEq)]
pub struct SimModel {
    /// sin(θ/2) of the groove.
    pub s: f64,
    /// m R² / I (5/2 for a solid sphere).
    pub k: f64,
    /// Coulomb friction (the high-slip limit when `vc_mps` is set).
    pub mu: f64,
    /// Velocity-dependent friction μ(u) = μ·(1 − exp(−|u|/v_c)), u the slip speed; None: constant.
    pub vc_mps: Option<f64>,
    pub drag: Drag,
    /// Rolling resistance c (dimensionless): a = −c·g·sign(v).
    pub roll_c: f64,
    /// Constant lab-frame acceleration (groove tilt: −g sin α).
    pub tilt_mps2: f64,
    /// Position-dependent force terms: a = amp·sin(kz·z + phase), as (amp_mps2, kz_per_m, phase_rad).
    pub position: Vec<(f64, f64, f64)>,
    /// Further physics terms (localized, step, time-periodic and spline forces), passed to the
    /// integrator as they are.
    pub terms: Vec<crate::physics::Term>,
    /// The index in `terms` of the force periodic in time whose phase each run profiles
    /// (`timeforce.rs`); a force periodic in time with one phase for every run is not it.
    pub phased_term: Option<usize>,
    /// How μ varies with direction, position and slip speed (none by default).
    pub variation: crate::physics::FrictionVariation,
    /// What the camera does to the positions (None: it records them as they are).
    pub distortion: Option<Distortion>,
}

/// A smooth distortion of the measured positions across the image: `z_meas = z + a₂P₂(x) +
/// a₃P₃(x)`, `x = (z − z_mid)/half_span` (Legendre polynomials: no constant or linear part,
/// which the run's offset and the physics' scale take).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distortion {
    pub z_mid_m: f64,
    pub half_span_m: f64,
    pub a2_m: f64,
    pub a3_m: f64,
}

impl Distortion {
    /// The measured position of a particle at `z_m`.
    pub fn measured(&self, z_m: f64) -> f64 {
        let x = (z_m - self.z_mid_m) / self.half_span_m.max(1e-9);
        z_m + self.a2_m * 0.5 * (3.0 * x * x - 1.0) + self.a3_m * 0.5 * (5.0 * x * x * x - 3.0 * x)
    }
}

/// Motion phase at a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Motion {
    Sliding,
    Rolling,
    Rest,
}

impl SimModel {
    /// The chapter's model alone: Coulomb friction μ and a linear drag of time T, in a groove of
    /// sin(θ/2) = `s` and m R²/I = `k`, with no further term.
    pub fn baseline(s: f64, k: f64, mu: f64, t_s: f64) -> SimModel {
        SimModel {
            s,
            k,
            mu,
            vc_mps: None,
            drag: Drag::Quadratic { t_s, c_per_m: 0.0 },
            roll_c: 0.0,
            tilt_mps2: 0.0,
            position: Vec::new(),
            terms: Vec::new(),
            phased_term: None,
            variation: Default::default(),
            distortion: None,
        }
    }

    /// The same physics as a `physics::Model` (for cross-checks against the event-driven integrator).
    pub fn to_physics(&self) -> crate::physics::Model {
        use crate::physics::{Friction, Groove, Model, Term};
        let mut terms = vec![match self.drag {
            Drag::Quadratic { t_s, .. } => Term::LinearDrag { t_s },
            Drag::Saturating { t0_s, tp_s_per_mps } => Term::SaturatingDrag { t0_s, tp_s_per_mps },
        }];
        if let Drag::Quadratic { c_per_m, .. } = self.drag {
            if c_per_m != 0.0 {
                terms.push(Term::QuadraticDrag { c_per_m });
            }
        }
        if self.roll_c != 0.0 {
            terms.push(Term::RollingResistance { c: self.roll_c });
        }
        if self.tilt_mps2 != 0.0 {
            terms.push(Term::GrooveTilt {
                alpha_deg: (-self.tilt_mps2 / G_MPS2).asin().to_degrees(),
            });
        }
        for &(amp_mps2, kz, phase_rad) in &self.position {
            terms.push(Term::PositionForce {
                amp_mps2,
                wavelength_m: std::f64::consts::TAU / kz,
                phase_rad,
            });
        }
        terms.extend(self.terms.iter().cloned());
        Model {
            groove: Groove {
                s: self.s,
                k: self.k,
            },
            friction: match self.vc_mps {
                None => Friction::Constant { mu: self.mu },
                Some(v_c_mps) => Friction::VelocityDependent {
                    mu_inf: self.mu,
                    v_c_mps,
                },
            },
            variation: self.variation,
            terms,
        }
    }

    /// Positions (and speeds, phases if asked) at sorted times t_s ≥ 0, from z0, v0 and no spin at
    /// t = 0, by the event-driven integrator of `physics` (adaptive, events located). True when
    /// the simulation stopped at its step budget before the last time (its state held from there).
    pub fn simulate(
        &self,
        z0_m: f64,
        v0_mps: f64,
        t_s: &[f64],
        z_out: &mut [f64],
        v_out: Option<&mut [f64]>,
        phase_out: Option<&mut [Motion]>,
    ) -> bool {
        let init = crate::physics::State {
            z_m: z0_m,
            v_mps: v0_mps,
            va_mps: 0.0,
        };
        let traj = crate::physics::simulate(&self.to_physics(), init, t_s);
        z_out.copy_from_slice(&traj.z_m);
        if let Some(d) = &self.distortion {
            z_out.iter_mut().for_each(|z| *z = d.measured(*z));
        }
        if let Some(v) = v_out {
            v.copy_from_slice(&traj.v_mps);
        }
        if let Some(p) = phase_out {
            for (o, ph) in p.iter_mut().zip(&traj.phase) {
                *o = match ph {
                    crate::physics::Phase::Sliding => Motion::Sliding,
                    crate::physics::Phase::Rolling => Motion::Rolling,
                    crate::physics::Phase::Rest => Motion::Rest,
                };
            }
        }
        traj.stalled
    }
}
