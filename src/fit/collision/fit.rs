//! `fit_collision`: detect the impacts of a collision run, fit both tracks jointly with the
//! closed-form motion between impacts, and add secondary impacts while the data demand them.
//!
//! Steps: (1) direction and noise; (2) first impact — the target's departure from rest (rolling
//! setup) or the kick before the first frame (contact setup); (3) a pre-fit of the striker's
//! approach, starting values after the impact from the impulse model; (4) the joint robust fit
//! (shared μ_pg, T; fitted impact times; z continuous); (5) a residual kink scan proposes a missed
//! impact where the pair is in contact; it is kept only if the robust cost drops by more than
//! `accept_chi2` noise units. Everything the fit finds is returned as data (`summarize_fit`).

use super::detect::{
    departure_time_s, gap_contacts, gap_series, index_at, noise_scale_m, robust_line,
};
use super::impulse::after_impact;
use super::lm::{minimize, LmOptions, LmResult};
use super::model::{Layout, TrackData};
use super::plan::{After, FirstPiece, Plan, PlanImpact};
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
    /// A secondary contact is fitted as an impact when the jump of the gap rate exceeds this
    /// many standard errors; otherwise the fit stops where the pair touches again.
    pub kink_z: f64,
    /// Starting values of μ_pg, T and μ_pp (the latter only seeds the spins after an impact).
    pub mu_start: f64,
    pub t_drag_start_s: f64,
    pub mu_pp_start: f64,
    /// Fit one drag time per piece between impacts (absorbs a drag that is not linear in v,
    /// which otherwise biases the velocities at the impacts) instead of one per run.
    pub drag_per_piece: bool,
}


impl Default for CollisionOptions {
    fn default() -> Self {
        CollisionOptions {
            s: (70.6f64.to_radians() / 2.0).sin(),
            k: 2.5,
            max_impacts: 6,
            kink_z: 6.0,
            mu_start: 0.3,
            t_drag_start_s: 0.06,
            mu_pp_start: 1.0,
            drag_per_piece: true,
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
    if std::env::var("COLLISION_DEBUG").is_ok() {
        eprintln!("DBG plan {plan:?}");
    }
    let (plan, t_stop) = fitter.add_secondary(plan);
    if std::env::var("COLLISION_DEBUG").is_ok() {
        eprintln!("DBG plan2 {plan:?} stop {t_stop}");
    }
    let cut = |tr: &TrackData| {
        let n = index_at(tr, t_stop);
        TrackData {
            t_s: tr.t_s[..n].to_vec(),
            z_m: tr.z_m[..n].to_vec(),
        }
    };
    let used = [cut(&fitter.tracks[0]), cut(&fitter.tracks[1])];
    let (mut layout, mut res) = fitter.solve_with(&plan, &used, 150);
    if res.scale > 3.0 * sigma {
        // a poor local minimum: start again from the default friction and drag
        let mut retry = plan.clone();
        (retry.mu, retry.t_drag_s) = (opts.mu_start, opts.t_drag_start_s);
        retry.piece_t_drag_s = [Vec::new(), Vec::new()];
        let (l2, r2) = fitter.solve_with(&retry, &used, 150);
        if r2.scale < res.scale {
            (layout, res) = (l2, r2);
        }
    }
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
    /// Largest spin (signed like `v`) friction can build up within one frame after a kick.
    fn va_max(&self, v: f64) -> f64 {
        v.signum() * self.opts.k * super::motion::G_MPS2 * super::plan::MU_BOUNDS.1 * self.frame_s
    }

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

    /// Contact setup: both particles start moving at the kick (fixed half a frame before the
    /// first frame) without spin: the resting pair sticks, so the impact changes no spin, and v_a
    /// is held at 0 (a brief slide cannot tell v' from v_a' at 1 µm noise; friction builds up
    /// at most k g μ · ½ frame ≈ 0.4 mm/s of spin within the timing uncertainty).
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
            drag_per_piece: self.opts.drag_per_piece,
            piece_t_drag_s: [Vec::new(), Vec::new()],
            z_start_m: [z1, z2],
            first: [None, None],
            impacts: vec![PlanImpact {
                t_s: t_kick_s,
                fixed: true,
                lower_s: t_kick_s,
                upper_s: t_kick_s,
                after: After::Kicked {
                    v_mps: [v1, v2],
                    va_mps: [0.0, 0.0],
                    va_max_mps: 0.0,
                },
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
            drag_per_piece: self.opts.drag_per_piece,
            piece_t_drag_s: [Vec::new(), Vec::new()],
            z_start_m: [z, super::detect::median(&mut head)],
            first: [
                Some(FirstPiece::Kicked {
                    t0_s: st.t_s[0],
                    v_mps: v,
                    va_mps: 0.0,
                    va_max_mps: self.va_max(v),
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
            // μ and T are held: a few ms of sliding cannot tell friction from drag
            plan.hold_friction = true;
            let (layout, res) = self.solve(&plan, &before);
            plan = plan.from_solution(&layout, &res.params);
            plan.hold_friction = false;
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
        plan.impacts.push(PlanImpact {
            t_s: t_dep_s,
            fixed: false,
            lower_s: t_dep_s,
            upper_s: t_dep_s,
            after: After::Impulse {
                j_mps: v2,
                w_mps: after[1].1,
            },
        });
        plan
    }

    /// Add the later contacts seen in the gap between the particles (secondary collisions) while
    /// they are resolved, and return the time where the fit must stop: the first return to
    /// contact that is not a resolved impact (after it the closed-form pieces no longer hold).
    fn add_secondary(&self, mut plan: Plan) -> (Plan, f64) {
        let Some(first) = plan.impacts.first().map(|i| i.t_s) else {
            return (plan, f64::INFINITY);
        };
        let gap = gap_series(&self.tracks);
        let sigma_gap = noise_scale_m(&gap).max(1e-10);
        let i0 = index_at(&gap, first);
        let contact_m = if plan.impacts[0].fixed {
            robust_line(&gap, 0, gap.t_s.len().min(8), first).map(|l| l.1)
        } else {
            robust_line(&gap, i0.saturating_sub(8), i0, first).map(|l| l.1)
        };
        let Some(contact_m) = contact_m else {
            return (plan, f64::INFINITY);
        };
        let tol = 10.0 * sigma_gap + 0.01 * contact_m.abs();
        let window = 20;
        let found = gap_contacts(
            &gap,
            sigma_gap,
            contact_m,
            tol,
            first + 0.5 * window as f64 * self.frame_s,
            window,
            self.opts.kink_z,
        );
        let s = self.opts.s;
        let mut last = first;
        loop {
            let t_stop = return_to_contact(&gap, sigma_gap, contact_m, last);
            // a resolved contact within a few ms after the gap closed again continues the fit
            let next = found.iter().find(|c| {
                c.t_s > last + 4.0 * self.frame_s && c.t_s <= t_stop + 50.0 * self.frame_s
            });
            let Some(c) = next.filter(|_| plan.impacts.len() < self.opts.max_impacts) else {
                return (plan, t_stop);
            };
            let vel = |p: usize, after: bool| {
                local_velocity(&self.tracks[p], c.t_s, after, window).unwrap_or(0.0)
            };
            let (v1, v2) = (vel(0, false), vel(1, false));
            let c_guess = (-c.gap_rate_after_mps / c.gap_rate_before_mps).clamp(0.0, 1.0);
            // before a secondary collision both particles have usually re-gained rolling
            let (after, _) = after_impact(
                [(v1, v1 / s), (v2, v2 / s)],
                c_guess,
                self.opts.mu_pp_start,
                self.opts.k,
            );
            let j = 0.5 * ((vel(1, true) - v2) - (vel(0, true) - v1));
            plan.impacts.push(PlanImpact {
                t_s: c.t_s,
                fixed: false,
                lower_s: c.t_s,
                upper_s: c.t_s,
                after: After::Impulse {
                    j_mps: j.max(0.0),
                    w_mps: after[1].1 - v2 / s,
                },
            });
            last = c.t_s;
        }
    }
}

/// First time after `after_s` at which the gap, having opened by more than 8 noise units,
/// closes again to within 4 noise units of contact (running median of 9 samples).
fn return_to_contact(gap: &TrackData, sigma_m: f64, contact_m: f64, after_s: f64) -> f64 {
    let i0 = index_at(gap, after_s);
    let n = gap.t_s.len();
    let mut opened = false;
    for i in i0..n {
        let lo = i.saturating_sub(4);
        let hi = (i + 5).min(n);
        let mut w = gap.z_m[lo..hi].to_vec();
        let g = super::detect::median(&mut w) - contact_m;
        if !opened {
            opened = g > 8.0 * sigma_m;
        } else if g < 4.0 * sigma_m {
            return gap.t_s[i];
        }
    }
    f64::INFINITY
}

/// Velocity of a track just before or just after `t` from a one-sided quadratic fit.
fn local_velocity(track: &TrackData, t_s: f64, after: bool, window: usize) -> Option<f64> {
    let i = index_at(track, t_s);
    let (lo, hi) = if after {
        (i, (i + window).min(track.t_s.len()))
    } else {
        (i.saturating_sub(window), i)
    };
    let keep = vec![true; track.t_s.len()];
    super::detect::quadratic_slope(track, &keep, lo, hi, t_s, 1.0).map(|q| q.0)
}

/// The start values of a plan as a parameter vector of its layout.
fn layout_params(plan: &Plan, layout: &Layout) -> Vec<f64> {
    let (_, specs) = plan.build(layout.tracks.clone(), layout.s, layout.k);
    specs.iter().map(|s| s.start).collect()
}
