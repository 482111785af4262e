//! The opening sentences of sections 3.1, 3.4–3.7, 5 and 6: what each found, from this run's
//! numbers (a run's fit, its residuals, the impacts, the audit's verdicts), in one or two sentences.

use crate::physics::Groove;
use crate::report::collisions::CollisionRun;
use crate::report::inputs::ReportData;
use crate::report::singles::SingleRow;
use crate::report::value::sig;

/// The median of `v` (None when empty).
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    let n = v.len();
    (n > 0).then(|| (v[(n - 1) / 2] + v[n / 2]) / 2.0)
}

/// 3.1: how long the example run slides, and how closely the baseline follows it.
pub fn trajectory(d: &ReportData, fit: &SingleRow) -> String {
    let slide = fit.t1_s.map_or(String::new(), |t1| {
        format!(" slides for {:.2} ms, then rolls;", t1 * 1e3)
    });
    let rms = fit.rms_m.map_or(String::new(), |r| {
        let typical = median(d.singles.iter().filter_map(|s| s.rms_m).collect());
        format!(
            " to {:.2} µm RMS{}",
            r * 1e6,
            typical.map_or(String::new(), |m| format!(
                " ({:.2} µm in the median single run)",
                m * 1e6
            ))
        )
    });
    format!(
        "Run {} ({}, v0 = {} m/s){slide} the baseline with μ_pg = {} and T = {} s follows it{rms}.{}",
        fit.run,
        fit.material,
        sig(fit.v0_mps.value, 3),
        sig(fit.mu.value, 3),
        sig(fit.t_drag_s.value, 3),
        under_accepted(d, fit)
    )
}

/// 3.1, when discovery accepted physics: how closely the run's fit under it follows the run,
/// beside the baseline's curve over the same samples.
fn under_accepted(d: &ReportData, fit: &SingleRow) -> String {
    let Some(s) = crate::report::figures::fig_4_2b::samples(d, fit) else {
        return String::new();
    };
    let Some(z) = crate::report::accepted_curve::curve(d, fit, &s) else {
        return String::new();
    };
    // the residuals' robust scale (1.4826 × median |r|: a tracking outlier does not set it)
    let scale = |f: &dyn Fn(usize) -> f64| {
        let r: Vec<f64> = (0..s.len()).map(|i| (s[i].z_obs_m - f(i)).abs()).collect();
        median(r).map_or(f64::NAN, |m| 1.4826 * m)
    };
    let (accepted, baseline) = (scale(&|i| z[i]), scale(&|i| s[i].z_fit_m));
    let head = "Fitted again under the physics discovery accepted (section 3.8: the material's μ and drag, the run's own start), its residuals";
    if (accepted - baseline).abs() < 0.05 * baseline {
        format!(
            " {head} scatter as much as about the baseline's curve ({:.2} µm, 1.4826 × median |residual|): on this run the two models differ by less than the noise. The residuals below are this fit's.",
            accepted * 1e6
        )
    } else {
        format!(
            " {head} scatter {:.2} µm (1.4826 × median |residual|), against {:.2} µm about the baseline's curve over the same frames; the residuals below are this fit's.",
            accepted * 1e6,
            baseline * 1e6
        )
    }
}

/// RMS (m) of data − fitted segments of both particles of `c`, where a segment is fitted.
fn collision_rms(d: &ReportData, c: &CollisionRun) -> Option<f64> {
    let rec = d.recordings.get(&c.run)?;
    let mut sum = 0.0;
    let mut n = 0usize;
    for (p, track) in rec.tracks.iter().take(2).enumerate() {
        for (&t, &z) in track.t_s.iter().zip(&track.z_m) {
            if let Some(f) = c.fitted_z_m(p as u32, t, d.groove) {
                sum += (z - f).powi(2);
                n += 1;
            }
        }
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// 3.4: the chosen collision run's impacts and how closely its segments fit.
pub fn collision(d: &ReportData, c: &CollisionRun) -> String {
    let first = c.impacts.first();
    let hit = match first {
        None => "no impact was fitted".to_string(),
        Some(i) => format!(
            "the striker hits the target {} at {} m/s{}{}",
            match i.t_s {
                Some(t) => format!("at t = {:.1} ms", t * 1e3),
                None => "once".into(),
            },
            sig(i.speed_mps, 3),
            i.restitution
                .map_or(String::new(), |r| format!(" (C = {r:.3})")),
            match c.impacts.len() {
                1 => String::new(),
                n => format!(", then {} more time{}", n - 1, if n > 2 { "s" } else { "" }),
            }
        ),
    };
    let fit = collision_rms(d, c).map_or(String::new(), |r| {
        format!(
            "; the fitted segments follow both particles to {:.2} µm RMS",
            r * 1e6
        )
    });
    format!("In run {} ({}) {hit}{fit}.", c.run, c.material)
}

/// 3.5: μ_pp from the slip impacts, or the bound the stick impacts give.
pub fn mu_pp(d: &ReportData) -> Option<String> {
    let impacts: Vec<_> = d.collisions.iter().flat_map(|c| &c.impacts).collect();
    let slip = impacts.iter().filter(|i| i.slip == Some(true)).count();
    let stick = impacts.iter().filter(|i| i.slip == Some(false)).count();
    let lower = crate::report::summary::mu_pp_stick_lower_bound(d);
    let est = crate::report::summary::mu_pp(d, d.groove.k);
    Some(match (est, lower) {
        (Some(a), lb) if slip > 0 => format!(
            "μ_pp = {}{} from {slip} slip impact{} (the chapter: 1.4){}.",
            sig(a.est.value, 3),
            a.interval
                .map_or(String::new(), |(lo, hi)| format!(" [{}, {}]", sig(lo, 3), sig(hi, 3))),
            if slip == 1 { "" } else { "s" },
            lb.map_or(String::new(), |b| format!(
                "; the {stick} stick impacts require μ_pp > {b:.2}"
            ))
        ),
        (_, Some(b)) => format!(
            "No impact here resolves a slip, so the slope gives no μ_pp; the {stick} stick impact{} bound it from below, μ_pp > {b:.2}, {}.",
            if stick == 1 { "" } else { "s" },
            if b > 1.4 { "which excludes the chapter's 1.4" } else { "consistent with the chapter's 1.4" }
        ),
        (Some(a), None) => format!(
            "μ_pp = {} ({}), against the chapter's 1.4.",
            sig(a.est.value, 3),
            a.source
        ),
        (None, None) => return None,
    })
}

/// 3.6: where C lies and whether it falls with impact speed, per setup.
pub fn restitution(d: &ReportData) -> Option<String> {
    let mut parts = Vec::new();
    let mut falls = Vec::new();
    for (contact, name) in [(false, "rolling pairs"), (true, "pairs in contact")] {
        let mut p: Vec<(f64, f64)> = d
            .collisions
            .iter()
            .filter(|c| c.contact == contact)
            .flat_map(|c| &c.impacts)
            .filter_map(|i| Some((i.speed_mps, i.restitution?)))
            .filter(|q| q.0.is_finite() && q.1.is_finite())
            .collect();
        if p.len() < 2 {
            continue;
        }
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        let half = p.len() / 2;
        let slow = p[..half].iter().map(|q| q.1).sum::<f64>() / half as f64;
        let fast = p[half..].iter().map(|q| q.1).sum::<f64>() / (p.len() - half) as f64;
        parts.push(format!(
            "for {name} ({} impacts, {}–{} m/s) the mean C is {slow:.2} in the slower half and {fast:.2} in the faster",
            p.len(),
            sig(p[0].0, 2),
            sig(p[p.len() - 1].0, 2)
        ));
        falls.push((name, fast < slow));
    }
    if parts.is_empty() {
        return None;
    }
    let mut s = parts.join("; ");
    s[..1].make_ascii_uppercase();
    let verdict = if falls.iter().all(|f| f.1) {
        "C falls with impact speed, as in the chapter".to_string()
    } else if falls.iter().all(|f| !f.1) {
        "C does not fall with impact speed here, unlike in the chapter".to_string()
    } else {
        let by = |x: bool| {
            falls
                .iter()
                .filter(|f| f.1 == x)
                .map(|f| f.0)
                .collect::<Vec<_>>()
                .join(" and ")
        };
        format!(
            "C falls with impact speed for {} but not for {}",
            by(true),
            by(false)
        )
    };
    Some(format!("{s}: {verdict}."))
}

/// 5: the defects the audit confirms, by their titles (each carries its computed number).
pub fn audit(items: &[crate::report::audit::AuditItem]) -> Option<String> {
    (!items.is_empty()).then(|| {
        let titles: Vec<&str> = items.iter().map(|a| a.title.as_str()).collect();
        format!(
            "Recomputed with groove's physics module, {} statements of the chapter do not hold as printed: {}.",
            items.len(),
            titles.join("; ")
        )
    })
}

/// 6: what made this report, in one sentence.
pub fn provenance(p: &crate::artifacts::Provenance) -> String {
    format!(
        "Made by groove {} with seed {} from {} input file{} through {} upstream stage{}, each named below by its hash, code commit and params; the same inputs and code give a byte-identical report.",
        p.groove_version,
        p.seed,
        p.inputs.len(),
        if p.inputs.len() == 1 { "" } else { "s" },
        p.stages.len(),
        if p.stages.len() == 1 { "" } else { "s" },
    )
}

/// 3.7: what the groove's factor means for secondary collisions.
pub fn secondary(g: Groove, theta_deg: f64, bound_deg: f64) -> String {
    let f = g.collision_factor();
    if theta_deg < bound_deg {
        format!(
            "With θ = {theta_deg:.1}° < {bound_deg:.1}° each collision leaves {:.0} % of the velocity difference, so the pair collides again and again (forever in the ideal model) and ends up rolling about 2R apart.",
            f * 100.0
        )
    } else {
        format!(
            "With θ = {theta_deg:.1}° ≥ {bound_deg:.1}° the factor is {f:.2}, not positive: after a collision and the re-acceleration the target rolls at least as fast as the striker, so no secondary collision follows."
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(vec![f64::NAN]), None);
    }
}
