//! ChaCha20 (20 rounds, a 64-bit block counter and a 64-bit stream number) computed one
//! 64-byte block at a time.
//!
//! The output is that of `rand_chacha::ChaCha20Rng` 0.3 word for word, for any mix of
//! `next_u32`, `next_u64` and `fill_bytes`: the same buffer of four blocks and the same rules
//! for reading it (`rand_core::block::BlockRng`), but a block is computed only when a word of
//! it is first read. The studies open a fresh stream per sample and read a few words of it
//! (one per coordinate); rand_chacha computes four blocks (64 words) at the first read, and
//! that was 41 % of the time of a study drawing 40 million chaos-surrogate points.
//!
//! The tests below compare every output with rand_chacha's.

use rand::{RngCore, SeedableRng};

/// Words in the buffer: four blocks of 16, as rand_chacha buffers them.
const WORDS: usize = 64;
/// Words in one block.
const BLOCK: usize = 16;
/// "expand 32-byte k".
const CONSTANTS: [u32; 4] = [0x6170_7865, 0x3320_646e, 0x7962_2d32, 0x6b20_6574];

/// A ChaCha20 stream: key, stream number and position, see the module documentation.
#[derive(Clone, Debug)]
pub struct ChaCha20 {
    key: [u32; 8],
    stream: u64,
    /// Block counter of the first block of the next buffer.
    counter: u64,
    /// The current buffer: blocks `counter - 4 ..` (their first `ready` computed).
    buf: [u32; WORDS],
    /// The next word of `buf` to read; `WORDS` when it is used up.
    index: usize,
    /// Blocks of `buf` computed so far.
    ready: usize,
}

impl SeedableRng for ChaCha20 {
    type Seed = [u8; 32];

    /// Stream 0 of the key `seed` (`seed_from_u64` is rand_core's, as for rand_chacha).
    fn from_seed(seed: [u8; 32]) -> Self {
        let mut key = [0u32; 8];
        for (k, bytes) in key.iter_mut().zip(seed.chunks_exact(4)) {
            *k = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        }
        ChaCha20 {
            key,
            stream: 0,
            counter: 0,
            buf: [0; WORDS],
            index: WORDS,
            ready: 0,
        }
    }
}

impl ChaCha20 {
    /// The same key on stream `stream`, at position 0.
    pub(crate) fn with_stream(mut self, stream: u64) -> Self {
        self.stream = stream;
        self.counter = 0;
        self.index = WORDS;
        self.ready = 0;
        self
    }

    /// Starts the next buffer of four blocks (none computed yet).
    fn refill(&mut self) {
        self.counter = self.counter.wrapping_add((WORDS / BLOCK) as u64);
        self.ready = 0;
    }

    /// Computes the blocks of the buffer up to the one holding word `i`.
    fn ensure(&mut self, i: usize) {
        while self.ready <= i / BLOCK {
            let counter = self
                .counter
                .wrapping_sub((WORDS / BLOCK) as u64)
                .wrapping_add(self.ready as u64);
            let at = self.ready * BLOCK;
            block(
                &self.key,
                counter,
                self.stream,
                &mut self.buf[at..at + BLOCK],
            );
            self.ready += 1;
        }
    }
}

/// One ChaCha20 block: the state of constants, key, counter and stream after 20 rounds,
/// plus that state (RFC 8439 §2.3, with a 64-bit counter in words 12–13 and the stream in
/// words 14–15).
fn block(key: &[u32; 8], counter: u64, stream: u64, out: &mut [u32]) {
    let mut input = [0u32; BLOCK];
    input[..4].copy_from_slice(&CONSTANTS);
    input[4..12].copy_from_slice(key);
    input[12] = counter as u32;
    input[13] = (counter >> 32) as u32;
    input[14] = stream as u32;
    input[15] = (stream >> 32) as u32;
    let mut x = input;
    for _ in 0..10 {
        quarter_round(&mut x, 0, 4, 8, 12);
        quarter_round(&mut x, 1, 5, 9, 13);
        quarter_round(&mut x, 2, 6, 10, 14);
        quarter_round(&mut x, 3, 7, 11, 15);
        quarter_round(&mut x, 0, 5, 10, 15);
        quarter_round(&mut x, 1, 6, 11, 12);
        quarter_round(&mut x, 2, 7, 8, 13);
        quarter_round(&mut x, 3, 4, 9, 14);
    }
    for ((o, x), i) in out.iter_mut().zip(x).zip(input) {
        *o = x.wrapping_add(i);
    }
}

#[inline(always)]
fn quarter_round(x: &mut [u32; BLOCK], a: usize, b: usize, c: usize, d: usize) {
    x[a] = x[a].wrapping_add(x[b]);
    x[d] = (x[d] ^ x[a]).rotate_left(16);
    x[c] = x[c].wrapping_add(x[d]);
    x[b] = (x[b] ^ x[c]).rotate_left(12);
    x[a] = x[a].wrapping_add(x[b]);
    x[d] = (x[d] ^ x[a]).rotate_left(8);
    x[c] = x[c].wrapping_add(x[d]);
    x[b] = (x[b] ^ x[c]).rotate_left(7);
}

impl RngCore for ChaCha20 {
    fn next_u32(&mut self) -> u32 {
        if self.index >= WORDS {
            self.refill();
            self.index = 0;
        }
        let i = self.index;
        self.ensure(i);
        self.index += 1;
        self.buf[i]
    }

    fn next_u64(&mut self) -> u64 {
        let i = self.index;
        if i < WORDS - 1 {
            self.ensure(i + 1);
            self.index += 2;
            u64::from(self.buf[i + 1]) << 32 | u64::from(self.buf[i])
        } else if i >= WORDS {
            self.refill();
            self.ensure(1);
            self.index = 2;
            u64::from(self.buf[1]) << 32 | u64::from(self.buf[0])
        } else {
            // The last word of this buffer, then the first of the next.
            self.ensure(i);
            let low = u64::from(self.buf[i]);
            self.refill();
            self.ensure(0);
            self.index = 1;
            u64::from(self.buf[0]) << 32 | low
        }
    }

    fn fill_bytes(&mut self, dest: &mut [u8]) {
        let mut done = 0;
        while done < dest.len() {
            if self.index >= WORDS {
                self.refill();
                self.index = 0;
            }
            let bytes = (dest.len() - done).min((WORDS - self.index) * 4);
            let words = bytes.div_ceil(4);
            self.ensure(self.index + words - 1);
            for (chunk, word) in dest[done..done + bytes]
                .chunks_mut(4)
                .zip(&self.buf[self.index..])
            {
                chunk.copy_from_slice(&word.to_le_bytes()[..chunk.len()]);
            }
            self.index += words;
            done += bytes;
        }
    }

    fn try_fill_bytes(&mut self, dest: &mut [u8]) -> Result<(), rand::Error> {
        self.fill_bytes(dest);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_chacha::ChaCha20Rng;

    /// Both generators on the same key and stream.
    fn pair(seed: u64, stream: u64) -> (ChaCha20, ChaCha20Rng) {
        let mut theirs = ChaCha20Rng::seed_from_u64(seed);
        theirs.set_stream(stream);
        (ChaCha20::seed_from_u64(seed).with_stream(stream), theirs)
    }

    #[test]
    fn words_match_rand_chacha_across_buffers() {
        for (seed, stream) in [(0, 0), (42, 7), (u64::MAX, u64::MAX), (3, 1 << 56 | 9)] {
            let (mut ours, mut theirs) = pair(seed, stream);
            for k in 0..300 {
                assert_eq!(ours.next_u64(), theirs.next_u64(), "seed {seed} word {k}");
            }
        }
    }

    #[test]
    fn mixed_reads_match_rand_chacha() {
        // Reads of 4, 8 and 1..=70 bytes in a pseudo-random order cross block and buffer
        // boundaries at every alignment, including a u64 split over two buffers.
        for seed in 0..40u64 {
            let (mut ours, mut theirs) = pair(seed, seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
            let mut choice = seed;
            for step in 0..400 {
                choice = choice
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                match (choice >> 60) % 3 {
                    0 => assert_eq!(ours.next_u32(), theirs.next_u32(), "{seed} {step}"),
                    1 => assert_eq!(ours.next_u64(), theirs.next_u64(), "{seed} {step}"),
                    _ => {
                        let n = 1 + (choice >> 40) as usize % 70;
                        let (mut a, mut b) = (vec![0u8; n], vec![0u8; n]);
                        ours.fill_bytes(&mut a);
                        theirs.fill_bytes(&mut b);
                        assert_eq!(a, b, "{seed} {step}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_u64_across_two_buffers_matches_rand_chacha() {
        let (mut ours, mut theirs) = pair(5, 11);
        for _ in 0..63 {
            assert_eq!(ours.next_u32(), theirs.next_u32());
        }
        assert_eq!(ours.next_u64(), theirs.next_u64());
        assert_eq!(ours.next_u64(), theirs.next_u64());
    }

    #[test]
    fn the_rfc_8439_block_test_vector() {
        // RFC 8439 §2.3.2 uses a 32-bit counter (1) and a 96-bit nonce
        // (00 00 00 09 00 00 00 4a 00 00 00 00); in the 64/64 layout that is the counter
        // 0x0900_0000_0000_0001 and the stream 0x4a00_0000.
        let mut key = [0u32; 8];
        for (i, k) in key.iter_mut().enumerate() {
            let b = 4 * i as u32;
            *k = u32::from_le_bytes([b as u8, b as u8 + 1, b as u8 + 2, b as u8 + 3]);
        }
        let mut out = [0u32; BLOCK];
        block(&key, 0x0900_0000_0000_0001, 0x4a00_0000, &mut out);
        assert_eq!(
            out,
            [
                0xe4e7_f110,
                0x1559_3bd1,
                0x1fdd_0f50,
                0xc471_20a3,
                0xc7f4_d1c7,
                0x0368_c033,
                0x9aaa_2204,
                0x4e6c_d4c3,
                0x4664_82d2,
                0x09aa_9f07,
                0x05d7_c214,
                0xa202_8bd9,
                0xd19c_12b5,
                0xb94e_16de,
                0xe883_d0cb,
                0x4e3c_50a2,
            ]
        );
    }
}
