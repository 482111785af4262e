//! One Dormand–Prince 5(4) step for an autonomous ODE, with its embedded error estimate and the
//! coefficients of its 4th-order continuous extension (Hairer, Nørsett & Wanner, dense output).

/// Result of one step: the new state, the derivative there (FSAL), the scaled error (≤ 1 ok),
/// and `h · Σ dᵢ kᵢ`, the last coefficient of the dense output.
pub(crate) struct Step<const N: usize> {
    pub y: [f64; N],
    pub f: [f64; N],
    pub err: f64,
    pub dense: [f64; N],
}

/// Absolute and relative tolerances per component.
pub(crate) struct Tolerance<const N: usize> {
    pub atol: [f64; N],
    pub rtol: f64,
}

fn axpy<const N: usize>(y: &[f64; N], h: f64, terms: &[(&[f64; N], f64)]) -> [f64; N] {
    let mut out = *y;
    for (k, c) in terms {
        for i in 0..N {
            out[i] += h * c * k[i];
        }
    }
    out
}

/// Take one step of size `h` from `y` (with `f0 = rhs(y)`).
pub(crate) fn dopri5<const N: usize>(
    rhs: &impl Fn(&[f64; N]) -> [f64; N],
    y: &[f64; N],
    f0: &[f64; N],
    h: f64,
    tol: &Tolerance<N>,
) -> Step<N> {
    let k1 = f0;
    let k2 = rhs(&axpy(y, h, &[(k1, 1.0 / 5.0)]));
    let k3 = rhs(&axpy(y, h, &[(k1, 3.0 / 40.0), (&k2, 9.0 / 40.0)]));
    let k4 = rhs(&axpy(
        y,
        h,
        &[(k1, 44.0 / 45.0), (&k2, -56.0 / 15.0), (&k3, 32.0 / 9.0)],
    ));
    let k5 = rhs(&axpy(
        y,
        h,
        &[
            (k1, 19372.0 / 6561.0),
            (&k2, -25360.0 / 2187.0),
            (&k3, 64448.0 / 6561.0),
            (&k4, -212.0 / 729.0),
        ],
    ));
    let k6 = rhs(&axpy(
        y,
        h,
        &[
            (k1, 9017.0 / 3168.0),
            (&k2, -355.0 / 33.0),
            (&k3, 46732.0 / 5247.0),
            (&k4, 49.0 / 176.0),
            (&k5, -5103.0 / 18656.0),
        ],
    ));
    let y_new = axpy(
        y,
        h,
        &[
            (k1, 35.0 / 384.0),
            (&k3, 500.0 / 1113.0),
            (&k4, 125.0 / 192.0),
            (&k5, -2187.0 / 6784.0),
            (&k6, 11.0 / 84.0),
        ],
    );
    let k7 = rhs(&y_new);
    const E: [f64; 7] = [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ];
    const D: [f64; 7] = [
        -12715105075.0 / 11282082432.0,
        0.0,
        87487479700.0 / 32700410799.0,
        -10690763975.0 / 1880347072.0,
        701980252875.0 / 199316789632.0,
        -1453857185.0 / 822651844.0,
        69997945.0 / 29380423.0,
    ];
    let mut err: f64 = 0.0;
    let mut dense = [0.0; N];
    for i in 0..N {
        let ks = [k1[i], k2[i], k3[i], k4[i], k5[i], k6[i], k7[i]];
        let e: f64 = h * E.iter().zip(&ks).map(|(c, k)| c * k).sum::<f64>();
        dense[i] = h * D.iter().zip(&ks).map(|(c, k)| c * k).sum::<f64>();
        let scale = tol.atol[i] + tol.rtol * y[i].abs().max(y_new[i].abs());
        err = err.max(e.abs() / scale);
    }
    Step {
        y: y_new,
        f: k7,
        err,
        dense,
    }
}
