//! The results store: one record per finished point, appended as it finishes, so that an
//! interrupted study resumes where it stopped.
//!
//! Layout of `DIR/store/`: `manifest.json` (fingerprint of the study and the FMU, number of
//! points and values per point) and `records.bin`, a sequence of CRC-32-framed records (see
//! [`format`](mod@format) for the bytes).
//!
//! Opening never panics and never gives up on good records: a damaged record is skipped and
//! reading resumes at the next valid one. What was skipped, and which points therefore have no
//! result and run again, is returned as a [`Recovery`] ([`Store::recovery`]). A damaged tail (a
//! kill during a write) is cut off; damage before the last valid record makes the store
//! rewrite `records.bin` with its valid records only, keeping the damaged file beside it as
//! `records.damaged-<unix seconds>.bin`. A store of the previous format (format 1, before
//! format 1) is read and converted, the old file kept as `records.v1.bin`.

pub mod export;
pub mod format;
pub mod lock;
mod runs;
pub(crate) mod valid;

use std::fmt;
use std::fs::{self, File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

pub use format::{encode, Format, Skipped, Slot};
pub use runs::{Entry, StoredRuns, Values};
use valid::RecordRules;

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

/// What opening the store skipped or repaired. Empty ([`Recovery::is_clean`]) for an intact
/// store.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recovery {
    /// `records.bin`.
    pub path: PathBuf,
    /// Damaged stretches skipped, in file order (byte offsets into the file as it was found).
    pub skipped: Vec<Skipped>,
    /// Points named by a damaged record (or a record that did not fit the design) that have
    /// no valid record: they have no result now and run again. Sorted.
    pub rerun: Vec<usize>,
    /// Points of the design without a result after opening (including never-run ones).
    pub missing: usize,
    /// Valid records kept.
    pub kept: usize,
    /// Bytes cut off the end of the file (a torn or damaged tail), if any.
    pub truncated: Option<u64>,
    /// Where the file as found was kept, when the store rewrote `records.bin`.
    pub backup: Option<PathBuf>,
    /// Whether the store was converted from format 1.
    pub converted_from_v1: bool,
    /// Whether `records.bin` did not say which study and FMU its records belong to (written
    /// before stores carried their identity), so that its records could only be taken on
    /// trust; the identity of the study it was opened for is now written at its start.
    pub identity_added: bool,
}

impl Recovery {
    /// Whether the store was intact (nothing skipped, cut, converted or identified).
    pub fn is_clean(&self) -> bool {
        self.skipped.is_empty()
            && self.truncated.is_none()
            && !self.converted_from_v1
            && !self.identity_added
    }

    /// A message for the user, or `None` when the store was intact.
    pub fn summary(&self) -> Option<String> {
        (!self.is_clean()).then(|| self.to_string())
    }
}

impl fmt::Display for Recovery {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "results store {}: ", self.path.display())?;
        if self.converted_from_v1 {
            write!(f, "converted from the format before format 2; ")?;
        }
        if self.identity_added {
            write!(
                f,
                "its records did not say which study and FMU they belong to (written by an \
                 earlier uq-driver; taken to be this study's, as its manifest.json says), so \
                 the study's identity was added at its start; "
            )?;
        }
        if !self.skipped.is_empty() {
            let n = self.skipped.len();
            write!(
                f,
                "skipped {n} damaged stretch{} (",
                if n == 1 { "" } else { "es" }
            )?;
            for (k, s) in self.skipped.iter().take(5).enumerate() {
                let sep = if k == 0 { "" } else { "; " };
                write!(
                    f,
                    "{sep}bytes {}..{}: {}",
                    s.bytes.start, s.bytes.end, s.reason
                )?;
                if let Some(p) = s.point {
                    write!(f, ", point {p}")?;
                }
            }
            if n > 5 {
                write!(f, "; and {} more", n - 5)?;
            }
            write!(f, "); ")?;
        }
        if let Some(t) = self.truncated {
            write!(f, "cut {t} bytes of a torn or damaged end; ")?;
        }
        write!(f, "kept {} valid records", self.kept)?;
        if !self.rerun.is_empty() {
            let shown: Vec<String> = self.rerun.iter().take(20).map(usize::to_string).collect();
            let more = self.rerun.len().saturating_sub(20);
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            write!(
                f,
                "; point{} {}{more} lost {} record and will be run again",
                if self.rerun.len() == 1 { "" } else { "s" },
                shown.join(", "),
                if self.rerun.len() == 1 {
                    "its"
                } else {
                    "their"
                }
            )?;
        }
        let unnamed = self.skipped.iter().filter(|s| s.point.is_none()).count();
        if unnamed > 0 {
            write!(
                f,
                "; {unnamed} damaged stretch{} named no point: any point {} held is among the \
                 {} points without a result, which a resumed run computes",
                if unnamed == 1 { "" } else { "es" },
                if unnamed == 1 { "it" } else { "they" },
                self.missing
            )?;
        }
        if let Some(b) = &self.backup {
            write!(f, "; the file as found is kept as {}", b.display())?;
        }
        Ok(())
    }
}

/// An open store, safe to append to from many threads.
#[derive(Debug)]
pub struct Store {
    path: PathBuf,
    /// The file, and its length (where the next record starts).
    file: Mutex<(File, usize)>,
    n_values: usize,
    recovery: Recovery,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Decodes format-2 records from `bytes`, skipping damaged stretches; returns the records and
/// the end of the last valid one. Serves the tests.
#[cfg(test)]
pub(crate) fn decode_all(bytes: &[u8], n_values: usize) -> (Vec<(usize, Record)>, usize) {
    let d = format::decode_format(bytes, n_values, Format::V2);
    let end = d.valid_end();
    (d.records.into_iter().map(|(i, r, _)| (i, r)).collect(), end)
}

impl Store {
    /// Opens (or creates) the store in `dir/store` for `manifest`. Returns the store and the
    /// records already finished, by point index (the first success, else the last failure, of
    /// each point), read into memory. What was skipped or repaired on the way is in
    /// [`Store::recovery`]. [`Store::open_in_place`] leaves the values in the file.
    pub fn open(
        dir: &Path,
        manifest: &Manifest,
        fresh: bool,
    ) -> Result<(Store, Vec<Option<Record>>), StoreError> {
        let (store, runs) = Store::open_in_place(dir, manifest, fresh)?;
        let records = runs.records()?;
        Ok((store, records))
    }

    /// Like [`Store::open`], but the values stay in the file: the runs found say where
    /// ([`StoredRuns`]). The file is scanned through a memory map (its pages are the page
    /// cache's, not this process's heap), and copied into memory only to repair a damaged
    /// or convert an old store.
    ///
    /// `records.bin` starts with the store's identity (the manifest: study hash, FMU
    /// SHA-256, sizes): a file that holds the identity of another study or FMU is refused
    /// ([`StoreError::Mismatch`]), as is a `manifest.json` of another, so a `records.bin`
    /// copied from another study's folder is never read as this one's. A file written before
    /// stores carried their identity gets it ([`Recovery::identity_added`]).
    pub fn open_in_place(
        dir: &Path,
        manifest: &Manifest,
        fresh: bool,
    ) -> Result<(Store, StoredRuns), StoreError> {
        Store::open_checked(dir, manifest, fresh, None)
    }

    /// [`Store::open_in_place`], where a successful record whose values break `rules`
    /// (a non-finite output: never stored by a run, so the file was damaged or edited) is
    /// read as a failure of its point that says so.
    pub(crate) fn open_checked(
        dir: &Path,
        manifest: &Manifest,
        fresh: bool,
        rules: Option<&RecordRules>,
    ) -> Result<(Store, StoredRuns), StoreError> {
        let sdir = dir.join("store");
        if fresh && sdir.exists() {
            fs::remove_dir_all(&sdir).map_err(io_err(&sdir))?;
        }
        // A planted link (the folder may be shared, the run root's) is never written through.
        out_file::sub_folder(&sdir).map_err(io_err(&sdir))?;
        check_manifest(dir, &sdir.join("manifest.json"), manifest)?;
        let identity = format::encode_identity(&identity_json(manifest));
        let path = sdir.join("records.bin");
        let mut file = OpenOptions::new()
            .create(true)
            .read(true)
            .append(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .map_err(io_err(&path))?;
        let len = file.metadata().map_err(io_err(&path))?.len();
        let map = if len == 0 {
            None
        } else {
            // No other run writes the file meanwhile (the caller holds the folder's lock); the
            // map is dropped before this function writes the file.
            Some(crate::sys::map_read_only(&file).map_err(io_err(&path))?)
        };
        let bytes: &[u8] = map.as_deref().unwrap_or_default();

        let fmt = format::detect_format(bytes);
        let scan = read_records(bytes, fmt, manifest, rules);
        check_identities(dir, &scan.identities, manifest)?;
        let Scan {
            mut done,
            kept,
            skipped,
            identities,
        } = scan;
        // The identity at the start of the file, where every store now has it.
        let identity_end = identities
            .first()
            .filter(|(_, r)| r.start == 0)
            .map(|(_, r)| r.end);
        let mut recovery = Recovery {
            path: path.clone(),
            kept: kept.len(),
            converted_from_v1: fmt == Format::V1,
            identity_added: !bytes.is_empty() && identity_end.is_none(),
            ..Recovery::default()
        };
        let valid_end = kept
            .last()
            .map_or(0, |(_, r)| r.end)
            .max(identity_end.unwrap_or(0));
        let damage_inside = skipped.iter().any(|s| s.bytes.start < valid_end as u64);
        let found = bytes.len();
        let mut len = found;
        if fmt == Format::V1 || damage_inside || recovery.identity_added {
            // The kept records go to a new file straight from the map, a record at a time:
            // a store larger than the memory is repaired too.
            let tmp = write_tmp(&path, |w| {
                w.write_all(&identity)?;
                write_kept(w, bytes, fmt, &kept, &done)
            })?;
            drop(map);
            // Adding the identity alone loses nothing: the file as found is kept only when
            // records were converted or dropped.
            let label = (fmt == Format::V1 || damage_inside).then(|| label(fmt));
            let (new_file, backup) = replace(&path, &tmp, label.as_deref())?;
            file = new_file;
            recovery.backup = backup;
            // Where each point's values are now.
            let new_len = file.metadata().map_err(io_err(&path))?.len();
            // As above: the file this run just wrote under the folder's lock (never empty:
            // it starts with the identity); the map is dropped before anything appends to it.
            let new_map = crate::sys::map_read_only(&file).map_err(io_err(&path))?;
            let written: &[u8] = &new_map[..new_len as usize];
            done = read_records(written, Format::V2, manifest, rules).done;
            len = written.len();
        } else if valid_end < found {
            drop(map);
            // A torn tail from an interrupted write (or a damaged last record): cut it off.
            file.set_len(valid_end as u64).map_err(io_err(&path))?;
            file.seek(SeekFrom::End(0)).map_err(io_err(&path))?;
            recovery.truncated = Some((found - valid_end) as u64);
            len = valid_end;
        }
        if len == 0 {
            // A new store: its identity first.
            file.write_all(&identity).map_err(io_err(&path))?;
            len = identity.len();
        }

        let mut rerun: Vec<usize> = skipped
            .iter()
            .filter_map(|s| s.point)
            .filter(|&p| p < manifest.n_points && done[p].is_none())
            .collect();
        rerun.sort_unstable();
        rerun.dedup();
        recovery.rerun = rerun;
        recovery.skipped = skipped;
        recovery.missing = done.iter().filter(|r| r.is_none()).count();
        let entries = done.into_iter().map(|d| d.map(Entry::of)).collect();
        let runs = StoredRuns::in_file(&path, manifest.n_values, entries)?;
        Ok((
            Store {
                path,
                file: Mutex::new((file, len)),
                n_values: manifest.n_values,
                recovery,
            },
            runs,
        ))
    }

    /// What opening skipped or repaired (empty for an intact store).
    pub fn recovery(&self) -> &Recovery {
        &self.recovery
    }

    /// Appends one record (one write call per record, under a lock); returns where it is
    /// (for [`StoredRuns::set`]).
    pub fn append(&self, index: usize, rec: &Record) -> Result<Entry, StoreError> {
        if let Record::Ok(v) = rec {
            debug_assert_eq!(v.len(), self.n_values);
        }
        let bytes = encode(index, rec);
        let mut f = self.file.lock().unwrap_or_else(|p| p.into_inner());
        let (file, len) = &mut *f;
        file.write_all(&bytes).map_err(io_err(&self.path))?;
        let start = *len;
        *len += bytes.len();
        Ok(match rec {
            Record::Ok(_) => Entry::Ok(format::payload_range(start, bytes.len())),
            Record::Failed(m) => Entry::Failed(m.clone()),
        })
    }
}

/// A valid record's point and its bytes in the file.
type Kept = (usize, std::ops::Range<usize>);

/// What [`read_records`] found.
struct Scan {
    /// The first record of each point (a later one replaces a failure).
    done: Vec<Option<Slot>>,
    /// Every valid record of the design, in file order.
    kept: Vec<Kept>,
    /// The skipped stretches, in file order.
    skipped: Vec<Skipped>,
    /// The identity frames (the manifest's JSON), in file order.
    identities: Vec<(Vec<u8>, std::ops::Range<usize>)>,
}

/// Scans `bytes` for `manifest`: the first record of each point (a later one replaces a
/// failure; a success whose values break `rules` reads as a failure that says so), every
/// valid record of the design (in file order), the skipped stretches (in file order; a valid
/// record of a point beyond the design counts as skipped) and the identity frames.
fn read_records(
    bytes: &[u8],
    fmt: Format,
    manifest: &Manifest,
    rules: Option<&RecordRules>,
) -> Scan {
    let scanned = format::scan_format(bytes, manifest.n_values, fmt);
    let mut done: Vec<Option<Slot>> = vec![None; manifest.n_points];
    let mut kept = Vec::with_capacity(scanned.records.len());
    let mut skipped = scanned.skipped;
    for (i, slot, range) in scanned.records {
        if i >= manifest.n_points {
            skipped.push(Skipped {
                bytes: range.start as u64..range.end as u64,
                point: None,
                reason: format!(
                    "record of point {i}, but the design has {} points",
                    manifest.n_points
                ),
            });
            continue;
        }
        let slot = match (slot, rules) {
            (Slot::Ok(r), Some(rules)) => match rules.check_bytes(&bytes[r.clone()]) {
                Ok(()) => Slot::Ok(r),
                Err(problem) => Slot::Failed(format!(
                    "its record in the results store holds {problem}: a run never stores \
                     one (the point fails instead), so the store was damaged or edited; \
                     --retry-failed runs the point again"
                )),
            },
            (slot, _) => slot,
        };
        // The first result of a point is kept, except that a later record replaces a failure
        // (a point run again by `--retry-failed`).
        if matches!(done[i], None | Some(Slot::Failed(_))) {
            done[i] = Some(slot);
        }
        kept.push((i, range));
    }
    skipped.sort_by_key(|s| s.bytes.start);
    Scan {
        done,
        kept,
        skipped,
        identities: scanned.identities,
    }
}

/// The identity a store's `records.bin` starts with: the manifest as JSON.
fn identity_json(manifest: &Manifest) -> Vec<u8> {
    serde_json::to_vec(manifest).expect("serializable")
}

/// Refuses identity frames of another study or FMU than `manifest`'s.
fn check_identities(
    dir: &Path,
    identities: &[(Vec<u8>, std::ops::Range<usize>)],
    manifest: &Manifest,
) -> Result<(), StoreError> {
    for (json, range) in identities {
        let other = match serde_json::from_slice::<Manifest>(json) {
            Ok(m) if &m == manifest => continue,
            Ok(m) => m,
            Err(_) => {
                return Err(StoreError::Mismatch {
                    dir: dir.to_path_buf(),
                    what: format!(
                        "store/records.bin holds, at byte {}, a study identity that cannot be \
                         read",
                        range.start
                    ),
                })
            }
        };
        let what = if other.fmu_sha256 != manifest.fmu_sha256 {
            "its FMU differs"
        } else if other.study_hash != manifest.study_hash {
            "its study definition differs"
        } else {
            "its design has other sizes"
        };
        let place = if range.start == 0 {
            String::new()
        } else {
            format!(" from byte {}", range.start)
        };
        return Err(StoreError::Mismatch {
            dir: dir.to_path_buf(),
            what: format!(
                "store/records.bin holds{place} the records of another study or FMU ({what}: \
                 study hash {}, FMU SHA-256 {}, where this one has {} and {}), although \
                 store/manifest.json matches: the file was copied from another folder",
                short(&other.study_hash),
                short(&other.fmu_sha256),
                short(&manifest.study_hash),
                short(&manifest.fmu_sha256)
            ),
        });
    }
    Ok(())
}

/// The first 12 characters of a hash, for messages.
fn short(hash: &str) -> &str {
    hash.get(..12).unwrap_or(hash)
}

/// The name of the kept copy of a store rewritten from format `fmt`.
fn label(fmt: Format) -> String {
    match fmt {
        Format::V1 => "v1".to_string(),
        Format::V2 => format!("damaged-{}", unix_seconds()),
    }
}

/// Writes the `kept` records only, in format 2: a format-1 store is re-encoded (the first
/// record of each point), a damaged one keeps the valid records' bytes.
fn write_kept(
    w: &mut dyn Write,
    bytes: &[u8],
    fmt: Format,
    kept: &[Kept],
    done: &[Option<Slot>],
) -> std::io::Result<()> {
    match fmt {
        Format::V1 => {
            // The first record of each point (later ones are never read).
            let mut written = vec![false; done.len()];
            for &(i, _) in kept {
                if let (Some(slot), false) = (&done[i], written[i]) {
                    let rec = match slot {
                        Slot::Ok(r) => Record::Ok(format::values_of(&bytes[r.clone()])),
                        Slot::Failed(m) => Record::Failed(m.clone()),
                    };
                    w.write_all(&encode(i, &rec))?;
                    written[i] = true;
                }
            }
        }
        Format::V2 => {
            for (_, r) in kept {
                w.write_all(&bytes[r.clone()])?;
            }
        }
    }
    Ok(())
}

/// Writes the manifest of a new store, or checks that an existing one is `manifest`.
fn check_manifest(dir: &Path, mpath: &Path, manifest: &Manifest) -> Result<(), StoreError> {
    if !mpath.exists() {
        let text = serde_json::to_string_pretty(manifest).expect("serializable");
        return out_file::write(mpath, text.as_bytes()).map_err(io_err(mpath));
    }
    let text = fs::read_to_string(mpath).map_err(io_err(mpath))?;
    let old: Manifest = serde_json::from_str(&text).map_err(|e| StoreError::Corrupt {
        path: mpath.to_path_buf(),
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
    Ok(())
}

fn unix_seconds() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

/// Writes the new content of the store file `path` to a temporary file beside it (synced to
/// the disk) and returns that file's path; the temporary file is removed if writing fails.
fn write_tmp(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<PathBuf, StoreError> {
    let tmp = path.with_extension("bin.tmp");
    let written = (|| {
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&tmp)?;
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        write(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()
    })();
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            source: e,
        });
    }
    Ok(tmp)
}

/// Replaces the store file `path` by `tmp` (from [`write_tmp`]), keeping the file as found
/// as `records.<label>.bin` when a label is given (a hard link where the file system allows
/// it, else a copy); returns the new file, open for reading and appending, and the backup's
/// path.
fn replace(
    path: &Path,
    tmp: &Path,
    label: Option<&str>,
) -> Result<(File, Option<PathBuf>), StoreError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let backup = label.map(|label| {
        let mut backup = dir.join(format!("records.{label}.bin"));
        let mut n = 1;
        while backup.exists() {
            n += 1;
            backup = dir.join(format!("records.{label}-{n}.bin"));
        }
        backup
    });
    let kept = (|| {
        if let Some(backup) = &backup {
            if fs::hard_link(path, backup).is_err() {
                fs::copy(path, backup)?;
            }
        }
        fs::rename(tmp, path)
    })();
    if let Err(e) = kept {
        let _ = fs::remove_file(tmp);
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            source: e,
        });
    }
    // Make the rename durable; not every platform can sync a folder.
    let _ = File::open(dir).and_then(|d| d.sync_all());
    let file = OpenOptions::new()
        .read(true)
        .append(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
        .map_err(io_err(path))?;
    Ok((file, backup))
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

    /// A records.bin copied from another study's folder (its manifest.json left as it was)
    /// was read as this study's: the shard's outputs paired with another design's inputs.
    #[test]
    fn a_records_file_of_another_study_is_refused_even_under_a_matching_manifest() {
        let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let mut other = manifest();
        other.study_hash = "t".into();
        let (s, _) = Store::open(a.path(), &manifest(), false).unwrap();
        s.append(0, &Record::Ok(vec![1.0, 2.0])).unwrap();
        drop(s);
        let (s, _) = Store::open(b.path(), &other, false).unwrap();
        s.append(0, &Record::Ok(vec![3.0, 4.0])).unwrap();
        drop(s);
        let records = |d: &tempfile::TempDir| d.path().join("store/records.bin");
        fs::copy(records(&b), records(&a)).unwrap();
        let e = Store::open(a.path(), &manifest(), false).unwrap_err();
        assert!(matches!(e, StoreError::Mismatch { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains(
                "store/records.bin holds the records of another study or FMU (its \
                           study definition differs"
            ) && text.contains("copied from another folder"),
            "{text}"
        );
        // Appended to this study's own file: refused too, naming where it starts.
        let own = {
            let (s, _) = Store::open(a.path(), &manifest(), true).unwrap();
            s.append(0, &Record::Ok(vec![1.0, 2.0])).unwrap();
            drop(s);
            fs::read(records(&a)).unwrap()
        };
        let theirs = fs::read(records(&b)).unwrap();
        fs::write(records(&a), [own.clone(), theirs].concat()).unwrap();
        let text = Store::open(a.path(), &manifest(), false)
            .unwrap_err()
            .to_string();
        assert!(text.contains(&format!("from byte {}", own.len())), "{text}");
    }

    /// A store written before stores carried their identity still resumes, once, with a
    /// note, and carries it from then on; nothing is lost.
    #[test]
    fn a_store_without_an_identity_is_resumed_and_gets_one() {
        let dir = tempfile::tempdir().unwrap();
        drop(Store::open(dir.path(), &manifest(), false).unwrap());
        let path = dir.path().join("store/records.bin");
        let old = [
            encode(0, &Record::Ok(vec![1.0, 2.0])),
            encode(3, &Record::Failed("x".into())),
        ]
        .concat();
        fs::write(&path, &old).unwrap();
        let (s, done) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert!(s.recovery().identity_added);
        assert_eq!(
            s.recovery().backup,
            None,
            "nothing to keep: no record was dropped"
        );
        assert!(s
            .recovery()
            .to_string()
            .contains("the study's identity was added"));
        assert_eq!(done[0], Some(Record::Ok(vec![1.0, 2.0])));
        assert_eq!(done[3], Some(Record::Failed("x".into())));
        drop(s);
        let bytes = fs::read(&path).unwrap();
        assert!(bytes.ends_with(&old));
        let (s, _) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert!(s.recovery().is_clean(), "{}", s.recovery());
    }

    /// A forged record of NaNs (valid checksums) gave a NaN mean in q.csv with exit status
    /// 0: with the study's rules it reads as a failure of its point that says why.
    #[test]
    fn a_stored_record_of_non_finite_values_reads_as_a_failed_point() {
        let dir = tempfile::tempdir().unwrap();
        let (s, _) = Store::open(dir.path(), &manifest(), false).unwrap();
        s.append(1, &Record::Ok(vec![f64::NAN, 2.0])).unwrap();
        s.append(2, &Record::Ok(vec![1.0, 2.0])).unwrap();
        drop(s);
        let rules = RecordRules::new(&["q".into()], &[0.0, 0.5], Vec::new());
        let (_, runs) = Store::open_checked(dir.path(), &manifest(), false, Some(&rules)).unwrap();
        match runs.record(1).unwrap() {
            Some(Record::Failed(m)) => assert!(
                m.starts_with(
                    "its record in the results store holds a non-finite value (NaN) of output \
                     'q' at t = 0 s"
                ) && m.contains("--retry-failed"),
                "{m}"
            ),
            other => panic!("{other:?}"),
        }
        assert_eq!(runs.record(2).unwrap(), Some(Record::Ok(vec![1.0, 2.0])));
        // A later valid record of the point (--retry-failed) replaces the failure.
        let (s, _) = Store::open(dir.path(), &manifest(), false).unwrap();
        s.append(1, &Record::Ok(vec![5.0, 6.0])).unwrap();
        drop(s);
        let (_, runs) = Store::open_checked(dir.path(), &manifest(), false, Some(&rules)).unwrap();
        assert_eq!(runs.record(1).unwrap(), Some(Record::Ok(vec![5.0, 6.0])));
    }

    #[test]
    fn corrupted_byte_skips_only_its_record() {
        let a = encode(0, &Record::Ok(vec![1.0, 2.0]));
        let mut b = encode(1, &Record::Ok(vec![3.0, 4.0]));
        b[30] ^= 1;
        let c = encode(2, &Record::Ok(vec![5.0, 6.0]));
        let all = [a.clone(), b.clone(), c.clone()].concat();
        let (recs, end) = decode_all(&all, 2);
        assert_eq!(
            recs,
            vec![
                (0, Record::Ok(vec![1.0, 2.0])),
                (2, Record::Ok(vec![5.0, 6.0]))
            ]
        );
        assert_eq!(end, all.len());
    }

    #[test]
    fn intact_store_reports_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (s, _) = Store::open(dir.path(), &manifest(), false).unwrap();
        s.append(1, &Record::Ok(vec![1.0, 2.0])).unwrap();
        drop(s);
        let (s, done) = Store::open(dir.path(), &manifest(), false).unwrap();
        assert!(s.recovery().is_clean(), "{}", s.recovery());
        assert_eq!(s.recovery().summary(), None);
        assert_eq!(s.recovery().kept, 1);
        assert_eq!(s.recovery().missing, 3);
        assert_eq!(done.iter().flatten().count(), 1);
    }
}
