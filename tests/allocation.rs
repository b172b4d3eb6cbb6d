//! The detector reuses its buffers: once warmed up on a scan, detecting a scan
//! of the same size allocates nothing, with or without the noise estimate and
//! the straightness test. Checked with a counting allocator.

#![allow(unsafe_code)] // the counting allocator below

mod support;

use pcaline::{Config, LineDetector};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steady_state_detection_does_not_allocate() {
    let walls = support::rectangle(-2.0, -3.0, 5.0, 4.0);
    let scans: Vec<_> = (0..4).map(|seed| support::utm_scan(&walls, 0.01, seed)).collect();
    for config in [Config::paper(), Config::default(), Config::adaptive()] {
        let mut det = LineDetector::new(config).unwrap();
        for scan in &scans {
            det.detect(scan);
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let mut lines = 0;
        for scan in &scans {
            lines += det.detect(scan).lines.len();
        }
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert!(lines > 0);
        assert_eq!(after - before, 0, "detection allocated {} times", after - before);
    }
}
