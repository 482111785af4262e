//! The impacts' own measurements, from each collision run's piecewise fit (`fit_collision`, the
//! fit stage's; no law is assumed in it): the coefficient of restitution against the approach
//! speed, per material and setup, and at the impacts where the contact slipped, the friction
//! between the spheres μ_pp = |Δv_a|/(k Δv_z) against the slip speed |v_a1 + v_a2| before.
//! Impacts whose C lies outside [0, 1] beyond its errors, or whose spin changed along the slip,
//! are unphysical; those whose C or μ_pp is too uncertain to say anything (the slowest secondary
//! impacts of a pair coming to rest) are unresolved; both are left out and counted.

use super::weighted::Pt;
use crate::artifacts::collision_fit::Contact;
use crate::fit::collision::fit::fit_collision;
use crate::fit::collision::options::CollisionOptions;
use crate::physics::Groove;
use crate::recording::{Experiment, Recording, Setup};
use std::collections::BTreeMap;

/// A C outside [0, 1] by more than this many standard errors is no restitution but a fit that
/// went wrong (an impact mislocated); it is left out and counted.
const UNPHYSICAL_SE: f64 = 3.0;
/// A C known no better than this, or a μ_pp no better than this fraction of itself, measures no
/// law (the slowest secondary impacts of a pair that is coming to rest); left out and counted.
const UNRESOLVED_C: f64 = 0.1;
const UNRESOLVED_MU: f64 = 0.5;

/// Per-impact points of one dataset.
#[derive(Debug, Default)]
pub struct ImpactPoints {
    /// (material, setup) → (approach speed, C, se).
    pub restitution: BTreeMap<(String, Setup), Vec<Pt>>,
    /// material → (slip speed, μ_pp, se) at the slipping impacts.
    pub slip: BTreeMap<String, Vec<Pt>>,
    /// material → impacts whose contact stuck (they bound μ_pp from below only).
    pub stuck: BTreeMap<String, usize>,
    /// (material, `restitution` or `slip`) → impacts left out as unphysical (C beyond [0, 1], a
    /// spin change along the slip).
    pub unphysical: BTreeMap<(String, &'static str), usize>,
    /// (material, `restitution` or `slip`) → impacts left out as unresolved (their C or μ_pp too
    /// uncertain to say anything).
    pub unresolved: BTreeMap<(String, &'static str), usize>,
}

/// The impacts of every collision run of `recordings` with a usable fit, on `groove`.
pub fn impact_points(recordings: &[Recording], groove: Groove) -> ImpactPoints {
    let mut out = ImpactPoints::default();
    let mut runs: Vec<&Recording> = recordings
        .iter()
        .filter(|r| r.info.experiment == Experiment::Collision)
        .collect();
    runs.sort_by(|a, b| a.info.run.cmp(&b.info.run));
    let k = groove.k;
    let opts = CollisionOptions {
        s: groove.s,
        k,
        ..CollisionOptions::default()
    };
    let mut rank: BTreeMap<String, usize> = BTreeMap::new();
    for rec in runs {
        let f = fit_collision(rec, &opts);
        let Some(setup) = f.setup.or(rec.info.setup) else {
            continue;
        };
        if !f.usable() {
            continue;
        }
        let material = rec.info.material.clone();
        let r = rank.entry(material.clone()).or_default();
        let run = *r;
        *r += 1;
        for im in &f.impacts {
            let (v, c) = (im.impact_speed_mps.value, im.restitution.value);
            let se = im.restitution.se.unwrap_or(f64::NAN);
            if v > 0.0 && c.is_finite() && se > 0.0 {
                if c < -UNPHYSICAL_SE * se || c > 1.0 + UNPHYSICAL_SE * se {
                    *out.unphysical
                        .entry((material.clone(), "restitution"))
                        .or_default() += 1;
                } else if se > UNRESOLVED_C {
                    *out.unresolved
                        .entry((material.clone(), "restitution"))
                        .or_default() += 1;
                } else {
                    out.restitution
                        .entry((material.clone(), setup))
                        .or_default()
                        .push(Pt {
                            x: v,
                            y: c,
                            se,
                            run,
                        });
                }
            }
            match im.contact {
                Contact::Stick => *out.stuck.entry(material.clone()).or_default() += 1,
                Contact::Slip => {
                    // the target's spin changes against the slip S = v_a1 + v_a2
                    let s_before = im.spin_sum_before_mps;
                    let dvz = im.target_dvz_mps.value;
                    let dva = -im.target_dva_mps.value * s_before.signum();
                    let (sz, sa) = (
                        im.target_dvz_mps.se.unwrap_or(f64::NAN),
                        im.target_dva_mps.se.unwrap_or(f64::NAN),
                    );
                    let mu = dva / (k * dvz);
                    let se = mu.abs() * ((sa / dva).powi(2) + (sz / dvz).powi(2)).sqrt();
                    if !(dvz > 0.0 && s_before != 0.0 && mu.is_finite() && se > 0.0) {
                        continue;
                    }
                    let tally = if mu <= 0.0 {
                        &mut out.unphysical
                    } else if se > UNRESOLVED_MU * mu {
                        &mut out.unresolved
                    } else {
                        out.slip.entry(material.clone()).or_default().push(Pt {
                            x: s_before.abs(),
                            y: mu,
                            se,
                            run,
                        });
                        continue;
                    };
                    *tally.entry((material.clone(), "slip")).or_default() += 1;
                }
                Contact::Undetermined => {}
            }
        }
    }
    out
}
