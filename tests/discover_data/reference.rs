//! An independent fixed-step RK4 integrator of the discovery models with located switches,
//! following the physics module's docs (src/physics): sliding while v ≠ s·v_a, constrained rolling (dv/dt = ks²/(1+ks²)·a)
//! while the friction needed stays ≤ gμ, rest when a resistance opposing motion holds the
//! particle. A reference the tests hold `physics::simulate` to (they agree within 1 nm for every
//! candidate term); no analysis uses it.

use groove::discover::sim::{Drag, Motion, SimModel};
use groove::discover::G_MPS2;

#[derive(Clone, Copy, Debug)]
struct St {
    z: f64,
    v: f64,
    va: f64,
}

/// Largest integration step while sliding (short, fast-changing phase) and while rolling.
const H_SLIDE_S: f64 = 2.0e-5;
const H_ROLL_S: f64 = 1.0e-4;
/// Slip speed below which sliding has ended (needed when μ → 0 with the slip).
const SLIP_EPS_MPS: f64 = 1.0e-9;

/// The reference integrator for one model (reads the model's fields through `Deref`).
pub struct Reference<'a>(pub &'a SimModel);

impl std::ops::Deref for Reference<'_> {
    type Target = SimModel;
    fn deref(&self) -> &SimModel {
        self.0
    }
}

impl Reference<'_> {
    fn ks2(&self) -> f64 {
        self.k * self.s * self.s
    }

    /// Non-dissipative acceleration: tilt and position-dependent force.
    fn conservative(&self, z: f64) -> f64 {
        let mut a = self.tilt_mps2;
        for &(amp, kz, ph) in &self.position {
            a += amp * (kz * z + ph).sin();
        }
        a
    }

    /// Every acceleration along z except groove friction.
    fn accel(&self, z: f64, v: f64) -> f64 {
        let drag = match self.drag {
            Drag::Quadratic { t_s, c_per_m } => -v / t_s - c_per_m * v * v.abs(),
            Drag::Saturating { t0_s, tp_s_per_mps } => -v / (t0_s + tp_s_per_mps * v.abs()),
        };
        let roll = if v != 0.0 {
            -self.roll_c * G_MPS2 * v.signum()
        } else {
            0.0
        };
        drag + roll + self.conservative(z)
    }

    fn mu_at(&self, slip: f64) -> f64 {
        match self.vc_mps {
            None => self.mu,
            Some(vc) => self.mu * (1.0 - (-slip.abs() / vc).exp()),
        }
    }

    fn deriv_slide(&self, x: St, d: f64) -> (f64, f64, f64) {
        let mu = self.mu_at(x.v - self.s * x.va);
        let dv = -d * G_MPS2 * mu / self.s + self.accel(x.z, x.v);
        let dva = d * self.k * G_MPS2 * mu;
        (x.v, dv, dva)
    }

    fn deriv_roll(&self, x: St) -> (f64, f64, f64) {
        let f = self.ks2() / (1.0 + self.ks2());
        let dv = f * self.accel(x.z, x.v);
        (x.v, dv, dv / self.s)
    }

    fn rk4(&self, x: St, h: f64, motion: Motion, d: f64) -> St {
        let f = |y: St| match motion {
            Motion::Sliding => self.deriv_slide(y, d),
            _ => self.deriv_roll(y),
        };
        let add = |y: St, k: (f64, f64, f64), c: f64| St {
            z: y.z + c * k.0,
            v: y.v + c * k.1,
            va: y.va + c * k.2,
        };
        let k1 = f(x);
        let k2 = f(add(x, k1, h / 2.0));
        let k3 = f(add(x, k2, h / 2.0));
        let k4 = f(add(x, k3, h));
        St {
            z: x.z + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            v: x.v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
            va: x.va + h / 6.0 * (k1.2 + 2.0 * k2.2 + 2.0 * k3.2 + k4.2),
        }
    }

    /// Fraction f in (0, 1] of a step of size h at which `g(state)` crosses zero (g(x) ≠ 0 at f = 0),
    /// by the Illinois variant of regula falsi on RK4 sub-steps from `x`.
    fn locate(&self, x: St, h: f64, motion: Motion, d: f64, g: impl Fn(St) -> f64) -> (f64, St) {
        let (mut a, mut ga) = (0.0, g(x));
        let end = self.rk4(x, h, motion, d);
        let (mut b, mut gb) = (1.0, g(end));
        let mut best = (1.0, end);
        let mut side = 0i8;
        for _ in 0..40 {
            let c = if (gb - ga).abs() > 0.0 {
                (a * gb - b * ga) / (gb - ga)
            } else {
                0.5 * (a + b)
            };
            let c = if c > a && c <= b { c } else { 0.5 * (a + b) };
            let xc = self.rk4(x, c * h, motion, d);
            let gc = g(xc);
            best = (c, xc);
            if (b - a) * h < 1e-13 || gc == 0.0 {
                break;
            }
            if gc.signum() == ga.signum() {
                a = c;
                ga = gc;
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            } else {
                b = c;
                gb = gc;
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            }
        }
        best
    }

    /// The same trajectory by an independent fixed-step RK4 with located switches: a reference the
    /// tests hold `physics::simulate` to (they agree within 1 nm for every candidate term).
    pub fn simulate_reference(
        &self,
        z0_m: f64,
        v0_mps: f64,
        t_s: &[f64],
        z_out: &mut [f64],
        mut v_out: Option<&mut [f64]>,
        mut phase_out: Option<&mut [Motion]>,
    ) {
        let mut x = St {
            z: z0_m,
            v: v0_mps,
            va: 0.0,
        };
        let mut t = 0.0;
        let mut motion = if v0_mps == 0.0 {
            Motion::Rest
        } else {
            Motion::Sliding
        };
        if motion == Motion::Rest && self.conservative(z0_m).abs() > self.roll_c * G_MPS2 {
            motion = Motion::Rolling;
        }
        let mut d = (x.v - self.s * x.va).signum();
        for (i, &target) in t_s.iter().enumerate() {
            let mut guard = 0usize;
            while t < target && guard < 10_000_000 {
                guard += 1;
                if motion == Motion::Rest {
                    t = target;
                    break;
                }
                let hmax = if motion == Motion::Sliding {
                    H_SLIDE_S
                } else {
                    H_ROLL_S
                };
                let h = hmax.min(target - t);
                let next = self.rk4(x, h, motion, d);
                match motion {
                    Motion::Sliding => {
                        let slip = next.v - self.s * next.va;
                        if slip * d <= 0.0 || slip.abs() < SLIP_EPS_MPS {
                            let (f, xs) = if slip * d < 0.0 {
                                self.locate(x, h, motion, d, |y| y.v - self.s * y.va)
                            } else {
                                (1.0, next)
                            };
                            x = St {
                                z: xs.z,
                                v: xs.v,
                                va: xs.v / self.s,
                            };
                            t += f * h;
                            motion = Motion::Rolling;
                            continue;
                        }
                        x = next;
                        t += h;
                    }
                    Motion::Rolling => {
                        // a resistance opposing motion stops the particle in finite time: the
                        // stop lies in this step when the current deceleration reaches v = 0
                        // (RK4 stages straddling the sign change would stall just short of it)
                        let dv = self.deriv_roll(x).1;
                        let tau = if dv * x.v < 0.0 {
                            -x.v / dv
                        } else {
                            f64::INFINITY
                        };
                        if self.roll_c > 0.0 && (tau <= h || next.v * x.v < 0.0) {
                            let tau = tau.min(h);
                            let xs = self.rk4(x, tau, motion, d);
                            t += tau;
                            x = St {
                                z: xs.z,
                                v: 0.0,
                                va: 0.0,
                            };
                            if self.conservative(x.z).abs() <= self.roll_c * G_MPS2 {
                                motion = Motion::Rest;
                            } else {
                                // pushed on: restart from rest in the direction of the push
                                x.v = 1e-12 * self.conservative(x.z).signum();
                            }
                            continue;
                        }
                        x = next;
                        t += h;
                        // the friction needed to keep rolling: |s·a/(1+ks²)| ≤ gμ, else slip again
                        let a = self.accel(x.z, x.v);
                        let need = (self.s * a / (1.0 + self.ks2())).abs();
                        if need > G_MPS2 * self.mu {
                            motion = Motion::Sliding;
                            d = a.signum();
                        }
                    }
                    Motion::Rest => {}
                }
            }
            z_out[i] = x.z;
            if let Some(v) = v_out.as_deref_mut() {
                v[i] = x.v;
            }
            if let Some(p) = phase_out.as_deref_mut() {
                p[i] = motion;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chapter(mu: f64, t_s: f64) -> SimModel {
        SimModel {
            s: (70.6f64.to_radians() / 2.0).sin(),
            k: 2.5,
            mu,
            vc_mps: None,
            drag: Drag::Quadratic { t_s, c_per_m: 0.0 },
            roll_c: 0.0,
            tilt_mps2: 0.0,
            position: vec![],
            terms: vec![],
            phased_term: None,
            variation: Default::default(),
            distortion: None,
        }
    }

    /// Closed form of the physics module's docs for the baseline, sliding then rolling, v0 > 0.
    fn closed_form(m: &SimModel, v0: f64, t: f64) -> f64 {
        let Drag::Quadratic { t_s: tt, .. } = m.drag else {
            unreachable!()
        };
        let a = G_MPS2 * m.mu * tt / m.s;
        let slide_v = |t: f64| (v0 + a) * (-t / tt).exp() - a;
        let slide_z = |t: f64| tt * (v0 + a) * (1.0 - (-t / tt).exp()) - a * t;
        let gap = |t: f64| slide_v(t) - m.s * m.k * G_MPS2 * m.mu * t;
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if gap(mid) > 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let t1 = 0.5 * (lo + hi);
        if t <= t1 {
            return slide_z(t);
        }
        let ks2 = Reference(m).ks2();
        let te = tt * (1.0 + ks2) / ks2;
        slide_z(t1) + slide_v(t1) * te * (1.0 - (-(t - t1) / te).exp())
    }

    #[test]
    fn integrator_matches_closed_form_both_directions() {
        let m = chapter(0.337, 0.06);
        let t: Vec<f64> = (0..600).map(|i| i as f64 * 1e-4 + 3e-5).collect();
        for v0 in [0.08, -0.08, 0.01] {
            let mut z = vec![0.0; t.len()];
            Reference(&m).simulate_reference(0.0, v0, &t, &mut z, None, None);
            for (ti, zi) in t.iter().zip(&z) {
                let want = v0.signum() * closed_form(&m, v0.abs(), *ti);
                assert!((zi - want).abs() < 1e-9, "t {ti} z {zi} want {want}");
            }
        }
    }

    #[test]
    fn rolling_resistance_brings_the_particle_to_rest() {
        let mut m = chapter(0.3, 10.0);
        m.roll_c = 0.01;
        let t: Vec<f64> = (0..400).map(|i| i as f64 * 1e-3).collect();
        let mut z = vec![0.0; t.len()];
        let mut ph = vec![Motion::Sliding; t.len()];
        Reference(&m).simulate_reference(0.0, -0.02, &t, &mut z, None, Some(&mut ph));
        assert_eq!(*ph.last().unwrap(), Motion::Rest);
        // rolling decelerates at ks²/(1+ks²)·c·g; the stop is reached and z stays put
        assert_eq!(z[398], z[399]);
        assert!(z[399] < 0.0);
    }
}
