//! Interpolation inside one integration step: quintic Hermite for positions (their first and
//! second derivatives are known exactly), the 4th-order Dormand–Prince dense output for the rest.
//!
//! States are particle triples `[z, v, va, z, v, va, ...]`, so a position's derivative is the next
//! component and its second derivative the next component of the derivative. A trailing component
//! outside the triples (the time carried for time-dependent terms) uses the dense output.

use super::rk::Step;

/// Interpolated state at fraction `th` ∈ [0, 1] of the step `step` of size `h` from (y0, f0).
pub(crate) fn interpolate<const N: usize>(
    h: f64,
    th: f64,
    y0: &[f64; N],
    f0: &[f64; N],
    step: &Step<N>,
) -> [f64; N] {
    let (y1, f1) = (&step.y, &step.f);
    let t2 = th * th;
    let t3 = t2 * th;
    let t4 = t3 * th;
    let t5 = t4 * th;
    let q0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5;
    let q1 = th - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
    let q2 = 0.5 * (t2 - 3.0 * t3 + 3.0 * t4 - t5);
    let q3 = 0.5 * (t3 - 2.0 * t4 + t5);
    let q4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
    let q5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
    let one = 1.0 - th;
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = if i % 3 == 0 && i + 2 < N {
            q0 * y0[i]
                + q1 * h * y0[i + 1]
                + q2 * h * h * f0[i + 1]
                + q3 * h * h * f1[i + 1]
                + q4 * h * y1[i + 1]
                + q5 * y1[i]
        } else {
            let r2 = y1[i] - y0[i];
            let r3 = h * f0[i] - r2;
            let r4 = r2 - h * f1[i] - r3;
            y0[i] + th * (r2 + one * (r3 + th * (r4 + one * step.dense[i])))
        };
    }
    out
}
