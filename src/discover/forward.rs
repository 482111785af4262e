//! Forward selection: test every candidate term against the current model, accept the strongest
//! (likelihood ratio less ln(n) per extra parameter) one that passes both the bootstrap likelihood-ratio test (Holm-corrected) and leave-runs-out
//! cross-validation, refit, repeat; then ask the drift probes whether a mismatch is left unexplained.

use super::bootstrap::{lr_replicates, Alternative};
use super::candidate::{Extra, ParamInfo, Spec, N_LOCAL};
use super::cv::{cross_validate, folds, paired_t, CvResult};
use super::data::RunData;
use super::diagnosis::{CandidateRow, Estimate, Evidence, Finding, ModelScore};
use super::holm::holm;
use super::joint::{fit_joint, FitControl, Fitted};
use super::null_distribution::{empirical_p, NullFit};
use super::{Options, G_MPS2};
use crate::stats::dist::t_upper_quantile;
use std::collections::BTreeMap;

/// Level of the one-sided paired test that held-out runs improve.
pub const CV_LEVEL: f64 = 0.05;

/// A fitted joint model.
#[derive(Clone)]
pub struct Model {
    pub spec: Spec,
    pub params: Vec<ParamInfo>,
    pub fit: Fitted,
}

impl Model {
    pub fn fit(
        spec: Spec,
        materials: &[String],
        runs: &[RunData],
        g: &[f64],
        l: &[[f64; N_LOCAL]],
        max_iter: usize,
    ) -> Model {
        let params = spec.global_params(materials);
        let fit = fit_joint(
            &spec,
            &params,
            runs,
            g,
            l,
            FitControl {
                max_iter,
                free_global: true,
            },
        );
        Model { spec, params, fit }
    }

    /// The model with `extra` added, fitted from this model's values (best of several starts).
    pub fn extend(
        &self,
        extra: &Extra,
        materials: &[String],
        runs: &[RunData],
        max_iter: usize,
    ) -> Model {
        let starts: Vec<Vec<f64>> = match extra {
            Extra::VelocityFriction { materials } => [1e-4f64, 2e-3, 2e-2]
                .iter()
                .map(|v| vec![v.ln(); *materials])
                .collect(),
            e => vec![e.params().iter().map(|p| p.start).collect()],
        };
        starts
            .into_iter()
            .map(|s| {
                let mut g = self.fit.global.clone();
                g.extend(s);
                Model::fit(
                    self.spec.with(extra.clone()),
                    materials,
                    runs,
                    &g,
                    &self.fit.local,
                    max_iter,
                )
            })
            .min_by(|a, b| a.fit.chi2.total_cmp(&b.fit.chi2))
            .expect("at least one start")
    }

    pub fn score(&self, runs: &[RunData], cv: Option<&CvResult>) -> ModelScore {
        let n: usize = runs.iter().map(|r| r.n_used()).sum();
        let sq: f64 = self
            .fit
            .chi2_run
            .iter()
            .zip(runs)
            .map(|(c, r)| c * r.sigma_m * r.sigma_m)
            .sum();
        ModelScore {
            cv_rms_m: cv.map(|c| c.cv_rms_m).unwrap_or(f64::NAN),
            rms_m: (sq / n.max(1) as f64).sqrt(),
            chi2: self.fit.chi2,
            n_global_params: self.spec.n_global(),
            terms: self.spec.extras.iter().map(|e| e.form()).collect(),
        }
    }
}

/// Starting values of a term's parameters: where it vanishes, plus a few for a nonlinear scale.
pub fn extra_starts(extra: &Extra) -> Vec<Vec<f64>> {
    match extra {
        Extra::VelocityFriction { materials } => [1e-4f64, 2e-3, 2e-2]
            .iter()
            .map(|v| vec![v.ln(); *materials])
            .collect(),
        e => vec![e.params().iter().map(|p| p.start).collect()],
    }
}

/// The parameters of extra term `i` of `m`, in SI units with physical names.
pub fn term_parameters(m: &Model, i: usize, materials: &[String]) -> BTreeMap<String, Estimate> {
    let off = m.spec.extra_offset(i);
    let g = &m.fit.global;
    let se = &m.fit.global_se;
    let est = Estimate::new;
    let mut out = BTreeMap::new();
    let nm = m.spec.n_materials;
    match &m.spec.extras[i] {
        Extra::QuadraticDrag => {
            out.insert("c_per_m".into(), est(g[off], se[off]));
            for (k, name) in materials.iter().enumerate() {
                out.insert(format!("t_s_{name}"), est(g[nm + k], se[nm + k]));
            }
        }
        Extra::SaturatingDrag => {
            out.insert("tp_s_per_mps".into(), est(g[off], se[off]));
            for (k, name) in materials.iter().enumerate() {
                out.insert(format!("t0_s_{name}"), est(g[nm + k], se[nm + k]));
            }
        }
        Extra::RollingResistance => {
            out.insert(
                "deceleration_mps2".into(),
                est(g[off] * G_MPS2, se[off] * G_MPS2),
            );
            out.insert("coefficient".into(), est(g[off], se[off]));
        }
        Extra::GrooveTilt => {
            out.insert("alpha_deg".into(), est(g[off], se[off]));
        }
        Extra::VelocityFriction { .. } => {
            for (k, name) in materials.iter().enumerate() {
                let vc = g[off + k].exp();
                out.insert(format!("v_c_mps_{name}"), est(vc, vc * se[off + k]));
                out.insert(format!("mu_inf_{name}"), est(g[k], se[k]));
            }
        }
        Extra::PositionForce {
            harmonics,
            z_min_m,
            span_m,
        } => {
            let mut peak: f64 = 0.0;
            for j in 0..=200 {
                let z = z_min_m + span_m * j as f64 / 200.0;
                let a: f64 = (0..*harmonics)
                    .map(|k| {
                        let u = std::f64::consts::PI * (k + 1) as f64 * (z - z_min_m) / span_m;
                        g[off + 2 * k] * u.sin() + g[off + 2 * k + 1] * u.cos()
                    })
                    .sum();
                peak = peak.max(a.abs());
            }
            out.insert("peak_accel_mps2".into(), est(peak, f64::NAN));
            out.insert("z_min_m".into(), est(*z_min_m, 0.0));
            out.insert("span_m".into(), est(*span_m, 0.0));
            for k in 0..2 * harmonics {
                out.insert(m.params[off + k].name.clone(), est(g[off + k], se[off + k]));
            }
        }
        Extra::SpeedDriftT { .. } | Extra::SpeedDriftMu { .. } | Extra::DirectionAsymmetry => {
            for (k, p) in m.spec.extras[i].params().iter().enumerate() {
                out.insert(p.name.clone(), est(g[off + k], se[off + k]));
            }
        }
    }
    out
}

/// Result of one round of tests against the current model.
pub struct Round {
    pub rows: Vec<CandidateRow>,
    /// (index into rows, extended model, its CV) of the accepted term, if any.
    pub accepted: Option<(usize, Model, CvResult)>,
    /// Probe rows significant after Holm over the probes.
    pub flagged_probes: Vec<CandidateRow>,
    pub probe_rows: Vec<CandidateRow>,
}

fn row(round: usize, e: &Extra, m: &Model, materials: &[String], ev: Evidence) -> CandidateRow {
    CandidateRow {
        round,
        effect: e.effect().unwrap_or("probe").to_string(),
        form: e.form(),
        accepted: false,
        parameters: term_parameters(m, m.spec.extras.len() - 1, materials),
        evidence: ev,
    }
}

/// Test `entries` (candidate terms) and `probes` against `current`.
#[allow(clippy::too_many_arguments)]
pub fn run_round(
    round: usize,
    current: &Model,
    current_cv: &CvResult,
    entries: &[Extra],
    probes: &[Extra],
    materials: &[String],
    runs: &[RunData],
    opts: &Options,
    fold: &[usize],
) -> Round {
    let all: Vec<&Extra> = entries.iter().chain(probes).collect();
    let fitted: Vec<Model> = all
        .iter()
        .map(|e| current.extend(e, materials, runs, 40))
        .collect();
    let alts: Vec<Alternative> = all
        .iter()
        .zip(&fitted)
        .map(|(e, m)| Alternative {
            spec: m.spec.clone(),
            params: m.params.clone(),
            extra_starts: extra_starts(e),
        })
        .collect();
    let seed = opts.seed ^ (round as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    let reps = lr_replicates(
        &current.spec,
        &current.params,
        &current.fit,
        &alts,
        runs,
        opts.bootstrap,
        seed,
        opts.bootstrap_iterations,
    );
    let lr: Vec<f64> = fitted
        .iter()
        .map(|m| (current.fit.chi2 - m.fit.chi2).max(0.0))
        .collect();
    let nulls: Vec<NullFit> = all
        .iter()
        .zip(&reps)
        .map(|(e, r)| NullFit::from_replicates(r, e.params().len() as f64))
        .collect();
    let p: Vec<f64> = nulls.iter().zip(&lr).map(|(n, l)| n.p_value(*l)).collect();
    let ne = entries.len();
    let p_holm_e = holm(&p[..ne]);
    let p_holm_p = holm(&p[ne..]);
    // the held-out check confirms a term the LR test already found; one-sided 5 % on the paired t
    // over the runs: Student's t with (runs − 1) degrees of freedom
    let t_cv = t_upper_quantile(CV_LEVEL, runs.len().saturating_sub(1) as f64);
    // cross-validate the significant candidates strongest first; the first that also predicts
    // held-out runs better is the one accepted, so weaker ones need no cross-validation
    // "Strongest" is the LR less a Schwarz penalty of ln(n) per extra parameter: when a
    // one-parameter term explains as much as a six-parameter series (rolling resistance against a
    // position force when each direction of motion covers its own stretch of the groove), the
    // simpler physics is named.
    let n_obs: usize = runs
        .iter()
        .map(|r| r.keep.iter().filter(|k| **k).count())
        .sum();
    let penalty = (n_obs.max(2) as f64).ln();
    let strength: Vec<f64> = (0..ne)
        .map(|i| lr[i] - penalty * all[i].params().len() as f64)
        .collect();
    let mut order: Vec<usize> = (0..ne).filter(|i| p_holm_e[*i] < opts.alpha).collect();
    order.sort_by(|a, b| strength[*b].total_cmp(&strength[*a]).then(a.cmp(b)));
    let mut cv_of: Vec<Option<(CvResult, f64)>> = vec![None; ne];
    let mut best: Option<(usize, CvResult)> = None;
    for &i in &order {
        let cv = cross_validate(
            &fitted[i].spec,
            &fitted[i].params,
            runs,
            &fitted[i].fit,
            fold,
            opts.folds,
        );
        let t = paired_t(current_cv, &cv);
        let passes = cv.cv_rms_m < current_cv.cv_rms_m && t > t_cv;
        cv_of[i] = Some((cv.clone(), t));
        if passes {
            best = Some((i, cv));
            break;
        }
    }
    let mut rows = Vec::new();
    for (i, e) in all.iter().enumerate() {
        let is_probe = i >= ne;
        let p_holm = if is_probe {
            p_holm_p[i - ne]
        } else {
            p_holm_e[i]
        };
        let mut ev = Evidence {
            round,
            lr: lr[i],
            extra_params: e.params().len(),
            bootstrap_replicates: reps[i].len(),
            null_mean_lr: nulls[i].mean,
            p_value: p[i],
            p_empirical: empirical_p(&reps[i], lr[i]),
            p_holm,
            cv_paired_t: None,
            cv_rms_m: None,
            decision: String::new(),
        };
        ev.decision = if is_probe {
            if p_holm < opts.alpha {
                "probe flags a mismatch"
            } else {
                "probe: no drift"
            }
            .into()
        } else if p_holm >= opts.alpha {
            "rejected: likelihood ratio within the bootstrap null".into()
        } else if let Some((cv, t)) = &cv_of[i] {
            ev.cv_paired_t = Some(*t);
            ev.cv_rms_m = Some(cv.cv_rms_m);
            if best.as_ref().map(|(b, _)| *b == i).unwrap_or(false) {
                "passes: bootstrap LR test and held-out runs".into()
            } else {
                "rejected: held-out runs do not improve".into()
            }
        } else {
            "significant, not cross-validated: a stronger term passed both tests".into()
        };
        rows.push(row(round, e, &fitted[i], materials, ev));
    }
    let accepted = best.map(|(i, cv)| {
        rows[i].accepted = true;
        rows[i].evidence.decision = "accepted: strongest term passing both tests".into();
        (i, fitted[i].clone(), cv)
    });
    let probe_rows: Vec<CandidateRow> = rows[ne..].to_vec();
    let flagged_probes = probe_rows
        .iter()
        .filter(|r| r.evidence.p_holm < opts.alpha)
        .cloned()
        .collect();
    rows.truncate(ne);
    Round {
        rows,
        accepted,
        flagged_probes,
        probe_rows,
    }
}

/// Build a finding from an accepted row.
pub fn finding(
    row: &CandidateRow,
    before: ModelScore,
    after: ModelScore,
    where_: BTreeMap<String, serde_json::Value>,
) -> Finding {
    Finding {
        effect: row.effect.clone(),
        accepted: row.accepted,
        form: row.form.clone(),
        parameters: row.parameters.clone(),
        evidence: row.evidence.clone(),
        where_,
        baseline: before,
        extended: after,
    }
}

/// Speed reference of the probes: the median |v0| of the runs.
pub fn median_speed(local: &[[f64; N_LOCAL]]) -> f64 {
    let mut v: Vec<f64> = local.iter().map(|l| l[2].abs()).collect();
    if v.is_empty() {
        return 0.0;
    }
    crate::stats::upper_median(&mut v)
}

/// Fold assignment for `runs` given per-run starting values.
pub fn fold_of(runs: &[RunData], local: &[[f64; N_LOCAL]], k: usize) -> Vec<usize> {
    folds(runs, local, k)
}
