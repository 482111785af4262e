//! Spectral search: pooled periodograms of the residuals in lab z and in time since the kick.
//!
//! At each trial wavenumber (or frequency) the residuals of every run, with its z0, t0, v0
//! projected out, are regressed on the run's linear response to `sin` and `cos` forces; the power
//! is the drop in χ² (residuals in units of each run's noise). In z the force is fixed in the lab,
//! so one (sin, cos) pair is shared by every run (coherent). In time a vibration starts anew in
//! each run, so each run gets its own pair and the drops add (incoherent, a phase per run). The
//! peaks only propose candidates and their starting values; whether a peak is real is decided by
//! the candidate's likelihood ratio against the parametric bootstrap, which repeats this search in
//! every replicate (so the look-elsewhere effect is in the null).

use super::response::{dot, Prepared};
use crate::lsq::dense::ScaledCholesky;
use rayon::prelude::*;
use std::f64::consts::TAU;

pub use crate::artifacts::diagnosis::{Peak, Spectrum};

/// The least-squares (sin, cos) amplitudes for the normal matrix `a` = [ss, sc, cc] and right
/// side `b`, the χ² drop x·b, and the trace of the inverse normal matrix (the noise part of
/// |x|²), by the shared dense back-end; None when the two columns are collinear to 1e-12.
fn solve_pair(a: [f64; 3], b: [f64; 2]) -> Option<([f64; 2], f64, f64)> {
    let f = ScaledCholesky::new(&[a[0], a[1], a[1], a[2]], 2, 0.0, 1e-12)?;
    let x = f.solve(&b);
    let inv = f.inverse();
    Some(([x[0], x[1]], x[0] * b[0] + x[1] * b[1], inv[0] + inv[3]))
}

/// The grid's local maxima (ends included), strongest first (ties by index).
fn local_maxima(power: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..power.len())
        .filter(|&i| {
            (i == 0 || power[i] >= power[i - 1])
                && (i + 1 == power.len() || power[i] >= power[i + 1])
        })
        .collect();
    idx.sort_by(|a, b| power[*b].total_cmp(&power[*a]).then(a.cmp(b)));
    idx
}

/// The `n` highest local maxima, at least 2.5 grid steps apart.
fn peaks_of(omega: &[f64], power: &[f64], coef: &[[f64; 2]], n: usize) -> Vec<Peak> {
    let idx = local_maxima(power);
    let mut out: Vec<Peak> = Vec::new();
    for i in idx {
        if out.len() >= n {
            break;
        }
        if out.iter().any(|p| {
            (p.omega - omega[i]).abs() < 2.5 * (omega[1.min(omega.len() - 1)] - omega[0]).abs()
        }) {
            continue;
        }
        out.push(Peak {
            omega: omega[i],
            power: power[i],
            coef: coef[i],
        });
    }
    out
}

/// The coherent fit at one wavenumber: the χ² drop and the (sin, cos) coefficients (m/s²).
fn z_power(prep: &[Prepared], z_ref: f64, kk: f64) -> (f64, [f64; 2]) {
    let mut a = [0.0; 3];
    let mut b = [0.0; 2];
    for p in prep {
        let z = p.track.variable(crate::physics::Variable::Z);
        let fs: Vec<f64> = z.iter().map(|z| (kk * (z - z_ref)).sin()).collect();
        let fc: Vec<f64> = z.iter().map(|z| (kk * (z - z_ref)).cos()).collect();
        let (rs, rc) = p.track.respond_values_pair(&fs, &fc);
        let (xs, xc) = (p.column(rs), p.column(rc));
        a[0] += dot(&xs, &xs);
        a[1] += dot(&xs, &xc);
        a[2] += dot(&xc, &xc);
        b[0] += dot(&xs, &p.y);
        b[1] += dot(&xc, &p.y);
    }
    solve_pair(a, b)
        .map(|(x, d, _)| (d, x))
        .unwrap_or((0.0, [0.0; 2]))
}

/// Grid maxima refined before they are ranked (the strongest by their grid power).
const REFINED: usize = 6;

/// The `n` highest maxima of `f`, each grid maximum (the `REFINED` strongest) refined by golden
/// section between its neighbours, distinct maxima only.
///
/// Runs that start near either end of the field of view put the signal of a lab-fixed force in
/// two clusters of positions a distance D apart: the periodogram then has fine lobes spaced
/// 2π/D, about as wide as the grid step, under an envelope set by each cluster's width, so a
/// grid point can sit on the flank of the true lobe and below the top of its neighbour. Ranked
/// at the grid the neighbour wins; the full fit started there converges to that alias (a
/// wavelength off by λ/D, 5 % at 0.5 mm), and what it leaves is taken up by further terms.
fn refined_peaks(
    omega: &[f64],
    power: &[f64],
    n: usize,
    f: impl Fn(f64) -> (f64, [f64; 2]) + Sync,
) -> Vec<Peak> {
    let mut idx = local_maxima(power);
    idx.truncate(REFINED);
    if omega.is_empty() {
        return vec![];
    }
    let last = omega.len() - 1;
    let step = if last > 0 {
        (omega[1] - omega[0]).abs()
    } else {
        0.0
    };
    let mut found: Vec<Peak> = idx
        .par_iter()
        .map(|&i| {
            let (a, b) = (omega[i.saturating_sub(1)], omega[(i + 1).min(last)]);
            let x = crate::lsq::golden::minimize(|w| -f(w).0, a, b, 16);
            let (p, coef) = f(x);
            // never below the grid point it started from
            if p >= power[i] {
                Peak {
                    omega: x,
                    power: p,
                    coef,
                }
            } else {
                let (p, coef) = f(omega[i]);
                Peak {
                    omega: omega[i],
                    power: p,
                    coef,
                }
            }
        })
        .collect();
    found.sort_by(|a, b| {
        b.power
            .total_cmp(&a.power)
            .then(a.omega.total_cmp(&b.omega))
    });
    let mut out: Vec<Peak> = Vec::new();
    for pk in found {
        if out.len() >= n {
            break;
        }
        if out.iter().any(|q| (q.omega - pk.omega).abs() < 0.5 * step) {
            continue;
        }
        out.push(pk);
    }
    out
}

/// The periodogram in lab z over wavenumbers `k` (rad/m), phases referred to `z_ref`; its peaks
/// refined off the grid.
pub fn z_spectrum(prep: &[Prepared], z_ref: f64, k: &[f64]) -> Spectrum {
    let rows: Vec<(f64, [f64; 2])> = k.par_iter().map(|&kk| z_power(prep, z_ref, kk)).collect();
    let power: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let mut peaks = refined_peaks(k, &power, 2, |kk| z_power(prep, z_ref, kk));
    if let Some(&k1) = k.first() {
        peaks.extend(long_wave_peaks(prep, z_ref, k1, &peaks));
    }
    Spectrum {
        variable: "z".into(),
        x: k.iter().map(|k| TAU / k).collect(),
        peaks,
        power,
        noise_power: 2.0,
    }
}

/// Extra starts at the long-wavelength end, where the grid's two points per Fourier step are
/// too coarse: a wave with one or two periods in view is partly absorbed by each run's μ and T,
/// so its power is low and no grid maximum lies near it (a 5 mm wave over a 12 mm view: grid
/// points at 3.1 and 5.5 mm, the stronger at 3.1 mm, and the fit settled there). Scanned eight
/// times finer from half to four times the first grid wavenumber `k1`; its two strongest local
/// maxima away from the peaks already found start the full fit too (the screen's trials, and so
/// its null, are unchanged).
fn long_wave_peaks(prep: &[Prepared], z_ref: f64, k1: f64, found: &[Peak]) -> Vec<Peak> {
    let fine: Vec<f64> = (0..=28).map(|i| k1 * (0.5 + i as f64 / 8.0)).collect();
    let rows: Vec<(f64, [f64; 2])> = fine
        .par_iter()
        .map(|&kk| z_power(prep, z_ref, kk))
        .collect();
    let power: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let mut out: Vec<Peak> = local_maxima(&power)
        .into_iter()
        .filter(|&i| found.iter().all(|p| (p.omega - fine[i]).abs() > 0.25 * k1))
        .map(|i| Peak {
            omega: fine[i],
            power: power[i],
            coef: rows[i].1,
        })
        .collect();
    out.truncate(2);
    out
}

/// The periodogram in time since the kick over frequencies `f_hz`, a phase per run.
pub fn t_spectrum(prep: &[Prepared], f_hz: &[f64]) -> Spectrum {
    let omega: Vec<f64> = f_hz.iter().map(|f| TAU * f).collect();
    let rows: Vec<(f64, [f64; 2])> = omega
        .par_iter()
        .map(|&w| {
            let (mut power, mut amp2, mut bias, mut n) = (0.0, 0.0, 0.0, 0.0);
            for p in prep {
                let (rs, rc) = p.track.respond_time(w);
                let xs = p.column(rs);
                let xc = p.column(rc);
                let a = [dot(&xs, &xs), dot(&xs, &xc), dot(&xc, &xc)];
                let b = [dot(&xs, &p.y), dot(&xc, &p.y)];
                if let Some((x, d, trace_inv)) = solve_pair(a, b) {
                    power += d;
                    amp2 += x[0] * x[0] + x[1] * x[1];
                    // the noise part of |x|²: trace of the inverse normal matrix
                    bias += trace_inv;
                    n += 1.0;
                }
            }
            let amp = if n > 0.0 {
                ((amp2 - bias) / n).max(0.0).sqrt()
            } else {
                0.0
            };
            (power, [amp, 0.0])
        })
        .collect();
    let power: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let coef: Vec<[f64; 2]> = rows.iter().map(|r| r.1).collect();
    Spectrum {
        variable: "t".into(),
        x: f_hz.to_vec(),
        peaks: peaks_of(&omega, &power, &coef, 2),
        power,
        noise_power: 2.0 * prep.len() as f64,
    }
}

/// Wavenumbers from the observed span down to `lambda_min_m`, two per Fourier step.
pub fn k_grid(span_m: f64, lambda_min_m: f64) -> Vec<f64> {
    let k_lo = TAU / span_m;
    let k_hi = TAU / lambda_min_m.min(span_m / 2.0);
    let dk = 0.5 * k_lo;
    let n = ((k_hi - k_lo) / dk).ceil() as usize + 1;
    (0..n).map(|i| k_lo + i as f64 * dk).collect()
}

/// Frequencies from one period over the longest run up to `f_max_hz`, two per Fourier step.
pub fn f_grid(duration_s: f64, f_max_hz: f64) -> Vec<f64> {
    let f_lo = 1.0 / duration_s;
    let df = 0.5 * f_lo;
    let n = ((f_max_hz - f_lo) / df).floor().max(0.0) as usize + 1;
    (0..n).map(|i| f_lo + i as f64 * df).collect()
}
