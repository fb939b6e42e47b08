//! The finished points of a study, their values left in the store file: only the position
//! of each point's values is held, so the runs of a study need not fit in memory.
//! The analysis reads the values it needs, a block of time columns at a time
//! ([`Values::read_into`], positioned reads of the file: they go through the page cache and
//! count in no process's memory).

use std::fs::File;
use std::ops::Range;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::format::Slot;
#[cfg(test)]
use super::format::{self, Format};
use super::{Record, StoreError};

/// The result of one point, its values left in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Entry {
    /// A finished run: its values are these bytes of the file (little-endian f64).
    Ok(Range<usize>),
    /// A failed run, with the reason.
    Failed(String),
}

impl Entry {
    /// The entry of a record found at `slot`.
    pub fn of(slot: Slot) -> Entry {
        match slot {
            Slot::Ok(r) => Entry::Ok(r),
            Slot::Failed(m) => Entry::Failed(m),
        }
    }
}

/// Where the values are.
#[derive(Debug)]
enum Source {
    /// The store file (read with positioned reads).
    File(File, PathBuf),
    /// Bytes in memory (records built in memory, [`StoredRuns::from_records`]: the tests).
    #[cfg(test)]
    Bytes(Vec<u8>),
}

/// The result of every point of a design, the values read from the results store on demand.
#[derive(Debug)]
pub struct StoredRuns {
    source: Source,
    n_values: usize,
    entries: Vec<Option<Entry>>,
}

impl StoredRuns {
    /// The runs of the store file `path` whose points have these `entries` (from
    /// [`Store::open_in_place`](super::Store::open_in_place) and the appends since). The
    /// file must keep the bytes the entries name (the study holds its folder's lock).
    pub fn in_file(
        path: &Path,
        n_values: usize,
        entries: Vec<Option<Entry>>,
    ) -> Result<StoredRuns, StoreError> {
        let file = File::open(path).map_err(|source| StoreError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(StoredRuns {
            source: Source::File(file, path.to_path_buf()),
            n_values,
            entries,
        })
    }

    /// The same from records in memory (one per point of a design). Serves the tests.
    #[cfg(test)]
    pub(crate) fn from_records(records: &[Option<Record>], n_values: usize) -> StoredRuns {
        let mut bytes = Vec::new();
        for (i, r) in records.iter().enumerate() {
            if let Some(r) = r {
                bytes.extend_from_slice(&format::encode(i, r));
            }
        }
        let scanned = format::scan_format(&bytes, n_values, Format::V2);
        let mut entries: Vec<Option<Entry>> = vec![None; records.len()];
        for (i, slot, _) in scanned.records {
            entries[i] = Some(Entry::of(slot));
        }
        StoredRuns {
            source: Source::Bytes(bytes),
            n_values,
            entries,
        }
    }

    /// Sets the result of point `i` (a run appended to the store).
    pub fn set(&mut self, i: usize, entry: Entry) {
        self.entries[i] = Some(entry);
    }

    /// Points of the design.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// The result of every point (`None`: not run).
    pub fn entries(&self) -> &[Option<Entry>] {
        &self.entries
    }

    /// The values of point `i` (in the file), if it succeeded.
    pub fn values(&self, i: usize) -> Option<Values<'_>> {
        match self.entries.get(i)? {
            Some(Entry::Ok(r)) => Some(Values {
                source: &self.source,
                bytes: r.clone(),
            }),
            _ => None,
        }
    }

    /// The record of point `i`, its values read into memory.
    pub fn record(&self, i: usize) -> Result<Option<Record>, StoreError> {
        Ok(match self.entries.get(i).and_then(Option::as_ref) {
            None => None,
            Some(Entry::Failed(m)) => Some(Record::Failed(m.clone())),
            Some(Entry::Ok(_)) => {
                let v = self.values(i).expect("a finished point");
                let mut out = vec![0.0; self.n_values];
                v.try_read_into(0..self.n_values, &mut out)?;
                Some(Record::Ok(out))
            }
        })
    }

    /// Every record read into memory (for small studies and tests).
    pub fn records(&self) -> Result<Vec<Option<Record>>, StoreError> {
        (0..self.len()).map(|i| self.record(i)).collect()
    }
}

/// The values of one run, in the file.
#[derive(Clone, Debug)]
pub struct Values<'a> {
    source: &'a Source,
    bytes: Range<usize>,
}

impl Values<'_> {
    /// Values `range` written into `out` (of the same length).
    pub fn try_read_into(&self, range: Range<usize>, out: &mut [f64]) -> Result<(), StoreError> {
        let (a, b) = (
            self.bytes.start + 8 * range.start,
            self.bytes.start + 8 * range.end,
        );
        assert!(
            b <= self.bytes.end && out.len() == range.len(),
            "values out of range"
        );
        match self.source {
            #[cfg(test)]
            Source::Bytes(v) => decode_into(&v[a..b], out),
            Source::File(f, path) => {
                // Straight into the f64 memory (the file is little endian, like the target
                // almost always is), in pieces of at most READ_PIECE bytes.
                for (k, piece) in out.chunks_mut(READ_PIECE / 8).enumerate() {
                    let at = (a + k * READ_PIECE) as u64;
                    f.read_exact_at(bytemuck::cast_slice_mut(piece), at)
                        .map_err(|source| StoreError::Io {
                            path: path.clone(),
                            source,
                        })?;
                    if cfg!(target_endian = "big") {
                        for x in piece.iter_mut() {
                            *x = f64::from_bits(u64::from_le(x.to_bits()));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// The most bytes read at once (1 MiB).
const READ_PIECE: usize = 1 << 20;

#[cfg(test)]
fn decode_into(bytes: &[u8], out: &mut [f64]) {
    for (o, c) in out.iter_mut().zip(bytes.chunks_exact(8)) {
        *o = f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_values_of_each_point_from_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("records.bin");
        let recs = [
            (2, Record::Failed("first".into())),
            (1, Record::Ok(vec![1.5, -2.0])),
            (2, Record::Ok(vec![3.0, 4.0])),
        ];
        let bytes: Vec<u8> = recs
            .iter()
            .flat_map(|(i, r)| format::encode(*i, r))
            .collect();
        std::fs::write(&path, &bytes).unwrap();
        let scanned = format::scan_format(&bytes, 2, Format::V2);
        let mut entries = vec![None; 4];
        for (i, slot, _) in scanned.records {
            entries[i] = Some(Entry::of(slot));
        }
        let runs = StoredRuns::in_file(&path, 2, entries).unwrap();
        assert_eq!(runs.record(0).unwrap(), None);
        assert_eq!(runs.record(1).unwrap(), Some(Record::Ok(vec![1.5, -2.0])));
        assert_eq!(runs.record(2).unwrap(), Some(Record::Ok(vec![3.0, 4.0])));
        let mut one = [0.0];
        runs.values(2)
            .unwrap()
            .try_read_into(1..2, &mut one)
            .unwrap();
        assert_eq!(one, [4.0]);
        let same = StoredRuns::from_records(&runs.records().unwrap(), 2);
        assert_eq!(same.records().unwrap(), runs.records().unwrap());
        // A file shortened under the reader: an error, not a panic.
        std::fs::write(&path, &bytes[..10]).unwrap();
        let runs = StoredRuns::in_file(&path, 2, runs.entries().to_vec()).unwrap();
        assert!(runs.record(1).is_err());
    }
}
