//! Discovery figures: held-out error of the baseline and of each candidate's extended model, and the
//! drift (fitted T against |v0|) before and after the accepted physics, when diagnosis.json has it.

use super::common::{legend, line, linear_chart, render, scatter_runs, span};
use crate::artifacts::diagnosis::{Diagnosis, DriftPoint};
use crate::report::style::{self, Marker};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// (effect, accepted, baseline cv rms, extended cv rms) of every finding that has both.
pub fn cv_rows(diag: &Diagnosis) -> Vec<(String, bool, f64, f64)> {
    diag.findings
        .iter()
        .filter_map(|f| {
            let b = finite(f.baseline.cv_rms_m)?;
            let e = finite(f.extended.cv_rms_m)?;
            Some((f.effect.clone(), f.accepted, b, e))
        })
        .collect()
}

/// Render the held-out error chart, or None when no finding carries cv_rms_m.
pub fn render_cv(diag: &Diagnosis) -> Result<Option<String>, String> {
    let rows = cv_rows(diag);
    if rows.is_empty() {
        return Ok(None);
    }
    let n = rows.len() as f64;
    let y_hi = rows.iter().flat_map(|r| [r.2, r.3]).fold(0.0, f64::max) * 1e6 * 1.25;
    let names: Vec<String> = rows.iter().map(|r| r.0.replace('_', " ")).collect();
    // each candidate's name wrapped to its category's width under its bars, the right margin
    // wide enough for the last
    let font = style::TICK_PX - 2;
    let (mut margin_right, mut lines) = (style::MARGIN_RIGHT, Vec::new());
    for _ in 0..2 {
        let width = category_px(margin_right, rows.len()) - 10.0;
        lines = names.iter().map(|n| wrap(n, width, font)).collect();
        let half_last = lines.last().map_or(0.0, |l: &Vec<String>| {
            l.iter().map(|t| text_px(t, font)).fold(0.0, f64::max) / 2.0
        });
        margin_right = right_margin(half_last, rows.len());
    }
    let n_lines = lines.iter().map(Vec::len).max().unwrap_or(1) as u32;
    let svg = render(|root| {
        let mut c = ChartBuilder::on(root)
            .caption(
                "Held-out error: baseline against each extended model",
                (style::FONT, style::CAPTION_PX),
            )
            .margin(14)
            .margin_right(margin_right)
            .x_label_area_size(8 + n_lines * (font + 3) + 34)
            .y_label_area_size(84)
            .build_cartesian_2d(-0.5..n - 0.5, 0.0..y_hi.max(1e-3))?;
        c.configure_mesh()
            .disable_x_mesh()
            .x_labels(rows.len())
            .x_label_formatter(&|_| String::new())
            .y_desc("cross-validated RMS of z (µm)")
            .x_desc("candidate physics")
            .label_style((style::FONT, style::TICK_PX - 2))
            .axis_desc_style((style::FONT, style::LABEL_PX))
            .light_line_style(style::LIGHT_GREY.mix(0.6))
            .draw()?;
        let bar = |i: usize, off: f64, v: f64| {
            [
                (i as f64 + off - 0.17, 0.0),
                (i as f64 + off + 0.17, v * 1e6),
            ]
        };
        for (i, l) in lines.iter().enumerate() {
            let (x, y) = c.backend_coord(&(i as f64, 0.0));
            for (k, t) in l.iter().enumerate() {
                let st = TextStyle::from((style::FONT, font).into_font())
                    .color(&style::BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top));
                root.draw(&Text::new(
                    t.clone(),
                    (x, y + 8 + k as i32 * (font as i32 + 3)),
                    st,
                ))?;
            }
        }
        c.draw_series(
            rows.iter()
                .enumerate()
                .map(|(i, r)| Rectangle::new(bar(i, -0.18, r.2), style::BEFORE.filled())),
        )?
        .label("baseline")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], style::BEFORE.filled()));
        c.draw_series(rows.iter().enumerate().map(|(i, r)| {
            let col = if r.1 {
                style::AFTER.mix(1.0)
            } else {
                style::AFTER.mix(0.35)
            };
            Rectangle::new(bar(i, 0.18, r.3), col.filled())
        }))?
        .label("extended (pale: not accepted)")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], style::AFTER.filled()));
        // each bar's top is a data point: titled with its candidate, a row of the CSV
        super::marks::axes("candidate", "cross-validated RMS of z (µm)");
        for (series, off, v) in [("baseline", -0.18, 2), ("extended", 0.18, 3)] {
            super::marks::label(if v == 2 {
                series
            } else {
                "extended (pale: not accepted)"
            });
            for (i, r) in rows.iter().enumerate() {
                let y = if v == 2 { r.2 } else { r.3 } * 1e6;
                super::marks::add(super::marks::Mark {
                    px: c.backend_coord(&(i as f64 + off, y)),
                    series: series.into(),
                    run: names[i].clone(),
                    x: i as f64,
                    y,
                });
            }
        }
        legend(&mut c, SeriesLabelPosition::UpperRight)
    })?;
    Ok(Some(svg))
}

/// A label broken at spaces into lines of at most `width` px (a longer word keeps its own line).
fn wrap(name: &str, width: f64, font: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in name.split(' ') {
        match lines.last_mut() {
            Some(l) if text_px(&format!("{l} {word}"), font) <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// The width in pixels of one of `n` categories with the right margin `margin_right`.
fn category_px(margin_right: u32, n: usize) -> f64 {
    (f64::from(style::FIG_W) - 14.0 - 84.0 - f64::from(margin_right)) / n.max(1) as f64
}

/// A text's width in pixels at `font` px, as wide as a sans-serif's digits (0.55 em each).
fn text_px(text: &str, font: u32) -> f64 {
    text.chars().count() as f64 * 0.55 * f64::from(font)
}

/// The right margin that holds half of the last of `n` category labels (`half` px) inside the
/// canvas: its centre sits half a category in from the plot's right edge.
fn right_margin(half: f64, n: usize) -> u32 {
    // the canvas less the left margin and the y labels' area
    let w0 = f64::from(style::FIG_W) - 14.0 - 84.0;
    let k = 1.0 / (2.0 * n.max(1) as f64);
    let need = ((half + 4.0 - w0 * k) / (1.0 - k)).ceil();
    (need.max(0.0) as u32).max(style::MARGIN_RIGHT)
}

/// (x, y) points of a figure.
pub type Points = Vec<(f64, f64)>;

/// (v0, T) of the per-run points with both numbers.
fn points(list: &[DriftPoint]) -> Points {
    list.iter()
        .filter_map(|p| Some((finite(p.v0_mps)?, finite(p.t_s)?)))
        .collect()
}

/// The runs of the points `points` keeps, in its order.
fn runs_of(list: &[DriftPoint]) -> Vec<String> {
    list.iter()
        .filter(|p| finite(p.v0_mps).is_some() && finite(p.t_s).is_some())
        .map(|p| p.run.clone())
        .collect()
}

/// The T-vs-v0 drift before and after (per-run T of the baseline and of the extended model).
pub fn drift(diag: &Diagnosis) -> Option<(Points, Points)> {
    let dr = diag.drift.as_ref()?;
    let (b, a) = (points(&dr.before), points(&dr.after));
    (!b.is_empty() && !a.is_empty()).then_some((b, a))
}

/// Render the drift before/after figure, or None when diagnosis.json has no drift data.
pub fn render_drift(diag: &Diagnosis) -> Result<Option<String>, String> {
    let Some((before, after)) = drift(diag) else {
        return Ok(None);
    };
    let (runs_before, runs_after) = diag
        .drift
        .as_ref()
        .map(|dr| (runs_of(&dr.before), runs_of(&dr.after)))
        .unwrap_or_default();
    let abs = |p: &[(f64, f64)]| p.iter().map(|(x, y)| (x.abs(), *y)).collect::<Vec<_>>();
    let (before, after) = (abs(&before), abs(&after));
    let xr = (0.0, span(before.iter().chain(&after).map(|p| p.0), 0.05).1);
    let yr = span(before.iter().chain(&after).map(|p| p.1).chain([0.0]), 0.08);
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            "Drift of the fitted drag time, before and after",
            xr,
            yr,
            "initial speed |v0| (m/s)",
            "drag time T (s)",
        )?;
        scatter_runs(
            &mut c,
            &before,
            &runs_before,
            Marker::Circle,
            style::BEFORE,
            false,
            Some("baseline fit: T per run"),
        )?;
        scatter_runs(
            &mut c,
            &after,
            &runs_after,
            Marker::Circle,
            style::AFTER,
            true,
            Some("extended model: T per run"),
        )?;
        for (p, col) in [(&before, style::BEFORE), (&after, style::AFTER)] {
            if let Some((a, b)) = super::common::ols(p) {
                line(
                    &mut c,
                    vec![(xr.0, a + b * xr.0), (xr.1, a + b * xr.1)],
                    col,
                    2,
                    false,
                    None,
                )?;
            }
        }
        legend(&mut c, SeriesLabelPosition::UpperLeft)
    })?;
    Ok(Some(svg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_wrap_to_their_category_and_the_last_fits_the_canvas() {
        let font = 17;
        assert_eq!(
            wrap("velocity dependent friction", 100.0, font),
            ["velocity", "dependent", "friction"]
        );
        assert_eq!(wrap("groove tilt", 200.0, font), ["groove tilt"]);
        // the last label's centre: half a category in from the plot's right edge
        for n in 1..9 {
            for half in [20.0, 60.0, 120.0] {
                let m = right_margin(half, n);
                let centre = f64::from(style::FIG_W) - f64::from(m) - category_px(m, n) / 2.0;
                assert!(
                    centre + half <= f64::from(style::FIG_W),
                    "n {n}, half {half}: margin {m}"
                );
                assert!(m >= style::MARGIN_RIGHT);
            }
        }
    }
}
