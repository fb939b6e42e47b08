//! `roll_moment`: the wheelset's roll moment with or without that of the lateral contact
//! forces.

use super::*;

/// The car on the RSGEO table in a steady curve (R = 1000 m, cant 0.05 rad, 30 m/s, entered
/// over 3 s) after `seconds`, with `roll_moment` = `code`.
fn in_curve(code: i32, seconds: usize) -> Vehicle {
    let mut m = Vehicle::default();
    m.set_string(VR_CONTACT_TABLE, &rsgeo_path()).unwrap();
    m.set_integer(VR_ROLL_MOMENT, code).unwrap();
    m.set_real(VR_V, 30.0).unwrap();
    m.set_real(VR_R, 1000.0).unwrap();
    m.set_real(VR_CANT, 0.05).unwrap();
    m.set_real(VR_TRANSITION, 3.0).unwrap();
    for w in 0..4 {
        m.set_real(VR_Y0_W1 + w, 0.0).unwrap();
    }
    m.initialize(&InitContext::default()).unwrap();
    for i in 0..seconds * 100 {
        m.do_step(i as f64 * 0.01, 0.01).unwrap();
    }
    m
}

#[test]
#[cfg_attr(debug_assertions, ignore = "dynamics: run with cargo test --release")]
fn the_lateral_forces_roll_moment_unloads_the_inner_wheels_more_and_keeps_the_balance() {
    let (reference, complete) = (in_curve(0, 25), in_curve(1, 25));
    // The curve turns to the right (R > 0): the right wheels are the inner ones. The lateral
    // forces push the wheelsets outward at the rail heads, r below the axles: their moment
    // takes load off the inner wheels (an independent model: inner ΔQ/Q 0.128 with it, 0.101
    // without, R = 1000 m, 30 m/s, cant 0.05 rad).
    for vr in [VR_DQQ_1R, VR_DQQ_1R + 2, VR_DQQ_1R + 4, VR_DQQ_1R + 6] {
        let (a, b) = (out(&reference, vr), out(&complete, vr));
        assert!(a > 0.05 && b > 1.15 * a && b < 1.5 * a, "dQQ {a} -> {b}");
    }
    // The rails still carry the uncompensated centrifugal force and the weight.
    let sum = |m: &Vehicle, from: u32| (from..from + 8).map(|vr| out(m, vr)).sum::<f64>();
    for (from, tolerance) in [(VR_Y_1L, 0.02), (VR_Q_1L, 1e-4)] {
        let (a, b) = (sum(&reference, from), sum(&complete, from));
        assert!((a - b).abs() < tolerance * a.abs(), "{a} vs {b}");
    }
}

#[test]
fn roll_moment_is_0_or_1_and_a_change_recomputes_the_linear_critical_speed() {
    let mut m = Vehicle::default();
    let e = m.set_integer(VR_ROLL_MOMENT, 2).unwrap_err().to_string();
    assert!(e.contains("must be 0") && e.contains("or 1"), "{e}");
    // Read before initialization, as an importer may, then changed: computed again.
    m.set_string(VR_CONTACT_TABLE, &rsgeo_path()).unwrap();
    let v0 = out(&m, VR_V_CR_LINEAR);
    m.set_integer(VR_ROLL_MOMENT, 1).unwrap();
    let v1 = out(&m, VR_V_CR_LINEAR);
    // Measured: 109.006 m/s without the moment, 109.027 with it.
    assert!(v0 != v1 && (v0 - v1).abs() < 0.2, "{v0} -> {v1}");
    m.initialize(&InitContext::default()).unwrap();
    assert_eq!(out(&m, VR_V_CR_LINEAR), v1);
}
