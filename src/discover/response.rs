//! Linear response of a fitted run to a small extra acceleration: how far each recorded position
//! would move if a force f(t) were added along the fitted trajectory.
//!
//! Along the fitted motion an extra acceleration f changes the velocity by `δv' = g(t)·(f + ∂a/∂v·δv)`
//! with gain g = 1 while sliding, ks²/(1 + ks²) while rolling and 0 at rest; at the switch from
//! sliding to rolling a velocity change moves the switch, which scales δv by
//! `1 + (v'_roll − v'_slide)/u'` (u the slip). Integrated on a grid of half a frame from the kick,
//! with the forcing integrated exactly over each step where it is known in closed form (periodic
//! forces in time). The force map and the spectral search regress the residuals on these
//! responses, with each run's z0, t0, v0 projected out; the named forms are then fitted exactly.

use super::data::RunData;
use super::sim::SimModel;
use crate::physics::{simulate, Phase, State, G_MPS2};

/// Grid points per frame (forcing known in closed form is integrated exactly within a step).
const SUB: f64 = 1.0;

/// The fitted motion of one run on a fine grid, with what the linear response needs.
pub struct Track {
    /// Grid step (s); grid times are `k·h` since the kick.
    pub h: f64,
    pub t: Vec<f64>,
    pub z: Vec<f64>,
    pub v: Vec<f64>,
    pub phase: Vec<Phase>,
    /// The acceleration friction gives at each grid point while sliding (0 elsewhere): the
    /// response of a relative change of μ is that of this force.
    pub friction: Vec<f64>,
    gain: Vec<f64>,
    damp: Vec<f64>,
    /// Factor applied to δv after step k (1 except at a slide → roll switch).
    jump: Vec<f64>,
    /// Kept samples: grid index below and the interpolation weight of the next point.
    at: Vec<(usize, f64)>,
    /// Weight 1/σ of the run.
    pub w: f64,
    /// Fitted velocity at each kept sample (the t0 column).
    v_sample: Vec<f64>,
}

impl Track {
    /// The motion of `run` under `model` from (z0, v0), kick `t0` before the first frame.
    pub fn new(model: &SimModel, z0_m: f64, t0_s: f64, v0_mps: f64, run: &RunData) -> Track {
        let fps = if run.fps > 0.0 { run.fps } else { 1e4 };
        let h = 1.0 / (SUB * fps);
        let t_last = run.t_s.last().copied().unwrap_or(0.0) + t0_s;
        let n = ((t_last / h).ceil() as usize + 2).max(3);
        let t: Vec<f64> = (0..n).map(|k| k as f64 * h).collect();
        let pm = model.to_physics();
        let init = State {
            z_m: z0_m,
            v_mps: v0_mps,
            va_mps: 0.0,
        };
        let tr = simulate(&pm, init, &t);
        let kappa = pm.groove.rolling_factor();
        let s = pm.groove.s;
        let gain: Vec<f64> = tr
            .phase
            .iter()
            .map(|p| match p {
                Phase::Sliding => 1.0,
                Phase::Rolling => kappa,
                Phase::Rest => 0.0,
            })
            .collect();
        let damp: Vec<f64> = (0..n)
            .map(|k| {
                let (z, v) = (tr.z_m[k], tr.v_mps[k]);
                if v == 0.0 || gain[k] == 0.0 {
                    return 0.0;
                }
                let e = 1e-6 * v.abs().max(1e-4);
                let d = (pm.accel(z, v + e, t[k]) - pm.accel(z, v - e, t[k])) / (2.0 * e);
                // a sign jump inside the difference is not a damping
                if (v + e).signum() != (v - e).signum() {
                    0.0
                } else {
                    gain[k] * d
                }
            })
            .collect();
        let friction: Vec<f64> = (0..n)
            .map(|k| match tr.phase[k] {
                Phase::Sliding => {
                    let slip = tr.v_mps[k] - s * tr.va_mps[k];
                    let dir = tr.v_mps[k].signum();
                    let mu = pm.friction.kinetic(slip) * pm.variation.factor(tr.z_m[k], dir, slip);
                    -slip.signum() * G_MPS2 * mu / s
                }
                _ => 0.0,
            })
            .collect();
        let mut jump = vec![1.0; n];
        for ev in &tr.events {
            if ev.from == Phase::Sliding && ev.to == Phase::Rolling {
                let k = ((ev.t_s / h).floor() as usize).min(n - 1);
                let before = k.saturating_sub(1);
                let d = (tr.v_mps[before] - s * tr.va_mps[before]).signum();
                let mu = pm.friction.static_limit();
                let a = pm.accel(ev.z_m, ev.v_mps, ev.t_s);
                let dv_slide = -d * G_MPS2 * mu / s + a;
                let dva_slide = d * pm.groove.k * G_MPS2 * mu;
                let du = dv_slide - s * dva_slide;
                if du.abs() > 1e-12 {
                    jump[k] = 1.0 + (kappa * a - dv_slide) / du;
                }
            }
        }
        let mut at = Vec::new();
        let mut v_sample = Vec::new();
        for (i, ts) in run.t_s.iter().enumerate() {
            if !run.keep[i] {
                continue;
            }
            let x = (ts + t0_s) / h;
            let k = (x.floor() as usize).min(n - 2);
            let f = (x - k as f64).clamp(0.0, 1.0);
            at.push((k, f));
            v_sample.push(tr.v_mps[k] * (1.0 - f) + tr.v_mps[k + 1] * f);
        }
        Track {
            h,
            t,
            z: tr.z_m,
            v: tr.v_mps,
            phase: tr.phase,
            friction,
            gain,
            damp,
            jump,
            at,
            w: 1.0 / run.sigma_m,
            v_sample,
        }
    }

    pub fn len(&self) -> usize {
        self.t.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Number of kept samples.
    pub fn n_samples(&self) -> usize {
        self.at.len()
    }

    /// δz at the kept samples for forcing integrals over each step: `f1[k] = ∫ f` and
    /// `f2[k] = ∫ (t_{k+1} − s) f(s) ds` over [t_k, t_{k+1}], plus an initial δv.
    pub fn respond(&self, f1: &[f64], f2: &[f64], dv0: f64) -> Vec<f64> {
        let n = self.t.len();
        let mut dz = vec![0.0; n];
        let mut dv = if self.gain[0] > 0.0 { dv0 } else { 0.0 };
        let h = self.h;
        for k in 0..n - 1 {
            let g = self.gain[k];
            let acc_free = self.damp[k] * dv;
            dz[k + 1] = dz[k] + h * dv + 0.5 * h * h * acc_free + g * f2[k];
            dv = (dv + h * acc_free + g * f1[k]) * self.jump[k];
            if self.gain[k + 1] == 0.0 {
                dv = 0.0;
            }
        }
        self.at
            .iter()
            .map(|&(k, f)| dz[k] * (1.0 - f) + dz[k + 1] * f)
            .collect()
    }

    /// `respond` for two forcings at once, each with no initial δv: the two recurrences are
    /// independent, so stepping them in one loop lets the second fill the first's wait on its
    /// previous step (the same arithmetic per forcing, so the same bits as two `respond` calls).
    pub fn respond_pair(
        &self,
        (f1a, f2a): (&[f64], &[f64]),
        (f1b, f2b): (&[f64], &[f64]),
    ) -> (Vec<f64>, Vec<f64>) {
        let n = self.t.len();
        let (mut za, mut zb) = (vec![0.0; n], vec![0.0; n]);
        let (mut va, mut vb) = (0.0f64, 0.0f64);
        let h = self.h;
        for k in 0..n - 1 {
            let g = self.gain[k];
            let (da, db) = (self.damp[k] * va, self.damp[k] * vb);
            za[k + 1] = za[k] + h * va + 0.5 * h * h * da + g * f2a[k];
            zb[k + 1] = zb[k] + h * vb + 0.5 * h * h * db + g * f2b[k];
            va = (va + h * da + g * f1a[k]) * self.jump[k];
            vb = (vb + h * db + g * f1b[k]) * self.jump[k];
            if self.gain[k + 1] == 0.0 {
                va = 0.0;
                vb = 0.0;
            }
        }
        let sample = |dz: &[f64]| -> Vec<f64> {
            self.at
                .iter()
                .map(|&(k, f)| dz[k] * (1.0 - f) + dz[k + 1] * f)
                .collect()
        };
        (sample(&za), sample(&zb))
    }

    /// Response to a force given by its values at the grid points (trapezoid within a step).
    pub fn respond_values(&self, f: &[f64]) -> Vec<f64> {
        let (f1, f2) = self.step_integrals(f);
        self.respond(&f1, &f2, 0.0)
    }

    /// `respond_values` for two forces at once (`respond_pair`).
    pub fn respond_values_pair(&self, fa: &[f64], fb: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (a1, a2) = self.step_integrals(fa);
        let (b1, b2) = self.step_integrals(fb);
        self.respond_pair((&a1, &a2), (&b1, &b2))
    }

    /// The forcing integrals over each step of a force given at the grid points (trapezoid).
    fn step_integrals(&self, f: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let h = self.h;
        let n = self.t.len();
        let mut f1 = vec![0.0; n];
        let mut f2 = vec![0.0; n];
        for k in 0..n - 1 {
            f1[k] = 0.5 * h * (f[k] + f[k + 1]);
            f2[k] = h * h * (2.0 * f[k] + f[k + 1]) / 6.0;
        }
        (f1, f2)
    }

    /// Responses to `sin(ω t)` and `cos(ω t)` (t since the kick), integrated exactly per step.
    pub fn respond_time(&self, omega: f64) -> (Vec<f64>, Vec<f64>) {
        let n = self.t.len();
        let (mut s1, mut s2, mut c1, mut c2) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let h = self.h;
        let (mut sa, mut ca) = (0.0f64, 1.0f64);
        // sin and cos on the uniform grid by rotation, re-anchored every 64 steps
        let (sh, chh) = (omega * h).sin_cos();
        // products with 1/ω and 1/ω² in place of divisions: four divisions a step were most
        // of this loop's time
        let (iw, iw2) = (1.0 / omega, 1.0 / (omega * omega));
        for k in 0..n - 1 {
            let (sb, cb) = if (k + 1) % 64 == 0 {
                (self.t[k + 1] * omega).sin_cos()
            } else {
                (sa * chh + ca * sh, ca * chh - sa * sh)
            };
            s1[k] = (ca - cb) * iw;
            s2[k] = h * ca * iw - (sb - sa) * iw2;
            c1[k] = (sb - sa) * iw;
            c2[k] = -h * sa * iw + (ca - cb) * iw2;
            sa = sb;
            ca = cb;
        }
        self.respond_pair((&s1, &s2), (&c1, &c2))
    }

    /// Values of a variable of the motion at the grid points: lab z, signed v, or t since the kick.
    pub fn variable(&self, var: crate::physics::Variable) -> &[f64] {
        match var {
            crate::physics::Variable::Z => &self.z,
            crate::physics::Variable::V => &self.v,
            crate::physics::Variable::T => &self.t,
        }
    }

    /// The columns of the run's own parameters at the kept samples: z0, t0, v0.
    pub fn local_columns(&self) -> [Vec<f64>; 3] {
        let n = self.t.len();
        let zero = vec![0.0; n];
        [
            vec![1.0; self.at.len()],
            self.v_sample.clone(),
            self.respond(&zero, &zero, 1.0),
        ]
    }
}

/// An orthonormal basis (in the weighted metric) of a run's local columns, to project them out.
pub struct Projector {
    q: Vec<Vec<f64>>,
}

impl Projector {
    /// Gram–Schmidt (twice) of the columns; near-dependent columns are dropped.
    pub fn new(cols: &[Vec<f64>]) -> Projector {
        let mut q: Vec<Vec<f64>> = Vec::new();
        for c in cols {
            let norm0 = dot(c, c).sqrt();
            if norm0 == 0.0 {
                continue;
            }
            let mut x = c.clone();
            for _ in 0..2 {
                for qi in &q {
                    let p = dot(qi, &x);
                    for (a, b) in x.iter_mut().zip(qi) {
                        *a -= p * b;
                    }
                }
            }
            let norm = dot(&x, &x).sqrt();
            if norm > 1e-9 * norm0 {
                x.iter_mut().for_each(|a| *a /= norm);
                q.push(x);
            }
        }
        Projector { q }
    }

    /// `x` with its components along the local columns removed, in place.
    pub fn apply(&self, x: &mut [f64]) {
        for qi in &self.q {
            let p = dot(qi, x);
            for (a, b) in x.iter_mut().zip(qi) {
                *a -= p * b;
            }
        }
    }
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A run ready for regression: its track, the projector of its locals, and its projected
/// residuals in units of its noise (kept samples only).
pub struct Prepared {
    pub track: Track,
    pub proj: Projector,
    /// Residual / σ with the locals projected out.
    pub y: Vec<f64>,
    /// Columns of the shared parameters (finite differences of the integrator), same units,
    /// with the locals projected out; one per global parameter (zero where it does not act).
    pub glob: Vec<Vec<f64>>,
    pub run: usize,
}

impl Prepared {
    /// A response in units of the noise with the locals projected out.
    pub fn column(&self, mut r: Vec<f64>) -> Vec<f64> {
        r.iter_mut().for_each(|x| *x *= self.track.w);
        self.proj.apply(&mut r);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::Term;

    fn run_of(t: &[f64]) -> RunData {
        RunData {
            run: "r".into(),
            material: 0,
            fps: 1e4,
            t_s: t.to_vec(),
            z_m: vec![0.0; t.len()],
            keep: vec![true; t.len()],
            sigma_m: 1e-6,
            fast: Default::default(),
            scale: Vec::new(),
            slow: Default::default(),
        }
    }

    fn base() -> SimModel {
        SimModel::baseline((70.6f64.to_radians() / 2.0).sin(), 2.5, 0.3, 0.05)
    }

    /// The linear response agrees with finite differences of the integrator within a few %.
    #[test]
    fn response_matches_the_integrator() {
        let t: Vec<f64> = (0..500).map(|k| 0.3e-4 + k as f64 * 1e-4).collect();
        let run = run_of(&t);
        for v0 in [0.04, -0.02] {
            let m = base();
            let track = Track::new(&m, 1e-3, 0.3e-4, v0, &run);
            let tt: Vec<f64> = t.iter().map(|x| x + 0.3e-4).collect();
            let sim = |m: &SimModel| {
                let mut z = vec![0.0; t.len()];
                m.simulate(1e-3, v0, &tt, &mut z, None, None);
                z
            };
            let z0 = sim(&m);
            let eps = 0.01;
            // a time-periodic force
            let omega = std::f64::consts::TAU * 180.0;
            let mut mt = base();
            mt.terms.push(Term::TimePeriodicForce {
                amp_mps2: eps,
                freq_hz: 180.0,
                phase_rad: 0.0,
            });
            let fd: Vec<f64> = sim(&mt)
                .iter()
                .zip(&z0)
                .map(|(a, b)| (a - b) / eps)
                .collect();
            let (rs, _) = track.respond_time(omega);
            let scale = fd.iter().map(|x| x.abs()).fold(0.0, f64::max);
            let err = fd
                .iter()
                .zip(&rs)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                err < 0.05 * scale,
                "v0 {v0}: time force err {err} of {scale}"
            );
            // a localized force in z
            let mut ml = base();
            ml.terms.push(Term::LocalizedForce {
                amp_mps2: eps,
                centre_m: 1e-3 + v0.signum() * 4e-4,
                width_m: 2e-4,
            });
            let fd: Vec<f64> = sim(&ml)
                .iter()
                .zip(&z0)
                .map(|(a, b)| (a - b) / eps)
                .collect();
            let f: Vec<f64> = track
                .z
                .iter()
                .map(|z| {
                    let u = (z - (1e-3 + v0.signum() * 4e-4)) / 2e-4;
                    (-0.5 * u * u).exp()
                })
                .collect();
            let r = track.respond_values(&f);
            let scale = fd.iter().map(|x| x.abs()).fold(0.0, f64::max);
            let err = fd
                .iter()
                .zip(&r)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 0.05 * scale, "v0 {v0}: bump err {err} of {scale}");
            // the v0 column
            let dv = 1e-6;
            let mut z1 = vec![0.0; t.len()];
            m.simulate(1e-3, v0 + dv, &tt, &mut z1, None, None);
            let fd: Vec<f64> = z1.iter().zip(&z0).map(|(a, b)| (a - b) / dv).collect();
            let col = &track.local_columns()[2];
            let scale = fd.iter().map(|x| x.abs()).fold(0.0, f64::max);
            let err = fd
                .iter()
                .zip(col)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                err < 0.03 * scale,
                "v0 {v0}: v0 column err {err} of {scale}"
            );
        }
    }
}
