//! One least-squares core for every fit in groove: the robust losses, one termination enum, and
//! the back-ends — `fixed` (allocation-free arrays, the per-run hot path) with its robust loop
//! `robust`, `dense` (Cholesky solves and inverses of small dense systems: collisions, and the
//! blocks and Schur complement of discovery's block-sparse fit), and `fd` (forward-difference
//! Jacobian columns that step inward at an upper bound). A singular system is `None` or
//! [`Termination::Singular`], never a made-up factor.

pub mod dense;
pub mod fd;
pub mod fixed;
pub mod loss;
pub mod robust;
pub mod termination;

pub use termination::Termination;
