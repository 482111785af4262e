//! Golden-section search for the minimum of a one-dimensional function on an interval.

/// The midpoint of the bracket left after `iterations` golden-section steps on [a, b], one
/// evaluation of `f` per step (the interior point kept from the step before is reused). For a
/// maximum, pass −f: the comparison is the same, so the steps are too.
pub fn minimize(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, iterations: usize) -> f64 {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (a, b);
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iterations {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_parabola_and_the_maximum_of_its_negative() {
        let x = minimize(|x| (x - 0.3).powi(2), -1.0, 2.0, 60);
        assert!((x - 0.3).abs() < 1e-9, "{x}");
        let y = minimize(|x| -(-(x - 1.7).powi(2)), 0.0, 2.0, 60);
        assert!((y - 1.7).abs() < 1e-9, "{y}");
        // a minimum at the bracket's end is approached, not passed
        let z = minimize(|x| x, 0.0, 1.0, 60);
        assert!((0.0..1e-9).contains(&z), "{z}");
    }
}
