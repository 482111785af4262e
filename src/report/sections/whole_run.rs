//! The whole-run collision fits in the report (beside Fig. 4.4a): the μ_pp profile per
//! material with what it says in words, the restitution law chosen by held-out error, and the
//! fits' status (summary.json → collisions.whole_run).

use super::{Block, Table};
use crate::artifacts::collision_fit::Estimate;
use crate::artifacts::diagnosis::Finding;
use crate::artifacts::summary::{MuPpProfile, ProfileVerdict, WholeRun, STOP_DEVIANCE};
use crate::report::inputs::ReportData;
use crate::report::value::serde_name;
use std::collections::BTreeMap;

/// The sentence about μ_pp of one material's profile verdict (`profile.verdict`).
pub fn mu_pp_words(material: &str, verdict: &ProfileVerdict) -> String {
    match *verdict {
        ProfileVerdict::Interval { estimate: e, lo, hi } => format!(
            "{material}: the profile has a minimum: μ_pp = {e:.3}, 95 % interval {lo:.3}–{hi:.3}; the chapter's 1.4 is {} it.",
            if lo <= 1.4 && 1.4 <= hi { "inside" } else { "outside" }
        ),
        ProfileVerdict::LowerBound { lo } => format!(
            "{material}: the profile is flat above: the recordings bound μ_pp from below at {lo:.2} (95 %), and the chapter's 1.4 is {}.",
            if lo <= 1.4 { "allowed but not measured" } else { "excluded" }
        ),
        ProfileVerdict::UpperBound { hi } => format!(
            "{material}: the profile is flat below: the recordings bound μ_pp from above at {hi:.2} (95 %)."
        ),
        ProfileVerdict::Unconstrained => format!("{material}: the profile is flat: the recordings do not constrain μ_pp over the range profiled."),
    }
}

/// Whether discovery accepted a friction that depends on the slip speed for `material` (its v_c
/// not at the search's floor): the whole-run fit holds μ_pg constant, so its μ_pp of that
/// material rests on a friction law the single runs reject. The words, or None.
pub fn speed_dependent_friction(d: &ReportData, material: &str) -> Option<String> {
    let f = d
        .diagnosis
        .as_ref()?
        .findings
        .iter()
        .find(|f| f.accepted && f.effect == "velocity_dependent_friction")?;
    let floor = format!("v_c of {material} at the search's floor");
    if super::params::at_bound(&f.where_)
        .iter()
        .any(|n| n.starts_with(&floor))
    {
        return None;
    }
    let vc = f.parameters.get(&format!("v_c_mps_{material}"))?.value;
    Some(format!(
        "{material}: discovery found this material's friction to depend on the slip speed (v_c = {} m/s); the whole-run model holds μ_pg constant, so its μ_pp of {material} rests on a friction law the single runs reject and is not a measurement of μ_pp.",
        crate::report::value::sig(vc, 3)
    ))
}

/// The single-run physics discovery accepted that the whole-run model (μ_pg and a saturating
/// drag fitted, made before discovery) does not carry: every accepted single-run effect but a
/// saturating drag and a speed-dependent friction (which has its own words). The words for
/// `material`, with μ_pp of discovery's pair check, which held that physics, or None.
pub fn uncarried_physics(d: &ReportData, material: &str) -> Option<String> {
    if super::under_accepted::whole_run_of(d, material).is_some() {
        // the refit carried it: 3.8 gives the numbers under it, no caveat is needed
        return None;
    }
    uncarried_words(&d.diagnosis.as_ref()?.findings, material)
}

fn uncarried_words(findings: &[Finding], material: &str) -> Option<String> {
    let names: Vec<String> = findings
        .iter()
        .filter(|f| {
            f.accepted
                && f.where_.get("experiment") != Some(&serde_json::json!("collision"))
                && f.effect != "velocity_dependent_friction"
                && !(f.effect == "velocity_dependent_drag" && f.form.starts_with("saturating"))
        })
        .map(|f| {
            format!(
                "{} ({})",
                f.effect.replace('_', " "),
                crate::report::formula::form(&f.form)
            )
        })
        .collect();
    if names.is_empty() {
        return None;
    }
    let held = findings
        .iter()
        .find(|f| {
            f.effect == "pair_physics_mismatch"
                && f.where_.get("material") == Some(&serde_json::json!(material))
        })
        .and_then(|f| f.where_.get("mu_pp_held"))
        .and_then(|h| Some((h.get("value")?.as_f64()?, h.get("converged")?.as_bool()?)));
    let check = match held {
        Some((mu, true)) => format!(
            " Discovery's pair check, which holds the single runs' accepted physics, fitted μ_pp = {mu:.3} (best fit; its error is not widened as the profile's is)."
        ),
        Some((mu, false)) => format!(
            " Discovery's pair check, which holds the single runs' accepted physics, ended at μ_pp = {mu:.3} without converging, so it gives no estimate of μ_pp."
        ),
        None => " Discovery's pair check did not fit this material's pairs (section 4 says why).".to_string(),
    };
    Some(format!(
        "{material}: discovery accepted for the single runs {}, which this whole-run model does not carry (it fits μ_pg and a saturating drag only), so its μ_pp and restitution laws of {material} are those of a model the single runs reject and can be biased by what it leaves out.{check}",
        names.join("; ")
    ))
}

fn fmt_param((name, p): (&str, &Estimate)) -> String {
    format!("{name} = {:.4} [{:.4}, {:.4}]", p.value, p.lo(), p.hi())
}

/// A best-fit value with its standard error, digits set by the error (a μ_pg known to 1e-5 is
/// not printed as `± 0.0000`).
fn fmt_est(e: &Estimate) -> String {
    crate::report::value::pm(*e)
}

/// How the profile's deviance was scaled: by the residuals' scale and serial correlation, by
/// the runs' dispersion, or not at all.
fn inflation_words(p: &MuPpProfile) -> String {
    let rho = p.score_lag1_autocorrelation;
    let rho_r = p.lag1_autocorrelation;
    let serial = p.serial_factor;
    let scale = p.scale_factor;
    let disp = p.dispersion;
    let noise = scale * serial;
    if p.inflation <= 1.0 {
        format!("the profile interval is not widened: the deviance's scale is {scale:.2}, the μ_pp score's lag-1 autocorrelation ρ = {rho:.2} (residuals' {rho_r:.2}) and the run dispersion {disp:.2}")
    } else if noise >= disp {
        format!("the profile interval is widened by the residuals: the deviance is divided by their scale {scale:.2} (mean ψ²/mean ψ′; the noise estimates are {}) times the serial-correlation factor (1 + ρ)/(1 − ρ) = {serial:.2} (the μ_pp score's lag-1 autocorrelation ρ = {rho:.2}, residuals' {rho_r:.2}), {noise:.2} in all (run dispersion {disp:.2})", if scale > 1.0 { "low" } else { "not low" })
    } else {
        format!("the profile interval is widened by the runs' dispersion: the deviance is divided by {disp:.2} (the residuals' scale {scale:.2}, the μ_pp score's lag-1 autocorrelation ρ = {rho:.2}, residuals' {rho_r:.2}, factor {serial:.2})")
    }
}

/// The grid values the profile did not fit, and why (None when it fitted them all).
fn not_fitted_words(p: &MuPpProfile) -> Option<String> {
    if p.not_fitted.is_empty() {
        return None;
    }
    let at: Vec<String> = p.not_fitted.iter().map(|mu| format!("{mu:.3}")).collect();
    Some(format!(
        "the profile was not fitted at μ_pp = {}: its walk along the grid stops in each direction after a fit beyond the estimate whose deviance rises more than {STOP_DEVIANCE:.0} above the best fit, where μ_pp is already excluded by far",
        at.join(", ")
    ))
}

/// The block, or None when the summary has no whole-run fits.
pub fn block(d: &ReportData, figs: &BTreeMap<String, String>) -> Option<Block> {
    let mats = &d.whole_run()?.materials;
    let mut b = Block::new("whole-run", "3.5.1 μ_pp and restitution from whole runs");
    b.para(
        "Each material's collision runs are fitted together, every run over its whole recording: the event-driven two-particle model (every impact, first and secondary, and the sliding and rolling of both particles between them) with shared μ_pg, drag $v/(T_0 + T'\\lvert v\\rvert)$, μ_pp and one restitution law per setup, and per run the kick speed, kick time, start position and gap. The secondary impacts slip, so the whole runs say what the first (stick) impacts cannot. The profile holds μ_pp at each value and refits everything else; its deviance is divided by the larger of the runs' dispersion (how much more the runs disagree than their noise says) and the residuals' own estimate of the same: their scale (mean ψ²/mean ψ′ of the Huber-clipped whitened residuals, above 1 when the noise estimates are low) times the serial-correlation factor (1 + ρ)/(1 − ρ), ρ the pooled lag-1 autocorrelation of the best fit's residuals weighted by their sensitivity to μ_pp (the μ_pp score): successive positions of a sliding sphere miss the model together, so the samples carry less independent information than their number says.",
    );
    b.figure(
        figs,
        "fig_mu_pp_profile.svg",
        "μ_pp profile: square root of the whole-run fit's deviance above its best (divided by the larger of the run dispersion and the residuals' scale times their serial-correlation factor), μ_pp held at each value (clipped at 12), on a linear μ_pp axis around the minimum; shaded, with a bar on the axis: each material's 95 % interval; dashed: the 95 % level and the chapter's 1.4 (where it lies on the axis).",
    );
    let mut t = Table::new(
        "Whole-run fits per material",
        &[
            "material",
            "runs",
            "status (iterations)",
            "μ_pp (best fit)",
            "μ_pg",
            "T0 (s)",
            "T' (s per m/s)",
            "RMS / noise",
            "run dispersion",
        ],
    );
    for m in mats {
        let name = &m.material;
        t.push(vec![
            name.to_string(),
            m.n_runs.to_string(),
            format!(
                "{} ({})",
                serde_name(&m.status).replace('_', " "),
                m.iterations
            ),
            fmt_est(&m.mu_pp),
            fmt_est(&m.mu_pg),
            fmt_est(&m.t0_s),
            fmt_est(&m.tp_s_per_mps),
            format!("{:.3}", m.rms_noise),
            format!("{:.2}", m.profile.dispersion),
        ]);
        b.para(mu_pp_words(name, &m.profile.verdict));
        if let Some(words) = speed_dependent_friction(d, name) {
            b.para(words);
        }
        if let Some(words) = uncarried_physics(d, name) {
            b.para(words);
        } else if super::under_accepted::whole_run_of(d, name).is_some() {
            b.para(format!("{name}: these are the baseline's fits; under the physics discovery accepted they are in 3.8, and the report trusts those."));
        }
        if let Some(w) = not_fitted_words(&m.profile) {
            b.para(format!("{name}: {w}."));
        }
        b.para(format!("{name}: {}.", inflation_words(&m.profile)));
        for n in &m.notes {
            b.para(format!("{name}: {n}."));
        }
    }
    b.table(t);
    let mut laws = Table::new(
        "Restitution law per material and setup, chosen by held-out error (k-fold over runs); parameters with 95 % intervals",
        &["material", "setup", "runs", "form", "parameters", "held-out RMS / noise"],
    );
    for m in mats {
        for c in &m.restitution {
            if let Some(law) = &c.discovered {
                laws.push(vec![
                    m.material.clone(),
                    serde_name(&c.setup),
                    c.n_runs.to_string(),
                    format!("**{}**", serde_name(&c.chosen)),
                    crate::report::impact_laws::discovered_law(law),
                    "— (not chosen: discovery's)".into(),
                ]);
            }
            for cand in &c.candidates {
                let form = serde_name(&cand.form);
                let params: Vec<String> = cand.ordered().into_iter().map(fmt_param).collect();
                laws.push(vec![
                    m.material.clone(),
                    serde_name(&c.setup),
                    c.n_runs.to_string(),
                    if cand.form == c.chosen {
                        format!("**{form}** (chosen)")
                    } else {
                        form
                    },
                    params.join("; "),
                    format!("{:.4}", cand.heldout_rms_noise),
                ]);
            }
        }
    }
    laws.folded = true;
    b.table(laws);
    let mut res = Table::new(
        "Pair residuals of the whole-run fits, RMS in units of the noise (mean over runs), by phase of the particle and by time since the last impact",
        &["material", "phase or time since impact", "RMS / noise", "runs"],
    );
    for m in mats {
        type ByKey = fn(&WholeRun) -> &BTreeMap<String, f64>;
        let keys: [ByKey; 2] = [
            |r| &r.residual_by_phase,
            |r| &r.residual_by_time_since_impact,
        ];
        for get in keys {
            let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
            for (k, x) in m.runs.iter().flat_map(get) {
                let e = acc.entry(k.clone()).or_default();
                e.0 += x;
                e.1 += 1;
            }
            for (k, (sum, n)) in acc {
                res.push(vec![
                    m.material.clone(),
                    k,
                    format!("{:.3}", sum / n.max(1) as f64),
                    n.to_string(),
                ]);
            }
        }
    }
    res.folded = true;
    b.table(res);
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_say_bound_or_interval_and_compare_with_the_chapter() {
        let lb = mu_pp_words("316", &ProfileVerdict::LowerBound { lo: 0.81 });
        assert!(
            lb.contains("bound μ_pp from below at 0.81") && lb.contains("allowed but not measured")
        );
        let iv = mu_pp_words(
            "440c",
            &ProfileVerdict::Interval {
                estimate: 1.39,
                lo: 1.35,
                hi: 1.43,
            },
        );
        assert!(
            iv.contains("μ_pp = 1.390") && iv.contains("1.4 is inside"),
            "{iv}"
        );
        let out = mu_pp_words(
            "440c",
            &ProfileVerdict::Interval {
                estimate: 0.3,
                lo: 0.29,
                hi: 0.31,
            },
        );
        assert!(out.contains("outside"), "{out}");
        let high = mu_pp_words("316", &ProfileVerdict::LowerBound { lo: 2.0 });
        assert!(high.contains("1.4 is excluded"), "{high}");
    }

    fn finding(effect: &str, form: &str, accepted: bool, where_: serde_json::Value) -> Finding {
        Finding {
            effect: effect.into(),
            accepted,
            form: form.into(),
            parameters: BTreeMap::new(),
            evidence: Default::default(),
            where_: serde_json::from_value(where_).unwrap(),
            baseline: Default::default(),
            extended: Default::default(),
        }
    }

    /// A wave the single runs accepted is named as not carried, with the pair check's μ_pp of
    /// the material asked for (not called an estimate when that fit did not converge); a
    /// saturating drag alone, a rejected wave, or a finding on the pairs themselves say nothing.
    #[test]
    fn single_run_physics_the_whole_run_fits_do_not_carry_is_said() {
        let pair = |m: &str, mu: f64| {
            finding(
                "pair_physics_mismatch",
                "μ_pg and drag",
                false,
                serde_json::json!({"experiment": "collision", "material": m, "mu_pp_held": {"value": mu, "stderr": 0.001, "converged": mu > 1.0}}),
            )
        };
        let drag = finding(
            "velocity_dependent_drag",
            "saturating: a = -v/(T0 + T'|v|)",
            true,
            serde_json::json!({}),
        );
        let wave = |accepted| {
            finding(
                "position_dependent_force",
                "periodic in z",
                accepted,
                serde_json::json!({}),
            )
        };
        let quiet = [
            drag.clone(),
            wave(false),
            pair("316", 1.2),
            pair("440c", 1.41),
        ];
        assert_eq!(uncarried_words(&quiet, "440c"), None);
        let found = [drag, wave(true), pair("316", 0.8), pair("440c", 1.41)];
        let words = uncarried_words(&found, "440c").unwrap();
        assert!(
            words.contains("position dependent force (periodic in z)")
                && words.contains("μ_pp = 1.410")
                && !words.contains("velocity dependent drag"),
            "{words}"
        );
        let stuck = uncarried_words(&found, "316").unwrap();
        assert!(
            stuck.contains("μ_pp = 0.800 without converging") && !stuck.contains("fitted μ_pp"),
            "{stuck}"
        );
        let untested = uncarried_words(&found[..2], "440c").unwrap();
        assert!(
            untested.contains("did not fit this material's pairs"),
            "{untested}"
        );
    }
}
