//! The fitted model trajectory of a collision run, for figures (the chapter's Fig. 4.3c–d):
//! position of either particle at any time from its segment's start state and drag time.

use super::types::{CollisionFit, PhaseKind};
use crate::physics::{Baseline, Groove};

impl CollisionFit {
    /// Fitted position (m, lab frame) of `particle` (0 striker, 1 target) at `t_s`, on `groove`
    /// (the one the run was fitted with). None outside the fitted time range or without a fit.
    pub fn position_m(&self, particle: u32, t_s: f64, groove: Groove) -> Option<f64> {
        let segs: Vec<_> = self
            .segments
            .iter()
            .filter(|s| s.particle == particle)
            .collect();
        let seg = segs.iter().rev().find(|s| s.t_start_s <= t_s)?;
        if t_s > seg.t_end_s + 1e-12 {
            return None;
        }
        if seg
            .phases
            .first()
            .is_some_and(|p| p.phase == PhaseKind::Rest)
        {
            return Some(seg.z_start_m);
        }
        let baseline = Baseline {
            mu: self.mu_pg.value,
            t_drag_s: seg.t_drag_s.value,
            groove,
        };
        let (dz, _, _, _) = baseline.state_from(
            seg.v_start_mps.value,
            seg.va_start_mps.value,
            t_s - seg.t_start_s,
        );
        Some(seg.z_start_m + dz).filter(|z| z.is_finite())
    }
}
