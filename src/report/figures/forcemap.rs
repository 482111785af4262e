//! Force-map figures: the missing acceleration against lab z, signed velocity and time since the
//! kick, with its 95 % band, for the baseline (grey) and after the accepted physics (green). A flat
//! map whose band holds zero is the picture of "nothing missing" in that variable.

use super::common::{legend, line, linear_chart, render, span};
use crate::artifacts::diagnosis::Diagnosis;
use crate::report::style;
use plotters::prelude::*;

/// (x, accel, se) of one map of `which` ("before"/"after") for `variable`.
fn map_of(diag: &Diagnosis, which: &str, variable: &str) -> Option<Vec<(f64, f64, f64)>> {
    let maps = diag.force_maps.as_ref()?;
    let list = if which == "before" {
        &maps.before
    } else {
        &maps.after
    };
    let m = list.iter().find(|m| m.variable == variable)?;
    let (x, a, s) = (&m.x, &m.accel_mps2, &m.se_mps2);
    (x.len() == a.len() && a.len() == s.len() && x.len() > 1).then(|| {
        x.iter()
            .zip(a)
            .zip(s)
            .map(|((x, a), s)| (*x, *a, *s))
            .collect()
    })
}

/// Scale and axis label of a variable.
fn axis(variable: &str) -> (f64, &'static str) {
    match variable {
        "z" => (1e3, "position in the lab z (mm)"),
        "v" => (1e3, "signed velocity v (mm/s)"),
        _ => (1e3, "time since the kick t (ms)"),
    }
}

/// The force map of `variable` before and after, or None when diagnosis.json has none.
pub fn render_map(diag: &Diagnosis, variable: &str) -> Result<Option<String>, String> {
    let before = map_of(diag, "before", variable);
    let after = map_of(diag, "after", variable);
    if before.is_none() && after.is_none() {
        return Ok(None);
    }
    let (sx, xdesc) = axis(variable);
    let all: Vec<&(f64, f64, f64)> = before.iter().chain(after.iter()).flatten().collect();
    let xr = span(all.iter().map(|p| p.0 * sx), 0.0);
    let yr = span(
        all.iter()
            .flat_map(|p| [p.1 - 1.96 * p.2, p.1 + 1.96 * p.2])
            .chain([0.0]),
        0.08,
    );
    let svg = render(|root| {
        let mut c = linear_chart(
            root,
            &format!("Force map in {variable}: missing acceleration, before and after"),
            xr,
            yr,
            xdesc,
            "missing acceleration (m/s²)",
        )?;
        line(
            &mut c,
            vec![(xr.0, 0.0), (xr.1, 0.0)],
            style::BLACK,
            1,
            true,
            None,
        )?;
        for (m, col, name) in [
            (&before, style::BEFORE, "baseline"),
            (&after, style::AFTER, "with the accepted physics"),
        ] {
            let Some(m) = m else { continue };
            let mut band: Vec<(f64, f64)> =
                m.iter().map(|p| (p.0 * sx, p.1 + 1.96 * p.2)).collect();
            band.extend(m.iter().rev().map(|p| (p.0 * sx, p.1 - 1.96 * p.2)));
            c.draw_series(std::iter::once(Polygon::new(band, col.mix(0.18).filled())))?;
            line(
                &mut c,
                m.iter().map(|p| (p.0 * sx, p.1)).collect(),
                col,
                2,
                false,
                Some(&format!("{name} (band: 95 %)")),
            )?;
        }
        legend(&mut c, SeriesLabelPosition::UpperRight)
    })?;
    Ok(Some(svg))
}
