//! Figs. 4.3c–d: a collision run's striker and target trajectories, and the striker's four motion
//! segments (sliding and rolling, before and after the impact).

use super::common::{legend, line, linear_chart, render, render_high, scatter_sized, span};
use super::residual_strip::{self, TALL_H};
use crate::recording::Track;
use crate::report::collisions::CollisionRun;
use crate::report::inputs::ReportData;
use crate::report::style::{self, Marker};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

const STRIKER: RGBColor = RGBColor(120, 120, 120);
const TARGET: RGBColor = RGBColor(0, 170, 170);
const STRIKER_FIT: RGBColor = RGBColor(10, 10, 10);
const TARGET_FIT: RGBColor = RGBColor(0, 80, 80);

/// The fitted trajectory of `particle` over `track`'s times, in (ms, mm) pieces where it is defined.
fn fitted_pieces(
    c: &CollisionRun,
    particle: u32,
    track: &Track,
    z_ref: f64,
    g: crate::physics::Groove,
) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let step = (track.t_s.len() / 400).max(1);
    for &t in track.t_s.iter().step_by(step) {
        match c.fitted_z_m(particle, t, g) {
            Some(z) => cur.push((t * 1e3, (z - z_ref) * 1e3)),
            None if !cur.is_empty() => pieces.push(std::mem::take(&mut cur)),
            None => {}
        }
    }
    if !cur.is_empty() {
        pieces.push(cur);
    }
    pieces
}

/// Draw the fitted pieces of one particle as lines (one legend entry).
fn draw_fit<'a, 'b: 'a>(
    ch: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    pieces: Vec<Vec<(f64, f64)>>,
    colour: RGBColor,
    label: &str,
) -> super::common::Res {
    for (i, p) in pieces.into_iter().enumerate() {
        line(ch, p, colour, 2, false, (i == 0).then_some(label))?;
    }
    Ok(())
}

/// The collision run Figs. 4.3c–d show: `wanted`, else the first rolling-setup run with an impact
/// and two tracks, else any collision run with two tracks.
pub fn choose<'a>(d: &'a ReportData, wanted: Option<&str>) -> Option<&'a CollisionRun> {
    let has_tracks = |c: &&CollisionRun| {
        d.recordings
            .get(&c.run)
            .is_some_and(|r| r.tracks.len() >= 2)
    };
    if let Some(w) = wanted {
        return d.collisions.iter().find(|c| c.run == w);
    }
    d.collisions
        .iter()
        .filter(has_tracks)
        .find(|c| !c.contact && !c.impacts.is_empty())
        .or_else(|| d.collisions.iter().find(has_tracks))
}

/// Data − fitted model of `particle` (ms, µm) where the fit is defined, as many samples as drawn.
fn residuals(
    c: &CollisionRun,
    particle: u32,
    track: &Track,
    g: crate::physics::Groove,
) -> Vec<(f64, f64)> {
    let step = (track.t_s.len() / 200).max(1);
    track
        .t_s
        .iter()
        .zip(&track.z_m)
        .step_by(step)
        .filter_map(|(&t, &z)| Some((t * 1e3, (z - c.fitted_z_m(particle, t, g)?) * 1e6)))
        .collect()
}

fn pts(t: &Track, z_ref: f64, keep: impl Fn(f64) -> bool) -> Vec<(f64, f64)> {
    let step = (t.t_s.len() / 200).max(1);
    t.t_s
        .iter()
        .zip(&t.z_m)
        .step_by(step)
        .filter(|(t, _)| keep(**t))
        .map(|(t, z)| (t * 1e3, (z - z_ref) * 1e3))
        .collect()
}

/// Fig. 4.3c: both particles' positions of collision run `c`, the fitted pieces and the impacts
/// (`impacts`, ms).
fn render_fig_c(
    c: &CollisionRun,
    s: &Track,
    t: &Track,
    z_ref: f64,
    impacts: &[f64],
    g: crate::physics::Groove,
) -> Result<String, String> {
    let all_t = s.t_s.iter().chain(&t.t_s).map(|x| x * 1e3);
    let xr = span(all_t, 0.02);
    let yr = span(s.z_m.iter().chain(&t.z_m).map(|z| (z - z_ref) * 1e3), 0.05);
    let setup = if c.contact { "contact" } else { "rolling" };
    let cap_c = format!(
        "Fig. 4.3c: collision run {} ({}, {setup})",
        c.run, c.material
    );
    let strip = [
        (residuals(c, 0, s, g), STRIKER, "striker"),
        (residuals(c, 1, t, g), TARGET, "target"),
    ];
    render_high(TALL_H, |whole| {
        super::marks::figure_run(&c.run);
        let (root, below) = whole.split_vertically(style::FIG_H);
        residual_strip::draw(&below, xr, &strip)?;
        let root = &root;
        let mut ch = linear_chart(
            root,
            &cap_c,
            xr,
            yr,
            "time t (ms)",
            "position z − z_striker(0) (mm)",
        )?;
        scatter_sized(
            &mut ch,
            &pts(s, z_ref, |_| true),
            Marker::Circle,
            STRIKER,
            true,
            Some("striker (particle 0)"),
            3,
        )?;
        scatter_sized(
            &mut ch,
            &pts(t, z_ref, |_| true),
            Marker::Circle,
            TARGET,
            true,
            Some("target (particle 1)"),
            3,
        )?;
        draw_fit(
            &mut ch,
            fitted_pieces(c, 0, s, z_ref, g),
            STRIKER_FIT,
            "striker, fitted",
        )?;
        draw_fit(
            &mut ch,
            fitted_pieces(c, 1, t, z_ref, g),
            TARGET_FIT,
            "target, fitted",
        )?;
        for (i, ti) in impacts.iter().enumerate() {
            let label = (i == 0).then_some("impact");
            line(
                &mut ch,
                vec![(*ti, yr.0), (*ti, yr.1)],
                style::GREY,
                1,
                true,
                label,
            )?;
        }
        legend(&mut ch, SeriesLabelPosition::LowerRight)
    })
}

/// Fig. 4.3d: the striker `s` alone, each sample coloured by its segment's phase and marked by
/// whether it comes before the first impact.
fn render_fig_d(
    c: &CollisionRun,
    s: &Track,
    z_ref: f64,
    impacts: &[f64],
    g: crate::physics::Groove,
) -> Result<String, String> {
    let segs: Vec<_> = c.segments.iter().filter(|g| g.particle == 0).collect();
    let rolling_at = |t: f64| {
        segs.iter()
            .find(|g| t >= g.t_start_s && t <= g.t_end_s)
            .and_then(|g| g.t_switch_s)
            .is_some_and(|sw| t >= sw)
    };
    let first_impact = c.impacts.iter().filter_map(|i| i.t_s).next();
    let before = |t: f64| first_impact.is_none_or(|ti| t < ti);
    let sx = span(s.t_s.iter().map(|x| x * 1e3), 0.02);
    let sy = span(s.z_m.iter().map(|z| (z - z_ref) * 1e3), 0.05);
    let cap_d = format!("Fig. 4.3d: striker's motion segments, run {}", c.run);
    render(|root| {
        super::marks::figure_run(&c.run);
        let mut ch = linear_chart(
            root,
            &cap_d,
            sx,
            sy,
            "time t (ms)",
            "striker position z − z(0) (mm)",
        )?;
        let groups = [
            (
                true,
                false,
                Marker::Circle,
                style::SLIDING,
                "before impact: sliding",
            ),
            (
                true,
                true,
                Marker::Circle,
                style::ROLLING,
                "before impact: rolling",
            ),
            (
                false,
                false,
                Marker::Triangle,
                style::SLIDING,
                "after impact: sliding",
            ),
            (
                false,
                true,
                Marker::Triangle,
                style::ROLLING,
                "after impact: rolling",
            ),
        ];
        for (is_before, is_rolling, mk, col, label) in groups {
            let p = pts(s, z_ref, |t| {
                before(t) == is_before && rolling_at(t) == is_rolling
            });
            if !p.is_empty() {
                scatter_sized(&mut ch, &p, mk, col, true, Some(label), 3)?;
            }
        }
        draw_fit(
            &mut ch,
            fitted_pieces(c, 0, s, z_ref, g),
            STRIKER_FIT,
            "fitted segments",
        )?;
        for ti in impacts {
            line(
                &mut ch,
                vec![(*ti, sy.0), (*ti, sy.1)],
                style::GREY,
                1,
                true,
                None,
            )?;
        }
        legend(&mut ch, SeriesLabelPosition::LowerRight)
    })
}

/// Render Figs. 4.3c and 4.3d, or None without a collision run that has both tracks.
pub fn render_figs(
    d: &ReportData,
    wanted: Option<&str>,
) -> Result<Option<(String, String)>, String> {
    let Some(c) = choose(d, wanted) else {
        return Ok(None);
    };
    let Some(rec) = d.recordings.get(&c.run) else {
        return Ok(None);
    };
    let (Some(s), Some(t)) = (rec.track(0), rec.track(1)) else {
        return Ok(None);
    };
    let z_ref = s.z_m.first().copied().unwrap_or(0.0);
    let impacts: Vec<f64> = c
        .impacts
        .iter()
        .filter_map(|i| i.t_s)
        .map(|t| t * 1e3)
        .collect();
    let fig_c = render_fig_c(c, s, t, z_ref, &impacts, d.groove)?;
    let fig_d = render_fig_d(c, s, z_ref, &impacts, d.groove)?;
    Ok(Some((fig_c, fig_d)))
}
