//! Fig. 4.2d: fitted μ_pg against |v0| for each material, our means for |v0| > 0.03 m/s (solid) and the
//! chapter's means (dashed).

use super::common::{
    error_bars, legend, line, linear_chart, render, robust_span, scatter_runs, span,
};
use crate::report::inputs::ReportData;
use crate::report::summary::mu_fast;
use crate::report::{chapter, style};
use plotters::prelude::*;

/// Render Fig. 4.2d, or None without single-run fits.
pub fn render_fig(d: &ReportData) -> Result<Option<String>, String> {
    let mats: Vec<String> = d
        .materials()
        .into_iter()
        .filter(|m| d.singles_of(m).next().is_some())
        .collect();
    if mats.is_empty() {
        return Ok(None);
    }
    let x_max = span(d.singles.iter().map(|r| r.v0_mps.value.abs()), 0.05)
        .1
        .max(0.01);
    let mut ys: Vec<f64> = d
        .singles
        .iter()
        .filter(|r| r.converged())
        .map(|r| r.mu.value)
        .collect();
    ys.extend([chapter::MU_316, chapter::MU_440C]);
    let (lo, hi) = robust_span(ys, 0.03, 0.08);
    let yr = (lo.min(0.2), hi.max(0.4));
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            "Fig. 4.2d: particle–groove friction against initial speed",
            (0.0, x_max),
            yr,
            "initial speed |v0| (m/s)",
            "friction coefficient μ_pg (dimensionless)",
        )?;
        let t = chapter::MU_MEAN_V0_MIN_MPS;
        line(
            &mut c,
            vec![(t, yr.0), (t, yr.1)],
            style::GREY,
            1,
            true,
            None,
        )?;
        for (i, m) in mats.iter().enumerate() {
            let col = style::material_colour(m, i);
            // runs whose μ falls off the axis are counted in the legend; error bars longer than
            // a quarter of the axis (barely constrained μ of the slowest runs) are left out
            let inside = |y: f64| y >= yr.0 && y <= yr.1;
            let all: Vec<(f64, f64)> = d
                .singles_of(m)
                .map(|r| (r.v0_mps.value.abs(), r.mu.value))
                .collect();
            let runs: Vec<String> = d
                .singles_of(m)
                .filter(|r| inside(r.mu.value))
                .map(|r| r.run.clone())
                .collect();
            let pts: Vec<(f64, f64)> = all.iter().copied().filter(|p| inside(p.1)).collect();
            let off = all.len() - pts.len();
            let bars: Vec<(f64, f64, f64)> = d
                .singles_of(m)
                .filter_map(|r| Some((r.v0_mps.value.abs(), r.mu.value, r.mu.se?)))
                .filter(|b| inside(b.1) && b.2 < 0.25 * (yr.1 - yr.0))
                .collect();
            error_bars(&mut c, &bars, col)?;
            let label = if off > 0 {
                format!("{m}: fitted μ_pg ({off} off scale)")
            } else {
                format!("{m}: fitted μ_pg")
            };
            scatter_runs(
                &mut c,
                &pts,
                &runs,
                style::marker(m, false),
                col,
                true,
                Some(&label),
            )?;
            if let Some(a) = mu_fast(d, m) {
                let v = a.est.value;
                line(
                    &mut c,
                    vec![(t, v), (x_max, v)],
                    col,
                    3,
                    false,
                    Some(&format!("{m}: our mean {v:.3}")),
                )?;
            }
        }
        // the chapter's means on top, dark dashed, one legend entry for both
        let chapter_mats: Vec<(String, f64)> = mats
            .iter()
            .filter_map(|m| Some((m.clone(), chapter::mu_for(m)?)))
            .collect();
        let label = chapter_mats
            .iter()
            .map(|(m, v)| format!("{v:.3} ({m})"))
            .collect::<Vec<_>>()
            .join(", ");
        for (i, (_, v)) in chapter_mats.iter().enumerate() {
            let lab = (i == 0).then(|| format!("chapter: {label}"));
            line(
                &mut c,
                vec![(t, *v), (x_max, *v)],
                style::BLACK,
                2,
                true,
                lab.as_deref(),
            )?;
        }
        legend(&mut c, SeriesLabelPosition::LowerRight)
    })?;
    Ok(Some(svg))
}
