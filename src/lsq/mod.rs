//! One least-squares core for every fit in groove: the robust losses, one termination enum, and
//! the back-ends — `fixed` (allocation-free arrays, the per-run hot path) with its robust loop
//! `robust`; `lm`, the Levenberg–Marquardt driver (Huber IRLS rounds, the same active-set bound
//! strategy) of `dense_fit` (a collision run) and `block` (shared plus per-run parameters through
//! a Schur complement: the whole-run pair fits and discovery's joint fit); `dense` (Cholesky
//! solves and inverses of small dense systems), and `fd` (forward-difference Jacobian
//! columns that step inward at an upper bound). A singular system is `None` or
//! [`Termination::Singular`], never a made-up factor.

pub mod block;
pub mod dense;
pub mod dense_fit;
pub mod fd;
pub mod fixed;
pub mod lm;
pub mod loss;
pub mod robust;
pub mod termination;

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
