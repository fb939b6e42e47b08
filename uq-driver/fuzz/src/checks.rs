//! What every input must satisfy. Each function panics on a violation (the fuzzer reports the
//! input); none may panic, hang or run out of memory for any input.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use uq_driver::fmu::description::ParseLimits;
use uq_driver::fmu::ModelDescription;
use uq_driver::internals::store::{self, Format, Manifest, Record, Store};

/// `ModelDescription::parse` on arbitrary bytes: no panic; what it accepts is consistent; a
/// tighter limit never accepts more.
pub fn model_description(data: &[u8]) {
    let parsed = ModelDescription::parse(data);
    if let Ok(md) = &parsed {
        assert_eq!(md.fmi_version, "2.0");
        assert!(!md.co_simulation.model_identifier.is_empty());
        let mut names = HashSet::new();
        for v in &md.variables {
            assert!(names.insert(v.name.as_str()), "duplicate name {:?}", v.name);
            assert!(!v.name.contains('\0'), "NUL in {:?}", v.name);
        }
        assert!(md
            .outputs
            .iter()
            .all(|&i| (1..=md.variables.len()).contains(&i)));
        assert_eq!(md.output_variables().count(), md.outputs.len());
    }
    // Error messages can always be formatted.
    if let Err(e) = &parsed {
        let _ = e.to_string();
    }
    let tight = ParseLimits {
        max_bytes: data.len(),
        max_depth: 6,
    };
    if let Ok(md) = ModelDescription::parse_with_limits(data, tight) {
        assert_eq!(
            parsed.as_ref().ok(),
            Some(&md),
            "a tighter limit accepted more"
        );
    }
}

/// Whether two records are the same, comparing values bit for bit (NaN included).
fn same(a: &Record, b: &Record) -> bool {
    match (a, b) {
        (Record::Ok(x), Record::Ok(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits())
        }
        (Record::Failed(x), Record::Failed(y)) => x == y,
        _ => false,
    }
}

/// The store reader on arbitrary bytes: decoding tiles the file into records and skipped
/// stretches, each record decodes alone to itself, and `Store::open` keeps exactly the first
/// valid record of each point, repairs the file, and finds it clean when opened again.
pub fn store_reader(data: &[u8]) {
    for n_values in [0, 1, 3] {
        let (format, d) = store::decode(data, n_values);
        let mut spans: Vec<(u64, u64)> = d
            .records
            .iter()
            .map(|(_, _, r)| (r.start as u64, r.end as u64))
            .chain(d.skipped.iter().map(|s| (s.bytes.start, s.bytes.end)))
            .collect();
        spans.sort_unstable();
        let mut at = 0;
        for (start, end) in spans {
            assert_eq!(start, at, "records and skipped stretches tile the file");
            assert!(end > start);
            at = end;
        }
        assert_eq!(at, data.len() as u64);
        if format == Format::V2 {
            for (i, rec, r) in &d.records {
                let (_, alone) = store::decode(&data[r.clone()], n_values);
                assert!(alone.skipped.is_empty());
                assert_eq!(alone.records.len(), 1);
                assert_eq!(alone.records[0].0, *i);
                assert!(same(&alone.records[0].1, rec));
            }
        }
    }
    open_store(data);
}

thread_local! {
    /// On a RAM disk where there is one: the store syncs what it rewrites.
    static DIR: tempfile::TempDir = tempfile::tempdir_in("/dev/shm")
        .or_else(|_| tempfile::tempdir())
        .expect("a temporary folder");
}

fn open_store(data: &[u8]) {
    let n_points = 8;
    let m = Manifest {
        study_hash: "fuzz".into(),
        fmu_sha256: "fuzz".into(),
        n_points,
        n_values: 1,
    };
    DIR.with(|dir| {
        let dir: &Path = dir.path();
        drop(Store::open(dir, &m, true).expect("fresh store"));
        let records: PathBuf = dir.join("store").join("records.bin");
        std::fs::write(&records, data).expect("write records.bin");
        let (_, d) = store::decode(data, 1);
        let mut want: Vec<Option<Record>> = vec![None; n_points];
        for (i, rec, _) in d.records {
            if i < n_points && want[i].is_none() {
                want[i] = Some(rec);
            }
        }
        let (s, done) = Store::open(dir, &m, false).expect("open");
        let agree = |done: &[Option<Record>]| {
            done.iter().zip(&want).all(|(a, b)| match (a, b) {
                (Some(a), Some(b)) => same(a, b),
                (None, None) => true,
                _ => false,
            })
        };
        assert!(agree(&done), "Store::open and decode disagree");
        assert_eq!(
            s.recovery().missing,
            want.iter().filter(|r| r.is_none()).count()
        );
        drop(s);
        let (s, done) = Store::open(dir, &m, false).expect("reopen");
        assert!(s.recovery().is_clean(), "not repaired: {}", s.recovery());
        assert!(agree(&done), "the repair changed the records");
    });
}

/// `Study::parse` on arbitrary bytes (as UTF-8 text, the way a study file is read): no panic,
/// no huge allocation (the parser validates, it does not build designs or time grids), an
/// error message that formats, and the same answer when parsed again.
pub fn study_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let first = uq_driver::spec::Study::parse(text, "fuzz.toml", None);
    match &first {
        Ok(s) => {
            assert!(!s.name.is_empty(), "a study without a name was accepted");
            for p in &s.parameters {
                assert!(
                    !p.name.is_empty(),
                    "a parameter without a name was accepted"
                );
            }
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
    let again = uq_driver::spec::Study::parse(text, "fuzz.toml", None);
    assert_eq!(
        format!("{first:?}"),
        format!("{again:?}"),
        "parsing the same text twice gave different answers"
    );
}
