//! Collision-run fits read from the per-run fit JSON: impacts (pre/post velocities and spins) and the
//! fitted motion segments of each particle.

use crate::artifacts::collision_fit::{
    CollisionFit, Contact, Estimate, ImpactFit, PhaseKind, SegmentFit,
};
use crate::recording::Setup;

/// One impact of a collision run.
#[derive(Debug, Clone, PartialEq)]
pub struct Impact {
    pub t_s: Option<f64>,
    /// Relative speed before the impact, |v1 − v2| (m/s).
    pub speed_mps: f64,
    pub restitution: Option<f64>,
    pub dvz_target_mps: Option<f64>,
    pub dva_target_mps: Option<f64>,
    /// true = slip, false = stick, None = not classified.
    pub slip: Option<bool>,
}

impl CollisionRun {
    /// The fitted position of `particle` at `t_s` from its segment's start state (physics closed
    /// form with the start spin), or None outside the fitted segments.
    pub fn fitted_z_m(
        &self,
        particle: u32,
        t_s: f64,
        groove: crate::physics::Groove,
    ) -> Option<f64> {
        let seg = self
            .segments
            .iter()
            .rev()
            .find(|s| s.particle == particle && s.t_start_s <= t_s)
            .filter(|s| t_s <= s.t_end_s + 1e-12)?;
        let st = seg.start?;
        if st.rest {
            return Some(st.z_m);
        }
        let b = crate::physics::Baseline {
            mu: self.mu_pg?,
            t_drag_s: st.t_drag_s,
            groove,
        };
        let dz = b.state_from(st.v_mps, st.va_mps, t_s - seg.t_start_s).0;
        Some(st.z_m + dz).filter(|z| z.is_finite())
    }

    /// A fit whose impacts can be used: converged (or stopped at the iteration cap with a result).
    pub fn usable(&self) -> bool {
        let s = self.status.to_ascii_lowercase();
        s.is_empty() || s == "converged" || s == "max_iterations"
    }
}

/// One fitted motion segment of one particle, with its sliding→rolling switch if it has one.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub particle: u32,
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub t_switch_s: Option<f64>,
    /// The fitted start state and drag time (for drawing the fit), when the fit JSON has them.
    pub start: Option<SegmentStart>,
}

/// A segment's fitted start: position, velocity, spin, drag time; `rest` when the particle rests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentStart {
    pub z_m: f64,
    pub v_mps: f64,
    pub va_mps: f64,
    pub t_drag_s: f64,
    pub rest: bool,
}

/// A collision run's fit as the report shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionRun {
    pub run: String,
    pub material: String,
    pub contact: bool,
    pub impacts: Vec<Impact>,
    pub segments: Vec<Segment>,
    pub status: String,
    /// Particle–groove friction of the run's fit (for drawing the fitted segments).
    pub mu_pg: Option<f64>,
}

fn value(e: &Estimate) -> Option<f64> {
    e.value.is_finite().then_some(e.value)
}

fn impact(i: &ImpactFit) -> Option<Impact> {
    Some(Impact {
        t_s: value(&i.t_s),
        speed_mps: value(&i.impact_speed_mps)?.abs(),
        restitution: value(&i.restitution),
        dvz_target_mps: value(&i.target_dvz_mps),
        dva_target_mps: value(&i.target_dva_mps),
        slip: match i.contact {
            Contact::Slip => Some(true),
            Contact::Stick => Some(false),
            Contact::Undetermined => None,
        },
    })
}

fn segment(s: &SegmentFit) -> Option<Segment> {
    let finite = |x: f64| x.is_finite().then_some(x);
    Some(Segment {
        particle: s.particle,
        t_start_s: finite(s.t_start_s)?,
        t_end_s: finite(s.t_end_s)?,
        t_switch_s: s.t_switch_s.and_then(finite),
        start: finite(s.z_start_m).map(|z_m| SegmentStart {
            z_m,
            v_mps: value(&s.v_start_mps).unwrap_or(0.0),
            va_mps: value(&s.va_start_mps).unwrap_or(0.0),
            t_drag_s: value(&s.t_drag_s).unwrap_or(f64::INFINITY),
            rest: s.phases.first().map(|p| p.phase) == Some(PhaseKind::Rest),
        }),
    })
}

/// One collision run's fit (the `fit` stage's item); `setup` from the recording when the fit has none.
pub fn from_fit(fit: &CollisionFit, setup: Option<Setup>) -> CollisionRun {
    let mut segments: Vec<Segment> = fit.segments.iter().filter_map(segment).collect();
    segments.sort_by(|a, b| {
        (a.particle, a.t_start_s)
            .partial_cmp(&(b.particle, b.t_start_s))
            .unwrap()
    });
    let status = fit.status.clone();
    CollisionRun {
        run: fit.run.clone(),
        material: fit.material.clone(),
        contact: fit.setup.or(setup) == Some(Setup::Contact),
        impacts: fit.impacts.iter().filter_map(impact).collect(),
        segments,
        status,
        mu_pg: value(&fit.mu_pg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::collision_fit::{Kin, PreImpactSource, Termination};

    fn est(value: f64) -> Estimate {
        Estimate::new(value, 0.001)
    }

    #[test]
    fn reads_impacts_and_status_from_the_typed_fit() {
        let kin = Kin {
            v_mps: est(0.1),
            va_mps: est(0.0),
        };
        let impact = ImpactFit {
            index: 0,
            t_s: est(0.005),
            striker_before: kin,
            striker_after: kin,
            target_before: kin,
            target_after: kin,
            striker_before_source: PreImpactSource::Fitted,
            impact_speed_mps: est(-0.1),
            restitution: est(0.7),
            target_dvz_mps: est(0.08),
            target_dva_mps: Estimate::new(f64::NAN, f64::NAN),
            striker_dva_mps: est(0.0),
            spin_sum_before_mps: 0.0,
            spin_sum_after_mps: est(0.0),
            momentum_mismatch_mps: 0.0,
            contact: Contact::Slip,
        };
        let fit = CollisionFit {
            run: "c1".into(),
            material: "316".into(),
            setup: None,
            direction: 1,
            termination: Termination::MaxIterations,
            status: Termination::MaxIterations.status_word().into(),
            message: String::new(),
            mu_pg: est(0.3),
            t_drag_s: est(0.05),
            segments: Vec::new(),
            impacts: vec![impact],
            rms_m: 1e-6,
            noise_m: 1e-6,
            n_points: 10,
            n_outliers: 0,
            iterations: 3,
            fit_end_s: None,
        };
        let c = from_fit(&fit, Some(Setup::Contact));
        assert!(c.contact && c.usable());
        assert_eq!(c.status, "max_iterations");
        let i = &c.impacts[0];
        assert_eq!(
            (i.speed_mps, i.restitution, i.slip),
            (0.1, Some(0.7), Some(true))
        );
        assert_eq!(i.dva_target_mps, None);
    }
}
