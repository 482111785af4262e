//! The joint piecewise model of a collision run: both tracks, split at the impact times, each
//! piece the closed-form motion from its own (v, slip) with shared μ and T, z continuous at impacts.
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

/// Index of the parameters of one piece of one particle's track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Piece {
    /// At rest (the target before the first impact): no parameters.
    Rest,
    /// Moving: parameter indices of the velocity and the slip v − s·v_a at the piece's start.
    Moving { v: usize, slip: usize },
    /// Moving just after a kick that gave no spin: parameter indices of v and of v_a itself,
    /// which is bounded to what friction can build up within the first frame.
    Kicked { v: usize, va: usize },
}

/// Layout of the parameter vector: [μ, T, impact times…, per particle: z_start, pieces…].
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
    pub n_params: usize,
}

pub const MU: usize = 0;
pub const T_DRAG: usize = 1;

impl Layout {
    pub fn n_residuals(&self) -> usize {
        self.tracks[0].t_s.len() + self.tracks[1].t_s.len()
    }

    pub fn motion(&self, p: &[f64]) -> Motion {
        Motion {
            mu: p[MU],
            t_drag_s: p[T_DRAG],
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

    /// Start times of a particle's pieces and the impact index each starts at (None: track start).
    pub fn piece_starts(&self, p: &[f64], particle: usize) -> Vec<(f64, Option<usize>)> {
        let mut starts = Vec::new();
        if let Some(t0) = self.first_start_s[particle] {
            starts.push((t0, None));
        }
        for j in 0..self.impacts.len() {
            starts.push((self.impact_time(p, j), Some(j)));
        }
        starts
    }

    /// Initial (v, v_a) of a piece.
    pub fn piece_state(&self, p: &[f64], piece: Piece) -> (f64, f64) {
        match piece {
            Piece::Rest => (0.0, 0.0),
            Piece::Moving { v, slip } => (p[v], (p[v] - p[slip]) / self.s),
            Piece::Kicked { v, va } => (p[v], p[va]),
        }
    }

    /// Model positions of one particle at its sample times.
    pub fn positions(&self, p: &[f64], particle: usize, out: &mut [f64]) {
        let track = &self.tracks[particle];
        let motion = self.motion(p);
        let starts = self.piece_starts(p, particle);
        let pieces = &self.pieces[particle];
        let mut z = p[self.z_start[particle]];
        let mut i = 0;
        let n = track.t_s.len();
        let mut buf: Vec<f64> = Vec::new();
        let mut rel: Vec<f64> = Vec::new();
        for (k, piece) in pieces.iter().enumerate() {
            let t0 = starts[k].0;
            let t_end = starts.get(k + 1).map(|s| s.0).unwrap_or(f64::INFINITY);
            let (v0, va0) = self.piece_state(p, *piece);
            let first = i;
            while i < n && (track.t_s[i] < t_end || k + 1 == pieces.len()) {
                i += 1;
            }
            rel.clear();
            rel.extend(track.t_s[first..i].iter().map(|t| (t - t0).max(0.0)));
            buf.resize(rel.len(), 0.0);
            if matches!(piece, Piece::Rest) {
                buf.iter_mut().for_each(|b| *b = 0.0);
            } else {
                motion.positions(v0, va0, &rel, &mut buf);
            }
            for (o, b) in out[first..i].iter_mut().zip(&buf) {
                *o = z + b;
            }
            if t_end.is_finite() && !matches!(piece, Piece::Rest) {
                z += motion.state(v0, va0, (t_end - t0).max(0.0)).dz_m;
            }
        }
    }

    /// Residuals model − data of both tracks, concatenated (striker first).
    pub fn residuals(&self, p: &[f64], out: &mut [f64]) {
        let n0 = self.tracks[0].t_s.len();
        let (a, b) = out.split_at_mut(n0);
        self.positions(p, 0, a);
        self.positions(p, 1, b);
        for (o, z) in a.iter_mut().zip(&self.tracks[0].z_m) {
            *o -= z;
        }
        for (o, z) in b.iter_mut().zip(&self.tracks[1].z_m) {
            *o -= z;
        }
    }

    /// State of a particle just before impact `j` (from the piece that ends there).
    pub fn before_impact(&self, p: &[f64], particle: usize, j: usize) -> Option<Kinematics> {
        let starts = self.piece_starts(p, particle);
        let k = starts.iter().position(|s| s.1 == Some(j))?;
        if k == 0 {
            return None;
        }
        let (t_prev, _) = starts[k - 1];
        let piece = self.pieces[particle][k - 1];
        let (v0, va0) = self.piece_state(p, piece);
        if matches!(piece, Piece::Rest) {
            return Some(Kinematics {
                dz_m: 0.0,
                v_mps: 0.0,
                va_mps: 0.0,
                sliding: false,
            });
        }
        Some(
            self.motion(p)
                .state(v0, va0, (starts[k].0 - t_prev).max(0.0)),
        )
    }

    /// State of a particle just after impact `j` (the start of the piece that begins there).
    pub fn after_impact(&self, p: &[f64], particle: usize, j: usize) -> Option<(f64, f64)> {
        let starts = self.piece_starts(p, particle);
        let k = starts.iter().position(|s| s.1 == Some(j))?;
        Some(self.piece_state(p, self.pieces[particle][k]))
    }

    /// Position, velocity and spin of a particle at time `t` (before the first piece: its start).
    pub fn state_at(&self, p: &[f64], particle: usize, t_s: f64) -> (f64, f64, f64) {
        let starts = self.piece_starts(p, particle);
        let motion = self.motion(p);
        let pieces = &self.pieces[particle];
        let mut z = p[self.z_start[particle]];
        for (k, piece) in pieces.iter().enumerate() {
            let t0 = starts[k].0;
            let t_end = starts.get(k + 1).map(|s| s.0).unwrap_or(f64::INFINITY);
            let (v0, va0) = self.piece_state(p, *piece);
            let moving = !matches!(piece, Piece::Rest);
            if t_s < t_end || k + 1 == pieces.len() {
                if !moving {
                    return (z, 0.0, 0.0);
                }
                let st = motion.state(v0, va0, (t_s - t0).max(0.0));
                return (z + st.dz_m, st.v_mps, st.va_mps);
            }
            if moving {
                z += motion.state(v0, va0, (t_end - t0).max(0.0)).dz_m;
            }
        }
        (z, 0.0, 0.0)
    }
}
