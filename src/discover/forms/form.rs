//! What a term of the joint model is (`Form`): its place, parameters, how it enters the physics,
//! its screen, its starts, and how the report says it.

use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::data::RunData;
use crate::discover::ranges::{Proposals, Ranges, Wanted};
use crate::discover::response::Prepared;
use crate::discover::screen_sums::{Trial, Typical, Vectors};
use crate::discover::sim::SimModel;
use crate::discover::time_scan::{TimeMemo, TimeScan};
use crate::physics::{FrictionVariation, Term};
use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::Arc;

/// Name, start, bounds and finite-difference step of one parameter (SI units, named with them).
#[derive(Clone, Debug)]
pub struct ParamInfo {
    pub name: String,
    pub start: f64,
    pub lo: f64,
    pub hi: f64,
    pub step: f64,
}

/// A parameter: name, start (where the term vanishes, or nearly), bounds and step. The bounds
/// carry the physical sign: a dissipation starts at its lower bound, zero.
pub fn p(name: &str, start: f64, lo: f64, hi: f64, step: f64) -> ParamInfo {
    ParamInfo {
        name: name.to_string(),
        start,
        lo,
        hi,
        step,
    }
}

/// Where a term enters the equations of motion (a probe only locates a mismatch).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    Force,
    Friction,
    Measurement,
    Probe,
}

impl Place {
    /// As `where.place` of a finding says it.
    pub fn id(self) -> &'static str {
        match self {
            Place::Force => "force",
            Place::Friction => "friction",
            Place::Measurement => "measurement",
            Place::Probe => "probe",
        }
    }
}

/// The physics of one run while the terms enter it in turn (`Spec::sim_model`): μ and T of the
/// run's material, a quadratic or saturating drag's parameter, and the model the rest is put in.
pub struct Entry {
    pub model: SimModel,
    pub mu: f64,
    pub t_s: f64,
    /// c of a quadratic drag (0: none).
    pub quad: f64,
    /// T' of a saturating drag, which turns T into T0.
    pub tp: Option<f64>,
    pub material: usize,
    pub v0_mps: f64,
}

/// A fitted term's values, as the report reads them.
pub struct Fitted<'a> {
    /// The term's values and standard errors (its slice of the global vector, and on).
    pub x: &'a [f64],
    pub se: &'a [f64],
    /// The whole global vector and its errors: μ per material, then T per material.
    pub global: &'a [f64],
    pub global_se: &'a [f64],
    pub n_materials: usize,
    pub materials: &'a [String],
    /// The term's parameters as the model names them.
    pub params: &'a [ParamInfo],
}

/// What a searched form's screen works on: the prepared runs, the noise replicates (`reps` of
/// them, 0 the data), the ranges the data allow, and the round's frequency scans (`time`),
/// which the forms periodic in time share.
pub struct Search<'a> {
    pub prep: &'a [Prepared],
    pub v: &'a Vectors,
    pub rg: &'a Ranges,
    pub reps: Range<usize>,
    pub time: &'a TimeMemo,
}

impl Search<'_> {
    /// The frequency scan of `grid` over this search's replicates (`time_scan`), computed by
    /// the first form that asks.
    pub fn time_scan(&self, grid: &[f64]) -> Arc<TimeScan> {
        self.time.get(self.prep, self.v, self.reps.clone(), grid)
    }
}

/// A finding of `diagnosis.json` read back as the form that wrote it (`forms::read`).
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    /// The form's name (`Form::name`).
    pub form: &'static str,
    pub place: Place,
    /// The force the form puts on any particle in the groove (a drag, a resistance, the tilt, a
    /// force fixed in z or locked to the kick), held at the finding's values so that other
    /// experiments in the same groove can carry it; Err says why this finding cannot be carried.
    /// None for a form that adds no force of its own.
    pub lab_force: Option<Result<Term, String>>,
    /// The slope T' of a drag time growing with speed, T = T0 + T'|v| (each material's T0 is its
    /// own drag time); None for a form that sets none.
    pub drag_slope: Option<Estimate>,
    /// The part of the friction's variation the form sets (along the groove, by direction, by
    /// slip speed), held at the finding's values: the collision runs slide in the same groove.
    /// None for a form that sets none.
    pub lab_friction: Option<FrictionVariation>,
}

/// One form of missing physics (or a drift probe). Every method but the first few has the
/// answer of most forms as its default.
pub trait Form: std::fmt::Debug + Send + Sync {
    /// The form's own name (`periodic_z`), unique in the registry.
    fn name(&self) -> &'static str;
    /// The diagnosis effect id, or None for a probe.
    fn effect(&self) -> Option<&'static str>;
    fn place(&self) -> Place;
    /// A short label of the form, with its formula (written as a finding's `form`).
    fn form(&self) -> String;
    /// What the term's size is called in words ("a groove tilt").
    fn size_name(&self) -> &'static str;
    /// A finding of this form in physical words, from its parameters: what changed, where and
    /// by how much ("μ varies by ± 21 % along the groove between z = 0.5 and 11.5 mm in the
    /// lab"); None when a parameter it needs is missing, or for a probe.
    fn in_words(&self, _f: &Finding) -> Option<String> {
        None
    }
    /// Parameters of the term, starting at the value that makes it vanish (or nearly).
    fn params(&self) -> Vec<ParamInfo>;
    /// How the term enters the physics of a run, at its values `x`.
    fn enter(&self, x: &[f64], e: &mut Entry);
    /// The fitted term's parameters in SI units with physical names.
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate>;

    /// The form as the library offers it for data of these ranges (None: never offered).
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self>
    where
        Self: Sized,
    {
        None
    }
    /// The form as a drift probe about the runs' median speed (None: no probe).
    fn probe(_v_ref_mps: f64) -> Option<Self>
    where
        Self: Sized,
    {
        None
    }
    /// The parameters as named in a model of `materials` (a term per material names them).
    fn named_params(&self, _materials: &[String]) -> Vec<ParamInfo> {
        self.params()
    }
    /// True for a term with parameters per material (a friction law that one run's own fit
    /// cannot carry).
    fn per_material(&self) -> bool {
        false
    }
    /// The name the per-material drag time takes beside this term (`t0_s` of a saturating drag).
    fn drag_time_name(&self) -> Option<&'static str> {
        None
    }
    /// Degrees of freedom that bound the shape of the gamma law fitted to the term's bootstrap
    /// null (`NullFit::from_replicates`): its parameter count unless the form says otherwise.
    fn null_df(&self, _runs: usize) -> f64 {
        self.params().len() as f64
    }
    /// True when z0 enters other than as an additive offset.
    fn position_dependent(&self) -> bool {
        false
    }
    /// True when the term has a phase of its own in each run (profiled in `Spec::run_model`).
    fn run_phase(&self) -> bool {
        false
    }
    /// True for an acceleration that depends on the particle's speed alone (a dissipation: the
    /// sum of such terms must oppose the motion, `admissible.rs`).
    fn speed_dependent(&self) -> bool {
        false
    }

    /// Pseudo-residuals the term adds to the joint fit's χ² at parameters `x` (a smoothness
    /// penalty, in noise units); none for a form with fixed shape.
    fn penalty(&self, _x: &[f64]) -> Vec<f64> {
        Vec::new()
    }

    /// True when the term's parameters enter the model through the acceleration alone (no
    /// friction, no measurement, no phase of each run's own): the joint fit then takes their
    /// columns from each run's linear response to ∂a/∂x along its fitted motion, one
    /// simulation for all of them instead of one each (`joint.rs`).
    fn through_force(&self) -> bool {
        self.place() == Place::Force && !self.run_phase()
    }

    /// The one variable whose force map can stand for this term (a force of z fixed in the lab,
    /// a force of the speed), None for a term that is no force of one variable. A constant
    /// force along the groove (the tilt) says z.
    fn map_variable(&self) -> Option<crate::physics::Variable> {
        use crate::physics::Variable;
        if self.place() != Place::Force {
            None
        } else if self.position_dependent() {
            Some(Variable::Z)
        } else if self.speed_dependent() {
            Some(Variable::V)
        } else {
            None
        }
    }

    /// True for a form searched over a grid of trials (a scale: wavelength, width, frequency,
    /// or a spline's coefficients) rather than screened along its secant.
    fn searched(&self) -> bool {
        false
    }
    /// A searched form's statistic on the replicates `s.reps` (its response columns regressed
    /// on the prepared runs), with the information about its size at its most sensitive trial.
    fn search(&self, _s: &Search) -> (Option<Trial>, Option<Typical>) {
        (None, None)
    }
    /// True when the term at parameters `x` is physical only over the speeds the runs reach (a
    /// quadratic drag with c < 0 opposes the motion up to v = 1/(T|c|) and pushes the particle
    /// beyond): of two forms the data cannot tell apart, such a one is named only where held-out
    /// runs prefer it (`forward::preferred`), the other being physical at every speed.
    fn physical_only_within_data(&self, _x: &[f64]) -> bool {
        false
    }
    /// True for a parameter whose bound (the `lower` one, or the upper) is no physical limit but
    /// the edge of what the form can mean (μ varying by 90 % of itself along the groove): a fit
    /// that ends there has bent the form to absorb something else, and the term is refused
    /// (`admissible.rs`).
    fn refused_at_bound(&self, _param: usize, _lower: bool) -> bool {
        false
    }
    /// A named form screened at a few trial scales (the best kept) instead of one secant: per
    /// trial, where its parameters start and the parameters stepped and where to.
    fn scale_trials(&self) -> Option<Vec<(Vec<f64>, Vec<(usize, f64)>)>> {
        None
    }

    /// What the form's starts need from the residuals.
    fn wanted(&self) -> Wanted {
        Wanted::default()
    }
    /// Starting values proposed by the residuals (unclamped; empty when none).
    fn proposed(&self, _p: &Proposals) -> Vec<Vec<f64>> {
        vec![]
    }
    /// True when what the residuals propose (`proposed`) is this form's screen estimate made
    /// smooth, so that a fit in full starts from the proposal alone when there is one (a
    /// spline: its force map's coefficients, where the screen's unpenalized estimate runs to
    /// its bounds at speeds or places no run reaches and only slows the fit).
    fn proposal_supersedes_screen(&self) -> bool {
        false
    }
    /// The form's own starting values: where it vanishes, plus a few for a nonlinear scale.
    fn starts(&self) -> Vec<Vec<f64>> {
        vec![self.params().iter().map(|p| p.start).collect()]
    }

    /// A parameter (`k`, at `x`) that ended at a bound in words, or None for the usual sentence.
    fn bound_note(
        &self,
        _k: usize,
        _x: f64,
        _info: &ParamInfo,
        _lower: bool,
        _materials: &[String],
    ) -> Option<String> {
        None
    }
    /// True when a parameter that starts at its bound and ends there is still said (it is no
    /// term that vanishes there).
    fn notes_start_bound(&self) -> bool {
        false
    }
    /// A searched scale: its parameter index and what it is called.
    fn scale(&self) -> Option<(usize, &'static str)> {
        None
    }
    /// Why the scale (at `x`, at the `lower` end of its search) is no finding there, or None where
    /// that end still is one (the coarse end of most forms: a slower variation the data show).
    fn scale_at_end(&self, _x: f64, _lower: bool) -> Option<String> {
        None
    }
    /// The reported parameters adjusted with where the runs go (a spline's size over the data);
    /// `cov` is the covariance of the term's parameters (empty when the fit gave none).
    fn report_over_runs(
        &self,
        _x: &[f64],
        _cov: &[Vec<f64>],
        _runs: &[RunData],
        _out: &mut BTreeMap<String, Estimate>,
    ) {
    }
    /// The size the detection limit is stated for: (parameter, unit, its standard error, scale to
    /// the reported unit), from the term's standard errors `se` and a searched form's standard
    /// error at its most sensitive trial; None for a form without one size.
    fn detection_size(
        &self,
        _se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        None
    }
    /// True when finding `f` was written by this form (its effect and its label).
    fn reads(&self, f: &Finding) -> bool {
        Some(f.effect.as_str()) == self.effect() && f.form == self.form()
    }
    /// The force on any particle in the groove that a finding of this form holds (a drag, a
    /// resistance, the tilt, a force fixed in z or locked to the kick), read from its parameters;
    /// Err says why another experiment cannot carry this finding.
    fn lab_force(&self, _f: &Finding) -> Option<Result<Term, String>> {
        None
    }
    /// The slope T' of the drag time in speed that a finding of this form holds (each material's
    /// T0 is its own drag time).
    fn lab_drag_slope(&self, _f: &Finding) -> Option<Estimate> {
        None
    }
    /// The part of the friction's variation that a finding of this form holds (the fields its
    /// `enter` sets), read from its parameters.
    fn lab_friction(&self, _f: &Finding) -> Option<FrictionVariation> {
        None
    }
}

/// The values of finding `f`'s parameters `names`, in that order; None when one is missing.
pub fn values_of(f: &Finding, names: &[&str]) -> Option<Vec<f64>> {
    names
        .iter()
        .map(|k| f.parameters.get(*k).map(|e| e.value))
        .collect()
}

/// The force finding `f` holds, made by `term` from its parameters `names` (in that order), or
/// why the pair fit cannot carry it (a parameter is missing): `Form::lab_force`'s body.
pub fn carried_force(
    f: &Finding,
    names: &[&str],
    term: impl FnOnce(&[f64]) -> Term,
) -> Option<Result<Term, String>> {
    Some(values_of(f, names).map(|v| term(&v)).ok_or_else(|| {
        format!(
            "the accepted model has a force ({}) the pair fit does not carry",
            f.form
        )
    }))
}

/// Each parameter of `form` as fitted, under its own name.
pub fn as_fitted(form: &dyn Form, f: &Fitted) -> BTreeMap<String, Estimate> {
    form.params()
        .iter()
        .enumerate()
        .map(|(k, p)| (p.name.clone(), Estimate::new(f.x[k], f.se[k])))
        .collect()
}

/// A drag form's parameters as fitted, with each material's drag time beside them under its
/// `drag_time_name` (`t_s` when the form leaves T as it is), suffixed with the material.
pub fn with_drag_times(form: &dyn Form, f: &Fitted) -> BTreeMap<String, Estimate> {
    let name = form.drag_time_name().unwrap_or("t_s");
    let mut out = as_fitted(form, f);
    let nm = f.n_materials;
    for (k, material) in f.materials.iter().enumerate() {
        out.insert(
            format!("{name}_{material}"),
            Estimate::new(f.global[nm + k], f.global_se[nm + k]),
        );
    }
    out
}
