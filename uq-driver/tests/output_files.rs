//! File-system safety of output files and folders: links planted in the
//! folder are never written through, and names of outputs and quantities never become
//! paths outside it nor overwrite the folder's own files; a device or pipe named as output
//! is written into, never replaced.

use std::os::unix::fs::symlink;
use std::path::Path;
use std::process::{Command, Output};

use crate::support::wheel::{self, write_study};
use crate::support::{
    assert_contains, qoi, read, run, run_study, stderr, stdout, study_head, test_fmus, utf8,
    write_file,
};

fn text(o: &Output) -> String {
    format!("{}{}", stdout(o), stderr(o))
}

const EXPERIMENT: &str = "start = 0.0\nstop = 0.5\nstep = 0.05";
const METHOD: &str = "kind = \"scm\"\nnodes = 2";

fn is_link(p: &Path) -> bool {
    std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_symlink())
}

#[test]
fn a_symlink_planted_as_the_lock_file_is_refused_and_its_target_kept() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, "");
    let victim = write_file(dir.path(), "passwd", "root:x:0:0:VICTIM:/root:/bin/sh\n");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    symlink(&victim, out.join("uq-driver.lock")).unwrap();
    let o = run_study(&study, &out, &[]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert_contains(&t, "symbolic link");
    assert!(!t.contains("VICTIM"), "the target's content is echoed: {t}");
    assert_eq!(read(&victim), "root:x:0:0:VICTIM:/root:/bin/sh\n");
    assert!(!out.join("store").exists(), "refused before any run");
}

#[test]
fn symlinks_planted_as_summary_json_and_points_csv_are_replaced_not_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, "");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let mut victims = Vec::new();
    for name in [
        "summary.json",
        "points.csv",
        "q.csv",
        "q_band.svg",
        "index.html",
        "guide.html",
    ] {
        let victim = dir.path().join(format!("victim-{name}"));
        std::fs::write(&victim, "precious\n").unwrap();
        symlink(&victim, out.join(name)).unwrap();
        victims.push((victim, out.join(name)));
    }
    let o = run_study(&study, &out, &[]);
    assert!(o.status.success(), "{}", text(&o));
    for (victim, planted) in victims {
        assert_eq!(read(&victim), "precious\n");
        assert!(!is_link(&planted), "{}", planted.display());
        assert!(std::fs::metadata(&planted).unwrap().len() > 0);
    }
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().starts_with(".uq-driver-tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn quantity_names_with_slashes_or_the_folders_own_names_stay_inside_and_apart() {
    let dir = tempfile::tempdir().unwrap();
    let names = ["../../escape_y", "points", "/tmp/uq-driver-abs-test"];
    let qoi = names.map(|n| qoi("final", n, "q")).concat();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, &qoi);
    let out = dir.path().join("a").join("b").join("out");
    std::fs::create_dir_all(&out).unwrap();
    let o = run_study(&study, &out, &[]);
    assert!(o.status.success(), "{}", text(&o));
    // Nothing beside or above the folder.
    let above: Vec<_> = std::fs::read_dir(dir.path().join("a"))
        .unwrap()
        .chain(std::fs::read_dir(dir.path().join("a/b")).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(above, ["b", "out"]);
    assert!(!Path::new("/tmp/uq-driver-abs-test_pdf.csv").exists());
    // points.csv is still the design; the quantity has its own, escaped files.
    let points = read(&out.join("points.csv"));
    assert!(points.starts_with("index,weight,K,C,status\n"), "{points}");
    for f in [
        "%2E.%2F..%2Fescape_y_samples.csv",
        "%70oints_samples.csv",
        "%70oints_pdf.csv",
        "%2Ftmp%2Fuq-driver-abs-test_samples.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let samples = read(&out.join("%70oints_samples.csv"));
    assert!(samples.starts_with("run,points\n"), "{samples}");
    // index.html links the real files.
    let html = read(&out.join("index.html"));
    assert!(
        html.contains("href=\"%2570oints_pdf.csv\""),
        "link to the escaped file"
    );
}

#[test]
fn every_figure_links_to_its_section_of_the_guide_page_written_beside_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, "");
    let out = dir.path().join("out");
    let o = run_study(&study, &out, &[]);
    assert!(o.status.success(), "{}", text(&o));
    let html = read(&out.join("index.html"));
    let guide = read(&out.join("guide.html"));
    let figures = html.matches("<figure>").count();
    assert!(figures >= 3, "{html}");
    assert_eq!(
        html.matches("how to read it</a>").count(),
        figures,
        "a figure without its guide link: {html}"
    );
    for link in html.split("href=\"guide.html#").skip(1) {
        let anchor = link.split('"').next().unwrap();
        assert!(
            guide.contains(&format!(" id=\"{anchor}\"")),
            "guide.html has no section {anchor}"
        );
    }
    assert!(html.contains("href=\"guide.html#band-mean--3σ-and-quantiles\""));
}

#[test]
fn two_names_that_would_share_a_file_are_refused_before_any_run() {
    let dir = tempfile::tempdir().unwrap();
    let qoi = ["y", "y_pdf"].map(|n| qoi("final", n, "q")).concat();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, &qoi);
    let out = dir.path().join("out");
    let o = run_study(&study, &out, &[]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(t.contains("'y'") && t.contains("'y_pdf'"), "{t}");
    assert!(!out.join("store").exists(), "refused before any run");
}

#[test]
fn no_report_names_the_folder_not_an_index_html_it_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path(), "s", "s", 1, EXPERIMENT, METHOD, "");
    let out = dir.path().join("out");
    let o = run_study(&study, &out, &["--no-report"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(!out.join("index.html").exists());
    assert!(!t.contains("index.html: "), "{t}");
    assert!(!t.contains("report: "), "{t}");
    assert_contains(&t, "--no-report");
}

#[test]
fn a_study_stopped_by_failed_points_still_writes_every_points_status() {
    // A study that stopped at its first failure, or had too few successful
    // runs to analyse, left only store/: the per-point messages could not be read. Now
    // points.csv is written with every point's status (the Features FMU fails its step at
    // t = misbehave_at with mode 1, an fmi2Error).
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Features") else {
        return;
    };
    for (name, extra, failures) in [
        ("stopped", "", "stopped at the first failure"),
        (
            "none-ok",
            "[analysis]\nallow_failures = true\n",
            "successful runs",
        ),
    ] {
        let low = if name == "none-ok" { 0.1 } else { 0.3 };
        let study = dir.path().join(format!("{name}.toml"));
        std::fs::write(
            &study,
            format!(
                "{}\
                 [method]\nkind = \"mc\"\nsamples = 8\n\
                 [[parameters]]\nname = \"misbehave_at\"\ndistribution = \"uniform\"\n\
                 low = {low}\nhigh = {}\n\
                 [fixed]\nmisbehave = 1\nread_file = \"\"\n\
                 [outputs]\nvariables = [\"u_integral\"]\n{extra}",
                study_head(name, &fmu, 1, "stop = 1.0\nstep = 0.1"),
                if name == "none-ok" { 0.9 } else { 1.8 },
            ),
        )
        .unwrap();
        let out = dir.path().join(name);
        let o = run_study(&study, &out, &["-t", "1"]);
        let all = text(&o);
        assert!(!o.status.success(), "{all}");
        assert_contains(&all, failures);
        let points = std::fs::read_to_string(out.join("points.csv")).unwrap_or_default();
        assert!(
            points.starts_with("index,misbehave_at,status"),
            "{name}: {all}"
        );
        assert!(points.contains("fails on purpose"), "{name}: {points}");
    }
}

/// `simulate` of the wheel for 0.5 s at 0.05 s: the CSV it writes (header and 11 rows).
fn simulate_to(out: &str) -> Output {
    let fmu = wheel::wheel_fmu();
    run(&[
        "simulate",
        utf8(&fmu),
        "--stop",
        "0.5",
        "--step",
        "0.05",
        "--out",
        out,
    ])
}

fn file_type(p: &Path) -> std::fs::FileType {
    std::fs::symlink_metadata(p).unwrap().file_type()
}

#[test]
fn simulate_out_a_named_pipe_writes_into_it_and_leaves_it_a_pipe() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let pipe = dir.path().join("p");
    assert!(Command::new("mkfifo")
        .arg(&pipe)
        .status()
        .unwrap()
        .success());
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || read(&pipe))
    };
    let o = simulate_to(utf8(&pipe));
    assert!(o.status.success(), "{}", text(&o));
    let got = reader.join().unwrap();
    assert!(got.starts_with("time,"), "{got}");
    assert_eq!(got.lines().count(), 12, "{got}");
    assert!(file_type(&pipe).is_fifo());
    // What a regular file gets is the same text.
    let file = dir.path().join("q.csv");
    let o = simulate_to(utf8(&file));
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(read(&file), got);
}

#[test]
fn simulate_out_dash_writes_to_standard_output() {
    let o = simulate_to("-");
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.starts_with("time,"), "{out}");
    assert_eq!(out.lines().count(), 12, "{out}");
    assert!(!Path::new("-").exists());
}

#[test]
fn simulate_out_a_character_device_leaves_it_that_device() {
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    // The null device's numbers (1, 3) under a temporary name: needs root (as CI is).
    let dir = tempfile::tempdir().unwrap();
    let dev = dir.path().join("null");
    let made = Command::new("mknod")
        .arg(&dev)
        .args(["c", "1", "3"])
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    if !made.success() {
        eprintln!("skipped: mknod needs root");
        return;
    }
    let o = simulate_to(utf8(&dev));
    assert!(o.status.success(), "{}", text(&o));
    let m = std::fs::symlink_metadata(&dev).unwrap();
    assert!(m.file_type().is_char_device());
    assert_eq!(m.rdev(), libc::makedev(1, 3));
}

#[test]
fn simulate_out_a_folder_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let o = simulate_to(utf8(dir.path()));
    assert!(!o.status.success());
    assert!(text(&o).contains("is a folder"), "{}", text(&o));
}
