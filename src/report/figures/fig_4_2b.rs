//! Fig. 4.2b: one single-run trajectory, sliding and rolling samples marked, with the fitted baseline
//! and, when discovery accepted physics, the run fitted under it (the model the report trusts,
//! whose residuals the strip below then shows).

use super::common::{legend, line, linear_chart, render_high, scatter_sized, span};
use super::residual_strip::{self, TALL_H};
use crate::report::inputs::ReportData;
use crate::report::singles::SingleRow;
use crate::report::style::{self, Marker};
use crate::report::trajectory::{self, Sample};
use plotters::prelude::*;

/// The run Fig. 4.2b shows: `wanted` if given and fitted, else the converged fit with v0 > 0 closest
/// to the chapter's 0.025 m/s (any direction if none moves in +z).
pub fn choose<'a>(d: &'a ReportData, wanted: Option<&str>) -> Option<&'a SingleRow> {
    if let Some(w) = wanted {
        return d.singles.iter().find(|r| r.run == w);
    }
    let dist =
        |r: &&SingleRow| (r.v0_mps.value.abs() - crate::report::chapter::FIG_4_2B_V0_MPS).abs();
    let ok = || {
        d.singles
            .iter()
            .filter(|r| r.converged() && d.recordings.contains_key(&r.run))
    };
    ok().filter(|r| r.v0_mps.value > 0.0)
        .min_by(|a, b| dist(a).total_cmp(&dist(b)))
        .or_else(|| ok().min_by(|a, b| dist(a).total_cmp(&dist(b))))
}

/// The samples of the chosen run: residuals if the simulate stage ran, else the fit evaluated here.
pub fn samples(d: &ReportData, fit: &SingleRow) -> Option<Vec<Sample>> {
    d.residuals
        .get(&fit.run)
        .and_then(trajectory::from_residuals)
        .or_else(|| trajectory::from_fit(d.recordings.get(&fit.run)?, fit, d.groove))
}

/// The legend label of the curve under the accepted physics (the report's caption looks for it).
pub const ACCEPTED_LABEL: &str = "fitted under the accepted physics";

/// Render Fig. 4.2b, or None when no single run has a usable fit.
pub fn render_fig(d: &ReportData, wanted: Option<&str>) -> Result<Option<String>, String> {
    let Some(fit) = choose(d, wanted) else {
        return Ok(None);
    };
    let Some(s) = samples(d, fit) else {
        return Ok(None);
    };
    let z_ref = s[0].z_obs_m;
    let mm = |z: f64| (z - z_ref) * 1e3;
    let ms = |t: f64| t * 1e3;
    let step = (s.len() / 160).max(1);
    let pick = |rolling: bool| -> Vec<(f64, f64)> {
        s.iter()
            .step_by(step)
            .filter(|p| p.rolling == rolling)
            .map(|p| (ms(p.t_s), mm(p.z_obs_m)))
            .collect()
    };
    let (sliding, rolling) = (pick(false), pick(true));
    let curve: Vec<(f64, f64)> = s.iter().map(|p| (ms(p.t_s), mm(p.z_fit_m))).collect();
    let accepted = crate::report::accepted_curve::curve(d, fit, &s);
    let accepted_curve: Option<Vec<(f64, f64)>> = accepted
        .as_ref()
        .map(|z| s.iter().zip(z).map(|(p, &z)| (ms(p.t_s), mm(z))).collect());
    // the trusted model's fitted position at each sample: the accepted physics' when drawn
    let trusted = |i: usize| accepted.as_ref().map_or(s[i].z_fit_m, |z| z[i]);
    let switch = s.iter().find(|p| p.rolling).map(|p| ms(p.t_s));
    let xr = span(s.iter().map(|p| ms(p.t_s)), 0.03);
    let yr = span(
        s.iter()
            .enumerate()
            .flat_map(|(i, p)| [mm(p.z_obs_m), mm(p.z_fit_m), mm(trusted(i))]),
        0.06,
    );
    let caption = format!(
        "Fig. 4.2b: run {} ({}), v0 = {:.4} m/s",
        fit.run, fit.material, fit.v0_mps.value
    );
    // data − the trusted model, µm, by phase, on the strip under the chart
    let resid = |rolling: bool| -> Vec<(f64, f64)> {
        s.iter()
            .enumerate()
            .step_by(step)
            .filter(|(_, p)| p.rolling == rolling)
            .map(|(i, p)| (ms(p.t_s), (p.z_obs_m - trusted(i)) * 1e6))
            .collect()
    };
    let strip = [
        (resid(false), style::SLIDING, "sliding"),
        (resid(true), style::ROLLING, "rolling"),
    ];
    let svg = render_high(TALL_H, |whole| {
        super::marks::figure_run(&fit.run);
        let (root, below) = whole.split_vertically(style::FIG_H);
        residual_strip::draw(&below, xr, &strip)?;
        let root = &root;
        let mut c = linear_chart(
            root,
            &caption,
            xr,
            yr,
            "time t (ms)",
            "position z − z(0) (mm)",
        )?;
        scatter_sized(
            &mut c,
            &sliding,
            Marker::Circle,
            style::SLIDING,
            true,
            Some("observed, sliding"),
            3,
        )?;
        scatter_sized(
            &mut c,
            &rolling,
            Marker::Circle,
            style::ROLLING,
            true,
            Some("observed, rolling"),
            3,
        )?;
        line(
            &mut c,
            curve,
            style::BLACK,
            2,
            false,
            Some("fitted baseline"),
        )?;
        if let Some(acc) = accepted_curve {
            line(&mut c, acc, style::ACCEPTED, 2, true, Some(ACCEPTED_LABEL))?;
        }
        if let Some(t1) = switch {
            line(
                &mut c,
                vec![(t1, yr.0), (t1, yr.1)],
                style::GREY,
                1,
                true,
                Some("switch t1"),
            )?;
        }
        let pos = if fit.v0_mps.value >= 0.0 {
            SeriesLabelPosition::LowerRight
        } else {
            SeriesLabelPosition::UpperRight
        };
        legend(&mut c, pos)
    })?;
    Ok(Some(svg))
}
