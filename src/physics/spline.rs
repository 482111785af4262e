//! A smooth force given by a cubic B-spline in one variable (lab z, signed v, or time since the
//! kick): the nonparametric model of a missing acceleration that no named form explains.

use serde::{Deserialize, Serialize};

/// The variable a spline force depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Variable {
    /// Position in the lab (m).
    Z,
    /// Signed velocity (m/s).
    V,
    /// Time since the kick (s).
    T,
}

impl Variable {
    /// A short name with the unit.
    pub fn label(&self) -> &'static str {
        match self {
            Variable::Z => "z (m)",
            Variable::V => "v (m/s)",
            Variable::T => "t (s)",
        }
    }
}

/// `a(x) = Σ_j c_j B_j(x)` on uniform knots over `[lo_x, lo_x + segments·dx]`; outside that range
/// x is held at the nearest end (the force keeps its edge value).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplineForce {
    pub variable: Variable,
    pub lo_x: f64,
    pub dx: f64,
    /// One coefficient per basis function (m/s²): `segments + 3` of them.
    pub coefs_mps2: Vec<f64>,
}

/// The cardinal cubic B-spline on [0, 4).
fn b3(u: f64) -> f64 {
    if !(0.0..4.0).contains(&u) {
        0.0
    } else if u < 1.0 {
        u * u * u / 6.0
    } else if u < 2.0 {
        (-3.0 * u * u * u + 12.0 * u * u - 12.0 * u + 4.0) / 6.0
    } else if u < 3.0 {
        (3.0 * u * u * u - 24.0 * u * u + 60.0 * u - 44.0) / 6.0
    } else {
        let w = 4.0 - u;
        w * w * w / 6.0
    }
}

/// Number of basis functions for `segments` knot intervals.
pub fn n_basis(segments: usize) -> usize {
    segments + 3
}

/// Basis function `j` of a uniform cubic B-spline starting at `lo_x` with spacing `dx`, at `x`
/// clamped into `[lo_x, lo_x + segments·dx]`.
pub fn basis(lo_x: f64, dx: f64, segments: usize, j: usize, x: f64) -> f64 {
    let hi = lo_x + segments as f64 * dx;
    let u = (x.clamp(lo_x, hi) - lo_x) / dx;
    // at the upper end take the limit from the left
    let u = if u >= segments as f64 {
        segments as f64 - 1e-12
    } else {
        u
    };
    b3(u - j as f64 + 3.0)
}

impl SplineForce {
    pub fn segments(&self) -> usize {
        self.coefs_mps2.len().saturating_sub(3)
    }

    /// The spline's value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        let n = self.segments();
        if n == 0 {
            return 0.0;
        }
        let hi = self.lo_x + n as f64 * self.dx;
        let u = (x.clamp(self.lo_x, hi) - self.lo_x) / self.dx;
        let i = (u.floor() as usize).min(n - 1);
        // the four basis functions alive on knot interval i, at its fraction t: b3(t + 3 − k)
        // for k = 0..4 written out (this is the integrator's inner loop under a spline force)
        let t = u - i as f64;
        let (t2, s) = (t * t, 1.0 - t);
        let c = &self.coefs_mps2[i..i + 4];
        (c[0] * s * s * s
            + c[1] * (3.0 * t2 * t - 6.0 * t2 + 4.0)
            + c[2] * (-3.0 * t2 * t + 3.0 * t2 + 3.0 * t + 1.0)
            + c[3] * t2 * t)
            / 6.0
    }

    /// Acceleration at (z, v, t).
    pub fn accel(&self, z_m: f64, v_mps: f64, t_s: f64) -> f64 {
        self.at(match self.variable {
            Variable::Z => z_m,
            Variable::V => v_mps,
            Variable::T => t_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_sums_to_one_and_reproduces_a_line() {
        let segments = 7;
        for k in 0..=70 {
            let x = 0.1 + 0.02 * k as f64 * 0.5;
            let s: f64 = (0..n_basis(segments))
                .map(|j| basis(0.1, 0.01, segments, j, x))
                .sum();
            assert!((s - 1.0).abs() < 1e-12, "partition of unity at {x}: {s}");
        }
        // coefficients on a line reproduce the line (cubic B-splines reproduce polynomials ≤ 3)
        let sp = SplineForce {
            variable: Variable::Z,
            lo_x: 0.0,
            dx: 1.0,
            coefs_mps2: (0..10).map(|j| 2.0 + 0.5 * (j as f64 - 1.0)).collect(),
        };
        for x in [0.0, 1.3, 4.5, 6.99] {
            assert!(
                (sp.at(x) - (2.0 + 0.5 * x)).abs() < 1e-12,
                "at {x}: {}",
                sp.at(x)
            );
        }
        assert!((sp.at(-3.0) - 2.0).abs() < 1e-12, "held at the lower end");
    }

    #[test]
    fn the_written_out_sum_is_the_basis_sum() {
        let segments = 5;
        let coefs: Vec<f64> = (0..n_basis(segments))
            .map(|j| ((j * 7 + 3) % 11) as f64 - 4.5)
            .collect();
        let sp = SplineForce {
            variable: Variable::V,
            lo_x: -0.02,
            dx: 0.01,
            coefs_mps2: coefs.clone(),
        };
        for k in 0..=240 {
            // beyond both ends, on every knot and between them
            let x = -0.04 + 0.09 * k as f64 / 240.0;
            let by_basis: f64 = (0..coefs.len())
                .map(|j| coefs[j] * basis(-0.02, 0.01, segments, j, x))
                .sum();
            // `basis` takes the upper end 1e-12 of an interval inside it
            assert!(
                (sp.at(x) - by_basis).abs() < 1e-10,
                "at {x}: {} against {by_basis}",
                sp.at(x)
            );
        }
    }
}
