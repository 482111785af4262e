//! The profile of μ_pp beside Fig. 4.4a: per material, the whole-run fit's deviance with μ_pp
//! held at each value (summary.json → collisions.whole_run), drawn as its square root (a
//! parabola's root is a V), with the 95 % level and the chapter's 1.4; and again for the fits made
//! under the physics discovery accepted (`refit`), when they were made again.

use super::common::{legend, line, linear_chart, render, scatter};
use crate::artifacts::summary::MaterialWholeRun;
use crate::report::chapter;
use crate::report::inputs::ReportData;
use crate::report::style;
use plotters::prelude::*;

/// √Δχ² above this is drawn at this value (the far ends of the profile rise by thousands).
pub const CLIP: f64 = 12.0;

/// (material, [(μ_pp, deviance)], threshold) of each material with a profile.
pub fn profiles(d: &ReportData) -> Vec<(String, Vec<(f64, f64)>, f64)> {
    d.whole_run().map_or_else(Vec::new, |w| of(&w.materials))
}

/// The profiles of `materials`' whole-run fits.
fn of(materials: &[MaterialWholeRun]) -> Vec<(String, Vec<(f64, f64)>, f64)> {
    materials
        .iter()
        .filter_map(|m| {
            let pts: Vec<(f64, f64)> = m
                .profile
                .points
                .iter()
                .map(|p| (p.mu_pp, p.deviance))
                .collect();
            (!pts.is_empty()).then(|| (m.material.clone(), pts, m.profile.threshold))
        })
        .collect()
}

/// Render the profile figure, or None without whole-run profiles.
pub fn render_fig(d: &ReportData) -> Result<Option<String>, String> {
    draw(profiles(d), "μ_pp profile of the whole-run fits")
}

/// The profile figure of the whole-run fits made again under the physics discovery accepted,
/// or None when none was made again (nothing accepted, or the baseline's fits carried it all).
pub fn render_accepted(d: &ReportData) -> Result<Option<String>, String> {
    let Some(c) = d
        .under_accepted
        .as_ref()
        .and_then(|u| u.collisions.as_ref())
    else {
        return Ok(None);
    };
    let refitted: Vec<MaterialWholeRun> = c
        .whole_run
        .materials
        .iter()
        .filter(|m| !c.unchanged.contains(&m.material))
        .cloned()
        .collect();
    draw(
        of(&refitted),
        "μ_pp profile of the whole-run fits under the accepted physics",
    )
}

fn draw(profs: Vec<(String, Vec<(f64, f64)>, f64)>, title: &str) -> Result<Option<String>, String> {
    if profs.is_empty() {
        return Ok(None);
    }
    let xs = profs.iter().flat_map(|p| p.1.iter().map(|q| q.0.log10()));
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |a, x| {
        (a.0.min(x), a.1.max(x))
    });
    let xr = (lo - 0.05, hi + 0.05);
    let yr = (0.0, CLIP * 1.05);
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            title,
            xr,
            yr,
            "log10 μ_pp",
            "√(deviance above the best fit)",
        )?;
        for (i, (m, pts, _)) in profs.iter().enumerate() {
            let col = style::material_colour(m, i);
            let p: Vec<(f64, f64)> = pts
                .iter()
                .map(|&(mu, dev)| (mu.log10(), dev.max(0.0).sqrt().min(CLIP)))
                .collect();
            line(&mut c, p.clone(), col, 2, false, None)?;
            scatter(&mut c, &p, style::marker(m, false), col, true, Some(m))?;
        }
        let thr = profs[0].2.sqrt();
        line(
            &mut c,
            vec![(xr.0, thr), (xr.1, thr)],
            style::GREY,
            1,
            true,
            Some("95 % level"),
        )?;
        let ch = chapter::MU_PP.log10();
        line(
            &mut c,
            vec![(ch, 0.0), (ch, yr.1)],
            style::BLACK,
            1,
            true,
            Some("chapter 1.4"),
        )?;
        legend(&mut c, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })?;
    Ok(Some(svg))
}
