//! A fit plan: starting values and bounds of every parameter of the joint model, turned into a
//! `Layout` plus `ParamSpec`s, and read back from a solution (to insert an impact and refit).

use super::lm::ParamSpec;
use super::model::{ImpactTime, Layout, Piece, TrackData, MU, T_DRAG};

/// The first piece of a particle's track when it does not start at an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FirstPiece {
    Rest {
        t0_s: f64,
    },
    Moving {
        t0_s: f64,
        v_mps: f64,
        slip_mps: f64,
    },
    /// Kicked within the frame before `t0_s` with no spin: v_a(t0) ∈ [0, k g μ_max · frame].
    Kicked {
        t0_s: f64,
        v_mps: f64,
        va_mps: f64,
        va_max_mps: f64,
    },
}

/// One impact: time (fitted within bounds, or fixed) and both particles' (v, slip) after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanImpact {
    pub t_s: f64,
    pub fixed: bool,
    pub lower_s: f64,
    pub upper_s: f64,
    pub after: [(f64, f64); 2],
}

#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub mu: f64,
    pub t_drag_s: f64,
    /// Hold μ and T at their start values (used for quick pre-fits).
    pub hold_friction: bool,
    pub z_start_m: [f64; 2],
    pub first: [Option<FirstPiece>; 2],
    pub impacts: Vec<PlanImpact>,
}

pub const MU_BOUNDS: (f64, f64) = (0.02, 1.5);
pub const T_BOUNDS_S: (f64, f64) = (0.003, 10.0);
const V_MAX_MPS: f64 = 3.0;

fn push(specs: &mut Vec<ParamSpec>, start: f64, lower: f64, upper: f64, step: f64) -> usize {
    specs.push(ParamSpec {
        start,
        lower,
        upper,
        step,
    });
    specs.len() - 1
}

impl Plan {
    pub fn build(&self, tracks: [TrackData; 2], s: f64, k: f64) -> (Layout, Vec<ParamSpec>) {
        let mut specs = Vec::new();
        let mut add = |start: f64, lower: f64, upper: f64, step: f64| {
            push(&mut specs, start, lower, upper, step)
        };
        let held = |x: f64, b: (f64, f64)| if self.hold_friction { (x, x) } else { b };
        let (ml, mh) = held(self.mu, MU_BOUNDS);
        let (tl, th) = held(self.t_drag_s, T_BOUNDS_S);
        assert_eq!(add(self.mu, ml, mh, 1e-6), MU);
        assert_eq!(add(self.t_drag_s, tl, th, 1e-6), T_DRAG);
        let impacts: Vec<ImpactTime> = self
            .impacts
            .iter()
            .map(|im| {
                if im.fixed {
                    ImpactTime::Fixed(im.t_s)
                } else {
                    ImpactTime::Param(add(im.t_s, im.lower_s, im.upper_s, 1e-8))
                }
            })
            .collect();
        let mut z_start = [0; 2];
        let mut first_start_s = [None; 2];
        let mut pieces: [Vec<Piece>; 2] = [Vec::new(), Vec::new()];
        for p in 0..2 {
            let z = self.z_start_m[p];
            z_start[p] = add(z, z - 0.1, z + 0.1, 1e-9);
            let moving = |add: &mut dyn FnMut(f64, f64, f64, f64) -> usize, v: f64, slip: f64| {
                Piece::Moving {
                    v: add(v, -V_MAX_MPS, V_MAX_MPS, 1e-7),
                    slip: add(slip, -3.0 * V_MAX_MPS, 3.0 * V_MAX_MPS, 1e-7),
                }
            };
            match self.first[p] {
                Some(FirstPiece::Rest { t0_s }) => {
                    first_start_s[p] = Some(t0_s);
                    pieces[p].push(Piece::Rest);
                }
                Some(FirstPiece::Moving {
                    t0_s,
                    v_mps,
                    slip_mps,
                }) => {
                    first_start_s[p] = Some(t0_s);
                    pieces[p].push(moving(&mut add, v_mps, slip_mps));
                }
                Some(FirstPiece::Kicked {
                    t0_s,
                    v_mps,
                    va_mps,
                    va_max_mps,
                }) => {
                    first_start_s[p] = Some(t0_s);
                    let (lo, hi) = if va_max_mps >= 0.0 {
                        (0.0, va_max_mps)
                    } else {
                        (va_max_mps, 0.0)
                    };
                    pieces[p].push(Piece::Kicked {
                        v: add(v_mps, -V_MAX_MPS, V_MAX_MPS, 1e-7),
                        va: add(va_mps.clamp(lo, hi), lo, hi, 1e-8),
                    });
                }
                None => {}
            }
            for im in &self.impacts {
                pieces[p].push(moving(&mut add, im.after[p].0, im.after[p].1));
            }
        }
        let n_params = specs.len();
        let layout = Layout {
            s,
            k,
            tracks,
            impacts,
            z_start,
            first_start_s,
            pieces,
            n_params,
        };
        (layout, specs)
    }

    /// The plan whose start values are the solution `p` of `layout` (same structure).
    pub fn from_solution(&self, layout: &Layout, p: &[f64]) -> Plan {
        let mut out = self.clone();
        out.mu = p[MU];
        out.t_drag_s = p[T_DRAG];
        for part in 0..2 {
            out.z_start_m[part] = p[layout.z_start[part]];
            let mut pieces = layout.pieces[part].iter();
            if let Some(first) = out.first[part].as_mut() {
                match (first, pieces.next().copied()) {
                    (
                        FirstPiece::Moving {
                            v_mps, slip_mps, ..
                        },
                        Some(Piece::Moving { v, slip }),
                    ) => {
                        *v_mps = p[v];
                        *slip_mps = p[slip];
                    }
                    (FirstPiece::Kicked { v_mps, va_mps, .. }, Some(Piece::Kicked { v, va })) => {
                        *v_mps = p[v];
                        *va_mps = p[va];
                    }
                    _ => {}
                }
            }
            for (im, piece) in out.impacts.iter_mut().zip(pieces) {
                if let Piece::Moving { v, slip } = *piece {
                    im.after[part] = (p[v], p[slip]);
                }
            }
        }
        for (j, im) in out.impacts.iter_mut().enumerate() {
            im.t_s = layout.impact_time(p, j);
        }
        out
    }
}
