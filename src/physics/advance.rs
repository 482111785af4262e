//! Adaptive integration of one smooth piece of motion up to a time or to its first event.
//!
//! An event `m` fires when its function goes from ≥ 0 at the start of a step to < 0 at its end;
//! its time is found by bisection on the step's Hermite interpolant and the state there is
//! recomputed by an exact Runge–Kutta step of the shortened size, so no step straddles a switch.

use super::hermite::interpolate;
use super::rk::{dopri5, Tolerance};

/// Largest step (s): keeps the interpolant far more accurate than any camera.
const H_MAX_S: f64 = 1e-3;

/// Where a piece ended: at `t_s` with state `y`, because of `event` (None: end time reached).
pub(crate) struct Stop<const N: usize> {
    pub t_s: f64,
    pub y: [f64; N],
    pub event: Option<usize>,
}

/// Sample times still to fill, in ascending order, and the callback that stores them.
pub(crate) struct Sampler<'a, F> {
    pub times: &'a [f64],
    pub next: usize,
    pub store: F,
}

impl<F> Sampler<'_, F> {
    /// Store every pending time ≤ `t_s` with the state from `at(t)`.
    fn fill_until<const N: usize>(&mut self, t_s: f64, mut at: impl FnMut(f64) -> [f64; N])
    where
        F: FnMut(usize, &[f64; N]),
    {
        while self.next < self.times.len() && self.times[self.next] <= t_s {
            let y = at(self.times[self.next]);
            (self.store)(self.next, &y);
            self.next += 1;
        }
    }
}

/// Integrate from (`t0`, `y0`) until `t_end` or the first event, filling samples on the way.
/// `h` carries the step size from one piece to the next; no step is longer than `h_max` (nor
/// than `H_MAX_S`): an event the error control cannot see coming (rest ending where a vibration
/// outgrows the hold, while nothing moves) is missed if a step can span it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn advance<const N: usize, const M: usize, F: FnMut(usize, &[f64; N])>(
    rhs: &impl Fn(&[f64; N]) -> [f64; N],
    events: &impl Fn(&[f64; N]) -> [f64; M],
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    sampler: &mut Sampler<'_, F>,
    tol: &Tolerance<N>,
    h: &mut f64,
    h_max: f64,
) -> Stop<N> {
    sampler.fill_until(t0, |_| y0);
    let (mut t, mut y) = (t0, y0);
    let mut f = rhs(&y);
    let mut e0 = events(&y);
    let mut rejects = 0;
    while t < t_end {
        let h_try = h.min(H_MAX_S).min(h_max).min(t_end - t);
        let step = dopri5(rhs, &y, &f, h_try, tol);
        let min_h = 1e-14 * t.abs().max(1e-3);
        if step.err > 1.0 && h_try > min_h && rejects < 200 {
            *h = h_try * (0.9 * step.err.powf(-0.2)).max(0.1);
            rejects += 1;
            continue;
        }
        rejects = 0;
        let e1 = events(&step.y);
        let mut first: Option<(f64, usize)> = None;
        for m in 0..M {
            if e0[m] >= 0.0 && e1[m] < 0.0 {
                let (mut lo, mut hi) = (0.0f64, 1.0f64);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let ym = interpolate(h_try, mid, &y, &f, &step);
                    if events(&ym)[m] >= 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                    if hi - lo < 1e-15 {
                        break;
                    }
                }
                if first.is_none_or(|(th, _)| hi < th) {
                    first = Some((hi, m));
                }
            }
        }
        if let Some((th, m)) = first {
            let h_ev = h_try * th;
            let short = dopri5(rhs, &y, &f, h_ev, tol);
            if short.err > 1.0 && h_ev > min_h && rejects < 200 {
                // the step to the event is itself too coarse (e.g. friction that changes fast
                // near zero slip): approach the event with smaller steps first
                *h = 0.5 * h_ev;
                rejects += 1;
                continue;
            }
            let (ys, fs) = (y, f);
            sampler.fill_until(t + h_ev, |ts| {
                interpolate(h_ev, (ts - t) / h_ev, &ys, &fs, &short)
            });
            return Stop {
                t_s: t + h_ev,
                y: short.y,
                event: Some(m),
            };
        }
        let (ys, fs) = (y, f);
        let t_new = if h_try == t_end - t { t_end } else { t + h_try };
        sampler.fill_until(t_new, |ts| {
            interpolate(h_try, (ts - t) / h_try, &ys, &fs, &step)
        });
        t = t_new;
        y = step.y;
        f = step.f;
        e0 = e1;
        *h = h_try * (0.9 * step.err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    Stop {
        t_s: t,
        y,
        event: None,
    }
}
