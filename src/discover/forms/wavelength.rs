//! What the two forms periodic in lab z share (a force, `periodic_z`; friction,
//! `friction_periodic`) and the force periodic in time locked to the kick (`time_common`): their
//! coherent (sin, cos) scan, the amplitude and phase of a fitted (sin, cos)
//! pair, and the words for a wavelength at the end of its search.

use super::form::{ParamInfo, Search};
use crate::artifacts::diagnosis::Estimate;
use crate::discover::response::Prepared;
use crate::discover::screen_sums::{best_of, coherent_scan_blocks, most_sensitive, Trial, Typical};
use crate::discover::spectral::k_grid;
use crate::physics::Variable;
use std::f64::consts::TAU;

/// The search over the grid's wavenumbers in [k_lo, k_hi]: at each k, the runs' responses to
/// the accelerations w sin(k(z − z_ref)) and w cos(k(z − z_ref)) at the grid points, with a run's
/// weights w = `weight(p)` (None: the run takes no part), regressed on the prepared runs
/// coherently (one pair shared by every run).
pub fn search<W>(
    s: &Search,
    (k_lo, k_hi): (f64, f64),
    z_ref: f64,
    weight: W,
) -> (Option<Trial>, Option<Typical>)
where
    W: Fn(&Prepared) -> Option<Vec<f64>> + Sync,
{
    let ks: Vec<f64> = k_grid(s.rg.span(), s.rg.lambda_min_m)
        .into_iter()
        .filter(|k| *k >= k_lo && *k <= k_hi)
        .collect();
    let (prep, v, reps) = (s.prep, s.v, s.reps.clone());
    let solved = coherent_scan_blocks(prep, v, 2, reps.clone(), &ks, |p, block| {
        let Some(w) = weight(p) else {
            return vec![None; block.len()];
        };
        let z = p.track.variable(Variable::Z);
        waves(z, z_ref, &w, block)
            .into_iter()
            .map(|(fs, fc)| {
                let (rs, rc) = p.track.respond_values_pair(&fs, &fc);
                Some(vec![p.column(rs), p.column(rc)])
            })
            .collect()
    });
    pair_trials(solved, &ks, reps.len(), |k| {
        format!("at a wavelength of {:.3} mm", 1e3 * TAU / k)
    })
}

/// w sin(k(z − z_ref)) and w cos(k(z − z_ref)) at each point of `z`, for each of the equally
/// spaced wavenumbers `ks`: the first by sin and cos, each next one by rotating the last through
/// the spacing (four products a point in place of two transcendental calls; the rounding grows by
/// about 10⁻¹⁶ a rotation, over the few a scan's block holds).
fn waves(z: &[f64], z_ref: f64, w: &[f64], ks: &[f64]) -> Vec<(Vec<f64>, Vec<f64>)> {
    let Some(&k0) = ks.first() else {
        return Vec::new();
    };
    let dk = ks.get(1).map_or(0.0, |k1| k1 - k0);
    let (mut s, mut c): (Vec<f64>, Vec<f64>) =
        z.iter().map(|z| (k0 * (z - z_ref)).sin_cos()).unzip();
    let step: Vec<(f64, f64)> = z.iter().map(|z| (dk * (z - z_ref)).sin_cos()).collect();
    let mut out = Vec::with_capacity(ks.len());
    for j in 0..ks.len() {
        if j > 0 {
            for ((s, c), (ds, dc)) in s.iter_mut().zip(c.iter_mut()).zip(&step) {
                (*s, *c) = (*s * dc + *c * ds, *c * dc - *s * ds);
            }
        }
        out.push((
            s.iter().zip(w).map(|(s, w)| s * w).collect(),
            c.iter().zip(w).map(|(c, w)| c * w).collect(),
        ));
    }
    out
}

/// The trials of a coherent (sin, cos) scan solved at each value of `grid` (`Sums::solve`'s
/// statistic per replicate, coefficients and variances; None: no trial there), each estimate
/// (x, sin, cos), over `n_rep` replicates; the most sensitive trial is said by `at(x)`.
pub fn pair_trials<A>(
    solved: Vec<Option<(Vec<f64>, Vec<f64>, Vec<f64>)>>,
    grid: &[f64],
    n_rep: usize,
    at: A,
) -> (Option<Trial>, Option<Typical>)
where
    A: Fn(f64) -> String,
{
    let trials: Vec<Option<Trial>> = solved
        .into_iter()
        .zip(grid)
        .map(|(t, &x)| {
            let (lr, b, var) = t?;
            Some((
                lr,
                vec![x, b[0], b[1]],
                vec![f64::NAN, var[0].sqrt(), var[1].sqrt()],
            ))
        })
        .collect();
    let typical = most_sensitive(&trials, |se| se[1].hypot(se[2]) / 2f64.sqrt())
        .map(|(se, t)| Typical::Se { se, at: at(t.1[0]) });
    (best_of(trials, n_rep), typical)
}

/// The amplitude, wavelength and phase (about z = 0) of a sin(k(z − z_ref)) + b cos(k(z − z_ref))
/// fitted at `x` = (k, a, b) with standard errors `se`.
pub fn amplitude_wavelength_phase(x: &[f64], se: &[f64], z_ref: f64) -> [Estimate; 3] {
    let (k, a, b) = (x[0], x[1], x[2]);
    let (sk, sa, sb) = (se[0], se[1], se[2]);
    let amp = a.hypot(b).max(1e-300);
    let amp_se = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp;
    let phase = (b.atan2(a) - k * z_ref).rem_euclid(TAU);
    let phase_se = (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp)).hypot(z_ref * sk);
    [
        Estimate::new(amp, amp_se),
        Estimate::new(TAU / k, TAU * sk / (k * k)),
        Estimate::new(phase, phase_se),
    ]
}

/// The words for a wavenumber parameter at the `lower` (longest wavelength) or upper end of its
/// search; None for another parameter.
pub fn bound_note(x: f64, info: &ParamInfo, lower: bool) -> Option<String> {
    (info.name == "k_per_m").then(|| format!(
        "the wavelength ({:.3} mm) is the {} the search allows: the data resolve no {} period, so wavelength and amplitude describe the observed stretch rather than a period",
        1e3 * TAU / x,
        if lower { "longest" } else { "shortest" },
        if lower { "longer" } else { "shorter" }
    ))
}

/// The words for a wavelength that ran to the shortest the search allows (the fine end).
pub fn at_fine_end(x: f64, lower: bool) -> Option<String> {
    (!lower).then(|| {
        format!(
            "its wavelength ran to the shortest the search allows ({:.3} mm)",
            1e3 * TAU / x
        )
    })
}

#[cfg(test)]
mod wave_tests {
    use super::waves;

    #[test]
    fn waves_by_rotation_match_sin_and_cos_at_every_wavenumber() {
        let z: Vec<f64> = (0..400).map(|i| 1e-3 + 2.5e-5 * i as f64).collect();
        let w: Vec<f64> = (0..400).map(|i| 1.0 + 0.001 * i as f64).collect();
        let (k0, dk, z_ref) = (600.0, 310.0, 4e-3);
        let ks: Vec<f64> = (0..16).map(|j| k0 + dk * j as f64).collect();
        let got = waves(&z, z_ref, &w, &ks);
        assert_eq!(got.len(), ks.len());
        for (k, (s, c)) in ks.iter().zip(&got) {
            for i in 0..z.len() {
                let (ws, wc) = (k * (z[i] - z_ref)).sin_cos();
                assert!(
                    (s[i] - w[i] * ws).abs() < 1e-13,
                    "sin at k = {k}, point {i}"
                );
                assert!(
                    (c[i] - w[i] * wc).abs() < 1e-13,
                    "cos at k = {k}, point {i}"
                );
            }
        }
        assert!(waves(&z, z_ref, &w, &[]).is_empty());
    }
}
