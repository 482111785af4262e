//! Discovery's verdict in one sentence per finding: the place, what and how much, and what the
//! held-out runs gained; a tie or an undecided case said as such.

use super::params::params_text;
use crate::artifacts::diagnosis::{Diagnosis, Effect, Finding};

/// The words a finding's place is said in, with the material of a collision finding.
fn place_words(f: &Finding) -> String {
    let words = place_name(f);
    match f.where_.get("material").and_then(|v| v.as_str()) {
        Some(m) if words == "the collisions" => format!("the collisions of the {m} pairs"),
        _ => words.to_string(),
    }
}

/// The words of a finding's place.
fn place_name(f: &Finding) -> &'static str {
    let place = f
        .where_
        .get("place")
        .and_then(|v| v.as_str())
        .map(str::to_string)
        .or_else(|| Effect::from_id(&f.effect).map(|e| e.place().to_string()));
    match place.as_deref() {
        Some("force") => "a force on the particle",
        Some("friction") => "the friction between particle and groove",
        Some("measurement") => "the measurement",
        Some("particles") => "differences between the particles",
        Some("pair") => "the collisions",
        _ => "an unplaced term",
    }
}

/// The forms an accepted finding is tied with, as its decision names them (`… tied with a and
/// b: these data cannot tell them apart …`): forms that passed both tests and predict held-out
/// runs as well.
pub fn tied_with(f: &Finding) -> Option<&str> {
    let rest = f.evidence.decision.split("tied with ").nth(1)?;
    Some(rest.split(':').next().unwrap_or(rest))
}

/// One sentence for an accepted finding.
fn sentence(f: &Finding) -> String {
    let mut s = format!(
        "In {}: {}, {}",
        place_words(f),
        f.effect.replace('_', " "),
        crate::report::formula::form(&f.form)
    );
    let params = params_text(&f.parameters);
    if !params.is_empty() {
        s.push_str(&format!(" ({params})"));
    }
    let (before, after) = (f.baseline.cv_rms_m, f.extended.cv_rms_m);
    if before.is_finite() && after.is_finite() && before > 0.0 && after > 0.0 {
        s.push_str(&format!(
            "; held-out RMS {:.3} → {:.3} µm",
            before * 1e6,
            after * 1e6
        ));
    }
    if let Some(other) = tied_with(f) {
        s.push_str(&format!(
            "; tied with {other}: these data cannot tell the two apart, and this one is in the model"
        ));
    }
    s.push('.');
    s
}

/// The verdict paragraph, or None when discovery tested nothing.
pub fn verdict(diag: &Diagnosis) -> Option<String> {
    if diag.candidates.is_empty() && diag.findings.is_empty() {
        return None;
    }
    let accepted: Vec<&Finding> = diag.findings.iter().filter(|f| f.accepted).collect();
    if accepted.is_empty() {
        return Some(if diag.mismatch {
            "Verdict: the baseline misses, and no candidate explains it well enough to be accepted."
                .to_string()
        } else {
            "Verdict: nothing missing was found, within the detection limits of the candidates tested."
                .to_string()
        });
    }
    let lines: Vec<String> = accepted.iter().map(|f| sentence(f)).collect();
    Some(format!(
        "Verdict: discovery accepted {}. {}",
        match accepted.len() {
            1 => "one finding".to_string(),
            n => format!("{n} findings"),
        },
        lines.join(" ")
    ))
}
