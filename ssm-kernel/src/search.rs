//! Searches along a scan whose test is costly.

/// The first index `k < n` where `pred(k)` holds, `pred` evaluated at every
/// `stride`-th index (and the last) and, past the first that holds,
/// bisected back to the index after the last that does not: the first of a
/// scan of every index when `pred` switches from false to true once within
/// a stride, in about `n / stride + log2(stride)` evaluations instead of up
/// to `n` (for a predicate that costs much, such as an error estimate along
/// a scan of amplitudes).
pub fn first_true(n: usize, stride: usize, mut pred: impl FnMut(usize) -> bool) -> Option<usize> {
    let stride = stride.max(1);
    // the first index not known to fail
    let mut start = 0;
    let mut k = 0;
    while k < n {
        if pred(k) {
            let mut hi = k;
            while start < hi {
                let mid = start + (hi - start) / 2;
                if pred(mid) {
                    hi = mid;
                } else {
                    start = mid + 1;
                }
            }
            return Some(hi);
        }
        start = k + 1;
        k = if k + 1 == n {
            n
        } else {
            (k + stride).min(n - 1)
        };
    }
    None
}
