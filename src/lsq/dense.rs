//! The dense back-end: Cholesky factor, solve and inverse of small symmetric positive-definite
//! systems stored row-major (n×n in one slice), and the normal equations of a Jacobian stored by
//! columns; an orthonormal basis of a few columns and the projection off it. A matrix that is
//! not positive definite gives `None`; nothing here invents a factor.

/// An orthonormal basis of `cols` (Gram–Schmidt, twice): a column that is zero, or within 1e-9
/// of its norm in the span of those before it, adds nothing.
pub fn orthonormal_basis(cols: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut q: Vec<Vec<f64>> = Vec::new();
    for mut x in cols {
        let norm0 = dot(&x, &x).sqrt();
        if !(norm0 > 0.0) {
            continue;
        }
        for _ in 0..2 {
            for qi in &q {
                let p = dot(qi, &x);
                x.iter_mut().zip(qi).for_each(|(a, b)| *a -= p * b);
            }
        }
        let norm = dot(&x, &x).sqrt();
        if norm > 1e-9 * norm0 {
            x.iter_mut().for_each(|a| *a /= norm);
            q.push(x);
        }
    }
    q
}

/// `x` with its components along the orthonormal `basis` removed.
pub fn project_out(basis: &[Vec<f64>], x: &mut [f64]) {
    for qi in basis {
        let p: f64 = qi.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
        x.iter_mut().zip(qi).for_each(|(a, b)| *a -= p * b);
    }
}

/// Cholesky factor L (lower, row-major) of a symmetric positive-definite matrix, or None.
pub fn cholesky(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            if i == j {
                let d = a[i * n + i] - s;
                if !(d > 0.0) || !d.is_finite() {
                    return None;
                }
                l[i * n + i] = d.sqrt();
            } else {
                l[i * n + j] = (a[i * n + j] - s) / l[j * n + j];
            }
        }
    }
    Some(l)
}

/// Solve L Lᵀ x = b in place.
pub fn chol_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i * n + k] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * n + i];
    }
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * n + i];
    }
}

/// Solve A x = b for a symmetric positive-definite A; None when A is not positive definite.
pub fn solve_spd(a: &[f64], n: usize, b: &[f64]) -> Option<Vec<f64>> {
    let l = cholesky(a, n)?;
    let mut x = b.to_vec();
    chol_solve(&l, n, &mut x);
    Some(x)
}

/// Inverse of a symmetric positive-definite matrix from its Cholesky factor.
pub fn chol_inverse(l: &[f64], n: usize) -> Vec<f64> {
    let mut inv = vec![0.0; n * n];
    let mut e = vec![0.0; n];
    for j in 0..n {
        e.iter_mut().for_each(|x| *x = 0.0);
        e[j] = 1.0;
        chol_solve(l, n, &mut e);
        for i in 0..n {
            inv[i * n + j] = e[i];
        }
    }
    inv
}

/// A symmetric positive-definite matrix factored on its scaling to unit diagonal (plus `ridge`
/// on that diagonal), so that the test for a singular system is relative: the system is singular
/// when a pivot of the scaled matrix is at or below `min_pivot` (for two columns, 1 − ρ² of
/// their correlation ρ). Solves and the inverse undo the scaling.
pub struct ScaledCholesky {
    n: usize,
    d: Vec<f64>,
    l: Vec<f64>,
}

impl ScaledCholesky {
    /// The factor of `a` (n×n row-major, both triangles), or None when singular.
    pub fn new(a: &[f64], n: usize, ridge: f64, min_pivot: f64) -> Option<Self> {
        let d: Vec<f64> = (0..n).map(|i| a[i * n + i].max(1e-300).sqrt()).collect();
        let mut scaled = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                scaled[i * n + j] = a[i * n + j] / (d[i] * d[j]) + if i == j { ridge } else { 0.0 };
            }
        }
        let l = cholesky(&scaled, n)?;
        if min_pivot > 0.0 && (0..n).any(|i| l[i * n + i] * l[i * n + i] <= min_pivot) {
            return None;
        }
        Some(Self { n, d, l })
    }

    /// x with A x = b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x: Vec<f64> = b.iter().zip(&self.d).map(|(b, d)| b / d).collect();
        chol_solve(&self.l, self.n, &mut x);
        x.iter_mut().zip(&self.d).for_each(|(x, d)| *x /= d);
        x
    }

    /// A⁻¹ (row-major).
    pub fn inverse(&self) -> Vec<f64> {
        let n = self.n;
        let mut inv = chol_inverse(&self.l, n);
        for i in 0..n {
            for j in 0..n {
                inv[i * n + j] /= self.d[i] * self.d[j];
            }
        }
        inv
    }
}

/// Inverse of a symmetric positive-definite matrix, computed on the matrix scaled to unit
/// diagonal plus `ridge` on that diagonal (so a parameter the data barely constrain does not
/// spoil the others' errors); None when not positive definite.
pub fn invert_spd_scaled(a: &[f64], n: usize, ridge: f64) -> Option<Vec<f64>> {
    ScaledCholesky::new(a, n, ridge, 0.0).map(|f| f.inverse())
}

/// Cholesky of a matrix that may be only semi-definite: with a diagonal jitter growing from
/// 1e-12 of the largest diagonal entry by tens until it factors; None for a zero diagonal or if
/// even a jitter of 1e3 does not factor it (the caller must treat the system as singular).
pub fn cholesky_jittered(a: &[f64], n: usize) -> Option<Vec<f64>> {
    if let Some(l) = cholesky(a, n) {
        return Some(l);
    }
    let scale = (0..n).map(|i| a[i * n + i].abs()).fold(0.0, f64::max);
    if !(scale > 1e-300) || !scale.is_finite() {
        // a zero (or non-finite) diagonal: any jitter would only invent the answer
        return None;
    }
    let mut eps = 1e-12;
    while eps <= 1e3 {
        let mut b = a.to_vec();
        for i in 0..n {
            b[i * n + i] += eps * scale.max(a[i * n + i].abs());
        }
        if let Some(l) = cholesky(&b, n) {
            return Some(l);
        }
        eps *= 10.0;
    }
    None
}

/// Weighted normal equations of a Jacobian stored by columns (`jac[j][i]` = ∂r_i/∂p_j):
/// A = Jᵀ W J (row-major, both triangles) and g = Jᵀ W r.
pub fn normal_equations(jac: &[Vec<f64>], r: &[f64], w: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let m = jac.len();
    let mut a = vec![0.0; m * m];
    let mut g = vec![0.0; m];
    for i in 0..m {
        g[i] = jac[i]
            .iter()
            .zip(r)
            .zip(w)
            .map(|((j, r), w)| j * r * w)
            .sum();
        for k in 0..=i {
            let v: f64 = jac[i]
                .iter()
                .zip(&jac[k])
                .zip(w)
                .map(|((a, b), w)| a * b * w)
                .sum();
            a[i * m + k] = v;
            a[k * m + i] = v;
        }
    }
    (a, g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_and_inverts_a_known_system() {
        let a = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let x = solve_spd(&a, 3, &[1.0, 2.0, 3.0]).unwrap();
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
            assert!((r - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
        }
        let inv = invert_spd_scaled(&a, 3, 0.0).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i * 3 + k] * inv[k * 3 + j]).sum();
                assert!((p - f64::from(u8::from(i == j))).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn the_scaled_factor_solves_and_flags_collinear_columns() {
        // badly scaled but well conditioned: a time column of ~1e-3 s beside a constant
        let a = [10.0, 0.01, 0.01, 2e-5];
        let f = ScaledCholesky::new(&a, 2, 0.0, 1e-12).unwrap();
        let x = f.solve(&[1.0, 1e-3]);
        for i in 0..2 {
            let r: f64 = (0..2).map(|j| a[i * 2 + j] * x[j]).sum();
            assert!((r - [1.0, 1e-3][i]).abs() < 1e-12 * [1.0, 1e-3][i]);
        }
        let inv = f.inverse();
        let det = a[0] * a[3] - a[1] * a[1];
        assert!((inv[0] - a[3] / det).abs() < 1e-9 * (a[3] / det));
        assert!((inv[3] - a[0] / det).abs() < 1e-9 * (a[0] / det));
        // correlation 1 − 1e-14: positive definite in exact arithmetic, singular at 1e-12
        let c = (1.0f64 - 1e-14).sqrt();
        let near = [1.0, c, c, 1.0];
        assert!(ScaledCholesky::new(&near, 2, 0.0, 1e-12).is_none());
        assert!(ScaledCholesky::new(&[1.0, 0.5, 0.5, 1.0], 2, 0.0, 1e-12).is_some());
        assert!(ScaledCholesky::new(&[0.0; 4], 2, 0.0, 1e-12).is_none());
    }

    #[test]
    fn a_singular_system_is_none_not_an_identity() {
        let zero = [0.0; 4];
        assert!(cholesky(&zero, 2).is_none());
        assert!(cholesky_jittered(&zero, 2).is_none());
        // semi-definite: a small jitter factors it
        let l = cholesky_jittered(&[1.0, 1.0, 1.0, 1.0], 2).unwrap();
        assert!(l[3] > 0.0 && l[3] < 1e-4);
    }
}
