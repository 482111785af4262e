//! One Dormand–Prince 5(4) step for an autonomous ODE, with its embedded error estimate.

/// Result of one step: the new state, the derivative there (FSAL), and the scaled error (≤ 1 ok).
pub(crate) struct Step<const N: usize> {
    pub y: [f64; N],
    pub f: [f64; N],
    pub err: f64,
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
    let mut err: f64 = 0.0;
    for i in 0..N {
        let e = h
            * (E[0] * k1[i]
                + E[2] * k3[i]
                + E[3] * k4[i]
                + E[4] * k5[i]
                + E[5] * k6[i]
                + E[6] * k7[i]);
        let scale = tol.atol[i] + tol.rtol * y[i].abs().max(y_new[i].abs());
        err = err.max(e.abs() / scale);
    }
    Step {
        y: y_new,
        f: k7,
        err,
    }
}
