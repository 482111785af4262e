//! Section 1: what was analysed, the key parameters with uncertainties, and what discovery found.

use super::{Block, Table};
use crate::artifacts::diagnosis::CONTACT_NOT_PHYSICS;
use crate::artifacts::Diagnosis;
use crate::report::inputs::ReportData;
use crate::report::summary::{mu_fast, mu_pp, t_line, Agg};
use crate::report::value::{count, pm};

/// `value ± se [lo, hi]` of an aggregate.
pub fn agg_text(a: &Agg) -> String {
    match a.interval {
        Some((lo, hi)) => format!(
            "{} [{}, {}]",
            pm(a.est),
            crate::report::value::sig(lo, 4),
            crate::report::value::sig(hi, 4)
        ),
        None => pm(a.est),
    }
}

/// One line per accepted finding of diagnosis.json, e.g. "velocity_dependent_drag (saturating): T0 = …".
pub fn accepted_findings(diag: &Diagnosis) -> Vec<String> {
    diag.findings
        .iter()
        .filter(|f| f.accepted)
        .map(|f| {
            let bounds = super::params::at_bound(&f.where_);
            let tie = super::verdict::tied_with(f).map_or(String::new(), |other| {
                format!(
                    "; but these data cannot tell {} from {other}, which predicts held-out runs as well",
                    crate::report::formula::form(&f.form)
                )
            });
            let pairs = f
                .where_
                .get("material")
                .and_then(|v| v.as_str())
                .filter(|_| f.where_.get("experiment").and_then(|v| v.as_str()) == Some("collision"))
                .map_or(String::new(), |m| format!(" in the {m} pairs"));
            format!(
                "{}{pairs} ({}): {}{}{tie}",
                f.effect.replace('_', " "),
                crate::report::formula::form(&f.form),
                super::params::params_text(&f.parameters),
                if bounds.is_empty() {
                    String::new()
                } else {
                    format!(" (at a bound: {})", bounds.join("; "))
                }
            )
        })
        .collect()
}

pub fn block(d: &ReportData) -> Block {
    let mut b = Block::new("summary", "1. Summary");
    let n_single = d.singles.len();
    let n_coll = d.collisions.len();
    let mats = d.materials();
    b.para(format!(
        "Analysed {}: {} with a baseline fit and {}, materials {}.",
        count(d.recordings.len().max(n_single + n_coll), "recorded run"),
        count(n_single, "single-particle run"),
        count(n_coll, "collision run"),
        if mats.is_empty() {
            "none".to_string()
        } else {
            mats.join(", ")
        }
    ));
    let mut t = Table::new("Key parameters (± standard error, [bootstrap interval] where the aggregate stage gives one)", &[
        "quantity", "ours", "chapter", "source",
    ]);
    let trusted = super::under_accepted::trusted(d).and_then(|u| u.single.as_ref());
    for (m, sm) in trusted.into_iter().flat_map(|s| &s.materials) {
        t.push(vec![
            format!("μ_pg of {m} (under the accepted physics)"),
            super::under_accepted::est_text(&sm.mu),
            crate::report::chapter::mu_for(m).map_or("—".into(), |v| format!("{v:.3}")),
            "under_accepted_physics.json (3.8)".into(),
        ]);
        if let Some(l) = sm.t_line {
            t.push(vec![
                format!(
                    "drag {} of {m}: $T_0$ (s)",
                    crate::report::formula::DRAG_LINE
                ),
                super::under_accepted::est_text(&l.intercept_s),
                "—".into(),
                "under_accepted_physics.json (3.8)".into(),
            ]);
            t.push(vec![
                format!(
                    "drag {} of {m}: $T'$ (s per m/s)",
                    crate::report::formula::DRAG_LINE
                ),
                super::under_accepted::est_text(&l.slope_s_per_mps),
                "—".into(),
                "under_accepted_physics.json (3.8)".into(),
            ]);
        }
    }
    for m in mats.iter().filter(|_| trusted.is_none()) {
        if let Some(a) = mu_fast(d, m) {
            let ch = crate::report::chapter::mu_for(m).map_or("—".into(), |v| format!("{v:.3}"));
            t.push(vec![
                format!("μ_pg of {m} (|v0| > 0.03 m/s)"),
                agg_text(&a),
                ch,
                a.source.into(),
            ]);
        }
    }
    if let Some((a, s)) = t_line(d, None).filter(|_| trusted.is_none()) {
        t.push(vec![
            "T(v0) intercept T0, all runs (s)".into(),
            agg_text(&a),
            "0.052".into(),
            a.source.into(),
        ]);
        t.push(vec![
            "T(v0) slope T', all runs (s per m/s)".into(),
            agg_text(&s),
            "1.10".into(),
            s.source.into(),
        ]);
    }
    if let Some(a) = mu_pp(d, d.groove.k) {
        t.push(vec![
            "μ_pp (particle–particle friction)".into(),
            agg_text(&a),
            "1.4".into(),
            a.source.into(),
        ]);
    } else if let Some(lb) = crate::report::summary::mu_pp_stick_lower_bound(d) {
        t.push(vec![
            "μ_pp (only bounded: no slip impact resolved)".into(),
            format!("> {lb:.2}"),
            "1.4".into(),
            "stick impacts".into(),
        ]);
    }
    // μ_pp of the whole-run fits: the profile's interval or bound per material
    // (under the accepted physics where the refit made the fit again: the trusted column)
    for base in d.whole_run().into_iter().flat_map(|w| &w.materials) {
        let name = &base.material;
        let refit = super::under_accepted::whole_run_of(d, name);
        let m = refit.unwrap_or(base);
        let text = super::under_accepted::verdict_text(&m.profile.verdict);
        let caveat = if refit.is_some() {
            ", under the accepted physics: see 3.8"
        } else if super::whole_run::speed_dependent_friction(d, name).is_some() {
            "; assumes a constant μ_pg, which discovery rejected for this material: see 3.5.1"
        } else if super::whole_run::uncarried_physics(d, name).is_some() {
            "; without the single-run physics discovery accepted: see 3.5.1"
        } else {
            ""
        };
        t.push(vec![
            format!("μ_pp of {name} (whole-run profile, 95 %{caveat})"),
            text,
            "1.4".into(),
            if refit.is_some() {
                "under_accepted_physics.json".into()
            } else {
                "summary.json".into()
            },
        ]);
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
    // what discovery found leads the summary
    match &d.diagnosis {
        None => b.lead = Some("Discovery did not run for this report (no diagnosis.json).".into()),
        Some(diag) => {
            let acc = accepted_findings(diag);
            b.lead = Some(if diag.candidates.is_empty() && diag.findings.is_empty() {
                untested(diag)
            } else if acc.is_empty() {
                if diag.mismatch {
                    "Discovery located a mismatch between the baseline and the recordings but accepted no candidate physics; see section 4.".to_string()
                } else {
                    clean(diag)
                }
            } else {
                format!(
                    "Discovery found missing physics and accepted: {}.",
                    acc.join("; ")
                )
            });
            if let Some(text) = contact_warning(diag) {
                b.para(text);
            }
        }
    }
    b
}

/// The summary of a discovery that tested nothing (too few runs): it says so, and why.
fn untested(diag: &Diagnosis) -> String {
    let note = diag.note.trim().trim_end_matches('.');
    if note.is_empty() {
        "Discovery tested nothing on this dataset, so nothing can be said about missing physics; see section 4.".into()
    } else {
        let mut c = note.chars();
        let first: String = c.next().into_iter().flat_map(char::to_uppercase).collect();
        format!("{first}{}; see section 4.", c.as_str())
    }
}

/// The summary of a clean discovery: nothing found, within the detection limits it had on these
/// runs (its power), or with no limit to give.
fn clean(diag: &Diagnosis) -> String {
    let limits = super::discovery::detection_limits(diag);
    let runs = count(diag.runs_used, "single run");
    if limits.is_empty() {
        format!("Discovery found nothing missing in {runs}, but gave no detection limit, so how small a missing term it could have missed is not known; see section 4.")
    } else {
        let sizes: Vec<&str> = limits
            .iter()
            .map(|l| l.trim_end_matches(" would have been found"))
            .collect();
        let list = match sizes.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => sizes.join(""),
        };
        format!(
            "Discovery found nothing missing in {runs}: the baseline (Coulomb friction plus linear drag) explains the recordings within their noise; it would have found {list} (its detection limits, section 4)."
        )
    }
}

/// A warning when the pair test found the pairs touching at another distance than the diameter
/// in runs.csv (a length calibration error or a wrong diameter), naming the materials.
fn contact_warning(diag: &Diagnosis) -> Option<String> {
    let found: Vec<String> = diag
        .findings
        .iter()
        .filter(|f| f.evidence.decision.starts_with(CONTACT_NOT_PHYSICS))
        .map(|f| {
            let material = f
                .where_
                .get("material")
                .and_then(|m| m.as_str())
                .unwrap_or("?");
            let scale = f
                .where_
                .get("contact_over_diameter")
                .and_then(|c| c.get("value"))
                .and_then(|v| v.as_f64())
                .unwrap_or(f64::NAN);
            format!("{material} at {scale:.4} ×")
        })
        .collect();
    (!found.is_empty()).then(|| {
        format!(
            "Check the length calibration (metres per pixel) and the diameter in runs.csv: the collision runs fit best touching at another distance than the diameter ({} the diameter), better than with friction or drag of their own; see section 4.",
            found.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped diagnosis with its accepted drag tied with another form: the summary's lead
    /// says the data cannot tell the two apart.
    #[test]
    fn a_tie_is_said_in_the_summary_as_undecidable() {
        let mut diag = crate::artifacts::diagnosis::shipped();
        let f = diag
            .findings
            .iter_mut()
            .find(|f| f.accepted)
            .expect("an accepted finding");
        let form = f.form.clone();
        let d = ReportData {
            diagnosis: Some(diag.clone()),
            ..ReportData::default()
        };
        let lead = block(&d).lead.unwrap();
        assert!(!lead.contains("cannot tell"), "{lead}");
        let f = diag.findings.iter_mut().find(|f| f.accepted).unwrap();
        f.evidence.decision = "accepted: strongest term passing both tests; tied with quadratic: these data cannot tell them apart, and this one (simpler, stronger, inside its bounds or of lower held-out error) is in the model".into();
        let d = ReportData {
            diagnosis: Some(diag),
            ..ReportData::default()
        };
        let lead = block(&d).lead.unwrap();
        assert!(
            lead.contains(&format!(
                "these data cannot tell {} from quadratic",
                crate::report::formula::form(&form)
            )),
            "{lead}"
        );
    }

    /// The shipped diagnosis has no contact warning; with its 316 pair test decided as a contact
    /// distance, the summary names the material and the factor.
    #[test]
    fn a_contact_distance_other_than_the_diameter_is_said_in_the_summary() {
        let mut diag = crate::artifacts::diagnosis::shipped();
        assert_eq!(contact_warning(&diag), None);
        let pair = diag
            .findings
            .iter_mut()
            .find(|f| f.effect == "pair_physics_mismatch" && f.where_["material"] == "316")
            .expect("the shipped diagnosis tests the 316 pairs");
        pair.evidence.decision = format!("{CONTACT_NOT_PHYSICS}: …");
        pair.where_.insert(
            "contact_over_diameter".into(),
            serde_json::json!({"value": 1.0202, "stderr": 0.0001, "chi2": 4493.0}),
        );
        let text = contact_warning(&diag).expect("a warning");
        assert!(text.contains("316 at 1.0202 ×"), "{text}");
        assert!(text.starts_with("Check the length calibration"), "{text}");
    }
}
