//! Discovery's verdict in one sentence per finding: the place, what and how much, and what the
//! held-out runs gained; a tie or an undecided case said as such.

use super::params::params_text;
use crate::artifacts::diagnosis::{Diagnosis, Effect, Finding};
use crate::discover::forms::words::{num, per_material};

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

/// Finding `f` in physical words: by the form that wrote it, or for the findings no form
/// writes (differences between particles, a force between the particles of a pair) from their
/// own parameters.
fn in_words(f: &Finding) -> Option<String> {
    if let Some(w) = crate::discover::forms::in_words(f) {
        return Some(w);
    }
    match Effect::from_id(&f.effect)? {
        Effect::ParticleDifferences => {
            // a spread of each material's particles, in % of its value (0 where none was seen)
            let spread = |prefix: &str| {
                let any = f
                    .parameters
                    .iter()
                    .any(|(k, e)| k.starts_with(prefix) && e.value > 0.0);
                any.then(|| per_material(f, prefix, 1e2)).flatten()
            };
            let mut parts = Vec::new();
            if let Some(mu) = spread("mu_sd_rel") {
                parts.push(format!("μ: {mu}"));
            }
            if let Some(size) = spread("size_sd_rel") {
                parts.push(format!("the drag (the size): {size}"));
            }
            (!parts.is_empty()).then(|| {
                format!(
                    "the particles differ from run to run beyond each run's noise, and each run's own μ and T leave it at its noise; standard deviations in % of each material's value, {}",
                    parts.join("; ")
                )
            })
        }
        Effect::ForceBetweenParticles => {
            let a = f.parameters.get("pair_amplitude_mps2")?.value;
            let range = f.parameters.get("pair_range_m")?.value;
            Some(format!(
                "a force between the particles of a pair {} before they touch, {} m/s² as they meet and falling over {} µm of their separation",
                if a >= 0.0 { "pushes them apart" } else { "pulls them together" },
                num(a.abs()),
                num(range * 1e6)
            ))
        }
        _ => None,
    }
}

/// One sentence for an accepted finding: its place, in physical words what changed and by how
/// much, then the form as fitted with its parameters and what held-out runs gained.
fn sentence(f: &Finding) -> String {
    let mut s = format!("In {}: ", place_words(f));
    if let Some(words) = in_words(f) {
        s.push_str(&format!("{words}; as fitted, "));
    }
    s.push_str(&format!(
        "{}, {}",
        f.effect.replace('_', " "),
        crate::report::formula::form(&f.form)
    ));
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
    // a size at a bound of its search is a limit the fit pushed against, not an estimate: the
    // words above must not be read as one
    let bounds = super::params::at_bound(&f.where_);
    if !bounds.is_empty() {
        s.push_str(&format!(
            "; at a bound of its search: {}",
            bounds.join("; ")
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

#[cfg(test)]
mod tests {
    use super::sentence;
    use crate::artifacts::diagnosis::{Estimate, Evidence, Finding, ModelScore};
    use std::collections::BTreeMap;

    fn finding(effect: &str, parameters: &[(&str, f64)]) -> Finding {
        Finding {
            effect: effect.into(),
            accepted: true,
            form: String::new(),
            parameters: parameters
                .iter()
                .map(|(k, v)| (k.to_string(), Estimate::new(*v, f64::NAN)))
                .collect(),
            evidence: Evidence::default(),
            where_: BTreeMap::new(),
            baseline: ModelScore::default(),
            extended: ModelScore::default(),
        }
    }

    /// The findings no form writes are said from their own parameters: a spread per material in
    /// %, none where none was seen; a pair force's sign, size and range; a size at a bound says so.
    #[test]
    fn particles_and_pair_forces_are_said_in_words() {
        let p = finding(
            "particle_differences",
            &[
                ("mu_sd_rel_316", 0.0203),
                ("mu_sd_rel_440c", 0.0179),
                ("size_sd_rel_316", 0.0),
                ("size_sd_rel_440c", 0.0),
            ],
        );
        let s = sentence(&p);
        assert!(
            s.contains("of each material's value, μ: 2.03 (316), 1.79 (440c)"),
            "{s}"
        );
        assert!(!s.contains("the drag (the size)"), "{s}");
        let mut q = finding(
            "force_between_particles",
            &[("pair_amplitude_mps2", -0.2), ("pair_range_m", 8.7e-5)],
        );
        q.where_.insert(
            "at_bound".into(),
            serde_json::json!(["pair_range_m = 8.7e-5 at its lower bound"]),
        );
        let s = sentence(&q);
        assert!(s.contains("pulls them together before they touch, 0.200 m/s² as they meet and falling over 87.0 µm"), "{s}");
        assert!(
            s.ends_with("; at a bound of its search: pair_range_m = 8.7e-5 at its lower bound."),
            "{s}"
        );
    }
}
