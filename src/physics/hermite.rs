//! Interpolation inside one integration step: quintic Hermite for positions, cubic for the rest.
//!
//! States are particle triples `[z, v, va, z, v, va, ...]`, so a position's derivative is the next
//! component and its second derivative the next component of the derivative.

/// Interpolated state at fraction `th` ∈ [0, 1] of a step of size `h` from (y0, f0) to (y1, f1).
pub(crate) fn interpolate<const N: usize>(
    h: f64,
    th: f64,
    y0: &[f64; N],
    f0: &[f64; N],
    y1: &[f64; N],
    f1: &[f64; N],
) -> [f64; N] {
    let t2 = th * th;
    let t3 = t2 * th;
    let t4 = t3 * th;
    let t5 = t4 * th;
    // cubic basis
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + th;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    // quintic basis
    let q0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5;
    let q1 = th - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
    let q2 = 0.5 * (t2 - 3.0 * t3 + 3.0 * t4 - t5);
    let q3 = 0.5 * (t3 - 2.0 * t4 + t5);
    let q4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
    let q5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = if i % 3 == 0 {
            q0 * y0[i]
                + q1 * h * y0[i + 1]
                + q2 * h * h * f0[i + 1]
                + q3 * h * h * f1[i + 1]
                + q4 * h * y1[i + 1]
                + q5 * y1[i]
        } else {
            h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i]
        };
    }
    out
}
