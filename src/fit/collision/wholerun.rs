//! Whole-run pair fits: every collision run of a material simulated from its kick with the
//! event-driven two-particle model (`physics::simulate_pair`: every impact, first and secondary,
//! and the sliding and rolling of both particles between them), fitted to both tracks at once.
//!
//! Shared per material: μ_pg, the drag (saturating v/(T0 + T'|v|), linear, or held at the single
//! runs' physics), μ_pp, and one restitution law C(v) per setup (a candidate form's two slots
//! fitted, or the law discovery accepted: a named form held as given, a map with its node
//! values refitted; μ_pp may carry discovery's dependence on the slip speed, μ_pp then being its
//! value at the reference slip speed). Per run: the
//! striker's start position and kick speed, the gap to the target (rolling setup; the contact
//! setup starts touching) and the kick time within the frame before the first sample. The
//! simulator locates every phase switch and impact as an event, so positions are continuous in
//! the parameters and the finite-difference derivatives of `lsq::block` see the events move, not
//! jump.

use super::detect::{median, noise_scale_m, robust_line};
use super::model::TrackData;
use crate::artifacts::collision_summary::LawForm;
use crate::lsq::block::{minimize_blocks, BlockProblem, BlockResult};
use crate::lsq::lm::ParamSpec;
use crate::lsq::lm::{Scale, Settings};
use crate::physics::{
    simulate_pair, Friction, FrictionVariation, Groove, Model, PairForce, PairParams,
    PairTrajectory, Restitution, SlipFriction, State, Term, MAX_MAP_NODES,
};
use crate::recording::{Recording, Setup};

impl LawForm {
    /// The law from its two parameter slots (a, b): constant (c, —), linear (c0, slope),
    /// saturating (c_inf, ln v_ref). A law held from discovery has no slots: `FitSpec` holds it
    /// itself (`held_laws`) and never asks here; asked, it is undetermined (C NaN, so a fit
    /// that lost it misfits every impact instead of simulating some other law).
    pub fn law(self, a: f64, b: f64) -> Restitution {
        match self {
            LawForm::Constant => Restitution::Constant(a),
            LawForm::Linear => Restitution::Linear {
                c0: a,
                slope_per_mps: b,
            },
            LawForm::Saturating => Restitution::SpeedDependent {
                c0: a,
                v_ref_mps: b.exp(),
            },
            LawForm::FromDiscovery => Restitution::Constant(f64::NAN),
        }
    }

    fn specs(self) -> [ParamSpec; 2] {
        let spec = |start: f64, lower: f64, upper: f64, step: f64| ParamSpec {
            start,
            lower,
            upper,
            step,
        };
        match self {
            LawForm::Constant => [spec(0.7, 0.0, 1.0, 1e-5), spec(0.0, 0.0, 0.0, 1e-5)],
            LawForm::Linear => [spec(0.95, 0.0, 1.2, 1e-5), spec(1.0, -5.0, 50.0, 1e-4)],
            LawForm::Saturating => [
                spec(0.5, 0.0, 1.0, 1e-5),
                spec(0.08f64.ln(), 1e-3f64.ln(), 3.0f64.ln(), 1e-5),
            ],
            // no slots: held at 0
            LawForm::FromDiscovery => [spec(0.0, 0.0, 0.0, 1e-5), spec(0.0, 0.0, 0.0, 1e-5)],
        }
    }
}

/// How drag enters the shared physics.
#[derive(Debug, Clone, PartialEq)]
pub enum DragSpec {
    /// −v/(T0 + T'|v|), both fitted (T' ≥ 0; T' = 0 is linear drag).
    Saturating,
    /// −v/T, fitted.
    Linear,
    /// These terms, held (the physics the single runs were found to follow); μ_pg stays fitted.
    Held(Vec<Term>),
    /// −v/(T0 + T'|v|) fitted, beside these terms held (the single runs' forces other than
    /// drag: a tilt, a resistance, a wave or a bump act on the pairs whatever their drag).
    SaturatingWith(Vec<Term>),
}

/// One collision run prepared for the whole-run fit (lab frame).
#[derive(Debug, Clone)]
pub struct PairRun {
    pub run: String,
    pub material: String,
    pub setup: Setup,
    /// +1 when the striker moves toward +z.
    pub direction: f64,
    pub diameter_m: f64,
    pub fps: f64,
    /// Sorted union of both tracks' sample times.
    pub t_s: Vec<f64>,
    /// Per particle: (index into `t_s`, measured z).
    pub samples: [Vec<(usize, f64)>; 2],
    /// Position noise (m) the residuals are divided by.
    pub sigma_m: f64,
    /// Start values of the own parameters.
    start: [f64; 4],
}

/// Indices of the shared parameters.
pub const MU_PG: usize = 0;
pub const LN_T0: usize = 1;
pub const TP: usize = 2;
pub const MU_PP: usize = 3;
/// Slots (a, b) of the rolling law, then of the contact law.
pub const LAW: usize = 4;
/// The contact distance over the diameter in runs.csv (held at 1 unless `FitSpec::free_contact`).
pub const CONTACT: usize = 8;
/// The force between the particles (`FitSpec::pair_force`; held at 0 without one): its
/// amplitude A at contact (m/s², > 0 repulsive), ln of its range λ (m), and the power law's n.
pub const PF_AMP: usize = 9;
pub const PF_LN_RANGE: usize = 10;
pub const PF_EXPONENT: usize = 11;
pub const N_SHARED: usize = 12;
/// The node values of a map law discovery accepted (`FitSpec::hold_law` with a
/// `Restitution::Map`), refitted here, after the `N_SHARED` parameters when the spec holds a map
/// (the chapter's fits have none, so their parameters are exactly as before): `MAX_MAP_NODES`
/// slots for the rolling setup's map, then as many for the contact setup's (held at 0 where
/// there is none).
pub const MAP: usize = N_SHARED;

/// Start values of a force between the particles, (A, ln λ, n): none, over 40 µm, n = 3.
pub const PAIR_FORCE_START: [f64; 3] = [0.0, -10.126631103850338, 3.0];

/// The shape of a force between the particles fitted with the pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairForceShape {
    Exponential,
    PowerLaw,
}
/// Indices of the own parameters of a run.
pub const Z1: usize = 0;
pub const GAP: usize = 1;
pub const V0: usize = 2;
pub const T_KICK: usize = 3;

/// The index of `setup` in `FitSpec::laws` and `held_laws`.
pub fn setup_index(setup: Setup) -> usize {
    match setup {
        Setup::Rolling => 0,
        Setup::Contact => 1,
    }
}

/// The first slot of `setup`'s map node values.
fn map_slot(setup: Setup) -> usize {
    MAP + setup_index(setup) * MAX_MAP_NODES
}

fn law_slot(setup: Setup) -> usize {
    match setup {
        Setup::Rolling => LAW,
        Setup::Contact => LAW + 2,
    }
}

const MIN_POINTS: usize = 20;

/// Why a collision recording cannot be fitted whole (the run is then left out, with this note).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PairRunError {
    #[error("needs tracks of particle 0 (striker) and 1 (target)")]
    MissingTrack,
    #[error("a track has fewer than {MIN_POINTS} samples")]
    TooFewSamples,
}

impl PairRun {
    /// Prepare a recording (particle 0 striker, 1 target; the setup from runs.csv or guessed
    /// from whether the target moves from the first frames).
    pub fn from_recording(
        rec: &Recording,
        setup_hint: Option<Setup>,
    ) -> Result<PairRun, PairRunError> {
        let info = &rec.info;
        let (Some(st), Some(tg)) = (rec.track(0), rec.track(1)) else {
            return Err(PairRunError::MissingTrack);
        };
        if st.t_s.len() < MIN_POINTS || tg.t_s.len() < MIN_POINTS {
            return Err(PairRunError::TooFewSamples);
        }
        let head = |z: &[f64]| {
            let mut h = z[..5].to_vec();
            median(&mut h)
        };
        let direction = if head(&tg.z_m) >= head(&st.z_m) {
            1.0
        } else {
            -1.0
        };
        let mut t: Vec<f64> = st.t_s.iter().chain(&tg.t_s).copied().collect();
        t.sort_by(|a, b| a.total_cmp(b));
        t.dedup();
        let index = |x: f64| t.partition_point(|y| *y < x);
        let samples = [st, tg].map(|tr| {
            tr.t_s
                .iter()
                .zip(&tr.z_m)
                .map(|(&ts, &z)| (index(ts), z))
                .collect::<Vec<_>>()
        });
        let data = |tr: &crate::recording::Track| TrackData {
            t_s: tr.t_s.clone(),
            z_m: tr.z_m.clone(),
        };
        let (ds, dt) = (data(st), data(tg));
        let sigma_m = noise_scale_m(&ds).min(noise_scale_m(&dt)).max(1e-8);
        let frame = 1.0 / info.fps;
        let t_first = t[0];
        let t_kick = t_first - 0.5 * frame;
        let line = |d: &TrackData| robust_line(d, 0, d.t_s.len().min(8), t_kick);
        let (v_st, z_st) = line(&ds).unwrap_or((0.0, ds.z_m[0]));
        let (v_tg, _) = line(&dt).unwrap_or((0.0, dt.z_m[0]));
        let moving_target = (v_tg * direction) > 0.2 * (v_st * direction).abs().max(1e-3);
        let setup = setup_hint.unwrap_or(if moving_target {
            Setup::Contact
        } else {
            Setup::Rolling
        });
        let v0 = match setup {
            Setup::Rolling => v_st,
            Setup::Contact => v_st + v_tg,
        };
        let gap = match setup {
            Setup::Rolling => (direction * (head(&tg.z_m) - z_st) - info.diameter_m).max(0.0),
            Setup::Contact => 0.0,
        };
        Ok(PairRun {
            run: info.run.clone(),
            material: info.material.clone(),
            setup,
            direction,
            diameter_m: info.diameter_m,
            fps: info.fps,
            t_s: t,
            samples,
            sigma_m,
            start: [z_st, gap, direction * (v0 * direction).max(1e-3), t_kick],
        })
    }

    /// Start values of the own parameters (z1, gap, v0, t_kick) read from the tracks.
    pub fn own_start(&self) -> [f64; 4] {
        self.start
    }

    pub fn n_samples(&self) -> usize {
        self.samples[0].len() + self.samples[1].len()
    }

    fn own_specs(&self) -> Vec<ParamSpec> {
        let frame = 1.0 / self.fps;
        let [z, gap, v0, tk] = self.start;
        let (vlo, vhi) = if self.direction > 0.0 {
            (1e-4, 3.0)
        } else {
            (-3.0, -1e-4)
        };
        vec![
            ParamSpec {
                start: z,
                lower: z - 0.05,
                upper: z + 0.05,
                step: 1e-9,
            },
            match self.setup {
                Setup::Rolling => ParamSpec {
                    start: gap,
                    lower: 0.0,
                    upper: gap + 0.05,
                    step: 1e-9,
                },
                Setup::Contact => ParamSpec {
                    start: 0.0,
                    lower: 0.0,
                    upper: 0.0,
                    step: 1e-9,
                },
            },
            ParamSpec {
                start: v0,
                lower: vlo,
                upper: vhi,
                step: 1e-7,
            },
            ParamSpec {
                start: tk,
                lower: self.t_s[0] - 1.5 * frame,
                upper: self.t_s[0] - 1e-3 * frame,
                step: 1e-8,
            },
        ]
    }

    /// The initial states at the kick (lab frame) for own parameters `own`, the pair's contact
    /// distance `contact` times the diameter.
    pub fn init(&self, own: &[f64], contact: f64) -> [State; 2] {
        [
            State {
                z_m: own[Z1],
                v_mps: own[V0],
                va_mps: 0.0,
            },
            State {
                z_m: own[Z1] + self.direction * (self.diameter_m * contact + own[GAP]),
                v_mps: 0.0,
                va_mps: 0.0,
            },
        ]
    }
}

/// The shared physics and contact laws of a whole-run fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSpec {
    pub groove: Groove,
    pub drag: DragSpec,
    /// Law forms of the rolling and the contact setup (`FromDiscovery` where `held_laws`
    /// holds the law).
    pub laws: [LawForm; 2],
    /// Laws discovery accepted (`FitSpec::hold_law`), per setup as `laws`, in place of a form's
    /// slots (held, unused): a named form held as given, a map at its nodes' speeds with its
    /// values refitted (`MAP`, started from discovery's).
    pub held_laws: [Option<Restitution>; 2],
    /// μ_pp depending on the slip speed, carried from discovery; μ_pp is then its value at the
    /// reference slip speed. None: one μ_pp.
    pub slip: Option<SlipFriction>,
    /// Hold μ_pp at this value (the profile), or fit it.
    pub mu_pp_held: Option<f64>,
    /// Fit the contact distance (`CONTACT`, a factor on the diameter) instead of holding it at 1.
    pub free_contact: bool,
    /// A force between the particles of this shape, fitted (`PF_AMP`…) from these start values
    /// of (A, ln λ, n); none when None.
    pub pair_force: Option<(PairForceShape, [f64; 3])>,
    /// The variation of μ_pg along the groove, by direction or by slip speed, held (the single
    /// runs' accepted friction: the pairs slide in the same groove); none by default.
    pub variation: FrictionVariation,
}

impl FitSpec {
    pub fn new(groove: Groove) -> FitSpec {
        FitSpec {
            groove,
            drag: DragSpec::Saturating,
            laws: [LawForm::Saturating, LawForm::Saturating],
            held_laws: [None, None],
            slip: None,
            mu_pp_held: None,
            free_contact: false,
            pair_force: None,
            variation: FrictionVariation::default(),
        }
    }

    /// The force between the particles at shared parameters `p` (None without one).
    pub fn force(&self, p: &[f64]) -> Option<PairForce> {
        let (shape, _) = self.pair_force?;
        let (amp_mps2, range_m) = (p[PF_AMP], p[PF_LN_RANGE].exp());
        match shape {
            PairForceShape::Exponential => Some(PairForce::Exponential { amp_mps2, range_m }),
            PairForceShape::PowerLaw => Some(PairForce::PowerLaw {
                amp_mps2,
                range_m,
                exponent: p[PF_EXPONENT],
            }),
        }
    }

    /// The contact distance over the diameter in shared parameters `p` (1 if it has none).
    pub fn contact(p: &[f64]) -> f64 {
        p.get(CONTACT).copied().unwrap_or(1.0)
    }

    fn law_form(&self, setup: Setup) -> LawForm {
        self.laws[setup_index(setup)]
    }

    /// Hold `law` for the runs of `setup` instead of fitting a form's slots.
    pub fn hold_law(&mut self, setup: Setup, law: Restitution) {
        let i = setup_index(setup);
        self.laws[i] = LawForm::FromDiscovery;
        self.held_laws[i] = Some(law);
    }

    /// The law held for `setup`, if any.
    pub fn held_law(&self, setup: Setup) -> Option<Restitution> {
        self.held_laws[setup_index(setup)]
    }

    /// The one-particle model at shared parameters `p`.
    pub fn model(&self, p: &[f64]) -> Model {
        let terms = match &self.drag {
            DragSpec::Saturating => vec![Term::SaturatingDrag {
                t0_s: p[LN_T0].exp(),
                tp_s_per_mps: p[TP],
            }],
            DragSpec::Linear => vec![Term::LinearDrag {
                t_s: p[LN_T0].exp(),
            }],
            DragSpec::Held(t) => t.clone(),
            DragSpec::SaturatingWith(t) => {
                let mut all = vec![Term::SaturatingDrag {
                    t0_s: p[LN_T0].exp(),
                    tp_s_per_mps: p[TP],
                }];
                all.extend(t.iter().cloned());
                all
            }
        };
        Model {
            groove: self.groove,
            friction: Friction::Constant { mu: p[MU_PG] },
            variation: self.variation,
            terms,
        }
    }

    /// The restitution law of `setup` at shared parameters `p`: a held map at its refitted node
    /// values, a held named form as held, else the form's from its slots.
    pub fn law_at(&self, p: &[f64], setup: Setup) -> Restitution {
        let i = law_slot(setup);
        match self.held_law(setup) {
            Some(Restitution::Map(m)) => {
                let j = map_slot(setup);
                Restitution::Map(m.with_values(p.get(j..j + m.len()).unwrap_or(&[])))
            }
            Some(law) => law,
            None => self.law_form(setup).law(p[i], p[i + 1]),
        }
    }

    /// The contact parameters of a run of `setup` at shared parameters `p`.
    pub fn pair(&self, p: &[f64], setup: Setup, diameter_m: f64) -> PairParams {
        PairParams {
            restitution: self.law_at(p, setup),
            mu_pp: p[MU_PP],
            radius_m: 0.5 * diameter_m * FitSpec::contact(p),
            force: self.force(p),
            slip: self.slip,
        }
    }

    /// Bounds and start values of the shared parameters (`start` overrides the defaults).
    pub fn shared_specs(&self, start: Option<&[f64]>, runs: &[PairRun]) -> Vec<ParamSpec> {
        let spec = |start: f64, lower: f64, upper: f64, step: f64| ParamSpec {
            start,
            lower,
            upper,
            step,
        };
        let hold = |s: ParamSpec, x: f64| ParamSpec {
            start: x,
            lower: x,
            upper: x,
            ..s
        };
        let mut out = vec![
            spec(0.3, 0.02, 1.5, 1e-6),
            spec(0.06f64.ln(), 0.003f64.ln(), 10f64.ln(), 1e-5),
            spec(0.5, 0.0, 30.0, 1e-4),
            spec(1.0, 0.02, 20.0, 1e-5),
        ];
        for form in self.laws {
            out.extend(form.specs());
        }
        let contact = spec(1.0, 0.9, 1.1, 1e-3);
        out.push(if self.free_contact {
            contact
        } else {
            hold(contact, 1.0)
        });
        // a force between the particles: |A| up to 100 g, λ from 5 µm (a frame's travel at a few
        // cm/s: shorter, it acts as a change of restitution, and the integrator crawls through
        // it) to 2 mm, n from 1.2 to 12
        let [a0, ln_l0, n0] = self.pair_force.map_or(PAIR_FORCE_START, |(_, s)| s);
        let force = [
            spec(a0, -1000.0, 1000.0, 1e-4),
            spec(ln_l0, 5e-6f64.ln(), 2e-3f64.ln(), 1e-4),
            spec(n0, 1.2, 12.0, 1e-4),
        ];
        match self.pair_force {
            None => out.extend(force.map(|f| hold(f, f.start))),
            Some((PairForceShape::Exponential, _)) => {
                out.extend([force[0], force[1], hold(force[2], force[2].start)])
            }
            Some((PairForceShape::PowerLaw, _)) => out.extend(force),
        }
        // a held map's node values, from discovery's (C of the impacts; kept within [0, 1.5],
        // the law clamps C to [0, 1]); the slots of no map are held at 0
        let maps = self
            .held_laws
            .iter()
            .any(|l| matches!(l, Some(Restitution::Map(_))));
        for setup in [Setup::Rolling, Setup::Contact]
            .into_iter()
            .filter(|_| maps)
        {
            let values = match self.held_law(setup) {
                Some(Restitution::Map(m)) => m.values().to_vec(),
                _ => Vec::new(),
            };
            for k in 0..MAX_MAP_NODES {
                out.push(match values.get(k) {
                    Some(&c) => spec(c.clamp(0.0, 1.5), 0.0, 1.5, 1e-5),
                    None => hold(spec(0.0, 0.0, 0.0, 1e-5), 0.0),
                });
            }
        }
        match self.drag {
            DragSpec::Saturating | DragSpec::SaturatingWith(_) => {}
            DragSpec::Linear => out[TP] = hold(out[TP], 0.0),
            DragSpec::Held(_) => {
                out[LN_T0] = hold(out[LN_T0], out[LN_T0].start);
                out[TP] = hold(out[TP], 0.0);
            }
        }
        if let Some(s) = start {
            for (o, x) in out.iter_mut().zip(s) {
                if o.lower < o.upper && x.is_finite() {
                    o.start = x.clamp(o.lower, o.upper);
                }
            }
        }
        // a law no run uses is held at its start; so is μ_pp when held
        for setup in [Setup::Rolling, Setup::Contact] {
            if !runs.iter().any(|r| r.setup == setup) {
                let i = law_slot(setup);
                let j = map_slot(setup);
                let map = if out.len() > j {
                    j..j + MAX_MAP_NODES
                } else {
                    j..j
                };
                for k in [i, i + 1].into_iter().chain(map) {
                    out[k] = hold(out[k], out[k].start);
                }
            }
        }
        if let Some(mu) = self.mu_pp_held {
            out[MU_PP] = hold(out[MU_PP], mu);
        }
        out
    }
}

struct Problem<'a> {
    runs: &'a [PairRun],
    spec: &'a FitSpec,
}

impl BlockProblem for Problem<'_> {
    fn n_blocks(&self) -> usize {
        self.runs.len()
    }
    fn n_residuals(&self, b: usize) -> usize {
        self.runs[b].n_samples()
    }
    fn residuals(&self, b: usize, shared: &[f64], own: &[f64], out: &mut [f64]) {
        residuals(&self.runs[b], self.spec, shared, own, out);
    }
    fn uses(&self, b: usize, i: usize) -> bool {
        let setup = self.runs[b].setup;
        if (LAW..CONTACT).contains(&i) {
            let slot = law_slot(setup);
            return i == slot || i == slot + 1;
        }
        if i >= MAP {
            let j = map_slot(setup);
            return (j..j + MAX_MAP_NODES).contains(&i);
        }
        true
    }
}

/// A run simulated at shared parameters `shared` and its own `own`: its sample times since the
/// kick, and the pair's trajectory at them.
pub fn simulate_run(
    run: &PairRun,
    spec: &FitSpec,
    shared: &[f64],
    own: &[f64],
) -> (Vec<f64>, PairTrajectory) {
    let model = spec.model(shared);
    let pair = spec.pair(shared, run.setup, run.diameter_m);
    let rel: Vec<f64> = run.t_s.iter().map(|t| (t - own[T_KICK]).max(0.0)).collect();
    let traj = simulate_pair(&model, &pair, run.init(own, FitSpec::contact(shared)), &rel);
    (rel, traj)
}

/// Whitened residuals (model − data)/σ of both tracks of a run, striker first.
pub fn residuals(run: &PairRun, spec: &FitSpec, shared: &[f64], own: &[f64], out: &mut [f64]) {
    let (_, traj) = simulate_run(run, spec, shared, own);
    let mut k = 0;
    for p in 0..2 {
        let z = &traj.particles[p].z_m;
        for &(i, zd) in &run.samples[p] {
            out[k] = match z.get(i) {
                Some(zm) if zm.is_finite() => (zm - zd) / run.sigma_m,
                _ => 1e6,
            };
            k += 1;
        }
    }
}

/// Solver settings of the whole-run fits: Huber at 3 (the residuals are whitened), three IRLS
/// rounds, converged when the deviance falls by less than 1e-3 plus a millionth of itself.
fn settings(max_iter: usize) -> Settings {
    Settings {
        max_iter,
        rounds: 3,
        huber_k: 3.0,
        scale: Scale::Fixed(1.0),
        cost_tol: 1e-3,
        rel_tol: 1e-6,
        damping: 1e-3,
    }
}

/// The result of a whole-run fit of one group of runs.
#[derive(Debug, Clone)]
pub struct GroupFit {
    pub spec: FitSpec,
    pub result: BlockResult,
}

impl GroupFit {
    pub fn cost(&self) -> f64 {
        self.result.cost()
    }
    pub fn converged(&self) -> bool {
        self.result.termination.is_converged()
    }
}

/// Fit `runs` (one material) with `spec`, from `start` (shared and per-run values of an earlier
/// fit of the same runs) or the defaults.
pub fn fit_group(
    runs: &[PairRun],
    spec: &FitSpec,
    start: Option<&GroupFit>,
    max_iter: usize,
) -> GroupFit {
    let shared_specs = spec.shared_specs(start.map(|s| s.result.shared.as_slice()), runs);
    let own = start.map(|s| s.result.own.as_slice());
    solve_group(runs, spec, &shared_specs, own, max_iter)
}

/// The per-run parameter specs, started from `own` (an earlier fit's values) when given.
fn own_specs_from(runs: &[PairRun], own: Option<&[Vec<f64>]>) -> Vec<Vec<ParamSpec>> {
    runs.iter()
        .enumerate()
        .map(|(b, r)| {
            let mut sp = r.own_specs();
            if let Some(o) = own.and_then(|o| o.get(b)) {
                for (s, x) in sp.iter_mut().zip(o) {
                    if s.lower < s.upper {
                        s.start = x.clamp(s.lower, s.upper);
                    }
                }
            }
            sp
        })
        .collect()
}

/// Solve the whole-run fit of `runs` for the shared specs given and per-run specs from `own`.
fn solve_group(
    runs: &[PairRun],
    spec: &FitSpec,
    shared_specs: &[ParamSpec],
    own: Option<&[Vec<f64>]>,
    max_iter: usize,
) -> GroupFit {
    let own_specs = own_specs_from(runs, own);
    let result = minimize_blocks(
        &Problem { runs, spec },
        shared_specs,
        &own_specs,
        &settings(max_iter),
    );
    GroupFit {
        spec: spec.clone(),
        result,
    }
}

/// Fit only the per-run parameters with every shared parameter held at `shared` (the held-out
/// part of cross-validation).
pub fn fit_own_only(runs: &[PairRun], spec: &FitSpec, shared: &[f64], max_iter: usize) -> GroupFit {
    fit_group_with(runs, spec, shared, None, &|_| false, max_iter)
}

/// Fit `runs` with `spec` from shared values `shared` (and per-run values `own` when given),
/// freeing only the shared parameters `free` picks; the others are held. The per-run
/// parameters are always fitted.
pub fn fit_group_with(
    runs: &[PairRun],
    spec: &FitSpec,
    shared: &[f64],
    own: Option<&[Vec<f64>]>,
    free: &dyn Fn(usize) -> bool,
    max_iter: usize,
) -> GroupFit {
    let shared_specs: Vec<ParamSpec> = spec
        .shared_specs(Some(shared), runs)
        .into_iter()
        .enumerate()
        .map(|(i, s)| {
            if free(i) {
                s
            } else {
                let x = if s.lower == s.upper {
                    s.start
                } else {
                    shared[i]
                };
                ParamSpec {
                    start: x,
                    lower: x,
                    upper: x,
                    ..s
                }
            }
        })
        .collect();
    solve_group(runs, spec, &shared_specs, own, max_iter)
}

/// The law slots (a, b) of `setup` in the shared parameters.
pub fn law_slots(setup: Setup) -> (usize, usize) {
    let i = law_slot(setup);
    (i, i + 1)
}

/// Default start values of a law form's slots.
pub fn law_start(form: LawForm) -> [f64; 2] {
    form.specs().map(|s| s.start)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Experiment, RunInfo, Track};

    fn pair(samples: [usize; 2]) -> Recording {
        let track = |particle: u32, n: usize| Track {
            particle,
            frame: (0..n as i64).collect(),
            t_s: (0..n).map(|k| k as f64 * 1e-4).collect(),
            z_m: (0..n)
                .map(|k| particle as f64 * 1e-3 + k as f64 * 1e-5)
                .collect(),
        };
        Recording {
            info: RunInfo {
                run: "c01".into(),
                experiment: Experiment::Collision,
                material: "316".into(),
                diameter_m: 3e-4,
                fps: 10_000.0,
                setup: Some(Setup::Rolling),
                extra: Default::default(),
            },
            tracks: vec![track(0, samples[0]), track(1, samples[1])],
        }
    }

    #[test]
    fn a_recording_that_cannot_be_fitted_whole_gives_a_typed_reason() {
        assert!(PairRun::from_recording(&pair([40, 40]), None).is_ok());
        let short = PairRun::from_recording(&pair([40, 5]), None).unwrap_err();
        assert_eq!(short, PairRunError::TooFewSamples);
        assert_eq!(short.to_string(), "a track has fewer than 20 samples");
        let mut alone = pair([40, 40]);
        alone.tracks.pop();
        let missing = PairRun::from_recording(&alone, None).unwrap_err();
        assert_eq!(missing, PairRunError::MissingTrack);
        assert!(missing
            .to_string()
            .contains("particle 0 (striker) and 1 (target)"));
    }
}
