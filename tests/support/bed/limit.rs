//! The operational detection limit of an effect in one dataset.
//!
//! The effect's signal is the change it makes to the noise-free recorded positions, frame by
//! frame (the same runs, kicks, frames and field of view with and without it), less what the
//! baseline's own free parameters can absorb of it: the change is projected, by linear least
//! squares, off the baseline's sensitivities to each run's start positions, kick speed and kick
//! time, to each material's μ and drag time T (shared by the material's runs), and, for the
//! collision runs, to each material's restitution law of each setup and to μ_pp, all in
//! the metric of the tracker noise's own covariance C (generalized least squares: every series is
//! whitened by [`Whitener`] first, so AR(1) errors, slow drifts and motion blur count as what
//! they are, not as white noise of the same size). What remains gives SNR² = Δᵀ C⁻¹ Δ over the
//! dataset, the square of what an ideal matched filter for this one effect would see.
//!
//! Discovery does not know the effect's shape: it searches places, forms and their parameters,
//! and must hold its false alarms on nulls. The limit is therefore set at SNR² = 36 (six standard
//! deviations along the effect's direction): five standard deviations after a trials factor of
//! about a hundred independent shapes.
//!
//! The collision runs' parameters are projected off as a pair fit frees them: unprojected, an
//! attraction between the particles that the fitted restitution law absorbs almost whole counted
//! as 8× its limit, where the pair fit's profile over the force gains a χ² of 4.

use super::dataset::{DatasetSpec, RunSpec};
use super::whiten::Whitener;
use crate::indsim::writer::RecordedRun;
use std::collections::BTreeMap;

/// SNR² defining the limit (see the module).
pub const LIMIT_SNR2: f64 = 36.0;

/// Relative steps of the finite differences.
const STEP_V0: f64 = 1e-3;
const STEP_MU: f64 = 1e-3;
const STEP_T: f64 = 1e-3;

/// Per-run local sensitivities and the global ones of the run's material, by key (frame, and
/// particle × [`PARTICLE_KEY`]), for each run of a base dataset.
pub struct Basis {
    runs: Vec<RunBasis>,
    materials: usize,
    /// Per run, key (frame + particle × 10⁶, as [`change`] keys) → the clean speed there.
    speeds: Vec<BTreeMap<usize, f64>>,
    whitener: Whitener,
}

/// Key → speed of every track of a clean rendering (central differences of the positions).
fn speeds(run: &RecordedRun) -> BTreeMap<usize, f64> {
    let mut out = BTreeMap::new();
    for (p, track) in run.tracks.iter().enumerate() {
        for (i, f) in track.iter().enumerate() {
            let (a, b) = (
                &track[i.saturating_sub(1)],
                &track[(i + 1).min(track.len() - 1)],
            );
            let v = if b.t_s > a.t_s {
                (b.z_m - a.z_m) / (b.t_s - a.t_s)
            } else {
                0.0
            };
            out.insert(f.frame + p * PARTICLE_KEY, v.abs());
        }
    }
    out
}

/// The key offset of the second particle of a collision run.
const PARTICLE_KEY: usize = 1_000_000;

/// The global columns: each material's μ and T (relative), then each material's restitution
/// laws of the rolling and the contact setups (c0, relative v_ref), then μ_pp, one for the
/// dataset (the simulator has one).
struct Globals {
    materials: usize,
}

impl Globals {
    fn mu(&self, m: usize) -> usize {
        2 * m
    }
    fn t(&self, m: usize) -> usize {
        2 * m + 1
    }
    /// c0 of material `m`'s law in `setup` (v_ref next to it).
    fn law(&self, m: usize, setup: &str) -> usize {
        2 * self.materials + 4 * m + if setup == "contact" { 2 } else { 0 }
    }
    fn mu_pp(&self) -> usize {
        6 * self.materials
    }
    fn count(&self) -> usize {
        6 * self.materials + 1
    }
}

/// Steps of the collision runs' finite differences: positions (m), c0 (absolute).
const STEP_Z: f64 = 1e-6;
const STEP_C0: f64 = 1e-3;
const STEP_VREF: f64 = 1e-3;
const STEP_MU_PP: f64 = 1e-3;

struct RunBasis {
    /// The global columns of this run's sensitivities, in the order of `rows`' second part.
    globals: Vec<usize>,
    /// key → (local columns, global columns); empty for a run that has none.
    rows: BTreeMap<usize, (Vec<f64>, Vec<f64>)>,
}

/// Key → z of every track of a rendering.
fn by_key(run: &RecordedRun) -> BTreeMap<usize, f64> {
    run.tracks
        .iter()
        .enumerate()
        .flat_map(|(p, t)| t.iter().map(move |f| (f.frame + p * PARTICLE_KEY, f.z_m)))
        .collect()
}

impl Basis {
    /// The sensitivities of `base`'s clean recording (finite differences of re-simulations).
    ///
    /// A single run's own parameters are its start position, kick speed and kick time; a
    /// collision run's are the striker's and the target's start positions (the pair's together
    /// in the contact setup, which starts touching), the kick speed and the kick time, as a pair
    /// fit frees them. The globals a material shares are μ and T, and for its collision runs the
    /// restitution law of each setup (c0, v_ref) and μ_pp: the baseline a pair effect must be
    /// told from is a pair model with its law and μ_pp fitted.
    pub fn new(base: &DatasetSpec) -> Basis {
        let clean = base.render(true);
        let perturbed = |f: &dyn Fn(&mut DatasetSpec)| {
            let mut s = base.clone();
            f(&mut s);
            s.render(true)
        };
        let dv = perturbed(&|s| s.runs.iter_mut().for_each(|r| r.v0 *= 1.0 + STEP_V0));
        let dmu = perturbed(&|s| {
            s.runs
                .iter_mut()
                .for_each(|r| r.physics.iter_mut().for_each(|p| p.mu *= 1.0 + STEP_MU))
        });
        let dt = perturbed(&|s| {
            s.runs.iter_mut().for_each(|r| {
                r.physics
                    .iter_mut()
                    .for_each(|p| p.drag = p.drag.with_t_s(p.drag.t_s() * (1.0 + STEP_T)))
            })
        });
        let dframe = 1e-3; // kick time: a shift of the frames by a thousandth of a frame
        let shifted = perturbed(&|s| s.runs.iter_mut().for_each(|r| r.frac += dframe));
        let pairs = base.runs.iter().any(|r| r.experiment == "collision");
        let pair_renders = pairs.then(|| {
            let collisions = |f: &dyn Fn(&mut RunSpec)| {
                perturbed(&|s| {
                    s.runs
                        .iter_mut()
                        .filter(|r| r.experiment == "collision")
                        .for_each(f)
                })
            };
            [
                // the striker (with the target when they start touching)
                collisions(&|r| {
                    r.z0[0] += STEP_Z;
                    if r.setup == "contact" {
                        r.z0[1] += STEP_Z;
                    }
                }),
                // the target alone (rolling setup)
                collisions(&|r| {
                    if r.setup != "contact" {
                        r.z0[1] += STEP_Z
                    }
                }),
                perturbed(&|s| {
                    s.materials.iter_mut().for_each(|m| {
                        m.restitution_rolling.0 += STEP_C0;
                        m.restitution_contact.0 += STEP_C0;
                    })
                }),
                perturbed(&|s| {
                    s.materials.iter_mut().for_each(|m| {
                        m.restitution_rolling.1 *= 1.0 + STEP_VREF;
                        m.restitution_contact.1 *= 1.0 + STEP_VREF;
                    })
                }),
                perturbed(&|s| s.mu_pp *= 1.0 + STEP_MU_PP),
            ]
        });
        let cols = Globals {
            materials: base.materials.len(),
        };
        let runs = base
            .runs
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                let z = by_key(&clean[i]);
                let m = spec.material;
                let mut locals = vec![(by_key(&dv[i]), STEP_V0 * spec.v0.abs())];
                locals.push((by_key(&shifted[i]), dframe));
                let mut globals = vec![
                    (cols.mu(m), by_key(&dmu[i]), STEP_MU),
                    (cols.t(m), by_key(&dt[i]), STEP_T),
                ];
                let single = spec.experiment == "single";
                if let (false, Some(r)) = (single, &pair_renders) {
                    locals.push((by_key(&r[0][i]), STEP_Z));
                    if spec.setup != "contact" {
                        locals.push((by_key(&r[1][i]), STEP_Z));
                    }
                    let law = cols.law(m, spec.setup);
                    globals.push((law, by_key(&r[2][i]), STEP_C0));
                    globals.push((law + 1, by_key(&r[3][i]), STEP_VREF));
                    globals.push((cols.mu_pp(), by_key(&r[4][i]), STEP_MU_PP));
                }
                let rows = z
                    .iter()
                    .filter(|&(&k, _)| !single || k < PARTICLE_KEY)
                    .filter_map(|(&k, &z0)| {
                        let d = |m: &BTreeMap<usize, f64>, h: f64| m.get(&k).map(|&x| (x - z0) / h);
                        // a single run's start position moves every frame by as much
                        let mut l: Vec<f64> = if single { vec![1.0] } else { Vec::new() };
                        for (m, h) in &locals {
                            l.push(d(m, *h)?);
                        }
                        let g = globals
                            .iter()
                            .map(|(_, m, h)| d(m, *h))
                            .collect::<Option<Vec<f64>>>()?;
                        Some((k, (l, g)))
                    })
                    .collect();
                RunBasis {
                    globals: globals.iter().map(|g| g.0).collect(),
                    rows,
                }
            })
            .collect();
        Basis {
            runs,
            materials: base.materials.len(),
            speeds: clean.iter().map(speeds).collect(),
            whitener: Whitener::new(&base.noise, base.camera.fps),
        }
    }

    /// Whitens the series `cols` over `keys` of run `run`, one track (particle) at a time.
    fn whiten(&self, run: usize, keys: &[usize], cols: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let mut out = (0..cols.len())
            .map(|_| Vec::with_capacity(keys.len()))
            .collect::<Vec<Vec<f64>>>();
        let mut start = 0;
        while start < keys.len() {
            let particle = keys[start] / PARTICLE_KEY;
            let end = keys[start..]
                .iter()
                .position(|k| k / PARTICLE_KEY != particle)
                .map_or(keys.len(), |n| start + n);
            let frames: Vec<usize> = keys[start..end].iter().map(|k| k % PARTICLE_KEY).collect();
            let speed: Vec<f64> = keys[start..end]
                .iter()
                .map(|k| self.speeds[run].get(k).copied().unwrap_or(0.0))
                .collect();
            let part: Vec<Vec<f64>> = cols.iter().map(|c| c[start..end].to_vec()).collect();
            for (o, w) in out
                .iter_mut()
                .zip(self.whitener.apply(&frames, &speed, &part))
            {
                o.extend(w);
            }
            start = end;
        }
        out
    }

    /// Δᵀ C⁻¹ Δ of the change `delta` (per run, key → Δz) after the projection, and the
    /// baseline parameter shifts of the projection.
    pub fn project(&self, delta: &[BTreeMap<usize, f64>]) -> (f64, Shift) {
        let ng = Globals {
            materials: self.materials,
        }
        .count();
        // normal equations, the local blocks eliminated (Schur complement)
        let mut s = vec![vec![0.0; ng]; ng];
        let mut rhs = vec![0.0; ng];
        let mut blocks = Vec::new();
        let mut raw = 0.0;
        for (index, (run, d)) in self.runs.iter().zip(delta).enumerate() {
            // the rows present in both, whitened together
            let keys: Vec<usize> = d
                .keys()
                .copied()
                .filter(|k| run.rows.contains_key(k))
                .collect();
            // a run with no sensitivities counts whole; a frame some perturbed rendering lacks
            // (the particle leaving the field of view) is left out
            if run.rows.is_empty() {
                let keys: Vec<usize> = d.keys().copied().collect();
                let w = self.whiten(index, &keys, &[d.values().copied().collect()]);
                raw += w[0].iter().map(|x| x * x).sum::<f64>();
                continue;
            }
            let Some((l0, g0)) = keys.first().map(|k| &run.rows[k]) else {
                continue;
            };
            let (nl, ngr) = (l0.len(), g0.len());
            let mut cols = vec![Vec::with_capacity(keys.len()); nl + ngr + 1];
            for k in &keys {
                let (l, g) = &run.rows[k];
                for (c, x) in cols.iter_mut().zip(l.iter().chain(g).chain([&d[k]])) {
                    c.push(*x);
                }
            }
            let w = self.whiten(index, &keys, &cols);
            let (lw, rest) = w.split_at(nl);
            let (gw, yw) = rest.split_at(ngr);
            let y = &yw[0];
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            let a: Vec<Vec<f64>> = lw
                .iter()
                .map(|li| lw.iter().map(|lj| dot(li, lj)).collect())
                .collect();
            let b: Vec<Vec<f64>> = lw
                .iter()
                .map(|li| gw.iter().map(|gj| dot(li, gj)).collect())
                .collect();
            let ay: Vec<f64> = lw.iter().map(|li| dot(li, y)).collect();
            let cy: Vec<f64> = gw.iter().map(|gi| dot(gi, y)).collect();
            let yy = dot(y, y);
            // A⁻¹ B (by global column) and A⁻¹ (Lᵀy)
            let ainv_b: Vec<Vec<f64>> = (0..ngr)
                .map(|j| solve(&a, &b.iter().map(|r| r[j]).collect::<Vec<_>>()))
                .collect();
            let ainv_y = solve(&a, &ay);
            let gcols = &run.globals;
            for i in 0..ngr {
                rhs[gcols[i]] += cy[i] - (0..nl).map(|q| b[q][i] * ainv_y[q]).sum::<f64>();
                for j in 0..ngr {
                    s[gcols[i]][gcols[j]] +=
                        dot(&gw[i], &gw[j]) - (0..nl).map(|q| b[q][i] * ainv_b[j][q]).sum::<f64>();
                }
            }
            blocks.push((index, yy, ay, cy, ainv_y, ainv_b));
        }
        // a tiny ridge keeps a material without single runs solvable
        for (i, row) in s.iter_mut().enumerate() {
            row[i] += 1e-30 + 1e-12 * row[i].abs();
        }
        let g = solve(&s, &rhs);
        // the residual sum of squares of each run: yᵀy − (fitted)ᵀ y at the least-squares optimum
        let mut total = raw;
        let mut shift = Shift {
            locals: vec![Vec::new(); self.runs.len()],
            globals: g.clone(),
        };
        for (index, yy, ay, cy, ainv_y, ainv_b) in blocks {
            let gl: Vec<f64> = self.runs[index].globals.iter().map(|&c| g[c]).collect();
            // (folded term by term, in the order of the columns)
            let local: Vec<f64> = (0..ay.len())
                .map(|q| (0..gl.len()).fold(ainv_y[q], |x, j| x - ainv_b[j][q] * gl[j]))
                .collect();
            let fitted = (0..gl.len()).fold(
                (0..ay.len()).map(|q| local[q] * ay[q]).sum::<f64>(),
                |x, j| x + gl[j] * cy[j],
            );
            total += (yy - fitted).max(0.0);
            shift.locals[index] = local;
        }
        (total, shift)
    }
}

/// The baseline parameter shifts that absorb most of a change: per run, its local columns (a
/// single run's z0 m, v0 relative to its step, the kick's fraction of a frame; a collision run's
/// v0, kick, the striker's and the target's z0), and the globals (per material relative μ and T
/// and the laws' c0 and relative v_ref, and the relative μ_pp).
pub struct Shift {
    locals: Vec<Vec<f64>>,
    globals: Vec<f64>,
}

impl Shift {
    /// Moves the runs and the materials of `spec` by the shift.
    fn apply(&self, spec: &mut DatasetSpec) {
        let cols = Globals {
            materials: spec.materials.len(),
        };
        for (run, local) in spec.runs.iter_mut().zip(&self.locals) {
            if local.is_empty() {
                continue;
            }
            if run.experiment == "single" {
                run.z0[0] += local[0];
                run.v0 += local[1] * run.v0.signum();
                run.frac += local[2];
            } else {
                run.v0 += local[0] * run.v0.signum();
                run.frac += local[1];
                run.z0[0] += local[2];
                if run.setup == "contact" {
                    run.z0[1] += local[2];
                } else if let Some(dz) = local.get(3) {
                    run.z0[1] += dz;
                }
            }
            let (dmu, dt) = (
                self.globals[cols.mu(run.material)],
                self.globals[cols.t(run.material)],
            );
            for p in run.physics.iter_mut() {
                p.mu *= 1.0 + dmu;
                p.drag = p.drag.with_t_s(p.drag.t_s() * (1.0 + dt));
            }
        }
        for (m, material) in spec.materials.iter_mut().enumerate() {
            for (law, setup) in [
                (&mut material.restitution_rolling, "rolling"),
                (&mut material.restitution_contact, "contact"),
            ] {
                let at = cols.law(m, setup);
                law.0 += self.globals[at];
                law.1 *= 1.0 + self.globals[at + 1];
            }
        }
        spec.mu_pp *= 1.0 + self.globals[cols.mu_pp()];
    }
}

/// Solves the small dense system `m x = b` (Gaussian elimination with partial pivoting; a
/// singular direction gets 0).
fn solve(m: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut a: Vec<Vec<f64>> = m
        .iter()
        .zip(b)
        .map(|(r, &y)| r.iter().copied().chain([y]).collect())
        .collect();
    let scale = a
        .iter()
        .map(|r| r[..n].iter().fold(0.0f64, |s, x| s.max(x.abs())))
        .fold(0.0f64, f64::max);
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, p);
        if a[c][c].abs() <= 1e-14 * scale {
            continue;
        }
        for r in 0..n {
            if r != c {
                let f = a[r][c] / a[c][c];
                for k in c..=n {
                    a[r][k] -= f * a[c][k];
                }
            }
        }
    }
    (0..n)
        .map(|i| {
            if a[i][i].abs() <= 1e-14 * scale {
                0.0
            } else {
                a[i][n] / a[i][i]
            }
        })
        .collect()
}

/// The change between two clean renderings, per run, frame → Δz (particle 0; both particles of
/// a collision run are summed in as separate frames).
pub fn change(base: &[RecordedRun], with: &[RecordedRun]) -> Vec<BTreeMap<usize, f64>> {
    base.iter()
        .zip(with)
        .map(|(a, b)| {
            let mut out = BTreeMap::new();
            for (p, (ta, tb)) in a.tracks.iter().zip(&b.tracks).enumerate() {
                let by: BTreeMap<usize, f64> = ta.iter().map(|f| (f.frame, f.z_m)).collect();
                for f in tb {
                    if let Some(z) = by.get(&f.frame) {
                        out.insert(f.frame + p * PARTICLE_KEY, f.z_m - z);
                    }
                }
            }
            out
        })
        .collect()
}

/// Gauss–Newton steps of the baseline's refit: a change the baseline absorbs exactly (a length
/// scale is μ over again) leaves a second-order remainder after one linear projection, which a
/// real refit removes.
const REFITS: usize = 3;

/// SNR² of the change from `base` to `with`, after what the baseline absorbs (see the module):
/// the least over a few Gauss–Newton refits of the baseline's parameters.
pub fn snr2(
    basis: &Basis,
    base: &DatasetSpec,
    base_render: &[RecordedRun],
    with: &DatasetSpec,
) -> f64 {
    let target = with.render(true);
    let mut moved = base.clone();
    let (mut best, mut shift) = basis.project(&change(base_render, &target));
    for _ in 1..REFITS {
        if best <= 0.0 {
            break;
        }
        shift.apply(&mut moved);
        let (s2, next) = basis.project(&change(&moved.render(true), &target));
        best = best.min(s2);
        shift = next;
    }
    best
}
