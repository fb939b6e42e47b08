//! The VehicleTrack step allocates nothing: a counting global allocator (this test binary's
//! own) sees no allocation during `do_step`, on every kernel path, at N = NM and NM = 2N + 1,
//! window shifts included.
//!
//! This file stays a test binary of its own, apart from `fmi_abi.rs`: a `#[global_allocator]`
//! is the allocator of the whole binary, and the count must see this one test's allocations
//! only (tests of the same binary run on other threads at the same time and would allocate
//! between the two readings of the counter).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use railuq::models::vehicle_track::variables::{VR_DT, VR_N_MODES, VR_N_SLEEPERS};
use railuq::models::vehicle_track::{Kernel, VehicleTrack};
use railuq::models::{InitContext, Model};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged; it only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout (see `alloc`).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract for `realloc` is passed on unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn do_step_allocates_nothing_on_any_kernel_path() {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let v = std::hint::black_box(vec![1.0f64; 3]);
    assert!(
        ALLOCATIONS.load(Ordering::Relaxed) > before && v.len() == 3,
        "the counter counts"
    );
    for (n, nm, dt) in [(63, 63, 1e-4), (63, 127, 2e-5)] {
        for kernel in Kernel::available() {
            let mut m = VehicleTrack::default();
            m.set_kernel(kernel);
            m.set_integer(VR_N_SLEEPERS, n).unwrap();
            m.set_integer(VR_N_MODES, nm).unwrap();
            m.set_real(VR_DT, dt).unwrap();
            m.initialize(&InitContext::default()).unwrap();
            let before = ALLOCATIONS.load(Ordering::Relaxed);
            // 0.3 s at 83 m/s: the 38 m window moves several times.
            for i in 0..30 {
                m.do_step(i as f64 * 0.01, 0.01).unwrap();
            }
            let count = ALLOCATIONS.load(Ordering::Relaxed) - before;
            assert_eq!(
                count, 0,
                "N = {n}, NM = {nm}, {kernel:?}: {count} allocations"
            );
        }
    }
}
