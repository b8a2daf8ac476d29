//! The harness process's peak resident memory during a scenario (issue 23: "peak memory of the
//! harness on the 4K city within 2 GiB beyond the adapter's own allocations"): Linux's `VmHWM`
//! from `/proc/self/status`, reset at the scenario's start through `/proc/self/clear_refs`
//! (value 5). It counts host memory only: what a discrete GPU's driver keeps in device memory is
//! not in it, what lavapipe (a CPU adapter) allocates is. `None` where the kernel does not offer it.
//!
//! Beside it, the harness's own heap: [`CountingAlloc`], the `tessera` binary's global allocator,
//! counts the bytes Rust code holds (frames, images, metric buffers, wgpu's own objects) and their
//! peak, reset at the scenario's start as `VmHWM` is. The Vulkan driver allocates through the C
//! allocator and `mmap`, which it does not see: resident minus heap is an upper bound of the
//! driver's and the libraries' host share, the heap peak is what the harness itself needs.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static HEAP_NOW: AtomicUsize = AtomicUsize::new(0);
static HEAP_PEAK: AtomicUsize = AtomicUsize::new(0);
static COUNTING: AtomicBool = AtomicBool::new(false);

/// The system allocator, counting live bytes and their peak (a few relaxed atomics per call).
/// Installed by `main.rs`; without it [`peak_heap_bytes`] is `None`.
pub struct CountingAlloc;

impl CountingAlloc {
    fn grew(size: usize) {
        let now = HEAP_NOW.fetch_add(size, Ordering::Relaxed) + size;
        HEAP_PEAK.fetch_max(now, Ordering::Relaxed);
    }
}

// SAFETY: every call is forwarded to `System` unchanged; only counters are updated beside it.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is `System`'s.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            COUNTING.store(true, Ordering::Relaxed);
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            COUNTING.store(true, Ordering::Relaxed);
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as `alloc`.
        unsafe { System.dealloc(ptr, layout) };
        HEAP_NOW.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                Self::grew(new_size - layout.size());
            } else {
                HEAP_NOW.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

/// Peak bytes of the harness's heap since the last [`reset_peak`]; `None` when
/// [`CountingAlloc`] is not the global allocator (library tests, other binaries).
pub fn peak_heap_bytes() -> Option<u64> {
    COUNTING
        .load(Ordering::Relaxed)
        .then(|| HEAP_PEAK.load(Ordering::Relaxed) as u64)
}

/// Resets both peaks to the current sizes, so the next [`peak_bytes`] and [`peak_heap_bytes`]
/// are this scenario's.
pub fn reset_peak() {
    HEAP_PEAK.store(HEAP_NOW.load(Ordering::Relaxed), Ordering::Relaxed);
    // Not an error where unsupported (other systems, restricted /proc): the peak is then `None`
    // or the process's own since its start.
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Peak resident bytes since the last [`reset_peak`] (or the process's start).
pub fn peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counter_follows_allocations_and_their_peak() {
        // The test binary's allocator is the system's: drive the counter directly.
        let layout = Layout::from_size_align(1 << 20, 8).unwrap();
        let before = HEAP_NOW.load(Ordering::Relaxed);
        // SAFETY: a valid non-zero layout, freed below with the same layout.
        let p = unsafe { CountingAlloc.alloc(layout) };
        assert!(!p.is_null());
        assert_eq!(HEAP_NOW.load(Ordering::Relaxed), before + (1 << 20));
        assert!(HEAP_PEAK.load(Ordering::Relaxed) >= before + (1 << 20));
        // SAFETY: grown from the same allocation and layout.
        let p = unsafe { CountingAlloc.realloc(p, layout, 3 << 20) };
        assert!(!p.is_null());
        let grown = Layout::from_size_align(3 << 20, 8).unwrap();
        assert_eq!(HEAP_NOW.load(Ordering::Relaxed), before + (3 << 20));
        // SAFETY: the allocation just made, with its current layout.
        unsafe { CountingAlloc.dealloc(p, grown) };
        assert_eq!(HEAP_NOW.load(Ordering::Relaxed), before);
        assert!(peak_heap_bytes().unwrap() >= (3 << 20) as u64);
        reset_peak();
        assert_eq!(HEAP_PEAK.load(Ordering::Relaxed), before);
    }

    #[test]
    fn the_peak_covers_what_was_touched_since_the_reset() {
        let Some(before) = super::peak_bytes() else {
            return; // not Linux: nothing to read (documented as `None`)
        };
        super::reset_peak();
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let after = super::peak_bytes().unwrap();
        assert!(
            after >= 64 << 20,
            "peak {after} after touching 64 MiB (before {before})"
        );
    }
}
