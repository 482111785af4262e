//! Discovery: locate where the baseline misses, name and fit the missing physics, decide by evidence.
//!
//! Files of this folder:
//!
//! - `admissible.rs`: Whether a fitted term is physics (its search resolved it; a dissipation never pushes)
//! - `blur.rs`: Tracking noise that grows with speed (motion blur)
//! - `candidate.rs`: The joint model's parameter layout (`Spec`), a run's physics and predictions
//! - `consolidate.rs`: One cause, one term: named forces of one variable that its force map outpredicts give way to the map
//! - `cv.rs`: Leave-runs-out cross-validation of the simulated trajectories
//! - `data.rs`: The runs discovery works on
//! - `detection.rs`: Detection limits
//! - `drift.rs`: Drift of per-run fitted parameters with run covariates
//! - `estimates.rs`: A fitted term's parameters as reported
//! - `findings.rs`: What a finished term selection reports
//! - `forward.rs`: Forward selection
//! - `holm.rs`: Holm's step-down correction for testing several candidates at once
//! - `joint.rs`: The joint fit: shared physics and per-run z0, t0, v0 on `lsq::block`
//! - `locate.rs`: Residuals of a fitted joint model with the model's phase
//! - `model.rs`: A fitted joint model
//! - `noise.rs`: A run's camera noise
//! - `noise_model.rs`: A run's tracking noise as every test's null draws it
//! - `noise_floor.rs`: The noise floor of a scan over frequencies measured on the data itself
//! - `null_distribution.rs`: p-values of a likelihood-ratio statistic from its null law
//! - `pairs.rs`: Discovery on pairs
//! - `pair_force.rs`: The test for a force between the two particles of a pair
//! - `pair_held_out.rs`: Held-out runs for the pair tests
//! - `pair_noise.rs`: The pairs' tracking noise over the time a signature lasts (long-run variance)
//! - `pair_range.rs`: One range for the force between the particles of every material
//! - `pairs_impact.rs`: The impact-specific test of the collision runs
//! - `particles.rs`: Differences between particles: μ and T varying from run to run beyond the noise
//! - `perrun.rs`: Per-run fits: each run alone with its own μ and T
//! - `position_order.rs`: Whether the runs' own μ or T follow where each run slides
//! - `proposal.rs`: Proposals: from the residuals of the current model
//! - `ranges.rs`: What the data allow the forms to take, and what the residuals propose
//! - `residual_structure.rs`: Where a model misses
//! - `response.rs`: Linear response of a fitted run to a small extra acceleration
//! - `run.rs`: The whole discovery on a set of recordings
//! - `screen.rs`: The screen: every candidate's likelihood-ratio statistic and its parametric-bootstrap null
//! - `screen_sums.rs`: The screen's linear algebra
//! - `selection.rs`: The state a discovery carries between its steps (`Ctx`, `Selection`, `Accepted`)
//! - `slow_noise.rs`: The slow part of the tracking noise, a drift over many frames
//! - `sim.rs`: one-particle trajectories for the discovery fits
//! - `spectral.rs`: Spectral search
//! - `ties.rs`: A tie decided again once the later terms are in the model
//! - `time_scan.rs`: The frequency scan the two forms periodic in time share
//! - `timeforce.rs`: Each run's own phase of a force periodic in time
//! - `forcemap/`: The force map: the missing acceleration as a smooth function of one variable
//! - `impact/`: The impact laws of the pairs (restitution, μ_pp against slip speed), read from the impacts
//! - `forms/`: The forms of missing physics, one file each, and their registry
//!
//! # The method, in six steps
//!
//! Stage `discover`, output `diagnosis.json`; rates and times on randomized datasets of an
//! independent simulator, and the history of each rule, are in `tests/bench/DISCOVERY.md`.
//!
//! 1. **Place.** Missing physics enters in one of a few places, each with its own signature:
//!    - a **force** on the particle, a(z, v, t): acts while sliding and rolling;
//!    - the particle–groove **friction** μ(slip speed, direction, z): acts only while sliding and
//!      on what holds rolling, so it leaves the rolling phase alone;
//!    - the **measurement**: a distortion of positions across the image, which changes no
//!      dynamics (a length scale or a time base is μ, T, z0, v0 over again on single runs);
//!    - **differences between particles**: μ and T scattering from run to run beyond their errors
//!      with nothing missing from the equations (`particles.rs`), tested after the terms
//!      against the slow drift at the long end of what the data allow.
//!
//!    Every place's forms compete in one screen, so the data decide the place, not an order.
//! 2. **Map.** Each single run is fitted alone (its noise level, its fast noise's shape — an
//!    AR(1), beside a white part when the runs' lag 2 asks for one — and its outliers come from
//!    what a sliding local cubic leaves; a noise growing with speed, shared by the dataset, from
//!    the same: `blur.rs`; a slow drift of the tracker, shared by the
//!    dataset, from the runs' own fits under each round's model, leaving out the few runs it
//!    cannot explain and a line in its spectrum, which no drift has: `slow_noise.rs`). A joint model shares μ and T per material and
//!    any accepted terms over all runs, with z0, t0, v0 per run. Its residuals, projected off each
//!    run's z0, t0, v0, are regressed on each run's linear response to extra forces
//!    (`response.rs`): a force map against lab z, signed v, time since the kick and the phase
//!    (`forcemap/`), periodograms in z and in time (`spectral.rs`) and a bump scan. They only
//!    propose starting values (`proposal.rs`).
//! 3. **Forms.** Drags (quadratic, saturating), a rolling resistance, a tilt, forces in lab z
//!    (periodic, localized, a step), a force periodic in time with a phase per run
//!    (`timeforce.rs`) or one phase for every run (locked to the kick), μ(u) of the slip speed
//!    (saturating, linear, or falling from a static value: Stribeck), μ by direction, μ along the groove (periodic, or its gradient and
//!    curvature), a distortion; a spline in one variable is the fallback (`unexplained`). Each form is a type in a file of
//!    `forms/` (`Form`: place, parameters in SI units with bounds and sign, how it enters the
//!    integrator, its screen, its sentence and estimates), listed once in its registry.
//! 4. **Decide.** Each candidate's first-order likelihood ratio (`screen.rs`, maximised over a
//!    searched form's trials) is compared with its null from replicates of each run's measured
//!    noise (`noise_model.rs`: its fast part, its blur and the slow drift) pushed through the same projections, or with a computed law for named terms
//!    (`null_distribution.rs`); a time force's replicates are raised to the noise floor the data
//!    show (`noise_floor.rs`), and the two time forms share one frequency scan, which stops where
//!    a force at their amplitude bound would stand below two standard errors (`time_scan.rs`). Holm at α = 0.01 over the candidates; the strongest significant
//!    ones are fitted in full (`joint.rs`, block-sparse Levenberg–Marquardt; a phase per run is
//!    profiled in each prediction and held in the Jacobian's differences, its direction
//!    projected out: Kaufman's variable projection; the columns of what enters through the
//!    force, and of t0 and v0, come from each run's linear response) and must predict
//!    held-out runs better (`cv.rs`: a paired t over the runs, or for a first term whose gain
//!    sits in few runs Wilcoxon's signed-rank test; a model with a phase per run is charged what
//!    its phases take from noise alone); the other forms of the passing term's effect with
//!    a comparable statistic are fitted too, a richer one named only where held-out runs prefer
//!    it, one as rich where its held-out error is lower. The strongest passing term is added,
//!    earlier terms re-tested (backward elimination), and the search repeats. When no single
//!    term passes, or only a searched force does, pairs of named forms are tried (of the
//!    searched force's place when one passed: `forward.rs`). Then, for z and for v, the force
//!    map fitted in place of the accepted forces of that variable replaces them when it predicts
//!    held-out runs better (`consolidate.rs`): a field or a step along the groove is one map,
//!    not a tilt, a wave and a bump.
//! 5. **Sanity.** A term must be physics (`admissible.rs`): a drag that pushes, a form whose
//!    scale ends at the fine end of its search, are refused; a parameter at a bound is said in
//!    words; two forms that held-out runs cannot tell apart are said as a tie, the simpler kept
//!    (of two as simple, the one with no parameter at a bound and physical at every speed, not
//!    only the runs': a quadratic drag with c < 0 pushes above 1/(T|c|)), and decided again
//!    beside the terms accepted after them (`ties.rs`).
//!    A map's peak and RMS are of the curve with its noise taken out (`forms/spline.rs`).
//!    Drift probes (T or μ drifting with |v0|, a direction asymmetry) say whether a mismatch is
//!    left unexplained. Every candidate carries its detection limit (90 % power on this dataset,
//!    `detection.rs`).
//! 6. **Report.** Each finding has its place (`where.place`), form, sizes, evidence and held-out
//!    gain, and its form says it in physical words (`Form::in_words`: what changed, where, by how
//!    much), the sentence the report's verdict opens with; the force maps, periodograms and residuals before and after go in `diagnosis.json`.
//!    The collision runs are checked by `pairs.rs`: the pairs fitted with μ_pg and drag held at
//!    the single runs' accepted physics against free (Wald χ², a contact-distance fit that names
//!    a length calibration), residuals after impacts (`pairs_impact.rs`), and a force between the
//!    particles before they touch, in their separation (`pair_force.rs`; one range for every
//!    material unless that costs more than chance, `pair_range.rs`); the impacts' own C and
//!    μ_pp against their speeds, a map beside the chapter's candidate laws (`impact/`).
//!
//! `GROOVE_DISCOVER_TRACE=1` prints each round's steps with their times, and how many simulations
//! have stopped at their step budget (`physics::budget_stops`), on stderr (not in any output).

pub mod admissible;
pub mod blur;
pub mod candidate;
mod consolidate;
pub mod cv;
pub mod data;
pub mod detection;
pub mod drift;
pub mod estimates;
mod findings;
pub mod forcemap;
pub mod forms;
pub mod forward;
pub mod holm;
pub mod impact;
pub mod joint;
pub mod locate;
pub mod model;
pub mod noise;
pub mod noise_floor;
pub mod noise_model;
pub mod null_distribution;
pub mod pair_force;
mod pair_held_out;
mod pair_noise;
mod pair_range;
pub mod pairs;
mod pairs_impact;
mod particles;
pub mod perrun;
mod position_order;
pub mod proposal;
pub mod ranges;
pub mod residual_structure;
pub mod response;
pub mod run;
pub mod screen;
mod screen_sums;
mod selection;
pub mod sim;
pub mod slow_noise;
pub mod spectral;
mod ties;
mod time_scan;
pub mod timeforce;

pub use crate::artifacts::diagnosis::Diagnosis;
pub use run::{discover, discover_reporting};

use serde::{Deserialize, Serialize};

pub use crate::physics::G_MPS2;

/// Every candidate effect id the library knows, in the order they are listed; all are tested
/// unless the `discover` stage's `candidates` param says otherwise (every place's forms compete
/// in one screen).
pub const EFFECTS: [&str; 9] = [
    "velocity_dependent_drag",
    "rolling_resistance",
    "groove_tilt",
    "velocity_dependent_friction",
    "direction_dependent_friction",
    "position_dependent_friction",
    "position_dependent_force",
    "time_dependent_force",
    "position_distortion",
];

/// Settings of a discovery (the `discover` stage params, plus the seed).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Parametric-bootstrap replicates per round.
    pub bootstrap: usize,
    /// Levenberg–Marquardt iterations of each bootstrap refit (warm started).
    pub bootstrap_iterations: usize,
    /// Family-wise error rate of each round (Holm) and level of the cross-validation test.
    pub alpha: f64,
    /// Leave-runs-out folds.
    pub folds: usize,
    /// Candidate effect ids to test (see `EFFECTS`).
    pub candidates: Vec<String>,
    /// Model structure in a force map that no named form explains with a spline in its
    /// variable (tested like a candidate, reported as `unexplained`).
    pub nonparametric: bool,
    /// At most this many terms are added.
    pub max_terms: usize,
    /// Opening angle of the groove and m R²/I of the particle.
    pub groove_angle_deg: f64,
    pub k: f64,
    /// Runs with fewer samples are left out.
    pub min_frames: usize,
    /// Seed of the bootstrap (the stage passes the pipeline seed).
    #[serde(skip)]
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            bootstrap: 24,
            bootstrap_iterations: 4,
            alpha: 0.01,
            folds: 5,
            candidates: EFFECTS.iter().map(|s| s.to_string()).collect(),
            nonparametric: true,
            max_terms: 3,
            groove_angle_deg: 70.6,
            k: 2.5,
            min_frames: 20,
            seed: 0,
        }
    }
}

impl Options {
    /// Check ranges and names; the message says how to fix.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if self.bootstrap < 5 {
            return bad(
                "bootstrap",
                "needs at least 5 replicates; use 20 or more".into(),
            );
        }
        if !(self.alpha > 0.0 && self.alpha < 0.5) {
            return bad("alpha", "must lie in (0, 0.5); the default is 0.01".into());
        }
        if self.folds < 2 {
            return bad("folds", "needs at least 2 folds; the default is 5".into());
        }
        for c in &self.candidates {
            if !EFFECTS.contains(&c.as_str()) {
                return bad(
                    "candidates",
                    format!("unknown effect `{c}`; use any of {}", EFFECTS.join(", ")),
                );
            }
        }

        if !(self.groove_angle_deg > 0.0 && self.groove_angle_deg < 180.0) {
            return bad("groove_angle_deg", "must lie in (0, 180) degrees".into());
        }
        Ok(())
    }
}
