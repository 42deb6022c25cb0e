//! Data parallelism that pays for itself: rayon for large loops, a plain loop for
//! small ones (a rayon call from outside its pool hands work across threads, which
//! costs more than a small loop). Each index's work is independent, so the results
//! are the same whichever path runs and however many threads there are.

use rayon::prelude::*;

/// Below this many items a loop runs on the calling thread.
pub const PARALLEL_MIN_ITEMS: usize = 2048;

/// `(0..n).map(f).collect()`, in parallel when `n` is large.
pub fn map_collect<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    if n < PARALLEL_MIN_ITEMS {
        (0..n).map(f).collect()
    } else {
        (0..n).into_par_iter().map(f).collect()
    }
}

/// Calls `f(i, &mut items[i])` for every item, in parallel when there are many.
pub fn for_each_mut<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) + Sync + Send) {
    if items.len() < PARALLEL_MIN_ITEMS {
        items.iter_mut().enumerate().for_each(|(i, x)| f(i, x));
    } else {
        items.par_iter_mut().enumerate().for_each(|(i, x)| f(i, x));
    }
}

/// Calls `f(i, chunk_i)` for consecutive chunks of `size` items.
pub fn for_each_chunk_mut<T: Send>(items: &mut [T], size: usize, f: impl Fn(usize, &mut [T]) + Sync + Send) {
    if items.len() < PARALLEL_MIN_ITEMS {
        items.chunks_mut(size).enumerate().for_each(|(i, c)| f(i, c));
    } else {
        items.par_chunks_mut(size).enumerate().for_each(|(i, c)| f(i, c));
    }
}

/// The largest of `f(i)` over `0..n` (exact whatever the order).
pub fn max_of(n: usize, f: impl Fn(usize) -> f64 + Sync + Send) -> f64 {
    if n < PARALLEL_MIN_ITEMS {
        (0..n).map(f).fold(f64::NEG_INFINITY, f64::max)
    } else {
        (0..n).into_par_iter().map(f).reduce(|| f64::NEG_INFINITY, f64::max)
    }
}
