//! Why a fit stopped: the shared [`crate::lsq::Termination`] (fits.csv's `status` comes from it).

pub use crate::lsq::Termination;
