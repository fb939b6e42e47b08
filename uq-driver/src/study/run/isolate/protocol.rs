//! The frames parent and worker exchange: a tag byte, a little-endian u64 length and the
//! payload (the tags: the module documentation of [`super`]).

use std::io::{Read, Write};

/// Largest frame accepted (bytes): far above any record, small enough to refuse garbage.
const MAX_FRAME: u64 = 1 << 34;

/// A frame read by the reader thread.
pub(super) type Frame = (u8, Vec<u8>);

pub(super) fn f64s_to_bytes(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

pub(super) fn bytes_to_f64s(b: &[u8]) -> Vec<f64> {
    b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

/// Writes one frame.
pub fn write_frame(w: &mut impl Write, tag: u8, payload: &[u8]) -> std::io::Result<()> {
    let mut head = [0u8; 9];
    head[0] = tag;
    head[1..].copy_from_slice(&(payload.len() as u64).to_le_bytes());
    w.write_all(&head)?;
    w.write_all(payload)?;
    w.flush()
}

/// Reads one frame; `None` at a clean end of the stream.
pub fn read_frame(r: &mut impl Read) -> std::io::Result<Option<Frame>> {
    let mut head = [0u8; 9];
    let mut got = 0;
    while got < head.len() {
        match r.read(&mut head[got..])? {
            0 if got == 0 => return Ok(None),
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => got += n,
        }
    }
    let len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
    if len > MAX_FRAME {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("frame of {len} bytes"),
        ));
    }
    // Grown as the bytes come: a garbage length allocates nothing up front.
    let mut payload = Vec::new();
    r.take(len).read_to_end(&mut payload)?;
    if payload.len() as u64 != len {
        return Err(std::io::ErrorKind::UnexpectedEof.into());
    }
    Ok(Some((head[0], payload)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_and_a_torn_frame_is_an_error() {
        let mut buf = Vec::new();
        write_frame(&mut buf, b'P', &f64s_to_bytes(&[1.5, -0.0, f64::NAN])).unwrap();
        write_frame(&mut buf, b'R', &[]).unwrap();
        let mut r = &buf[..];
        let (tag, p) = read_frame(&mut r).unwrap().unwrap();
        assert_eq!(tag, b'P');
        let v = bytes_to_f64s(&p);
        assert_eq!(v[0], 1.5);
        assert!(v[1] == 0.0 && v[1].is_sign_negative());
        assert!(v[2].is_nan());
        assert_eq!(read_frame(&mut r).unwrap(), Some((b'R', Vec::new())));
        assert_eq!(read_frame(&mut r).unwrap(), None);
        let torn = &buf[..12];
        assert!(read_frame(&mut &torn[..]).is_err());
        let mut huge = vec![b'O'];
        huge.extend_from_slice(&u64::MAX.to_le_bytes());
        assert!(read_frame(&mut &huge[..]).is_err());
    }
}
