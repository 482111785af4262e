//! The impact laws of the pairs, read from the impacts themselves: is the coefficient of
//! restitution a law outside the chapter's candidates (constant, linear, saturating), and does
//! the friction between the spheres μ_pp depend on the slip speed at their contact?
//!
//! Each collision run's piecewise fit (the fit stage's, which assumes no law) gives every impact
//! its own C at its approach speed and, where the contact slipped, its own μ_pp at its slip speed,
//! each with a standard error (`points.rs`). Per material and setup (restitution) or per material
//! (μ_pp), the best candidate is fitted by weighted least squares and so is a map, piecewise
//! linear in ln speed with one node per two points (3–6; μ_pp: per three, 2–4; `weighted.rs`). The F test of map
//! against candidate scales by the scatter the map leaves, so it follows the noise the runs'
//! own fits left, whatever its source; Holm over the groups of each law, α = 0.01. A departure
//! is accepted only when it is also large enough to be physics (C by 0.02 somewhere, μ_pp by 5 %),
//! and confirmed on held-out runs: each run left out in turn, the map fitted to the others must
//! predict it better than the candidate does (summed, also without the run that gains most),
//! and the test must stay significant (Holm p < 0.05) with any one run's impacts left out (a law
//! is no law if one run carries it). Points the map leaves more than 5 robust scales away are
//! outliers, left out and counted. Then it is named: the named forms (adhesion
//! C = a √(1 − (v_s/v)²), viscoelastic 1 − C = a v^(1/5), a power law, adhesion with losses
//! growing with speed; μ_pp linear in
//! the slip speed or weakening as a/(1 + u/u0)) that fit as well as the map (F test p ≥ 0.05)
//! with no parameter at the end of its search,
//! fewest parameters first; two that fit equally are a tie, said in words; none: the map is the
//! answer, its values reported (an accepted power law also writes its reference speed,
//! `POWER_LAW_REFERENCE`, so that the refit can carry it; `fit::refit_impact`). Where a force
//! between the particles was accepted for the material, a restitution law that passes is a tie with it, said on both findings (an attraction
//! of short range slows the parting pair as a sticking contact does), and the force is kept.
//! Too few impacts (fewer than 8 with their own C, 6 slipping ones)
//! is said in words, not tested.
//!
//! Files of this folder:
//!
//! - `points.rs`: The impacts' own measurements, from each collision run's piecewise fit
//! - `weighted.rs`: Weighted least squares of one quantity against a speed

mod points;
pub mod weighted;

use super::holm::holm;
use crate::artifacts::diagnosis::{Effect, Estimate as Value, Evidence, Finding, ModelScore};
use crate::physics::Groove;
use crate::recording::{Recording, Setup};
use crate::stats::abs_scale;
use points::impact_points;
use std::collections::BTreeMap;
use weighted::{f_test, fit, map_nodes, Fit, Pt, Shape};

/// Where an accepted power law's reference speed is written on its finding (`where`): the
/// impacts' geometric mean speed, at which `restitution_c_at_mean_speed` is C.
pub const POWER_LAW_REFERENCE: &str = "power_law_reference_speed_mps";

/// Family-wise error rate of each law's test (Holm over its groups).
pub const ALPHA: f64 = 0.01;
/// A named form describes the map when its F test against the map is above this.
const FORM_P: f64 = 0.05;
/// The smallest departure from the candidate that counts as physics: C by this much somewhere
/// in the measured speeds, μ_pp by this fraction of its mean.
const MIN_DC: f64 = 0.02;
const MIN_DMU: f64 = 0.05;
/// Two named forms with the same number of parameters whose χ² differ by less than this (in units
/// of the scatter) are a tie: χ²₁(0.99).
const TIE_CHI2: f64 = 6.635;
/// With any one run's impacts left out, the test's Holm p must stay below this.
const ROBUST_P: f64 = 0.05;
/// A point the map of its group leaves more than this many robust scales away is an outlier.
const OUTLIER: f64 = 5.0;

/// Which law a test is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Law {
    Restitution,
    SlipFriction,
}

impl Law {
    fn effect(self) -> Effect {
        match self {
            Law::Restitution => Effect::RestitutionLaw,
            Law::SlipFriction => Effect::PairFrictionSlipSpeed,
        }
    }
    fn candidates(self) -> &'static [Shape] {
        match self {
            Law::Restitution => &[Shape::Constant, Shape::Linear, Shape::Saturating],
            Law::SlipFriction => &[Shape::Constant],
        }
    }
    fn named(self) -> &'static [Shape] {
        match self {
            Law::Restitution => &[
                Shape::Viscoelastic,
                Shape::Adhesive,
                Shape::PowerLaw,
                Shape::AdhesiveYield,
            ],
            Law::SlipFriction => &[Shape::Linear, Shape::Weakening],
        }
    }
    fn min_points(self) -> usize {
        match self {
            Law::Restitution => 8,
            Law::SlipFriction => 6,
        }
    }
    fn map_size(self, n: usize) -> usize {
        match self {
            Law::Restitution => (n / 2).clamp(3, 6),
            Law::SlipFriction => (n / 3).clamp(2, 4),
        }
    }
    fn quantity(self) -> &'static str {
        match self {
            Law::Restitution => "C",
            Law::SlipFriction => "μ_pp",
        }
    }
    fn variable(self) -> &'static str {
        match self {
            Law::Restitution => "impact speed",
            Law::SlipFriction => "slip speed at the contact (|v_a1 + v_a2| before the impact)",
        }
    }
}

/// Said when a force between the particles was accepted for the material: a short-range
/// attraction slows the parting pair as a contact that sticks at low speed does.
const TIED_WITH_FORCE: &str = "the force between the particles accepted for these pairs reads the same at the impacts (an attraction of short range slows the parting pair as a contact that sticks at low speed does): these tests do not tell the two apart, and the force, tested on the whole runs, is the one in the model";

/// The score of a law not fitted: no numbers (a zero would read as a perfect fit).
fn no_score() -> ModelScore {
    ModelScore {
        cv_rms_m: f64::NAN,
        rms_m: f64::NAN,
        chi2: f64::NAN,
        n_global_params: 0,
        terms: Vec::new(),
    }
}

/// What a group's test found.
#[derive(Debug)]
struct Tested {
    /// The points tested: the group's, without its outliers.
    pts: Vec<Pt>,
    outliers: usize,
    candidate: Fit,
    map: Fit,
    f: f64,
    p: f64,
    /// The map's largest departure from the candidate at the measured speeds.
    size: f64,
    /// The scatter per degree of freedom the map leaves (at least 1).
    s2: f64,
    /// The map's χ² gain over the candidate on runs held out one at a time, and that gain
    /// without the run that gains most.
    gain: f64,
    gain_but_one: f64,
    /// The largest p of the test with one run's impacts left out: a law is no law if one run
    /// carries it.
    p_without_one: f64,
    /// The named form that describes the map, with its errors, and one tied with it.
    named: Option<(Fit, Vec<f64>)>,
    tie: Option<Fit>,
}

/// One law's test on one group of impacts.
#[derive(Debug)]
struct LawTest {
    law: Law,
    material: String,
    setup: Option<Setup>,
    pts: Vec<Pt>,
    /// Err: why it was not tested.
    outcome: Result<Tested, String>,
    /// Said beside the decision (e.g. a force between the particles accepted for the material).
    caveat: Option<String>,
}

fn shape_name(s: Shape) -> &'static str {
    match s {
        Shape::Constant => "constant",
        Shape::Linear => "linear",
        Shape::Saturating => "saturating",
        Shape::Viscoelastic => "viscoelastic",
        Shape::Adhesive => "adhesive",
        Shape::PowerLaw => "power law",
        Shape::AdhesiveYield => "adhesive with yield",
        Shape::Weakening => "weakening",
        Shape::Map => "map",
    }
}

/// Each run left out in turn: the candidate and the map fitted to the other runs' impacts, the
/// map's χ² gain over the candidate on the run left out (in units of `s2`), and the F test's p on
/// the rest. Returns the gains' sum, that sum without the largest gain, and the largest p (1
/// when a fit fails).
fn leave_each_run_out(pts: &[Pt], candidate: Shape, nodes: &[f64], s2: f64) -> (f64, f64, f64) {
    let mut runs: Vec<usize> = pts.iter().map(|q| q.run).collect();
    runs.sort_unstable();
    runs.dedup();
    let (mut gains, mut worst) = (Vec::new(), 0.0f64);
    for &r in &runs {
        let (out, rest): (Vec<Pt>, Vec<Pt>) = pts.iter().partition(|q| q.run == r);
        match (fit(candidate, &rest, &[]), fit(Shape::Map, &rest, nodes)) {
            (Some(c), Some(m)) => {
                let p = f_test(&c, &m, rest.len()).1;
                worst = if p.is_finite() { worst.max(p) } else { 1.0 };
                gains.push((c.chi2_on(&out) - m.chi2_on(&out)) / s2);
            }
            _ => worst = 1.0,
        }
    }
    let sum: f64 = gains.iter().sum();
    let largest = gains.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (sum, sum - largest, worst)
}

/// The named form that describes the map (fits as well by the F test, or by χ² within the scatter
/// when it has as many parameters), fewest parameters first, and another tied with it.
fn name_form(
    law: Law,
    pts: &[Pt],
    map: &Fit,
    candidate: &Fit,
    s2: f64,
) -> (Option<Fit>, Option<Fit>) {
    let n = pts.len();
    let mut describing: Vec<Fit> = law
        .named()
        .iter()
        .filter_map(|&s| fit(s, pts, &[]))
        .filter(|f| !f.at_bound && f.chi2 < candidate.chi2)
        .filter(|f| {
            if f.k() < map.k() {
                f_test(f, map, n).1 >= FORM_P
            } else {
                f.chi2 <= map.chi2 + 3.841 * s2
            }
        })
        .collect();
    describing.sort_by(|a, b| a.k().cmp(&b.k()).then(a.chi2.total_cmp(&b.chi2)));
    let mut it = describing.into_iter();
    let best = it.next();
    let tie = best
        .as_ref()
        .and_then(|b| it.find(|f| f.k() == b.k() && f.chi2 - b.chi2 < TIE_CHI2 * s2));
    (best, tie)
}

/// `pts` without the points the map of all of them leaves more than `OUTLIER` robust scales
/// away (an impact the run's fit mislocated), and how many were left out.
fn without_outliers(pts: &[Pt], nodes: &[f64]) -> (Vec<Pt>, usize) {
    let Some(map) = fit(Shape::Map, pts, nodes) else {
        return (pts.to_vec(), 0);
    };
    let r: Vec<f64> = pts.iter().map(|q| (q.y - map.at(q.x)) / q.se).collect();
    let scale = abs_scale(&r).max(1.0);
    let kept: Vec<Pt> = pts
        .iter()
        .zip(&r)
        .filter(|(_, r)| r.abs() <= OUTLIER * scale)
        .map(|(q, _)| *q)
        .collect();
    let dropped = pts.len() - kept.len();
    (kept, dropped)
}

fn test_group(law: Law, all: &[Pt]) -> Result<Tested, String> {
    let (pts, outliers) = without_outliers(all, &map_nodes(all, law.map_size(all.len())));
    let pts = &pts[..];
    let n = pts.len();
    let runs = {
        let mut r: Vec<usize> = pts.iter().map(|q| q.run).collect();
        r.sort_unstable();
        r.dedup();
        r.len()
    };
    let what = match law {
        Law::Restitution => "impacts with their own C",
        Law::SlipFriction => "slipping impacts",
    };
    if n < law.min_points() || runs < 4 {
        let left = if outliers > 0 {
            format!(", {outliers} more left out as outliers")
        } else {
            String::new()
        };
        return Err(format!(
            "too few {what} ({n}, in {runs} runs{left}) to decide: the test needs {} in 4 runs",
            law.min_points()
        ));
    }
    let nodes = map_nodes(pts, law.map_size(n));
    let map = fit(Shape::Map, pts, &nodes).ok_or("the map of the impacts is not determined")?;
    let candidate = law
        .candidates()
        .iter()
        .filter_map(|&s| fit(s, pts, &[]))
        .min_by(|a, b| a.chi2.total_cmp(&b.chi2))
        .ok_or("no candidate law could be fitted")?;
    if map.k() <= candidate.k() || n <= map.k() + 2 {
        return Err(format!(
            "the {what} ({n}) span too few distinct speeds for a map richer than the {} law",
            shape_name(candidate.shape)
        ));
    }
    let (f, p) = f_test(&candidate, &map, n);
    let s2 = (map.chi2 / (n - map.k()) as f64).max(1.0);
    let size = pts
        .iter()
        .map(|q| (map.at(q.x) - candidate.at(q.x)).abs())
        .fold(0.0, f64::max);
    let size = match law {
        Law::Restitution => size,
        Law::SlipFriction => size / candidate.p[0].abs().max(1e-12),
    };
    let (gain, gain_but_one, p_without_one) =
        leave_each_run_out(pts, candidate.shape, &map.nodes, s2);
    let (named, tie) = name_form(law, pts, &map, &candidate, s2);
    let named = named.map(|f| {
        let se = f.standard_errors(pts, s2);
        (f, se)
    });
    Ok(Tested {
        pts: pts.to_vec(),
        outliers,
        candidate,
        map,
        f,
        p,
        size,
        s2,
        gain,
        gain_but_one,
        p_without_one,
        named,
        tie,
    })
}

impl LawTest {
    fn p(&self) -> f64 {
        self.outcome.as_ref().map_or(f64::NAN, |t| t.p)
    }

    fn min_size(&self) -> f64 {
        match self.law {
            Law::Restitution => MIN_DC,
            Law::SlipFriction => MIN_DMU,
        }
    }

    /// Accepted at Holm p-value `p_holm`, and the decision in words.
    fn decision(&self, p_holm: f64) -> (bool, String) {
        let t = match &self.outcome {
            Err(why) => return (false, why.clone()),
            Ok(t) => t,
        };
        let q = self.law.quantity();
        let cand = shape_name(t.candidate.shape);
        let size_words = match self.law {
            Law::Restitution => format!("{:.3} in C", t.size),
            Law::SlipFriction => format!("{:.0} % of μ_pp", 100.0 * t.size),
        };
        let min_words = match self.law {
            Law::Restitution => format!("{MIN_DC} in C"),
            Law::SlipFriction => format!("{:.0} %", 100.0 * MIN_DMU),
        };
        if !(p_holm < ALPHA) {
            return (
                false,
                format!(
                    "no departure of the impacts' {q} from the {cand} law (p Holm {p_holm:.2})"
                ),
            );
        }
        if t.size < self.min_size() {
            return (
                false,
                format!("significant but small: the impacts' {q} departs from the {cand} law by at most {size_words}, below the {min_words} that counts as physics"),
            );
        }
        let (g, g1) = (t.gain, t.gain_but_one);
        if !(g > 0.0 && g1 > 0.0) {
            return (
                false,
                format!("significant in all impacts (p Holm {p_holm:.1e}), but not confirmed on held-out runs (χ² gain {g:.1} over runs held out one at a time, {g1:.1} without the run that gains most)"),
            );
        }
        // the same Holm factor as the test over all impacts
        let p_one = (t.p_without_one * p_holm / t.p.max(f64::MIN_POSITIVE)).min(1.0);
        if !(p_one < ROBUST_P) {
            return (
                false,
                format!("significant in all impacts (p Holm {p_holm:.1e}) and on held-out runs, but one run carries it: without that run's impacts p Holm is {p_one:.2}"),
            );
        }
        let shape = self.shape_words(t);
        if let Some(c) = &self.caveat {
            return (
                false,
                format!("{shape}; confirmed on held-out runs (χ² gain {g:.1}, {g1:.1} without the run that gains most), but {c}"),
            );
        }
        let tie = t.tie.as_ref().map_or(String::new(), |o| {
            format!(
                "; tied with the {} form: these data cannot tell them apart",
                shape_name(o.shape)
            )
        });
        (
            true,
            format!("{shape}; confirmed on held-out runs (χ² gain {g:.1} over runs held out one at a time, {g1:.1} without the run that gains most){tie}"),
        )
    }

    /// The law in physical words.
    fn shape_words(&self, t: &Tested) -> String {
        let cand = shape_name(t.candidate.shape);
        let Some((f, _)) = &t.named else {
            let (lo, hi) = self.speed_range();
            return format!(
                "{} depends on the {} in a way neither the {cand} law nor a named form carries: up to {:.3} from it between {:.0} and {:.0} mm/s (the map's values are given)",
                self.law.quantity(),
                self.law.variable(),
                t.size * if self.law == Law::SlipFriction { t.candidate.p[0] } else { 1.0 },
                1e3 * lo,
                1e3 * hi
            );
        };
        let p = &f.p;
        match f.shape {
            Shape::Viscoelastic => format!(
                "viscoelastic spheres: 1 − C grows as the fifth root of the impact speed, 1 − C = a v^(1/5), a = {:.3} (s/m)^(1/5)",
                p[0]
            ),
            Shape::Adhesive => format!(
                "adhesion: C rises from zero at v_s = {:.1} mm/s towards {:.3} (C = a √(1 − (v_s/v)²)); the contact sticks below v_s",
                1e3 * p[1],
                p[0]
            ),
            Shape::PowerLaw => format!(
                "C falls as a power of the impact speed, C ∝ v^(−{:.3}) ({:.3} at {:.0} mm/s)",
                p[1],
                p[0],
                1e3 * f.nodes[0].exp()
            ),
            Shape::AdhesiveYield => format!(
                "adhesion below v_s = {:.1} mm/s and losses growing with speed above (C = a √(1 − (v_s/v)²) e^(−v/v_y), a = {:.3}, v_y = {:.0} mm/s)",
                1e3 * p[1],
                p[0],
                1e3 * p[2]
            ),
            Shape::Linear => {
                let (lo, hi) = self.speed_range();
                format!(
                    "μ_pp changes linearly with the slip speed: {:.3} at {:.0} mm/s, {:.3} at {:.0} mm/s",
                    f.at(lo),
                    1e3 * lo,
                    f.at(hi),
                    1e3 * hi
                )
            }
            Shape::Weakening => format!(
                "μ_pp weakens with the slip speed u: μ_pp = {:.3}/(1 + u/u0), u0 = {:.0} mm/s",
                p[0],
                1e3 * p[1]
            ),
            _ => String::new(),
        }
    }

    fn speed_range(&self) -> (f64, f64) {
        let pts = self.outcome.as_ref().map_or(&self.pts, |t| &t.pts);
        pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), q| {
            (a.min(q.x), b.max(q.x))
        })
    }

    /// The named form's parameters with their errors (the map's values when none is named).
    fn parameters(&self) -> BTreeMap<String, Value> {
        let mut out = BTreeMap::new();
        let Ok(t) = &self.outcome else {
            return out;
        };
        let prefix = match self.law {
            Law::Restitution => "restitution",
            Law::SlipFriction => "mu_pp",
        };
        match &t.named {
            Some((f, se)) => {
                let names: &[&str] = match f.shape {
                    Shape::Viscoelastic => &["viscous_coefficient"],
                    Shape::Adhesive => &["c_elastic", "v_stick_mps"],
                    Shape::PowerLaw => &["c_at_mean_speed", "exponent"],
                    Shape::AdhesiveYield => &["c_elastic", "v_stick_mps", "v_yield_mps"],
                    Shape::Linear => &["at_zero_slip", "fall_per_mps"],
                    Shape::Weakening => &["at_zero_slip", "slip_scale_mps"],
                    _ => &[],
                };
                for ((name, v), s) in names.iter().zip(&f.p).zip(se) {
                    out.insert(format!("{prefix}_{name}"), Value::new(*v, *s));
                }
            }
            None => {
                let se = t.map.standard_errors(&t.pts, t.s2);
                for (i, (v, s)) in t.map.p.iter().zip(&se).enumerate() {
                    let at = 1e3 * t.map.nodes[i].exp();
                    out.insert(format!("{prefix}_map_at_{at:.0}_mmps"), Value::new(*v, *s));
                }
            }
        }
        out
    }

    fn finding(&self, p_holm: f64) -> Finding {
        let (accepted, decision) = self.decision(p_holm);
        let mut where_ = BTreeMap::new();
        if decision.ends_with(TIED_WITH_FORCE) {
            where_.insert(
                "tied_with".into(),
                serde_json::json!(Effect::ForceBetweenParticles.id()),
            );
        }
        where_.insert("experiment".into(), serde_json::json!("collision"));
        where_.insert("material".into(), serde_json::json!(self.material));
        if let Some(s) = self.setup {
            where_.insert("setup".into(), serde_json::json!(s));
        }
        where_.insert("variable".into(), serde_json::json!(self.law.variable()));
        where_.insert("n_impacts".into(), serde_json::json!(self.pts.len()));
        if let Ok(t) = &self.outcome {
            where_.insert("outliers_left_out".into(), serde_json::json!(t.outliers));
        }
        let (mut evidence, mut baseline, mut extended) = (
            Evidence {
                p_value: f64::NAN,
                p_holm,
                lr: f64::NAN,
                decision,
                ..Evidence::default()
            },
            no_score(),
            no_score(),
        );
        let mut form = match self.law {
            Law::Restitution => {
                "restitution law C(v) beyond the candidates (constant, linear, saturating)"
                    .to_string()
            }
            Law::SlipFriction => "μ_pp depending on the slip speed at the contact".to_string(),
        };
        if let Ok(t) = &self.outcome {
            let (lo, hi) = self.speed_range();
            where_.insert("speed_range_mps".into(), serde_json::json!([lo, hi]));
            where_.insert(
                "candidate".into(),
                serde_json::json!(shape_name(t.candidate.shape)),
            );
            where_.insert("largest_departure".into(), serde_json::json!(t.size));
            where_.insert(
                "map".into(),
                serde_json::json!({
                    "speeds_mps": t.map.nodes.iter().map(|u| u.exp()).collect::<Vec<_>>(),
                    "values": t.map.p,
                }),
            );
            where_.insert(
                "held_out".into(),
                serde_json::json!({"chi2_gain": t.gain, "chi2_gain_but_the_largest": t.gain_but_one}),
            );
            if let Some(o) = &t.tie {
                where_.insert(
                    "tie".into(),
                    serde_json::json!(format!(
                        "{} or {}: these data cannot tell them apart",
                        t.named.as_ref().map_or("?", |n| shape_name(n.0.shape)),
                        shape_name(o.shape)
                    )),
                );
            }
            evidence.lr = t.f;
            evidence.p_value = t.p;
            evidence.extra_params = t.map.k() - t.candidate.k();
            baseline = ModelScore {
                cv_rms_m: f64::NAN,
                rms_m: f64::NAN,
                chi2: t.candidate.chi2,
                n_global_params: t.candidate.k(),
                terms: vec![format!("{} law", shape_name(t.candidate.shape))],
            };
            let best = t.named.as_ref().map_or(&t.map, |n| &n.0);
            extended = ModelScore {
                cv_rms_m: f64::NAN,
                rms_m: f64::NAN,
                chi2: best.chi2,
                n_global_params: best.k(),
                terms: vec![shape_name(best.shape).to_string()],
            };
            if accepted {
                form = self.shape_words(t);
                if let Some((f, _)) = t.named.as_ref().filter(|n| n.0.shape == Shape::PowerLaw) {
                    where_.insert(
                        POWER_LAW_REFERENCE.into(),
                        serde_json::json!(f.nodes[0].exp()),
                    );
                }
            }
        }
        Finding {
            effect: self.law.effect().id().into(),
            accepted,
            form,
            parameters: if accepted {
                self.parameters()
            } else {
                BTreeMap::new()
            },
            evidence,
            where_,
            baseline,
            extended,
        }
    }
}

/// The impact laws of every material (restitution per setup, μ_pp against slip speed) from the
/// collision runs of `recordings` on `groove`; `forced` names the materials whose pairs were
/// found to feel a force between the particles (their impacts' speeds carry it, so a departure of
/// C is not told apart from it). Findings carry `where.experiment = "collision"`.
pub fn test_impact_laws(
    recordings: &[Recording],
    groove: Groove,
    forced: &[String],
) -> Vec<Finding> {
    let pts = impact_points(recordings, groove);
    let caveat = |m: &str| {
        forced
            .iter()
            .any(|f| f == m)
            .then(|| TIED_WITH_FORCE.to_string())
    };
    let mut tests: Vec<LawTest> = pts
        .restitution
        .iter()
        .map(|((m, setup), p)| LawTest {
            law: Law::Restitution,
            material: m.clone(),
            setup: Some(*setup),
            pts: p.clone(),
            outcome: test_group(Law::Restitution, p),
            caveat: caveat(m),
        })
        .collect();
    let materials: Vec<&String> = pts.restitution.keys().map(|(m, _)| m).collect();
    for m in materials
        .into_iter()
        .collect::<std::collections::BTreeSet<_>>()
    {
        let p = pts.slip.get(m).cloned().unwrap_or_default();
        let mut t = LawTest {
            law: Law::SlipFriction,
            material: m.clone(),
            setup: None,
            outcome: test_group(Law::SlipFriction, &p),
            pts: p,
            caveat: None,
        };
        if let Err(why) = &mut t.outcome {
            let stuck = pts.stuck.get(m).copied().unwrap_or(0);
            if stuck > 0 {
                why.push_str(&format!(
                    " ({stuck} impacts stuck at the contact: they bound μ_pp from below only)"
                ));
            }
        }
        tests.push(t);
    }
    let mut findings = Vec::new();
    for law in [Law::Restitution, Law::SlipFriction] {
        // Holm over the groups tested; one not tested has no p
        let group: Vec<&LawTest> = tests.iter().filter(|t| t.law == law).collect();
        let tested: Vec<f64> = group
            .iter()
            .filter(|t| t.outcome.is_ok())
            .map(|t| t.p())
            .collect();
        let mut adjusted = holm(&tested).into_iter();
        for t in group {
            let p = if t.outcome.is_ok() {
                adjusted.next().unwrap_or(f64::NAN)
            } else {
                f64::NAN
            };
            let mut f = t.finding(p);
            for (key, tally) in [
                ("left_out_unphysical", &pts.unphysical),
                ("left_out_unresolved", &pts.unresolved),
            ] {
                let law = match t.law {
                    Law::Restitution => "restitution",
                    Law::SlipFriction => "slip",
                };
                if let Some(&u) = tally.get(&(t.material.clone(), law)) {
                    f.where_.insert(key.into(), serde_json::json!(u));
                }
            }
            findings.push(f);
        }
    }
    findings
}
