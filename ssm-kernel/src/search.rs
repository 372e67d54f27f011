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
            return Some(bisect(start, k, pred));
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

/// [`first_true`] with the strided indices tested a batch at a time, one
/// per thread of the current rayon pool (the bisection, whose tests depend
/// on each other, one by one): the same index for the same `pred`, at the
/// cost of up to a batch's worth of tests past the first that holds.
pub fn first_true_par(
    n: usize,
    stride: usize,
    pred: impl Fn(usize) -> bool + Sync,
) -> Option<usize> {
    use rayon::prelude::*;
    let stride = stride.max(1);
    // the indices first_true tests before it bisects, in its order
    let mut points = Vec::with_capacity(n / stride + 2);
    let mut k = 0;
    while k < n {
        points.push(k);
        k = if k + 1 == n {
            n
        } else {
            (k + stride).min(n - 1)
        };
    }
    let batch = rayon::current_num_threads().max(1);
    // the first index not known to fail
    let mut start = 0;
    for group in points.chunks(batch) {
        let holds: Vec<bool> = group.par_iter().map(|&k| pred(k)).collect();
        if let Some(pos) = holds.iter().position(|&h| h) {
            if pos > 0 {
                start = group[pos - 1] + 1;
            }
            return Some(bisect(start, group[pos], pred));
        }
        start = group[group.len() - 1] + 1;
    }
    None
}

/// The first index of `start ..= hi` where `pred` holds, given that it holds
/// at `hi` and switches once in between.
fn bisect(mut start: usize, mut hi: usize, mut pred: impl FnMut(usize) -> bool) -> usize {
    while start < hi {
        let mid = start + (hi - start) / 2;
        if pred(mid) {
            hi = mid;
        } else {
            start = mid + 1;
        }
    }
    hi
}
