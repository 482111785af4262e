//! `fit_collision`: detect the impacts of a collision run, fit both tracks jointly with the
//! closed-form motion between impacts, and add secondary impacts while the data demand them.
//!
//! Steps: (1) direction and noise; (2) first impact — the target's departure from rest (rolling
//! setup) or the kick before the first frame (contact setup); (3) a pre-fit of the striker's
//! approach, starting values after the impact from the impulse model; (4) the joint robust fit
//! (shared μ_pg, T; fitted impact times; z continuous); (5) a residual kink scan proposes a missed
//! impact where the pair is in contact; it is kept only if the robust cost drops by more than
//! `accept_chi2` noise units. Everything the fit finds is returned as data (`summarize_fit`).

use super::detect::{departure_time_s, index_at, kink_scan, noise_scale_m, robust_line};
use super::impulse::after_impact;
use super::lm::{minimize, LmOptions, LmResult};
use super::model::{Layout, TrackData};
use super::plan::{FirstPiece, Plan, PlanImpact};
use super::report::{failed_fit, summarize_fit};
use super::types::{CollisionFit, CollisionStatus};
use crate::recording::{Recording, Setup};

/// Settings of the collision fit.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionOptions {
    /// sin(θ/2) of the groove.
    pub s: f64,
    /// m R² / I of the spheres.
    pub k: f64,
    /// At most this many impacts per run (the first and its secondaries).
    pub max_impacts: usize,
    /// A proposed impact needs a kink of at least this many standard errors …
    pub kink_z: f64,
    /// … and must lower the robust cost by this many (noise-scaled) units.
    pub accept_chi2: f64,
    /// Starting values of μ_pg, T and μ_pp (the latter only seeds the spins after an impact).
    pub mu_start: f64,
    pub t_drag_start_s: f64,
    pub mu_pp_start: f64,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        CollisionOptions {
            s: (70.6f64.to_radians() / 2.0).sin(),
            k: 2.5,
            max_impacts: 6,
            kink_z: 6.0,
            accept_chi2: 40.0,
            mu_start: 0.3,
            t_drag_start_s: 0.06,
            mu_pp_start: 1.0,
        }
    }
}

const MIN_POINTS: usize = 20;

/// Fit one collision run (particle 0 striker, particle 1 target).
pub fn fit_collision(rec: &Recording, opts: &CollisionOptions) -> CollisionFit {
    let info = &rec.info;
    let (Some(st), Some(tg)) = (rec.track(0), rec.track(1)) else {
        return failed_fit(
            info,
            CollisionStatus::TooFewPoints,
            "a collision run needs tracks of particle 0 (striker) and 1 (target); check the particle column",
        );
    };
    if st.t_s.len() < MIN_POINTS || tg.t_s.len() < MIN_POINTS {
        return failed_fit(
            info,
            CollisionStatus::TooFewPoints,
            &format!("striker or target has fewer than {MIN_POINTS} samples; record longer runs"),
        );
    }
    let head = |z: &[f64]| {
        let mut h = z[..5].to_vec();
        super::detect::median(&mut h)
    };
    let direction = if head(&tg.z_m) >= head(&st.z_m) {
        1.0
    } else {
        -1.0
    };
    let mirror = |t: &crate::recording::Track| TrackData {
        t_s: t.t_s.clone(),
        z_m: t.z_m.iter().map(|z| direction * z).collect(),
    };
    let tracks = [mirror(st), mirror(tg)];
    let sigma = noise_scale_m(&tracks[0])
        .min(noise_scale_m(&tracks[1]))
        .max(1e-10);
    let frame_s = 1.0 / info.fps;
    let t_first = tracks[0].t_s[0].min(tracks[1].t_s[0]);
    let departure = departure_time_s(&tracks[1], sigma);
    let setup = info.setup.unwrap_or(match departure {
        Some(t) if t <= t_first + 2.0 * frame_s => Setup::Contact,
        _ => Setup::Rolling,
    });
    let fitter = Fitter {
        tracks,
        opts,
        sigma,
        frame_s,
    };
    let plan = match setup {
        Setup::Contact => fitter.contact_plan(t_first - 0.5 * frame_s),
        Setup::Rolling => match departure {
            Some(t) => fitter.rolling_plan(t),
            None => {
                let plan = fitter.approach_plan();
                let (layout, res) = fitter.solve(&plan, &fitter.tracks);
                let mut fit = summarize_fit(info, direction, &layout, &res);
                fit.status = CollisionStatus::NoImpact;
                fit.message = "the target never left rest: no impact in this run".into();
                return fit;
            }
        },
    };
    let (_, _, plan) = fitter.grow(plan);
    // a final polish with a larger iteration budget
    let (layout, res) = fitter.solve_with(&plan, &fitter.tracks, 150);
    let mut fit = summarize_fit(info, direction, &layout, &res);
    fit.setup = Some(setup);
    fit
}

struct Fitter<'a> {
    tracks: [TrackData; 2],
    opts: &'a CollisionOptions,
    sigma: f64,
    frame_s: f64,
}

impl Fitter<'_> {
    fn solve(&self, plan: &Plan, tracks: &[TrackData; 2]) -> (Layout, LmResult) {
        self.solve_with(plan, tracks, 60)
    }

    fn solve_with(
        &self,
        plan: &Plan,
        tracks: &[TrackData; 2],
        max_iter: usize,
    ) -> (Layout, LmResult) {
        let mut plan = plan.clone();
        self.set_time_bounds(&mut plan);
        let (layout, specs) = plan.build(tracks.clone(), self.opts.s, self.opts.k);
        let lm = LmOptions {
            max_iter,
            scale_floor: 0.05 * self.sigma,
            ..LmOptions::default()
        };
        let res = minimize(
            |p, out| layout.residuals(p, out),
            layout.n_residuals(),
            &specs,
            &lm,
        );
        (layout, res)
    }

    /// Fitted impact times stay within 3 frames of their start and between their neighbours.
    fn set_time_bounds(&self, plan: &mut Plan) {
        let times: Vec<f64> = plan.impacts.iter().map(|i| i.t_s).collect();
        for (j, im) in plan.impacts.iter_mut().enumerate() {
            if im.fixed {
                continue;
            }
            let prev = if j > 0 {
                0.5 * (times[j - 1] + times[j])
            } else {
                f64::NEG_INFINITY
            };
            let next = times
                .get(j + 1)
                .map(|n| 0.5 * (n + times[j]))
                .unwrap_or(f64::INFINITY);
            im.lower_s = (im.t_s - 3.0 * self.frame_s).max(prev);
            im.upper_s = (im.t_s + 3.0 * self.frame_s).min(next);
        }
    }

    /// Robust cost in noise units (Huber, c = 2.5), comparable between nested models.
    fn cost(&self, r: &[f64]) -> f64 {
        let c = 2.5;
        r.iter()
            .map(|x| {
                let a = (x / self.sigma).abs();
                if a <= c {
                    a * a
                } else {
                    2.0 * c * a - c * c
                }
            })
            .sum()
    }

    /// Contact setup: both particles start moving at the kick (fixed time before the first frame).
    fn contact_plan(&self, t_kick_s: f64) -> Plan {
        let start = |tr: &TrackData| {
            let hi = tr.t_s.len().min(8);
            robust_line(tr, 0, hi, t_kick_s).unwrap_or((0.0, tr.z_m[0]))
        };
        let (v1, z1) = start(&self.tracks[0]);
        let (v2, z2) = start(&self.tracks[1]);
        Plan {
            mu: self.opts.mu_start,
            t_drag_s: self.opts.t_drag_start_s,
            hold_friction: false,
            z_start_m: [z1, z2],
            first: [None, None],
            impacts: vec![PlanImpact {
                t_s: t_kick_s,
                fixed: true,
                lower_s: t_kick_s,
                upper_s: t_kick_s,
                after: [(v1, v1), (v2, v2)],
            }],
        }
    }

    /// The striker's approach alone, target at rest (also the plan of a run without impact).
    fn approach_plan(&self) -> Plan {
        let [st, tg] = &self.tracks;
        let (v, z) = robust_line(st, 0, st.t_s.len().min(8), st.t_s[0]).unwrap_or((0.0, st.z_m[0]));
        let mut head: Vec<f64> = tg.z_m[..tg.z_m.len().min(15)].to_vec();
        Plan {
            mu: self.opts.mu_start,
            t_drag_s: self.opts.t_drag_start_s,
            hold_friction: false,
            z_start_m: [z, super::detect::median(&mut head)],
            first: [
                Some(FirstPiece::Kicked {
                    t0_s: st.t_s[0],
                    v_mps: v,
                    va_mps: 0.0,
                    va_max_mps: v.signum()
                        * self.opts.k
                        * super::motion::G_MPS2
                        * super::plan::MU_BOUNDS.1
                        * self.frame_s,
                }),
                Some(FirstPiece::Rest { t0_s: tg.t_s[0] }),
            ],
            impacts: Vec::new(),
        }
    }

    /// Rolling setup: pre-fit the approach up to the departure, then seed the impact.
    fn rolling_plan(&self, t_dep_s: f64) -> Plan {
        let cut = |tr: &TrackData| {
            let n = index_at(tr, t_dep_s - self.frame_s);
            TrackData {
                t_s: tr.t_s[..n].to_vec(),
                z_m: tr.z_m[..n].to_vec(),
            }
        };
        let before = [cut(&self.tracks[0]), cut(&self.tracks[1])];
        let mut plan = self.approach_plan();
        if before[0].t_s.len() >= 8 && before[1].t_s.len() >= 3 {
            let (layout, res) = self.solve(&plan, &before);
            plan = plan.from_solution(&layout, &res.params);
        }
        let (layout, _) = plan.build(self.tracks.clone(), self.opts.s, self.opts.k);
        let p0 = layout_params(&plan, &layout);
        let (_, v1, va1) = layout.state_at(&p0, 0, t_dep_s);
        let tg = &self.tracks[1];
        let i = index_at(tg, t_dep_s);
        let v2 = robust_line(tg, i, (i + 6).min(tg.t_s.len()), t_dep_s)
            .map(|l| l.0)
            .unwrap_or(v1);
        let c_guess = ((v2 - (v1 - v2)) / v1.max(1e-6)).clamp(0.0, 1.0);
        let (after, _) = after_impact(
            [(v1, va1), (0.0, 0.0)],
            c_guess,
            self.opts.mu_pp_start,
            self.opts.k,
        );
        let s = self.opts.s;
        plan.impacts.push(PlanImpact {
            t_s: t_dep_s,
            fixed: false,
            lower_s: t_dep_s,
            upper_s: t_dep_s,
            after: after.map(|(v, va)| (v, v - s * va)),
        });
        plan
    }

    /// Fit, then add impacts proposed by the kink scan while they pay off.
    fn grow(&self, plan: Plan) -> (Layout, LmResult, Plan) {
        let (mut layout, mut res) = self.solve(&plan, &self.tracks);
        let mut plan = plan.from_solution(&layout, &res.params);
        while plan.impacts.len() < self.opts.max_impacts {
            let Some(candidate) = self.propose(&layout, &res, &plan) else {
                break;
            };
            let (l2, r2) = self.solve(&candidate, &self.tracks);
            let gain = self.cost(&res.residuals) - self.cost(&r2.residuals);
            if gain < self.opts.accept_chi2 {
                break;
            }
            plan = candidate.from_solution(&l2, &r2.params);
            (layout, res) = (l2, r2);
        }
        (layout, res, plan)
    }

    /// A plan with one more impact where the residuals kink, or None.
    fn propose(&self, layout: &Layout, res: &LmResult, plan: &Plan) -> Option<Plan> {
        let p = &res.params;
        let n0 = self.tracks[0].t_s.len();
        let known: Vec<f64> = (0..layout.impacts.len())
            .map(|j| layout.impact_time(p, j))
            .collect();
        let t_first_impact = known.first().copied()?;
        let gap = |t: f64| layout.state_at(p, 1, t).0 - layout.state_at(p, 0, t).0;
        let contact = gap(t_first_impact);
        let tol = (15.0 * self.sigma).max(0.03 * contact.abs());
        let allowed = |t: f64| t > t_first_impact && (gap(t) - contact).abs() < tol;
        let prop = kink_scan(
            &self.tracks,
            [&res.residuals[..n0], &res.residuals[n0..]],
            &known,
            4.0 * self.frame_s,
            20.0 * self.frame_s,
            &allowed,
        )?;
        if prop.z_score < self.opts.kink_z {
            return None;
        }
        let tb = prop.t_s;
        let (_, v1, va1) = layout.state_at(p, 0, tb);
        let (_, v2, va2) = layout.state_at(p, 1, tb);
        let jump = 0.5 * (prop.jump_mps[1] - prop.jump_mps[0]);
        let c_guess = (2.0 * jump / (v1 - v2).max(1e-6) - 1.0).clamp(0.0, 1.0);
        let (after, _) = after_impact(
            [(v1, va1), (v2, va2)],
            c_guess,
            self.opts.mu_pp_start,
            self.opts.k,
        );
        let s = self.opts.s;
        let mut out = plan.clone();
        let at = out.impacts.partition_point(|im| im.t_s < tb);
        out.impacts.insert(
            at,
            PlanImpact {
                t_s: tb,
                fixed: false,
                lower_s: tb,
                upper_s: tb,
                after: after.map(|(v, va)| (v, v - s * va)),
            },
        );
        Some(out)
    }
}

/// The start values of a plan as a parameter vector of its layout.
fn layout_params(plan: &Plan, layout: &Layout) -> Vec<f64> {
    let (_, specs) = plan.build(layout.tracks.clone(), layout.s, layout.k);
    specs.iter().map(|s| s.start).collect()
}
