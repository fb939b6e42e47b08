//! Honest reports: degenerate studies (one run, zero spread, no exceedance) get no
//! density and the right words; units from the modelDescription appear on the axes, in
//! summary.json and in units.csv; every plot file is well-formed SVG (parsed with quick-xml)
//! or PNG (decoded); `--no-report` writes the data files only; `export --runs` and `compare`
//! write what they promise.

use std::path::{Path, PathBuf};

use crate::support::csv::Csv;
use crate::support::wheel::wheel_fmu;
use crate::support::{
    assert_contains, failed, final_quantity, fmu_dir, read, run, run_builtin, run_ok, run_study_ok,
    stderr, study_head, summary, utf8, write_file, write_toml,
};

/// A wheel study: `parameters` and `method` as TOML, output q, quantities `q_end` (final q)
/// with a limit no run reaches and `q_peak` (largest |q| after 0.5 s).
fn study(dir: &Path, name: &str, method: &str, parameters: &str) -> PathBuf {
    let text = format!(
        r#"{head}[method]
{method}
{parameters}
{outputs}limits = [1.0]
[[qoi]]
kind = "max_abs"
name = "q_peak"
signal = "q"
from = 0.5
limits = [10.0]
"#,
        head = study_head(
            name,
            &wheel_fmu(),
            3,
            "start = 0.0\nstop = 2.0\nstep = 0.01"
        ),
        outputs = final_quantity("q", "q_end")
    );
    write_toml(dir, name, &text)
}

/// K ~ N(100, 10²), the wheel's stiffness.
const K: &str = "[[parameters]]\nname = \"K\"\nmean = 100.0\nstd = 10.0";

/// K ~ N(100, 10²) and C ~ N(20, (0.1 × 20)²), the wheel's stiffness and damping.
const K_AND_C: &str = "[[parameters]]\nname = \"K\"\nmean = 100.0\nstd = 10.0\n\
                       [[parameters]]\nname = \"C\"\nmean = 20.0\ncov = 0.1";

/// A new temporary folder, where [`study`] `name` runs into `out` with the arguments `extra`;
/// returns the folder, `out` and the standard output.
fn run_wheel(
    name: &str,
    method: &str,
    parameters: &str,
    extra: &[&str],
) -> (tempfile::TempDir, PathBuf, String) {
    run_in_new_dir(|dir| study(dir, name, method, parameters), extra)
}

/// The text of the wheel study `name` over [0, `stop`] s in steps of 0.01 s by `method`, K
/// (as [`K`]) its random parameter, the one output `output` and `rest` appended.
fn k_study([name, stop, method, output]: [&str; 4], rest: &str) -> String {
    format!(
        "name = \"{name}\"\nfmu = \"{}\"\n[experiment]\nstop = {stop}\nstep = 0.01\n\
         [method]\n{method}\n{K}\n[outputs]\nvariables = [\"{output}\"]\n{rest}",
        wheel_fmu().display()
    )
}

/// A new temporary folder, where the study file that `write` writes into it runs into `out`
/// with the arguments `extra`; returns the folder, `out` and the standard output.
fn run_in_new_dir(
    write: impl FnOnce(&Path) -> PathBuf,
    extra: &[&str],
) -> (tempfile::TempDir, PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    let s = write(dir.path());
    let out = dir.path().join("out");
    let stdout = run_study_ok(&s, &out, extra);
    (dir, out, stdout)
}

/// Every `.svg` of `dir` parses as XML (quick-xml, to the end) with an `<svg>` root, every
/// `.png` decodes.
fn plots_are_well_formed(dir: &Path) -> usize {
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        match p.extension().and_then(|x| x.to_str()) {
            Some("svg") => {
                let text = read(&p);
                let mut reader = quick_xml::Reader::from_str(&text);
                let mut depth = 0i64;
                let mut root = None;
                loop {
                    match reader.read_event() {
                        Ok(quick_xml::events::Event::Start(s)) => {
                            depth += 1;
                            root.get_or_insert_with(|| s.name().as_ref().to_vec());
                        }
                        Ok(quick_xml::events::Event::End(_)) => depth -= 1,
                        Ok(quick_xml::events::Event::Eof) => break,
                        Ok(_) => {}
                        Err(e) => panic!("{}: not well-formed: {e}", p.display()),
                    }
                }
                assert_eq!(depth, 0, "{}: unbalanced elements", p.display());
                assert_eq!(root.as_deref(), Some(&b"svg"[..]), "{}", p.display());
                assert!(!text.contains("NaN"), "{}: NaN coordinates", p.display());
                n += 1;
            }
            Some("png") => {
                let bytes = std::fs::read(&p).unwrap();
                let mut reader = png::Decoder::new(&bytes[..]).read_info().unwrap();
                let mut buf = vec![0; reader.output_buffer_size()];
                let info = reader.next_frame(&mut buf).unwrap();
                assert!(info.width > 0 && info.height > 0, "{}", p.display());
                n += 1;
            }
            _ => {}
        }
    }
    n
}

#[test]
fn a_single_run_has_no_density_and_says_so() {
    let (_dir, out, stdout) = run_wheel("one-run", "kind = \"nominal\"", K, &[]);
    assert_contains(&stdout, "q_end = ");
    assert_contains(&stdout, "(nominal run;");
    assert_contains(
        &stdout,
        "is below the limit 1 m (nominal run; no probability)",
    );
    for f in [
        "q_pdf.svg",
        "q_pdf.png",
        "q_end_pdf.svg",
        "q_peak_pdf.svg",
        "q_sobol.svg",
        "q_sobol_overall.svg",
    ] {
        assert!(!out.join(f).exists(), "{f} drawn for a single run");
    }
    let html = read(&out.join("index.html"));
    // A nominal run is a value against each limit, not a probability
    // ("0 of 1 runs exceeded 1 (95 % upper bound of P: 0.950)"), and its inputs were held at
    // their means, not sampled.
    assert_contains(
        &html,
        "from the one nominal run (every parameter at its mean)",
    );
    assert!(html.contains("no density"));
    assert_contains(
        &html,
        "is below the limit 1 m (nominal run; no probability)",
    );
    for wrong in [
        "upper bound of P",
        "0 of 1 run",
        "quantile 0.",
        "<td>Std</td>",
        "CoV",
    ] {
        assert!(!html.contains(wrong), "{wrong} on a nominal page:\n{html}");
    }
    assert_contains(&html, "<th>value used</th>");
    assert_contains(&html, "normal, mean 100, std 10 (cov 0.1) (not sampled)");
    assert_contains(&html, "1 model run (");
    assert!(!html.contains("1 model runs"), "{html}");
    assert!(!html.contains("Some("), "Rust debug text in the page");
    assert!(!html.contains("Normal {"), "Rust debug text in the page");
    let s = summary(&out);
    assert_eq!(s["quantities"]["q_end"]["deterministic"], true);
    assert_eq!(s["quantities"]["q_end"]["pdf"], serde_json::json!([]));
    assert_eq!(s["outputs"]["q"]["deterministic"], true);
    assert!(plots_are_well_formed(&out) >= 1);
}

#[test]
fn zero_spread_and_no_exceedance_read_as_such() {
    // The largest RK4 step h around 1.5 ms always gives 7 substeps per 0.01 s step: every run
    // computes the same q, bit for bit.
    let (_dir, out, printed) = run_wheel(
        "zero-spread",
        "kind = \"lhs\"\nsamples = 20",
        "[[parameters]]\nname = \"h\"\nmean = 0.0015\nstd = 1e-7",
        &[],
    );
    assert!(
        !out.join("q_pdf.svg").exists(),
        "heat map of a deterministic output"
    );
    assert!(!out.join("q_end_pdf.svg").exists());
    let html = read(&out.join("index.html"));
    assert_contains(&html, "every one of the 20 runs gives the same value");
    assert!(html.contains("q has the same value in every run at every time"));
    // No run exceeds the limit: a count with its upper bound, not "0 ± 0".
    assert_contains(
        &html,
        "0 of 20 runs exceeded 1 m (95 % upper bound of P: 0.139)",
    );
    // The terminal says the same, the limit with its unit.
    assert_contains(
        &printed,
        "P(q_end > 1 m): 0 of 20 runs exceeded 1 m (95 % upper bound",
    );
    assert!(!html.contains("± 0"), "{html}");
    let s = summary(&out);
    let e = &s["quantities"]["q_end"]["exceedance_counts"][0];
    assert_eq!(
        (e["exceeded"].as_u64(), e["of"].as_u64()),
        (Some(0), Some(20))
    );
    // 1 - 0.05^(1/20), the exact one-sided binomial bound.
    assert!((e["upper_95"].as_f64().unwrap() - 0.1391).abs() < 1e-4);
    plots_are_well_formed(&out);
}

#[test]
fn units_reach_axes_summary_and_sidecar() {
    let (_dir, out, _) = run_wheel("units", "kind = \"scm\"\nnodes = 3", K_AND_C, &[]);
    let s = summary(&out);
    assert_eq!(s["outputs"]["q"]["unit"], "m");
    assert_eq!(s["quantities"]["q_peak"]["unit"], "m");
    assert_eq!(s["units"]["K"], "N/m");
    assert_eq!(s["units"]["C"], "N.s/m");
    assert_eq!(s["units"]["time"], "s");
    for k in ["runs_s", "analysis_s", "report_s"] {
        assert!(s["timing"][k].as_f64().unwrap() >= 0.0, "{k}");
    }
    assert_eq!(s["record_layout"]["outputs"], serde_json::json!(["q"]));
    let units = read(&out.join("units.csv"));
    for line in [
        "q.csv,time,s",
        "q.csv,mean,m",
        "q.csv,q99,m",
        "q_pdf.csv,density,1/m",
        "q_sobol.csv,S_K,1",
        "q_sobol_overall.csv,ST_C,1",
        "q_peak_samples.csv,q_peak,m",
        "points.csv,K,N/m",
    ] {
        assert!(units.lines().any(|l| l == line), "{line} not in:\n{units}");
    }
    let band = read(&out.join("q_band.svg"));
    assert!(band.contains("q [m]") && band.contains("time [s]"));
    let pdf = read(&out.join("q_peak_pdf.svg"));
    assert!(pdf.contains("q_peak [m]"));
    let heat = read(&out.join("q_pdf.svg"));
    assert!(heat.contains("PDF of q [1/m]"));
    // The colour bar starts at 0.
    assert!(heat.contains(">0</text>"), "colour bar without 0");
    // Sobol' bars of the scalar quantities, labelled by parameter.
    let bars = read(&out.join("q_peak_sobol.svg"));
    assert!(bars.contains(">K</text>") && bars.contains(">C</text>"));
    assert!(bars.contains("first order S") && bars.contains("total ST"));
    // And of the whole series of q: shares in [0, 1], first order at most total.
    let overall = read(&out.join("q_sobol_overall.svg"));
    assert!(overall.contains(">K</text>") && overall.contains("whole series"));
    let csv = read(&out.join("q_sobol_overall.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "S_K,S_C,ST_K,ST_C");
    let v: Vec<f64> = lines[1].split(',').map(|x| x.parse().unwrap()).collect();
    assert!(v.iter().all(|x| (0.0..=1.0 + 1e-12).contains(x)), "{v:?}");
    assert!(v[0] <= v[2] + 1e-12 && v[1] <= v[3] + 1e-12, "{v:?}");
    // Inputs as written.
    let html = read(&out.join("index.html"));
    assert_contains(&html, "normal, mean 20, std 2 (cov 0.1)");
    assert!(plots_are_well_formed(&out) >= 6);
}

#[test]
fn no_report_export_and_compare() {
    let dir = tempfile::tempdir().unwrap();
    let s = study(dir.path(), "lhs", "kind = \"lhs\"\nsamples = 30", K);
    let a = dir.path().join("a");
    run_study_ok(&s, &a, &["--no-report"]);
    assert!(a.join("q.csv").exists() && a.join("summary.json").exists());
    assert!(!a.join("index.html").exists() && !a.join("q_band.svg").exists());
    run_ok(&["export", utf8(&a), "--runs"]);
    let csv = read(&a.join("runs/runs.csv"));
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("run,time,q"));
    assert_eq!(lines.count(), 30 * 201);
    let npz = std::fs::File::open(a.join("runs/runs.npz")).unwrap();
    let mut z = zip::ZipArchive::new(npz).unwrap();
    let names: Vec<String> = (0..z.len())
        .map(|i| z.by_index(i).unwrap().name().to_owned())
        .collect();
    for n in ["time.npy", "run.npy", "q.npy", "K.npy"] {
        assert!(names.iter().any(|x| x == n), "{n} not in {names:?}");
    }
    let mut q = Vec::new();
    std::io::Read::read_to_end(&mut z.by_name("q.npy").unwrap(), &mut q).unwrap();
    let hlen = u16::from_le_bytes([q[8], q[9]]) as usize;
    assert!(std::str::from_utf8(&q[10..10 + hlen])
        .unwrap()
        .contains("'shape': (30, 201)"));
    assert_eq!(q.len(), 10 + hlen + 8 * 30 * 201);
    // The first value of the first run is q(0) = q0 = 0.1 m, as in runs.csv.
    let first = f64::from_le_bytes(q[10 + hlen..10 + hlen + 8].try_into().unwrap());
    assert_eq!(first, 0.1);

    // Every value of runs.npz is the one runs.csv gives (the npz's series are copied from the
    // store without decoding).
    let data = &q[10 + hlen..];
    for (n, line) in csv.lines().skip(1).enumerate() {
        let v: f64 = line.split(',').nth(2).unwrap().parse().unwrap();
        let w = f64::from_le_bytes(data[8 * n..8 * n + 8].try_into().unwrap());
        assert_eq!(v, w, "row {n}");
    }
    // A second record of point 0 (as a resumed or re-merged store may hold) is not exported:
    // the first success of each point is.
    let records = a.join("store/records.bin");
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("store/manifest.json")).unwrap()).unwrap();
    let n_values = manifest["n_values"].as_u64().unwrap() as usize;
    let extra = uq_driver::internals::store::encode(
        0,
        &uq_driver::internals::store::Record::Ok(vec![42.0; n_values]),
    );
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(&records)
        .unwrap();
    std::io::Write::write_all(&mut f, &extra).unwrap();
    drop(f);
    run_ok(&["export", utf8(&a), "--runs"]);
    let again = read(&a.join("runs/runs.csv"));
    assert_eq!(again, csv);
    // While a run holds the folder, export refuses instead of reading a store being written.
    let held = uq_driver::internals::store::FolderLock::acquire(&a).unwrap();
    let o = run(&["export", utf8(&a), "--runs"]);
    let err = failed(&o);
    assert_contains(&err, "is in use by another uq-driver run");
    drop(held);

    let b = dir.path().join("b");
    run_study_ok(&s, &b, &[]);
    let page = dir.path().join("page");
    run_ok(&["compare", utf8(&a), utf8(&b), "--out", utf8(&page)]);
    let html = read(&page.join("index.html"));
    assert_contains(&html, "href=\"../b/index.html\"");
    assert!(html.contains("Quantity q_end"));
    plots_are_well_formed(&page);
}

#[test]
fn names_are_forgiven_or_suggested() {
    // A built-in without the prefix; a misspelt one gets the closest.
    let out = run(&["show", "wheel-scm"]);
    assert!(out.status.success());
    let out = run(&["run", "wheel-sgn", "--out", "/nonexistent/x"]);
    let err = stderr(&out);
    assert!(!out.status.success());
    assert_contains(&err, "did you mean the built-in study wheel-sgm?");
    // A misspelt key and a misspelt variable; cov = 15 is most likely 15 %.
    let dir = tempfile::tempdir().unwrap();
    let kk = "[[parameters]]\nname = \"Kk\"\nmean = 100.0\nstd = 10.0";
    let cov = "[[parameters]]\nname = \"K\"\nmean = 100.0\ncov = 15";
    for (name, method, parameters, hint) in [
        ("typo", "nodse = 3", K, "hint: did you mean `nodes`?"),
        ("var", "nodes = 2", kk, "'Kk': did you mean 'K'?"),
        ("cov", "nodes = 2", cov, "did you mean cov = 0.15?"),
    ] {
        let s = study(
            dir.path(),
            name,
            &format!("kind = \"scm\"\n{method}"),
            parameters,
        );
        let out = run(&["run", utf8(&s), "--out", utf8(&dir.path().join(name))]);
        assert_contains(&stderr(&out), hint);
    }
}

#[test]
fn a_missing_fmu_lists_every_place_searched() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_file(
        dir.path(),
        "s.toml",
        "name = \"s\"\nfmu = \"Nowhere.fmu\"\n[experiment]\nstop = 1.0\nstep = 0.1\n\
         [method]\nkind = \"scm\"\nnodes = 2\n[[parameters]]\nname = \"K\"\nmean = 1.0\nstd = 0.1\n\
         [outputs]\nvariables = [\"q\"]\n",
    );
    let out = run(&["run", utf8(&p), "--out", utf8(&dir.path().join("o"))]);
    let err = stderr(&out);
    assert_contains(&err, "FMU Nowhere.fmu not found; looked in:");
    assert!(err.contains(&dir.path().join("Nowhere.fmu").display().to_string()));
    assert_contains(&err, "share/railuq/fmu/Nowhere.fmu");
    assert!(err.contains(&fmu_dir().join("Nowhere.fmu").display().to_string()));
}

#[test]
fn a_one_letter_signal_is_described_after_its_name() {
    // With `signal = "a"` the definition read "pea (Acceleration q'')k-to-peak
    // (max − min) of a over 0.5–2 s" in summary.json, on the page and on the terminal: the
    // description went after the first "a" of the sentence, inside "peak".
    let text = k_study(
        ["a", "2.0", "kind = \"lhs\"\nsamples = 10", "a"],
        "[[qoi]]\nkind = \"range\"\nname = \"a_range\"\nsignal = \"a\"\nfrom = 0.5\n\
         to = 2.0\nlimits = [1.0]\n",
    );
    let (_dir, out, stdout) = run_in_new_dir(|dir| write_toml(dir, "a", &text), &[]);
    let expected = "peak-to-peak (max − min) of a (Acceleration q'') over 0.5–2 s";
    let s = summary(&out);
    assert_eq!(
        s["quantities"]["a_range"]["definition"]["text"], expected,
        "summary.json"
    );
    assert_eq!(
        s["quantities"]["a_range"]["definition"]["settings"]["signal_description"],
        "Acceleration q''"
    );
    assert_contains(&stdout, expected);
    let html = read(&out.join("index.html"));
    assert!(
        html.contains(&expected.replace('\'', "&#39;")),
        "{expected} not on the page"
    );
    assert!(!html.contains("pea ("), "{html}");
}

#[test]
fn a_suite_variant_page_names_its_suite_and_the_reference_row_shows_no_zero_difference() {
    // A variant's page was headed "railuq study scm" with no word of
    // its suite and no way back; the suite table gave the reference "0.000e0" against itself.
    let text = k_study(
        ["two", "1.0", "kind = \"scm\"\nnodes = 2", "q"],
        "[[variants]]\nname = \"scm\"\n[variants.method]\nkind = \"scm\"\nnodes = 3\n\
         [[variants]]\nname = \"lhs\"\n[variants.method]\nkind = \"lhs\"\nsamples = 20\n",
    );
    let (_dir, out, _) = run_in_new_dir(|dir| write_toml(dir, "s", &text), &[]);
    let page = read(&out.join("lhs/index.html"));
    assert_contains(&page, "railuq study lhs, a variant of the suite");
    assert_contains(&page, "href=\"../index.html\"");
    let suite = read(&out.join("index.html"));
    assert!(!suite.contains("0.000e0"), "{suite}");
    assert_contains(&suite, "(reference)");
}

#[test]
fn an_sgm_page_shows_its_system_and_claims_no_fmu_units_or_runs() {
    // The SGM page said "1 model runs … on 1 threads" and "Units are those the
    // FMU declares" (there is no FMU), and its description promised a system "given below"
    // that the page did not show.
    let (_dir, out, stdout) = run_builtin("wheel-sgm");
    assert_contains(&stdout, "the Galerkin system solved once");
    let html = read(&out.join("index.html"));
    for wrong in [
        "1 model runs",
        "1 threads",
        "Units are those the FMU declares",
    ] {
        assert!(!html.contains(wrong), "{wrong}:\n{html}");
    }
    assert_contains(&html, "No model runs");
    assert_contains(&html, "declares no unit");
    assert_contains(&html, "<td>M (constant part)</td><td>[[10]]</td>");
    assert_contains(&html, "K += K · [[1]]");
    // `export --runs` of this folder failed with "cannot read
    // .../store/manifest.json: No such file or directory"; an SGM study ran no model.
    assert!(!out.join("points.csv").exists() && !out.join("store").exists());
    let o = run(&["export", utf8(&out), "--runs"]);
    let err = failed(&o);
    assert_contains(&err, "an SGM study has no model runs to export");
    assert!(!err.contains("No such file"), "{err}");
    assert!(!out.join("runs").exists());
}

/// Column `name` of a CSV file with a header row.
fn csv_column(path: &Path, name: &str) -> Vec<f64> {
    Csv::read(path).col(name)
}

/// The wheel-rail impact of `vehicle-track-defect` lasts about 2 ms, between two
/// evenly spaced heat-map columns; the columns must include the times of the extremes of
/// the quantiles and of the mean, and the grid must span the band over every time (the old
/// heat map took its range from the sampled columns and cut the peak off).
#[test]
fn pdf_heat_map_columns_catch_a_short_event() {
    let (_dir, out, _) = run_builtin("vehicle-track-defect");
    let csv = out.join("P1.csv");
    let t = csv_column(&csv, "time");
    let pdf = out.join("P1_pdf.csv");
    let (pdf_t, grid) = (csv_column(&pdf, "time"), csv_column(&pdf, "x"));
    let at = |name: &str, largest: bool| {
        let v = csv_column(&csv, name);
        let k = (0..v.len())
            .reduce(|a, b| {
                let better = if largest { v[b] > v[a] } else { v[b] < v[a] };
                if better {
                    b
                } else {
                    a
                }
            })
            .unwrap();
        (t[k], v[k])
    };
    for (name, largest) in [
        ("q99", true),
        ("q1", false),
        ("mean", true),
        ("mean", false),
    ] {
        let (time, _) = at(name, largest);
        assert!(
            pdf_t.contains(&time),
            "no heat-map column at t = {time}, where {name} is {}",
            if largest { "largest" } else { "least" }
        );
    }
    let lo = at("q1", false).1.min(at("lower_3sigma", false).1);
    let hi = at("q99", true).1.max(at("upper_3sigma", true).1);
    let (g0, g1) = grid
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    assert!(
        g0 <= lo && g1 >= hi,
        "grid {g0}..{g1} misses the band {lo}..{hi}"
    );
    assert!(plots_are_well_formed(&out) >= 6);
}

/// A wheel study by Sobol' sampling (QMC base, replicates), for the intervals and the
/// convergence of the sampled estimates.
fn sobol_sampling_study(dir: &Path) -> PathBuf {
    let s = study(
        dir,
        "sobol",
        "kind = \"sobol_sampling\"\nsamples = 256\nbase = \"qmc\"\nreplicates = 8",
        K_AND_C,
    );
    let out = dir.join("out");
    run_study_ok(&s, &out, &[]);
    out
}

/// The Sobol' bars of `sobol_sampling` carry the intervals the method
/// computes (a whisker per bar, labelled in the words of the method's summary), and the
/// running mean and Std of the convergence plot end at the reported mean and Std (they were
/// taken over every pick-freeze row, the statistics over A and B only).
#[test]
fn sobol_sampling_bars_have_intervals_and_convergence_ends_at_the_statistic() {
    let dir = tempfile::tempdir().unwrap();
    let out = sobol_sampling_study(dir.path());
    let s = summary(&out);
    let q = &s["quantities"]["q_peak"];
    let ci = q["sobol"]["first_ci"]["C"]
        .as_array()
        .expect("first_ci of C");
    assert_eq!(ci.len(), 2);
    let bars = read(&out.join("q_peak_sobol.svg"));
    assert!(
        bars.contains(">95 % interval (8 replicates,<") && bars.contains(">Student t)<"),
        "{bars}"
    );
    // One whisker (a vertical stroke with two caps) per bar: 2 parameters × 2 groups.
    assert_eq!(
        bars.matches("stroke=\"#222\" stroke-width=\"1.3\"").count(),
        4
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    let conv = out.join("q_peak_convergence.csv");
    let (mean, std) = (csv_column(&conv, "mean"), csv_column(&conv, "std"));
    let (m, sd) = (q["mean"].as_f64().unwrap(), q["std"].as_f64().unwrap());
    assert!(rel(*mean.last().unwrap(), m) < 1e-12, "{mean:?} vs {m}");
    assert!(rel(*std.last().unwrap(), sd) < 1e-12, "{std:?} vs {sd}");
    // The output's convergence (at the time of its largest Std) ends at q.csv's values.
    let largest = csv_column(&out.join("q.csv"), "std")
        .into_iter()
        .fold(0.0, f64::max);
    let conv = csv_column(&out.join("q_convergence.csv"), "std");
    assert!(
        rel(*conv.last().unwrap(), largest) < 1e-12,
        "{conv:?} vs {largest}"
    );
    let runs = csv_column(&out.join("q_peak_convergence.csv"), "runs");
    assert_eq!(*runs.last().unwrap(), 512.0, "A and B of 256 base rows");
    let band = read(&out.join("q_peak_convergence.svg"));
    assert_contains(&band, "iid standard errors");
    // Scalar densities are per unit of the quantity .
    let pdf = read(&out.join("q_peak_pdf.svg"));
    assert_contains(&pdf, "probability density [1/m]");
    assert!(plots_are_well_formed(&out) >= 6);
}

/// Every single-study page shows Std(t) (`<V>_std.svg`, with the chaos's
/// Std and its truncation-error estimate where there are), and the convergence against the
/// chaos order has whole-number ticks and a dot at every order.
#[test]
fn std_over_time_and_chaos_convergence_read_as_such() {
    let (_dir, out, _) = run_wheel("stdplot", "kind = \"scm\"\nnodes = 4", K_AND_C, &[]);
    let html = read(&out.join("index.html"));
    assert!(html.contains("q_std.svg"), "Std plot not on the page");
    let std = read(&out.join("q_std.svg"));
    assert!(
        std.contains("Std q [m]") && std.contains("Std of q"),
        "{std}"
    );
    assert!(
        std.contains("std_pce") && std.contains("order_difference"),
        "{std}"
    );
    let conv = read(&out.join("q_convergence.svg"));
    let orders = csv_column(&out.join("q_convergence.csv"), "order").len();
    // Two curves, a dot at every order but 0 on each, plus two legend dots.
    assert_eq!(
        conv.matches("<circle").count(),
        2 * (orders - 1) + 2,
        "{conv}"
    );
    // Tick labels of the order axis are whole numbers.
    for label in [">0.5<", ">1.5<", ">2.5<", ">1.2<", ">1.4<"] {
        assert!(!conv.contains(label), "fractional order tick {label}");
    }
    assert!(plots_are_well_formed(&out) >= 6);
}

/// The header fields of a CSV file (RFC 4180 quoting of the header is not needed for the
/// plain names these studies use).
fn csv_header(path: &Path) -> Vec<String> {
    Csv::read(path).header
}

/// Columns that are counts or text, which have no unit.
const UNITLESS: [&str; 5] = ["index", "status", "run", "runs", "order"];

/// Checks `out/units.csv` against the CSV files of `out`: every numeric column of every file
/// has a row, no row names a file or column that does not exist, and the truncation-error
/// estimates are dimensionless.
fn units_match_the_files(out: &Path) {
    let units = read(&out.join("units.csv"));
    let rows: Vec<(String, String, String)> = units
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 3, "{l}");
            (f[0].to_owned(), f[1].to_owned(), f[2].to_owned())
        })
        .collect();
    let mut files = 0;
    for e in std::fs::read_dir(out).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_str().unwrap().to_owned();
        if !name.ends_with(".csv") || name == "units.csv" {
            continue;
        }
        files += 1;
        for col in csv_header(&p) {
            if UNITLESS.contains(&col.as_str()) {
                continue;
            }
            assert!(
                rows.iter().any(|(f, c, _)| *f == name && *c == col),
                "{name},{col} has no row in units.csv of {}:\n{units}",
                out.display()
            );
        }
    }
    assert!(files >= 4, "{files} CSV files in {}", out.display());
    for (f, c, u) in &rows {
        let p = out.join(f);
        assert!(p.is_file(), "units.csv names {f}, which was not written");
        assert!(
            csv_header(&p).contains(c),
            "units.csv names {f},{c}, but {f} has no such column"
        );
        if ["order_difference", "level_difference", "loo"].contains(&c.as_str()) {
            assert_eq!(u, "1", "{f},{c}: a share of the variance is dimensionless");
        }
    }
}

#[test]
fn units_csv_names_every_column_written_and_no_other() {
    // The truncation-error columns had the output's unit, the
    // `<V>_convergence.csv` columns and the Sobol' interval columns were missing, and a
    // sampling method's `<q>_convergence.csv` was listed with a `std_of_order` it lacks.
    let dir = tempfile::tempdir().unwrap();
    let params = "[[parameters]]\nname = \"K\"\nmean = 100.0\nstd = 10.0\n\
                  [[parameters]]\nname = \"C\"\nmean = 20.0\ncov = 0.1";
    for (name, method) in [
        ("lhs", "kind = \"lhs\"\nsamples = 40"),
        ("scm", "kind = \"scm\"\nnodes = 3"),
        ("sparse", "kind = \"sparse_grid\"\nlevel = 2"),
        (
            "sobol",
            "kind = \"sobol_sampling\"\nsamples = 64\nbase = \"qmc\"\nreplicates = 4",
        ),
        (
            "pce",
            "kind = \"pce_regression\"\ndesign = \"qmc\"\nsamples = 40\norder = 3",
        ),
    ] {
        let s = study(dir.path(), name, method, params);
        let out = dir.path().join(name);
        run_study_ok(&s, &out, &[]);
        units_match_the_files(&out);
    }
    let u = read(&dir.path().join("sobol/units.csv"));
    assert!(u.lines().any(|l| l == "q_sobol.csv,ST_C_hi,1"), "{u}");
    let u = read(&dir.path().join("scm/units.csv"));
    assert!(u.lines().any(|l| l == "q.csv,order_difference,1"), "{u}");
    assert!(
        u.lines().any(|l| l == "q_convergence.csv,std_of_order,m"),
        "{u}"
    );
}

#[test]
fn nominal_studies_write_no_header_only_density_files() {
    // A nominal study wrote `q_pdf.csv` and `q_end_pdf.csv` with a header
    // and no rows, although the README says none is written for a deterministic result.
    let (_dir, out, _) = run_wheel("nom", "kind = \"nominal\"", K, &[]);
    for f in ["q_pdf.csv", "q_end_pdf.csv", "q_peak_pdf.csv"] {
        assert!(!out.join(f).exists(), "{f} written for a nominal study");
    }
    assert!(out.join("q.csv").is_file() && out.join("q_end_samples.csv").is_file());
    let s = summary(&out);
    assert!(
        s["outputs"]["q"]["pdf_csv"].is_null(),
        "{}",
        s["outputs"]["q"]
    );
    let html = read(&out.join("index.html"));
    assert!(!html.contains("_pdf.csv"), "the page links a missing file");
    units_match_the_files(&out);
}

#[test]
fn summary_json_gives_each_inputs_own_mean_and_std() {
    // The README promised a truncated normal's own mean and Std in summary.json;
    // only the page had them. K: N(100, 10²) truncated to [95, ∞): α = −0.5, λ = φ(α)/(1 − Φ(α)),
    // mean = 100 + 10 λ, variance = 10² (1 + α λ − λ²), with Φ(−0.5) from the normal table.
    let (_dir, out, _) = run_wheel(
        "moments",
        "kind = \"lhs\"\nsamples = 8",
        "[[parameters]]\nname = \"K\"\ndistribution = \"truncated_normal\"\nmean = 100.0\nstd = 10.0\nlow = 95.0\nhigh = inf\n\
         [[parameters]]\nname = \"C\"\ndistribution = \"lognormal\"\nmean = 20.0\nstd = 2.0",
        &["--no-report"],
    );
    let summary = summary(&out);
    let p = &summary["parameters"];
    let alpha: f64 = -0.5;
    let phi = (-alpha * alpha / 2.0).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let lambda = phi / (1.0 - 0.308_537_538_725_986_9);
    let (mean, std) = (
        100.0 + 10.0 * lambda,
        10.0 * (1.0 + alpha * lambda - lambda * lambda).sqrt(),
    );
    let got = |k: usize, key: &str| p[k][key].as_f64().unwrap();
    assert!((got(0, "mean") - mean).abs() < 1e-9, "{p}");
    assert!((got(0, "std") - std).abs() < 1e-9, "{p}");
    // The parent normal's parameters stay as written; the infinite bound is null.
    assert_eq!(p[0]["distribution"]["mean"], 100.0);
    assert!(p[0]["distribution"]["high"].is_null());
    // A lognormal given by its mean and Std: those of X, not of ln X.
    assert!((got(1, "mean") - 20.0).abs() < 1e-9 && (got(1, "std") - 2.0).abs() < 1e-9);
}
