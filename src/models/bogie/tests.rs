use super::*;

/// Runs `b` from t = 0 to `stop` (s) with communication step `comm` (s) and returns the
/// samples (t, Y, V).
fn run(b: &mut Bogie, stop: f64, comm: f64) -> Vec<(f64, f64, f64)> {
    b.initialize(&InitContext::default()).unwrap();
    let n = (stop / comm).round() as usize;
    let mut out = Vec::with_capacity(n + 1);
    out.push((0.0, b.x[0], b.speed(0.0)));
    for i in 0..n {
        let t = i as f64 * comm;
        b.do_step(t, comm).unwrap();
        let t1 = (i + 1) as f64 * comm;
        out.push((t1, b.x[0], b.speed(t1)));
    }
    out
}

/// The paper's "speed at which the oscillation dies out", as the uq-driver's critical-speed
/// quantity defines it: t* is the first sample time after which every trailing `window` (s)
/// holds only |Y| < `threshold` (m); the speed reported is V(t* − window). With samples
/// every `comm` s, t* − window lies within one sample after the last |Y| >= threshold.
fn died_out_speed(samples: &[(f64, f64, f64)], window: f64, threshold: f64) -> Option<f64> {
    let last = samples.iter().rposition(|s| s.1.abs() >= threshold)?;
    let t_last = samples[last].0;
    let star = samples.iter().find(|s| s.0 - window > t_last)?.0;
    let (t0, v0) = (samples[0].0, samples[0].2);
    let slope = (samples[1].2 - v0) / (samples[1].0 - t0); // the speed is linear in t
    Some(v0 + slope * (star - window - t0))
}

fn max_abs_y(samples: &[(f64, f64, f64)], from: f64) -> f64 {
    samples
        .iter()
        .filter(|s| s.0 >= from)
        .fold(0.0, |m, s| m.max(s.1.abs()))
}

#[test]
fn creep_law_is_continuous_at_saturation_and_linear_for_small_creepage() {
    let p = BogieParams::default();
    let mun = p.mu * p.n;
    // Along several directions, u = 3 ± ε gives the same force, of magnitude μN.
    for angle in [0.0f64, 0.3, 1.0, 2.5, 4.0] {
        let (cx, cy) = (angle.cos() * p.psi, angle.sin() * p.phi_c);
        let below = creep_force(cx * (3.0 - 1e-9), cy * (3.0 - 1e-9), &p);
        let above = creep_force(cx * (3.0 + 1e-9), cy * (3.0 + 1e-9), &p);
        assert!((below.0 - above.0).abs() < 1e-5 * mun, "{angle}");
        assert!((below.1 - above.1).abs() < 1e-5 * mun, "{angle}");
        let r = below.0.hypot(below.1);
        assert!((r - mun).abs() < 1e-6 * mun, "|F| = {r} at u = 3");
        // Far beyond saturation the resultant stays μN.
        let far = creep_force(cx * 50.0, cy * 50.0, &p);
        assert!((far.0.hypot(far.1) - mun).abs() < 1e-9 * mun);
    }
    // u -> 0: F -> μN ξ/ψ, μN ξ/ϕ (no 0/0).
    assert_eq!(creep_force(0.0, 0.0, &p), (0.0, 0.0));
    let (xx, xy) = (1e-10, -2e-10);
    let (fx, fy) = creep_force(xx, xy, &p);
    assert!((fx / (mun * xx / p.psi) - 1.0).abs() < 1e-6);
    assert!((fy / (mun * xy / p.phi_c) - 1.0).abs() < 1e-6);
    // The cubic itself: u = 1 along x gives μN (1 - 1/3 + 1/27).
    let (fx, fy) = creep_force(p.psi, 0.0, &p);
    assert!((fx - mun * (1.0 - 1.0 / 3.0 + 1.0 / 27.0)).abs() < 1e-9 * mun);
    assert_eq!(fy, 0.0);
}

#[test]
fn flange_force_is_continuous_at_clearance_and_odd() {
    let (k0, d) = (14.6e6, 9.1e-3);
    for y in [d - 1e-12, d, d + 1e-12] {
        assert!(flange_force(y, k0, d).abs() < 1e-4, "{y}");
        assert!(flange_force(-y, k0, d).abs() < 1e-4, "{y}");
    }
    assert_eq!(flange_force(0.0, k0, d), 0.0);
    assert_eq!(flange_force(0.5 * d, k0, d), 0.0);
    for y in [0.0, 0.005, 0.0091, 0.0095, 0.012, 0.05] {
        assert_eq!(flange_force(-y, k0, d), -flange_force(y, k0, d));
    }
    assert!((flange_force(0.0101, k0, d) - k0 * 0.001).abs() < 1e-6);
}

#[test]
fn linear_state_matrix_is_the_jacobian_of_rhs_at_the_centre() {
    let p = BogieParams::default();
    for v in [30.0, 75.0, 120.0] {
        let a = linear_state_matrix(&p, v);
        // Central differences with steps far inside the dead band and the linear creep range.
        let steps = [1e-7, 1e-8, 1e-6, 1e-7];
        for j in 0..4 {
            let mut xp = [0.0; 4];
            let mut xm = [0.0; 4];
            xp[j] = steps[j];
            xm[j] = -steps[j];
            let (fp, fm) = (rhs(&p, v, &xp), rhs(&p, v, &xm));
            for i in 0..4 {
                let d = (fp[i] - fm[i]) / (2.0 * steps[j]);
                let scale = a[(i, j)].abs().max(1e-6);
                assert!(
                    (d - a[(i, j)]).abs() < 1e-4 * scale,
                    "V={v} A[{i},{j}] = {} vs finite difference {d}",
                    a[(i, j)]
                );
            }
        }
    }
}

#[test]
fn linear_critical_speed_is_near_75() {
    let b = Bogie::default();
    let v = linear_critical_speed(&b);
    assert!((v - 74.92).abs() < 0.01, "v_lin = {v}");
    assert!(linear_growth_rate(&b.p, v - 0.01) < 0.0);
    assert!(linear_growth_rate(&b.p, v + 0.01) > 0.0);
    // Stiffer anti-yaw suspension raises it; a larger conicity lowers it.
    let mut stiff = Bogie::default();
    stiff.p.k_phi *= 1.1;
    assert!(linear_critical_speed(&stiff) > v);
    let mut conic = Bogie::default();
    conic.p.lambda = 0.055;
    assert!(linear_critical_speed(&conic) < v);
}

#[test]
fn small_disturbance_decays_below_and_grows_above_the_linear_critical_speed() {
    let v_lin = linear_critical_speed(&Bogie::default());
    let at = |v: f64| {
        let mut b = Bogie {
            v0: v,
            ramp: 0.0,
            y0: 1e-3,
            ..Bogie::default()
        };
        let s = run(&mut b, 40.0, 0.01);
        assert!(s.iter().all(|x| x.2 == v), "constant speed");
        max_abs_y(&s, 38.0)
    };
    let below = at(0.95 * v_lin);
    let above = at(1.05 * v_lin);
    assert!(
        below < 1e-4,
        "at 0.95 v_lin the 1 mm disturbance should decay: {below}"
    );
    assert!(
        above > 5e-3,
        "at 1.05 v_lin it should grow into hunting: {above}"
    );
}

#[test]
fn halving_dt_changes_y_by_less_than_2e_6_m_over_20_s() {
    // 20 s from V0 = 80 m/s (hunting with flange contact, amplitude ~ 9 mm). The flange kinks
    // at ±δ make the convergence order irregular: max |Y(dt) - Y(dt/2)| measured for
    // dt = 4, 2, 1, 0.5, 0.25 ms: 2.8e-6, 3.1e-6, 8.0e-7, 2.0e-7, 1.1e-7 m. The default
    // dt = 1 ms is within 1e-4 of the amplitude of dt/2.
    let traj = |dt: f64| {
        let mut b = Bogie {
            v0: 80.0,
            dt,
            ..Bogie::default()
        };
        run(&mut b, 20.0, 0.01)
    };
    let (coarse, fine) = (traj(1e-3), traj(5e-4));
    let amplitude = max_abs_y(&coarse, 10.0);
    assert!(amplitude > 8e-3, "hunting expected: {amplitude}");
    let diff = coarse
        .iter()
        .zip(&fine)
        .map(|(c, f)| (c.1 - f.1).abs())
        .fold(0.0, f64::max);
    assert!(diff < 2e-6, "max |Y(dt) - Y(dt/2)| = {diff:e} m");
}

#[test]
fn ramp_critical_speed_matches_the_paper_within_1_percent() {
    // The paper's ramp: V0 = 100 m/s, Δf = 10, Y0 = 12 mm; "died out" = 1 s sliding maximum
    // of |Y| below 0.1 mm; speed read at the start of the quiet window. Measured 64.865 m/s
    // (V at the end of the window: 64.765 m/s); the paper reports 64.82 m/s, MODELS.md's
    // reconstruction ~64.7 m/s. Halving dt does not move it (the same 0.01 s sample).
    let vcr = |dt: f64| {
        let mut b = Bogie {
            dt,
            ..Bogie::default()
        };
        let s = run(&mut b, 400.0, 0.01);
        died_out_speed(&s, 1.0, 1e-4).expect("the hunting dies out on the ramp")
    };
    let (v, v_half) = (vcr(1e-3), vcr(5e-4));
    assert!((v - v_half).abs() < 0.01, "dt 1 ms: {v}, 0.5 ms: {v_half}");
    let paper = 64.82;
    assert!(
        (v - paper).abs() < 0.01 * paper,
        "v_cr = {v} vs paper {paper}"
    );
    assert!((v - 64.865).abs() < 0.005, "regression: v_cr = {v}");
}

#[test]
fn full_ramp_reaches_55_m_per_s_and_stops_before_1_m_per_s() {
    let mut b = Bogie::default();
    b.initialize(&InitContext::default()).unwrap();
    // One big communication step exercises the substep logic.
    b.do_step(0.0, 450.0).unwrap();
    assert!((b.get_real(VR_V).unwrap() - 55.0).abs() < 1e-9);
    assert!(b.get_real(VR_Y).unwrap().abs() < 1e-9, "hunting died out");
    // Slow speeds are stable thanks to the rate-limited substeps, down to the guard.
    let mut slow = Bogie {
        v0: 10.0,
        ramp: 1.0,
        ..Bogie::default()
    };
    slow.initialize(&InitContext::default()).unwrap();
    let mut i = 0;
    let err = loop {
        match slow.do_step(0.1 * i as f64, 0.1) {
            Ok(()) => i += 1,
            Err(e) => break e,
        }
        assert!(slow.x.iter().all(|x| x.is_finite()));
        assert!(i < 100, "the speed guard must fire before t = 9 s");
    };
    assert_eq!(i, 89, "the step from 8.9 s to 9 s reaches V = 1 m/s");
    let msg = err.to_string();
    assert!(msg.contains("1 m/s") && msg.contains("t = 9 s"), "{msg}");
}

#[test]
fn an_absurd_step_is_refused_with_an_error_not_a_hang() {
    // At constant speed nothing else stops a step of 1e300 s: the substep count overflowed.
    let mut b = Bogie {
        ramp: 0.0,
        ..Bogie::default()
    };
    b.initialize(&InitContext::default()).unwrap();
    for h in [1e300, 1e6] {
        let e = b.do_step(0.0, h).unwrap_err();
        assert!(matches!(e, ModelError::StepTooLong(_)), "{e}");
    }
    b.do_step(0.0, 0.01).unwrap();
    // On the ramp the speed guard refuses it first.
    let mut b = Bogie::default();
    b.initialize(&InitContext::default()).unwrap();
    assert!(b
        .do_step(0.0, 1e300)
        .unwrap_err()
        .to_string()
        .contains("1 m/s"));
}

#[test]
fn refuses_bad_parameters() {
    let mut b = Bogie::default();
    for vr in [VR_K_SY, VR_C_SY, VR_K_PHI, VR_K0] {
        assert!(b.set_real(vr, -1.0).is_err(), "vr {vr} negative");
        assert!(b.set_real(vr, f64::NAN).is_err(), "vr {vr} NaN");
        assert!(b.set_real(vr, f64::INFINITY).is_err(), "vr {vr} inf");
    }
    for vr in [VR_M_B, VR_I_B, VR_H, VR_A, VR_R0, VR_PSI, VR_PHI_C, VR_DT] {
        assert!(b.set_real(vr, 0.0).is_err(), "vr {vr} zero");
        assert!(b.set_real(vr, -1.0).is_err(), "vr {vr} negative");
    }
    assert!(b.set_real(VR_V0, 1.0).is_err());
    assert!(b.set_real(VR_V0, f64::NAN).is_err());
    assert!(b.set_real(VR_RAMP, f64::INFINITY).is_err());
    assert!(b.set_real(VR_Y, 0.0).is_err(), "outputs are not settable");
    assert!(b.set_real(999, 0.0).is_err());
    // Refused values leave the parameter unchanged.
    assert_eq!(b.get_real(VR_K_SY).unwrap(), 0.1823e6);
    // Legal edge values.
    assert!(b.set_real(VR_K_SY, 0.0).unwrap().is_none());
    assert!(b.set_real(VR_RAMP, 0.0).unwrap().is_none());
    assert!(b.set_real(VR_RAMP, -5.0).unwrap().is_none());
}

#[test]
fn tunable_parameters_act_from_the_next_step() {
    let mut a = Bogie::default();
    let mut b = Bogie::default();
    a.initialize(&InitContext::default()).unwrap();
    b.initialize(&InitContext::default()).unwrap();
    a.do_step(0.0, 1.0).unwrap();
    b.do_step(0.0, 1.0).unwrap();
    b.set_real(VR_K_SY, 0.2e6).unwrap();
    a.do_step(1.0, 0.5).unwrap();
    b.do_step(1.0, 0.5).unwrap();
    assert_ne!(a.x, b.x);
}

#[test]
fn a_new_speed_takes_effect_from_the_step_it_is_set_and_restarts_the_ramp() {
    // Set at t = 1 s to 80 m/s on a ramp of 10 s²/m: V(1.5) = 80 − 0.5/10.
    let mut b = Bogie::default();
    b.initialize(&InitContext::default()).unwrap();
    b.do_step(0.0, 1.0).unwrap();
    assert!((b.get_real(VR_V).unwrap() - 99.9).abs() < 1e-12);
    b.set_real(VR_V0, 80.0).unwrap();
    assert_eq!(b.get_real(VR_V).unwrap(), 80.0);
    b.do_step(1.0, 0.5).unwrap();
    assert!((b.get_real(VR_V).unwrap() - 79.95).abs() < 1e-12);
    // The same as a run that started at 80 m/s at t = 1 s from the same state.
    let mut c = Bogie {
        v0: 80.0,
        ..Bogie::default()
    };
    c.initialize(&InitContext {
        start_time: 1.0,
        ..InitContext::default()
    })
    .unwrap();
    let mut a = Bogie::default();
    a.initialize(&InitContext::default()).unwrap();
    a.do_step(0.0, 1.0).unwrap();
    c.x = a.x;
    c.do_step(1.0, 0.5).unwrap();
    assert_eq!(c.x, b.x);
}

#[test]
fn save_restore_round_trip() {
    let mut b = Bogie {
        v0: 90.0,
        ..Bogie::default()
    };
    b.set_real(VR_C_SY, 31e3).unwrap();
    b.initialize(&InitContext {
        start_time: 2.0,
        ..InitContext::default()
    })
    .unwrap();
    b.do_step(2.0, 0.37).unwrap();
    let mut out = StateWriter::default();
    b.save(&mut out);
    let mut c = Bogie::default();
    c.restore(&mut StateReader::new(&out.bytes)).unwrap();
    assert_eq!(c.x, b.x);
    assert_eq!(c.p, b.p);
    for v in &VARIABLES {
        assert_eq!(
            b.get_real(v.vr).unwrap().to_bits(),
            c.get_real(v.vr).unwrap().to_bits(),
            "{}",
            v.name
        );
    }
    // Both continue identically.
    b.do_step(2.37, 0.5).unwrap();
    c.do_step(2.37, 0.5).unwrap();
    assert_eq!(c.x, b.x);
    assert!(c
        .restore(&mut StateReader::new(&out.bytes[..out.bytes.len() - 3]))
        .is_err());
}

#[test]
fn variable_table_matches_defaults_and_units() {
    let b = Bogie::default();
    crate::models::assert_table_sorted_and_unique(&INFO);
    for v in &VARIABLES {
        let value = b.get_real(v.vr).unwrap();
        assert!(value.is_finite(), "{}", v.name);
        if let crate::models::Start::Real(Some(start)) = v.start {
            assert_eq!(value, start, "{}: start value vs Bogie::default()", v.name);
        }
        if let Some(u) = v.unit {
            assert!(
                crate::fmi2::xml::UNITS.iter().any(|(n, _)| *n == u),
                "{}: unit {u} not in the unit table",
                v.name
            );
        }
    }
    assert!(crate::fmi2::xml::model_description(&INFO).is_ok());
}

#[test]
fn outputs_are_consistent_with_the_equations() {
    let mut b = Bogie::default();
    b.initialize(&InitContext::default()).unwrap();
    b.do_step(0.0, 3.21).unwrap();
    let g = |vr| b.get_real(vr).unwrap();
    let (y, phi) = (g(VR_Y), g(VR_PHI));
    assert!((g(VR_V) - (100.0 - 0.321)).abs() < 1e-12);
    assert_eq!(g(VR_Y1), y + 1.5 * phi);
    assert_eq!(g(VR_Y2), y - 1.5 * phi);
    assert_eq!(g(VR_F_T), flange_force(g(VR_Y1), 14.6e6, 9.1e-3));
    let (fx1, fy1) = creep_force(g(VR_XI_X1), g(VR_XI_Y1), &b.p);
    assert_eq!((g(VR_FX1), g(VR_FY1)), (fx1, fy1));
    let ydd =
        (-2.0 * 29.2e3 * g(VR_YD) - 2.0 * 0.1823e6 * y - 2.0 * (g(VR_FY1) + g(VR_FY2)) - g(VR_F_T))
            / 4963.0;
    assert!((g(VR_YDD) - ydd).abs() < 1e-9 * ydd.abs().max(1.0));
}
