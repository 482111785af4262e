//! A fit plan: starting values and bounds of every parameter of the joint model, turned into a
//! `Layout` plus `ParamSpec`s, and read back from a solution.

use super::model::{DragPrior, ImpactTime, Layout, Piece, TrackData, MU, T_DRAG};
use crate::lsq::lm::ParamSpec;

/// The first piece of a particle's track when it does not start at an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FirstPiece {
    Rest {
        t0_s: f64,
    },
    /// Kicked within the frame before `t0_s` with no spin: v_a(t0) between 0 and `va_max_mps`.
    Kicked {
        t0_s: f64,
        v_mps: f64,
        va_mps: f64,
        va_max_mps: f64,
    },
}

/// How the states after an impact are parameterized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum After {
    /// Tied to the states before: striker v − J, target v + J, both v_a + W.
    Impulse { j_mps: f64, w_mps: f64 },
    /// Both particles start at the kick (contact setup) with free v and v_a ∈ [0, va_max].
    Kicked {
        v_mps: [f64; 2],
        va_mps: [f64; 2],
        va_max_mps: f64,
    },
}

/// One impact: time (fitted within bounds, or fixed) and the states after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanImpact {
    pub t_s: f64,
    pub fixed: bool,
    pub lower_s: f64,
    pub upper_s: f64,
    pub after: After,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub mu: f64,
    pub t_drag_s: f64,
    /// Hold μ and T at their start values (a short approach cannot separate them).
    pub hold_friction: bool,
    /// One drag time per piece (start values below, default `t_drag_s`) instead of one per run.
    pub drag_per_piece: bool,
    pub piece_t_drag_s: [Vec<f64>; 2],
    /// Position noise (m): the unit of the drag prior's pseudo-residuals.
    pub noise_m: f64,
    pub z_start_m: [f64; 2],
    pub first: [Option<FirstPiece>; 2],
    pub impacts: Vec<PlanImpact>,
}

pub const MU_BOUNDS: (f64, f64) = (0.02, 1.5);
pub const T_BOUNDS_S: (f64, f64) = (0.003, 10.0);
const V_MAX_MPS: f64 = 3.0;
/// Spread of a piece's ln T around the run's T: a factor e^0.5 ≈ 1.6.
pub const DRAG_PRIOR_SIGMA_LN: f64 = 0.5;

fn push(specs: &mut Vec<ParamSpec>, start: f64, lower: f64, upper: f64, step: f64) -> usize {
    specs.push(ParamSpec {
        start: start.clamp(lower, upper),
        lower,
        upper,
        step,
    });
    specs.len() - 1
}

fn va_bounds(va_max: f64) -> (f64, f64) {
    if va_max >= 0.0 {
        (0.0, va_max)
    } else {
        (va_max, 0.0)
    }
}

impl Plan {
    pub fn build(&self, tracks: [TrackData; 2], s: f64, k: f64) -> (Layout, Vec<ParamSpec>) {
        let mut sp = Vec::new();
        let held = |x: f64, b: (f64, f64)| if self.hold_friction { (x, x) } else { b };
        let (mu_lo, mu_hi) = held(self.mu, MU_BOUNDS);
        let ln = |b: (f64, f64)| (b.0.ln(), b.1.ln());
        let (t_lo, t_hi) = held(self.t_drag_s.ln(), ln(T_BOUNDS_S));
        assert_eq!(push(&mut sp, self.mu, mu_lo, mu_hi, 1e-6), MU);
        assert_eq!(push(&mut sp, self.t_drag_s.ln(), t_lo, t_hi, 1e-5), T_DRAG);
        let mut impacts = Vec::new();
        // per impact: the pieces it starts for the striker and the target
        let mut after: Vec<[Piece; 2]> = Vec::new();
        for im in &self.impacts {
            impacts.push(if im.fixed {
                ImpactTime::Fixed(im.t_s)
            } else {
                ImpactTime::Param(push(&mut sp, im.t_s, im.lower_s, im.upper_s, 1e-8))
            });
            after.push(match im.after {
                After::Impulse { j_mps, w_mps } => {
                    let j = push(&mut sp, j_mps, 0.0, V_MAX_MPS, 1e-7);
                    let w = push(&mut sp, w_mps, -3.0 * V_MAX_MPS, 3.0 * V_MAX_MPS, 1e-7);
                    [
                        Piece::Impulse { j, w, sign: -1.0 },
                        Piece::Impulse { j, w, sign: 1.0 },
                    ]
                }
                After::Kicked {
                    v_mps,
                    va_mps,
                    va_max_mps,
                } => {
                    let (lo, hi) = va_bounds(va_max_mps);
                    [0, 1].map(|p| Piece::Kicked {
                        v: push(&mut sp, v_mps[p], -V_MAX_MPS, V_MAX_MPS, 1e-7),
                        va: push(&mut sp, va_mps[p], lo, hi, 1e-8),
                    })
                }
            });
        }
        let mut z_start = [0; 2];
        let mut first_start_s = [None; 2];
        let mut pieces: [Vec<Piece>; 2] = [Vec::new(), Vec::new()];
        let mut drag: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        for p in 0..2 {
            let z = self.z_start_m[p];
            z_start[p] = push(&mut sp, z, z - 0.1, z + 0.1, 1e-9);
            match self.first[p] {
                Some(FirstPiece::Rest { t0_s }) => {
                    first_start_s[p] = Some(t0_s);
                    pieces[p].push(Piece::Rest);
                }
                Some(FirstPiece::Kicked {
                    t0_s,
                    v_mps,
                    va_mps,
                    va_max_mps,
                }) => {
                    first_start_s[p] = Some(t0_s);
                    let (lo, hi) = va_bounds(va_max_mps);
                    pieces[p].push(Piece::Kicked {
                        v: push(&mut sp, v_mps, -V_MAX_MPS, V_MAX_MPS, 1e-7),
                        va: push(&mut sp, va_mps, lo, hi, 1e-8),
                    });
                }
                None => {}
            }
            pieces[p].extend(after.iter().map(|a| a[p]));
            for (k, piece) in pieces[p].iter().enumerate() {
                drag[p].push(if self.drag_per_piece && *piece != Piece::Rest {
                    let t = self.piece_t_drag_s[p]
                        .get(k)
                        .copied()
                        .unwrap_or(self.t_drag_s);
                    let (lo, hi) = held(t.ln(), ln(T_BOUNDS_S));
                    push(&mut sp, t.ln(), lo, hi, 1e-5)
                } else {
                    T_DRAG
                });
            }
        }
        let n_params = sp.len();
        let layout = Layout {
            s,
            k,
            tracks,
            impacts,
            z_start,
            first_start_s,
            pieces,
            drag,
            drag_prior: self.drag_per_piece.then_some(DragPrior {
                sigma_ln: DRAG_PRIOR_SIGMA_LN,
                noise_m: self.noise_m,
            }),
            n_params,
        };
        (layout, sp)
    }

    /// The plan whose start values are the solution `p` of `layout` (built from this plan).
    pub fn from_solution(&self, layout: &Layout, p: &[f64]) -> Plan {
        let mut out = self.clone();
        out.mu = p[MU];
        out.t_drag_s = p[T_DRAG].exp();
        for part in 0..2 {
            out.z_start_m[part] = p[layout.z_start[part]];
            let offset = usize::from(out.first[part].is_some());
            if let (Some(FirstPiece::Kicked { v_mps, va_mps, .. }), Piece::Kicked { v, va }) =
                (out.first[part].as_mut(), layout.pieces[part][0])
            {
                *v_mps = p[v];
                *va_mps = p[va];
            }
            for (j, im) in out.impacts.iter_mut().enumerate() {
                match (&mut im.after, layout.pieces[part][j + offset]) {
                    (After::Impulse { j_mps, w_mps }, Piece::Impulse { j, w, .. }) => {
                        *j_mps = p[j];
                        *w_mps = p[w];
                    }
                    (After::Kicked { v_mps, va_mps, .. }, Piece::Kicked { v, va }) => {
                        v_mps[part] = p[v];
                        va_mps[part] = p[va];
                    }
                    _ => {}
                }
            }
        }
        for (j, im) in out.impacts.iter_mut().enumerate() {
            im.t_s = layout.impact_time(p, j);
        }
        out.piece_t_drag_s =
            [0, 1].map(|part| layout.drag[part].iter().map(|&i| p[i].exp()).collect());
        out
    }
}
