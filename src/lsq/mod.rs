//! One least-squares core for every fit in groove: the robust losses, one termination enum, and
//! the back-ends — `fixed` (allocation-free arrays, the per-run hot path) with its robust loop
//! `robust`; `lm`, the Levenberg–Marquardt driver (Huber IRLS rounds, the same active-set bound
//! strategy) of `dense_fit` (a collision run) and `block` (shared plus per-run parameters through
//! a Schur complement: the whole-run pair fits and discovery's joint fit); `dense` (Cholesky
//! solves and inverses of small dense systems), `fd` (forward-difference Jacobian
//! columns that step inward at an upper bound), and `golden` (a one-dimensional golden-section
//! search). A singular system is `None` or
//! [`Termination::Singular`], never a made-up factor.
//!
//! Files of this folder:
//!
//! - `block.rs`: The block-arrow back-end of the [`lm`] driver
//! - `dense.rs`: The dense back-end
//! - `dense_fit.rs`: The dense back-end of the [`lm`] driver
//! - `fd.rs`: Forward-difference Jacobians for models without an analytic one
//! - `fixed.rs`: The fixed-size, allocation-free back-end
//! - `golden.rs`: Golden-section search for the minimum of a one-dimensional function
//! - `lm.rs`: The Levenberg–Marquardt driver of the allocating back-ends
//! - `loss.rs`: Robust losses: ρ(u) and the IRLS weight ψ(u)/u
//! - `robust.rs`: The robust loop of the fixed-size back-end
//! - `termination.rs`: Why a minimisation stopped
//! - `wide.rs`: The fit's hottest loop compiled for wider vectors where the CPU has them

pub mod block;
pub mod dense;
pub mod dense_fit;
pub mod fd;
pub mod fixed;
pub mod golden;
pub mod lm;
pub mod loss;
pub mod robust;
pub mod termination;
pub mod wide;

pub use termination::Termination;

/// Where a step of `step` from `x` leaves the box [lo, hi]: the step that stops on the bound it
/// crosses (`bound − x`), or None inside. The active-set step of every back-end pins with it.
#[inline]
pub fn step_to_bound(x: f64, step: f64, lo: f64, hi: f64) -> Option<f64> {
    let to = x + step;
    if to < lo {
        Some(lo - x)
    } else if to > hi {
        Some(hi - x)
    } else {
        None
    }
}

/// The active set's pinning, one round: each parameter still `on` whose `step` from `x` leaves
/// its box `bounds(i)` = (lo, hi) is moved exactly onto the bound it crosses (that step kept in
/// `pinned`, the parameter taken off `on`); true when any was. The bounded steps of `fixed` and
/// `lm` both pin through it, so the two back-ends share one bound strategy.
#[inline]
pub fn pin_crossings(
    x: &[f64],
    step: &[f64],
    bounds: impl Fn(usize) -> (f64, f64),
    on: &mut [bool],
    pinned: &mut [Option<f64>],
) -> bool {
    let mut hit = false;
    for i in 0..x.len() {
        if !on[i] {
            continue;
        }
        let (lo, hi) = bounds(i);
        let Some(d) = step_to_bound(x[i], step[i], lo, hi) else {
            continue;
        };
        on[i] = false;
        pinned[i] = Some(d);
        hit = true;
    }
    hit
}
