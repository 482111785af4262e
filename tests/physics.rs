//! Physics tests with known answers: closed form, chapter equations, integrator, collisions.

use groove::physics::{
    simulate, simulate_pair, Baseline, Friction, Groove, Model, PairParams, Phase, Restitution,
    State, Term, G_MPS2,
};

fn chapter(mu: f64, t_drag_s: f64) -> Baseline {
    Baseline::new(mu, t_drag_s)
}

/// Eqs. 4.3 and 4.4 (no drag): final rolling speed, time and distance to reach it.
fn eq_4_3_4_4(g: Groove, mu: f64, v0: f64, va0: f64) -> (f64, f64, f64) {
    let (s, k) = (g.s, g.k);
    let ks2 = g.ks2();
    let v1 = ks2 / (ks2 + 1.0) * v0 + s / (ks2 + 1.0) * va0;
    let dt = s / (ks2 + 1.0) * (v0 - s * va0) / (G_MPS2 * mu);
    let dz = 0.5 * s / (ks2 + 1.0) * (v0 - s * va0) / (G_MPS2 * mu)
        * ((2.0 * k * s * s + 1.0) / (ks2 + 1.0) * v0 + s / (ks2 + 1.0) * va0);
    (v1, dt, dz)
}

#[test]
fn baseline_without_drag_matches_eqs_4_3_and_4_4() {
    let b = chapter(0.337, f64::INFINITY);
    for &(v0, va0) in &[(0.05, 0.0), (0.1, 0.02), (0.02, -0.03), (0.08, 0.05)] {
        let (v1, dt, dz) = eq_4_3_4_4(b.groove, b.mu, v0, va0);
        let t1 = b.switch_time_from_s(v0, va0);
        assert!((t1 - dt).abs() < 1e-15, "t1 {t1} vs Eq. 4.4 {dt}");
        let (z, v, va, phase) = b.state_from(v0, va0, t1 + 0.01);
        assert_eq!(phase, Phase::Rolling);
        assert!((v - v1).abs() < 1e-15, "v {v} vs Eq. 4.3 {v1}");
        assert!((va - v1 / b.groove.s).abs() < 1e-14);
        assert!(
            (z - (dz + 0.01 * v1)).abs() < 1e-15,
            "z {z} vs Eq. 4.4 {dz}"
        );
    }
}

#[test]
fn baseline_is_mirror_symmetric() {
    let b = chapter(0.293, 0.07);
    for &t in &[0.0, 0.001, 0.004, 0.02, 0.06] {
        let (zp, vp, vap, pp) = b.state_from(0.04, 0.01, t);
        let (zm, vm, vam, pm) = b.state_from(-0.04, -0.01, t);
        assert_eq!(pp, pm);
        assert!((zp + zm).abs() < 1e-18 && (vp + vm).abs() < 1e-18 && (vap + vam).abs() < 1e-17);
    }
    assert_eq!(b.switch_time_s(0.04), b.switch_time_s(-0.04));
}

#[test]
fn baseline_switch_is_where_slip_vanishes_and_rolling_decays_with_te() {
    let b = chapter(0.337, 0.06);
    let s = b.groove.s;
    for &v0 in &[0.005, 0.03, 0.1, 0.3, -0.07] {
        let t1 = b.switch_time_s(v0);
        let (z1, v1, va1, _) = b.state_from(v0, 0.0, t1);
        assert!((v1 - s * va1).abs() < 1e-14, "slip at t1 {}", v1 - s * va1);
        // just before: sliding with slip in the direction of v0
        let (_, vb, vab, pb) = b.state_from(v0, 0.0, t1 * (1.0 - 1e-9));
        assert_eq!(pb, Phase::Sliding);
        assert!((vb - s * vab) * v0.signum() > 0.0);
        // rolling: Te = T (1 + ks²)/ks²
        let te = 0.06 * (1.0 + b.groove.ks2()) / b.groove.ks2();
        let dt = 0.02;
        let (z2, v2, _, p2) = b.state_from(v0, 0.0, t1 + dt);
        assert_eq!(p2, Phase::Rolling);
        assert!((v2 / v1 - (-dt / te).exp()).abs() < 1e-13);
        assert!((z2 - z1 - v1 * te * (1.0 - (-dt / te).exp())).abs() < 1e-15);
    }
}

#[test]
fn baseline_sliding_matches_its_textbook_formula() {
    // v(t) = (v0 + A) e^{−t/T} − A, z = T (v0 + A)(1 − e^{−t/T}) − A t with A = g μ T / s
    let (mu, t_drag) = (0.337, 0.052);
    let b = chapter(mu, t_drag);
    let a = G_MPS2 * mu * t_drag / b.groove.s;
    let v0 = 0.08;
    let t1 = b.switch_time_s(v0);
    for i in 0..10 {
        let t = t1 * i as f64 / 10.0;
        let (z, v, p) = b.state(v0, t);
        assert_eq!(p, Phase::Sliding);
        let ve = (v0 + a) * (-t / t_drag).exp() - a;
        let ze = t_drag * (v0 + a) * (1.0 - (-t / t_drag).exp()) - a * t;
        assert!(
            (v - ve).abs() < 1e-15 && (z - ze).abs() < 1e-16,
            "t {t}: {z} vs {ze}"
        );
    }
}

#[test]
fn baseline_positions_equal_state() {
    let b = chapter(0.3, 0.08);
    let t: Vec<f64> = (0..600).map(|i| i as f64 * 1e-4).collect();
    let mut dz = vec![0.0; t.len()];
    b.positions_from(0.06, 0.01, &t, &mut dz);
    for (ti, zi) in t.iter().zip(&dz) {
        assert_eq!(*zi, b.state_from(0.06, 0.01, *ti).0);
    }
}

#[test]
fn baseline_at_rest_stays_at_rest() {
    let b = chapter(0.3, 0.08);
    assert_eq!(b.state_from(0.0, 0.0, 0.05), (0.0, 0.0, 0.0, Phase::Rest));
}

#[test]
fn baseline_backspin_can_make_friction_accelerate() {
    // striker after a collision: v ≈ 0 but spinning forward, friction drives it forward
    let b = chapter(0.337, 0.06);
    let (_, v, _, p) = b.state_from(0.0, 0.05, b.switch_time_from_s(0.0, 0.05) + 1e-3);
    assert_eq!(p, Phase::Rolling);
    assert!(v > 0.0);
}

fn times(n: usize, dt: f64) -> Vec<f64> {
    (0..n).map(|i| i as f64 * dt).collect()
}

fn model(mu: f64, terms: Vec<Term>) -> Model {
    Model {
        groove: Groove::CHAPTER,
        friction: Friction::Constant { mu },
        variation: Default::default(),
        terms,
    }
}

fn kick(v0: f64, va0: f64) -> State {
    State {
        z_m: 0.0,
        v_mps: v0,
        va_mps: va0,
    }
}

#[test]
fn integrator_matches_closed_form_both_directions() {
    // tolerance: 1e-10 m and 1e-9 m/s, far below a camera's µm
    let t = times(1000, 1e-4);
    for &(mu, t_drag) in &[(0.337, 0.052), (0.293, 0.16), (0.05, 0.01)] {
        let b = Baseline::new(mu, t_drag);
        let m = Model::baseline(mu, t_drag);
        for &(v0, va0) in &[
            (0.1, 0.0),
            (-0.1, 0.0),
            (0.005, 0.0),
            (-0.03, 0.02),
            (0.0, 0.08),
            (0.3, 0.0),
        ] {
            let tr = simulate(&m, kick(v0, va0), &t);
            let mut worst: f64 = 0.0;
            for (k, &tk) in t.iter().enumerate() {
                let (z, v, va, ph) = b.state_from(v0, va0, tk);
                worst = worst.max((tr.z_m[k] - z).abs());
                assert!(
                    (tr.z_m[k] - z).abs() < 1e-10,
                    "mu {mu} T {t_drag} v0 {v0} t {tk}: z {} vs {z}",
                    tr.z_m[k]
                );
                assert!(
                    (tr.v_mps[k] - v).abs() < 1e-9,
                    "mu {mu} T {t_drag} v0 {v0} va0 {va0} t {tk} ph {ph:?}: v {} vs {v}",
                    tr.v_mps[k]
                );
                assert!(
                    (tr.va_mps[k] - va).abs() < 1e-8,
                    "va {} vs {va}",
                    tr.va_mps[k]
                );
                let near_switch = (tk - b.switch_time_from_s(v0, va0)).abs() < 1e-9;
                assert!(
                    ph == tr.phase[k] || near_switch,
                    "phase at {tk}: {ph:?} vs {:?}",
                    tr.phase[k]
                );
            }
            let t1 = b.switch_time_from_s(v0, va0);
            let last = tr.events.last().expect("a switch to rolling");
            assert_eq!(last.to, Phase::Rolling);
            assert!(
                (last.t_s - t1).abs() < 1e-10,
                "event {} vs closed form {t1}",
                last.t_s
            );
        }
    }
}

#[test]
fn integrator_without_drag_matches_eqs_4_3_and_4_4() {
    let m = model(0.293, vec![]);
    for &(v0, va0) in &[(0.06, 0.0), (-0.06, 0.0), (0.02, 0.05), (0.1, -0.04)] {
        // the chapter's equations are written for v0 − s va0 > 0; the other way is their mirror
        let sign = (v0 - m.groove.s * va0).signum();
        let (v1, dt, dz) = eq_4_3_4_4(m.groove, 0.293, sign * v0, sign * va0);
        let (v1, dz) = (sign * v1, sign * dz);
        let tr = simulate(&m, kick(v0, va0), &[0.0, 2.0 * dt]);
        let ev = &tr.events[0];
        assert_eq!((ev.from, ev.to), (Phase::Sliding, Phase::Rolling));
        assert!((ev.t_s - dt).abs() < 1e-13, "Δt {} vs Eq. 4.4 {dt}", ev.t_s);
        assert!((ev.z_m - dz).abs() < 1e-13, "Δz {} vs Eq. 4.4 {dz}", ev.z_m);
        assert!(
            (tr.v_mps[1] - v1).abs() < 1e-12,
            "v {} vs Eq. 4.3 {v1}",
            tr.v_mps[1]
        );
        assert!((tr.va_mps[1] - v1 / m.groove.s).abs() < 1e-11);
    }
}

#[test]
fn rolling_decays_with_te_not_t() {
    let t_drag = 0.05;
    let m = Model::baseline(0.337, t_drag);
    let tr = simulate(&m, kick(0.05, 0.05 / m.groove.s), &[0.0, 0.01, 0.05]);
    assert!(tr.phase.iter().all(|p| *p == Phase::Rolling));
    let te = -0.04 / (tr.v_mps[2] / tr.v_mps[1]).ln();
    let expected = t_drag * (1.0 + m.groove.ks2()) / m.groove.ks2();
    assert!((te / expected - 1.0).abs() < 1e-8, "Te {te} vs {expected}");
    assert!((te / t_drag - 2.198).abs() < 1e-3);
}

/// The first sample at rest; every later one is at rest too, where it stopped.
fn first_rest(tr: &groove::physics::Trajectory) -> usize {
    let stop = tr
        .phase
        .iter()
        .position(|p| *p == Phase::Rest)
        .expect("it comes to rest");
    assert!(tr.phase[stop..].iter().all(|p| *p == Phase::Rest));
    assert!(tr.z_m[stop..].iter().all(|z| *z == tr.z_m[stop]));
    stop
}

/// A particle still sliding when a rolling resistance stops it, with a friction too weak to spin
/// it up against that resistance (μ at a fit's lower bound, 0.001, against c = 0.004): at v = 0
/// both ways are barred, so it rests there. It used to chatter about v = 0, a switch per
/// crossing, up to the cap of 10,000 (a per-run fit of a slow run took 8 s), and end "sliding".
#[test]
fn a_slide_stopped_by_a_resistance_stronger_than_its_friction_rests() {
    let (mu, c, v0) = (0.001, 0.004, -0.0035);
    let m = model(mu, vec![Term::RollingResistance { c }]);
    let t = times(1200, 1e-4);
    let tr = simulate(&m, kick(v0, 0.0), &t);
    let stop = first_rest(&tr);
    assert!(tr.phase[..stop].iter().all(|p| *p == Phase::Sliding));
    assert!(tr.events.len() <= 3, "{} switches", tr.events.len());
    // where: the slip (−v0 at first, the spin 0) closes first, under v' = g(μ/s + c) and
    // u' = v' + s k g μ; then it cannot roll and slides the other way, v' = g(c − μ/s), to v = 0
    let (s, k) = (m.groove.s, m.groove.k);
    let a1 = G_MPS2 * (mu / s + c);
    let t1 = -v0 / (a1 + s * k * G_MPS2 * mu);
    let v1 = v0 + a1 * t1;
    let a2 = G_MPS2 * (c - mu / s);
    let z_stop = v0 * t1 + 0.5 * a1 * t1 * t1 - v1 * v1 / (2.0 * a2);
    assert!(
        (tr.z_m[stop] - z_stop).abs() < 1e-9,
        "{} vs {z_stop}",
        tr.z_m[stop]
    );
}

/// A particle whose motion a rolling resistance stops while it still slips, spun against its
/// motion, rests there when its spin's friction (g μ/s) is weaker than what the resistance holds
/// (c g): carried on, v crossed zero back and forth to the cap on switches.
#[test]
fn a_particle_stopped_while_it_slips_rests_if_the_resistance_holds_it() {
    let (mu, c, v0) = (0.001, 0.004, -0.0035);
    let m = model(mu, vec![Term::RollingResistance { c }]);
    let t = times(1200, 1e-4);
    // back-spin: the slip closes long after v reaches 0
    let tr = simulate(&m, kick(v0, 0.05), &t);
    let stop = first_rest(&tr);
    assert!(tr.events.len() <= 2, "{} switches", tr.events.len());
    // sliding all the way with v' = g(μ/s + c): v0²/(2a)
    let a = G_MPS2 * (mu / m.groove.s + c);
    let z_stop = -v0 * v0 / (2.0 * a);
    assert!(
        (tr.z_m[stop] - z_stop).abs() < 1e-9,
        "{} vs {z_stop}",
        tr.z_m[stop]
    );
}

/// Start rolling at v0 with one extra term and return samples of (t, z, v, phase).
fn roll(term: Term, v0: f64, t: &[f64]) -> groove::physics::Trajectory {
    let m = model(0.337, vec![term]);
    simulate(&m, kick(v0, v0 / m.groove.s), t)
}

#[test]
fn each_term_has_its_analytic_rolling_motion() {
    let f = Groove::CHAPTER.rolling_factor();
    let t = times(200, 5e-4);
    // quadratic drag: v = v0 / (1 + f c v0 t), in both directions
    for &v0 in &[0.08, -0.08] {
        let tr = roll(Term::QuadraticDrag { c_per_m: 20.0 }, v0, &t);
        for (k, &tk) in t.iter().enumerate() {
            let v = v0 / (1.0 + f * 20.0 * v0.abs() * tk);
            assert!(
                (tr.v_mps[k] - v).abs() < 1e-10,
                "quadratic: {} vs {v}",
                tr.v_mps[k]
            );
        }
    }
    // saturating drag: T0 ln(v0/v) + T'(v0 − v) = f t
    let (t0, tp) = (0.05, 2.0);
    let tr = roll(
        Term::SaturatingDrag {
            t0_s: t0,
            tp_s_per_mps: tp,
        },
        0.1,
        &t,
    );
    for (k, &tk) in t.iter().enumerate() {
        let v = tr.v_mps[k];
        let lhs = t0 * (0.1 / v).ln() + tp * (0.1 - v);
        assert!(
            (lhs - f * tk).abs() < 1e-9,
            "saturating: {lhs} vs {}",
            f * tk
        );
    }
    // rolling resistance: v falls linearly and the particle stops and stays at rest
    let c = 0.002;
    let tr = roll(Term::RollingResistance { c }, -0.02, &t);
    let t_stop = 0.02 / (f * c * G_MPS2);
    let z_stop = -0.02 * 0.02 / (2.0 * f * c * G_MPS2);
    for (k, &tk) in t.iter().enumerate() {
        if tk < t_stop {
            assert_eq!(tr.phase[k], Phase::Rolling);
            assert!((tr.v_mps[k] - (-0.02 + f * c * G_MPS2 * tk)).abs() < 1e-12);
        } else {
            assert_eq!(tr.phase[k], Phase::Rest);
            assert!(
                (tr.z_m[k] - z_stop).abs() < 1e-12,
                "stop at {} vs {z_stop}",
                tr.z_m[k]
            );
        }
    }
    // groove tilt: constant lab-frame acceleration, rolling reverses smoothly (no chatter)
    let alpha: f64 = 0.2;
    let a = -G_MPS2 * alpha.to_radians().sin();
    let tr = roll(Term::GrooveTilt { alpha_deg: alpha }, 0.01, &t);
    for (k, &tk) in t.iter().enumerate() {
        assert_eq!(tr.phase[k], Phase::Rolling);
        assert!((tr.z_m[k] - (0.01 * tk + 0.5 * f * a * tk * tk)).abs() < 1e-13);
    }
    // position force: energy ½v² − f ∫a dz is conserved while rolling
    let (amp, lambda, phi) = (0.05, 1e-3, 0.3);
    let tr = roll(
        Term::PositionForce {
            amp_mps2: amp,
            wavelength_m: lambda,
            phase_rad: phi,
        },
        0.02,
        &t,
    );
    let k_ = std::f64::consts::TAU / lambda;
    let potential = |z: f64| f * amp / k_ * (k_ * z + phi).cos();
    let e0 = 0.5 * 0.02 * 0.02 + potential(0.0);
    for k in 0..t.len() {
        let e = 0.5 * tr.v_mps[k] * tr.v_mps[k] + potential(tr.z_m[k]);
        assert!((e - e0).abs() < 1e-12, "energy {e} vs {e0}");
    }
}

#[test]
fn rest_holds_against_a_small_tilt_but_not_a_large_one() {
    let f = Groove::CHAPTER.rolling_factor();
    let t = times(200, 5e-4);
    let hold = |alpha_deg: f64| {
        let m = model(
            0.337,
            vec![
                Term::RollingResistance { c: 0.01 },
                Term::GrooveTilt { alpha_deg },
            ],
        );
        simulate(&m, kick(0.0, 0.0), &t)
    };
    let tr = hold(0.3); // g sin α = 0.051 < c g = 0.098
    assert!(tr.phase.iter().all(|p| *p == Phase::Rest) && tr.z_m.iter().all(|z| *z == 0.0));
    let tr = hold(1.0); // 0.171 > 0.098: rolls downhill (−z)
    let a = f * (-G_MPS2 * 1f64.to_radians().sin() + 0.01 * G_MPS2);
    let k = t.len() - 1;
    assert_eq!(tr.phase[k], Phase::Rolling);
    assert!((tr.z_m[k] - 0.5 * a * t[k] * t[k]).abs() < 1e-13);
}

/// Rest under a force that grows in time is not for good: a particle held by a rolling
/// resistance (c g = 0.039 m/s²) starts rolling exactly when a vibration A sin(ωt) outgrows the
/// hold, and then rolls as the closed form says. It used to stay where it was to the end.
#[test]
fn a_particle_at_rest_starts_when_a_force_in_time_outgrows_the_hold() {
    let (c, amp, freq) = (0.004, 0.1, 10.0);
    let m = model(
        0.337,
        vec![
            Term::RollingResistance { c },
            Term::TimePeriodicForce {
                amp_mps2: amp,
                freq_hz: freq,
                phase_rad: 0.0,
            },
        ],
    );
    let t = times(600, 1e-4);
    let tr = simulate(&m, kick(0.0, 0.0), &t);
    let (hold, w) = (c * G_MPS2, std::f64::consts::TAU * freq);
    let t_start = (hold / amp).asin() / w;
    let first = &tr.events[0];
    assert_eq!((first.from, first.to), (Phase::Rest, Phase::Rolling));
    assert!(
        (first.t_s - t_start).abs() < 1e-9,
        "{} vs {t_start}",
        first.t_s
    );
    // rolling forward from rest: v' = f (A sin ωt − c g), up to the next switch
    let f = m.groove.rolling_factor();
    let z = |t: f64| {
        let dt = t - t_start;
        f * (amp / w * (dt * (w * t_start).cos() - ((w * t).sin() - (w * t_start).sin()) / w)
            - 0.5 * hold * dt * dt)
    };
    let end = tr.events.get(1).map_or(f64::INFINITY, |e| e.t_s);
    let mut rolled = 0;
    for (k, &tk) in t.iter().enumerate() {
        if tk < t_start {
            assert_eq!((tr.phase[k], tr.z_m[k]), (Phase::Rest, 0.0));
        } else if tk < end {
            assert_eq!(tr.phase[k], Phase::Rolling);
            assert!(
                (tr.z_m[k] - z(tk)).abs() < 1e-12,
                "t {tk}: {} vs {}",
                tr.z_m[k],
                z(tk)
            );
            rolled += 1;
        }
    }
    assert!(rolled > 300, "{rolled} samples rolling");
    assert!(
        tr.z_m[t.len() - 1] > 1e-5,
        "it moved {} m",
        tr.z_m[t.len() - 1]
    );
    // a vibration just above the hold (1.02×) at 900 Hz outgrows it for 71 µs a half period:
    // the first such window starts it, however large the steps at rest had grown
    let (amp, freq) = (1.02 * hold, 900.0);
    let mut fast = m.clone();
    fast.terms[1] = Term::TimePeriodicForce {
        amp_mps2: amp,
        freq_hz: freq,
        phase_rad: 0.0,
    };
    let first = &simulate(&fast, kick(0.0, 0.0), &t).events[0];
    let t_first = (hold / amp).asin() / (std::f64::consts::TAU * freq);
    assert_eq!((first.from, first.to), (Phase::Rest, Phase::Rolling));
    assert!(
        (first.t_s - t_first).abs() < 1e-9,
        "{} vs {t_first}",
        first.t_s
    );
    // a pair at rest far apart: each moves as the single particle does
    let p = PairParams {
        restitution: Restitution::Constant(0.9),
        mu_pp: 0.3,
        radius_m: 150e-6,
        force: None,
        slip: None,
    };
    let far = State {
        z_m: 0.01,
        ..kick(0.0, 0.0)
    };
    let pair = simulate_pair(&m, &p, [kick(0.0, 0.0), far], &t);
    for (q, z0) in pair.particles.iter().zip([0.0, 0.01]) {
        assert!(
            (q.events[0].t_s - t_start).abs() < 1e-9,
            "{}",
            q.events[0].t_s
        );
        for k in 0..t.len() {
            assert!((q.z_m[k] - z0 - tr.z_m[k]).abs() < 1e-12, "t {}", t[k]);
        }
    }
}

#[test]
fn friction_limit_makes_a_steep_groove_slide() {
    // need |s a/(1 + ks²)| = 2.7 m/s² > g μ = 0.49 m/s²: cannot roll, slides downhill
    let m = model(0.05, vec![Term::GrooveTilt { alpha_deg: 60.0 }]);
    let t = times(11, 1e-3);
    let tr = simulate(&m, kick(0.0, 0.0), &t);
    assert!(tr.phase.iter().skip(1).all(|p| *p == Phase::Sliding));
    let a = -G_MPS2 * 60f64.to_radians().sin() + G_MPS2 * 0.05 / m.groove.s;
    assert!(
        (tr.v_mps[10] - a * 0.01).abs() < 1e-12,
        "v {} vs {}",
        tr.v_mps[10],
        a * 0.01
    );
    // and a gentle tilt rolls
    let m = model(0.05, vec![Term::GrooveTilt { alpha_deg: 5.0 }]);
    let tr = simulate(&m, kick(0.0, 0.0), &t);
    assert!(tr.phase.iter().all(|p| *p == Phase::Rolling));
}

#[test]
fn velocity_dependent_friction_slides_longer_and_tends_to_coulomb() {
    let t = times(400, 2.5e-4);
    let coulomb = simulate(&Model::baseline(0.293, 0.05), kick(0.02, 0.0), &t);
    let with = |v_c: f64| {
        let m = Model {
            groove: Groove::CHAPTER,
            friction: Friction::VelocityDependent {
                mu_inf: 0.293,
                v_c_mps: v_c,
            },
            variation: Default::default(),
            terms: vec![Term::LinearDrag { t_s: 0.05 }],
        };
        simulate(&m, kick(0.02, 0.0), &t)
    };
    let sharp = with(1e-7);
    for (k, tk) in t.iter().enumerate() {
        assert!(
            (sharp.z_m[k] - coulomb.z_m[k]).abs() < 2e-9,
            "v_c → 0 is Coulomb: t {tk} {} vs {}",
            sharp.z_m[k],
            coulomb.z_m[k]
        );
    }
    let soft = with(0.02);
    let t1 = |tr: &groove::physics::Trajectory| tr.events.last().unwrap().t_s;
    assert_eq!(soft.events.last().unwrap().to, Phase::Rolling);
    assert!(
        t1(&soft) > 1.5 * t1(&coulomb),
        "{} vs {}",
        t1(&soft),
        t1(&coulomb)
    );
}

#[test]
fn integrator_is_mirror_symmetric_with_extra_terms() {
    let terms = vec![
        Term::SaturatingDrag {
            t0_s: 0.05,
            tp_s_per_mps: 1.5,
        },
        Term::QuadraticDrag { c_per_m: 3.0 },
        Term::RollingResistance { c: 0.001 },
    ];
    let m = model(0.337, terms);
    let t = times(600, 1e-4);
    let a = simulate(&m, kick(0.07, 0.01), &t);
    let b = simulate(&m, kick(-0.07, -0.01), &t);
    for k in 0..t.len() {
        assert!((a.z_m[k] + b.z_m[k]).abs() < 1e-15 && a.phase[k] == b.phase[k]);
    }
}

fn rolling_pair(
    groove: Groove,
    mu_pp: f64,
    t_drag: Option<f64>,
    u1: f64,
) -> (Model, PairParams, [State; 2]) {
    let m = Model {
        groove,
        friction: Friction::Constant { mu: 0.337 },
        variation: Default::default(),
        terms: t_drag
            .map(|t_s| vec![Term::LinearDrag { t_s }])
            .unwrap_or_default(),
    };
    let p = PairParams {
        restitution: Restitution::Constant(1.0),
        mu_pp,
        radius_m: 150e-6,
        force: None,
        slip: None,
    };
    let init = [
        State {
            z_m: 0.0,
            v_mps: u1,
            va_mps: u1 / groove.s,
        },
        State {
            z_m: 1e-4 + 2.0 * p.radius_m,
            v_mps: 0.0,
            va_mps: 0.0,
        },
    ];
    (m, p, init)
}

#[test]
fn rolling_pair_velocity_difference_scales_by_0_090() {
    // the first impact, then each particle re-accelerates alone to rolling (no drag, elastic)
    for &mu_pp in &[1.4, 0.05] {
        let (m, p, init) = rolling_pair(Groove::CHAPTER, mu_pp, None, 0.05);
        let pair = simulate_pair(&m, &p, init, &[0.0, 0.01]);
        let first = &pair.impacts[0];
        assert_eq!(first.slip, mu_pp < 0.5, "stick for μ_pp 1.4, slip for 0.05");
        let after = |s: State| simulate(&m, State { z_m: 0.0, ..s }, &[1.0]).v_mps[0];
        let ratio = (after(first.post[0]) - after(first.post[1])) / (0.05 - 0.0);
        let expected = Groove::CHAPTER.collision_factor();
        assert!(
            (ratio - expected).abs() < 1e-10,
            "ratio {ratio} vs {expected}"
        );
        assert!((ratio - 0.090).abs() < 5e-4);
    }
}

#[test]
fn secondary_collisions_below_78_5_degrees_only() {
    // Eq. 4.18 is exact for the ideal model (elastic, no drag); with drag, at the chapter's angle
    let cases = [
        (70.6, None, true),
        (70.6, Some(0.05), true),
        (78.0, None, true),
        (79.0, None, false),
        (79.0, Some(0.05), false),
        (90.0, None, false),
    ];
    for &(theta, t_drag, cascade) in &cases {
        let g = Groove::from_angle_deg(theta);
        let (m, p, init) = rolling_pair(g, 1.4, t_drag, 0.05);
        // without drag the second impact at 78° comes after ~0.8 s
        let pair = simulate_pair(&m, &p, init, &times(301, 1e-2));
        let n = pair.impacts.len();
        if cascade {
            assert!(n >= 3, "θ {theta}: {n} impacts");
            // approach speeds shrink from one impact to the next
            for w in pair.impacts.windows(2) {
                assert!(w[1].v_impact_mps < w[0].v_impact_mps);
            }
        } else {
            assert_eq!(n, 1, "θ {theta}: {n} impacts");
        }
    }
}

#[test]
fn pair_ends_up_rolling_2r_apart() {
    for &dir in &[1.0, -1.0] {
        let m = Model::baseline(0.337, 0.08);
        let p = PairParams {
            restitution: Restitution::SpeedDependent {
                c0: 0.5,
                v_ref_mps: 0.05,
            },
            mu_pp: 1.4,
            radius_m: 150e-6,
            force: None,
            slip: None,
        };
        let (s, r) = (
            State {
                z_m: 0.0,
                v_mps: dir * 0.08,
                va_mps: 0.0,
            },
            State {
                z_m: dir * 1.3e-3,
                v_mps: 0.0,
                va_mps: 0.0,
            },
        );
        let t = times(1001, 1e-4);
        let pair = simulate_pair(&m, &p, [s, r], &t);
        let k = t.len() - 1;
        let dist = (pair.particles[1].z_m[k] - pair.particles[0].z_m[k]).abs();
        assert!((dist - 3e-4).abs() < 1e-6, "distance {dist} vs 2R = 3e-4");
        assert!(pair
            .particles
            .iter()
            .all(|tr| tr.phase[k] == Phase::Rolling));
        assert!(
            pair.particles[1].z_m[k] * dir > 1.3e-3,
            "target moved forward"
        );
        // every impact conserves momentum
        for i in &pair.impacts {
            let pre = i.pre[0].v_mps + i.pre[1].v_mps;
            let post = i.post[0].v_mps + i.post[1].v_mps;
            assert!((pre - post).abs() < 1e-15);
        }
    }
}

#[test]
fn contact_pair_collides_at_once() {
    let m = Model::baseline(0.293, 0.06);
    let p = PairParams {
        restitution: Restitution::Constant(0.8),
        mu_pp: 1.4,
        radius_m: 150e-6,
        force: None,
        slip: None,
    };
    let init = [
        State {
            z_m: 0.0,
            v_mps: 0.2,
            va_mps: 0.0,
        },
        State {
            z_m: 3e-4,
            v_mps: 0.0,
            va_mps: 0.0,
        },
    ];
    let pair = simulate_pair(&m, &p, init, &times(601, 1e-4));
    let first = &pair.impacts[0];
    assert_eq!(first.t_s, 0.0);
    assert!((first.post[1].v_mps - 0.9 * 0.2).abs() < 1e-15);
    assert!((first.post[0].v_mps - 0.1 * 0.2).abs() < 1e-15);
    // measured restitution (Eq. 4.20) recovers C
    let c = (first.post[1].v_mps - first.post[0].v_mps) / (first.pre[0].v_mps - first.pre[1].v_mps);
    assert!((c - 0.8).abs() < 1e-14);
}

/// The slide's own equations (`v' = −d g μ(u)/s + a`, `va' = d k g μ(u)`, slip `u = v − s va`
/// of a fixed sign) by classical RK4 at step `h`, far below the slip's relaxation time: the
/// reference for a creep. Returns z at every multiple of `every` steps, from t = 0.
fn slide_by_rk4(m: &Model, init: State, h: f64, steps: usize, every: usize) -> Vec<f64> {
    let g = m.groove;
    let d = (init.v_mps - g.s * init.va_mps).signum();
    let f = |y: [f64; 3], t: f64| {
        let mu = m.friction.kinetic(y[1] - g.s * y[2]);
        let a = m.accel(y[0], y[1], t);
        [y[1], -d * G_MPS2 * mu / g.s + a, d * g.k * G_MPS2 * mu]
    };
    let add =
        |y: [f64; 3], k: [f64; 3], c: f64| [y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2]];
    let mut y = [init.z_m, init.v_mps, init.va_mps];
    let mut z = vec![y[0]];
    for i in 0..steps {
        let t = i as f64 * h;
        let k1 = f(y, t);
        let k2 = f(add(y, k1, h / 2.0), t + h / 2.0);
        let k3 = f(add(y, k2, h / 2.0), t + h / 2.0);
        let k4 = f(add(y, k3, h), t + h);
        for j in 0..3 {
            y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
        assert!(
            d * (y[1] - g.s * y[2]) > 0.0,
            "the reference's slip changed sign"
        );
        if (i + 1) % every == 0 {
            z.push(y[0]);
        }
    }
    z
}

#[test]
fn a_slip_held_by_a_downhill_force_creeps_as_the_stiff_slide_does() {
    // v_c = 50 µm/s: the slip relaxes in τ ≈ 5 µs, and a tilt downhill (0.17 m/s²) with a 0.4 mm
    // waviness (0.05 m/s², so the held slip changes along the way) keeps it from ever reaching
    // zero: the particle slides to the end, on the slip's quasi-static value after 2 ms
    let m = Model {
        groove: Groove::CHAPTER,
        friction: Friction::VelocityDependent {
            mu_inf: 0.3,
            v_c_mps: 5e-5,
        },
        variation: Default::default(),
        terms: vec![
            Term::GrooveTilt { alpha_deg: -1.0 },
            Term::PositionForce {
                amp_mps2: 0.05,
                wavelength_m: 0.4e-3,
                phase_rad: 0.3,
            },
        ],
    };
    let init = kick(0.02, 0.0);
    let (h, every) = (2e-7, 2_500);
    let t = times(101, h * every as f64);
    let reference = slide_by_rk4(&m, init, h, 100 * every, every);
    let tr = simulate(&m, init, &t);
    assert!(tr.phase.iter().all(|p| *p == Phase::Sliding));
    assert!(tr.z_m[100] > 0.5e-3, "it moved {} m", tr.z_m[100]);
    for (k, tk) in t.iter().enumerate() {
        // within 2e-12 m; without the creep's u' = τ ȧ z was off by up to 4e-9 m, and without
        // the slip put on its quasi-static value at entry by 5e-9 m
        assert!(
            (tr.z_m[k] - reference[k]).abs() < 2e-11,
            "t {tk}: {} vs the stiff slide's {} ({:.1e} m apart)",
            tr.z_m[k],
            reference[k],
            tr.z_m[k] - reference[k]
        );
    }
}

/// A simulation the error control cannot finish within its step budget says so (`stalled`), and
/// one that ends normally does not: a force of 1 nm wavelength, crossed at 0.1 m/s, asks for
/// steps far below its 10 ns period, so the budget covers well under the 20 ms asked for.
#[test]
fn a_simulation_that_stops_at_its_step_budget_says_it_stalled() {
    let t = times(41, 5e-4);
    let calm = simulate(&model(0.337, vec![]), kick(0.1, 0.0), &t);
    assert!(!calm.stalled);
    let rough = model(
        0.337,
        vec![Term::PositionForce {
            amp_mps2: 50.0,
            wavelength_m: 1e-9,
            phase_rad: 0.0,
        }],
    );
    let tr = simulate(&rough, kick(0.1, 0.0), &t);
    assert!(tr.stalled, "the budget covered the whole run");
    assert_eq!(tr.z_m.len(), t.len(), "every sample is still filled");
    assert_eq!(tr.z_m[40], tr.z_m[39], "the state reached is held");
}
