//! Two equal particles in one groove: one-particle dynamics for each, impulses at contact (2R),
//! and the cascade of secondary collisions.
//!
//! The cascade of an ideal rolling pair is infinite but converges (Zeno): once the approach speed
//! at an impact is below `V_TOGETHER_MPS`, or under an attraction at contact the rebound could
//! open no more than `JOIN_GAP_M` (or after `MAX_IMPACTS`), the impact is completed by giving both
//! particles their mean v and va, so they move on together in contact.
//!
//! Under an attraction at contact such a pair is then held together as one body (`hold`): both
//! keep one speed, the contact's normal force that this needs is solved from their modes
//! (`PairParams::held`), its friction brakes both spins (`PairParams::contact_friction`), and
//! the two part where that force would pull. Left as two free particles, an attracted pair
//! chattered at the contact (the attraction released at each parting by 10⁻¹³ m and the contact's
//! friction with it), in steps so small that one simulation took up to 2 s and a pair check under
//! a waviness over half an hour; held, it takes milliseconds.
//!
//! μ_pp is one number, or (`PairParams::slip`) a function of the slip speed at the contact,
//! |v_a1 + v_a2| before each impact, through which the impulse is then applied.

use super::advance::{advance, Pace, Sampler};
use super::impulse::collide;
use super::mode::{start, Mode};
use super::pair_force::PairForce;
use super::rk::Tolerance;
use super::slip_friction::SlipFriction;
use super::{Model, Phase, Restitution, State, SwitchEvent, Trajectory};
use serde::{Deserialize, Serialize};
use std::cell::Cell;

/// Approach speed (m/s) below which an impact ends the cascade: the pair moves on together.
pub const V_TOGETHER_MPS: f64 = 1e-7;
/// Most impacts resolved one by one in a simulation.
const MAX_IMPACTS: usize = 1000;
/// Under an attraction at contact, the widest gap (m) a rebound may open before the attraction
/// brings the pair back for the impact to be resolved as a bounce: a rebound that could open no
/// more (a nanometre, a thousandth of what a tracker resolves) starts a cascade of bounces no
/// camera sees, and the pair is joined at once. Resolved one by one, such a cascade took hundreds
/// of bounces at approach speeds of 10⁻⁷ m/s, each in hundreds of steps, until the simulation's
/// step budget ran out (one refit under a fitted attraction stopped there 621 times).
const JOIN_GAP_M: f64 = 1e-9;
/// Overlap (relative to 2R) that counts as touching: rounding never starts a false impact.
const CONTACT_SLACK: f64 = 1e-9;
/// Cap on all events (phase switches and impacts).
const MAX_EVENTS: usize = 20_000;
/// The cap with a force between the particles: a pair that an attraction pulls back after each
/// impact bounces at contact in ever smaller steps before it is held. Past the cap the pair stays
/// where it is, a misfit the fit sees.
const MAX_EVENTS_WITH_FORCE: usize = 2_000;

/// The time in which the friction of a held pair's contact stops its slip once the slip is small
/// (`PairParams::contact_friction`): a Coulomb law smoothed below the slip it takes away in this
/// time, so that a contact that sticks (the spins' sum held at zero) relaxes there in a tenth of a
/// frame instead of chattering.
const CONTACT_STICK_S: f64 = 1e-5;

/// A mode's `[z', v', va']` with the contact's spin friction `tau` added: on the spin alone while
/// sliding; while rolling the groove's friction shares it with the motion (va = v/s holds), so
/// v' gains s τ/(1 + ks²) (`spin_gain`).
fn with_spin(d: [f64; 3], mode: Mode, model: &Model, tau: f64) -> [f64; 3] {
    let g = &model.groove;
    match mode {
        Mode::Slide { .. } | Mode::Creep { .. } => [d[0], d[1], d[2] + tau],
        Mode::Roll { .. } => {
            let dv = spin_gain(mode, model) * tau;
            [d[0], d[1] + dv, d[2] + dv / g.s]
        }
        Mode::Rest => d,
    }
}

/// How much `v'` moves per unit of spin friction in this mode (`with_spin`).
fn spin_gain(mode: Mode, model: &Model) -> f64 {
    let g = &model.groove;
    match mode {
        Mode::Roll { .. } => g.s / (1.0 + g.ks2()),
        _ => 0.0,
    }
}

/// The force a rolling hold sees beside the contact's spin friction `tau`: rolling needs the
/// groove's friction s(a − sτ)/(1 + ks²), as under a force a − sτ alone.
fn hold_ext(ext: f64, model: &Model, tau: f64) -> f64 {
    ext - model.groove.s * tau
}

/// A pair an attraction holds together, at one state: the contact's normal force per unit mass
/// (> 0 presses the two apart; below 0 they part), the contact's spin friction on each particle,
/// and the force on each from outside its own model (the attraction and the normal force).
#[derive(Clone, Copy)]
struct Held {
    normal: f64,
    tau: f64,
    ext: [f64; 2],
}

impl Held {
    /// The force particle `i` in mode `m` sees in its events: a rolling hold bears the spin
    /// friction too.
    fn seen(&self, i: usize, m: Mode, model: &Model) -> f64 {
        match m {
            Mode::Roll { .. } => hold_ext(self.ext[i], model, self.tau),
            _ => self.ext[i],
        }
    }
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

    /// The attraction at contact (m/s², < 0), or None when the pair feels none there: only then
    /// can the two be held together.
    fn contact_attraction(&self) -> Option<f64> {
        let a = self.force?.accel(0.0);
        (a < 0.0).then_some(a)
    }

    /// The friction of a held pair's contact on both spins (the rate of change of each `va`)
    /// under the normal force `normal` per unit mass: the slip speed at the contact is the sum of
    /// the spins (two particles spinning the same way rub there), so each spin is braked by
    /// μ_pp k N, the friction the impacts' impulse carries (`impulse::collide`) taken as a rate.
    /// An attraction's pair that rolls on joined is slowed by it to rest: without it, such a pair
    /// lost 0.008 m/s² where the independent simulator's chatter of contacts took 0.11 m/s².
    fn contact_friction(&self, y: &[f64], (l, r): (usize, usize), normal: f64, k: f64) -> f64 {
        if normal <= 0.0 {
            return 0.0;
        }
        let sum = y[3 * l + 2] + y[3 * r + 2];
        let brake = self.mu_pp_at(sum) * k * normal;
        // smoothed over the slip the brake takes away in `CONTACT_STICK_S`
        let scale = (brake * CONTACT_STICK_S).max(f64::MIN_POSITIVE);
        -brake * (sum / scale).clamp(-1.0, 1.0)
    }

    /// The held pair at `y` in modes `ms`: the normal force that keeps both at one speed. Each
    /// mode's v' is affine in the force from outside (`Mode::ext_gain`, `spin_gain`), so it is
    /// solved for; the spin friction it carries is taken at the normal force without it.
    fn held(&self, model: &Model, ms: [Mode; 2], y: &[f64; 7], (l, r): (usize, usize)) -> Held {
        let a0 = self.contact_attraction().unwrap_or(0.0);
        let mut e = [0.0; 2];
        e[l] = -a0;
        e[r] = a0;
        let free =
            |i: usize| ms[i].rhs(model, &[y[3 * i], y[3 * i + 1], y[3 * i + 2]], y[6], e[i])[1];
        let (dl, dr) = (free(l), free(r));
        let gain = ms[l].ext_gain(model) + ms[r].ext_gain(model);
        let (sl, sr) = (spin_gain(ms[l], model), spin_gain(ms[r], model));
        // both at rest: the contact holds the attraction
        let solve = |tau: f64| {
            if gain > 0.0 {
                (dl - dr + (sl - sr) * tau) / gain
            } else {
                -a0
            }
        };
        let tau = self.contact_friction(y, (l, r), solve(0.0), model.groove.k);
        let normal = solve(tau);
        let mut ext = e;
        ext[l] -= normal;
        ext[r] += normal;
        Held { normal, tau, ext }
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
    let mut pace = Pace::new(t_end, Mode::Rest.step_cap(model));
    let mut next = 0;
    let mut n_events = 0;
    let max_events = if pair.force.is_some() {
        MAX_EVENTS_WITH_FORCE
    } else {
        MAX_EVENTS
    };
    // held together by an attraction (see `PairSim::hold`)
    let mut held = false;
    let sim = PairSim {
        model,
        pair,
        lr: (l, r),
    };
    loop {
        #[cfg(test)]
        LOOPS.with(|c| c.set(c.get() + 1));
        // an impact is due when the particles touch and approach
        let gap = y[3 * r] - y[3 * l] - two_r;
        let approach = y[3 * l + 1] - y[3 * r + 1];
        if !held && gap <= CONTACT_SLACK * two_r && approach > 0.0 && n_events < max_events {
            let joined = sim.impact(t, &mut y, &mut modes, &mut out);
            n_events += 1;
            if joined {
                held = sim.hold(t, &mut y, &mut modes, &mut out);
            }
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
        let part = |yy: &[f64; 7], i: usize| [yy[3 * i], yy[3 * i + 1], yy[3 * i + 2]];
        let stop = if held {
            // dopri5's last stage of a step and the events are taken at the same state: the
            // held pair there is solved once
            let last: Cell<Option<([f64; 7], Held)>> = Cell::new(None);
            let held_at = |yy: &[f64; 7]| match last.get() {
                Some((at, hd)) if at == *yy => hd,
                _ => {
                    let hd = pair.held(model, ms, yy, (l, r));
                    last.set(Some((*yy, hd)));
                    hd
                }
            };
            advance(
                &|yy: &[f64; 7]| {
                    let hd = held_at(yy);
                    let a = ms[0].rhs(model, &part(yy, 0), yy[6], hd.ext[0]);
                    let b = ms[1].rhs(model, &part(yy, 1), yy[6], hd.ext[1]);
                    let (a, b) = (
                        with_spin(a, ms[0], model, hd.tau),
                        with_spin(b, ms[1], model, hd.tau),
                    );
                    // one speed: the two sides agree but for rounding
                    let dv = 0.5 * (a[1] + b[1]);
                    [a[0], dv, a[2], b[0], dv, b[2], 1.0]
                },
                &|yy: &[f64; 7]| {
                    let hd = held_at(yy);
                    let a = ms[0].events(model, &part(yy, 0), yy[6], hd.seen(0, ms[0], model));
                    let b = ms[1].events(model, &part(yy, 1), yy[6], hd.seen(1, ms[1], model));
                    [a[0], a[1], b[0], b[1], hd.normal]
                },
                t,
                with_t(&y, t),
                t_end,
                &mut sampler,
                &TOL,
                &mut pace,
                ms[0].step_cap(model).min(ms[1].step_cap(model)),
            )
        } else {
            advance(
                &|yy: &[f64; 7]| {
                    let e = pair.ext(yy, (l, r));
                    let a = ms[0].rhs(model, &part(yy, 0), yy[6], e[0]);
                    let b = ms[1].rhs(model, &part(yy, 1), yy[6], e[1]);
                    [a[0], a[1], a[2], b[0], b[1], b[2], 1.0]
                },
                &|yy: &[f64; 7]| {
                    let e = pair.ext(yy, (l, r));
                    let a = ms[0].events(model, &part(yy, 0), yy[6], e[0]);
                    let b = ms[1].events(model, &part(yy, 1), yy[6], e[1]);
                    let gap = yy[3 * r] - yy[3 * l] - two_r;
                    [a[0], a[1], b[0], b[1], gap + CONTACT_SLACK * two_r]
                },
                t,
                with_t(&y, t),
                t_end,
                &mut sampler,
                &TOL,
                &mut pace,
                ms[0].step_cap(model).min(ms[1].step_cap(model)),
            )
        };
        next = sampler.next;
        t = stop.t_s;
        y.copy_from_slice(&stop.y[..6]);
        n_events += 1;
        match stop.event {
            None => break,
            // the contact's normal force reached zero: the particles part
            Some(4) if held => held = false,
            Some(4) => {
                // touching: put them exactly 2R apart, then the impact fires
                touch(&mut y, (l, r), two_r);
            }
            Some(e) => {
                let fired = Some((e / 2, e % 2));
                sim.mode_events(t, &mut y, &mut modes, held, fired, &mut out);
                if held {
                    // the event's projection moved one particle's speed: both take it
                    let i = e / 2;
                    share_speed(model, &mut y, modes, i, (l, r), two_r);
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

/// What stays fixed through one pair's simulation: the physics, the pair's parameters, and which
/// particle is at lower z (`lr.0`) and which at higher (`lr.1`), an order that never changes.
#[derive(Clone, Copy)]
struct PairSim<'a> {
    model: &'a Model,
    pair: &'a PairParams,
    lr: (usize, usize),
}

impl PairSim<'_> {
    /// The force each particle sees in its mode's events at `y`: the pair force, or for a held
    /// pair the attraction and the contact's normal force (and a rolling hold its spin friction).
    fn seen_ext(&self, y: &[f64; 7], modes: [Mode; 2], held: bool) -> [f64; 2] {
        let model = self.model;
        if held {
            let hd = self.pair.held(model, modes, y, self.lr);
            [hd.seen(0, modes[0], model), hd.seen(1, modes[1], model)]
        } else {
            self.pair.ext(y, self.lr)
        }
    }

    /// Apply the mode event `fired` (particle, event) at time `t`, then any other mode event
    /// whose function is already below zero there: `advance` stops at one event, and a function
    /// already past zero would not fire again.
    fn mode_events(
        &self,
        t: f64,
        y: &mut [f64; 6],
        modes: &mut [Mode; 2],
        held: bool,
        fired: Option<(usize, usize)>,
        out: &mut PairTrajectory,
    ) {
        let model = self.model;
        let mut switch = |y: &mut [f64; 6], modes: &mut [Mode; 2], i: usize, k: usize| {
            let ext = self.seen_ext(&with_t(y, t), *modes, held);
            let yi = [y[3 * i], y[3 * i + 1], y[3 * i + 2]];
            let (m, y_new) = modes[i].after_event(model, k, &yi, t, ext[i]);
            note_switch(&mut out.particles[i], t, modes[i], m, &y_new);
            modes[i] = m;
            y[3 * i..3 * i + 3].copy_from_slice(&y_new);
        };
        if let Some((i, k)) = fired {
            switch(y, modes, i, k);
        }
        // free, only the other particle's event at the same time (a force in time starting both at
        // rest at once); held, each switch moves the normal force both particles see
        let (passes, whose) = match fired {
            Some((i, _)) if !held => (1, [1 - i, 1 - i]),
            _ => (4, [0, 1]),
        };
        for _ in 0..passes {
            let ext = self.seen_ext(&with_t(y, t), *modes, held);
            let due = whose.into_iter().find_map(|j| {
                let yj = [y[3 * j], y[3 * j + 1], y[3 * j + 2]];
                let ej = modes[j].events(model, &yj, t, ext[j]);
                (0..ej.len()).find(|&k| ej[k] < 0.0).map(|k| (j, k))
            });
            match due {
                Some((j, k)) if Some((j, k)) != fired => switch(y, modes, j, k),
                _ => break,
            }
        }
    }

    /// After an impact that ended the cascade (the pair at one speed, touching): whether an
    /// attraction holds the two together from here, and if so the pair set on that motion, 2R
    /// apart, each particle's mode settled under the contact's normal force. Without an
    /// attraction at contact, or where the contact would already pull, the two go on free.
    fn hold(
        &self,
        t: f64,
        y: &mut [f64; 6],
        modes: &mut [Mode; 2],
        out: &mut PairTrajectory,
    ) -> bool {
        let (model, pair, (l, r)) = (self.model, self.pair, self.lr);
        if pair.contact_attraction().is_none()
            || pair.held(model, *modes, &with_t(y, t), (l, r)).normal < 0.0
        {
            return false;
        }
        let two_r = 2.0 * pair.radius_m;
        touch(y, (l, r), two_r);
        self.mode_events(t, y, modes, true, None, out);
        share_speed(model, y, *modes, l, (l, r), two_r);
        true
    }

    /// Resolve one impact in place: new velocities, spins and modes of both particles. True when
    /// it ends the cascade (the pair moves on together).
    fn impact(
        &self,
        t_s: f64,
        y: &mut [f64; 6],
        modes: &mut [Mode; 2],
        out: &mut PairTrajectory,
    ) -> bool {
        let (model, pair, (l, r)) = (self.model, self.pair, self.lr);
        let pre = [state_of(y, 0), state_of(y, 1)];
        let v = [y[3 * l + 1], y[3 * r + 1]];
        let va = [y[3 * l + 2], y[3 * r + 2]];
        let approach = v[0] - v[1];
        let c = pair.restitution.at(approach);
        // a rebound at c·approach against the attraction on both particles (2|a| between them)
        // opens at most (c·approach)²/(4|a|)
        let unseen = pair
            .contact_attraction()
            .is_some_and(|a| (c * approach).powi(2) < 4.0 * a.abs() * JOIN_GAP_M);
        let joined = approach < V_TOGETHER_MPS || unseen || out.impacts.len() >= MAX_IMPACTS;
        let (c, slip, v_new, va_new) = if joined {
            let vm = 0.5 * (v[0] + v[1]);
            let vam = 0.5 * (va[0] + va[1]);
            (0.0, false, [vm, vm], [vam, vam])
        } else {
            let kick = collide(v, va, c, pair.mu_pp_at(va[0] + va[1]), model.groove.k);
            (c, kick.slip, kick.v, kick.va)
        };
        for (idx, p) in [l, r].into_iter().enumerate() {
            y[3 * p + 1] = v_new[idx];
            y[3 * p + 2] = va_new[idx];
        }
        // the mode each particle starts in (a pair that goes on held together is settled again by
        // `hold`)
        let ext = pair.ext(y, (l, r));
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
        joined
    }
}

/// Put a held pair's particles back on one speed and 2R apart after particle `i`'s event moved
/// its state (a projection onto rest, a turn at v = 0): the other takes `i`'s speed, its spin
/// with it while it rolls.
fn share_speed(
    model: &Model,
    y: &mut [f64; 6],
    modes: [Mode; 2],
    i: usize,
    (l, r): (usize, usize),
    two_r: f64,
) {
    let j = 1 - i;
    y[3 * j + 1] = y[3 * i + 1];
    match modes[j] {
        Mode::Roll { .. } => y[3 * j + 2] = y[3 * j + 1] / model.groove.s,
        Mode::Rest => y[3 * j + 2] = 0.0,
        _ => {}
    }
    touch(y, (l, r), two_r);
}

/// Puts the particles of state `y` (`l` at lower z) exactly `two_r` apart, about their centre.
fn touch(y: &mut [f64; 6], (l, r): (usize, usize), two_r: f64) {
    let mid = 0.5 * (y[3 * l] + y[3 * r]);
    y[3 * l] = mid - 0.5 * two_r;
    y[3 * r] = mid + 0.5 * two_r;
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

    /// A striker rolling at `v_mps` from z = 0 into a target at rest at `target_z_m`.
    fn striker_into_target(v_mps: f64, target_z_m: f64) -> [State; 2] {
        let s = Groove::CHAPTER.s;
        [
            State {
                z_m: 0.0,
                v_mps,
                va_mps: v_mps / s,
            },
            State {
                z_m: target_z_m,
                v_mps: 0.0,
                va_mps: 0.0,
            },
        ]
    }

    /// The impact at which `tr` joined, after checking that it is the last one and that from it
    /// on the two are 2R apart at one speed at every sample of `t`.
    fn held_from_the_join(tr: &PairTrajectory, t: &[f64]) -> usize {
        let joined = tr
            .impacts
            .iter()
            .position(|i| i.joined)
            .expect("the pair joins");
        assert_eq!(joined + 1, tr.impacts.len(), "no impact once held");
        let t_join = tr.impacts[joined].t_s;
        let (a, b) = (&tr.particles[0], &tr.particles[1]);
        assert_eq!(a.t_s.len(), t.len(), "every sample filled");
        for k in (0..t.len()).filter(|&k| t[k] > t_join) {
            assert!(
                ((b.z_m[k] - a.z_m[k]) - 300e-6).abs() < 1e-12,
                "apart at {}",
                t[k]
            );
            assert!(
                (b.v_mps[k] - a.v_mps[k]).abs() < 1e-12,
                "speeds at {}",
                t[k]
            );
        }
        joined
    }

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
        let init = striker_into_target(0.05, 3.001e-4);
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
        let init = striker_into_target(0.05, 4e-4);
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

    #[test]
    fn an_attracted_pair_joins_once_a_rebound_could_open_no_more_than_a_nanometre() {
        // a short, strong attraction (as a refit fitted one) pulls every rebound back: at
        // C = 0.95 a bounce, a cascade from 5 cm/s resolved one by one down to 10⁻⁷ m/s takes
        // about 250 bounces (in a refit's pairs, hundreds of steps each: the step budget)
        let model = Model::baseline(0.337, 0.05);
        let init = striker_into_target(0.05, 4e-4);
        let t: Vec<f64> = (0..600).map(|k| k as f64 * 1e-4).collect();
        let a = -111.0;
        let pair = PairParams {
            restitution: Restitution::Constant(0.95),
            mu_pp: 0.9,
            radius_m: 150e-6,
            force: Some(PairForce::Exponential {
                amp_mps2: a,
                range_m: 13.7e-6,
            }),
            slip: None,
        };
        LOOPS.with(|c| c.set(0));
        let tr = simulate_pair(&model, &pair, init, &t);
        let loops = LOOPS.with(|c| c.get());
        let opens = |v: f64| (0.95 * v).powi(2) / (4.0 * a.abs());
        // held from the join on: 2R apart at one speed, every sample filled
        let joined = held_from_the_join(&tr, &t);
        // every bounce before could open more than a nanometre; the joined one could not
        for im in &tr.impacts[..joined] {
            assert!(opens(im.v_impact_mps) >= JOIN_GAP_M, "{im:?}");
        }
        assert!(opens(tr.impacts[joined].v_impact_mps) < JOIN_GAP_M);
        assert!(tr.impacts[joined].v_impact_mps > 1e3 * V_TOGETHER_MPS);
        // 5 cm/s to 0.7 mm/s at 0.95 a bounce is about 85 bounces, each with its flight
        assert!(joined < 120, "{joined} bounces");
        assert!(loops < 4 * tr.impacts.len() + 50, "{loops} loops");
    }

    #[test]
    fn an_attracted_pair_is_held_as_one_body_and_a_repelled_one_is_not() {
        // a rolling striker into a resting target under a 2 mm waviness and a strong attraction:
        // left free at the contact this pair chattered to the cap on events, 1.9 s of steps
        let mut model = Model::baseline(0.293, 0.05);
        model.terms.push(crate::physics::Term::PositionForce {
            amp_mps2: 0.05,
            wavelength_m: 2e-3,
            phase_rad: 0.7,
        });
        let init = striker_into_target(0.1, 1.3e-3);
        let t: Vec<f64> = (0..600).map(|k| k as f64 * 1e-4).collect();
        let mut pair = PairParams {
            restitution: Restitution::Constant(0.9),
            mu_pp: 1.4,
            radius_m: 150e-6,
            force: Some(PairForce::Exponential {
                amp_mps2: -3.0,
                range_m: 300e-6,
            }),
            slip: None,
        };
        LOOPS.with(|c| c.set(0));
        let tr = simulate_pair(&model, &pair, init, &t);
        let loops = LOOPS.with(|c| c.get());
        assert!(loops < 200, "{loops} loops");
        // from the join on: 2R apart at one speed
        held_from_the_join(&tr, &t);
        // the same pair pushed apart instead: free, and the two part
        pair.force = Some(PairForce::Exponential {
            amp_mps2: 3.0,
            range_m: 300e-6,
        });
        let tr = simulate_pair(&model, &pair, init, &t);
        let k = t.len() - 1;
        assert!(tr.particles[1].z_m[k] - tr.particles[0].z_m[k] > 310e-6);
    }
}
