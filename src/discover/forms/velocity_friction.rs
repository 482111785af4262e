//! μ of the slip speed, saturating: μ(u) = μ∞·(1 − exp(−|u|/v_c)), v_c per material (fitted as ln
//! v_c; a material whose v_c runs to the lower bound keeps a constant μ).

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::Term;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct VelocityFriction {
    pub materials: usize,
}


impl Form for VelocityFriction {
    fn offer(n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(VelocityFriction {
            materials: n_materials,
        })
    }
    fn name(&self) -> &'static str {
        "velocity_friction"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("velocity_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "mu(u) = mu_inf (1 - exp(-|u|/v_c)), u slip speed".into()
    }
    fn size_name(&self) -> &'static str {
        "a velocity-dependent friction"
    }
    /// The slip speed over which μ rises to its full value, per material.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::per_material;
        Some(format!(
            "μ rises with slip speed to its full value over v_c = {} mm/s, while sliding",
            per_material(f, "v_c_mps", 1e3)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        (0..self.materials)
            .map(|m| p(&format!("ln_vc_mps_{m}"), (1e-4f64).ln(), -14.0, 0.0, 1e-3))
            .collect()
    }
    fn named_params(&self, materials: &[String]) -> Vec<ParamInfo> {
        let mut ps = self.params();
        for (p, m) in ps.iter_mut().zip(materials) {
            p.name = format!("ln_vc_mps_{m}");
        }
        ps
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.vc_mps = Some(x[e.material].exp());
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let mut out = BTreeMap::new();
        for (k, name) in f.materials.iter().enumerate() {
            let vc = f.x[k].exp();
            out.insert(format!("v_c_mps_{name}"), Estimate::new(vc, vc * f.se[k]));
            out.insert(
                format!("mu_inf_{name}"),
                Estimate::new(f.global[k], f.global_se[k]),
            );
        }
        out
    }
    /// Screened at a few trial scales v_c (the best kept), every material's at once.
    fn scale_trials(&self) -> Option<Vec<(Vec<f64>, Vec<(usize, f64)>)>> {
        let lo = self.params()[0].lo;
        let theta0 = vec![lo; self.materials];
        let trials = [1e-3f64, 3e-3, 1e-2, 3e-2]
            .iter()
            .map(|vc| {
                let steps = (0..self.materials).map(|m| (m, vc.ln())).collect();
                (theta0.clone(), steps)
            })
            .collect();
        Some(trials)
    }
    fn starts(&self) -> Vec<Vec<f64>> {
        [1e-4f64, 2e-3, 2e-2]
            .iter()
            .map(|v| vec![v.ln(); self.materials])
            .collect()
    }
    fn per_material(&self) -> bool {
        true
    }
    fn notes_start_bound(&self) -> bool {
        true
    }
    fn bound_note(
        &self,
        k: usize,
        x: f64,
        _info: &ParamInfo,
        lower: bool,
        materials: &[String],
    ) -> Option<String> {
        let name = materials.get(k).map_or("?", |s| s.as_str());
        Some(if lower {
            format!(
                "v_c of {name} at the search's floor ({:.1e} m/s): no speed dependence of {name}'s friction is resolved (its μ is constant, mu_inf_{name})",
                x.exp()
            )
        } else {
            format!(
                "v_c of {name} at the search's ceiling ({:.2} m/s): {name}'s friction still rises at the highest slip speeds; no plateau is resolved",
                x.exp()
            )
        })
    }
    /// μ of the slip speed per material: the pair fit holds one constant μ.
    fn lab_force(&self, _f: &Finding) -> Option<Result<Term, String>> {
        Some(Err(
            "the accepted model has a velocity-dependent friction, which the pair fit does not carry".into(),
        ))
    }
}
