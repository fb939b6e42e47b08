//! Tests of `track`.

use super::*;

pub(crate) fn paper_track(n: usize, nm: usize) -> TrackParams {
    TrackParams {
        mr: 60.64,
        ei: 6.6e6,
        ms: 125.5,
        mb: 310.0,
        kp: 60e6,
        cp: 75e3,
        kb: 150e6,
        cb: 60e3,
        kf: 70e6,
        cf: 100e3,
        kw: 78e6,
        cw: 80e3,
        ls: 0.6,
        n_sleepers: n,
        n_modes: nm,
    }
}

/// Deflection under one load P at x (m) of a track with `kw`.
fn bowl(n: usize, nm: usize, kw: f64, x: f64, p: f64) -> (Track, Vec<f64>, usize) {
    let mut tp = paper_track(n, nm);
    tp.kw = kw;
    let mut t = Track::new(tp).unwrap();
    t.set_wheels(&[x, x, x, x]);
    let mut y = vec![0.0; t.dim()];
    let it = t.static_solve(&[p, 0.0, 0.0, 0.0], &mut y).unwrap();
    (t, y, it)
}

#[test]
fn wheel_sines_by_recurrence_are_accurate() {
    let mut t = Track::new(paper_track(255, 511)).unwrap();
    t.set_wheels(&[0.3, 76.9, 100.123, 153.0]);
    for j in 0..4 {
        let x = [0.3, 76.9, 100.123, 153.0][j];
        let mut worst = 0.0f64;
        for k in 1..=511 {
            let exact = (k as f64 * PI * x / t.length).sin();
            worst = worst.max((t.wheel_sine(j, k) - exact).abs());
        }
        assert!(worst < 1e-10, "x = {x}: error {worst:e}");
    }
}

#[test]
fn static_load_is_carried_to_the_subgrade() {
    // Far from the ends, the subgrade springs carry the whole load (Σ Kf Zb = P).
    // (Up to the part of the point load that NM modes cannot resolve: 6e-4 at NM = N/2.)
    let p = 69e3;
    for (nm, tol) in [(128, 1e-3), (255, 2e-4)] {
        let (t, y, it) = bowl(255, nm, 78e6, 76.8, p);
        let zb = &y[t.nm + t.n..];
        let sum: f64 = zb.iter().map(|z| t.p.kf * z).sum();
        assert!(
            (sum / p - 1.0).abs() < tol,
            "NM {nm}: subgrade carries {sum} N"
        );
        assert!(it < 500, "{it} iterations");
    }
}

#[test]
fn deflection_close_to_a_winkler_beam() {
    // Without ballast shear the supports are independent springs in series, smeared
    // over l_s: a beam on an elastic foundation k = Kp·Kb·Kf/(…)/l_s. Peak deflection
    // P/(8 EI β³), β = (k/(4EI))^¼, within the error of smearing discrete supports.
    let p = 69e3;
    let (t, y, _) = bowl(255, 255, 0.0, 76.8, p);
    let zr = t.rail_at_wheels(&y[..t.nm])[0];
    let tp = t.p;
    let ks = 1.0 / (1.0 / tp.kp + 1.0 / tp.kb + 1.0 / tp.kf) / tp.ls;
    let beta = (ks / (4.0 * tp.ei)).powf(0.25);
    let w = p / (8.0 * tp.ei * beta.powi(3));
    assert!(
        (zr / w - 1.0).abs() < 0.05,
        "rail {zr:e} m, Winkler {w:e} m"
    );
}

#[test]
fn dynamic_forces_vanish_in_the_static_state() {
    let p = 69e3;
    let (mut t, y, _) = bowl(127, 64, 78e6, 40.0, p);
    let mut acc = vec![0.0; t.dim()];
    let yd = vec![0.0; t.dim()];
    t.accelerations(&y, &yd, &[p, 0.0, 0.0, 0.0], &mut acc);
    let max = acc.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!(max < 1e-6, "max residual acceleration {max:e}");
}

#[test]
fn window_shift_moves_the_deflection_bowl() {
    // The bowl under a load at x, moved back by m sleepers, is the bowl under x − m l_s:
    // exactly for sleepers and ballast, and for the rail up to its projection on NM modes.
    for (nm, tol) in [(255usize, 2e-5), (128, 2e-3)] {
        let (mut t1, mut y1, _) = bowl(255, nm, 78e6, 90.0, 69e3);
        t1.shift(20, &mut y1);
        let (mut t2, y2, _) = bowl(255, nm, 78e6, 78.0, 69e3);
        t2.set_wheels(&[78.0; 4]);
        let peak = t2.rail_at_wheels(&y2[..nm])[0];
        let nodal = y1[nm..]
            .iter()
            .zip(&y2[nm..])
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            nodal < tol * peak,
            "NM {nm}: sleepers/ballast differ by {nodal:e}"
        );
        for x in [70.0, 78.0, 78.3, 85.0] {
            t1.set_wheels(&[x; 4]);
            t2.set_wheels(&[x; 4]);
            let (a, b) = (
                t1.rail_at_wheels(&y1[..nm])[0],
                t2.rail_at_wheels(&y2[..nm])[0],
            );
            assert!(
                (a - b).abs() < tol * peak,
                "NM {nm}, x = {x}: rail {a:e} vs {b:e}"
            );
        }
    }
}

#[test]
fn refuses_bad_sizes() {
    assert!(Track::new(paper_track(100, 50)).is_err());
    assert!(Track::new(paper_track(63, 0)).is_err());
    assert!(Track::new(paper_track(63, 128)).is_err());
    assert!(Track::new(paper_track(63, 127)).is_ok());
}

#[test]
fn contiguous_fold_equals_the_sine_identity_bit_for_bit() {
    // Independent of the kernel: the fold must reproduce Σ_k w_k sin(kπi/(N+1)) at every
    // sleeper i, i.e. bin b collects +w_{b+1} and −w_{2N+1−b}; mode N + 1 vanishes on the grid.
    for (n, nm) in [(7, 3), (7, 7), (7, 8), (7, 9), (7, 15), (127, 255)] {
        let modal: Vec<f64> = (0..nm)
            .map(|k| ((k * 37 % 11) as f64 - 5.3) * 1.7)
            .collect();
        let mut bins = vec![f64::NAN; n];
        fold(&modal, &mut bins);
        for (b, &got) in bins.iter().enumerate() {
            let mut want = 0.0;
            for (k, &w) in modal.iter().enumerate() {
                let m = k + 1;
                if m == b + 1 {
                    want += w;
                } else if m == 2 * n + 1 - b {
                    want -= w;
                }
            }
            assert_eq!(got.to_bits(), want.to_bits(), "n {n} nm {nm} bin {b}");
        }
        // The sine identity itself, on the grid.
        let l = (n + 1) as f64;
        for i in 1..=n {
            let direct: f64 = (1..=nm)
                .map(|m| modal[m - 1] * (m as f64 * PI * i as f64 / l).sin())
                .sum();
            let folded: f64 = (1..=n)
                .map(|m| bins[m - 1] * (m as f64 * PI * i as f64 / l).sin())
                .sum();
            assert!((direct - folded).abs() < 1e-9, "n {n} nm {nm} i {i}");
        }
    }
}

#[test]
fn pad_input_folded_as_computed_gives_the_bits_of_the_folded_modal_vector() {
    // The stepping kernel folds Kp q + Cp q' onto the sleeper grid as it computes it; the rail
    // at the sleepers (the sine transform of those bins) must be the bits of the transform of
    // `fold` applied to the modal vector, for every count of folded modes.
    for (n, nm) in [(63, 64), (63, 65), (63, 100), (63, 127), (255, 511)] {
        let mut t = Track::new(paper_track(n, nm)).unwrap();
        let dim = t.dim();
        let y: Vec<f64> = (0..dim)
            .map(|i| ((i * 37 % 101) as f64 - 50.3) * 1e-6)
            .collect();
        let yd: Vec<f64> = (0..dim)
            .map(|i| ((i * 53 % 97) as f64 - 48.1) * 1e-4)
            .collect();
        t.set_wheels(&[10.0, 12.5, 27.9, 30.4]);
        let mut acc = vec![0.0; dim];
        t.accelerations(&y, &yd, &[7e4, 7e4, 7e4, 7e4], &mut acc);
        let tp = t.p;
        let modal: Vec<f64> = (0..nm).map(|k| tp.kp * y[k] + tp.cp * yd[k]).collect();
        let mut bins = vec![f64::NAN; n];
        fold(&modal, &mut bins);
        let mut want = vec![0.0; n];
        DstI::new(n).unwrap().transform(&bins, &mut want);
        for i in 0..n {
            assert_eq!(
                t.r[i].to_bits(),
                want[i].to_bits(),
                "n {n} nm {nm} sleeper {i}"
            );
        }
    }
}
