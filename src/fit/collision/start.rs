//! Starting plans of the joint fit: the contact setup's kick, the striker's approach alone, and
//! the rolling setup's first impact seeded from a pre-fit of the approach and the impulse model.

use super::detect::{index_at, median, robust_line};
use super::fit::Fitter;
use super::impulse::after_impact;
use super::model::{Layout, TrackData};
use super::plan::{After, FirstPiece, Plan, PlanImpact};

impl Fitter<'_> {
    /// Contact setup: both particles start moving at the kick (fixed half a frame before the
    /// first frame) without spin: the resting pair sticks, so the impact changes no spin, and v_a
    /// is held at 0 (a brief slide cannot tell v' from v_a' at 1 µm noise; friction builds up
    /// at most k g μ · ½ frame ≈ 0.4 mm/s of spin within the timing uncertainty).
    pub(super) fn contact_plan(&self, t_kick_s: f64) -> Plan {
        let start = |tr: &TrackData| {
            let hi = tr.t_s.len().min(8);
            robust_line(tr, 0, hi, t_kick_s).unwrap_or((0.0, tr.z_m[0]))
        };
        let (v1, z1) = start(&self.tracks[0]);
        let (v2, z2) = start(&self.tracks[1]);
        Plan {
            mu: self.opts.mu_start,
            t_drag_s: self.opts.t_drag_start_s,
            hold_friction: false,
            drag_per_piece: self.opts.drag_per_piece,
            piece_t_drag_s: [Vec::new(), Vec::new()],
            noise_m: self.sigma,
            z_start_m: [z1, z2],
            first: [None, None],
            impacts: vec![PlanImpact {
                t_s: t_kick_s,
                fixed: true,
                lower_s: t_kick_s,
                upper_s: t_kick_s,
                after: After::Kicked {
                    v_mps: [v1, v2],
                    va_mps: [0.0, 0.0],
                    va_max_mps: 0.0,
                },
            }],
        }
    }

    /// The striker's approach alone, target at rest (also the plan of a run without impact).
    pub(super) fn approach_plan(&self) -> Plan {
        let [st, tg] = &self.tracks;
        let (v, z) = robust_line(st, 0, st.t_s.len().min(8), st.t_s[0]).unwrap_or((0.0, st.z_m[0]));
        let mut head: Vec<f64> = tg.z_m[..tg.z_m.len().min(15)].to_vec();
        Plan {
            mu: self.opts.mu_start,
            t_drag_s: self.opts.t_drag_start_s,
            hold_friction: false,
            drag_per_piece: self.opts.drag_per_piece,
            piece_t_drag_s: [Vec::new(), Vec::new()],
            noise_m: self.sigma,
            z_start_m: [z, median(&mut head)],
            first: [
                Some(FirstPiece::Kicked {
                    t0_s: st.t_s[0],
                    v_mps: v,
                    va_mps: 0.0,
                    va_max_mps: self.va_max(v),
                }),
                Some(FirstPiece::Rest { t0_s: tg.t_s[0] }),
            ],
            impacts: Vec::new(),
        }
    }

    /// Rolling setup: pre-fit the approach up to the departure, then seed the impact.
    pub(super) fn rolling_plan(&self, t_dep_s: f64) -> Plan {
        let cut = |tr: &TrackData| {
            let n = index_at(tr, t_dep_s - self.frame_s);
            TrackData {
                t_s: tr.t_s[..n].to_vec(),
                z_m: tr.z_m[..n].to_vec(),
            }
        };
        let before = [cut(&self.tracks[0]), cut(&self.tracks[1])];
        let mut plan = self.approach_plan();
        if before[0].t_s.len() >= 8 && before[1].t_s.len() >= 3 {
            // μ and T are held: a few ms of sliding cannot tell friction from drag
            plan.hold_friction = true;
            let (layout, res) = self.solve(&plan, &before);
            plan = plan.from_solution(&layout, &res.params);
            plan.hold_friction = false;
        }
        let (layout, _) = plan.build(self.tracks.clone(), self.opts.s, self.opts.k);
        let p0 = layout_params(&plan, &layout);
        let (_, v1, va1) = layout.state_at(&p0, 0, t_dep_s);
        let tg = &self.tracks[1];
        let i = index_at(tg, t_dep_s);
        let v2 = robust_line(tg, i, (i + 6).min(tg.t_s.len()), t_dep_s)
            .map(|l| l.0)
            .unwrap_or(v1);
        let c_guess = ((v2 - (v1 - v2)) / v1.max(1e-6)).clamp(0.0, 1.0);
        let (after, _) = after_impact(
            [(v1, va1), (0.0, 0.0)],
            c_guess,
            self.opts.mu_pp_start,
            self.opts.k,
        );
        plan.impacts.push(PlanImpact {
            t_s: t_dep_s,
            fixed: false,
            lower_s: t_dep_s,
            upper_s: t_dep_s,
            after: After::Impulse {
                j_mps: v2,
                w_mps: after[1].1,
            },
        });
        plan
    }
}

/// The start values of a plan as a parameter vector of its layout.
fn layout_params(plan: &Plan, layout: &Layout) -> Vec<f64> {
    let (_, specs) = plan.build(layout.tracks.clone(), layout.s, layout.k);
    specs.iter().map(|s| s.start).collect()
}
