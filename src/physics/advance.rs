//! Adaptive integration of one smooth piece of motion up to a time or to its first event.
//!
//! An event `m` fires when its function goes from ≥ 0 at the start of a step to < 0 at its end;
//! its time is found by bisection on the step's Hermite interpolant and the state there is
//! recomputed by an exact Runge–Kutta step of the shortened size, so no step straddles a switch.

use super::hermite::interpolate;
use super::rk::{dopri5, Tolerance};

/// Largest step (s): keeps the interpolant far more accurate than any camera.
const H_MAX_S: f64 = 1e-3;

/// Most Runge–Kutta steps (tried or taken) in one simulation beyond those its step cap forces.
/// A smooth run takes a few hundred to a few thousand; a model whose error control asks for steps
/// near rounding (a pair that a fit pushed where its contact chatters) would otherwise crawl for
/// hours. Past the budget the simulation stops where it is and holds that state at every later
/// sample: a misfit the fit sees.
pub(crate) const MAX_STEPS: usize = 100_000;

/// Simulations in this process that stopped at their step budget (for traces; never in outputs,
/// which must not depend on what else the process ran).
static BUDGET_STOPS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// How many simulations in this process have stopped at their step budget so far.
pub fn budget_stops() -> u64 {
    BUDGET_STOPS.load(std::sync::atomic::Ordering::Relaxed)
}

/// What one simulation carries from one smooth piece to the next: the step size, the steps it
/// has left, and whether it stopped because none was.
pub(crate) struct Pace {
    pub h: f64,
    pub steps_left: usize,
    pub stopped: bool,
}

impl Pace {
    /// A simulation to `t_end_s` whose pieces may be capped at steps of `finest_cap_s` (rest under
    /// a vibration): a first step of 0.1 ms, and `MAX_STEPS` beside twice the steps the cap forces.
    pub(crate) fn new(t_end_s: f64, finest_cap_s: f64) -> Pace {
        // `as` saturates (and takes NaN, a zero time over a zero cap, to 0)
        let capped = (2.0 * t_end_s.max(0.0) / finest_cap_s).ceil().min(1e9) as usize;
        Pace {
            h: 1e-4,
            steps_left: MAX_STEPS + capped,
            stopped: false,
        }
    }

    /// Count one step; false once none is left.
    fn take(&mut self) -> bool {
        if self.steps_left == 0 {
            return false;
        }
        self.steps_left -= 1;
        true
    }
}

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
/// `pace` carries the step size from one piece to the next; no step is longer than `h_max` (nor
/// than `H_MAX_S`): an event the error control cannot see coming (rest ending where a vibration
/// outgrows the hold, while nothing moves) is missed if a step can span it. When `pace` runs out
/// of steps every pending sample gets the state reached and the piece ends there with no event.
#[allow(clippy::too_many_arguments)]
pub(crate) fn advance<const N: usize, const M: usize, F: FnMut(usize, &[f64; N])>(
    rhs: &impl Fn(&[f64; N]) -> [f64; N],
    events: &impl Fn(&[f64; N]) -> [f64; M],
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    sampler: &mut Sampler<'_, F>,
    tol: &Tolerance<N>,
    pace: &mut Pace,
    h_max: f64,
) -> Stop<N> {
    sampler.fill_until(t0, |_| y0);
    let (mut t, mut y) = (t0, y0);
    let mut f = rhs(&y);
    let mut e0 = events(&y);
    let mut rejects = 0;
    while t < t_end {
        if !pace.take() {
            BUDGET_STOPS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            pace.stopped = true;
            sampler.fill_until(t_end, |_| y);
            break;
        }
        let h_try = pace.h.min(H_MAX_S).min(h_max).min(t_end - t);
        let step = dopri5(rhs, &y, &f, h_try, tol);
        let min_h = 1e-14 * t.abs().max(1e-3);
        if step.err > 1.0 && h_try > min_h && rejects < 200 {
            pace.h = h_try * (0.9 * step.err.powf(-0.2)).max(0.1);
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
                pace.h = 0.5 * h_ev;
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
        pace.h = h_try * (0.9 * step.err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    Stop {
        t_s: t,
        y,
        event: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL1: Tolerance<2> = Tolerance {
        atol: [1e-12, 1e-12],
        rtol: 1e-10,
    };

    /// Run `rhs` on `[y, t]` from y = 1 at t = 0 to 10 ms, sampled at 0, 5 and 10 ms.
    fn run(rhs: impl Fn(&[f64; 2]) -> [f64; 2]) -> (Stop<2>, Vec<(usize, f64)>, Pace) {
        let times = [0.0, 0.005, 0.01];
        let mut got = Vec::new();
        let mut sampler = Sampler {
            times: &times,
            next: 0,
            store: |i: usize, y: &[f64; 2]| got.push((i, y[0])),
        };
        let mut pace = Pace::new(0.01, f64::INFINITY);
        let stop = advance(
            &rhs,
            &|y: &[f64; 2]| [y[0] + 1.0],
            0.0,
            [1.0, 0.0],
            0.01,
            &mut sampler,
            &TOL1,
            &mut pace,
            f64::INFINITY,
        );
        (stop, got, pace)
    }

    #[test]
    fn a_smooth_piece_reaches_its_end_well_within_the_budget() {
        let (stop, got, pace) = run(|y| [-100.0 * y[0], 1.0]);
        assert_eq!(stop.event, None);
        assert_eq!(stop.t_s, 0.01);
        assert!(!pace.stopped);
        let used = MAX_STEPS - pace.steps_left;
        let capped = Pace::new(0.01, 1e-7).steps_left - MAX_STEPS;
        assert!((200_000..=200_001).contains(&capped), "{capped}");
        assert!(
            used < 200,
            "{used} steps for a decay over one time constant"
        );
        assert_eq!(got.len(), 3);
        let want = (-1.0f64).exp();
        assert!((got[2].1 - want).abs() < 1e-8 * want, "{got:?}");
    }

    #[test]
    fn a_stiff_piece_stops_at_the_budget_and_holds_its_state_at_every_later_sample() {
        // a relaxation time of 1 ns: an explicit step is stable only below about 3 ns, so the
        // 10 ms piece would take millions of steps
        let before = budget_stops();
        let (stop, got, pace) = run(|y| [-1e9 * (y[0] - 0.5), 1.0]);
        assert_eq!(pace.steps_left, 0);
        assert!(pace.stopped, "the simulation knows it stopped");
        // other tests may stop at theirs meanwhile: at least this one is counted
        assert!(budget_stops() > before, "the stop is counted");
        assert_eq!(stop.event, None);
        assert!(stop.t_s < 0.01, "stopped at {} s", stop.t_s);
        let idx: Vec<usize> = got.iter().map(|g| g.0).collect();
        assert_eq!(idx, [0, 1, 2], "every sample is filled once");
        // the held state is the relaxed one, 0.5, reached long before the budget ran out
        assert!(
            (got[1].1 - 0.5).abs() < 1e-6 && got[2].1 == got[1].1,
            "{got:?}"
        );
        assert_eq!(stop.y[0], got[2].1);
    }
}
