//! The fit's hottest loop compiled for wider vectors where the CPU has them: the build targets
//! baseline x86-64 (2 doubles per SSE2 instruction), and AVX2 takes 4. The body is one function
//! (`body`), inlined into both compilations; Rust never fuses a multiply and an add unless
//! asked, and the loop's sums keep their order, so the two give the same bits.
//! The only `unsafe` in groove: calling the AVX2 compilation, after checking the CPU has AVX2.
#![allow(unsafe_code)]

/// Weighted normal equations H = Σ wh JᵀJ (upper and lower filled) and gradient g = Σ w J r,
/// by the widest compilation this CPU runs (the same bits either way).
pub fn normal_equations<const N: usize>(
    jac: &[[f64; N]],
    r: &[f64],
    w: &[f64],
    wh: &[f64],
) -> ([[f64; N]; N], [f64; N]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above), the one requirement of the call.
        return unsafe { normal_equations_avx2(jac, r, w, wh) };
    }
    body(jac, r, w, wh)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn normal_equations_avx2<const N: usize>(
    jac: &[[f64; N]],
    r: &[f64],
    w: &[f64],
    wh: &[f64],
) -> ([[f64; N]; N], [f64; N]) {
    body(jac, r, w, wh)
}

/// The one body of both compilations.
#[inline(always)]
fn body<const N: usize>(
    jac: &[[f64; N]],
    r: &[f64],
    w: &[f64],
    wh: &[f64],
) -> ([[f64; N]; N], [f64; N]) {
    let mut h = [[0.0; N]; N];
    let mut g = [0.0; N];
    for (((row, &ri), &wi), &whi) in jac.iter().zip(r).zip(w).zip(wh) {
        if wi == 0.0 {
            continue;
        }
        for a in 0..N {
            g[a] += wi * ri * row[a];
            let wa = whi * row[a];
            for b in a..N {
                h[a][b] += wa * row[b];
            }
        }
    }
    for a in 0..N {
        for b in 0..a {
            h[a][b] = h[b][a];
        }
    }
    (h, g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn the_wide_compilation_gives_the_baselines_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for rows in [0, 1, 5, 600, 1001] {
            let jac: Vec<[f64; 6]> = (0..rows)
                .map(|_| std::array::from_fn(|_| rng.random_range(-1e3..1e3)))
                .collect();
            let r: Vec<f64> = (0..rows).map(|_| rng.random_range(-1.0..1.0)).collect();
            // some rows weigh nothing, as a robust fit's outliers do
            let w: Vec<f64> = (0..rows)
                .map(|k| {
                    if k % 7 == 3 {
                        0.0
                    } else {
                        rng.random_range(0.0..2.0)
                    }
                })
                .collect();
            let wh: Vec<f64> = w.iter().map(|x| x * 0.5).collect();
            let (h, g) = normal_equations(&jac, &r, &w, &wh);
            let (h0, g0) = body(&jac, &r, &w, &wh);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&g), bits(&g0), "{rows} rows");
            assert_eq!(
                bits(h.as_flattened()),
                bits(h0.as_flattened()),
                "{rows} rows"
            );
        }
    }
}
