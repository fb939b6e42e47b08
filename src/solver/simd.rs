//! Runtime choice of the instruction set for the models' hot loops.
//!
//! The shipped binaries are built for the baseline x86-64 (SSE2). Where the CPU has AVX2 and
//! FMA, the hot loops run compiled for it instead: a [`Job`] whose `run` is
//! `#[inline(always)]` (and everything it calls in the hot path, too) is compiled twice, once
//! as is and once inside a `#[target_feature(enable = "avx2,fma")]` function, and
//! [`Simd::dispatch`] calls the one this CPU runs. The compiler does not contract `a * b + c`
//! into fused multiply–adds on its own, and wider vectors do not reorder the arithmetic, so
//! both paths compute the same numbers; the tests run every path the machine has.
//!
//! This module holds the only `unsafe` of the models' code: calling the AVX2 copy, which is
//! sound because a [`Simd`] naming AVX2 exists only after the CPU was found to support it.
#![allow(unsafe_code)]

/// An instruction set the hot loops can be compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// The target's baseline (x86-64: SSE2).
    Baseline,
    /// x86-64 with AVX2 and FMA.
    Avx2,
}

/// An instruction set this CPU supports (constructed only by detection).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Simd {
    isa: Isa,
}

/// A piece of work to run compiled for the chosen instruction set. Implement `run` with
/// `#[inline(always)]`, and mark the functions of its hot path `#[inline(always)]`, so that
/// they are compiled into each copy.
pub trait Job {
    /// The work.
    fn run(&mut self);
}

impl Simd {
    /// The widest instruction set of this CPU.
    pub fn best() -> Simd {
        Simd::new(Isa::Avx2).unwrap_or(Simd::baseline())
    }

    /// The baseline (always available).
    pub const fn baseline() -> Simd {
        Simd { isa: Isa::Baseline }
    }

    /// `isa`, if this CPU supports it.
    pub fn new(isa: Isa) -> Option<Simd> {
        let supported = match isa {
            Isa::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 => false,
        };
        supported.then_some(Simd { isa })
    }

    /// Every instruction set this CPU supports.
    pub fn available() -> Vec<Simd> {
        [Isa::Baseline, Isa::Avx2]
            .into_iter()
            .filter_map(Simd::new)
            .collect()
    }

    /// The instruction set.
    pub fn isa(self) -> Isa {
        self.isa
    }

    /// Runs `job` compiled for this instruction set.
    #[inline]
    pub fn dispatch<J: Job>(self, job: &mut J) {
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                // SAFETY: a `Simd` with `Isa::Avx2` is only made by `Simd::new`, after
                // `is_x86_feature_detected!` found AVX2 and FMA on this CPU.
                unsafe { run_avx2(job) }
            }
            _ => job.run(),
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2,fma")]
fn run_avx2<J: Job>(job: &mut J) {
    job.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sum<'a>(&'a [f64], f64);

    impl Job for Sum<'_> {
        #[inline(always)]
        fn run(&mut self) {
            self.1 = self.0.iter().map(|x| x * 0.5 + 1.0).sum();
        }
    }

    #[test]
    fn every_available_path_gives_the_same_numbers() {
        let data: Vec<f64> = (0..1000).map(|i| (i as f64).sqrt()).collect();
        let results: Vec<f64> = Simd::available()
            .into_iter()
            .map(|s| {
                let mut job = Sum(&data, 0.0);
                s.dispatch(&mut job);
                job.1
            })
            .collect();
        assert!(results.iter().all(|r| r.to_bits() == results[0].to_bits()));
        assert_eq!(Simd::baseline().isa(), Isa::Baseline);
        assert!(Simd::available().contains(&Simd::best()));
    }
}
