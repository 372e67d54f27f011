//! Live and peak heap bytes of the process, counted by its allocator.
//!
//! A front end (the `ssm-engine` binary, the Python module) installs
//! [`Counting`] as its global allocator; it forwards every request to the
//! system allocator and keeps two counters: the bytes allocated and not yet
//! freed, and their highest value. The numerics read [`live`] around what
//! they hold (a sparse factorization, the SSM's coefficients) to report
//! their memory as measured, not estimated, and [`peak`] says what a run
//! needed at most. Where [`Counting`] is not the allocator (unit tests, a
//! library user's own program), both return `None`.
//!
//! The counters are two relaxed atomics per allocation: exact for one thread,
//! and, while several threads allocate, a value each of them saw.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static INSTALLED: AtomicBool = AtomicBool::new(false);

/// The system allocator, with the counters of this module.
#[derive(Debug, Default, Clone, Copy)]
pub struct Counting;

impl Counting {
    fn grew(size: usize) {
        let now = LIVE.fetch_add(size, Ordering::Relaxed) + size;
        PEAK.fetch_max(now, Ordering::Relaxed);
        if !INSTALLED.load(Ordering::Relaxed) {
            INSTALLED.store(true, Ordering::Relaxed);
        }
    }

    fn shrank(size: usize) {
        LIVE.fetch_sub(size, Ordering::Relaxed);
    }
}

// SAFETY: every method forwards to `System` with the caller's layout and
// pointer unchanged; the counters do not touch the memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is passed on.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc_zeroed` is passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            Self::grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract for `dealloc` is passed on.
        unsafe { System.dealloc(ptr, layout) };
        Self::shrank(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract for `realloc` is passed on.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            Self::shrank(layout.size());
            Self::grew(new_size);
        }
        p
    }
}

/// Makes the system allocator keep the memory the process frees for its
/// own later requests instead of handing it back to the kernel: large
/// blocks come from the heap rather than from their own mappings
/// (`M_MMAP_MAX = 0`), the heap's top is not trimmed below 2 GiB
/// (`M_TRIM_THRESHOLD`), and all threads share one arena (`M_ARENA_MAX = 1`,
/// whose empty per-thread heaps would otherwise be unmapped). For a front
/// end to call once at start-up, before its threads run.
///
/// Why: a numeric run allocates and frees sparse factors of hundreds of
/// megabytes over and over. Handed back, every new one is fresh pages the
/// kernel must zero on first touch, and on a virtual machine whose freed
/// pages go back to the host (free page reporting) also fault in through
/// the host: on the 2-core KVM machine of CI a fresh 200 MB block took 0.5
/// to 1.5 s to fill against 7 ms for one reused, and a 96,484-state plate
/// run touched about 9 GB of fresh pages (2.4 GB, its peak, with this policy).
/// The process's resident memory stays at its peak instead of falling
/// after it; the peak itself is unchanged.
///
/// Returns whether the policy applies (glibc on Linux); elsewhere the
/// allocator is left as it is.
pub fn retain_freed_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets glibc's tuning parameters; each call is
        // checked and none changes memory already allocated.
        unsafe {
            libc::mallopt(libc::M_MMAP_MAX, 0) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX) == 1
                && libc::mallopt(libc::M_ARENA_MAX, 1) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

/// Heap bytes allocated and not freed now; `None` unless [`Counting`] is
/// the global allocator.
pub fn live() -> Option<usize> {
    INSTALLED
        .load(Ordering::Relaxed)
        .then(|| LIVE.load(Ordering::Relaxed))
}

/// The highest value [`live`] has had; `None` unless [`Counting`] is the
/// global allocator.
pub fn peak() -> Option<usize> {
    INSTALLED
        .load(Ordering::Relaxed)
        .then(|| PEAK.load(Ordering::Relaxed))
}

/// The bytes a value built by `f` holds once `f` returns (what stays
/// allocated, temporaries excluded), with the value; `None` bytes unless
/// [`Counting`] is the global allocator.
pub fn held<T>(f: impl FnOnce() -> T) -> (T, Option<usize>) {
    let before = live();
    let value = f();
    let bytes = before.zip(live()).map(|(b, a)| a.saturating_sub(b));
    (value, bytes)
}
