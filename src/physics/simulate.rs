//! Event-driven simulation of one particle under any `Model`, sampled at requested times.

use super::advance::{advance, Pace, Sampler};
use super::mode::{start, Mode};
use super::rk::Tolerance;
use super::{Model, State, SwitchEvent, Trajectory};

/// Cap on mode switches in one simulation (a guard against Zeno behaviour of odd models).
const MAX_SWITCHES: usize = 10_000;

/// Integration tolerances for one particle `[z, v, va, t]` (t carried along for time-dependent terms).
pub(crate) const TOL: Tolerance<4> = Tolerance {
    atol: [1e-12, 1e-11, 1e-11, 1e-12],
    rtol: 1e-10,
};

fn with_t(y: &[f64; 3], t: f64) -> [f64; 4] {
    [y[0], y[1], y[2], t]
}

fn head(y: &[f64; 4]) -> [f64; 3] {
    [y[0], y[1], y[2]]
}

/// Simulate one particle from `init` at t = 0 and sample it at `t_s` (sorted ascending; times
/// ≤ 0 get the initial state). Switches between sliding, rolling and rest are located as events.
pub fn simulate(model: &Model, init: State, t_s: &[f64]) -> Trajectory {
    assert!(
        t_s.windows(2).all(|w| w[0] <= w[1]),
        "simulate: sample times must be sorted ascending"
    );
    let mut traj = Trajectory::with_capacity(t_s.len());
    let Some(&t_end) = t_s.last() else {
        return traj;
    };
    let (mut mode, mut y) = start(model, init.z_m, init.v_mps, init.va_mps, 0.0, 0.0);
    let mut t = 0.0;
    let mut pace = Pace::new(t_end, Mode::Rest.step_cap(model));
    let mut next = 0;
    let mut switches = 0;
    loop {
        let phase = mode.phase();
        if mode.absorbing(model) || switches >= MAX_SWITCHES {
            for &ts in &t_s[next..] {
                traj.push(ts, &y, phase);
            }
            break;
        }
        let m = mode;
        let mut sampler = Sampler {
            times: t_s,
            next,
            store: |i: usize, yy: &[f64; 4]| traj.push(t_s[i], &yy[..3], phase),
        };
        let stop = advance(
            &|yy: &[f64; 4]| {
                let d = m.rhs(model, &head(yy), yy[3], 0.0);
                [d[0], d[1], d[2], 1.0]
            },
            &|yy: &[f64; 4]| m.events(model, &head(yy), yy[3], 0.0),
            t,
            with_t(&y, t),
            t_end,
            &mut sampler,
            &TOL,
            &mut pace,
            mode.step_cap(model),
        );
        next = sampler.next;
        t = stop.t_s;
        let Some(k) = stop.event else { break };
        let (new_mode, new_y) = mode.after_event(model, k, &head(&stop.y), t, 0.0);
        let slip_flip = matches!((mode, new_mode), (Mode::Slide { d: a, .. }, Mode::Slide { d: b, .. }) if a != b);
        if new_mode.phase() != phase || slip_flip {
            traj.events.push(SwitchEvent {
                t_s: t,
                from: phase,
                to: new_mode.phase(),
                z_m: new_y[0],
                v_mps: new_y[1],
                va_mps: new_y[2],
            });
        }
        mode = new_mode;
        y = new_y;
        switches += 1;
    }
    traj.stalled = pace.stopped;
    traj
}
