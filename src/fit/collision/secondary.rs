//! Secondary collisions: contacts seen in the gap between the particles after the first impact,
//! added to the plan while they are resolved, and where the fit must stop when they are not.

use super::detect::{
    gap_contacts, gap_series, index_at, median, noise_scale_m, quadratic_slope, robust_line,
};
use super::fit::Fitter;
use super::impulse::after_impact;
use super::model::TrackData;
use super::plan::{After, Plan, PlanImpact};

impl Fitter<'_> {
    /// Add the later contacts seen in the gap between the particles (secondary collisions) while
    /// they are resolved, and return the time where the fit must stop: the first return to
    /// contact that is not a resolved impact (after it the closed-form pieces no longer hold).
    pub(super) fn add_secondary(&self, mut plan: Plan) -> (Plan, f64) {
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
            self.opts.contact_z,
        );
        let s = self.opts.s;
        let mut last = first;
        loop {
            let t_stop = return_to_contact(&gap, sigma_gap, contact_m, last, 30);
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

/// Where the fit must stop after the impact at `after_s`: the first time the gap, having
/// opened by more than 6 noise units, closes again to within 3 (running median of 9 samples);
/// if it never opens within `open_within` samples the pair moves on touching, and the fit stops
/// there.
fn return_to_contact(
    gap: &TrackData,
    sigma_m: f64,
    contact_m: f64,
    after_s: f64,
    open_within: usize,
) -> f64 {
    let i0 = index_at(gap, after_s);
    let n = gap.t_s.len();
    let mut opened = false;
    for i in i0..n {
        let lo = i.saturating_sub(4);
        let hi = (i + 5).min(n);
        let mut w = gap.z_m[lo..hi].to_vec();
        let g = median(&mut w) - contact_m;
        if !opened {
            opened = g > 6.0 * sigma_m;
            if !opened && i >= i0 + open_within {
                return gap.t_s[i];
            }
        } else if g < 3.0 * sigma_m {
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
    quadratic_slope(track, &keep, lo, hi, t_s, 1.0).map(|q| q.0)
}
