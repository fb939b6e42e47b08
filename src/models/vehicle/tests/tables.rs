//! The contact tables the car reads: table files, tables computed from profile files, and the
//! built-in table (its spline and its geometry figures).

use super::*;

#[test]
fn contact_table_files_are_read_from_the_resources_folder_and_bad_ones_refused() {
    let dir = std::env::temp_dir().join(format!("railuq-vehicle-table-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The built-in table written to a file gives the same car.
    std::fs::write(
        dir.join("t.csv"),
        builtin_contact_table().unwrap().to_string(),
    )
    .unwrap();
    let ctx = InitContext {
        start_time: 0.0,
        resource_dir: Some(dir.clone()),
    };
    let mut m = Vehicle::default();
    m.set_string(VR_CONTACT_TABLE, "t.csv").unwrap();
    m.initialize(&ctx).unwrap();
    let reference = model(40.0, [1e-4, 0.0, 8e-3, 0.0]);
    assert_eq!(out(&m, VR_Y_1L), out(&reference, VR_Y_1L));
    // Bad files: the message names the file and the line, never its contents.
    let good = builtin_contact_table().unwrap().to_string();
    let lines: Vec<&str> = good.lines().collect();
    let mut bad_value = lines.clone();
    bad_value[3] = "SECRET,1,2,3,4,5,6,7,8,9,10,11";
    let mut nan = lines.clone();
    let nan_line = lines[5].replacen(',', ",nan,", 1);
    nan[5] = nan_line.as_str();
    let mut descending = lines.clone();
    descending.swap(7, 8);
    let one_side: String = lines
        .iter()
        .enumerate()
        .filter(|(i, l)| *i == 0 || !l.starts_with('-'))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let cases = [
        (
            "value.csv",
            bad_value.join("\n"),
            "line 4: column 'y' is not a number",
        ),
        ("nan.csv", nan.join("\n"), "line 6: column"),
        (
            "desc.csv",
            descending.join("\n"),
            "line 8: y must ascend in equal steps",
        ),
        ("oneside.csv", one_side, "y must cover both signs around 0"),
    ];
    for (name, text, expected) in cases {
        std::fs::write(dir.join(name), text).unwrap();
        let mut m = Vehicle::default();
        m.set_string(VR_CONTACT_TABLE, name).unwrap();
        let e = m.initialize(&ctx).unwrap_err().to_string();
        assert!(e.contains(expected) && e.contains(name), "{e}");
        assert!(!e.contains("SECRET") && e.len() < 300, "{e}");
    }
    let mut m = Vehicle::default();
    m.set_string(VR_CONTACT_TABLE, dir.to_str().unwrap())
        .unwrap();
    let e = m.initialize(&ctx).unwrap_err().to_string();
    assert!(e.contains("is a directory"), "{e}");
    #[cfg(unix)]
    if std::process::Command::new("mkfifo")
        .arg(dir.join("fifo"))
        .status()
        .is_ok_and(|s| s.success())
    {
        let mut m = Vehicle::default();
        m.set_string(VR_CONTACT_TABLE, "fifo").unwrap();
        let e = m.initialize(&ctx).unwrap_err().to_string();
        assert!(e.contains("FIFO"), "{e}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Largest excursion of the spline through `t` (column `col` of [`TableRow::values`]) beyond
/// the range of the four rows around each interval, sampled at 9 points per interval, less
/// what the rows' own curvature allows (a smooth extremum between two rows: a quarter of the
/// larger second difference at the interval's ends), and the y where it happens.
fn spline_overshoot(t: &ContactTable, col: usize) -> (f64, f64) {
    let sp = ContactSpline::new(t);
    let rows = t.rows();
    let mut worst = (0.0f64, 0.0);
    for i in 1..rows.len() - 2 {
        let near: Vec<f64> = rows[i - 1..=i + 2]
            .iter()
            .map(|r| r.values()[col])
            .collect();
        let lo = near.iter().fold(f64::INFINITY, |a, b| a.min(*b));
        let hi = near.iter().fold(f64::NEG_INFINITY, |a, b| a.max(*b));
        let curvature = (near[0] - 2.0 * near[1] + near[2])
            .abs()
            .max((near[1] - 2.0 * near[2] + near[3]).abs());
        for k in 1..10 {
            let y = rows[i].y + (rows[i + 1].y - rows[i].y) * k as f64 / 10.0;
            let v = sp.left(y).unwrap().values()[col];
            let excess = (lo - v).max(v - hi) - 0.25 * curvature;
            if excess > worst.0 {
                worst = (excess, y);
            }
        }
    }
    worst
}

#[test]
fn the_spline_through_the_built_in_table_stays_within_its_neighbouring_rows() {
    // The rigid table's jumps (tread, flange root, flange flank) make the spline overshoot
    // by a good part of the jump; the built-in (smoothed) table's does not.
    let raw = crate::contact::default_table().unwrap();
    let built_in = builtin_contact_table().unwrap();
    let (delta_raw, at) = spline_overshoot(&raw, 2);
    assert!(delta_raw > 5e-3, "raw δ overshoot {delta_raw} rad at {at}");
    let (r_raw, _) = spline_overshoot(&raw, 6);
    assert!(r_raw > 1e-5, "raw r overshoot {r_raw} m");
    for (col, name, tol) in [(2, "delta", 1e-9), (6, "r", 1e-12), (5, "aw", 1e-12)] {
        let (o, y) = spline_overshoot(&built_in, col);
        assert!(
            o <= tol,
            "{name}: the spline leaves its rows by {o} at y = {y} m"
        );
    }
    // The same rows as `railuq-fmu contact --smooth 0.05` writes.
    assert_eq!(BUILTIN_SMOOTHING, 0.05e-3);
    assert_eq!(built_in.range(), raw.range());
}

/// λ_eq at amplitudes 1..5 mm of a table's Δr(y) = r(y) − r(−y), and where the flange is met
/// (δ ≥ 0.5 rad).
fn table_figures(t: &ContactTable) -> ([f64; 5], f64) {
    let rows = t.rows();
    let n = rows.len();
    let y: Vec<f64> = rows.iter().map(|r| r.y).collect();
    let dr: Vec<f64> = (0..n).map(|i| rows[i].r - rows[n - 1 - i].r).collect();
    let d = crate::contact::conicity::DeltaR::new(&y, &dr).unwrap();
    let lambda = std::array::from_fn(|k| d.conicity((k + 1) as f64 * 1e-3).unwrap());
    let flange = rows
        .iter()
        .find(|r| r.y >= 0.0 && r.delta >= 0.5)
        .map_or(f64::NAN, |r| r.y);
    (lambda, flange)
}

/// Figures of the built-in table against other smoothing widths and RSGEO's table:
/// `cargo test --release -p railuq --lib vehicle::tests::contact_table_figures -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn contact_table_figures() {
    let raw = crate::contact::default_table().unwrap();
    let rsgeo = ContactTable::parse_csv(RSGEO).unwrap();
    let mut tables = vec![("RSGEO".to_string(), rsgeo)];
    for w in [0.0, 0.05, 0.1, 0.2, 0.3, 0.5] {
        tables.push((
            format!("computed, smoothed {w} mm"),
            crate::contact::smooth::smoothed(&raw, w * 1e-3),
        ));
    }
    for (name, t) in &tables {
        let (lambda, flange) = table_figures(t);
        let spline = ContactSpline::new(t);
        let car = Car::new(Vehicle::default().p, &spline);
        let t0 = std::time::Instant::now();
        let v_cr = stability::linear_critical_speed(&car, &spline);
        println!(
            "{name}: lambda_eq(1..5 mm) {:?}, flange from {:.2} mm, overshoot delta {:.2e} r {:.2e}, \
             v_cr_linear {v_cr:?} ({:.2} s)",
            lambda.map(|l| (l * 1e3).round() / 1e3),
            flange * 1e3,
            spline_overshoot(t, 2).0,
            spline_overshoot(t, 6).0,
            t0.elapsed().as_secs_f64()
        );
    }
}

#[test]
fn profiles_given_as_files_give_the_table_of_the_built_in_profiles() {
    // S1002 and UIC60 sampled into CSV files (y, z in mm, in the files' own frames) and
    // given as wheel_profile / rail_profile: the table computed from them matches the
    // built-in one (computed from the analytic profiles) to the resampling's accuracy.
    let dir = std::env::temp_dir().join(format!("railuq-vehicle-profiles-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let rolling = crate::contact::s1002::ROLLING_CIRCLE_FROM_FLANGE_BACK;
    let csv = |points: Vec<(f64, f64)>, shift: f64| -> String {
        let mut t = String::from("y,z\n");
        for (u, z) in points {
            t.push_str(&format!("{},{}\n", (u + shift) * 1e3, z * 1e3));
        }
        t
    };
    std::fs::write(
        dir.join("wheel.csv"),
        csv(crate::contact::s1002::s1002().sample(4000), rolling),
    )
    .unwrap();
    std::fs::write(
        dir.join("rail.csv"),
        csv(crate::contact::uic60::uic60().sample(4000), 0.0),
    )
    .unwrap();
    let ctx = InitContext {
        start_time: 0.0,
        resource_dir: Some(dir.clone()),
    };
    let mut m = Vehicle::default();
    m.set_string(VR_WHEEL_PROFILE, "wheel.csv").unwrap();
    m.set_string(VR_RAIL_PROFILE, "rail.csv").unwrap();
    let (from_files, _) = m.load_table_for_test(&ctx);
    let built_in = builtin_contact_table().unwrap();
    let (a, b) = (from_files.rows(), built_in.rows());
    assert_eq!(a.len(), b.len());
    // On the tread (|y| <= 4 mm) the rolling radius agrees to 2 µm, the contact angle to 2 mrad.
    for (x, y) in a.iter().zip(b).filter(|(x, _)| x.y.abs() <= 4e-3) {
        assert!((x.r - y.r).abs() < 2e-6, "y {} r {} vs {}", x.y, x.r, y.r);
        assert!(
            (x.delta - y.delta).abs() < 2e-3,
            "y {} δ {} vs {}",
            x.y,
            x.delta,
            y.delta
        );
    }
    m.initialize(&ctx).unwrap();
    // A table and profiles at once are refused; a bad profile names its parameter, not its text.
    let mut both = Vehicle::default();
    both.set_string(VR_WHEEL_PROFILE, "wheel.csv").unwrap();
    both.set_string(VR_CONTACT_TABLE, "t.csv").unwrap();
    let e = both.initialize(&ctx).unwrap_err().to_string();
    assert!(e.contains("both set"), "{e}");
    std::fs::write(dir.join("bad.csv"), "y,z\n0,0\nSECRET,1\n").unwrap();
    let mut bad = Vehicle::default();
    bad.set_string(VR_RAIL_PROFILE, "bad.csv").unwrap();
    let e = bad.initialize(&ctx).unwrap_err().to_string();
    assert!(e.contains("rail_profile") && !e.contains("SECRET"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
