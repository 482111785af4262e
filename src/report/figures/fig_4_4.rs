//! Figs. 4.4a–c: the target's spin change against its velocity change (slope μ_pp·k), and the
//! coefficient of restitution against impact speed per material, rolling and contact setups,
//! with the whole-run law chosen under the accepted physics where `refit` made the fits again,
//! and the impacts' own law (discovery's map) where discovery accepted one outside the candidates
//! (which the refit then takes, drawn as its whole-run law).

use super::common::{legend, line, linear_chart, render, scatter_runs, span};
use crate::artifacts::collision_summary::LawForm;
use crate::artifacts::diagnosis::Effect;
use crate::artifacts::summary::MaterialWholeRun;
use crate::physics::Restitution;
use crate::recording::Setup;
use crate::report::chapter;
use crate::report::inputs::ReportData;
use crate::report::style;
use crate::report::summary::mu_pp;
use crate::report::value::serde_name;
use plotters::prelude::*;

/// Render Fig. 4.4a, or None without impacts that carry Δv_z and Δv_a of the target.
pub fn render_a(d: &ReportData, k: f64) -> Result<Option<String>, String> {
    let mats = d.materials();
    let mut any = false;
    let mut groups = Vec::new();
    for (i, m) in mats.iter().enumerate() {
        for slip in [true, false] {
            let (runs, p): (Vec<String>, Vec<(f64, f64)>) = d
                .collisions
                .iter()
                .filter(|c| &c.material == m)
                .flat_map(|c| c.impacts.iter().map(move |im| (&c.run, im)))
                .filter(|(_, im)| im.slip.unwrap_or(true) == slip)
                .filter_map(|(run, im)| {
                    Some((
                        run.clone(),
                        (im.dvz_target_mps? * 1e3, im.dva_target_mps? * 1e3),
                    ))
                })
                .unzip();
            any |= !p.is_empty();
            groups.push((m.clone(), i, slip, p, runs));
        }
    }
    if !any {
        return Ok(None);
    }
    let xs = groups.iter().flat_map(|g| g.3.iter().map(|p| p.0));
    let (_, x_hi) = span(xs.chain([0.0]), 0.08);
    let xr = (0.0_f64.min(-x_hi * 0.05), x_hi);
    let slope_ours = mu_pp(d, k).map(|a| a.est.value * k);
    let slope_ch = chapter::MU_PP * k;
    let ys = groups.iter().flat_map(|g| g.3.iter().map(|p| p.1));
    let sign = if groups.iter().flat_map(|g| &g.3).map(|p| p.1).sum::<f64>() < 0.0 {
        -1.0
    } else {
        1.0
    };
    let yr = span(ys.chain([0.0, sign * slope_ch * x_hi]), 0.06);
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            "Fig. 4.4a: target's spin change against velocity change",
            xr,
            yr,
            "target velocity change Δv_z (mm/s)",
            "target spin change Δv_a (mm/s)",
        )?;
        for (m, i, slip, p, runs) in &groups {
            if p.is_empty() {
                continue;
            }
            let col = style::material_colour(m, *i);
            let label = format!("{m}, {}", if *slip { "slip" } else { "stick" });
            let mk = style::marker(m, false);
            scatter_runs(&mut c, p, runs, mk, col, *slip, Some(&label))?;
        }
        if let Some(sl) = slope_ours {
            let label = format!("ours: slope μ_pp·k = {sl:.2} (μ_pp = {:.2})", sl / k);
            line(
                &mut c,
                vec![(0.0, 0.0), (x_hi, sign * sl * x_hi)],
                style::BLACK,
                2,
                false,
                Some(&label),
            )?;
        }
        let label = format!("chapter: μ_pp = 1.4, slope {slope_ch:.2}");
        line(
            &mut c,
            vec![(0.0, 0.0), (x_hi, sign * slope_ch * x_hi)],
            style::GREY,
            2,
            true,
            Some(&label),
        )?;
        legend(&mut c, SeriesLabelPosition::UpperLeft)
    })?;
    Ok(Some(svg))
}

/// C = 1 − a·v through (0, 1), fitted by least squares to (v, C) points.
pub fn restitution_slope(p: &[(f64, f64)]) -> Option<f64> {
    let sxx: f64 = p.iter().map(|(v, _)| v * v).sum();
    let sxy: f64 = p.iter().map(|(v, c)| v * (1.0 - c)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Render the restitution figure of one material, or None without its impacts.
pub fn render_bc(
    d: &ReportData,
    material: &str,
    index: usize,
    fig: &str,
) -> Result<Option<String>, String> {
    let with_runs: Vec<(bool, Vec<(f64, f64)>, Vec<String>)> = [false, true]
        .into_iter()
        .map(|contact| {
            let (runs, p) = d
                .collisions
                .iter()
                .filter(|c| c.material == material && c.contact == contact)
                .flat_map(|c| c.impacts.iter().map(move |i| (&c.run, i)))
                .filter_map(|(run, i)| Some((run.clone(), (i.speed_mps, i.restitution?))))
                .unzip();
            (contact, p, runs)
        })
        .collect();
    let series: Vec<(bool, Vec<(f64, f64)>)> =
        with_runs.iter().map(|(c, p, _)| (*c, p.clone())).collect();
    if series.iter().all(|(_, p)| p.is_empty()) {
        return Ok(None);
    }
    let v_max = span(series.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)), 0.05)
        .1
        .max(0.01);
    let (lo, hi) = span(
        series
            .iter()
            .flat_map(|(_, p)| p.iter().map(|q| q.1))
            .chain([1.0]),
        0.08,
    );
    let yr = (lo.clamp(-0.2, 0.0), hi.max(1.05));
    let cap = format!("Fig. {fig}: restitution against impact speed, {material}");
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            &cap,
            (0.0, v_max),
            yr,
            "impact speed |v1 − v2| (m/s)",
            "coefficient of restitution C (dimensionless)",
        )?;
        line(
            &mut c,
            vec![(0.0, 1.0), (v_max, 1.0)],
            style::GREY,
            1,
            true,
            None,
        )?;
        for (contact, p, runs) in &with_runs {
            if p.is_empty() {
                continue;
            }
            let col = style::setup_colour(material, *contact, index);
            let setup = if *contact { "in contact" } else { "rolling" };
            scatter_runs(
                &mut c,
                p,
                runs,
                style::marker(material, *contact),
                col,
                true,
                Some(&format!("{material}, {setup}")),
            )?;
            // the law the whole-run fit chose (the report's table), else the linear one
            let v_hi = p.iter().map(|q| q.0).fold(0.0, f64::max);
            let chosen = d
                .whole_run()
                .and_then(|w| w.materials.iter().find(|m| m.material == material))
                .and_then(|m| law_of(m, *contact));
            let fitted = crate::report::summary::restitution_curve(d, material, *contact)
                .map(|(a, _)| a.est.value);
            if let Some((law, form)) = chosen {
                let label = format!(
                    "{setup}: {} law, chosen by the whole-run fit",
                    serde_name(&form)
                );
                line(&mut c, law_curve(&law, v_hi), col, 2, false, Some(&label))?;
            } else if let Some(a) = fitted.or_else(|| restitution_slope(p)) {
                let label = format!("{setup}: C = 1 − {a:.2}·v");
                // drawn over the measured speeds only, not extrapolated
                line(
                    &mut c,
                    vec![(0.0, 1.0), (v_hi, 1.0 - a * v_hi)],
                    col,
                    2,
                    false,
                    Some(&label),
                )?;
            }
            let accepted = crate::report::sections::under_accepted::whole_run_of(d, material)
                .and_then(|m| law_of(m, *contact));
            if let Some((law, form)) = accepted {
                let label = if form == LawForm::FromDiscovery {
                    format!("{setup}: under the accepted physics, discovery's law")
                } else {
                    format!("{setup}: whole-run law under the accepted physics")
                };
                line(&mut c, law_curve(&law, v_hi), col, 1, true, Some(&label))?;
            }
            if let Some(map) = impact_law_map(d, material, *contact) {
                let label = format!("{setup}: the impacts' own law, accepted by discovery (map)");
                line(&mut c, map, col, 3, true, Some(&label))?;
            }
        }
        legend(&mut c, SeriesLabelPosition::LowerLeft)
    })?;
    Ok(Some(svg))
}

/// The map of C against impact speed of an accepted restitution law outside the candidates
/// (discovery's `restitution_law` finding for this material and setup), at its nodes.
fn impact_law_map(d: &ReportData, material: &str, contact: bool) -> Option<Vec<(f64, f64)>> {
    let setup = if contact { "contact" } else { "rolling" };
    let f = d.diagnosis.as_ref()?.findings.iter().find(|f| {
        f.accepted
            && f.effect == Effect::RestitutionLaw.id()
            && f.where_.get("material").and_then(|m| m.as_str()) == Some(material)
            && f.where_.get("setup").and_then(|s| s.as_str()) == Some(setup)
    })?;
    let map = f.where_.get("map")?;
    let speeds: Vec<f64> = serde_json::from_value(map.get("speeds_mps")?.clone()).ok()?;
    let values: Vec<f64> = serde_json::from_value(map.get("values")?.clone()).ok()?;
    Some(speeds.into_iter().zip(values).collect())
}

/// `law` sampled from 0 to `v_hi` (the measured speeds only, not extrapolated).
fn law_curve(law: &Restitution, v_hi: f64) -> Vec<(f64, f64)> {
    (0..=60)
        .map(|i| {
            let v = v_hi * i as f64 / 60.0;
            (v, law.at(v))
        })
        .collect()
}

/// The restitution law a material's whole-run fit chose for the setup (the baseline's fit, or
/// the one made again under the physics discovery accepted, which may take discovery's law), and
/// its form; None without one.
fn law_of(m: &MaterialWholeRun, contact: bool) -> Option<(Restitution, LawForm)> {
    let setup = if contact {
        Setup::Contact
    } else {
        Setup::Rolling
    };
    let choice = m.restitution.iter().find(|c| c.setup == setup)?;
    Some((choice.law()?, choice.chosen))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped diagnosis with its 316 rolling-setup restitution test made accepted: the map
    /// is drawn for that material and setup only.
    #[test]
    fn an_accepted_impact_law_is_drawn_for_its_material_and_setup() {
        let mut diag = crate::artifacts::diagnosis::shipped();
        let f = diag
            .findings
            .iter_mut()
            .find(|f| {
                f.effect == "restitution_law"
                    && f.where_["material"] == "316"
                    && f.where_["setup"] == "rolling"
            })
            .expect("the shipped diagnosis tests the 316 rolling impacts");
        let nodes = f.where_["map"]["values"].as_array().unwrap().len();
        let d = ReportData {
            diagnosis: Some(diag.clone()),
            ..ReportData::default()
        };
        assert_eq!(
            impact_law_map(&d, "316", false),
            None,
            "not accepted: not drawn"
        );
        diag.findings
            .iter_mut()
            .find(|f| f.effect == "restitution_law" && f.where_["setup"] == "rolling")
            .unwrap()
            .accepted = true;
        let d = ReportData {
            diagnosis: Some(diag),
            ..ReportData::default()
        };
        let map = impact_law_map(&d, "316", false).expect("drawn");
        assert!(map.len() == nodes && nodes >= 3, "{map:?}");
        assert!(map.windows(2).all(|w| w[0].0 < w[1].0), "{map:?}");
        assert_eq!(impact_law_map(&d, "316", true), None);
        assert_eq!(impact_law_map(&d, "440c", false), None);
    }

    /// A law taken from discovery is the law drawn, under its form's name.
    #[test]
    fn a_law_from_discovery_is_the_law_drawn() {
        use crate::physics::LnMap;
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let summary: crate::artifacts::Summary =
            serde_json::from_slice(&std::fs::read(root.join("reports/summary.json")).unwrap())
                .unwrap();
        let mut m = summary.collisions.unwrap().whole_run.unwrap().materials[0].clone();
        let (law, form) = law_of(&m, true).expect("the shipped fit chose a contact law");
        assert_ne!(form, LawForm::FromDiscovery);
        assert!(law.at(0.1) > 0.0 && law.at(0.1) <= 1.0);
        let held = Restitution::Map(LnMap::new(&[0.05, 0.2], &[0.9, 0.7]).unwrap());
        let c = m
            .restitution
            .iter_mut()
            .find(|c| c.setup == Setup::Contact)
            .unwrap();
        c.chosen = LawForm::FromDiscovery;
        c.candidates.clear();
        c.discovered = Some(held);
        assert_eq!(law_of(&m, true), Some((held, LawForm::FromDiscovery)));
        // a form from discovery whose law is missing draws nothing rather than another law
        m.restitution.iter_mut().for_each(|c| c.discovered = None);
        let contact = m.restitution.iter().find(|c| c.setup == Setup::Contact);
        assert_eq!(contact.and_then(|c| c.law()), None);
    }
}
