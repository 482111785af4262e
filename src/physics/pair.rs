//! Two equal particles in one groove: one-particle dynamics for each, impulses at contact (2R),
//! and the cascade of secondary collisions.
//!
//! The cascade of an ideal rolling pair is infinite but converges (Zeno): once the approach speed
//! at an impact is below `V_TOGETHER_MPS` (or after `MAX_IMPACTS`), the impact is completed by
//! giving both particles their mean v and va, so they move on together in contact.
//!
//! μ_pp is one number, or (`PairParams::slip`) a function of the slip speed at the contact,
//! |v_a1 + v_a2| before each impact, through which the impulse is then applied.

use super::advance::{advance, Sampler};
use super::impulse::collide;
use super::mode::{start, Mode};
use super::pair_force::PairForce;
use super::rk::Tolerance;
use super::slip_friction::SlipFriction;
use super::{Model, Phase, Restitution, State, SwitchEvent, Trajectory};
use serde::{Deserialize, Serialize};

/// Approach speed (m/s) below which an impact ends the cascade: the pair moves on together.
pub const V_TOGETHER_MPS: f64 = 1e-7;
/// Most impacts resolved one by one in a simulation.
const MAX_IMPACTS: usize = 1000;
/// Overlap (relative to 2R) that counts as touching: rounding never starts a false impact.
const CONTACT_SLACK: f64 = 1e-9;
/// Cap on all events (phase switches and impacts).
const MAX_EVENTS: usize = 20_000;
/// The cap with a force between the particles: a pair that an attraction holds together while
/// its own motions pull it apart bounces at contact in ever smaller steps (the model has no
/// bound state), and a scan of strong attractions on pairs under a waviness spent minutes per
/// simulation there. Past the cap the pair stays where it is, a misfit the fit sees.
const MAX_EVENTS_WITH_FORCE: usize = 2_000;

/// The time in which the contact's friction under an attraction stops its slip once the slip is
/// small (`PairParams::contact_spin`): a Coulomb law smoothed below the slip it takes away in
/// this time, so that a contact that sticks (the spins' sum held at zero) relaxes there in a tenth
/// of a frame instead of chattering. With the sharp law of a 10⁻⁶ m/s smoothing, a touching pair
/// kicked from rest under a strong attraction took steps of 10⁻⁹ s, and the pair tests crawled.
const CONTACT_STICK_S: f64 = 1e-5;

/// A mode's `[z', v', va']` with the contact's spin friction `tau` added: on the spin alone while
/// sliding; while rolling the groove's friction shares it with the motion (va = v/s holds), so
/// v' gains s τ/(1 + ks²).
fn with_spin(d: [f64; 3], mode: Mode, model: &Model, tau: f64) -> [f64; 3] {
    let g = &model.groove;
    match mode {
        Mode::Slide { .. } | Mode::Creep { .. } => [d[0], d[1], d[2] + tau],
        Mode::Roll { .. } => {
            let dv = g.s * tau / (1.0 + g.ks2());
            [d[0], d[1] + dv, d[2] + dv / g.s]
        }
        Mode::Rest => d,
    }
}

/// The force a rolling hold sees beside the contact's spin friction `tau`: rolling needs the
/// groove's friction s(a − sτ)/(1 + ks²), as under a force a − sτ alone.
fn hold_ext(ext: f64, model: &Model, tau: f64) -> f64 {
    ext - model.groove.s * tau
}

const TOL: Tolerance<7> = Tolerance {
    atol: [1e-12, 1e-11, 1e-11, 1e-12, 1e-11, 1e-11, 1e-12],
    rtol: 1e-10,
};

/// Contact parameters of the pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairParams {
    pub restitution: Restitution,
    /// Particle–particle Coulomb friction (at `slip.u_ref_mps` when it depends on the slip
    /// speed).
    pub mu_pp: f64,
    pub radius_m: f64,
    /// A force between the particles before they touch (none in the chapter's model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<PairForce>,
    /// μ_pp depending on the slip speed at the contact (`mu_pp` is its value at the reference
    /// slip speed); None: one μ_pp, as in the chapter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slip: Option<SlipFriction>,
}

impl PairParams {
    /// μ_pp at an impact whose spins before sum to `va_sum` (the slip speed is its magnitude).
    pub fn mu_pp_at(&self, va_sum: f64) -> f64 {
        match self.slip {
            Some(s) => self.mu_pp * s.factor(va_sum),
            None => self.mu_pp,
        }
    }

    /// The friction of the contact on both particles' spins (lab frame, the rate of change of
    /// each `va`) while an attraction presses them together: the contact carries a normal force
    /// |a| per unit mass, and its slip speed is the sum of the spins (two particles spinning the
    /// same way rub at the contact), so each spin is braked by μ_pp k |a|, the friction the
    /// impacts' impulse carries (`impulse::collide`) taken as a rate. A pair that an attraction
    /// holds together and rolls on joined is slowed by it: without it, such a pair rolled on
    /// 10× too far (100 mm/s² of braking missing under a 0.1 m/s² attraction, where the
    /// independent simulator's chatter of contacts carries it).
    fn contact_spin(&self, y: &[f64], (l, r): (usize, usize), k: f64) -> f64 {
        let Some(f) = self.force else {
            return 0.0;
        };
        let two_r = 2.0 * self.radius_m;
        let gap = y[3 * r] - y[3 * l] - two_r;
        let a = f.accel(gap);
        if gap > CONTACT_SLACK * two_r || a >= 0.0 {
            return 0.0;
        }
        let sum = y[3 * l + 2] + y[3 * r + 2];
        let brake = self.mu_pp_at(sum) * k * (-a);
        // smoothed over the slip the brake takes away in `CONTACT_STICK_S`
        let scale = (brake * CONTACT_STICK_S).max(f64::MIN_POSITIVE);
        -brake * (sum / scale).clamp(-1.0, 1.0)
    }

    /// The accelerations from the pair force on particles 0 and 1 in state `y` (particle `l`
    /// at lower z), 0 without one.
    fn ext(&self, y: &[f64], (l, r): (usize, usize)) -> [f64; 2] {
        let Some(f) = self.force else {
            return [0.0, 0.0];
        };
        let two_r = 2.0 * self.radius_m;
        let gap = y[3 * r] - y[3 * l] - two_r;
        let [al, ar] = f.on_particle(gap, gap <= CONTACT_SLACK * two_r);
        let mut out = [0.0; 2];
        out[l] = al;
        out[r] = ar;
        out
    }
}

/// One impact: time, states of both particles just before and just after.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Impact {
    pub t_s: f64,
    /// Approach speed `v_l − v_r` (> 0) of the lower-z and upper-z particle.
    pub v_impact_mps: f64,
    /// Coefficient of restitution used (0 for the closing impact that joins the pair).
    pub restitution: f64,
    /// The contact slipped (spin change μ_pp k J) rather than stuck.
    pub slip: bool,
    /// This impact ended the cascade: the pair moves on together.
    pub joined: bool,
    pub pre: [State; 2],
    pub post: [State; 2],
}

/// Both particles sampled at the requested times (index = particle), and every impact.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PairTrajectory {
    pub particles: [Trajectory; 2],
    pub impacts: Vec<Impact>,
}

fn state_of(y: &[f64; 6], i: usize) -> State {
    State {
        z_m: y[3 * i],
        v_mps: y[3 * i + 1],
        va_mps: y[3 * i + 2],
    }
}

/// Simulate two particles from `init` at t = 0 (their centres at least 2R apart; touching
/// particles that approach collide at once) and sample both at `t_s` (sorted ascending).
pub fn simulate_pair(
    model: &Model,
    pair: &PairParams,
    init: [State; 2],
    t_s: &[f64],
) -> PairTrajectory {
    assert!(
        t_s.windows(2).all(|w| w[0] <= w[1]),
        "simulate_pair: sample times must be sorted ascending"
    );
    let mut out = PairTrajectory {
        particles: [
            Trajectory::with_capacity(t_s.len()),
            Trajectory::with_capacity(t_s.len()),
        ],
        impacts: Vec::new(),
    };
    let Some(&t_end) = t_s.last() else {
        return out;
    };
    // l is the particle at lower z; the order never changes
    let (l, r) = if init[0].z_m <= init[1].z_m {
        (0, 1)
    } else {
        (1, 0)
    };
    let two_r = 2.0 * pair.radius_m;
    let k = model.groove.k;
    let mut modes = [Mode::Rest; 2];
    let mut y = [0.0; 6];
    for i in 0..2 {
        y[3 * i] = init[i].z_m;
        y[3 * i + 1] = init[i].v_mps;
    }
    let ext0 = pair.ext(&y, (l, r));
    for i in 0..2 {
        let (m, yi) = start(
            model,
            init[i].z_m,
            init[i].v_mps,
            init[i].va_mps,
            0.0,
            ext0[i],
        );
        modes[i] = m;
        y[3 * i..3 * i + 3].copy_from_slice(&yi);
    }
    let mut t = 0.0;
    let mut h = 1e-4;
    let mut next = 0;
    let mut n_events = 0;
    let max_events = if pair.force.is_some() {
        MAX_EVENTS_WITH_FORCE
    } else {
        MAX_EVENTS
    };
    loop {
        #[cfg(test)]
        LOOPS.with(|c| c.set(c.get() + 1));
        // an impact is due when the particles touch and approach
        let gap = y[3 * r] - y[3 * l] - two_r;
        let approach = y[3 * l + 1] - y[3 * r + 1];
        if gap <= CONTACT_SLACK * two_r && approach > 0.0 && n_events < max_events {
            impact(model, pair, t, &mut y, &mut modes, (l, r), &mut out);
            n_events += 1;
            continue;
        }
        let phases = [modes[0].phase(), modes[1].phase()];
        let ms = modes;
        // at rest the pair force is fixed too (neither moves), so rest lasts as for one particle
        let both_rest = ms[0].absorbing(model) && ms[1].absorbing(model);
        let (p0, p1) = out.particles.split_at_mut(1);
        let mut sampler = Sampler {
            times: t_s,
            next,
            store: |i: usize, yy: &[f64; 7]| {
                p0[0].push(t_s[i], &yy[0..3], phases[0]);
                p1[0].push(t_s[i], &yy[3..6], phases[1]);
            },
        };
        if both_rest || n_events >= max_events {
            let yy = with_t(&y, t);
            for i in next..t_s.len() {
                (sampler.store)(i, &yy);
            }
            break;
        }
        let stop = advance(
            &|yy: &[f64; 7]| {
                let e = pair.ext(yy, (l, r));
                let tau = pair.contact_spin(yy, (l, r), k);
                let a = ms[0].rhs(model, &[yy[0], yy[1], yy[2]], yy[6], e[0]);
                let b = ms[1].rhs(model, &[yy[3], yy[4], yy[5]], yy[6], e[1]);
                let (a, b) = (
                    with_spin(a, ms[0], model, tau),
                    with_spin(b, ms[1], model, tau),
                );
                [a[0], a[1], a[2], b[0], b[1], b[2], 1.0]
            },
            &|yy: &[f64; 7]| {
                let e = pair.ext(yy, (l, r));
                let tau = pair.contact_spin(yy, (l, r), k);
                // a rolling hold bears the contact's spin friction too
                let seen = |i: usize| match ms[i] {
                    Mode::Roll { .. } => hold_ext(e[i], model, tau),
                    _ => e[i],
                };
                let a = ms[0].events(model, &[yy[0], yy[1], yy[2]], yy[6], seen(0));
                let b = ms[1].events(model, &[yy[3], yy[4], yy[5]], yy[6], seen(1));
                let gap = yy[3 * r] - yy[3 * l] - two_r;
                [a[0], a[1], b[0], b[1], gap + CONTACT_SLACK * two_r]
            },
            t,
            with_t(&y, t),
            t_end,
            &mut sampler,
            &TOL,
            &mut h,
            ms[0].step_cap(model).min(ms[1].step_cap(model)),
        );
        next = sampler.next;
        t = stop.t_s;
        y.copy_from_slice(&stop.y[..6]);
        n_events += 1;
        match stop.event {
            None => break,
            Some(4) => {
                // touching: put them exactly 2R apart about their centre, then the impact fires
                let mid = 0.5 * (y[3 * l] + y[3 * r]);
                y[3 * l] = mid - 0.5 * two_r;
                y[3 * r] = mid + 0.5 * two_r;
            }
            Some(e) => {
                let tau = pair.contact_spin(&y, (l, r), k);
                let ext = pair.ext(&y, (l, r)).map(|a| hold_ext(a, model, tau));
                let i = e / 2;
                let yi = [y[3 * i], y[3 * i + 1], y[3 * i + 2]];
                let (m, y_new) = modes[i].after_event(model, e % 2, &yi, t, ext[i]);
                note_switch(&mut out.particles[i], t, modes[i], m, &y_new);
                modes[i] = m;
                y[3 * i..3 * i + 3].copy_from_slice(&y_new);
                // the other particle's event at the same time (a force in time starting both at
                // rest at once): `advance` stops at one event, and the other's function, already
                // past zero, would not fire again, so it is taken here too
                let j = 1 - i;
                let yj = [y[3 * j], y[3 * j + 1], y[3 * j + 2]];
                let ej = modes[j].events(model, &yj, t, ext[j]);
                if let Some(k) = (0..ej.len()).find(|&k| ej[k] < 0.0) {
                    let (m, y_new) = modes[j].after_event(model, k, &yj, t, ext[j]);
                    note_switch(&mut out.particles[j], t, modes[j], m, &y_new);
                    modes[j] = m;
                    y[3 * j..3 * j + 3].copy_from_slice(&y_new);
                }
            }
        }
    }
    out
}

/// The pair state with the time since the kick appended (time-dependent terms).
fn with_t(y: &[f64; 6], t: f64) -> [f64; 7] {
    [y[0], y[1], y[2], y[3], y[4], y[5], t]
}

fn note_switch(traj: &mut Trajectory, t_s: f64, from: Mode, to: Mode, y: &[f64; 3]) {
    let flip = matches!((from, to), (Mode::Slide { d: a, .. }, Mode::Slide { d: b, .. }) if a != b);
    if from.phase() != to.phase() || flip {
        traj.events.push(SwitchEvent {
            t_s,
            from: from.phase(),
            to: to.phase(),
            z_m: y[0],
            v_mps: y[1],
            va_mps: y[2],
        });
    }
}

/// Resolve one impact in place: new velocities, spins and modes of both particles.
fn impact(
    model: &Model,
    pair: &PairParams,
    t_s: f64,
    y: &mut [f64; 6],
    modes: &mut [Mode; 2],
    (l, r): (usize, usize),
    out: &mut PairTrajectory,
) {
    let pre = [state_of(y, 0), state_of(y, 1)];
    let v = [y[3 * l + 1], y[3 * r + 1]];
    let va = [y[3 * l + 2], y[3 * r + 2]];
    let approach = v[0] - v[1];
    let joined = approach < V_TOGETHER_MPS || out.impacts.len() >= MAX_IMPACTS;
    let (c, slip, v_new, va_new) = if joined {
        let vm = 0.5 * (v[0] + v[1]);
        let vam = 0.5 * (va[0] + va[1]);
        (0.0, false, [vm, vm], [vam, vam])
    } else {
        let c = pair.restitution.at(approach);
        let kick = collide(v, va, c, pair.mu_pp_at(va[0] + va[1]), model.groove.k);
        (c, kick.slip, kick.v, kick.va)
    };
    for (idx, p) in [l, r].into_iter().enumerate() {
        y[3 * p + 1] = v_new[idx];
        y[3 * p + 2] = va_new[idx];
    }
    // the mode each particle starts in, its hold bearing the contact's spin friction if an
    // attraction presses the two together
    let tau = pair.contact_spin(y, (l, r), model.groove.k);
    let ext = pair.ext(y, (l, r)).map(|a| hold_ext(a, model, tau));
    for (idx, p) in [l, r].into_iter().enumerate() {
        let (m, yi) = start(model, y[3 * p], v_new[idx], va_new[idx], t_s, ext[p]);
        let from = modes[p];
        note_switch_phase(&mut out.particles[p], t_s, from, m, &yi);
        modes[p] = m;
        y[3 * p..3 * p + 3].copy_from_slice(&yi);
    }
    out.impacts.push(Impact {
        t_s,
        v_impact_mps: approach,
        restitution: c,
        slip,
        joined,
        pre,
        post: [state_of(y, 0), state_of(y, 1)],
    });
}

fn note_switch_phase(traj: &mut Trajectory, t_s: f64, from: Mode, to: Mode, y: &[f64; 3]) {
    if from.phase() != to.phase() {
        traj.events.push(SwitchEvent {
            t_s,
            from: from.phase(),
            to: to.phase(),
            z_m: y[0],
            v_mps: y[1],
            va_mps: y[2],
        });
    }
}

#[cfg(test)]
thread_local! {
    static LOOPS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

impl PairTrajectory {
    /// Phase of particle `i` at sample `k`.
    pub fn phase(&self, i: usize, k: usize) -> Phase {
        self.particles[i].phase[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::Groove;

    #[test]
    fn mu_pp_follows_the_slip_speed_when_it_depends_on_it() {
        use crate::physics::{SlipFriction, SlipShape};
        let mut pair = PairParams {
            restitution: Restitution::Constant(0.9),
            mu_pp: 0.3,
            radius_m: 150e-6,
            force: None,
            slip: None,
        };
        assert_eq!(pair.mu_pp_at(0.2), 0.3);
        pair.slip = Some(SlipFriction {
            shape: SlipShape::Weakening {
                slip_scale_mps: 0.05,
            },
            u_ref_mps: 0.05,
        });
        assert!((pair.mu_pp_at(-0.05) - 0.3).abs() < 1e-15);
        assert!((pair.mu_pp_at(0.15) - 0.15).abs() < 1e-15);
        // a rolling striker into a resting target slips at μ_pp(u) of its spin: the target's
        // spin change is μ_pp(u) k J
        let model = Model::baseline(0.337, 0.08);
        let s = Groove::CHAPTER.s;
        let init = [
            State {
                z_m: 0.0,
                v_mps: 0.05,
                va_mps: 0.05 / s,
            },
            State {
                z_m: 3.001e-4,
                v_mps: 0.0,
                va_mps: 0.0,
            },
        ];
        let t = [0.0, 1e-4];
        let first = |p: &PairParams| simulate_pair(&model, p, init, &t).impacts[0].clone();
        let im = first(&pair);
        let u = im.pre[0].va_mps + im.pre[1].va_mps;
        let j = 0.5 * 1.9 * (im.pre[0].v_mps - im.pre[1].v_mps);
        assert!(im.slip);
        let dva = im.post[1].va_mps - im.pre[1].va_mps;
        let want = pair.mu_pp_at(u) * model.groove.k * j;
        assert!((dva.abs() - want).abs() < 1e-12 * want, "{dva} vs {want}");
        let constant = first(&PairParams { slip: None, ..pair });
        assert!((constant.post[1].va_mps - im.post[1].va_mps).abs() > 1e-6);
    }

    #[test]
    fn a_joined_pair_costs_no_more_events() {
        // rolling striker into a resting target: a cascade, then the pair moves on together
        let model = Model::baseline(0.337, 0.08);
        let pair = PairParams {
            restitution: Restitution::Constant(0.9),
            mu_pp: 1.4,
            radius_m: 150e-6,
            force: None,
            slip: None,
        };
        let s = Groove::CHAPTER.s;
        let init = [
            State {
                z_m: 0.0,
                v_mps: 0.05,
                va_mps: 0.05 / s,
            },
            State {
                z_m: 4e-4,
                v_mps: 0.0,
                va_mps: 0.0,
            },
        ];
        let t: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-4).collect();
        LOOPS.with(|c| c.set(0));
        let tr = simulate_pair(&model, &pair, init, &t);
        let loops = LOOPS.with(|c| c.get());
        let joined = tr.impacts.iter().filter(|i| i.joined).count();
        assert_eq!(joined, 1, "joined once: {:?}", tr.impacts.len());
        // impacts + phase switches of both particles + end, with a little room
        let switches: usize = tr.particles.iter().map(|p| p.events.len()).sum();
        assert!(
            loops <= tr.impacts.len() * 3 + switches + 4,
            "{loops} loops for {} impacts",
            tr.impacts.len()
        );
    }
}
