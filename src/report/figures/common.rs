//! Drawing helpers shared by the figures: an SVG canvas rendered to a String, markers, error bars, lines.

use crate::report::style::{self, Marker};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// What every drawing step returns.
pub type Res = Result<(), Box<dyn std::error::Error>>;

/// Render one figure into an SVG string of the standard size.
pub fn render(draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Res) -> Result<String, String> {
    render_high(style::FIG_H, draw)
}

/// Render one figure of the standard width and `height` pixels high.
pub fn render_high(
    height: u32,
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Res,
) -> Result<String, String> {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (style::FIG_W, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        super::marks::open();
        let drawn = draw(&root).map_err(|e| format!("drawing a figure failed: {e}"));
        if let Err(e) = drawn {
            super::marks::close(String::new());
            return Err(e);
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(super::marks::close(out))
}

/// A linear chart with caption, axis descriptions (with units) and a light grid.
pub fn linear_chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    caption: &str,
    x: (f64, f64),
    y: (f64, f64),
    x_desc: &str,
    y_desc: &str,
) -> Result<
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    Box<dyn std::error::Error>,
> {
    super::marks::axes(x_desc, y_desc);
    let mut chart = ChartBuilder::on(root)
        .caption(caption, (style::FONT, style::CAPTION_PX))
        .margin(14)
        .margin_right(style::MARGIN_RIGHT)
        .x_label_area_size(56)
        .y_label_area_size(84)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((style::FONT, style::TICK_PX))
        .axis_desc_style((style::FONT, style::LABEL_PX))
        .light_line_style(style::LIGHT_GREY.mix(0.6))
        .bold_line_style(style::LIGHT_GREY)
        .x_labels(8)
        .y_labels(8)
        .draw()?;
    Ok(chart)
}

/// Scatter `pts` with a material's marker; `label` puts it in the legend.
pub fn scatter<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    marker: Marker,
    colour: RGBColor,
    filled: bool,
    label: Option<&str>,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    scatter_sized(chart, pts, marker, colour, filled, label, 5)
}

/// `scatter` of one point per run, each point titled with its run (`runs[i]` is `pts[i]`'s).
#[allow(clippy::too_many_arguments)]
pub fn scatter_runs<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    runs: &[String],
    marker: Marker,
    colour: RGBColor,
    filled: bool,
    label: Option<&str>,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    draw_points(chart, pts, Some(runs), marker, colour, filled, label, 5)
}

/// `scatter` with marker radius `r` pixels (small markers for dense trajectories).
pub fn scatter_sized<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    marker: Marker,
    colour: RGBColor,
    filled: bool,
    label: Option<&str>,
    r: i32,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    draw_points(chart, pts, None, marker, colour, filled, label, r)
}

/// Draw the points with their marker, note each (pixel, run, values) for its title and the CSV,
/// and the label for the legend.
#[allow(clippy::too_many_arguments)]
fn draw_points<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    runs: Option<&[String]>,
    marker: Marker,
    colour: RGBColor,
    filled: bool,
    label: Option<&str>,
    r: i32,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let area = chart.plotting_area().get_pixel_range();
    for (i, &(x, y)) in pts.iter().enumerate() {
        let px = chart.backend_coord(&(x, y));
        // a point outside the axes' ranges is not drawn (plotters clips it)
        if !area.0.contains(&px.0) || !area.1.contains(&px.1) || !x.is_finite() || !y.is_finite() {
            continue;
        }
        super::marks::add(super::marks::Mark {
            px,
            series: label.unwrap_or("").to_string(),
            run: runs.and_then(|r| r.get(i)).cloned().unwrap_or_default(),
            x,
            y,
        });
    }
    if let Some(label) = label {
        super::marks::label(label);
    }
    let st = if filled {
        colour.filled()
    } else {
        colour.stroke_width(2)
    };
    let pts = pts.to_vec();
    let anno = match marker {
        Marker::Circle => chart.draw_series(pts.into_iter().map(move |p| Circle::new(p, r, st)))?,
        Marker::Square => chart.draw_series(pts.into_iter().map(move |p| {
            EmptyElement::at(p) + Rectangle::new([(1 - r, 1 - r), (r - 1, r - 1)], st)
        }))?,
        Marker::Triangle => chart.draw_series(
            pts.into_iter()
                .map(move |p| TriangleMarker::new(p, r + 1, st)),
        )?,
        Marker::Diamond => chart.draw_series(pts.into_iter().map(move |p| {
            EmptyElement::at(p)
                + Polygon::new(vec![(0, -r - 1), (r + 1, 0), (0, r + 1), (-r - 1, 0)], st)
        }))?,
    };
    // the legend's sample of a series is the very element its points are drawn with (shape,
    // size, filled or open), so the legend shows what the plot shows
    if let Some(label) = label {
        let anno = anno.label(label);
        let at = |(x, y): (i32, i32)| EmptyElement::at((x + 8, y));
        match marker {
            Marker::Circle => anno.legend(move |p| at(p) + Circle::new((0, 0), r, st)),
            Marker::Square => {
                anno.legend(move |p| at(p) + Rectangle::new([(1 - r, 1 - r), (r - 1, r - 1)], st))
            }
            Marker::Triangle => {
                anno.legend(move |p| at(p) + TriangleMarker::new((0, 0), r + 1, st))
            }
            Marker::Diamond => anno.legend(move |p| {
                at(p) + Polygon::new(vec![(0, -r - 1), (r + 1, 0), (0, r + 1), (-r - 1, 0)], st)
            }),
        };
    }
    Ok(())
}

/// Vertical error bars of ±`err` at each (x, y).
pub fn error_bars<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64, f64)],
    colour: RGBColor,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let st = colour.mix(0.5).stroke_width(1);
    chart.draw_series(
        pts.iter()
            .filter(|(_, _, e)| e.is_finite() && *e > 0.0)
            .map(move |&(x, y, e)| PathElement::new(vec![(x, y - e), (x, y + e)], st)),
    )?;
    Ok(())
}

/// A polyline; `dashed` for reference values (the chapter's), solid for ours.
pub fn line<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pts: Vec<(f64, f64)>,
    colour: RGBColor,
    width: u32,
    dashed: bool,
    label: Option<&str>,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let st = colour.stroke_width(width);
    let anno = if dashed {
        chart.draw_series(DashedLineSeries::new(pts, 9, 6, st))?
    } else {
        chart.draw_series(LineSeries::new(pts, st))?
    };
    if let Some(label) = label {
        super::marks::label(label);
        // a dashed sample is two short strokes, a solid one a single stroke
        let gap = if dashed { (7, 12) } else { (18, 18) };
        anno.label(label).legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (gap.0, 0)], st)
                + PathElement::new(vec![(gap.1, 0), (20, 0)], st)
        });
    }
    Ok(())
}

/// Draw the legend box in the given corner, or, when a data point lies under it there, in the
/// first corner or middle where none does, else the first place of a 10-pixel grid over the plot
/// where none does (else where the fewest do).
pub fn legend<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>,
    pos: SeriesLabelPosition,
) -> Res
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    use SeriesLabelPosition::*;
    let (w, h) = legend_size(&super::marks::labels())?;
    let (base, dim) = (
        chart.plotting_area().get_base_pixel(),
        chart.plotting_area().dim_in_pixel(),
    );
    let place = |p: &SeriesLabelPosition| -> (i32, i32) {
        let x = match p {
            UpperLeft | MiddleLeft | LowerLeft => 5,
            UpperMiddle | MiddleMiddle | LowerMiddle => (dim.0 as i32 - w) / 2,
            _ => dim.0 as i32 - w - 5,
        };
        let y = match p {
            UpperLeft | UpperMiddle | UpperRight => 5,
            MiddleLeft | MiddleMiddle | MiddleRight => (dim.1 as i32 - h) / 2,
            _ => dim.1 as i32 - h - 5,
        };
        (x, y)
    };
    let points = super::marks::drawn();
    let covered = |(x, y): (i32, i32)| {
        let (x0, y0) = (base.0 + x - 7, base.1 + y - 7);
        points
            .iter()
            .filter(|p| p.0 >= x0 && p.0 <= x0 + w + 14 && p.1 >= y0 && p.1 <= y0 + h + 14)
            .count()
    };
    let order = [
        pos,
        UpperRight,
        UpperLeft,
        LowerRight,
        LowerLeft,
        UpperMiddle,
        LowerMiddle,
        MiddleRight,
        MiddleLeft,
    ];
    // when every corner and middle covers a point, any place of the plot on a 10-pixel grid
    let free = (dim.0 as i32 - w - 10).max(0);
    let tall = (dim.1 as i32 - h - 10).max(0);
    let grid = (0..=tall / 10).flat_map(|j| (0..=free / 10).map(move |i| (5 + 10 * i, 5 + 10 * j)));
    let spot = order
        .iter()
        .map(place)
        .chain(grid)
        .enumerate()
        .min_by_key(|(i, at)| (covered(*at), *i))
        .map(|(_, at)| at)
        .unwrap_or((5, 5));
    chart
        .configure_series_labels()
        .position(Coordinate(spot.0, spot.1))
        .label_font((style::FONT, style::LEGEND_PX))
        .background_style(WHITE.mix(0.85))
        .border_style(style::GREY)
        .margin(10)
        .draw()?;
    Ok(())
}

/// The legend box's size in pixels for these labels, as plotters lays it out (label text, the
/// 30-pixel sample area and a 10-pixel margin on each side).
fn legend_size(labels: &[String]) -> Result<(i32, i32), Box<dyn std::error::Error>> {
    let font: TextStyle = (style::FONT, style::LEGEND_PX).into_font().into();
    let mut text = MultiLineText::<_, &str>::new((0, 0), &font);
    for l in labels {
        text.push_line(l.as_str());
    }
    let (w, h) = text
        .estimate_dimension()
        .map_err(|e| format!("legend text: {e:?}"))?;
    Ok((w + 30 + 20, h + 20))
}

/// A padded range covering `values` (and `extra`); a sensible unit range when empty or flat.
pub fn span(values: impl IntoIterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 * (1.0 + hi.abs()) {
        let d = if hi.abs() > 0.0 { hi.abs() * 0.1 } else { 1.0 };
        return (lo - d, hi + d);
    }
    let d = (hi - lo) * pad;
    (lo - d, hi + d)
}

/// Like `span`, over the central part of the values (quantiles `q` and 1 − `q`), so a few wild
/// per-run estimates (e.g. μ of the slowest runs, barely constrained) do not squash the axis.
pub fn robust_span(values: impl IntoIterator<Item = f64>, q: f64, pad: f64) -> (f64, f64) {
    let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
    if v.len() < 10 {
        return span(v, pad);
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| crate::stats::quantile_nearest(&v, p);
    span([at(q), at(1.0 - q)], pad)
}

/// Least-squares line y = a + b x; None with fewer than two distinct x.
pub fn ols(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    let (x, y): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
    let all: Vec<usize> = (0..pts.len()).collect();
    let (a, b) = crate::stats::ols_indexed(&x, &y, &all);
    (!a.is_nan() && !b.is_nan()).then_some((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ols_recovers_a_line() {
        let pts: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 0.052 + 1.1 * i as f64)).collect();
        let (a, b) = ols(&pts).unwrap();
        assert!((a - 0.052).abs() < 1e-12 && (b - 1.1).abs() < 1e-12);
        assert_eq!(span([], 0.1), (0.0, 1.0));
    }
}
