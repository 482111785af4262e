//! The operational detection limit of an effect in one dataset.
//!
//! The effect's signal is the change it makes to the noise-free recorded positions, frame by
//! frame (the same runs, kicks, frames and field of view with and without it), less what the
//! baseline's own free parameters can absorb of it: the change is projected, by linear least
//! squares, off the baseline's sensitivities to each single run's start position, kick speed and
//! kick time, and to each material's μ and drag time T (shared by the material's runs), all in
//! the metric of the tracker noise's own covariance C (generalized least squares: every series is
//! whitened by [`Whitener`] first, so AR(1) errors, slow drifts and motion blur count as what
//! they are, not as white noise of the same size). What remains gives SNR² = Δᵀ C⁻¹ Δ over the
//! dataset, the square of what an ideal matched filter for this one effect would see.
//!
//! Discovery does not know the effect's shape: it searches places, forms and their parameters,
//! and must hold its false alarms on nulls. The limit is therefore set at SNR² = 36 (six standard
//! deviations along the effect's direction): five standard deviations after a trials factor of
//! about a hundred independent shapes. Collision runs enter unprojected (whitened alike).

use super::dataset::DatasetSpec;
use super::whiten::Whitener;
use crate::indsim::writer::RecordedRun;
use std::collections::BTreeMap;

/// SNR² defining the limit (see the module).
pub const LIMIT_SNR2: f64 = 36.0;

/// Relative steps of the finite differences.
const STEP_V0: f64 = 1e-3;
const STEP_MU: f64 = 1e-3;
const STEP_T: f64 = 1e-3;

/// Per-run local sensitivities (z0, v0, t0) and global ones (μ, T of the run's material), by
/// frame, for each single run of a base dataset.
pub struct Basis {
    runs: Vec<Option<RunBasis>>,
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

struct RunBasis {
    material: usize,
    /// frame → (local columns, the two global columns of its material)
    rows: BTreeMap<usize, ([f64; 3], [f64; 2])>,
}

fn by_frame(run: &RecordedRun) -> BTreeMap<usize, f64> {
    run.tracks[0].iter().map(|f| (f.frame, f.z_m)).collect()
}

impl Basis {
    /// The sensitivities of `base`'s clean recording (finite differences of re-simulations).
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
        let runs = base
            .runs
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                if spec.experiment != "single" {
                    return None;
                }
                let (z, v, mu, t, sh) = (
                    by_frame(&clean[i]),
                    by_frame(&dv[i]),
                    by_frame(&dmu[i]),
                    by_frame(&dt[i]),
                    by_frame(&shifted[i]),
                );
                let rows = z
                    .iter()
                    .filter_map(|(&k, &z0)| {
                        let d = |m: &BTreeMap<usize, f64>, h: f64| m.get(&k).map(|&x| (x - z0) / h);
                        Some((
                            k,
                            (
                                [1.0, d(&v, STEP_V0 * spec.v0.abs())?, d(&sh, dframe)?],
                                [d(&mu, STEP_MU)?, d(&t, STEP_T)?],
                            ),
                        ))
                    })
                    .collect();
                Some(RunBasis {
                    material: spec.material,
                    rows,
                })
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
        let ng = 2 * self.materials;
        // normal equations, the local blocks eliminated (Schur complement)
        let mut s = vec![vec![0.0; ng]; ng];
        let mut rhs = vec![0.0; ng];
        let mut blocks = Vec::new();
        let mut raw = 0.0;
        for (index, (run, d)) in self.runs.iter().zip(delta).enumerate() {
            let Some(run) = run else {
                let keys: Vec<usize> = d.keys().copied().collect();
                let w = self.whiten(index, &keys, &[d.values().copied().collect()]);
                raw += w[0].iter().map(|x| x * x).sum::<f64>();
                continue;
            };
            // the rows present in both, whitened together
            let keys: Vec<usize> = d
                .keys()
                .copied()
                .filter(|k| run.rows.contains_key(k))
                .collect();
            let mut cols = (0..6)
                .map(|_| Vec::with_capacity(keys.len()))
                .collect::<Vec<Vec<f64>>>();
            for k in &keys {
                let (l, g) = &run.rows[k];
                for (c, x) in cols.iter_mut().zip(l.iter().chain(g).chain([&d[k]])) {
                    c.push(*x);
                }
            }
            let w = self.whiten(index, &keys, &cols);
            let cols: Vec<usize> = vec![2 * run.material, 2 * run.material + 1];
            let (mut a, mut b, mut c) = ([[0.0; 3]; 3], [[0.0; 2]; 3], [[0.0; 2]; 2]);
            let (mut ay, mut cy, mut yy) = ([0.0; 3], [0.0; 2], 0.0);
            for r in 0..keys.len() {
                let (l, g, y) = ([w[0][r], w[1][r], w[2][r]], [w[3][r], w[4][r]], w[5][r]);
                yy += y * y;
                for i in 0..3 {
                    ay[i] += l[i] * y;
                    for j in 0..3 {
                        a[i][j] += l[i] * l[j];
                    }
                    for j in 0..2 {
                        b[i][j] += l[i] * g[j];
                    }
                }
                for i in 0..2 {
                    cy[i] += g[i] * y;
                    for j in 0..2 {
                        c[i][j] += g[i] * g[j];
                    }
                }
            }
            let a_vec: Vec<Vec<f64>> = a.iter().map(|r| r.to_vec()).collect();
            // A⁻¹ B and A⁻¹ (Jᵀy)
            let ainv_b: Vec<Vec<f64>> = (0..2)
                .map(|j| solve(&a_vec, &[b[0][j], b[1][j], b[2][j]]))
                .collect();
            let ainv_y = solve(&a_vec, &ay);
            for i in 0..2 {
                rhs[cols[i]] += cy[i] - (0..3).map(|q| b[q][i] * ainv_y[q]).sum::<f64>();
                for j in 0..2 {
                    s[cols[i]][cols[j]] +=
                        c[i][j] - (0..3).map(|q| b[q][i] * ainv_b[j][q]).sum::<f64>();
                }
            }
            blocks.push((index, cols, yy, ay, cy, ainv_y, ainv_b));
        }
        // a tiny ridge keeps a material without single runs solvable
        for (i, row) in s.iter_mut().enumerate() {
            row[i] += 1e-30 + 1e-12 * row[i].abs();
        }
        let g = solve(&s, &rhs);
        // the residual sum of squares of each run: yᵀy − (fitted)ᵀ y at the least-squares optimum
        let mut total = raw;
        let mut shift = Shift {
            locals: vec![None; self.runs.len()],
            globals: g.clone(),
        };
        for (index, cols, yy, ay, cy, ainv_y, ainv_b) in blocks {
            let gl = [g[cols[0]], g[cols[1]]];
            let local: Vec<f64> = (0..3)
                .map(|q| ainv_y[q] - ainv_b[0][q] * gl[0] - ainv_b[1][q] * gl[1])
                .collect();
            let fitted =
                (0..3).map(|q| local[q] * ay[q]).sum::<f64>() + gl[0] * cy[0] + gl[1] * cy[1];
            total += (yy - fitted).max(0.0);
            shift.locals[index] = Some([local[0], local[1], local[2]]);
        }
        (total, shift)
    }
}

/// The baseline parameter shifts that absorb most of a change: per single run (z0 m, v0 m/s
/// along its motion, the kick's fraction of a frame), per material (relative μ, relative T).
pub struct Shift {
    locals: Vec<Option<[f64; 3]>>,
    globals: Vec<f64>,
}

impl Shift {
    /// Moves the single runs of `spec` by the shift.
    fn apply(&self, spec: &mut DatasetSpec) {
        for (run, local) in spec.runs.iter_mut().zip(&self.locals) {
            let Some([dz, dv, dframe]) = *local else {
                continue;
            };
            run.z0[0] += dz;
            run.v0 += dv * run.v0.signum();
            run.frac += dframe;
            let (dmu, dt) = (
                self.globals[2 * run.material],
                self.globals[2 * run.material + 1],
            );
            for p in run.physics.iter_mut() {
                p.mu *= 1.0 + dmu;
                p.drag = p.drag.with_t_s(p.drag.t_s() * (1.0 + dt));
            }
        }
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
