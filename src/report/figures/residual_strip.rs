//! The strip of residuals (data − model, µm) under a fitted-trajectory figure (Figs. 4.2b, 4.3c):
//! the same time axis, plot edges aligned with the chart above, drawn in the same SVG below it.

use super::common::Res;
use crate::report::style;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Height of the strip in SVG pixels, added below the figure's standard height.
pub const STRIP_H: u32 = 170;

/// The strip's axis description (the SVG text a reader and the tests find it by).
pub const Y_DESC: &str = "data − model (µm)";

/// A figure's canvas height with its residual strip.
pub const TALL_H: u32 = style::FIG_H + STRIP_H;

/// One series of residuals: (t ms, residual µm), its colour and its name (each point's title and
/// CSV row say it: "sliding", "striker").
pub type Series = (Vec<(f64, f64)>, RGBColor, &'static str);

/// The part name of the strip's points (`marks::part`): they go to `<figure>_residuals.csv`.
pub const PART: &str = "residuals";

/// A symmetric y range holding 99 % of the residuals, never empty.
fn limit(series: &[Series]) -> f64 {
    let mut a: Vec<f64> = series
        .iter()
        .flat_map(|(p, _, _)| p.iter().map(|q| q.1.abs()))
        .filter(|v| v.is_finite())
        .collect();
    a.sort_by(f64::total_cmp);
    let q = a
        .get((a.len().saturating_sub(1) as f64 * 0.99) as usize)
        .copied()
        .unwrap_or(0.0);
    if q > 0.0 {
        q * 1.15
    } else {
        1.0
    }
}

/// Draw the residual strip in `area` over the time range `x` (ms). Points beyond the range are
/// drawn on its edge.
pub fn draw(area: &DrawingArea<SVGBackend, Shift>, x: (f64, f64), series: &[Series]) -> Res {
    let lim = limit(series);
    let mut c = ChartBuilder::on(area)
        .margin(14)
        .margin_top(0)
        .margin_right(style::MARGIN_RIGHT)
        .x_label_area_size(44)
        .y_label_area_size(84)
        .build_cartesian_2d(x.0..x.1, -lim..lim)?;
    c.configure_mesh()
        .y_desc(Y_DESC)
        .label_style((style::FONT, style::TICK_PX))
        .axis_desc_style((style::FONT, style::TICK_PX))
        .light_line_style(style::LIGHT_GREY.mix(0.6))
        .bold_line_style(style::LIGHT_GREY)
        .x_labels(8)
        .y_labels(5)
        .draw()?;
    c.draw_series(LineSeries::new(
        vec![(x.0, 0.0), (x.1, 0.0)],
        style::BLACK.stroke_width(1),
    ))?;
    super::marks::part(PART, "time t (ms)", Y_DESC);
    for (pts, colour, name) in series {
        let shown: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .copied()
            .collect();
        for &(t, r) in &shown {
            // each point titled with its own value, drawn on the edge when beyond the range
            super::marks::add(super::marks::Mark {
                px: c.backend_coord(&(t, r.clamp(-lim, lim))),
                series: (*name).to_string(),
                run: String::new(),
                x: t,
                y: r,
            });
        }
        c.draw_series(
            shown
                .iter()
                .map(|p| Circle::new((p.0, p.1.clamp(-lim, lim)), 2, colour.filled())),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_range_holds_the_residuals_and_is_never_empty() {
        let s: Vec<Series> = vec![(
            (0..100)
                .map(|i| (i as f64, if i == 50 { 90.0 } else { (i % 5) as f64 - 2.0 }))
                .collect(),
            style::BLACK,
            "sliding",
        )];
        let lim = limit(&s);
        assert!((2.0..90.0).contains(&lim), "{lim}");
        assert_eq!(limit(&[]), 1.0);
    }
}
