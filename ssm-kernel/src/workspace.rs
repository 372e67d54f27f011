//! The address space faer's dense matrix kernels reserve, taken up front.
//!
//! faer multiplies dense blocks (supernodal LU updates, QZ, Krylov bases,
//! POD snapshot products) with the x86 kernels of `private-gemm-x86`, which
//! give every thread that runs one a buffer of twice the last-level cache,
//! as the CPU reports it, on first use and for the thread's life. Where the L3 is
//! reported as 480 MiB (the 2-core virtual machines this project is measured
//! on), that is 960 MiB of address space per thread. The pages are not touched until used, so
//! resident memory barely moves, but under an address-space limit
//! (`ulimit -v`) a thread's first large product fails to allocate and the
//! process aborts.
//!
//! [`reserve`] makes the calling thread and every thread of the rayon pool
//! take that buffer now, when the limit leaves room for it: afterwards the
//! room the memory gate reads (the limit minus `VmSize`) is the room the
//! run really has, and the heap the buffers took is known
//! ([`reserved_bytes`]), so memory reports can leave it out. When it does
//! not fit, nothing is reserved and the [`Workspace`] says how much address
//! space is missing, so the gate can refuse the run with a typed error
//! instead of an abort. Untouched pages count against neither the
//! machine's available memory nor a cgroup.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// What [`reserve`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workspace {
    /// Address space one thread's buffer takes (twice the L3 cache; 0 where
    /// faer does not use those kernels).
    pub per_thread: f64,
    /// The threads that still had to reserve it (the caller and the pool's).
    pub threads: usize,
    /// Bytes the address-space limit could not hold (0 when reserved, or
    /// with no such limit).
    pub missing: f64,
}

thread_local! {
    /// Whether this thread has taken its buffer.
    static TAKEN: Cell<bool> = const { Cell::new(false) };
}

/// Whether every thread of the global rayon pool has taken its buffer.
static POOL_TAKEN: AtomicBool = AtomicBool::new(false);

/// Heap bytes the buffers took, as counted by the allocator.
static RESERVED: AtomicUsize = AtomicUsize::new(0);

/// Room kept free beside the buffers (the allocator's arenas, stacks, the
/// first allocations of a run) when deciding whether they fit.
const MARGIN: f64 = 128.0 * 1024.0 * 1024.0;

/// Takes the kernels' buffers on this thread and on the pool's threads when
/// the address-space limit holds them (see the module's text); otherwise
/// reserves nothing and reports what is missing.
pub fn reserve() -> Workspace {
    let per_thread = per_thread_bytes();
    let caller = !TAKEN.with(Cell::get);
    let pool = !POOL_TAKEN.load(Ordering::Acquire);
    let threads = usize::from(caller)
        + if pool {
            rayon::current_num_threads()
        } else {
            0
        };
    let needed = per_thread * threads as f64;
    if let Some(room) = ssm_api::limits::address_space_room() {
        if needed > 0.0 && needed + MARGIN > room {
            return Workspace {
                per_thread,
                threads,
                missing: needed + MARGIN - room,
            };
        }
    }
    let before = crate::heap::live();
    if caller {
        take();
    }
    if pool {
        rayon::broadcast(|_| take());
        POOL_TAKEN.store(true, Ordering::Release);
    }
    if let Some((b, a)) = before.zip(crate::heap::live()) {
        RESERVED.fetch_add(a.saturating_sub(b), Ordering::Relaxed);
    }
    Workspace {
        per_thread,
        threads,
        missing: 0.0,
    }
}

/// Heap bytes [`reserve`] has taken for the buffers so far (counted where
/// [`crate::heap::Counting`] is the allocator, else 0): address space that
/// is mostly never touched, so memory reports leave it out of their heap
/// figures.
pub fn reserved_bytes() -> usize {
    RESERVED.load(Ordering::Relaxed)
}

/// Runs one product large enough for faer's x86 kernels (above its
/// 16 x 16 x 16 threshold) on this thread, once.
fn take() {
    if TAKEN.with(Cell::get) {
        return;
    }
    let a = faer::Mat::<f64>::from_fn(32, 32, |i, j| (i + j) as f64);
    let mut c = faer::Mat::<f64>::zeros(32, 32);
    faer::linalg::matmul::matmul(
        c.as_mut(),
        faer::Accum::Replace,
        a.as_ref(),
        a.as_ref(),
        1.0,
        faer::Par::Seq,
    );
    std::hint::black_box(&c);
    TAKEN.with(|t| t.set(true));
}

/// Twice the L3 cache in bytes, rounded up to pages, where faer uses the
/// kernels of `private-gemm-x86` (x86-64 with AVX-512F, or AVX2 and FMA);
/// 0 elsewhere or when the cache size cannot be read.
fn per_thread_bytes() -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        let kernels = std::arch::is_x86_feature_detected!("avx512f")
            || (std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma"));
        if kernels {
            return l3_bytes().map_or(0.0, |b| 2.0 * (b / 4096.0).ceil() * 4096.0);
        }
    }
    0.0
}

/// The L3 cache of the first CPU in bytes, from sysfs.
fn l3_bytes() -> Option<f64> {
    let dir = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache").ok()?;
    dir.flatten().find_map(|e| {
        let level = std::fs::read_to_string(e.path().join("level")).ok()?;
        if level.trim() != "3" {
            return None;
        }
        cache_size(&std::fs::read_to_string(e.path().join("size")).ok()?)
    })
}

/// A sysfs cache size (`491520K`, `32M`, `512`) in bytes.
fn cache_size(text: &str) -> Option<f64> {
    let t = text.trim();
    let (digits, unit) = match t.chars().last()? {
        'K' => (&t[..t.len() - 1], 1024.0),
        'M' => (&t[..t.len() - 1], 1024.0 * 1024.0),
        'G' => (&t[..t.len() - 1], 1024.0 * 1024.0 * 1024.0),
        _ => (t, 1.0),
    };
    digits.parse::<f64>().ok().map(|v| v * unit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sysfs_cache_sizes_are_read_with_their_unit() {
        assert_eq!(cache_size("491520K\n"), Some(491_520.0 * 1024.0));
        assert_eq!(cache_size("32M"), Some(32.0 * 1024.0 * 1024.0));
        assert_eq!(cache_size("512"), Some(512.0));
        assert_eq!(cache_size("x"), None);
        assert_eq!(cache_size(""), None);
    }
}
