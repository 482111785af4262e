//! `fit_collision`: find the impacts of a collision run and fit both tracks jointly with the
//! closed-form motion between impacts; everything it finds is returned as data.
//!
//! Steps: (1) direction of motion and position noise; (2) the first impact — the target's
//! departure from rest (rolling setup) or the kick half a frame before the first frame (contact
//! setup); (3) starting values: a pre-fit of the striker's approach, then the impulse model
//! (`start`); (4) secondary contacts seen in the gap between the particles while they are
//! resolved, and the time where the fit must stop (`secondary`); (5) the joint robust fit:
//! shared μ_pg, a drag time per piece drawn toward the run's T, fitted impact times, z continuous,
//! states after an impact tied to those before by the impulse (momentum conserved, equal spin
//! changes); (6) the record (`report`).

use super::detect::{departure_time_s, index_at, noise_scale_m};
use super::model::{Layout, TrackData};
use super::options::CollisionOptions;
use super::plan::Plan;
use super::report::{failed_fit, summarize_fit};
use crate::artifacts::collision_fit::{CollisionFit, NO_IMPACT};
use crate::lsq::dense_fit::{minimize, DenseFit as LmResult};
use crate::lsq::lm::{Scale, Settings};
use crate::lsq::Termination;
use crate::recording::{Recording, Setup};

const MIN_POINTS: usize = 20;

/// Fit one collision run (particle 0 striker, particle 1 target).
pub fn fit_collision(rec: &Recording, opts: &CollisionOptions) -> CollisionFit {
    let info = &rec.info;
    let (Some(st), Some(tg)) = (rec.track(0), rec.track(1)) else {
        return failed_fit(
            info,
            Termination::TooFewPoints,
            "a collision run needs tracks of particle 0 (striker) and 1 (target); check the particle column",
        );
    };
    if st.t_s.len() < MIN_POINTS || tg.t_s.len() < MIN_POINTS {
        return failed_fit(
            info,
            Termination::TooFewPoints,
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
                fit.status = NO_IMPACT.into();
                fit.message = "the target never left rest: no impact in this run".into();
                return fit;
            }
        },
    };
    let (plan, t_stop) = fitter.add_secondary(plan);
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
    if fit.termination == Termination::MaxIterations {
        fit.message = format!(
            "stopped at its iteration limit ({} iterations) with χ² still falling slowly: the \
             solver creeps along the kinks the sliding–rolling switches put into the closed-form \
             pieces. The whole-run fit (summary.json, collisions.whole_run) models the same run \
             event by event",
            res.iterations
        );
    }
    if t_stop.is_finite() {
        fit.fit_end_s = Some(t_stop);
        let stop = format!(
            "fitted up to t = {t_stop:.5} s: there the pair touches again without an impact the \
             data resolve, and the closed-form pieces no longer describe the motion"
        );
        fit.message = if fit.message.is_empty() {
            stop
        } else {
            format!("{stop}; {}", fit.message)
        };
    }
    fit
}

/// One run's data and settings while it is being fitted (the steps live in `start` and
/// `secondary`).
pub(super) struct Fitter<'a> {
    pub(super) tracks: [TrackData; 2],
    pub(super) opts: &'a CollisionOptions,
    pub(super) sigma: f64,
    pub(super) frame_s: f64,
}

impl Fitter<'_> {
    /// Largest spin (signed like `v`) friction can build up within one frame after a kick,
    /// for a friction up to twice the starting μ.
    pub(super) fn va_max(&self, v: f64) -> f64 {
        v.signum() * self.opts.k * super::motion::G_MPS2 * 2.0 * self.opts.mu_start * self.frame_s
    }

    pub(super) fn solve(&self, plan: &Plan, tracks: &[TrackData; 2]) -> (Layout, LmResult) {
        self.solve_with(plan, tracks, 60)
    }

    pub(super) fn solve_with(
        &self,
        plan: &Plan,
        tracks: &[TrackData; 2],
        max_iter: usize,
    ) -> (Layout, LmResult) {
        let mut plan = plan.clone();
        self.set_time_bounds(&mut plan);
        let (layout, specs) = plan.build(tracks.clone(), self.opts.s, self.opts.k);
        // Huber at 2.5 robust scales (uncentred MAD of the positions, at least 5 % of the
        // noise), four IRLS rounds; converged when χ² falls by less than 1e-3
        let lm = Settings {
            max_iter,
            rounds: 4,
            huber_k: 2.5,
            scale: Scale::Mad {
                floor: 0.05 * self.sigma,
            },
            cost_tol: 1e-3,
            rel_tol: 1e-10,
            damping: 1e-3,
        };
        let res = minimize(
            |p, out| layout.residuals(p, out),
            layout.n_residuals(),
            &specs,
            &lm,
        );
        (layout, res)
    }

    /// Fitted impact times stay near their start (3 frames for the first, 8 for later ones)
    /// and between their neighbours.
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
            // the first impact is located to a frame by the departure; later ones only to a few
            let reach = if j == 0 { 3.0 } else { 8.0 } * self.frame_s;
            im.lower_s = (im.t_s - reach).max(prev);
            im.upper_s = (im.t_s + reach).min(next);
        }
    }
}
