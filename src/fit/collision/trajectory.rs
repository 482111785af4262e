//! The fitted model trajectory of a collision run: position, velocity and phase of either
//! particle at any time, from its piece's start state and drag time. The one evaluation of a
//! fitted collision run, used by the figures (the chapter's Fig. 4.3c–d) and the residuals.

use crate::artifacts::collision_fit::CollisionFit;
use crate::physics::{Baseline, Groove, Phase};

/// The fitted state of one particle at an instant (lab frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedState {
    pub z_m: f64,
    pub v_mps: f64,
    pub phase: Phase,
}

impl CollisionFit {
    /// Fitted state of `particle` (0 striker, 1 target) at `t_s` on `groove` (the one the run
    /// was fitted with), from the first piece whose span holds `t_s` (at an impact time the
    /// piece that ends there; a resting piece has zero start velocity and spin, so it stays
    /// put). None outside every fitted piece.
    pub fn state_at(&self, particle: u32, t_s: f64, groove: Groove) -> Option<FittedState> {
        let seg = self
            .segments
            .iter()
            .find(|s| s.particle == particle && s.t_start_s <= t_s && t_s <= s.t_end_s)?;
        let baseline = Baseline {
            mu: self.mu_pg.value,
            t_drag_s: seg.t_drag_s.value,
            groove,
        };
        let (dz, v, _, phase) = baseline.state_from(
            seg.v_start_mps.value,
            seg.va_start_mps.value,
            t_s - seg.t_start_s,
        );
        Some(FittedState {
            z_m: seg.z_start_m + dz,
            v_mps: v,
            phase,
        })
    }

    /// Fitted position (m, lab frame) of `particle` at `t_s` (see [`CollisionFit::state_at`]);
    /// None outside the fitted pieces, without a fit, or where the model is not finite.
    pub fn position_m(&self, particle: u32, t_s: f64, groove: Groove) -> Option<f64> {
        self.state_at(particle, t_s, groove)
            .map(|s| s.z_m)
            .filter(|z| z.is_finite())
    }
}
