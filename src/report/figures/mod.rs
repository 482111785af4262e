//! Every figure of the report, each rendered to an SVG string by its own file; `render_all` names them.
//!
//! Files of this folder:
//!
//! - `common.rs`: Drawing helpers shared by the figures
//! - `discovery.rs`: Discovery figures
//! - `fig_4_2b.rs`: Fig. 4.2b: one trajectory with its fit, sliding and rolling marked
//! - `fig_4_2c.rs`: Fig. 4.2c: fitted T against v0
//! - `fig_4_2d.rs`: Fig. 4.2d: fitted μ against v0
//! - `fig_4_3.rs`: Figs. 4.3c–d: striker and target trajectories
//! - `fig_4_4.rs`: Figs. 4.4a–c: spin change against velocity change, restitution
//! - `forcemap.rs`: force-map figures
//! - `marks.rs`: The data points of a figure: titles, CSV rows, the legend's place
//! - `mu_pp_profile.rs`: The profile of μ_pp beside Fig. 4.4a
//! - `residual_strip.rs`: The strip of residuals under a fitted-trajectory figure
//! - `secondary.rs`: The secondary-collision factor

pub mod common;
pub mod discovery;
pub mod fig_4_2b;
pub mod fig_4_2c;
pub mod fig_4_2d;
pub mod fig_4_3;
pub mod fig_4_4;
pub mod forcemap;
pub mod marks;
pub mod mu_pp_profile;
pub mod residual_strip;
pub mod secondary;

use super::inputs::ReportData;
use crate::physics::Groove;
use std::collections::BTreeMap;

/// Which runs the single-trajectory figures show (None: chosen as documented in each figure),
/// and the groove the fitted curves are drawn on.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FigureOptions {
    /// Run for Fig. 4.2b (default: the single run with v0 closest to 0.025 m/s).
    pub trajectory_run: Option<String>,
    /// Run for Figs. 4.3c–d (default: the first rolling-setup collision run with an impact).
    pub collision_run: Option<String>,
    /// Opening angle of the groove, degrees (the chapter's 70.6 by default).
    pub groove_angle_deg: f64,
    /// k = m R² / I of the particles (5/2, a solid sphere, by default).
    pub k: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            trajectory_run: None,
            collision_run: None,
            groove_angle_deg: 70.6,
            k: 2.5,
        }
    }
}

impl FigureOptions {
    /// The groove these options name.
    pub fn groove(&self) -> Groove {
        Groove::of_params(self.groove_angle_deg, self.k)
    }
}

/// File name of the restitution figure of a material: 4.4b for 316, 4.4c for 440c, else by name.
pub fn restitution_name(material: &str) -> (String, String) {
    match material.to_ascii_lowercase().as_str() {
        "316" | "ss316" => ("fig_4_4b.svg".into(), "4.4b".into()),
        "440c" | "ss440c" => ("fig_4_4c.svg".into(), "4.4c".into()),
        other => {
            let safe: String = other
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            (format!("fig_4_4_{safe}.svg"), format!("4.4 ({material})"))
        }
    }
}

/// Render every figure the data allows, by file name (`fig_4_2b.svg` → SVG text, and
/// `fig_4_2b.csv` → its data points when it has any, `fig_4_2b_residuals.csv` → its residual
/// strip's). Parts without data
/// (no collision runs, no diagnosis) are simply absent; the report says why.
pub fn render_all(
    d: &ReportData,
    opts: &FigureOptions,
) -> Result<BTreeMap<String, String>, String> {
    let g = d.groove;
    let mut out = BTreeMap::new();
    // each figure's data points beside it, as `<name>.csv`, and a strip's as `<name>_<part>.csv`
    let mut put = |name: &str, svg: Option<String>| {
        if let Some(s) = svg {
            for (part, csv) in marks::csv_parts(&s) {
                let suffix = if part.is_empty() {
                    String::new()
                } else {
                    format!("_{part}")
                };
                out.insert(name.replace(".svg", &format!("{suffix}.csv")), csv);
            }
            out.insert(name.to_string(), s);
        }
    };
    put(
        "fig_4_2b.svg",
        fig_4_2b::render_fig(d, opts.trajectory_run.as_deref())?,
    );
    put("fig_4_2c.svg", fig_4_2c::render_fig(d)?);
    put("fig_4_2d.svg", fig_4_2d::render_fig(d)?);
    if let Some((c, dd)) = fig_4_3::render_figs(d, opts.collision_run.as_deref())? {
        put("fig_4_3c.svg", Some(c));
        put("fig_4_3d.svg", Some(dd));
    }
    put("fig_4_4a.svg", fig_4_4::render_a(d, g.k)?);
    put("fig_mu_pp_profile.svg", mu_pp_profile::render_fig(d)?);
    put(
        "fig_mu_pp_profile_accepted.svg",
        mu_pp_profile::render_accepted(d)?,
    );
    let coll_mats: Vec<String> = {
        let mut m: Vec<String> = d.collisions.iter().map(|c| c.material.clone()).collect();
        m.sort();
        m.dedup();
        m
    };
    for (i, m) in coll_mats.iter().enumerate() {
        let (name, fig) = restitution_name(m);
        put(&name, fig_4_4::render_bc(d, m, i, &fig)?);
    }
    put("fig_secondary.svg", Some(secondary::render_fig(g)?));
    if let Some(diag) = &d.diagnosis {
        put("fig_discovery_cv.svg", discovery::render_cv(diag)?);
        put("fig_discovery_drift.svg", discovery::render_drift(diag)?);
        for v in ["z", "v", "t"] {
            put(
                &format!("fig_discovery_forcemap_{v}.svg"),
                forcemap::render_map(diag, v)?,
            );
        }
    }
    Ok(out)
}
