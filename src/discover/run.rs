//! The whole discovery on a set of recordings: measure, fit the joint baseline, select terms, report.

use super::candidate::{Extra, Spec, N_LOCAL};
use super::cv::CvResult;
use super::data::{prepare_runs, RunData};
use super::findings::{drift_of, findings_of, model_parameters};
use super::forcemap::ForceMap;
use super::forms;
use super::forward::{fold_of, median_speed, run_round, runs_under, LazyProposals, Round, Setting};
use super::locate::{locate, stalled_note};
use super::model::Model;
use super::perrun::{measure_noise, PerRunFit};
use super::proposal::{propose, wanted_for};
use super::ranges::{Proposals, Ranges, Wanted};
use super::selection::{Accepted, Ctx, Selection, Tied};
use super::Options;
use crate::artifacts::diagnosis::{Diagnosis, ForceMaps, ModelScore, Settings};
use crate::physics::Variable;
use crate::recording::Recording;
use std::collections::BTreeMap;

fn median(mut v: Vec<f64>) -> f64 {
    crate::stats::upper_median(&mut v)
}

fn empty(opts: &Options, runs_used: usize, materials: Vec<String>, note: &str) -> Diagnosis {
    Diagnosis {
        mismatch: false,
        findings: vec![],
        candidates: vec![],
        model: ModelScore::default(),
        model_parameters: BTreeMap::new(),
        baseline_model: ModelScore::default(),
        residuals_before: None,
        residuals_after: None,
        drift: None,
        force_maps: None,
        spectra: vec![],
        runs_used,
        materials,
        settings: settings(opts),
        tracking_drift: None,
        tracking_blur: None,
        note: note.into(),
    }
}

fn settings(opts: &Options) -> Settings {
    Settings {
        bootstrap: opts.bootstrap,
        alpha: opts.alpha,
        folds: opts.folds,
        seed: opts.seed,
        candidates: opts.candidates.clone(),
    }
}

/// The baseline joint model with its starting values from the per-run fits.
fn fit_baseline(
    runs: &mut [RunData],
    materials: &[String],
    opts: &Options,
) -> (Model, Vec<PerRunFit>, Option<super::blur::Blur>) {
    let s = (opts.groove_angle_deg.to_radians() / 2.0).sin();
    let base_spec = Spec {
        n_materials: materials.len(),
        s,
        k: opts.k,
        extras: vec![],
    };
    let base_params = base_spec.global_params(materials);
    let (per_run, blur) = measure_noise(runs, &base_spec, &base_params);
    // each material's median μ, then each material's median T (the global parameters' order)
    let of_material = |m: usize, field: fn(&PerRunFit) -> f64| {
        median(
            runs.iter()
                .zip(&per_run)
                .filter(|(r, _)| r.material == m)
                .map(|(_, f)| field(f))
                .collect(),
        )
    };
    let mut g0: Vec<f64> = (0..materials.len())
        .map(|m| of_material(m, |f| f.mu))
        .collect();
    g0.extend((0..materials.len()).map(|m| of_material(m, |f| f.t_s)));
    let l0: Vec<[f64; N_LOCAL]> = per_run.iter().map(|f| f.local).collect();
    // also from the parameters' own starts: where the baseline cannot follow the runs (runs that
    // come to rest) the per-run μ end at their bounds, and their medians start the joint fit in
    // a basin it does not leave (60 such runs: χ² 28.6 M from them, 15.6 M from these, and only
    // from the second did the rolling resistance's fit reach the truth)
    let prior: Vec<f64> = base_params.iter().map(|p| p.start).collect();
    let baseline = if prior == g0 {
        Model::fit(base_spec, materials, runs, &g0, &l0, 80)
    } else {
        let (from_runs, from_prior) = rayon::join(
            || Model::fit(base_spec.clone(), materials, runs, &g0, &l0, 80),
            || Model::fit(base_spec.clone(), materials, runs, &prior, &l0, 80),
        );
        if from_prior.fit.chi2 < from_runs.fit.chi2 {
            from_prior
        } else {
            from_runs
        }
    };
    (baseline, per_run, blur)
}

impl Ctx<'_> {
    /// With GROOVE_DISCOVER_TRACE set, print what was done and when (stderr only).
    fn trace(&self, what: &str) {
        if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
            eprintln!(
                "discover: {what} at {:.2} s ({} simulations stopped at their step budget so far)",
                self.t0.elapsed().as_secs_f64(),
                crate::physics::budget_stops()
            );
        }
    }

    /// What the residuals of `model` propose (spectra, bumps, force maps, as `wanted`).
    fn proposals(&self, model: &Model, wanted: Wanted) -> Proposals {
        propose(
            &model.spec,
            &model.params,
            &model.fit.global,
            &model.fit.local,
            self.runs,
            self.rg,
            wanted,
            Some((self.fold, self.opts.folds)),
        )
    }

    /// The force maps of `model` alone.
    pub(super) fn force_maps(&self, model: &Model) -> Proposals {
        self.proposals(
            model,
            Wanted {
                z: false,
                t: false,
                bump: false,
                maps: true,
            },
        )
    }

    /// What every round reads.
    pub(super) fn setting(&self) -> Setting<'_> {
        Setting {
            materials: self.materials,
            runs: self.runs,
            opts: self.opts,
            fold: self.fold,
            rg: self.rg,
            say: self.say,
            pairs_allowed: false,
        }
    }

    pub(super) fn cross_validate(&self, model: &Model) -> CvResult {
        model.held_out(self.runs, self.fold, self.opts.folds, self.opts.seed)
    }
}

impl Selection {
    fn new(baseline: &Model, base_cv: &CvResult) -> Selection {
        Selection {
            current: baseline.clone(),
            current_cv: base_cv.clone(),
            accepted: Vec::new(),
            removed: Vec::new(),
            parts: Vec::new(),
            ties: Vec::new(),
            table: Vec::new(),
            last_rows: Vec::new(),
            last_probes: Vec::new(),
            unexplained: Vec::new(),
            maps_before: Vec::new(),
            spectra: Vec::new(),
            round: 0,
        }
    }

    /// The library's candidates not yet accepted: one cause, one term, so a named effect is not
    /// added twice, except position forces of another form (a waviness and a bump).
    fn candidates_left(&self, ctx: &Ctx) -> Vec<Extra> {
        forms::library(&ctx.opts.candidates, ctx.materials.len(), ctx.rg)
            .into_iter()
            .filter(|e| {
                !self.accepted.iter().any(|a| {
                    if e.effect() == Some("position_dependent_force") {
                        a.extra.name() == e.name()
                    } else {
                        Some(a.row.effect.as_str()) == e.effect()
                    }
                })
            })
            .collect()
    }

    /// Make `model` (with its CV) the current one, accepting row `i` of round `r` as `extra`.
    fn accept(&mut self, r: &Round, i: usize, extra: Extra, model: Model, cv: CvResult, ctx: &Ctx) {
        let before = self.current.score(ctx.runs, Some(&self.current_cv));
        let after = model.score(ctx.runs, Some(&cv));
        let mut row = r.rows[i].clone();
        row.evidence.decision = format!(
            "{} (flagged by {} probe(s))",
            row.evidence.decision,
            r.flagged_probes.len()
        );
        self.accepted.push(Accepted {
            row,
            before,
            after,
            probes_after: vec![],
            null: r.nulls[i].clone(),
            extra,
        });
        self.current = model;
        self.current_cv = cv;
    }

    /// Accept row `j` of round `r` as `extra`, fitted together with the term just accepted
    /// (already in the current model): the two share their scores.
    fn accept_partner(&mut self, r: &Round, j: usize, extra: Extra) {
        let first = self.accepted.last().expect("the pair's first term");
        let (before, after) = (first.before.clone(), first.after.clone());
        let mut row = r.rows[j].clone();
        row.evidence.decision = format!(
            "{} (flagged by {} probe(s))",
            row.evidence.decision,
            r.flagged_probes.len()
        );
        self.accepted.push(Accepted {
            row,
            before,
            after,
            probes_after: vec![],
            null: r.nulls[j].clone(),
            extra,
        });
    }

    /// Backward elimination: drop the weakest earlier term whose likelihood ratio, given the
    /// others, is within its own bootstrap null; repeat until every term is needed.
    fn eliminate(&mut self, ctx: &Ctx) {
        loop {
            if self.accepted.len() < 2 {
                return;
            }
            let last = self.accepted.len() - 1;
            let mut weakest: Option<(usize, f64, f64, Model)> = None;
            for (a, acc) in self.accepted.iter().enumerate().take(last) {
                let Some(i) = self
                    .current
                    .spec
                    .extras
                    .iter()
                    .position(|e| *e == acc.extra)
                else {
                    continue;
                };
                let without = self.current.without(i, ctx.materials, ctx.runs, 40);
                let lr = (without.fit.chi2 - self.current.fit.chi2).max(0.0);
                let p = acc.null.p_value(lr);
                if p >= ctx.opts.alpha && weakest.as_ref().map(|w| p > w.2).unwrap_or(true) {
                    weakest = Some((a, lr, p, without));
                }
            }
            let Some((a, lr, p, without)) = weakest else {
                return;
            };
            let mut gone = self.accepted.remove(a);
            gone.row.accepted = false;
            gone.row.evidence.decision = format!(
                "removed by backward elimination: with the later terms its likelihood ratio is {lr:.1} (p = {p:.3}), within its bootstrap null"
            );
            self.removed.push(gone);
            self.current = without;
            self.current_cv = ctx.cross_validate(&self.current);
        }
    }
}

/// Forward selection from the baseline: each round tests the candidates left, accepts the
/// strongest passing both tests and re-tests the earlier terms; it stops when none passes, when
/// the library is exhausted or at `max_terms`.
fn select_terms(baseline: &Model, base_cv: &CvResult, ctx: &Ctx) -> Selection {
    let vref = median_speed(&baseline.fit.local);
    let probes = forms::probes(vref);
    let mut sel = Selection::new(baseline, base_cv);
    loop {
        sel.round += 1;
        let entries = sel.candidates_left(ctx);
        if entries.is_empty() {
            break;
        }
        let refs: Vec<&Extra> = entries.iter().collect();
        let mut wanted = wanted_for(&refs);
        wanted.maps = sel.round == 1;
        if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
            eprintln!("round {} starts", sel.round);
        }
        (ctx.say)(&format!(
            "round {}: screening {} candidates against {} noise replicates",
            sel.round,
            entries.len(),
            super::screen::REPLICATES.max(ctx.opts.bootstrap)
        ));
        // the first round's spectra and maps are reported, so they are made at once; a later
        // round's proposals only start a proposed form fitted in full, if any
        let props = if sel.round == 1 {
            let props = ctx.proposals(&sel.current, wanted);
            sel.maps_before = props.maps.clone();
            sel.spectra = props.z.iter().chain(props.t.iter()).cloned().collect();
            ctx.trace("proposed");
            LazyProposals::ready(props)
        } else {
            let current = &sel.current;
            LazyProposals::new(move || ctx.proposals(current, wanted))
        };
        let mut r = run_round(
            sel.round,
            &sel.current,
            &sel.current_cv,
            &entries,
            &probes,
            &props,
            &Setting {
                pairs_allowed: sel.accepted.len() + 2 <= ctx.opts.max_terms,
                ..ctx.setting()
            },
        );
        drop(props);
        sel.table.extend(r.rows.iter().cloned());
        sel.table.extend(r.probe_rows.iter().cloned());
        if let Some(last) = sel.accepted.last_mut() {
            last.probes_after = r.probe_rows.clone();
        }
        match r.accepted.take() {
            Some((i, model, cv)) if sel.accepted.len() < ctx.opts.max_terms => {
                sel.accept(&r, i, entries[i].clone(), model, cv, ctx);
                let before = sel.accepted.last().map(|a| a.before.clone());
                for t in std::mem::take(&mut r.tied) {
                    sel.ties.push(Tied {
                        with: entries[i].clone(),
                        alt: Accepted {
                            row: r.rows[t.row].clone(),
                            before: before.clone().expect("just accepted"),
                            after: t.after,
                            probes_after: vec![],
                            null: r.nulls[t.row].clone(),
                            extra: entries[t.row].clone(),
                        },
                        start: t.start,
                    });
                }
                if let Some(j) = r.partner {
                    sel.accept_partner(&r, j, entries[j].clone());
                }
                sel.last_probes = r.probe_rows;
                sel.eliminate(ctx);
            }
            _ => {
                sel.last_rows = r.rows;
                sel.unexplained = r.flagged_probes;
                sel.last_probes = r.probe_rows;
                break;
            }
        }
        if sel.accepted.len() >= ctx.opts.max_terms {
            break;
        }
    }
    sel
}

/// The nonparametric fallback: structure in a force map that no named form explained is
/// modelled by a spline in the map's variable and tested like a candidate. Returns the accepted
/// spline, if any, and the force maps of the final model.
fn model_what_is_left(sel: &mut Selection, ctx: &Ctx) -> (Option<Accepted>, Vec<ForceMap>) {
    if !ctx.opts.nonparametric {
        return (None, Vec::new());
    }
    let props = ctx.force_maps(&sel.current);
    let strongest = props
        .maps
        .iter()
        .filter(|m| m.spline.is_some() && m.cv_gain > 0.0)
        .max_by(|a, b| a.cv_gain.total_cmp(&b.cv_gain))
        .cloned();
    let Some(map) = strongest else {
        return (None, props.maps);
    };
    let var = match map.variable.as_str() {
        "z" => Variable::Z,
        "v" => Variable::V,
        _ => Variable::T,
    };
    let Some(spline) = forms::Spline::on(&map, var).map(Extra::from) else {
        return (None, props.maps);
    };
    sel.round += 1;
    let maps = props.maps.clone();
    let r = run_round(
        sel.round,
        &sel.current,
        &sel.current_cv,
        std::slice::from_ref(&spline),
        &[],
        &LazyProposals::ready(props),
        &ctx.setting(),
    );
    sel.table.extend(r.rows.iter().cloned());
    let Some((i, model, cv)) = r.accepted else {
        return (None, maps);
    };
    let before = sel.current.score(ctx.runs, Some(&sel.current_cv));
    let after = model.score(ctx.runs, Some(&cv));
    let mut row = r.rows[i].clone();
    row.evidence.decision = format!(
        "accepted as a model of what no named form explains: the force map in {} shows structure (held-out χ² drop {:.1})",
        map.variable, map.cv_gain
    );
    let accepted = Accepted {
        row,
        before,
        after,
        probes_after: vec![],
        null: r.nulls[i].clone(),
        extra: spline,
    };
    sel.current = model;
    sel.current_cv = cv;
    (Some(accepted), ctx.force_maps(&sel.current).maps)
}

/// Run the whole discovery on `recordings` (single runs are used; collision runs are skipped):
/// measure each run's noise and fit the joint baseline, select terms, model what is left with the
/// force map, then report the findings, the drift and the residuals before and after.
pub fn discover(recordings: &[Recording], opts: &Options) -> Diagnosis {
    discover_reporting(recordings, opts, &|_| {})
}

/// `discover`, saying each step as it starts through `say` (e.g. `round 2: screening 9
/// candidates against 60 noise replicates`); what is said never enters the diagnosis.
pub fn discover_reporting(
    recordings: &[Recording],
    opts: &Options,
    say: &(dyn Fn(&str) + Sync),
) -> Diagnosis {
    let t0 = std::time::Instant::now();
    let (mut runs, materials) = prepare_runs(recordings, opts.min_frames);
    if runs.len() < 2 * opts.folds.max(2) {
        return empty(
            opts,
            runs.len(),
            materials,
            &format!(
                "discovery did not run: {} single run{} with at least {} frames, fewer than the {} a joint model with {}-fold cross-validation needs; nothing was tested, so nothing can be said about missing physics",
                runs.len(),
                if runs.len() == 1 { "" } else { "s" },
                opts.min_frames,
                2 * opts.folds.max(2),
                opts.folds
            ),
        );
    }
    say(&format!(
        "fitting the baseline model to {} runs",
        runs.len()
    ));
    let (baseline, per_run, blur) = fit_baseline(&mut runs, &materials, opts);
    let fold = fold_of(&runs, &baseline.fit.local, opts.folds);
    let rg = Ranges::of(&runs);
    let ctx = Ctx {
        runs: &runs,
        materials: &materials,
        fold: &fold,
        rg: &rg,
        opts,
        t0,
        say,
    };
    ctx.trace("baseline fitted");
    say("cross-validating the baseline");
    let base_cv = ctx.cross_validate(&baseline);
    ctx.trace("baseline cross-validated");
    let mut sel = select_terms(&baseline, &base_cv, &ctx);
    ctx.trace("rounds done");
    super::ties::redecide(&mut sel, &ctx);
    ctx.trace("ties decided again");
    say("mapping what is left (force maps in z, v, t and phase)");
    let (fallback, maps_after) = model_what_is_left(&mut sel, &ctx);
    ctx.trace("fallback done");
    say("trying a map in z and in v in place of the named forces of each");
    let (fallback, maps_after) =
        super::consolidate::consolidate(&mut sel, fallback, maps_after, &ctx);
    ctx.trace("maps in place of named forms tried");
    say("residuals and drift before and after");
    let (residuals_before, _) = locate(&baseline.spec, &baseline.fit, &runs, &materials);
    let (residuals_after, stalled) = locate(&sel.current.spec, &sel.current.fit, &runs, &materials);
    ctx.trace("residuals located");
    let drift = drift_of(&sel.current, &per_run, &ctx);
    ctx.trace("drift done");
    let final_score = sel.current.score(&runs, Some(&sel.current_cv));
    let mut findings = findings_of(
        &sel,
        fallback.as_ref(),
        [&residuals_before, &residuals_after],
        &final_score,
        &ctx,
    );
    say("testing whether the particles differ");
    // a spread that tracks the runs' speed or direction is physics the model lacks, which the
    // drift probes flag; particles that differ are independent of how hard they were kicked
    // the slow noise under the final model: what its terms explain is no longer noise
    let runs_final = runs_under(&sel.current, &runs).unwrap_or_else(|| runs.clone());
    let drift_left = !sel.unexplained.is_empty()
        || sel
            .last_probes
            .iter()
            .any(|p| p.evidence.p_holm < opts.alpha);
    if let Some(f) = particle_finding(
        &sel.current,
        &runs_final,
        &materials,
        opts,
        &final_score,
        drift_left,
    ) {
        // accepted findings come first: after them, or first of them when accepted
        let at = findings.iter().take_while(|f| f.accepted).count();
        findings.insert(at, f);
    }
    ctx.trace("particles checked");
    // every finding says where its physics enters, from its effect (the unexplained one too)
    for f in &mut findings {
        if let Some(e) = crate::artifacts::diagnosis::Effect::from_id(&f.effect) {
            f.where_
                .entry("place".to_string())
                .or_insert_with(|| serde_json::json!(e.place()));
        }
    }
    let any_accepted = findings.iter().any(|f| f.accepted);
    Diagnosis {
        mismatch: any_accepted || !sel.unexplained.is_empty(),
        findings,
        model: final_score,
        model_parameters: model_parameters(&sel.current),
        baseline_model: baseline.score(&runs, Some(&base_cv)),
        residuals_before: Some(residuals_before),
        residuals_after: Some(residuals_after),
        drift: Some(drift),
        force_maps: Some(ForceMaps {
            before: sel.maps_before,
            after: maps_after,
        }),
        spectra: sel.spectra,
        candidates: sel.table,
        runs_used: runs.len(),
        materials,
        settings: settings(opts),
        tracking_drift: tracking_drift(&runs_final),
        tracking_blur: blur.map(|b| crate::artifacts::diagnosis::TrackingBlur {
            noise_per_speed_s: b.gain_s,
        }),
        note: stalled_note(stalled, runs.len()),
    }
}

/// The slow tracking noise the runs carry, its correlation time at their median frame rate.
fn tracking_drift(runs: &[RunData]) -> Option<crate::artifacts::diagnosis::TrackingDrift> {
    let slow = runs.first()?.slow;
    let fps = median(runs.iter().map(|r| r.fps).collect());
    (slow.kappa > 0.0).then(|| crate::artifacts::diagnosis::TrackingDrift {
        variance_ratio: slow.kappa,
        time_constant_s: -1.0 / slow.rho.ln() / fps,
        runs: runs.len(),
        runs_left_out: slow.left_out,
        line_hz: (slow.line.0 * fps, slow.line.1 * fps),
    })
}

/// The finding of `particles::check` on the final model: accepted when the particles differ,
/// a row saying so otherwise (None when the check cannot run: fewer than 4 runs of a material,
/// or a friction law per material that one run's own fit cannot carry).
fn particle_finding(
    current: &Model,
    runs: &[RunData],
    materials: &[String],
    opts: &Options,
    score: &ModelScore,
    drift_left: bool,
) -> Option<crate::artifacts::diagnosis::Finding> {
    if materials.len() > 1 && current.spec.extras.iter().any(|e| e.per_material()) {
        return None;
    }
    let c = super::particles::check(
        current,
        runs,
        materials,
        opts.alpha,
        opts.seed ^ 0x005E_ED0F_9A27,
    )?;
    let mut parameters = BTreeMap::new();
    let est = crate::artifacts::Estimate::new;
    for s in &c.spreads {
        let m = &s.material;
        parameters.insert(format!("mu_{m}"), est(s.mu, f64::NAN));
        parameters.insert(format!("t_s_{m}"), est(s.t_s, f64::NAN));
        parameters.insert(format!("n_runs_{m}"), est(s.n_runs as f64, 0.0));
        parameters.insert(format!("mu_sd_{m}"), est(s.mu_sd, f64::NAN));
        parameters.insert(format!("t_sd_s_{m}"), est(s.t_sd, f64::NAN));
        parameters.insert(format!("mu_se_run_{m}"), est(s.mu_se, f64::NAN));
        parameters.insert(format!("t_se_run_s_{m}"), est(s.t_se, f64::NAN));
        // the spreads relative to the material's values; a drag time goes as the radius squared
        // (a viscous drag on a sphere of the same steel: m/(6πηR) ∝ R²), so radii that differ
        // by δR/R give drag times that differ by twice that
        let (mu_rel, t_rel) = (s.mu_sd / s.mu, s.t_sd / s.t_s);
        parameters.insert(format!("mu_sd_rel_{m}"), est(mu_rel, f64::NAN));
        parameters.insert(format!("t_sd_rel_{m}"), est(t_rel, f64::NAN));
        parameters.insert(format!("size_sd_rel_{m}"), est(0.5 * t_rel, f64::NAN));
    }
    // the drift probes' null is the noise alone: particles that differ make a per-run slope
    // look significant against it, so a drift counts only beyond the runs' scatter
    let drift_left = drift_left && c.drift_beyond_scatter;
    let follows_position = c.position_p < opts.alpha;
    let decision = if c.differ && follows_position {
        format!(
            "rejected: the runs' own mu and T take up {:.2}x what the noise gives them (p = {:.2e}), but runs that slide over the same stretch of groove take the same values (p = {:.2e}): a friction or a force that varies along the groove, not particles that differ",
            c.f, c.p_value, c.position_p
        )
    } else if c.differ && drift_left {
        format!(
            "rejected: the runs' own mu and T take up {:.2}x what the noise gives them (p = {:.2e}), but they drift with the runs' speed or direction beyond their scatter from run to run: physics the model lacks, not particles that differ",
            c.f, c.p_value
        )
    } else if c.differ {
        format!(
            "accepted: the runs' own mu and T take up {:.2}x what the noise gives them while what they leave is {:.2}x the noise's (p = {:.2e})",
            c.f, c.residual_ratio, c.p_value
        )
    } else if c.p_value < opts.alpha && c.wander_ratio > super::particles::WANDER_LIMIT {
        format!(
            "undecided: the runs' own mu and T take up {:.2}x what the noise gives them (p = {:.2e}), but the runs' noise wanders over many frames ({:.2}x the measured noise in slow shapes mu and T cannot make), and a run's own mu and T take up such a noise as well: these data cannot tell particles that differ from a wandering tracker",
            c.f, c.p_value, c.wander_ratio
        )
    } else if c.p_value < opts.alpha && c.f < super::particles::MIN_RATIO {
        format!(
            "rejected: the runs' own mu and T take up {:.2}x what the noise gives them (p = {:.2e}), less than the {:.1}x a difference between particles must show",
            c.f, c.p_value, super::particles::MIN_RATIO
        )
    } else if c.p_value < opts.alpha {
        format!(
            "rejected: the runs' own mu and T take up more than noise ({:.2}x, p = {:.2e}), but leave {:.2}x the noise: something the equations lack, not particles that differ",
            c.f, c.p_value, c.residual_ratio
        )
    } else {
        format!(
            "rejected: the runs' own mu and T take up {:.2}x what the noise gives them (p = {:.2}): the particles agree within their noise",
            c.f, c.p_value
        )
    };
    let mut w = BTreeMap::new();
    w.insert("place".to_string(), serde_json::json!("particles"));
    w.insert(
        "residual_ratio".to_string(),
        serde_json::json!(c.residual_ratio),
    );
    w.insert(
        "wander_ratio".to_string(),
        serde_json::json!(c.wander_ratio),
    );
    w.insert(
        "position_order_p".to_string(),
        serde_json::json!(c.position_p),
    );
    Some(crate::artifacts::diagnosis::Finding {
        effect: "particle_differences".into(),
        accepted: c.differ && !drift_left && !follows_position,
        form: "mu (friction) and T (drag) of each particle scatter about the material's".into(),
        parameters,
        evidence: crate::artifacts::diagnosis::Evidence {
            round: 0,
            lr: c.lr,
            extra_params: 2 * runs.len().saturating_sub(materials.len()),
            bootstrap_replicates: 200,
            null_mean_lr: c.lr_null_mean,
            p_value: c.p_value,
            p_empirical: c.p_value,
            p_holm: c.p_value,
            cv_paired_t: None,
            cv_rms_m: None,
            decision,
            detection_limit: None,
        },
        where_: w,
        baseline: score.clone(),
        extended: score.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::diagnosis::CandidateRow;
    use crate::discover::forms::{GrooveTilt, QuadraticDrag, RollingResistance, SaturatingDrag};
    use crate::discover::null_distribution::NullFit;
    use std::collections::BTreeMap;
    use std::sync::Mutex;

    /// The recordings of `tests/fixtures/truths/null_small.toml` (16 runs, nothing missing).
    fn null_small() -> Vec<Recording> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/truths/null_small.toml");
        let truth = crate::synth::Truth::parse(&std::fs::read_to_string(path).unwrap()).unwrap();
        let tables = crate::synth::synth_tables(&truth);
        let mut files = BTreeMap::new();
        files.insert("runs.csv".to_string(), tables.runs_csv.into_bytes());
        files.insert(
            "trajectories.csv".to_string(),
            tables.trajectories_csv.into_bytes(),
        );
        crate::ingest::ingest(&files, &crate::ingest::IngestParams::default())
            .unwrap()
            .recordings
    }

    #[test]
    fn too_few_runs_say_so_with_the_count_in_words() {
        let recs = null_small();
        let singles: Vec<Recording> = recs
            .into_iter()
            .filter(|r| r.info.experiment == crate::recording::Experiment::Single)
            .collect();
        for (n, want) in [(1, "1 single run with"), (3, "3 single runs with")] {
            let d = discover(&singles[..n], &Options::default());
            assert!(d.note.contains(want), "{n} runs: {}", d.note);
        }
    }

    /// The single runs of the small null, their baseline fitted, and the runs prepared for the
    /// screen under it.
    fn null_small_baseline() -> (Vec<RunData>, Model, Vec<super::super::response::Prepared>) {
        let opts = Options::default();
        let (mut runs, materials) = prepare_runs(&null_small(), opts.min_frames);
        let (baseline, _, _) = fit_baseline(&mut runs, &materials, &opts);
        let prep = super::super::candidate::prepare(
            &baseline.spec,
            &baseline.params,
            &baseline.fit.global,
            &baseline.fit.local,
            &runs,
        );
        (runs, baseline, prep)
    }

    /// A named term's null law is computed from its columns and the noise model, and is the law
    /// of its replicates: over 3,000 replicates of the baseline's noise, each named term's and
    /// probe's mean statistic is the law's (within 4 standard errors) and as many replicates
    /// exceed the law's 95 % and 99 % points as should (within 4 binomial standard deviations),
    /// one-sided (the drags and the resistance: 0 half the time) or not (the tilt, the probes).
    #[test]
    fn a_named_terms_computed_null_is_the_law_of_its_replicates() {
        let (mut runs, baseline, prep) = null_small_baseline();
        let vref = median_speed(&baseline.fit.local);
        let mut named: Vec<Extra> = vec![
            QuadraticDrag.into(),
            SaturatingDrag.into(),
            RollingResistance.into(),
            GrooveTilt.into(),
        ];
        named.extend(forms::probes(vref));
        let refs: Vec<&Extra> = named.iter().collect();
        let b = 3000;
        // as measured (white), then as if every run's noise had a lag-1 correlation of 0.6
        for rho in [None, Some(0.6)] {
            if let Some(rho) = rho {
                runs.iter_mut()
                    .for_each(|r| r.fast = super::super::noise_model::Fast::ar1(rho));
            }
            check_named_laws(&named, &refs, &baseline, &runs, &prep, b);
        }
    }

    /// A searched form's grid scanned in blocks (each reading a run's replicates once) gives
    /// every trial the numbers of that trial alone, to the bit: bumps over the grid the
    /// localized form searches, on the baseline of a small null.
    #[test]
    fn a_scan_in_blocks_gives_each_trial_its_own_numbers() {
        use super::super::ranges::{bump_column, bump_trials};
        use super::super::screen_sums::{coherent, coherent_scan, Vectors};
        let (runs, _, prep) = null_small_baseline();
        let v = Vectors::new(&prep, &runs, 9, 5);
        let rg = Ranges::of(&runs);
        let trials = bump_trials(&rg, 0.0, f64::INFINITY);
        assert!(trials.len() > 20, "{} trials", trials.len());
        let cols = |p: &super::super::response::Prepared, &(c, w): &(f64, f64)| {
            bump_column(p, c, w).map(|x| vec![x])
        };
        // two columns a trial too (a bump and one twice as wide), as a wave's sin and cos
        let cols2 = |p: &super::super::response::Prepared, &(c, w): &(f64, f64)| {
            Some(vec![bump_column(p, c, w)?, bump_column(p, c, 2.0 * w)?])
        };
        let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
        for (q, reps) in [(1, 0..10), (1, 4..9), (2, 0..10), (2, 3..10)] {
            let cols = |p: &super::super::response::Prepared, t: &(f64, f64)| match q {
                1 => cols(p, t),
                _ => cols2(p, t),
            };
            let scanned = coherent_scan(&prep, &v, q, reps.clone(), &trials, cols);
            assert_eq!(scanned.len(), trials.len());
            for (t, got) in trials.iter().zip(&scanned) {
                let alone = coherent(&prep, &v, q, reps.clone(), &[], |p| cols(p, t));
                match (alone, got) {
                    (Some(a), Some(g)) => {
                        assert_eq!(bits(&a.0), bits(&g.0), "{t:?}");
                        assert_eq!(bits(&a.1), bits(&g.1), "{t:?}");
                        assert_eq!(bits(&a.2), bits(&g.2), "{t:?}");
                    }
                    (None, None) => {}
                    (a, g) => panic!("{t:?}: alone {a:?}, scanned {g:?}"),
                }
            }
        }
    }

    /// The frequency scan the two forms periodic in time share gives each the numbers of its
    /// own pass, to the bit: the coherent sums solved as `coherent` solves them alone, and each
    /// replicate's Σ|b| over runs as the runs' own projections sum, with the data in the batch
    /// and out of it; a second request for the same batch is the first one's scan.
    #[test]
    fn the_shared_time_scan_gives_each_form_its_own_numbers() {
        use super::super::screen_sums::{coherent, dot, dot2, Vectors};
        use super::super::spectral::f_grid;
        use super::super::time_scan::TimeMemo;
        use std::f64::consts::TAU;
        let (runs, _, prep) = null_small_baseline();
        let v = Vectors::new(&prep, &runs, 9, 5);
        let rg = Ranges::of(&runs);
        let grid: Vec<f64> = f_grid(rg.duration_s, rg.f_max_hz)
            .into_iter()
            .step_by(7)
            .collect();
        assert!(grid.len() > 20, "{} frequencies", grid.len());
        let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
        let memo = TimeMemo::default();
        for reps in [0..10, 3..10] {
            let scan = memo.get(&prep, &v, reps.clone(), &grid);
            assert!(std::sync::Arc::ptr_eq(
                &scan,
                &memo.get(&prep, &v, reps.clone(), &grid)
            ));
            assert_eq!(scan.grid, grid[..scan.grid.len()]);
            assert_eq!(scan.at.len(), scan.grid.len());
            for (&f, at) in scan.grid.iter().zip(&scan.at) {
                let cols = |p: &super::super::response::Prepared| {
                    let (rs, rc) = p.track.respond_time(TAU * f);
                    Some(vec![p.column(rs), p.column(rc)])
                };
                let alone = coherent(&prep, &v, 2, reps.clone(), &[], cols).map(|a| bits(&a.0));
                assert_eq!(
                    alone,
                    at.coherent.solve(&v, &[]).map(|g| bits(&g.0)),
                    "{f} Hz"
                );
                let (mut sb, mut data) = (vec![0.0; reps.len()], 0.0);
                for (p, yr) in prep.iter().zip(&v.y) {
                    let c = cols(p).unwrap();
                    if 0.5 * (dot(&c[0], &c[0]) + dot(&c[1], &c[1])) > 0.0 {
                        for (s, y) in sb.iter_mut().zip(&yr[reps.clone()]) {
                            let (bs, bc) = dot2(&c[0], &c[1], y);
                            *s += bs.hypot(bc);
                        }
                        let (bs, bc) = dot2(&c[0], &c[1], &yr[0]);
                        data += bs.hypot(bc);
                    }
                }
                assert_eq!(bits(&sb), bits(&at.per_run), "{f} Hz");
                let data_out = if reps.start == 0 { 0.0 } else { data };
                assert_eq!(data_out.to_bits(), at.per_run_data.to_bits(), "{f} Hz");
            }
        }
    }

    /// The time scan stops where a force at the forms' amplitude bound would stand below two
    /// standard errors: at every frequency asked beyond its grid the amplitude's error, from
    /// the runs' own responses, is above half the bound; at the last frequency of the coarse
    /// pass it kept, at most half; at its most sensitive frequency far below.
    #[test]
    fn the_time_scan_stops_where_no_force_could_be_seen() {
        use super::super::response::dot;
        use super::super::screen_sums::Vectors;
        use super::super::spectral::f_grid;
        use super::super::time_scan::{TimeMemo, AMPLITUDE_BOUND_MPS2, COARSE_STEP};
        use std::f64::consts::TAU;
        let (runs, _, prep) = null_small_baseline();
        let v = Vectors::new(&prep, &runs, 3, 5);
        let rg = Ranges::of(&runs);
        let grid = f_grid(rg.duration_s, rg.f_max_hz);
        let scan = TimeMemo::default().get(&prep, &v, 0..4, &grid);
        let se = |f: f64| {
            let a: f64 = prep
                .iter()
                .map(|p| {
                    let (rs, rc) = p.track.respond_time(TAU * f);
                    let (xs, xc) = (p.column(rs), p.column(rc));
                    0.5 * (dot(&xs, &xs) + dot(&xc, &xc))
                })
                .sum();
            1.0 / a.sqrt()
        };
        let kept = scan.grid.len();
        assert!(
            kept > 10 && kept < grid.len(),
            "{kept} of {} kept",
            grid.len()
        );
        for &f in grid[kept..].iter().step_by(5) {
            assert!(2.0 * se(f) > AMPLITUDE_BOUND_MPS2, "{f} Hz: se {}", se(f));
        }
        assert!(20.0 * se(scan.grid[kept / 4]) < AMPLITUDE_BOUND_MPS2);
        // and not before: the last frequency of the coarse pass that was kept resolves the bound
        let last_seen = grid[kept - 1 - COARSE_STEP];
        assert!(
            2.0 * se(last_seen) <= AMPLITUDE_BOUND_MPS2,
            "{last_seen} Hz: se {}",
            se(last_seen)
        );
    }

    /// The check of `a_named_terms_computed_null_is_the_law_of_its_replicates` at the runs'
    /// noise as they carry it.
    fn check_named_laws(
        named: &[Extra],
        refs: &[&Extra],
        baseline: &Model,
        runs: &[RunData],
        prep: &[super::super::response::Prepared],
        b: usize,
    ) {
        use super::super::detection::critical_lr;
        use super::super::screen::{screen, Control};
        let screened = screen(
            refs,
            baseline,
            runs,
            prep,
            &Ranges::of(runs),
            &Control {
                replicates: b,
                seed: 11,
                alpha: 0.01,
                say: &|_: &str| {},
            },
        );
        for (e, s) in named.iter().zip(&screened) {
            let s = s.as_ref().expect("every named term is screened");
            let exact = s.exact.as_ref().expect("a named term's law is computed");
            let law = NullFit::exact(exact, b);
            let reps = &s.replicates;
            assert_eq!(reps.len(), b);
            let mean = reps.iter().sum::<f64>() / b as f64;
            let se = (law.var / b as f64).sqrt();
            assert!(
                (mean - law.mean).abs() < 4.0 * se,
                "{} (ρ {}): replicates' mean {mean:.4}, law's {:.4} ± {se:.4}",
                e.form(),
                runs[0].fast.rho,
                law.mean
            );
            for level in [0.05, 0.01] {
                let c = critical_lr(&law, level);
                let above = reps.iter().filter(|x| **x > c).count() as f64 / b as f64;
                let sd = (level * (1.0 - level) / b as f64).sqrt();
                assert!(
                    (above - level).abs() < 4.0 * sd,
                    "{} (ρ {}): {above:.4} of the replicates above the law's {level} point {c:.3}",
                    e.form(),
                    runs[0].fast.rho
                );
            }
        }
    }

    /// With the law computed, the count of replicates changes only the empirical p-value.
    #[test]
    fn a_named_terms_p_value_does_not_depend_on_the_replicates_drawn() {
        let recs = null_small();
        let opts = |bootstrap| Options {
            bootstrap,
            candidates: [
                "velocity_dependent_drag",
                "rolling_resistance",
                "groove_tilt",
            ]
            .map(String::from)
            .to_vec(),
            nonparametric: false,
            seed: 5,
            ..Options::default()
        };
        let round_1 = |d: &Diagnosis| -> Vec<CandidateRow> {
            d.candidates
                .iter()
                .filter(|c| c.evidence.round == 1)
                .cloned()
                .collect()
        };
        let (few, many) = (
            round_1(&discover(&recs, &opts(60))),
            round_1(&discover(&recs, &opts(600))),
        );
        // quadratic and saturating drag, resistance, tilt and the three probes
        assert_eq!(few.len(), 7);
        for (f, m) in few.iter().zip(&many) {
            assert_eq!(f.form, m.form);
            assert_eq!(f.evidence.lr, m.evidence.lr, "{}", f.form);
            assert_eq!(f.evidence.p_value, m.evidence.p_value, "{}", f.form);
            assert_eq!(
                (
                    f.evidence.bootstrap_replicates,
                    m.evidence.bootstrap_replicates
                ),
                (60, 600)
            );
        }
    }

    /// The progress line hears each round, each candidate of the screen with its replicates
    /// done, and the searched forms' batches; the diagnosis is the same with or without it.
    #[test]
    fn the_progress_says_round_candidate_and_replicates() {
        let recs = null_small();
        let opts = Options {
            bootstrap: 12,
            folds: 4,
            seed: 3,
            ..Options::default()
        };
        let said = Mutex::new(Vec::<String>::new());
        let d = discover_reporting(&recs, &opts, &|w: &str| {
            said.lock().unwrap().push(w.to_string())
        });
        let said = said.into_inner().unwrap();
        assert!(d.note.is_empty(), "discovery ran: {}", d.note);
        let has = |s: &str| said.iter().any(|w| w.contains(s));
        assert!(has("round 1: screening"), "{said:?}");
        assert!(has("round 1: candidate 1/"), "{said:?}");
        assert!(has("periodic in time: replicates 0/60 done"), "{said:?}");
        assert!(has("groove tilt") || has("tilt: 60 replicates"), "{said:?}");
        let again = serde_json::to_vec(&discover(&recs, &opts)).unwrap();
        assert_eq!(serde_json::to_vec(&d).unwrap(), again);
    }
}
