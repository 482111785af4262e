//! Two particles in one groove: the contact impulse with restitution and μ_pp, and a force
//! between them that depends on their separation.

use super::events::Particle;
use super::model::Physics;
use super::run::Fine;

/// What the collision model needs besides each particle's physics.
#[derive(Clone, Debug)]
pub struct PairModel {
    /// Particle radius (contact at 2R).
    pub radius_m: f64,
    /// Particle–particle friction.
    pub mu_pp: f64,
    /// Restitution C(v) = c0 + (1 − c0) exp(−v/v_ref), v the approach speed.
    pub c0: f64,
    pub v_ref_mps: f64,
    /// A force between the two, on each along the line of centres, pushing apart when > 0.
    pub force: Option<Between>,
    /// A restitution law other than the saturating one above (None: that one).
    pub law: Option<Law>,
    /// μ_pp falls with the slip speed u at the contact as μ_pp/(1 + u/u0) (None: constant).
    pub mu_pp_weakening_mps: Option<f64>,
}

/// Restitution laws outside the saturating one, in this simulator's own forms.
#[derive(Clone, Copy, Debug)]
pub enum Law {
    /// Viscoelastic spheres to second order in v^(1/5): `1 − a v^0.2 + 0.6 a² v^0.4`.
    Viscoelastic { a: f64 },
    /// Adhesion at low speed and yield at high: `c (1 − e^{−(v/v_a)²}) e^{−v/v_p}`.
    Humped { c: f64, v_a: f64, v_p: f64 },
    /// Sticking below a speed: `c (1 − e^{−(v − v_s)/w})` above `v_s`, a floor of 0.05 below.
    Sticky { c: f64, v_s: f64, w: f64 },
}

impl Law {
    pub fn at(&self, v: f64) -> f64 {
        let v = v.abs();
        match *self {
            Law::Viscoelastic { a } => 1.0 - a * v.powf(0.2) + 0.6 * a * a * v.powf(0.4),
            Law::Humped { c, v_a, v_p } => {
                c * (1.0 - (-(v / v_a).powi(2)).exp()) * (-v / v_p).exp()
            }
            Law::Sticky { c, v_s, w } => (c * (1.0 - (-(v - v_s).max(0.0) / w).exp())).max(0.05),
        }
    }
}

/// Shapes of a force between the two particles in their gap s (surface to surface).
#[derive(Clone, Copy, Debug)]
pub enum Between {
    /// `amp e^{−s/range}` (m/s², m).
    Screened { amp: f64, range: f64 },
    /// `amp (d/(d + s))^p`: a softened inverse power.
    InversePower { amp: f64, d: f64, p: f64 },
    /// A liquid bridge: `amp (1 − s/rupture)` until it ruptures at `rupture`, nothing beyond.
    Bridge { amp: f64, rupture: f64 },
}

impl Between {
    pub fn at(&self, gap: f64) -> f64 {
        let s = gap.max(0.0);
        match *self {
            Between::Screened { amp, range } => amp * (-s / range).exp(),
            Between::InversePower { amp, d, p } => amp * (d / (d + s)).powf(p),
            Between::Bridge { amp, rupture } => {
                if s < rupture {
                    amp * (1.0 - s / rupture)
                } else {
                    0.0
                }
            }
        }
    }

    /// The work per unit mass over the whole range, ∫₀^∞ a ds (by quadrature: this simulator
    /// keeps no closed forms of the fitting code's).
    pub fn work(&self) -> f64 {
        let (mut sum, mut prev) = (0.0, (0.0, self.at(0.0)));
        for k in 1..=200_000 {
            let s = 1e-8 * 1e7f64.powf(k as f64 / 200_000.0);
            let a = self.at(s);
            sum += 0.5 * (a + prev.1) * (s - prev.0);
            prev = (s, a);
        }
        sum
    }
}

impl PairModel {
    pub fn restitution(&self, v: f64) -> f64 {
        match self.law {
            Some(l) => l.at(v),
            None => self.c0 + (1.0 - self.c0) * (-v.abs() / self.v_ref_mps).exp(),
        }
    }

    /// μ_pp at slip speed `u` (m/s) at the contact.
    pub fn mu_pp_at(&self, u: f64) -> f64 {
        match self.mu_pp_weakening_mps {
            Some(u0) => self.mu_pp / (1.0 + u.abs() / u0),
            None => self.mu_pp,
        }
    }
}

/// One collision: the time and the velocities and spins just before and after.
#[derive(Clone, Copy, Debug)]
pub struct Impact {
    pub t_s: f64,
    pub before: [(f64, f64); 2],
    pub after: [(f64, f64); 2],
}

/// The impulse between `a` (behind, moving towards `b`) and `b`, along `n` = sign(z_b − z_a).
pub fn impulse(m: &PairModel, a: &mut Particle, b: &mut Particle, n: f64) {
    let (v1, v2) = (n * a.x.v, n * b.x.v);
    let (w1, w2) = (n * a.x.va, n * b.x.va);
    let j = 0.5 * (1.0 + m.restitution(v1 - v2)) * (v1 - v2);
    let (v1n, v2n) = (v1 - j, v2 + j);
    let sum = w1 + w2;
    let mu = m.mu_pp_at(sum);
    let (w1n, w2n) = if sum.abs() >= 2.0 * mu * 2.5 * j {
        let dw = sum.signum() * mu * 2.5 * j;
        (w1 - dw, w2 - dw)
    } else {
        (0.5 * (w1 - w2), 0.5 * (w2 - w1))
    };
    a.x.v = n * v1n;
    b.x.v = n * v2n;
    a.x.va = n * w1n;
    b.x.va = n * w2n;
}

/// Particle 0 (the striker, kicked to `v0`) and particle 1 (the target, at rest), for
/// `duration_s`; returns both fine trajectories and the impacts.
pub fn simulate_pair(
    p: [&Physics; 2],
    m: &PairModel,
    z0: [f64; 2],
    v0: f64,
    duration_s: f64,
    dt: f64,
) -> ([Fine; 2], Vec<Impact>) {
    let mut parts = [Particle::kicked(z0[0], v0), Particle::kicked(z0[1], 0.0)];
    let n = (z0[1] - z0[0]).signum();
    let ext = |parts: &[Particle; 2]| -> [f64; 2] {
        match m.force {
            Some(b) => {
                let gap = n * (parts[1].x.z - parts[0].x.z) - 2.0 * m.radius_m;
                let f = b.at(gap);
                [-n * f, n * f]
            }
            None => [0.0, 0.0],
        }
    };
    let e = ext(&parts);
    parts[0].settle(p[0], 0.0, e[0]);
    parts[1].settle(p[1], 0.0, e[1]);
    let mut fine = [
        Fine {
            dt,
            ..Fine::default()
        },
        Fine {
            dt,
            ..Fine::default()
        },
    ];
    let mut impacts = Vec::new();
    let gap = |q: &[Particle; 2]| n * (q[1].x.z - q[0].x.z) - 2.0 * m.radius_m;
    let closing = |q: &[Particle; 2]| n * (q[0].x.v - q[1].x.v) > 0.0;
    let collide = |q: &mut [Particle; 2], t: f64, e: [f64; 2], impacts: &mut Vec<Impact>| {
        let before = [(q[0].x.v, q[0].x.va), (q[1].x.v, q[1].x.va)];
        let [a, b] = &mut *q;
        impulse(m, a, b, n);
        q[0].settle(p[0], t, e[0]);
        q[1].settle(p[1], t, e[1]);
        impacts.push(Impact {
            t_s: t,
            before,
            after: [(q[0].x.v, q[0].x.va), (q[1].x.v, q[1].x.va)],
        });
    };
    if gap(&parts) <= 0.0 && closing(&parts) {
        collide(&mut parts, 0.0, e, &mut impacts);
    }
    for (f, q) in fine.iter_mut().zip(&parts) {
        f.push(q, 0.0);
    }
    let steps = (duration_s / dt).ceil() as usize + 1;
    for i in 0..steps {
        let t = i as f64 * dt;
        let e = ext(&parts);
        let start = parts;
        let step = |h: f64| {
            let mut q = start;
            q[0].advance(p[0], t, h, e[0]);
            q[1].advance(p[1], t, h, e[1]);
            q
        };
        let q = step(dt);
        if gap(&q) <= 0.0 && closing(&q) && gap(&start) > 0.0 {
            let (mut lo, mut hi) = (0.0, dt);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if gap(&step(mid)) <= 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            parts = step(hi);
            collide(&mut parts, t + hi, e, &mut impacts);
            parts[0].advance(p[0], t + hi, dt - hi, e[0]);
            parts[1].advance(p[1], t + hi, dt - hi, e[1]);
        } else {
            parts = q;
            if gap(&parts) <= 0.0 && closing(&parts) {
                collide(&mut parts, t + dt, e, &mut impacts);
            }
        }
        for (f, q) in fine.iter_mut().zip(&parts) {
            f.push(q, t + dt);
        }
    }
    (fine, impacts)
}
