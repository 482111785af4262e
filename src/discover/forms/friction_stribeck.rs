//! μ falling with the slip speed (a Stribeck curve): μ_m·(1 + δ_s e^(−|u|/v_s)), a static
//! friction 1 + δ_s times the kinetic μ_m at zero slip that falls off over the slip speed v_s.
//! Fitted as δ_s ≥ 0 and ln v_s; screened at a few trial v_s, since at δ_s = 0 the data say
//! nothing of v_s.

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::FrictionVariation;
use std::collections::BTreeMap;

/// The slip speeds the screen tries v_s at (m/s): from a few frames' worth of a sliding
/// phase's deceleration to the fastest kicks.
const TRIAL_VS_MPS: [f64; 4] = [2e-3, 6e-3, 2e-2, 6e-2];

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionStribeck;

impl Form for FrictionStribeck {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(FrictionStribeck)
    }
    fn name(&self) -> &'static str {
        "friction_stribeck"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("velocity_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "Stribeck: mu(u) = mu (1 + delta exp(-|u|/v_s)), u slip speed".into()
    }
    fn size_name(&self) -> &'static str {
        "a friction falling with slip speed"
    }
    /// How far above the kinetic μ the static one lies, and over what slip speed it falls.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "μ falls with slip speed from a static value {} % above the kinetic one, over v_s = {} mm/s",
            with_error(f, "delta_mu_rel", 1e2)?,
            with_error(f, "v_s_mps", 1e3)?
        ))
    }
    /// δ_s from 0 (none) to 2: a static friction three times the kinetic is no metal pair's;
    /// v_s from 0.1 mm/s (slower than any slip a frame resolves) to 0.3 m/s (above every kick,
    /// where the curve is a straight line, the linear form's).
    fn params(&self) -> Vec<ParamInfo> {
        vec![
            p("delta_mu_rel", 0.0, 0.0, 2.0, 1e-4),
            p("ln_vs_mps", (1e-2f64).ln(), (1e-4f64).ln(), (0.3f64).ln(), 1e-3),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.variation.stribeck = [x[0], x[1].exp()];
    }
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["delta_mu_rel", "v_s_mps"])?;
        Some(FrictionVariation {
            stribeck: [v[0], v[1]],
            ..FrictionVariation::default()
        })
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let vs = f.x[1].exp();
        let mut out = BTreeMap::new();
        out.insert("delta_mu_rel".into(), Estimate::new(f.x[0], f.se[0]));
        out.insert("v_s_mps".into(), Estimate::new(vs, vs * f.se[1]));
        for (k, name) in f.materials.iter().enumerate() {
            out.insert(
                format!("mu_static_{name}"),
                Estimate::new(f.global[k] * (1.0 + f.x[0]), f64::NAN),
            );
            out.insert(
                format!("mu_kinetic_{name}"),
                Estimate::new(f.global[k], f.global_se[k]),
            );
        }
        out
    }
    /// A δ_s at its ceiling (a static friction three times the kinetic) is a form bent to take
    /// something else; δ_s at 0 is no excess at all, which held-out runs judge.
    fn refused_at_bound(&self, param: usize, lower: bool) -> bool {
        param == 0 && !lower
    }
    fn scale_trials(&self) -> Option<Vec<(Vec<f64>, Vec<(usize, f64)>)>> {
        Some(
            TRIAL_VS_MPS
                .iter()
                .map(|vs| (vec![0.0, vs.ln()], vec![(0, 0.1)]))
                .collect(),
        )
    }
    fn starts(&self) -> Vec<Vec<f64>> {
        TRIAL_VS_MPS.iter().map(|vs| vec![0.1, vs.ln()]).collect()
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((1, "slip speed scale"))
    }
    fn scale_at_end(&self, x: f64, lower: bool) -> Option<String> {
        lower.then(|| {
            format!(
                "its slip speed scale v_s ran to the slowest the search allows ({:.2} mm/s)",
                1e3 * x.exp()
            )
        })
    }
}
