//! The harness process's peak resident memory during a scenario (issue 23: "peak memory of the
//! harness on the 4K city within 2 GiB beyond the adapter's own allocations"): Linux's `VmHWM`
//! from `/proc/self/status`, reset at the scenario's start through `/proc/self/clear_refs`
//! (value 5). It counts host memory only: what a discrete GPU's driver keeps in device memory is
//! not in it, what lavapipe (a CPU adapter) allocates is. `None` where the kernel does not offer it.

/// Resets the peak to the current resident size, so the next [`peak_bytes`] is this scenario's.
pub fn reset_peak() {
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
