//! Regression tests for the results store: it never panics, keeps every
//! good record after a bad one, and reports what it skipped and which points run again.
//!
//! The expected records are known independently: the test writes them itself, then damages the
//! file at known places.

use std::fs;
use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use uq_driver::internals::store::{self, Manifest, Record, Store};

use crate::support::assert_contains;

fn manifest(n_points: usize, n_values: usize) -> Manifest {
    Manifest {
        study_hash: "study".into(),
        fmu_sha256: "fmu".into(),
        n_points,
        n_values,
    }
}

fn value(i: usize, k: usize) -> f64 {
    i as f64 * 10.0 + k as f64 + 0.25
}

fn ok(i: usize, n_values: usize) -> Record {
    Record::Ok((0..n_values).map(|k| value(i, k)).collect())
}

fn records_path(dir: &Path) -> std::path::PathBuf {
    dir.join("store").join("records.bin")
}

/// A store of [`manifest`]`(n_points, n_values)` written by [`write_store`] into a new
/// temporary folder: the manifest, the folder, the records' byte ranges and the bytes of the
/// records file.
fn written_store(
    n_points: usize,
    n_values: usize,
) -> (
    Manifest,
    tempfile::TempDir,
    Vec<std::ops::Range<usize>>,
    Vec<u8>,
) {
    let m = manifest(n_points, n_values);
    let dir = tempfile::tempdir().unwrap();
    let ranges = write_store(dir.path(), &m);
    let clean = fs::read(records_path(dir.path())).unwrap();
    (m, dir, ranges, clean)
}

/// A store of `n` finished points written through the public API; returns each record's byte
/// range in `records.bin`.
fn write_store(dir: &Path, m: &Manifest) -> Vec<std::ops::Range<usize>> {
    let (s, _) = Store::open(dir, m, true).unwrap();
    let mut ranges = Vec::new();
    // The store's identity frame comes first.
    let mut at = fs::metadata(records_path(dir)).unwrap().len() as usize;
    for i in 0..m.n_points {
        let rec = if i % 7 == 3 {
            Record::Failed(format!("point {i} failed: ∆ too large"))
        } else {
            ok(i, m.n_values)
        };
        let len = store::encode(i, &rec).len();
        s.append(i, &rec).unwrap();
        ranges.push(at..at + len);
        at += len;
    }
    ranges
}

fn expected(i: usize, n_values: usize) -> Record {
    if i % 7 == 3 {
        Record::Failed(format!("point {i} failed: ∆ too large"))
    } else {
        ok(i, n_values)
    }
}

#[test]
fn flipped_byte_in_record_1_of_1000_keeps_the_other_999() {
    // Before: the resume kept record 0 and silently dropped the 999 after the damage.
    let (m, dir, ranges, clean) = written_store(1000, 3);
    for byte in ranges[1].clone() {
        for bit in [0u8, 7] {
            let mut bytes = clean.clone();
            bytes[byte] ^= 1 << bit;
            fs::write(records_path(dir.path()), &bytes).unwrap();
            let (s, done) = Store::open(dir.path(), &m, false).unwrap();
            let where_ = format!("byte {byte} bit {bit}");
            assert_eq!(done[1], None, "{where_}");
            for (i, d) in done.iter().enumerate().filter(|(i, _)| *i != 1) {
                assert_eq!(d.as_ref(), Some(&expected(i, 3)), "{where_}: point {i}");
            }
            let r = s.recovery();
            assert_eq!(r.kept, 999, "{where_}");
            assert_eq!(r.missing, 1, "{where_}");
            assert_eq!(r.skipped.len(), 1, "{where_}: {r}");
            assert_eq!(
                r.skipped[0].bytes,
                ranges[1].start as u64..ranges[1].end as u64,
                "{where_}"
            );
            // The point is named whenever the header survived (the flip is in the payload
            // or the record checksum).
            let header_intact = byte - ranges[1].start >= 25;
            assert_eq!(r.rerun == vec![1], header_intact, "{where_}: {r}");
            let text = r.summary().unwrap();
            assert_contains(&text, "skipped 1 damaged stretch");
            assert_contains(&text, "kept 999 valid records");
            if header_intact {
                assert_contains(&text, "point 1 lost its record and will be run again");
            } else {
                assert_contains(&text, "among the 1 points without a result");
            }
            assert!(r.backup.is_some(), "damage before the end is rewritten");
            drop(s);
            // The rewritten store is clean; re-running point 1 completes it.
            let (s, _) = Store::open(dir.path(), &m, false).unwrap();
            assert!(s.recovery().is_clean(), "{}", s.recovery());
            s.append(1, &expected(1, 3)).unwrap();
            drop(s);
            let (s, done) = Store::open(dir.path(), &m, false).unwrap();
            assert!(s.recovery().is_clean());
            assert!(done
                .iter()
                .enumerate()
                .all(|(i, d)| d.as_ref() == Some(&expected(i, 3))));
            drop(s);
            for e in fs::read_dir(dir.path().join("store")).unwrap() {
                let e = e.unwrap();
                if e.file_name()
                    .to_string_lossy()
                    .starts_with("records.damaged")
                {
                    assert_eq!(
                        fs::read(e.path()).unwrap(),
                        bytes,
                        "the damaged file is kept"
                    );
                    fs::remove_file(e.path()).unwrap();
                }
            }
        }
    }
}

#[test]
fn huge_length_field_never_panics_in_either_format() {
    // Format 1 (the store before format 2): a huge length wrapped around and panicked
    // ("slice index starts at 21 but ends at 5") on this and every later run.
    let m = manifest(3, 2);
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir_all(dir.path().join("store")).unwrap();
    let payload = |i: usize| -> Vec<u8> {
        (0..2)
            .flat_map(|k| value(i, k).to_le_bytes())
            .collect::<Vec<u8>>()
    };
    let mut bytes = Vec::new();
    for i in 0..3 {
        let mut rec = v1_record(i as u64, 0, &payload(i));
        if i == 1 {
            rec[13..21].copy_from_slice(&(u64::MAX - 15).to_le_bytes());
        }
        bytes.extend(rec);
    }
    fs::write(records_path(dir.path()), &bytes).unwrap();
    for open in 0..2 {
        let (s, done) = Store::open(dir.path(), &m, false).unwrap();
        assert_eq!(done[0], Some(ok(0, 2)));
        assert_eq!(done[1], None);
        assert_eq!(
            done[2],
            Some(ok(2, 2)),
            "the record after the bad one is kept"
        );
        // The first open converts the store (and skips the bad record); the second finds it
        // clean.
        assert_eq!(s.recovery().is_clean(), open == 1, "{}", s.recovery());
    }

    // Format 2, with a header checksum that matches the huge length.
    let good = store::encode(0, &ok(0, 2));
    let mut huge = store::encode(1, &ok(1, 2));
    huge[13..21].copy_from_slice(&u64::MAX.to_le_bytes());
    let crc = crc32(&huge[4..21]);
    huge[21..25].copy_from_slice(&crc.to_le_bytes());
    let after = store::encode(2, &ok(2, 2));
    let all = [good, huge, after].concat();
    fs::write(records_path(dir.path()), &all).unwrap();
    let (s, done) = Store::open(dir.path(), &m, false).unwrap();
    assert_eq!(done, vec![Some(ok(0, 2)), None, Some(ok(2, 2))]);
    assert_eq!(s.recovery().rerun, vec![1], "{}", s.recovery());
}

/// CRC-32 (IEEE), bit by bit: independent of the crate the store uses.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn record_format_is_as_documented() {
    let rec = store::encode(5, &Record::Ok(vec![1.5]));
    assert_eq!(&rec[..4], &[0xF5, b'R', b'Q', b'2']);
    assert_eq!(&rec[4..12], &5u64.to_le_bytes());
    assert_eq!(rec[12], 0);
    assert_eq!(&rec[13..21], &8u64.to_le_bytes());
    assert_eq!(&rec[21..25], &crc32(&rec[4..21]).to_le_bytes());
    assert_eq!(&rec[25..33], &1.5f64.to_le_bytes());
    let mut covered = rec[4..21].to_vec();
    covered.extend_from_slice(&rec[25..33]);
    assert_eq!(&rec[33..], &crc32(&covered).to_le_bytes());
}

/// A format-1 record, as the store wrote it before format 2.
fn v1_record(index: u64, kind: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = b"REC1".to_vec();
    out.extend_from_slice(&index.to_le_bytes());
    out.push(kind);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(payload);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in index
        .to_le_bytes()
        .into_iter()
        .chain([kind])
        .chain(payload.iter().copied())
    {
        h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    out.extend_from_slice(&h.to_le_bytes());
    out
}

#[test]
fn old_format_store_is_converted_and_kept_as_records_v1() {
    let m = manifest(4, 1);
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir_all(dir.path().join("store")).unwrap();
    let old = [
        v1_record(2, 0, &7.5f64.to_le_bytes()),
        v1_record(0, 1, b"diverged"),
    ]
    .concat();
    fs::write(records_path(dir.path()), &old).unwrap();
    let (s, done) = Store::open(dir.path(), &m, false).unwrap();
    assert_eq!(
        done,
        vec![
            Some(Record::Failed("diverged".into())),
            None,
            Some(Record::Ok(vec![7.5])),
            None
        ]
    );
    let r = s.recovery();
    assert!(r.converted_from_v1);
    let backup = r.backup.clone().unwrap();
    assert_eq!(backup.file_name().unwrap(), "records.v1.bin");
    assert_eq!(fs::read(&backup).unwrap(), old);
    assert!(r
        .summary()
        .unwrap()
        .contains("converted from the format before format 2"));
    s.append(1, &Record::Ok(vec![1.0])).unwrap();
    drop(s);
    let (s, done) = Store::open(dir.path(), &m, false).unwrap();
    assert!(s.recovery().is_clean(), "{}", s.recovery());
    assert_eq!(done[1], Some(Record::Ok(vec![1.0])));
    assert_eq!(done[2], Some(Record::Ok(vec![7.5])));
}

#[test]
fn torn_tail_is_cut_and_its_point_reported() {
    let (m, dir, ranges, clean) = written_store(5, 2);
    let last = ranges[4].clone();
    for cut in last.start + 1..last.end {
        fs::write(records_path(dir.path()), &clean[..cut]).unwrap();
        let (s, done) = Store::open(dir.path(), &m, false).unwrap();
        assert_eq!(done[4], None, "cut at {cut}");
        assert!(done[..4]
            .iter()
            .enumerate()
            .all(|(i, d)| d.as_ref() == Some(&expected(i, 2))));
        let r = s.recovery();
        assert_eq!(r.truncated, Some((cut - last.start) as u64), "cut at {cut}");
        assert_eq!(r.backup, None, "a torn tail is cut, not rewritten");
        // Once the header (25 bytes) is complete, the record names its point.
        assert_eq!(
            r.rerun == vec![4],
            cut - last.start >= 25,
            "cut at {cut}: {r}"
        );
        s.append(4, &expected(4, 2)).unwrap();
        drop(s);
        assert_eq!(fs::read(records_path(dir.path())).unwrap(), clean);
    }
}

#[test]
fn random_garbage_never_panics() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let magic2 = store::MAGIC;
    for round in 0..3000 {
        let len = rng.gen_range(0..400);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.gen()).collect();
        // Sprinkle record markers of both formats and real records, so the resync paths run.
        for _ in 0..rng.gen_range(0..4) {
            if bytes.len() >= 4 {
                let at = rng.gen_range(0..bytes.len() - 3);
                let m = if rng.gen() { magic2 } else { *b"REC1" };
                bytes[at..at + 4].copy_from_slice(&m);
            }
        }
        if round % 3 == 0 {
            let at = rng.gen_range(0..=bytes.len());
            let rec = store::encode(rng.gen_range(0..5), &ok(1, 1));
            bytes.splice(at..at, rec);
        }
        for n_values in [0, 1, 3] {
            let (_, d) = store::decode(&bytes, n_values);
            for s in &d.skipped {
                assert!(s.bytes.start < s.bytes.end && s.bytes.end <= bytes.len() as u64);
            }
        }
    }
    // Whole stores of garbage, opened as a resume would.
    let m = manifest(5, 1);
    for round in 0..50 {
        let dir = tempfile::tempdir().unwrap();
        fs::create_dir_all(dir.path().join("store")).unwrap();
        let mut bytes: Vec<u8> = (0..rng.gen_range(0..2000)).map(|_| rng.gen()).collect();
        if round % 2 == 0 {
            bytes.splice(0..0, store::encode(2, &ok(2, 1)));
        }
        fs::write(records_path(dir.path()), &bytes).unwrap();
        let (s, done) = Store::open(dir.path(), &m, false).unwrap();
        if round % 2 == 0 {
            assert_eq!(done[2], Some(ok(2, 1)));
        }
        drop(s);
        let (s, _) = Store::open(dir.path(), &m, false).unwrap();
        assert!(s.recovery().is_clean(), "{}", s.recovery());
    }
}

/// One way of damaging a record.
#[derive(Clone, Copy, Debug)]
enum Damage {
    FlipBytes,
    Truncate,
    InsertInside,
    Drop,
}

#[test]
fn random_corruptions_keep_every_intact_record() {
    // Property: whatever happens to some records (and between them), every record left intact
    // is read back exactly, no damaged record is read, and nothing panics.
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    for round in 0..400 {
        let n = rng.gen_range(1..60);
        let n_values = rng.gen_range(0..5);
        let mut file = Vec::new();
        let mut intact = vec![false; n];
        for (i, ok_i) in intact.iter_mut().enumerate() {
            if rng.gen_bool(0.15) {
                let garbage: Vec<u8> = (0..rng.gen_range(1..80)).map(|_| rng.gen()).collect();
                file.extend(garbage);
            }
            let mut rec = store::encode(i, &expected(i, n_values));
            let damage = match rng.gen_range(0..10) {
                0 => Some(Damage::FlipBytes),
                1 => Some(Damage::Truncate),
                2 => Some(Damage::InsertInside),
                3 => Some(Damage::Drop),
                _ => None,
            };
            match damage {
                None => *ok_i = true,
                Some(Damage::FlipBytes) => {
                    for _ in 0..rng.gen_range(1..4) {
                        let at = rng.gen_range(0..rec.len());
                        rec[at] ^= rng.gen_range(1..=255);
                    }
                }
                Some(Damage::Truncate) => rec.truncate(rng.gen_range(0..rec.len())),
                Some(Damage::InsertInside) => {
                    let at = rng.gen_range(1..rec.len());
                    let junk: Vec<u8> = (0..rng.gen_range(1..20)).map(|_| rng.gen()).collect();
                    rec.splice(at..at, junk);
                }
                Some(Damage::Drop) => rec.clear(),
            }
            file.extend(rec);
        }
        let (_, d) = store::decode(&file, n_values);
        let mut got: Vec<Option<Record>> = vec![None; n];
        for (i, r, _) in d.records {
            assert!(i < n, "round {round}: invented point {i}");
            got[i].get_or_insert(r);
        }
        for i in 0..n {
            if intact[i] {
                assert_eq!(
                    got[i],
                    Some(expected(i, n_values)),
                    "round {round} point {i}"
                );
            } else {
                assert_eq!(got[i], None, "round {round}: damaged point {i} was read");
            }
        }
        if round % 20 == 0 {
            // The same through Store::open, twice (the second open finds a repaired store).
            let dir = tempfile::tempdir().unwrap();
            let m = manifest(n, n_values);
            fs::create_dir_all(dir.path().join("store")).unwrap();
            fs::write(records_path(dir.path()), &file).unwrap();
            let (s, done) = Store::open(dir.path(), &m, false).unwrap();
            assert_eq!(done, got, "round {round}");
            let lost: Vec<usize> = (0..n).filter(|&i| !intact[i]).collect();
            assert!(s.recovery().rerun.iter().all(|p| lost.contains(p)));
            assert_eq!(s.recovery().missing, lost.len());
            drop(s);
            let (s, done) = Store::open(dir.path(), &m, false).unwrap();
            assert!(s.recovery().is_clean(), "round {round}: {}", s.recovery());
            assert_eq!(done, got);
        }
    }
}
