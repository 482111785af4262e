//! The least-squares problem of one track: observed positions against the closed-form model.

use super::model::{Prepared, NP};
use crate::lsq::fixed::{self, Problem};
use crate::physics::Groove;

/// Box bounds of a track's fit; a parameter with `free[i] == false` stays at its start value.
pub type Bounds = fixed::Bounds<NP>;
/// Stopping rules of a track's fit.
pub type Settings = fixed::Settings<NP>;
/// Buffers reused across fits (the iterations allocate nothing).
pub type Workspace = fixed::Workspace<NP>;
/// How the robust fit of a track treats residuals.
pub type RobustOptions = crate::lsq::robust::RobustOptions<NP>;
/// The result of a track's robust fit.
pub type RobustFit = crate::lsq::robust::RobustFit<NP>;

/// Frames (t, z) of one track, the model's time origin and the groove.
pub struct TrackProblem<'a> {
    pub t_s: &'a [f64],
    pub z_m: &'a [f64],
    pub t_ref_s: f64,
    pub groove: Groove,
}

impl Problem<NP> for TrackProblem<'_> {
    fn n_obs(&self) -> usize {
        self.t_s.len()
    }

    fn residuals(&self, x: &[f64; NP], r: &mut [f64], jac: Option<&mut [[f64; NP]]>) -> bool {
        let Some(m) = Prepared::new(x, self.groove) else {
            return false;
        };
        let mut finite = true;
        match jac {
            Some(jac) => {
                let n = self.t_s.len();
                m.eval_grad_many(self.t_s, self.t_ref_s, &mut r[..n], &mut jac[..n]);
                for (ri, &z) in r[..n].iter_mut().zip(self.z_m) {
                    *ri -= z;
                    finite &= ri.is_finite();
                }
            }
            None => {
                for ((ri, &t), &z) in r.iter_mut().zip(self.t_s).zip(self.z_m) {
                    *ri = m.eval(t, self.t_ref_s) - z;
                    finite &= ri.is_finite();
                }
            }
        }
        finite
    }
}
