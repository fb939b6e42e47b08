//! The byte format of `records.bin`: framing, checksums, and a reader that resynchronises
//! after damage. Every function here accepts any input without panicking.
//!
//! Format 2 (written since format 2), all integers little endian:
//!
//! ```text
//! magic F5 52 51 32 | index u64 | kind u8 | length u64 | header crc32 | payload | record crc32
//! ```
//!
//! `kind` is 0 for a finished run (payload: `length / 8` f64 values), 1 for a failed run
//! (payload: a UTF-8 message) and 2 for the store's identity (index 0; payload: the JSON of
//! the store's [`Manifest`](super::Manifest): the study hash, the FMU's SHA-256 and the
//! sizes), the first frame of every store written since stores carry it, so that the file
//! itself says which study and FMU its records belong to. The header CRC-32 covers index, kind and length, so a length is
//! trusted only when its header checksum holds; the record CRC-32 covers index, kind, length
//! and payload. After a bad record the reader scans forward for the next magic whose header and
//! record checksums hold, so one damaged record costs only its own point. The first magic byte
//! 0xF5 never occurs in UTF-8, so a failure message cannot contain a record start; f64 data
//! can, by chance, but a false start also needs two matching CRC-32s.
//!
//! Format 1 (the first): `"REC1" | index u64 | kind u8 | length u64 | payload | FNV-1a
//! u64` over index, kind and payload. It is only read, to convert an old store.

use std::ops::Range;

use super::Record;

/// Marks the start of a format-2 record.
pub const MAGIC: [u8; 4] = [0xF5, b'R', b'Q', b'2'];
/// Magic, index, kind, length, header checksum.
const HEADER: usize = 4 + 8 + 1 + 8 + 4;
/// Record checksum.
const TRAILER: usize = 4;

/// Marks the start of a format-1 record.
pub const MAGIC_V1: [u8; 4] = *b"REC1";
/// Magic, index, kind, length.
const HEADER_V1: usize = 4 + 8 + 1 + 8;
/// FNV-1a checksum.
const TRAILER_V1: usize = 8;

/// The record format of a store file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Format 1: `"REC1"` records with an FNV-1a checksum and no way to resynchronise.
    V1,
    /// Format 2: CRC-32-framed records (current).
    V2,
}

/// A stretch of `records.bin` that holds no valid record and was skipped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// The damaged bytes (offsets into the file).
    pub bytes: Range<u64>,
    /// The point whose record started there, when its header was intact.
    pub point: Option<usize>,
    /// Why the bytes were skipped.
    pub reason: String,
}

/// What [`decode`] found in a store file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Decoded {
    /// The valid records, in file order, with their byte ranges.
    pub records: Vec<(usize, Record, Range<usize>)>,
    /// The damaged stretches, in file order.
    pub skipped: Vec<Skipped>,
    /// The identity frames (the store's manifest as JSON), in file order, with their byte
    /// ranges: one at the start of a store written since stores carry one.
    pub identities: Vec<(Vec<u8>, Range<usize>)>,
}

impl Decoded {
    /// End of the last valid record (0 if there is none). Serves the tests.
    #[cfg(test)]
    pub(crate) fn valid_end(&self) -> usize {
        self.records.last().map_or(0, |(_, _, r)| r.end)
    }
}

/// `kind` of the frame that holds a store's identity.
const KIND_IDENTITY: u8 = 2;

/// Encodes one record in format 2.
pub fn encode(index: usize, rec: &Record) -> Vec<u8> {
    let (kind, payload): (u8, Vec<u8>) = match rec {
        Record::Ok(v) => (0, v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Record::Failed(m) => (1, m.as_bytes().to_vec()),
    };
    frame(index, kind, &payload)
}

/// Encodes the identity frame of a store (`identity`: the manifest's JSON), written first.
pub fn encode_identity(identity: &[u8]) -> Vec<u8> {
    frame(0, KIND_IDENTITY, identity)
}

/// One format-2 frame.
fn frame(index: usize, kind: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + payload.len() + TRAILER);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&(index as u64).to_le_bytes());
    out.push(kind);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    let header_crc = crc32fast::hash(&out[4..HEADER - 4]);
    out.extend_from_slice(&header_crc.to_le_bytes());
    out.extend_from_slice(payload);
    let mut h = crc32fast::Hasher::new();
    h.update(&out[4..HEADER - 4]);
    h.update(payload);
    out.extend_from_slice(&h.finalize().to_le_bytes());
    out
}

/// The payload bytes of a format-2 record of `len` bytes that starts at `start`.
pub fn payload_range(start: usize, len: usize) -> Range<usize> {
    start + HEADER..start + len - TRAILER
}

/// One framed record, checksums verified.
struct Frame<'a> {
    index: u64,
    kind: u8,
    payload: &'a [u8],
    end: usize,
}

/// Why no valid record starts at a position: the point, when the header was intact.
struct NoFrame {
    point: Option<u64>,
    reason: &'static str,
}

fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[..8]);
    u64::from_le_bytes(a)
}

fn le_u32(b: &[u8]) -> u32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[..4]);
    u32::from_le_bytes(a)
}

/// The end of a record of `len` payload bytes framed by `head` and `tail` bytes at `pos`, if
/// it is representable.
fn record_end(pos: usize, head: usize, len: u64, tail: usize) -> Option<usize> {
    pos.checked_add(head)?
        .checked_add(usize::try_from(len).ok()?)?
        .checked_add(tail)
}

fn frame_at(bytes: &[u8], pos: usize) -> Result<Frame<'_>, NoFrame> {
    let bad = |point, reason| Err(NoFrame { point, reason });
    let rest = bytes.get(pos..).unwrap_or_default();
    if !rest.starts_with(&MAGIC[..rest.len().min(4)]) {
        return bad(None, "no record marker");
    }
    let Some(h) = rest.get(..HEADER) else {
        return bad(None, "incomplete record (the file ends inside its header)");
    };
    if crc32fast::hash(&h[4..HEADER - 4]) != le_u32(&h[HEADER - 4..]) {
        return bad(None, "header checksum mismatch");
    }
    let (index, kind, len) = (le_u64(&h[4..]), h[12], le_u64(&h[13..]));
    let end = record_end(pos, HEADER, len, TRAILER);
    let Some(end) = end.filter(|&e| e <= bytes.len()) else {
        return bad(Some(index), "incomplete record (the file ends inside it)");
    };
    let payload = &bytes[pos + HEADER..end - TRAILER];
    let mut crc = crc32fast::Hasher::new();
    crc.update(&h[4..HEADER - 4]);
    crc.update(payload);
    if crc.finalize() != le_u32(&bytes[end - TRAILER..end]) {
        return bad(Some(index), "checksum mismatch");
    }
    Ok(Frame {
        index,
        kind,
        payload,
        end,
    })
}

fn fnv1a(index: u64, kind: u8, payload: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in index
        .to_le_bytes()
        .iter()
        .chain([kind].iter())
        .chain(payload)
    {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

fn frame_v1_at(bytes: &[u8], pos: usize) -> Result<Frame<'_>, NoFrame> {
    let bad = |point, reason| Err(NoFrame { point, reason });
    let rest = bytes.get(pos..).unwrap_or_default();
    if !rest.starts_with(&MAGIC_V1[..rest.len().min(4)]) {
        return bad(None, "no record marker");
    }
    let Some(h) = rest.get(..HEADER_V1) else {
        return bad(None, "incomplete record (the file ends inside its header)");
    };
    let (index, kind, len) = (le_u64(&h[4..]), h[12], le_u64(&h[13..]));
    // Format 1 has no header checksum: the length may be garbage (it once wrapped around).
    let end = record_end(pos, HEADER_V1, len, TRAILER_V1);
    let Some(end) = end.filter(|&e| e <= bytes.len()) else {
        return bad(None, "incomplete record, or a damaged length");
    };
    let payload = &bytes[pos + HEADER_V1..end - TRAILER_V1];
    if fnv1a(index, kind, payload) != le_u64(&bytes[end - TRAILER_V1..end]) {
        return bad(None, "checksum mismatch");
    }
    Ok(Frame {
        index,
        kind,
        payload,
        end,
    })
}

/// Reads the frame at a position: [`frame_at`] or [`frame_v1_at`].
type FrameReader = fn(&[u8], usize) -> Result<Frame<'_>, NoFrame>;

/// A valid record found by [`scan_format`], its values not read: where they are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Slot {
    /// A finished run: its `n_values` little-endian f64 values are these bytes of the file.
    Ok(Range<usize>),
    /// A failed run, with the reason.
    Failed(String),
}

/// What [`scan_format`] found in a store file: like [`Decoded`], with the values left in the
/// file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scanned {
    /// The valid records, in file order, with their byte ranges.
    pub records: Vec<(usize, Slot, Range<usize>)>,
    /// The damaged stretches, in file order.
    pub skipped: Vec<Skipped>,
    /// The identity frames, as [`Decoded::identities`].
    pub identities: Vec<(Vec<u8>, Range<usize>)>,
}

/// The values of a record's payload (`n_values` little-endian f64).
pub fn values_of(payload: &[u8]) -> Vec<f64> {
    payload
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect()
}

/// What a checksummed frame holds.
enum Content {
    /// A point's record.
    Record(usize, Slot),
    /// The store's identity (the manifest's JSON).
    Identity,
}

/// The record a checksummed frame at `pos` holds, or why it cannot be used.
fn interpret(
    f: &Frame<'_>,
    pos: usize,
    head: usize,
    n_values: usize,
    format: Format,
) -> Result<Content, String> {
    if f.kind == KIND_IDENTITY && format == Format::V2 {
        return Ok(Content::Identity);
    }
    let index = usize::try_from(f.index).map_err(|_| format!("point {} out of range", f.index))?;
    let record = |slot| Ok(Content::Record(index, slot));
    match f.kind {
        0 if Some(f.payload.len()) == n_values.checked_mul(8) => {
            record(Slot::Ok(pos + head..pos + head + f.payload.len()))
        }
        0 => Err(format!(
            "{} bytes of values where the study records {n_values} values ({} bytes)",
            f.payload.len(),
            n_values.saturating_mul(8)
        )),
        1 => record(Slot::Failed(
            String::from_utf8_lossy(f.payload).into_owned(),
        )),
        k => Err(format!("unknown record kind {k}")),
    }
}

/// Decodes a store file of format `format` whose successful records hold `n_values` values
/// each. Never panics: damaged stretches are skipped (and listed) and decoding resumes at the
/// next valid record.
pub fn decode_format(bytes: &[u8], n_values: usize, format: Format) -> Decoded {
    let scanned = scan_format(bytes, n_values, format);
    Decoded {
        records: scanned
            .records
            .into_iter()
            .map(|(i, slot, range)| {
                let rec = match slot {
                    Slot::Ok(r) => Record::Ok(values_of(&bytes[r])),
                    Slot::Failed(m) => Record::Failed(m),
                };
                (i, rec, range)
            })
            .collect(),
        skipped: scanned.skipped,
        identities: scanned.identities,
    }
}

/// [`decode_format`] without reading the values: where each valid record's values are.
pub fn scan_format(bytes: &[u8], n_values: usize, format: Format) -> Scanned {
    let (frame, magic, head): (FrameReader, [u8; 4], usize) = match format {
        Format::V1 => (frame_v1_at, MAGIC_V1, HEADER_V1),
        Format::V2 => (frame_at, MAGIC, HEADER),
    };
    let mut out = Scanned::default();
    let mut pos = 0;
    while pos < bytes.len() {
        match frame(bytes, pos) {
            Ok(f) => {
                match interpret(&f, pos, head, n_values, format) {
                    Ok(Content::Record(i, slot)) => out.records.push((i, slot, pos..f.end)),
                    Ok(Content::Identity) => {
                        out.identities.push((f.payload.to_vec(), pos..f.end));
                    }
                    Err(reason) => out.skipped.push(Skipped {
                        bytes: pos as u64..f.end as u64,
                        point: usize::try_from(f.index).ok(),
                        reason,
                    }),
                }
                pos = f.end;
            }
            Err(no) => {
                let next = next_frame(bytes, pos + 1, magic, frame).unwrap_or(bytes.len());
                out.skipped.push(Skipped {
                    bytes: pos as u64..next as u64,
                    point: no.point.and_then(|p| usize::try_from(p).ok()),
                    reason: no.reason.to_string(),
                });
                pos = next;
            }
        }
    }
    out
}

/// The first position at or after `from` where a valid frame starts.
fn next_frame(bytes: &[u8], from: usize, magic: [u8; 4], frame: FrameReader) -> Option<usize> {
    let mut at = from;
    while at < bytes.len() {
        let off = bytes[at..].windows(4).position(|w| w == magic)?;
        at += off;
        if frame(bytes, at).is_ok() {
            return Some(at);
        }
        at += 1;
    }
    None
}

/// The format of a store file: format 1 if it starts with a format-1 record marker, or if it
/// holds no format-2 record but some format-1 record; format 2 otherwise (and when empty).
pub fn detect_format(bytes: &[u8]) -> Format {
    if bytes.starts_with(&MAGIC_V1) {
        return Format::V1;
    }
    if bytes.is_empty() || frame_at(bytes, 0).is_ok() {
        return Format::V2;
    }
    if next_frame(bytes, 0, MAGIC, frame_at).is_none()
        && next_frame(bytes, 0, MAGIC_V1, frame_v1_at).is_some()
    {
        return Format::V1;
    }
    Format::V2
}

/// Decodes a store file of either format (see `detect_format`).
pub fn decode(bytes: &[u8], n_values: usize) -> (Format, Decoded) {
    let format = detect_format(bytes);
    (format, decode_format(bytes, n_values, format))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_of_both_kinds() {
        let a = encode(7, &Record::Ok(vec![1.5, -2.0]));
        let b = encode(3, &Record::Failed("bad ∆".into()));
        assert_eq!(a.len(), HEADER + 16 + TRAILER);
        let all = [a.clone(), b].concat();
        let (format, d) = decode(&all, 2);
        assert_eq!(format, Format::V2);
        assert!(d.skipped.is_empty());
        assert_eq!(d.records.len(), 2);
        assert_eq!(d.records[0].0, 7);
        assert_eq!(d.records[0].1, Record::Ok(vec![1.5, -2.0]));
        assert_eq!(d.records[1].1, Record::Failed("bad ∆".into()));
        assert_eq!(d.records[1].2, a.len()..all.len());
        assert_eq!(d.valid_end(), all.len());
    }

    #[test]
    fn wrong_value_count_is_skipped_with_its_point() {
        let a = encode(4, &Record::Ok(vec![1.0]));
        let b = encode(5, &Record::Ok(vec![1.0, 2.0]));
        let d = decode_format(&[a.clone(), b].concat(), 2, Format::V2);
        assert_eq!(d.records.len(), 1);
        assert_eq!(d.skipped.len(), 1);
        assert_eq!(d.skipped[0].point, Some(4));
        assert_eq!(d.skipped[0].bytes, 0..a.len() as u64);
    }

    /// A format-1 record as the old code wrote it (an independent re-implementation).
    pub(crate) fn encode_v1(index: u64, kind: u8, payload: &[u8]) -> Vec<u8> {
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
    fn format_1_is_detected_and_read() {
        let one: Vec<u8> = [1.0f64, 2.0].iter().flat_map(|x| x.to_le_bytes()).collect();
        let all = [encode_v1(0, 0, &one), encode_v1(1, 1, b"boom")].concat();
        let (format, d) = decode(&all, 2);
        assert_eq!(format, Format::V1);
        assert_eq!(
            d.records
                .iter()
                .map(|(i, r, _)| (*i, r.clone()))
                .collect::<Vec<_>>(),
            vec![
                (0, Record::Ok(vec![1.0, 2.0])),
                (1, Record::Failed("boom".into()))
            ]
        );
        // First marker damaged: still recognised as format 1 by the records after it.
        let mut damaged = all.clone();
        damaged[0] = b'X';
        let (format, d) = decode(&damaged, 2);
        assert_eq!(format, Format::V1);
        assert_eq!(d.records.len(), 1);
        assert_eq!(d.skipped[0].bytes.start, 0);
    }
}
