//! Detection limits: the smallest size of each candidate this dataset would have found.
//!
//! A named term's limit comes from the standard error of its size in the candidate model. A form
//! whose scale is searched (a wavelength, a bump's centre and width, a frequency) has a limit for
//! each trial scale; it is given at the grid's most sensitive trial, named in the text
//! (`screen::Typical`), not at the trial the data happened to like best: that one's information
//! can be anything from the grid's best to its worst (a force in time must grow as f² to move the
//! positions as much, so near the Nyquist limit it hardly moves them), and a limit read there says
//! more about the noise than about the dataset. A median over the trials is no better: over a
//! frequency grid spaced evenly it sits among the high frequencies, where the information is least.

use super::candidate::Extra;
use super::model::Model;
use super::null_distribution::NullFit;
use super::screen::Typical;
use crate::artifacts::diagnosis::DetectionLimit;
use std::f64::consts::FRAC_PI_2;

/// One-sided 90 % power: the size is found in 90 % of datasets.
const Z_POWER: f64 = 1.2816;

/// The LR a term must exceed at `level` under its bootstrap null (bisection on the gamma tail).
pub fn critical_lr(null: &NullFit, level: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1.0);
    while null.p_value(hi) > level && hi < 1e9 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if null.p_value(mid) > level {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The smallest size of a term this dataset would have detected (90 % power at the first Holm
/// level `level`). For a term estimated coherently over the runs: the size θ with |θ̂| > se·√c in
/// 90 % of data sets, θ̂ ~ N(θ, s·se²), c the critical LR and s the null's inflation over χ²
/// (dependent frames); se at the most sensitive trial for a searched form. For a force periodic in time
/// with a phase per run: see `time_limit`. None for terms without one size.
pub fn detection_limit(
    e: &Extra,
    m: &Model,
    typical: Option<&Typical>,
    null: &NullFit,
    level: f64,
) -> Option<DetectionLimit> {
    let off = m.spec.extra_offset(m.spec.extras.len() - 1);
    let se = &m.fit.global_se;
    let typical_se = match typical {
        Some(Typical::Se { se, .. }) => Some(*se),
        _ => None,
    };
    let at = match typical {
        Some(Typical::Se { at, .. }) | Some(Typical::PerRun { at, .. }) => format!(" {at}"),
        None => String::new(),
    };
    let (name, unit, se_size, scale) = e.detection_size(&se[off..], typical_se)?;
    let c = critical_lr(null, level);
    // a phase per run: only a force periodic in time is searched so (`Typical::PerRun`)
    let value = match typical {
        Some(Typical::PerRun { a, floor, .. }) => floored_time_limit(a, *floor, c)?,
        _ => {
            if !(se_size.is_finite() && se_size > 0.0) {
                return None;
            }
            let df = e.params().len() as f64;
            let inflation = (null.mean / df).max(1.0);
            scale * se_size * (c.sqrt() + Z_POWER * inflation.sqrt())
        }
    };
    Some(DetectionLimit {
        parameter: name.into(),
        value,
        text: format!(
            "{} above {} {}{at} would have been found",
            e.size_name(),
            sig(value),
            unit
        ),
    })
}

/// The amplitude of a force periodic in time, with its own phase in each run, that the screen's
/// statistic `S = (Σ|b_r|)²/Σa_r` (`forms/time_periodic.rs`) exceeds the critical value `c` with
/// 90 % power, `a_r` each run's information at the typical frequency. In each run's noise units
/// |b_r|/√a_r follows a Rice law of parameter ν_r = A√a_r (a run's projection at its best phase),
/// with mean R(ν) and variance 2 + ν² − R(ν)², so √S has mean Σ√a_r R(ν_r)/√Σa and variance
/// Σa_r(2 + ν_r² − R²)/Σa. When each run alone sees the force below its noise (ν_r < 1), R(ν)
/// grows with ν² only, and the limit is far above the `se·√c` of a coherent term.
fn time_limit(a: &[f64], c: f64) -> Option<f64> {
    let sa: f64 = a.iter().sum();
    if !(sa > 0.0 && c.is_finite()) {
        return None;
    }
    let margin = |amp: f64| {
        let (mut mean, mut var) = (0.0, 0.0);
        for &ar in a {
            let nu = amp * ar.sqrt();
            let r = rice_mean(nu);
            mean += ar.sqrt() * r;
            var += ar * (2.0 + nu * nu - r * r).max(0.0);
        }
        mean / sa.sqrt() - Z_POWER * (var / sa).sqrt() - c.sqrt()
    };
    let mut hi = 1.0 / sa.sqrt();
    while margin(hi) < 0.0 {
        hi *= 2.0;
        if hi > 1e6 {
            return None;
        }
    }
    let mut lo = 0.0;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if margin(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(hi)
}

/// `time_limit` where the data's noise runs `floor` (k ≥ 1) times the replicates' model at the
/// typical frequency (the screen raised the replicates by k there, so the critical value `c` is
/// in the data's units): each run's projection has variance k·a_r, so its Rice parameter is
/// A√(a_r/k), and √S = √k·T with T the statistic in the data's noise units, which must exceed
/// √(c/k). Read as if the noise were the model's against a critical value in the data's units,
/// the limit came out too high (on a floor of 1.8: 0.32 m/s² where 0.26 is found in 90 % of
/// datasets; 0.32 is found in 99.5 %).
fn floored_time_limit(a: &[f64], floor: f64, c: f64) -> Option<f64> {
    let k = if floor.is_finite() {
        floor.max(1.0)
    } else {
        1.0
    };
    let scaled: Vec<f64> = a.iter().map(|x| x / k).collect();
    time_limit(&scaled, c / k)
}

/// Mean of the length of a 2-D Gaussian vector with unit variance per component and mean of
/// length ν (the Rice law): √(π/2)·[(1 + 2x)·I0e(x) + 2x·I1e(x)], x = ν²/4.
pub fn rice_mean(nu: f64) -> f64 {
    let x = 0.25 * nu * nu;
    if x > 700.0 {
        return nu + 0.5 / nu;
    }
    FRAC_PI_2.sqrt() * ((1.0 + 2.0 * x) * i0e(x) + 2.0 * x * i1e(x))
}

// The modified Bessel functions are written here (Abramowitz & Stegun 9.8.1–9.8.4, tested
// against their Table 9.8 below) because no kept crate gives what the Rice mean needs: statrs 0.19
// has neither modified Bessel functions nor the Rice law, and puruspe's `In` is unscaled, so
// I0(x) overflows past x ≈ 700 where this needs e^(−x)·I0(x) (statrs has no Bessel functions, and puruspe's unscaled `In` overflows there, so the scaled forms of Abramowitz & Stegun are kept, tested against their table).

/// e^(−x)·I0(x), x ≥ 0 (polynomial approximations, relative error below 6e-7).
fn i0e(x: f64) -> f64 {
    if x < 3.75 {
        let t = (x / 3.75).powi(2);
        (-x).exp()
            * (1.0
                + t * (3.5156229
                    + t * (3.0899424
                        + t * (1.2067492 + t * (0.2659732 + t * (0.0360768 + t * 0.0045813))))))
    } else {
        let t = 3.75 / x;
        (0.39894228
            + t * (0.01328592
                + t * (0.00225319
                    + t * (-0.00157565
                        + t * (0.00916281
                            + t * (-0.02057706
                                + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377))))))))
            / x.sqrt()
    }
}

/// e^(−x)·I1(x), x ≥ 0 (polynomial approximations, relative error below 6e-7).
fn i1e(x: f64) -> f64 {
    if x < 3.75 {
        let t = (x / 3.75).powi(2);
        (-x).exp()
            * x
            * (0.5
                + t * (0.87890594
                    + t * (0.51498869
                        + t * (0.15084934 + t * (0.02658733 + t * (0.00301532 + t * 0.00032411))))))
    } else {
        let t = 3.75 / x;
        (0.39894228
            + t * (-0.03988024
                + t * (-0.00362018
                    + t * (0.00163801
                        + t * (-0.01031555
                            + t * (0.02282967
                                + t * (-0.02895312 + t * (0.01787654 - t * 0.00420059))))))))
            / x.sqrt()
    }
}

/// Three significant digits.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let d = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.d$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Rice mean against a direct quadrature of E|ν + Z| over the plane.
    #[test]
    fn rice_mean_matches_a_quadrature() {
        for nu in [0.0, 0.3, 1.0, 1.7, 3.0, 5.5, 12.0] {
            let (h, n) = (0.02, 500);
            let mut s = 0.0;
            for i in -n..=n {
                for j in -n..=n {
                    let (x, y) = (i as f64 * h, j as f64 * h);
                    let w = (-0.5 * (x * x + y * y)).exp();
                    s += w * ((nu + x).powi(2) + y * y).sqrt();
                }
            }
            let q = s * h * h / std::f64::consts::TAU;
            let r = rice_mean(nu);
            assert!((r - q).abs() < 1e-4 * q, "nu {nu}: {r} against {q}");
        }
    }

    /// Datasets drawn with a force in time at the stated limit, each run at its own phase, on
    /// noise k times the model's: the screen's statistic exceeds the critical value in 90 % of
    /// them; the limit that ignores the floor is found far more often (it reads too high).
    #[test]
    fn the_time_limit_on_a_raised_noise_floor_is_found_90_percent_of_the_time() {
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let a = vec![30.0; 40];
        let (c, k) = (144.0, 1.8);
        let sa: f64 = a.iter().sum();
        let found = |amp: f64, seed: u64| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let n = 4000;
            let hits = (0..n)
                .filter(|_| {
                    let s: f64 = a
                        .iter()
                        .map(|&ar| {
                            let phase = rng.random_range(0.0..std::f64::consts::TAU);
                            let sd = (k * ar).sqrt();
                            let bs =
                                amp * ar * phase.cos() + sd * rng.sample::<f64, _>(StandardNormal);
                            let bc =
                                amp * ar * phase.sin() + sd * rng.sample::<f64, _>(StandardNormal);
                            bs.hypot(bc)
                        })
                        .sum();
                    s * s / sa > c
                })
                .count();
            hits as f64 / n as f64
        };
        let floored = floored_time_limit(&a, k, c).expect("a limit");
        let power = found(floored, 7);
        let plain = time_limit(&a, c).expect("a limit");
        let plain_power = found(plain, 8);
        assert!((power - 0.9).abs() < 0.02, "found in {power} at {floored}");
        assert!(
            plain_power > 0.97 && plain > 1.1 * floored,
            "the floor ignored: found in {plain_power} at {plain}"
        );
        assert_eq!(floored_time_limit(&a, 1.0, c), time_limit(&a, c));
    }

    /// The scaled Bessel functions against Abramowitz & Stegun Table 9.8 (e^(−x)·I0(x) and
    /// e^(−x)·I1(x), ten digits; x = 3.75 and 50 from the power series), on both sides of the
    /// switch at 3.75, to 6e-7 (A&S state 2.2e-7 absolute on √x·e^(−x)·I(x) ≈ 0.4 for x ≥ 3.75;
    /// at x = 50 the error is 3.4e-7).
    #[test]
    fn scaled_bessel_functions_match_published_values() {
        let table = [
            (0.5, 0.645_035_270_4, 0.156_420_803_2),
            (1.0, 0.465_759_607_6, 0.207_910_415_4),
            (2.0, 0.308_508_322_6, 0.215_269_289_2),
            (3.75, 0.214_457_051_2, 0.182_968_420_9),
            (5.0, 0.183_540_812_6, 0.163_972_266_9),
            (10.0, 0.127_833_337_2, 0.121_262_681_4),
            (50.0, 0.056_561_626_65, 0.055_993_123_89),
        ];
        for (x, i0, i1) in table {
            assert!(
                (i0e(x) - i0).abs() < 6e-7 * i0,
                "I0e({x}) = {} against {i0}",
                i0e(x)
            );
            assert!(
                (i1e(x) - i1).abs() < 6e-7 * i1,
                "I1e({x}) = {} against {i1}",
                i1e(x)
            );
        }
        // large ν: the Rice mean meets its asymptote ν + 1/(2ν) at the switch (x = 700)
        let nu = (4.0f64 * 700.0).sqrt();
        let below = rice_mean(nu * (1.0 - 1e-9));
        assert!(
            (below - (nu + 0.5 / nu)).abs() < 1e-5,
            "{below} against {}",
            nu + 0.5 / nu
        );
    }

    /// The limit is the amplitude at which the statistic's mean less 1.28 of its spread meets
    /// the critical value, and it grows with the critical value.
    #[test]
    fn time_limit_reaches_the_critical_value_with_90_percent_power() {
        let a = vec![400.0; 60];
        let c = 180.0;
        let amp = time_limit(&a, c).expect("a limit");
        let nu = amp * 20.0;
        let r = rice_mean(nu);
        let mean = 60f64.sqrt() * r;
        let sd = (2.0 + nu * nu - r * r).sqrt();
        assert!((mean - Z_POWER * sd - c.sqrt()).abs() < 1e-6, "{mean} {sd}");
        assert!(time_limit(&a, 2.0 * c).expect("a limit") > amp);
    }
}
