//! The joint piecewise model of a collision run: both tracks, split at the impact times, each
//! piece the closed-form motion from its own initial state with shared μ and T, z continuous at
//! impacts. After an impact the state is either free, or tied to the state before by the
//! impulse (v ∓ J, v_a + W for both particles: momentum conserved, equal spin changes).
//!
//! Positions are in the striker-forward frame (z multiplied by the direction sign), so the
//! striker always approaches the target from below.

use super::motion::{Kinematics, Motion};

/// One particle's samples (striker-forward frame), sorted by time.
#[derive(Debug, Clone, Default)]
pub struct TrackData {
    pub t_s: Vec<f64>,
    pub z_m: Vec<f64>,
}

/// Where an impact's time comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ImpactTime {
    /// Fitted: the parameter index.
    Param(usize),
    /// Fixed (the contact setup's kick, before the first frame).
    Fixed(f64),
}

/// How the initial state of one piece of one particle's track is parameterized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Piece {
    /// At rest (the target before the first impact): no parameters.
    Rest,
    /// Free: parameter indices of the velocity and the slip v − s·v_a at the piece's start.
    Moving { v: usize, slip: usize },
    /// Just after a kick that gave no spin: parameter indices of v and of v_a itself, which is
    /// bounded to what friction can build up within the first frame.
    Kicked { v: usize, va: usize },
    /// After an impact, from the state just before: v + sign·J, v_a + W (parameter indices of
    /// the impulse per mass J and the common spin change W; sign −1 striker, +1 target).
    Impulse { j: usize, w: usize, sign: f64 },
}

/// Layout of the parameter vector: [μ, T, then whatever the plan adds].
#[derive(Debug, Clone)]
pub struct Layout {
    pub s: f64,
    pub k: f64,
    pub tracks: [TrackData; 2],
    pub impacts: Vec<ImpactTime>,
    /// Per particle: the parameter index of the position at its first piece's start.
    pub z_start: [usize; 2],
    /// Per particle: the start time of the first piece when it is not an impact (rolling setup).
    pub first_start_s: [Option<f64>; 2],
    /// Per particle: its pieces in time order. A particle whose first piece starts at an impact
    /// (contact setup) has one piece per impact; otherwise one more.
    pub pieces: [Vec<Piece>; 2],
    /// Per particle, per piece: the parameter index of its drag time T (the run's shared T, or
    /// one per piece, which absorbs a drag that is not linear in v).
    pub drag: [Vec<usize>; 2],
    /// With one T per piece: each piece's ln T is drawn toward the run's shared T with this
    /// standard deviation, a pseudo-residual in units of the position noise `noise_m`. Short
    /// pieces that say little about drag keep the run's T; long ones speak for themselves.
    pub drag_prior: Option<DragPrior>,
    pub n_params: usize,
}

/// Shrinkage of per-piece drag times toward the run's T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DragPrior {
    pub sigma_ln: f64,
    pub noise_m: f64,
}

pub const MU: usize = 0;
pub const T_DRAG: usize = 1;

/// Start of one piece: time, position, velocity, spin, and the impact it starts at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PieceStart {
    pub t_s: f64,
    pub z_m: f64,
    pub v_mps: f64,
    pub va_mps: f64,
    pub impact: Option<usize>,
    pub rest: bool,
}

impl Layout {
    /// Number of position samples (the first residuals).
    pub fn n_data(&self) -> usize {
        self.tracks[0].t_s.len() + self.tracks[1].t_s.len()
    }

    fn prior_params(&self) -> impl Iterator<Item = usize> + '_ {
        self.drag.iter().flatten().copied().filter(|&i| i != T_DRAG)
    }

    pub fn n_residuals(&self) -> usize {
        self.n_data()
            + if self.drag_prior.is_some() {
                self.prior_params().count()
            } else {
                0
            }
    }

    /// The motion of piece `k` of `particle`.
    pub fn motion(&self, p: &[f64], particle: usize, k: usize) -> Motion {
        let t = self.drag[particle].get(k).copied().unwrap_or(T_DRAG);
        Motion {
            mu: p[MU],
            t_drag_s: p[t],
            s: self.s,
            k: self.k,
        }
    }

    pub fn impact_time(&self, p: &[f64], j: usize) -> f64 {
        match self.impacts[j] {
            ImpactTime::Param(i) => p[i],
            ImpactTime::Fixed(t) => t,
        }
    }

    /// The start state of every piece of a particle, in time order.
    pub fn piece_starts(&self, p: &[f64], particle: usize) -> Vec<PieceStart> {
        let mut times: Vec<(f64, Option<usize>)> = Vec::new();
        if let Some(t0) = self.first_start_s[particle] {
            times.push((t0, None));
        }
        times.extend((0..self.impacts.len()).map(|j| (self.impact_time(p, j), Some(j))));
        let mut out: Vec<PieceStart> = Vec::with_capacity(times.len());
        let mut z = p[self.z_start[particle]];
        let (mut v_end, mut va_end) = (0.0, 0.0);
        for (k, piece) in self.pieces[particle].iter().enumerate() {
            let (t0, impact) = times[k];
            if let Some(prev) = out.last() {
                if prev.rest {
                    (v_end, va_end) = (0.0, 0.0);
                } else {
                    let motion = self.motion(p, particle, k - 1);
                    let st = motion.state(prev.v_mps, prev.va_mps, (t0 - prev.t_s).max(0.0));
                    z = prev.z_m + st.dz_m;
                    (v_end, va_end) = (st.v_mps, st.va_mps);
                }
            }
            let (v, va) = match *piece {
                Piece::Rest => (0.0, 0.0),
                Piece::Moving { v, slip } => (p[v], (p[v] - p[slip]) / self.s),
                Piece::Kicked { v, va } => (p[v], p[va]),
                Piece::Impulse { j, w, sign } => (v_end + sign * p[j], va_end + p[w]),
            };
            out.push(PieceStart {
                t_s: t0,
                z_m: z,
                v_mps: v,
                va_mps: va,
                impact,
                rest: matches!(piece, Piece::Rest),
            });
        }
        out
    }

    /// Model positions of one particle at its sample times.
    pub fn positions(&self, p: &[f64], particle: usize, out: &mut [f64]) {
        let track = &self.tracks[particle];
        let starts = self.piece_starts(p, particle);
        let n = track.t_s.len();
        let mut i = 0;
        let mut rel: Vec<f64> = Vec::new();
        let mut buf: Vec<f64> = Vec::new();
        for (k, st) in starts.iter().enumerate() {
            let t_end = starts.get(k + 1).map(|s| s.t_s).unwrap_or(f64::INFINITY);
            let first = i;
            while i < n && (track.t_s[i] < t_end || k + 1 == starts.len()) {
                i += 1;
            }
            if st.rest {
                out[first..i].iter_mut().for_each(|o| *o = st.z_m);
                continue;
            }
            rel.clear();
            rel.extend(track.t_s[first..i].iter().map(|t| (t - st.t_s).max(0.0)));
            buf.resize(rel.len(), 0.0);
            self.motion(p, particle, k)
                .positions(st.v_mps, st.va_mps, &rel, &mut buf);
            for (o, b) in out[first..i].iter_mut().zip(&buf) {
                *o = st.z_m + b;
            }
        }
    }

    /// Residuals model − data of both tracks, concatenated (striker first).
    pub fn residuals(&self, p: &[f64], out: &mut [f64]) {
        let n0 = self.tracks[0].t_s.len();
        let (data, prior) = out.split_at_mut(self.n_data());
        if let Some(dp) = self.drag_prior {
            for (o, i) in prior.iter_mut().zip(self.prior_params()) {
                *o = (p[i] / p[T_DRAG]).ln() / dp.sigma_ln * dp.noise_m;
            }
        }
        let (a, b) = data.split_at_mut(n0);
        self.positions(p, 0, a);
        self.positions(p, 1, b);
        for (o, z) in a.iter_mut().zip(&self.tracks[0].z_m) {
            *o -= z;
        }
        for (o, z) in b.iter_mut().zip(&self.tracks[1].z_m) {
            *o -= z;
        }
    }

    /// State of a particle just before impact `j` (None if its track starts at that impact).
    pub fn before_impact(&self, p: &[f64], particle: usize, j: usize) -> Option<Kinematics> {
        let starts = self.piece_starts(p, particle);
        let k = starts.iter().position(|s| s.impact == Some(j))?;
        let prev = starts.get(k.checked_sub(1)?)?;
        if prev.rest {
            return Some(Kinematics {
                dz_m: 0.0,
                v_mps: 0.0,
                va_mps: 0.0,
                sliding: false,
            });
        }
        let motion = self.motion(p, particle, k - 1);
        Some(motion.state(prev.v_mps, prev.va_mps, (starts[k].t_s - prev.t_s).max(0.0)))
    }

    /// (v, v_a) of a particle just after impact `j`.
    pub fn after_impact(&self, p: &[f64], particle: usize, j: usize) -> Option<(f64, f64)> {
        let starts = self.piece_starts(p, particle);
        let st = starts.iter().find(|s| s.impact == Some(j))?;
        Some((st.v_mps, st.va_mps))
    }

    /// Position, velocity and spin of a particle at time `t` (before the first piece: its start).
    pub fn state_at(&self, p: &[f64], particle: usize, t_s: f64) -> (f64, f64, f64) {
        let starts = self.piece_starts(p, particle);
        let k = starts.iter().rposition(|s| s.t_s <= t_s).unwrap_or(0);
        let st = starts[k];
        if st.rest {
            return (st.z_m, 0.0, 0.0);
        }
        let kin = self
            .motion(p, particle, k)
            .state(st.v_mps, st.va_mps, (t_s - st.t_s).max(0.0));
        (st.z_m + kin.dz_m, kin.v_mps, kin.va_mps)
    }
}
