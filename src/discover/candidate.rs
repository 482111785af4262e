//! The candidate physics library and the joint model's parameter layout.
//!
//! Global parameters are laid out as `[μ per material][T per material][extra terms…]`; each run
//! adds its own `[z0, t0, v0]`. An `Extra` is either a candidate physical term (with the effect id
//! the diagnosis uses) or a drift probe: a phenomenological term that only locates a mismatch.

use super::data::RunData;
pub use super::data::N_LOCAL;
use super::sim::{Drag, SimModel};
use super::G_MPS2;
use crate::physics::{SplineForce, Term, Variable};

/// One extra term of a joint model.
#[derive(Clone, Debug, PartialEq)]
pub enum Extra {
    /// a = −v/T − c·v|v| (c of either sign).
    QuadraticDrag,
    /// a = −v/(T0 + T'|v|); the per-material T become T0.
    SaturatingDrag,
    /// a = −c·g·sign(v).
    RollingResistance,
    /// a = −g·sin α, fixed lab-frame sign.
    GrooveTilt,
    /// μ(u) = μ∞·(1 − exp(−|u|/v_c)) of the slip speed u, v_c per material (fitted as ln v_c; a
    /// material whose v_c runs to the lower bound keeps a constant μ).
    VelocityFriction { materials: usize },
    /// a(z) = Σ_k a_k sin(πk(z−z_min)/span) + b_k cos(πk(z−z_min)/span), k = 1..harmonics.
    PositionForce {
        harmonics: usize,
        z_min_m: f64,
        span_m: f64,
    },
    /// a(z) = s·sin(k(z − z_ref)) + c·cos(k(z − z_ref)): a periodic force fixed in the lab
    /// (waviness) with free wavenumber k in [k_lo, k_hi].
    PeriodicZ { z_ref_m: f64, k_lo: f64, k_hi: f64 },
    /// a(z) = A·exp(−(z − z_c)²/(2w²)): a localized force fixed in the lab (a bump, a defect).
    Localized {
        z_lo: f64,
        z_hi: f64,
        w_lo: f64,
        w_hi: f64,
    },
    /// a(t) = A·sin(2π f t + φ_run), t since the kick, with each run's own phase (profiled).
    TimePeriodic { f_lo: f64, f_hi: f64 },
    /// μ differs by the direction of motion: μ_m·(1 + δ·dir) (friction, not a force: it acts
    /// while sliding and on the rolling hold only).
    FrictionDirection,
    /// μ varies along the lab: μ_m·(1 + p₁P₁(x) + p₂P₂(x)), x over the observed stretch.
    FrictionPosition { z_mid_m: f64, half_span_m: f64 },
    /// μ varies with the slip speed u: μ_m·(1 + β(|u|/u_ref − 1)), rising or falling.
    FrictionSlip { u_ref_mps: f64 },
    /// The camera distorts positions: z_meas = z + a₂P₂(x) + a₃P₃(x), x over the observed
    /// stretch (the linear part is a length scale, which μ and T absorb exactly).
    Distortion { z_mid_m: f64, half_span_m: f64 },
    /// The nonparametric model: a cubic B-spline in one variable with `segments` knot intervals.
    Spline {
        variable: Variable,
        lo: f64,
        dx: f64,
        segments: usize,
    },
    /// Probe: T of a run = T_m + β·(|v0| − v_ref).
    SpeedDriftT { v_ref_mps: f64 },
    /// Probe: μ of a run = μ_m + γ·(|v0| − v_ref).
    SpeedDriftMu { v_ref_mps: f64 },
    /// Probe: μ_m + δμ·dir and T_m·(1 + δT·dir), dir = ±1 the run's direction.
    DirectionAsymmetry,
}

/// Name, start, bounds and finite-difference step of one parameter.
#[derive(Clone, Debug)]
pub struct ParamInfo {
    pub name: String,
    pub start: f64,
    pub lo: f64,
    pub hi: f64,
    pub step: f64,
}

fn p(name: &str, start: f64, lo: f64, hi: f64, step: f64) -> ParamInfo {
    ParamInfo {
        name: name.to_string(),
        start,
        lo,
        hi,
        step,
    }
}

impl Extra {
    /// The diagnosis effect id, or None for a probe.
    pub fn effect(&self) -> Option<&'static str> {
        match self {
            Extra::QuadraticDrag | Extra::SaturatingDrag => Some("velocity_dependent_drag"),
            Extra::RollingResistance => Some("rolling_resistance"),
            Extra::GrooveTilt => Some("groove_tilt"),
            Extra::VelocityFriction { .. } => Some("velocity_dependent_friction"),
            Extra::PositionForce { .. } => Some("position_dependent_force"),
            Extra::PeriodicZ { .. } | Extra::Localized { .. } => Some("position_dependent_force"),
            Extra::TimePeriodic { .. } => Some("time_dependent_force"),
            Extra::Spline { .. } => Some("unexplained"),
            Extra::FrictionDirection => Some("direction_dependent_friction"),
            Extra::FrictionPosition { .. } => Some("position_dependent_friction"),
            Extra::FrictionSlip { .. } => Some("velocity_dependent_friction"),
            Extra::Distortion { .. } => Some("position_distortion"),
            _ => None,
        }
    }

    /// A short label of the term's form (also names probes).
    pub fn form(&self) -> String {
        match self {
            Extra::QuadraticDrag => "quadratic: a = -v/T - c v|v|".into(),
            Extra::SaturatingDrag => "saturating: a = -v/(T0 + T'|v|)".into(),
            Extra::RollingResistance => "constant resistance: a = -c g sign(v)".into(),
            Extra::GrooveTilt => "tilt: a = -g sin(alpha)".into(),
            Extra::VelocityFriction { .. } => {
                "mu(u) = mu_inf (1 - exp(-|u|/v_c)), u slip speed".into()
            }
            Extra::PositionForce { harmonics, .. } => {
                format!("a(z) = Fourier series over the observed z range, {harmonics} harmonics")
            }
            Extra::PeriodicZ { .. } => {
                "periodic in z: a = A sin(2 pi z / lambda + phi), fixed in the lab".into()
            }
            Extra::Localized { .. } => {
                "localized in z: a = A exp(-(z - z_c)^2 / (2 w^2)), fixed in the lab".into()
            }
            Extra::TimePeriodic { .. } => {
                "periodic in time: a = A sin(2 pi f t + phi_run), t since the kick, a phase per run"
                    .into()
            }
            Extra::Spline {
                variable, segments, ..
            } => format!(
                "spline in {}: a = cubic B-spline with {} coefficients (no named form)",
                variable.label(),
                segments + 3
            ),
            Extra::FrictionDirection => {
                "mu by direction: mu (1 + delta dir), while sliding and holding".into()
            }
            Extra::FrictionPosition { .. } => {
                "mu along the groove: mu (1 + p1 P1(x) + p2 P2(x)), fixed in the lab".into()
            }
            Extra::FrictionSlip { .. } => {
                "mu(u) = mu (1 + beta (|u|/u_ref - 1)), u slip speed".into()
            }
            Extra::Distortion { .. } => {
                "distortion: z_meas = z + a2 P2(x) + a3 P3(x), x across the image".into()
            }
            Extra::SpeedDriftT { .. } => "probe: T drifts with |v0|".into(),
            Extra::SpeedDriftMu { .. } => "probe: mu drifts with |v0|".into(),
            Extra::DirectionAsymmetry => "probe: mu and T differ by direction".into(),
        }
    }

    /// What the term's size is called in words ("a groove tilt").
    pub fn size_name(&self) -> &'static str {
        match self {
            Extra::QuadraticDrag => "a quadratic drag coefficient",
            Extra::SaturatingDrag => "a saturating drag slope T'",
            Extra::RollingResistance => "a rolling resistance",
            Extra::GrooveTilt => "a groove tilt",
            Extra::VelocityFriction { .. } => "a velocity-dependent friction",
            Extra::PositionForce { .. } | Extra::PeriodicZ { .. } => "a periodic force in z",
            Extra::Localized { .. } => "a localized force",
            Extra::TimePeriodic { .. } => "a periodic force in time",
            Extra::Spline { .. } => "a smooth force",
            Extra::FrictionDirection => "a difference of friction by direction",
            Extra::FrictionPosition { .. } => "a variation of friction along the groove",
            Extra::FrictionSlip { .. } => "a slip-speed dependence of friction",
            Extra::Distortion { .. } => "a distortion of the measured positions",
            _ => "a drift",
        }
    }

    /// Degrees of freedom that bound the shape of the gamma law fitted to the term's bootstrap
    /// null (`NullFit::from_replicates`): its parameter count, except for a force in time with a
    /// phase per run, whose statistic (Σ|b_r|)²/Σa_r sums a Rayleigh draw per run and so sits far
    /// from zero with a narrow spread, like a χ² of two per run. Bounded by its two parameters, the
    /// law came out so wide that a 0.15 m/s² vibration at 120 Hz (LR 510 against replicates
    /// near 200) read p = 0.012 before Holm, below the detection limit the report states.
    pub fn null_df(&self, runs: usize) -> f64 {
        match self {
            Extra::TimePeriodic { .. } => (2 * runs.max(1)) as f64,
            e => e.params().len() as f64,
        }
    }

    /// Parameters of the term, starting at the value that makes it vanish (or nearly).
    pub fn params(&self) -> Vec<ParamInfo> {
        match self {
            Extra::QuadraticDrag => vec![p("c_per_m", 0.0, -1e3, 1e3, 1e-2)],
            Extra::SaturatingDrag => vec![p("tp_s_per_mps", 0.0, 0.0, 1e3, 1e-3)],
            Extra::RollingResistance => vec![p("c", 0.0, 0.0, 0.5, 1e-6)],
            Extra::GrooveTilt => vec![p("alpha_deg", 0.0, -10.0, 10.0, 1e-4)],
            Extra::VelocityFriction { materials } => (0..*materials)
                .map(|m| p(&format!("ln_vc_mps_{m}"), (1e-4f64).ln(), -14.0, 0.0, 1e-3))
                .collect(),
            Extra::PositionForce { harmonics, .. } => (1..=*harmonics)
                .flat_map(|k| {
                    [
                        p(&format!("sin{k}_mps2"), 0.0, -5.0, 5.0, 1e-4),
                        p(&format!("cos{k}_mps2"), 0.0, -5.0, 5.0, 1e-4),
                    ]
                })
                .collect(),
            Extra::PeriodicZ { k_lo, k_hi, .. } => vec![
                p("k_per_m", 0.5 * (k_lo + k_hi), *k_lo, *k_hi, 1e-7 * k_hi),
                p("sin_mps2", 0.0, -5.0, 5.0, 1e-4),
                p("cos_mps2", 0.0, -5.0, 5.0, 1e-4),
            ],
            Extra::Localized {
                z_lo,
                z_hi,
                w_lo,
                w_hi,
            } => vec![
                p("amplitude_mps2", 0.0, -5.0, 5.0, 1e-4),
                p("centre_m", 0.5 * (z_lo + z_hi), *z_lo, *z_hi, 1e-8),
                p("width_m", (w_lo * w_hi).sqrt(), *w_lo, *w_hi, 1e-8),
            ],
            Extra::TimePeriodic { f_lo, f_hi } => vec![
                p("frequency_hz", 0.5 * (f_lo + f_hi), *f_lo, *f_hi, 1e-3),
                p("amplitude_mps2", 0.0, 0.0, 5.0, 1e-4),
            ],
            Extra::Spline { segments, .. } => (0..segments + 3)
                .map(|j| p(&format!("coef{j}_mps2"), 0.0, -20.0, 20.0, 1e-4))
                .collect(),
            Extra::FrictionDirection => vec![p("delta_dir", 0.0, -0.9, 0.9, 1e-5)],
            Extra::FrictionPosition { .. } => vec![
                p("p1_rel", 0.0, -0.9, 0.9, 1e-5),
                p("p2_rel", 0.0, -0.9, 0.9, 1e-5),
            ],
            Extra::FrictionSlip { .. } => vec![p("beta_rel", 0.0, -0.95, 5.0, 1e-5)],
            Extra::Distortion { .. } => vec![
                p("a2_m", 0.0, -1e-3, 1e-3, 1e-9),
                p("a3_m", 0.0, -1e-3, 1e-3, 1e-9),
            ],
            Extra::SpeedDriftT { .. } => vec![p("dT_dv_s_per_mps", 0.0, -1e3, 1e3, 1e-3)],
            Extra::SpeedDriftMu { .. } => vec![p("dmu_dv_s_per_m", 0.0, -1e3, 1e3, 1e-4)],
            Extra::DirectionAsymmetry => vec![
                p("dmu_dir", 0.0, -0.5, 0.5, 1e-5),
                p("dT_rel_dir", 0.0, -0.9, 0.9, 1e-5),
            ],
        }
    }
}

/// The structure of a joint model: materials and the extra terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    pub n_materials: usize,
    pub s: f64,
    pub k: f64,
    pub extras: Vec<Extra>,
}

impl Spec {
    pub fn with(&self, extra: Extra) -> Spec {
        let mut s = self.clone();
        s.extras.push(extra);
        s
    }

    /// Every global parameter, in layout order, named with the material names.
    pub fn global_params(&self, materials: &[String]) -> Vec<ParamInfo> {
        let saturating = self.extras.contains(&Extra::SaturatingDrag);
        let mut out = Vec::new();
        for m in materials.iter().take(self.n_materials) {
            out.push(p(&format!("mu_{m}"), 0.3, 1e-3, 2.0, 1e-5));
        }
        for m in materials.iter().take(self.n_materials) {
            let name = if saturating { "t0_s" } else { "t_s" };
            out.push(p(&format!("{name}_{m}"), 0.08, 1e-3, 1e3, 1e-5));
        }
        for e in &self.extras {
            let mut ps = e.params();
            if let Extra::VelocityFriction { .. } = e {
                for (p, m) in ps.iter_mut().zip(materials) {
                    p.name = format!("ln_vc_mps_{m}");
                }
            }
            out.extend(ps);
        }
        out
    }

    pub fn n_global(&self) -> usize {
        2 * self.n_materials + self.extras.iter().map(|e| e.params().len()).sum::<usize>()
    }

    /// Offset of extra `i` in the global vector.
    pub fn extra_offset(&self, i: usize) -> usize {
        2 * self.n_materials
            + self.extras[..i]
                .iter()
                .map(|e| e.params().len())
                .sum::<usize>()
    }

    /// Global parameters a run of `material` depends on.
    pub fn affecting(&self, material: usize) -> Vec<usize> {
        let mut v = vec![material, self.n_materials + material];
        v.extend(2 * self.n_materials..self.n_global());
        v
    }

    /// True when z0 enters other than as an additive offset (a position-dependent force).
    pub fn position_dependent(&self) -> bool {
        self.extras.iter().any(|e| {
            matches!(
                e,
                Extra::PositionForce { .. }
                    | Extra::PeriodicZ { .. }
                    | Extra::Localized { .. }
                    | Extra::FrictionPosition { .. }
                    | Extra::Distortion { .. }
                    | Extra::Spline {
                        variable: Variable::Z,
                        ..
                    }
            )
        })
    }

    /// True when a term has a phase of its own in each run (profiled in `run_model`).
    pub fn has_run_phase(&self) -> bool {
        self.extras
            .iter()
            .any(|e| matches!(e, Extra::TimePeriodic { .. }))
    }

    /// The physics of one run, with each run's own phase of a time-periodic force chosen to fit
    /// the run's recorded positions best (locals `l` = z0, t0, v0).
    pub fn run_model(&self, g: &[f64], l: &[f64; N_LOCAL], run: &RunData) -> SimModel {
        let mut m = self.sim_model(g, run.material, l[2]);
        if self.has_run_phase() {
            super::timeforce::profile_phase(&mut m, l, run);
        }
        m
    }

    /// The physics of one run for global parameters `g` and the run's v0.
    pub fn sim_model(&self, g: &[f64], material: usize, v0_mps: f64) -> SimModel {
        let mut mu = g[material];
        let mut t_s = g[self.n_materials + material];
        let mut m = SimModel {
            s: self.s,
            k: self.k,
            mu,
            vc_mps: None,
            drag: Drag::Quadratic { t_s, c_per_m: 0.0 },
            roll_c: 0.0,
            tilt_mps2: 0.0,
            position: Vec::new(),
            terms: Vec::new(),
            variation: Default::default(),
            distortion: None,
        };
        let mut quad = 0.0;
        let mut tp = None;
        for (i, e) in self.extras.iter().enumerate() {
            let x = &g[self.extra_offset(i)..];
            match e {
                Extra::QuadraticDrag => quad = x[0],
                Extra::SaturatingDrag => tp = Some(x[0]),
                Extra::RollingResistance => m.roll_c = x[0],
                Extra::GrooveTilt => m.tilt_mps2 = -G_MPS2 * x[0].to_radians().sin(),
                Extra::VelocityFriction { .. } => m.vc_mps = Some(x[material].exp()),
                Extra::PositionForce {
                    harmonics,
                    z_min_m,
                    span_m,
                } => {
                    for kk in 0..*harmonics {
                        let (a, b) = (x[2 * kk], x[2 * kk + 1]);
                        let kz = std::f64::consts::PI * (kk + 1) as f64 / span_m;
                        // a sin(u) + b cos(u) = A sin(u + atan2(b, a)), u = kz (z − z_min)
                        let amp = a.hypot(b);
                        if amp > 0.0 {
                            m.position.push((amp, kz, b.atan2(a) - kz * z_min_m));
                        }
                    }
                }
                Extra::PeriodicZ { z_ref_m, .. } => {
                    let (k, a, b) = (x[0], x[1], x[2]);
                    let amp = a.hypot(b);
                    if amp > 0.0 {
                        m.position.push((amp, k, b.atan2(a) - k * z_ref_m));
                    }
                }
                Extra::Localized { .. } => m.terms.push(Term::LocalizedForce {
                    amp_mps2: x[0],
                    centre_m: x[1],
                    width_m: x[2],
                }),
                Extra::TimePeriodic { .. } => m.terms.push(Term::TimePeriodicForce {
                    amp_mps2: x[1],
                    freq_hz: x[0],
                    phase_rad: 0.0,
                }),
                Extra::Spline {
                    variable,
                    lo,
                    dx,
                    segments,
                } => m.terms.push(Term::Spline(SplineForce {
                    variable: *variable,
                    lo_x: *lo,
                    dx: *dx,
                    coefs_mps2: x[..segments + 3].to_vec(),
                })),
                Extra::FrictionDirection => m.variation.by_direction = x[0],
                Extra::FrictionPosition {
                    z_mid_m,
                    half_span_m,
                } => {
                    m.variation.z_mid_m = *z_mid_m;
                    m.variation.half_span_m = *half_span_m;
                    m.variation.by_position = [x[0], x[1]];
                }
                Extra::FrictionSlip { u_ref_mps } => {
                    m.variation.u_ref_mps = *u_ref_mps;
                    m.variation.by_slip = x[0];
                }
                Extra::Distortion {
                    z_mid_m,
                    half_span_m,
                } => {
                    m.distortion = Some(super::sim::Distortion {
                        z_mid_m: *z_mid_m,
                        half_span_m: *half_span_m,
                        a2_m: x[0],
                        a3_m: x[1],
                    })
                }
                Extra::SpeedDriftT { v_ref_mps } => t_s += x[0] * (v0_mps.abs() - v_ref_mps),
                Extra::SpeedDriftMu { v_ref_mps } => mu += x[0] * (v0_mps.abs() - v_ref_mps),
                Extra::DirectionAsymmetry => {
                    let dir = v0_mps.signum();
                    mu += x[0] * dir;
                    t_s *= 1.0 + x[1] * dir;
                }
            }
        }
        m.mu = mu.max(1e-6);
        let t_s = t_s.max(1e-4);
        m.drag = match tp {
            Some(tp) => Drag::Saturating {
                t0_s: t_s,
                tp_s_per_mps: tp,
            },
            None => Drag::Quadratic { t_s, c_per_m: quad },
        };
        m
    }
}
/// Predicted positions of `run` at its sample times.
pub fn predict(spec: &Spec, g: &[f64], l: &[f64; N_LOCAL], run: &RunData, out: &mut [f64]) {
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let model = spec.run_model(g, l, run);
    model.simulate(l[0], l[2], &tt, out, None, None);
}
