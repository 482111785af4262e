//! The profile of μ_pp beside Fig. 4.4a: per material, the whole-run fit's deviance with μ_pp
//! held at each value (summary.json → collisions.whole_run), drawn as its square root (a
//! parabola's root is a V), with the 95 % level and the chapter's 1.4; and again for the fits made
//! under the physics discovery accepted (`refit`), when they were made again.

use super::common::{legend, line, linear_chart, render, scatter, span};
use crate::artifacts::collision_summary::ProfileVerdict;
use crate::artifacts::summary::MaterialWholeRun;
use crate::report::chapter;
use crate::report::inputs::ReportData;
use crate::report::style;
use crate::report::value::sig;
use plotters::prelude::*;

/// √Δχ² above this is drawn at this value, without a marker (the far ends of the profile rise by
/// thousands).
pub const CLIP: f64 = 12.0;

/// One material's profile: its name, [(μ_pp, deviance)], the deviance threshold of the 95 %
/// interval, and that interval (lo, hi) when the profile has a minimum inside its grid.
pub type Profile = (String, Vec<(f64, f64)>, f64, Option<(f64, f64)>);

/// The profile of each material that has one.
pub fn profiles(d: &ReportData) -> Vec<Profile> {
    d.whole_run().map_or_else(Vec::new, |w| of(&w.materials))
}

/// The profiles of `materials`' whole-run fits.
fn of(materials: &[MaterialWholeRun]) -> Vec<Profile> {
    materials
        .iter()
        .filter_map(|m| {
            let pts: Vec<(f64, f64)> = m
                .profile
                .points
                .iter()
                .map(|p| (p.mu_pp, p.deviance))
                .collect();
            let interval = match m.profile.verdict {
                ProfileVerdict::Interval { lo, hi, .. } => Some((lo, hi)),
                _ => None,
            };
            (!pts.is_empty()).then(|| (m.material.clone(), pts, m.profile.threshold, interval))
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

/// √ of a deviance, clipped at `CLIP`.
fn root(dev: f64) -> f64 {
    dev.max(0.0).sqrt().min(CLIP)
}

/// The μ_pp range shown on the linear axis: where the profiles are below the clip, and the
/// intervals, padded; the far grid values (deviances of thousands) would squash the minimum.
fn mu_range(profs: &[Profile]) -> (f64, f64) {
    let inside = profs.iter().flat_map(|p| {
        p.1.iter()
            .filter(|q| q.1.max(0.0).sqrt() < CLIP)
            .map(|q| q.0)
            .chain(p.3.into_iter().flat_map(|(lo, hi)| [lo, hi]))
    });
    let (lo, hi) = span(inside, 0.0);
    let all = span(profs.iter().flat_map(|p| p.1.iter().map(|q| q.0)), 0.0);
    // nothing below the clip: the whole grid
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        all
    };
    let pad = (hi - lo) * 0.2;
    (lo - pad, hi + pad)
}

fn draw(profs: Vec<Profile>, title: &str) -> Result<Option<String>, String> {
    if profs.is_empty() {
        return Ok(None);
    }
    let xr = mu_range(&profs);
    let shown = |x: f64| x >= xr.0 && x <= xr.1;
    let yr = (0.0, CLIP * 1.05);
    let svg = render(|root_area| {
        let mut c = linear_chart(
            root_area,
            title,
            xr,
            yr,
            "μ_pp (particle–particle friction)",
            "√(deviance above the best fit)",
        )?;
        for (i, (m, pts, _, interval)) in profs.iter().enumerate() {
            let col = style::material_colour(m, i);
            if let Some((lo, hi)) = interval {
                let band = Rectangle::new([(*lo, 0.0), (*hi, yr.1)], col.mix(0.18).filled());
                c.draw_series(std::iter::once(band))?;
                // the interval as a bar on the axis, labelled with its ends
                let label = format!("{m}: 95 % interval [{}, {}]", sig(*lo, 5), sig(*hi, 5));
                line(
                    &mut c,
                    vec![(*lo, 0.15), (*hi, 0.15)],
                    col,
                    5,
                    false,
                    Some(&label),
                )?;
            }
            let p: Vec<(f64, f64)> = pts
                .iter()
                .filter(|q| shown(q.0))
                .map(|&(mu, dev)| (mu, root(dev)))
                .collect();
            line(&mut c, p.clone(), col, 2, false, None)?;
            // a grid value above the clip has no value to mark: its line runs out of the top
            let marked: Vec<(f64, f64)> = p.iter().copied().filter(|q| q.1 < CLIP).collect();
            scatter(&mut c, &marked, style::marker(m, false), col, true, Some(m))?;
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
        let ch = chapter::MU_PP;
        if shown(ch) {
            line(
                &mut c,
                vec![(ch, 0.0), (ch, yr.1)],
                style::BLACK,
                1,
                true,
                Some("chapter 1.4"),
            )?;
        }
        legend(&mut c, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })?;
    Ok(Some(svg))
}
