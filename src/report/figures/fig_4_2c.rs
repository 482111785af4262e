//! Fig. 4.2c: fitted drag time T against |v0| for each material, our regression lines, the chapter's
//! line T = 0.052 + 1.10 v0, and the free-air Stokes time (2.2 s) on a log axis so all fit.

use super::common::{legend, line, render, scatter_runs, span};
use crate::report::chapter;
use crate::report::inputs::ReportData;
use crate::report::style;
use crate::report::summary::t_line;
use plotters::prelude::*;

/// A straight line T(v) sampled densely: on a log axis it is a curve, not a segment.
fn sampled(x_max: f64, f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    (0..=60)
        .map(|i| x_max * i as f64 / 60.0)
        .map(|v| (v, f(v)))
        .collect()
}

/// Tick label of a log axis: only 1, 2 and 5 times a power of ten are written.
fn log_label(y: &f64) -> String {
    let e = y.log10().floor();
    let m = y / 10f64.powf(e);
    if [1.0, 2.0, 5.0].iter().any(|k| (m - k).abs() < 1e-6) {
        let decimals = (-e).max(0.0) as usize;
        format!("{y:.decimals$}")
    } else {
        String::new()
    }
}

/// The ticks of a log axis from `lo` to `hi`: 1, 2 and 5 times each power of ten, each once.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    for e in e0..=e1 {
        for k in [1.0, 2.0, 5.0] {
            // the decimal text parsed back: 1e-1 * 2 prints 0.2, not 0.20000000000000001
            let v: f64 = format!("{k}e{e}").parse().unwrap_or(f64::NAN);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
    }
    out
}

/// Render Fig. 4.2c, or None without single-run fits.
pub fn render_fig(d: &ReportData) -> Result<Option<String>, String> {
    let mats: Vec<String> = d
        .materials()
        .into_iter()
        .filter(|m| d.singles_of(m).next().is_some())
        .collect();
    if mats.is_empty() {
        return Ok(None);
    }
    let stokes = chapter::stokes_time_s(
        chapter::RADIUS_M,
        chapter::DENSITY_KG_M3,
        chapter::AIR_VISCOSITY_PA_S,
    );
    let all: Vec<f64> = d
        .singles
        .iter()
        .filter(|r| r.converged())
        .map(|r| r.t_drag_s.value)
        .collect();
    let x_max = span(d.singles.iter().map(|r| r.v0_mps.value.abs()), 0.05)
        .1
        .max(0.01);
    let y_lo = all
        .iter()
        .cloned()
        .filter(|t| *t > 0.0)
        .fold(chapter::T0_S, f64::min)
        * 0.7;
    let y_hi = stokes * 1.6;
    let svg = render(|root| {
        super::marks::axes("initial speed |v0| (m/s)", "fitted drag time T (s)");
        let mut c = ChartBuilder::on(root)
            .caption(
                "Fig. 4.2c: drag time T against initial speed",
                (style::FONT, style::CAPTION_PX),
            )
            .margin(14)
            .margin_right(style::MARGIN_RIGHT)
            .x_label_area_size(56)
            .y_label_area_size(84)
            .build_cartesian_2d(
                0.0..x_max,
                (y_lo..y_hi)
                    .log_scale()
                    .with_key_points(log_ticks(y_lo, y_hi)),
            )?;
        c.configure_mesh()
            .x_desc("initial speed |v0| (m/s)")
            .y_desc("fitted drag time T (s, log scale)")
            .label_style((style::FONT, style::TICK_PX))
            .axis_desc_style((style::FONT, style::LABEL_PX))
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(style::LIGHT_GREY)
            .y_label_formatter(&log_label)
            .draw()?;
        for (i, m) in mats.iter().enumerate() {
            let col = style::material_colour(m, i);
            let pts: Vec<(f64, f64)> = d
                .singles_of(m)
                .map(|r| (r.v0_mps.value.abs(), r.t_drag_s.value))
                .collect();
            let runs: Vec<String> = d.singles_of(m).map(|r| r.run.clone()).collect();
            let bars: Vec<(f64, f64, f64)> = d
                .singles_of(m)
                .filter_map(|r| Some((r.v0_mps.value.abs(), r.t_drag_s.value, r.t_drag_s.se?)))
                .filter(|(_, t, e)| t - e > y_lo && t + e < y_hi)
                .collect();
            super::common::error_bars(&mut c, &bars, col)?;
            scatter_runs(
                &mut c,
                &pts,
                &runs,
                style::marker(m, false),
                col,
                true,
                Some(&format!("{m}: fitted T")),
            )?;
            if let Some((a, b)) = t_line(d, Some(m)) {
                let (a, b) = (a.est.value, b.est.value);
                let pts = sampled(x_max, |v| a + b * v);
                let label = format!("{m}: T = {a:.3} + {b:.2}·v0");
                line(&mut c, pts, col, 2, false, Some(&label))?;
            }
        }
        let ch = sampled(x_max, chapter::t_line_s);
        line(
            &mut c,
            ch,
            style::BLACK,
            2,
            true,
            Some("chapter: T = 0.052 + 1.10·v0"),
        )?;
        let label = format!("Stokes drag in free air: {stokes:.2} s");
        line(
            &mut c,
            vec![(0.0, stokes), (x_max, stokes)],
            style::GREY,
            2,
            true,
            Some(&label),
        )?;
        legend(&mut c, SeriesLabelPosition::MiddleLeft)
    })?;
    Ok(Some(svg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_log_tick_is_there_once() {
        let t = log_ticks(0.035, 3.5);
        assert_eq!(t, vec![0.05, 0.1, 0.2, 0.5, 1.0, 2.0]);
        let labels: Vec<String> = t.iter().map(log_label).collect();
        assert_eq!(labels, ["0.05", "0.1", "0.2", "0.5", "1", "2"]);
    }
}
