//! Forward-difference Jacobians for models without an analytic one: each column steps one
//! parameter by its own step, inward (negative) where a step up would leave the box.

/// The signed step for a parameter at `x` with nominal step `h` > 0 and upper bound `hi`.
#[inline]
pub fn inward_step(x: f64, h: f64, hi: f64) -> f64 {
    if x + h > hi {
        -h
    } else {
        h
    }
}

/// Columns ∂r/∂p_j of `f` at `p` (residuals `r0` there) into `jac[j]`, by forward differences
/// with steps `step[j]`; a held parameter (`lower[j] == upper[j]`) gets a zero column.
pub fn jacobian_columns<F>(
    f: &F,
    p: &[f64],
    step: &[f64],
    lower: &[f64],
    upper: &[f64],
    r0: &[f64],
    jac: &mut [Vec<f64>],
) where
    F: Fn(&[f64], &mut [f64]),
{
    let mut q = p.to_vec();
    let mut r1 = vec![0.0; r0.len()];
    for j in 0..p.len() {
        if lower[j] == upper[j] {
            jac[j].iter_mut().for_each(|x| *x = 0.0);
            continue;
        }
        let h = inward_step(p[j], step[j], upper[j]);
        q[j] = p[j] + h;
        f(&q, &mut r1);
        for (i, col) in jac[j].iter_mut().enumerate() {
            *col = (r1[i] - r0[i]) / h;
        }
        q[j] = p[j];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_of_a_known_model_and_the_inward_step() {
        // r = (p0², p0·p1): ∂/∂p0 = (2p0, p1), ∂/∂p1 = (0, p0)
        let f = |p: &[f64], out: &mut [f64]| {
            out[0] = p[0] * p[0];
            out[1] = p[0] * p[1];
        };
        let p = [2.0, 3.0];
        let mut r0 = [0.0; 2];
        f(&p, &mut r0);
        let mut jac = vec![vec![0.0; 2]; 2];
        jacobian_columns(
            &f,
            &p,
            &[1e-7, 1e-7],
            &[-9.0, -9.0],
            &[9.0, 3.0],
            &r0,
            &mut jac,
        );
        assert!((jac[0][0] - 4.0).abs() < 1e-5 && (jac[0][1] - 3.0).abs() < 1e-6);
        assert!(jac[1][0].abs() < 1e-12 && (jac[1][1] - 2.0).abs() < 1e-6);
        assert_eq!(inward_step(3.0, 1e-7, 3.0), -1e-7);
    }
}
