//! The results store: one record per finished point, appended as it finishes, so that an
//! interrupted study resumes where it stopped.
//!
//! Layout of `DIR/store/`: `manifest.json` (fingerprint of the study and the FMU, number of
//! points and values per point) and `records.bin`, a sequence of records
//! `"REC1" | index u64 | kind u8 (0 ok, 1 failed) | length u64 | payload | checksum u64`
//! (little endian; payload: f64 values, or a UTF-8 failure message; FNV-1a checksum over
//! index, kind and payload). A torn record at the end (a kill during a write) is cut off on
//! the next open.

use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

const MAGIC: &[u8; 4] = b"REC1";

/// What the store is for; a store written for another study is refused.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// Hash of the study definition (everything that changes the numbers).
    pub study_hash: String,
    /// SHA-256 of the FMU file.
    pub fmu_sha256: String,
    /// Number of points of the design.
    pub n_points: usize,
    /// Values recorded per successful point.
    pub n_values: usize,
}

/// One finished point.
#[derive(Clone, Debug, PartialEq)]
pub enum Record {
    /// The run succeeded: the output values (outputs × times, output-major).
    Ok(Vec<f64>),
    /// The run failed, with the reason.
    Failed(String),
}

/// Store failures.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// File system error.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The folder holds results of something else.
    #[error("{dir} holds results of a different study or FMU ({what}); use another --out folder or --fresh")]
    Mismatch {
        /// The folder.
        dir: PathBuf,
        /// What differs.
        what: String,
    },
    /// A record is inconsistent with the manifest.
    #[error("{path}: {message}")]
    Corrupt {
        /// File.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// An open store, safe to append to from many threads.
#[derive(Debug)]
pub struct Store {
    path: PathBuf,
    file: Mutex<File>,
    n_values: usize,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn checksum(index: u64, kind: u8, payload: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in index
        .to_le_bytes()
        .iter()
        .chain(std::iter::once(&kind))
        .chain(payload)
    {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Encodes one record.
pub fn encode(index: usize, rec: &Record) -> Vec<u8> {
    let (kind, payload): (u8, Vec<u8>) = match rec {
        Record::Ok(v) => (0, v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Record::Failed(m) => (1, m.as_bytes().to_vec()),
    };
    let mut out = Vec::with_capacity(payload.len() + 29);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(index as u64).to_le_bytes());
    out.push(kind);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    out.extend_from_slice(&checksum(index as u64, kind, &payload).to_le_bytes());
    out
}

/// Decodes records from `bytes`; returns them and the length of the valid prefix.
pub fn decode_all(bytes: &[u8], n_values: usize) -> (Vec<(usize, Record)>, usize) {
    let mut out = Vec::new();
    let mut pos = 0;
    loop {
        let rest = &bytes[pos..];
        if rest.len() < 21 || &rest[..4] != MAGIC {
            break;
        }
        let index = u64::from_le_bytes(rest[4..12].try_into().expect("8"));
        let kind = rest[12];
        let len = u64::from_le_bytes(rest[13..21].try_into().expect("8")) as usize;
        if rest.len() < 21 + len + 8 {
            break;
        }
        let payload = &rest[21..21 + len];
        let sum = u64::from_le_bytes(rest[21 + len..29 + len].try_into().expect("8"));
        if sum != checksum(index, kind, payload) {
            break;
        }
        let rec = match kind {
            0 if len == 8 * n_values => Record::Ok(
                payload
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().expect("8")))
                    .collect(),
            ),
            1 => Record::Failed(String::from_utf8_lossy(payload).into_owned()),
            _ => break,
        };
        out.push((index as usize, rec));
        pos += 29 + len;
    }
    (out, pos)
}

impl Store {
    /// Opens (or creates) the store in `dir/store` for `manifest`. Returns the store and the
    /// records already finished, by point index (first record wins).
    pub fn open(
        dir: &Path,
        manifest: &Manifest,
        fresh: bool,
    ) -> Result<(Store, Vec<Option<Record>>), StoreError> {
        let sdir = dir.join("store");
        if fresh && sdir.exists() {
            fs::remove_dir_all(&sdir).map_err(io_err(&sdir))?;
        }
        fs::create_dir_all(&sdir).map_err(io_err(&sdir))?;
        let mpath = sdir.join("manifest.json");
        if mpath.exists() {
            let text = fs::read_to_string(&mpath).map_err(io_err(&mpath))?;
            let old: Manifest = serde_json::from_str(&text).map_err(|e| StoreError::Corrupt {
                path: mpath.clone(),
                message: e.to_string(),
            })?;
            if &old != manifest {
                let what = if old.fmu_sha256 != manifest.fmu_sha256 {
                    "the FMU differs"
                } else {
                    "the study definition differs"
                };
                return Err(StoreError::Mismatch {
                    dir: dir.to_path_buf(),
                    what: what.into(),
                });
            }
        } else {
            let text = serde_json::to_string_pretty(manifest).expect("serializable");
            fs::write(&mpath, text).map_err(io_err(&mpath))?;
        }
        let path = sdir.join("records.bin");
        let mut file = OpenOptions::new()
            .create(true)
            .read(true)
            .append(true)
            .open(&path)
            .map_err(io_err(&path))?;
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes).map_err(io_err(&path))?;
        let (records, valid) = decode_all(&bytes, manifest.n_values);
        if valid < bytes.len() {
            // A torn tail from an interrupted write: cut it off.
            file.set_len(valid as u64).map_err(io_err(&path))?;
            file.seek(SeekFrom::End(0)).map_err(io_err(&path))?;
        }
        let mut done: Vec<Option<Record>> = vec![None; manifest.n_points];
        for (i, r) in records {
            if i >= manifest.n_points {
                return Err(StoreError::Corrupt {
                    path: path.clone(),
                    message: format!(
                        "record for point {i}, but the design has {}",
                        manifest.n_points
                    ),
                });
            }
            if done[i].is_none() {
                done[i] = Some(r);
            }
        }
        Ok((
            Store {
                path,
                file: Mutex::new(file),
                n_values: manifest.n_values,
            },
            done,
        ))
    }

    /// Appends one record (one write call per record, under a lock).
    pub fn append(&self, index: usize, rec: &Record) -> Result<(), StoreError> {
        if let Record::Ok(v) = rec {
            debug_assert_eq!(v.len(), self.n_values);
        }
        let bytes = encode(index, rec);
        let mut f = self.file.lock().unwrap_or_else(|p| p.into_inner());
        f.write_all(&bytes).map_err(io_err(&self.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest() -> Manifest {
        Manifest {
            study_hash: "s".into(),
            fmu_sha256: "f".into(),
            n_points: 4,
            n_values: 2,
        }
    }

    #[test]
    fn round_trip_and_torn_tail() {
        let dir = tempfile::tempdir().unwrap();
        let (s, done) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert!(done.iter().all(Option::is_none));
        s.append(2, &Record::Ok(vec![1.5, -2.0])).unwrap();
        s.append(0, &Record::Failed("boom".into())).unwrap();
        drop(s);
        // Simulate a kill in the middle of a write.
        let p = dir.path().join("store/records.bin");
        let mut f = OpenOptions::new().append(true).open(&p).unwrap();
        f.write_all(&encode(1, &Record::Ok(vec![3.0, 4.0]))[..20])
            .unwrap();
        drop(f);
        let (s, done) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert_eq!(done[2], Some(Record::Ok(vec![1.5, -2.0])));
        assert_eq!(done[0], Some(Record::Failed("boom".into())));
        assert_eq!(done[1], None);
        s.append(1, &Record::Ok(vec![3.0, 4.0])).unwrap();
        drop(s);
        let (_, done) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert_eq!(done[1], Some(Record::Ok(vec![3.0, 4.0])));
    }

    #[test]
    fn refuses_a_store_of_another_study() {
        let dir = tempfile::tempdir().unwrap();
        Store::open(dir.path(), &manifest(), false).unwrap();
        let mut other = manifest();
        other.study_hash = "t".into();
        assert!(matches!(
            Store::open(dir.path(), &other, false),
            Err(StoreError::Mismatch { .. })
        ));
        assert!(
            Store::open(dir.path(), &other, true).is_ok(),
            "--fresh starts over"
        );
    }

    #[test]
    fn corrupted_byte_stops_reading_there() {
        let a = encode(0, &Record::Ok(vec![1.0, 2.0]));
        let mut b = encode(1, &Record::Ok(vec![3.0, 4.0]));
        b[25] ^= 1;
        let all = [a.clone(), b].concat();
        let (recs, valid) = decode_all(&all, 2);
        assert_eq!(recs.len(), 1);
        assert_eq!(valid, a.len());
    }
}
