//! The candidate physics library and the joint model's parameter layout.
//!
//! Global parameters are laid out as `[μ per material][T per material][extra terms…]`; each run
//! adds its own `[z0, t0, v0]`. An `Extra` is either a candidate physical term (with the effect id
//! the diagnosis uses) or a drift probe: a phenomenological term that only locates a mismatch.

use super::sim::{Drag, SimModel};
use super::G_MPS2;

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
            Extra::SpeedDriftT { .. } => "probe: T drifts with |v0|".into(),
            Extra::SpeedDriftMu { .. } => "probe: mu drifts with |v0|".into(),
            Extra::DirectionAsymmetry => "probe: mu and T differ by direction".into(),
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

/// Number of per-run parameters: z0 (m), t0 (s, kick before the first frame), v0 (m/s).
pub const N_LOCAL: usize = 3;

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
        self.extras
            .iter()
            .any(|e| matches!(e, Extra::PositionForce { .. }))
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
