//! The finished points of a study read in place: the store file is memory-mapped and only
//! the position of each point's values is held, so the runs of a study need not fit in memory
//! (issue 12). The analysis reads the values it needs, a block of time columns at a time
//! ([`StoredRuns::values`]); the operating system pages the file in and out.

use std::fs::File;
use std::ops::Range;
use std::path::{Path, PathBuf};

use memmap2::Mmap;

use super::format::{self, Format, Slot};
use super::{Record, StoreError};

/// The result of one point, its values left in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Entry {
    /// A finished run: its values are these bytes of the file (little-endian f64).
    Ok(Range<usize>),
    /// A failed run, with the reason.
    Failed(String),
}

/// The bytes the entries point into.
#[derive(Debug)]
enum Bytes {
    /// The store file, mapped.
    Mapped(Mmap),
    /// Bytes in memory (records built in memory, an empty file).
    Owned(Vec<u8>),
}

/// The result of every point of a design, read in place from a results store.
#[derive(Debug)]
pub struct StoredRuns {
    bytes: Bytes,
    n_values: usize,
    entries: Vec<Option<Entry>>,
}

impl StoredRuns {
    /// The store file `path` of a design of `n_points` points recording `n_values` values
    /// each: per point, its first successful record, else its last failure (the rule of
    /// [`Store::open`](super::Store::open)); damaged stretches are skipped. The file must not
    /// be shortened while this is alive (the study holds its folder's lock; see
    /// [`super::super::lock`]).
    pub fn open(path: &Path, n_points: usize, n_values: usize) -> Result<StoredRuns, StoreError> {
        let io = |source| StoreError::Io {
            path: PathBuf::from(path),
            source,
        };
        let file = File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let bytes = if len == 0 {
            Bytes::Owned(Vec::new())
        } else {
            // SAFETY: the map is read-only and only read as bytes; the store file is only
            // appended to (never shortened or rewritten in place) while a study holds its
            // folder's lock, which the caller holds (or, for a finished shard, no run writes).
            // Bytes appended after mapping are not seen.
            Bytes::Mapped(unsafe { Mmap::map(&file) }.map_err(io)?)
        };
        Ok(StoredRuns::index(bytes, n_points, n_values))
    }

    /// The same from records in memory (one per point of a design).
    pub fn from_records(records: &[Option<Record>], n_values: usize) -> StoredRuns {
        let mut bytes = Vec::new();
        for (i, r) in records.iter().enumerate() {
            if let Some(r) = r {
                bytes.extend_from_slice(&format::encode(i, r));
            }
        }
        StoredRuns::index(Bytes::Owned(bytes), records.len(), n_values)
    }

    fn index(bytes: Bytes, n_points: usize, n_values: usize) -> StoredRuns {
        let data: &[u8] = match &bytes {
            Bytes::Mapped(m) => m,
            Bytes::Owned(v) => v,
        };
        let scanned = format::scan_format(data, n_values, Format::V2);
        let mut entries: Vec<Option<Entry>> = vec![None; n_points];
        for (i, slot, _) in scanned.records {
            let Some(e) = entries.get_mut(i) else {
                continue;
            };
            if matches!(e, None | Some(Entry::Failed(_))) {
                *e = Some(match slot {
                    Slot::Ok(r) => Entry::Ok(r),
                    Slot::Failed(m) => Entry::Failed(m),
                });
            }
        }
        StoredRuns {
            bytes,
            n_values,
            entries,
        }
    }

    fn data(&self) -> &[u8] {
        match &self.bytes {
            Bytes::Mapped(m) => m,
            Bytes::Owned(v) => v,
        }
    }

    /// Points of the design.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the design has no point.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Values per successful point.
    pub fn n_values(&self) -> usize {
        self.n_values
    }

    /// The result of every point (`None`: not run).
    pub fn entries(&self) -> &[Option<Entry>] {
        &self.entries
    }

    /// The values of point `i` as bytes (8 per value, little endian), if it succeeded.
    pub fn values(&self, i: usize) -> Option<Values<'_>> {
        match self.entries.get(i)? {
            Some(Entry::Ok(r)) => Some(Values(&self.data()[r.clone()])),
            _ => None,
        }
    }

    /// The record of point `i`, its values read into memory.
    pub fn record(&self, i: usize) -> Option<Record> {
        match self.entries.get(i)?.as_ref()? {
            Entry::Ok(r) => Some(Record::Ok(format::values_of(&self.data()[r.clone()]))),
            Entry::Failed(m) => Some(Record::Failed(m.clone())),
        }
    }

    /// Every record read into memory (for small studies and tests).
    pub fn records(&self) -> Vec<Option<Record>> {
        (0..self.len()).map(|i| self.record(i)).collect()
    }
}

/// The values of one run, in the file.
#[derive(Clone, Copy, Debug)]
pub struct Values<'a>(&'a [u8]);

impl Values<'_> {
    /// Value `k`.
    pub fn get(&self, k: usize) -> f64 {
        let b = &self.0[8 * k..8 * k + 8];
        f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
    }

    /// Values `range` written into `out` (of the same length).
    pub fn read_into(&self, range: Range<usize>, out: &mut [f64]) {
        let bytes = &self.0[8 * range.start..8 * range.end];
        for (o, c) in out.iter_mut().zip(bytes.chunks_exact(8)) {
            *o = f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_in_place_what_was_appended() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("records.bin");
        let recs = [
            (2, Record::Failed("first".into())),
            (1, Record::Ok(vec![1.5, -2.0])),
            (2, Record::Ok(vec![3.0, 4.0])),
            (1, Record::Ok(vec![9.0, 9.0])),
            (0, Record::Failed("a".into())),
            (0, Record::Failed("b".into())),
            (7, Record::Ok(vec![0.0, 0.0])),
        ];
        let bytes: Vec<u8> = recs
            .iter()
            .flat_map(|(i, r)| format::encode(*i, r))
            .collect();
        std::fs::write(&path, &bytes).unwrap();
        let runs = StoredRuns::open(&path, 4, 2).unwrap();
        assert_eq!(runs.record(0), Some(Record::Failed("b".into())));
        assert_eq!(runs.record(1), Some(Record::Ok(vec![1.5, -2.0])));
        assert_eq!(runs.record(2), Some(Record::Ok(vec![3.0, 4.0])));
        assert_eq!(runs.record(3), None);
        let v = runs.values(2).unwrap();
        assert_eq!(v.get(1), 4.0);
        let mut out = [0.0; 2];
        v.read_into(0..2, &mut out);
        assert_eq!(out, [3.0, 4.0]);
        let same = StoredRuns::from_records(&runs.records(), 2);
        assert_eq!(same.records(), runs.records());
        std::fs::write(&path, b"").unwrap();
        assert_eq!(
            StoredRuns::open(&path, 2, 2).unwrap().records(),
            vec![None, None]
        );
    }
}
