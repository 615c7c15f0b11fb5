//! Deterministic parallel loops.
//!
//! Rayon decides at run time which thread takes which item; a floating-point sum whose order depends
//! on that would differ between runs with 1 and 2 threads. Every reduction here therefore splits the
//! index range into chunks whose length [`chunk_len`] depends only on the number of items (never on
//! the thread count), sums each chunk in index order, and adds the chunk sums in chunk order. The
//! result is bit-identical for any number of threads.

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

/// Items per chunk of a large loop (enough to amortise rayon's task cost).
pub const CHUNK: usize = 2048;

/// Fewest items per chunk: below this a task costs more than the work it carries.
const MIN_CHUNK: usize = 64;

/// the chunk length for a loop over `n` items: [`CHUNK`] for large loops, and for small ones
/// about an eighth of the loop (at least [`MIN_CHUNK`]), so that a scene of a few hundred
/// particles still has work for every core. A function of `n` alone: the same chunks, hence the
/// same sums, for any thread count.
pub fn chunk_len(n: usize) -> usize {
    (n / 8).clamp(MIN_CHUNK, CHUNK)
}

/// Particles each thread needs before another thread pays for its hand-offs: below this a step's
/// loops are so short that handing half of each to a second worker costs what it saves.
/// Measured with `mpm run` on 2 cores (2 threads against 1): the flume (336 particles) 0.96×,
/// a collapsing column of 800 particles 0.86×, of 1 568 0.97×, of 3 200 1.12–1.18×, of 12 800
/// 1.41×; so a second thread from 2 400 particles.
pub const PARTICLES_PER_THREAD: usize = 1200;

/// how many of `available` threads a scene of `particles` particles should use: one per whole
/// [`PARTICLES_PER_THREAD`] particles, at least one (a second thread from 2 400 particles). Results do not depend on it (every loop
/// is chunked by size alone), only the wall time does.
pub fn useful_threads(particles: usize, available: usize) -> usize {
    (particles / PARTICLES_PER_THREAD).clamp(1, available.max(1))
}

/// Most chunks a [`counting_sort`] splits its items into: its per-chunk counters grow with
/// chunks × keys.
const SORT_CHUNKS: usize = 16;

/// A stable counting sort, in parallel: every item i < n emits up to `K` (key, value) pairs
/// (key `u32::MAX` emits nothing); afterwards the values of key k are
/// `values[start[k]..start[k + 1]]`, in increasing item order (and emission order within an item),
/// whatever the thread count. Per-chunk counts, a prefix over (key, chunk), then each chunk places
/// its values at its own offsets (atomic stores, relaxed: the positions are disjoint and the
/// join orders them before any read). `counts` is scratch; nothing is allocated once warmed up.
pub(crate) fn counting_sort<const K: usize>(
    n: usize,
    keys: usize,
    emit: impl Fn(usize) -> [(u32, u32); K] + Sync,
    start: &mut Vec<u32>,
    values: &mut Vec<AtomicU32>,
    counts: &mut Vec<u32>,
) {
    let chunk = chunk_len(n).max(n.div_ceil(SORT_CHUNKS)).max(1);
    let chunks = n.div_ceil(chunk);
    counts.clear();
    counts.resize(chunks * keys, 0);
    counts.par_chunks_mut(keys.max(1)).enumerate().for_each(|(c, h)| {
        for i in c * chunk..n.min((c + 1) * chunk) {
            for (key, _) in emit(i) {
                if key != u32::MAX {
                    h[key as usize] += 1;
                }
            }
        }
    });
    start.clear();
    start.resize(keys + 1, 0);
    let mut at = 0u32;
    for k in 0..keys {
        start[k] = at;
        for c in 0..chunks {
            let count = counts[c * keys + k];
            counts[c * keys + k] = at;
            at += count;
        }
    }
    start[keys] = at;
    values.resize_with(at as usize, || AtomicU32::new(0));
    let values = &values[..];
    counts.par_chunks_mut(keys.max(1)).enumerate().for_each(|(c, next)| {
        for i in c * chunk..n.min((c + 1) * chunk) {
            for (key, value) in emit(i) {
                if key != u32::MAX {
                    let slot = &mut next[key as usize];
                    values[*slot as usize].store(value, Ordering::Relaxed);
                    *slot += 1;
                }
            }
        }
    });
}

/// Σ_{i<n} f(i), bit-identical for every thread count.
pub fn sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let chunk = chunk_len(n);
    let chunk_sum = |c: usize| {
        let mut s = 0.0;
        for i in c * chunk..((c + 1) * chunk).min(n) {
            s += f(i);
        }
        s
    };
    let chunks = map_chunks(n.div_ceil(chunk), &chunk_sum);
    chunks.iter().sum()
}

/// `f(c)` for every chunk `c < chunks`, in parallel, in chunk order. The chunk's work reaches
/// rayon through one indirect call per chunk (never per item), so rayon's machinery is compiled
/// once per result type instead of once per loop and per solver type: the loops over chunks of
/// every model and shape function share it (compile time, not run time, is what this saves).
pub(crate) fn map_chunks<T: Send>(chunks: usize, f: &(dyn Fn(usize) -> T + Sync)) -> Vec<T> {
    (0..chunks).into_par_iter().map(f).collect()
}

/// `f(c)` for every chunk `c < chunks`, in parallel, merged by `merge` (associative, with
/// `identity` its neutral element); as [`map_chunks`], one copy of rayon's machinery per `T`.
pub(crate) fn reduce_chunks<T: Send + Copy + Sync>(
    chunks: usize,
    identity: T,
    f: &(dyn Fn(usize) -> T + Sync),
    merge: fn(T, T) -> T,
) -> T {
    (0..chunks).into_par_iter().map(f).reduce(|| identity, merge)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_scenes_use_fewer_threads() {
        assert_eq!(useful_threads(336, 2), 1);
        assert_eq!(useful_threads(0, 8), 1);
        assert_eq!(useful_threads(2 * PARTICLES_PER_THREAD, 2), 2);
        assert_eq!(useful_threads(1_000_000, 2), 2);
        assert_eq!(useful_threads(1_000_000, 0), 1);
    }

    #[test]
    fn sum_is_identical_for_one_and_two_threads() {
        for n in [10 * CHUNK + 17, 300] {
            sum_is_identical_for(n);
        }
    }

    /// `counting_sort` against the plain serial bucketing it must equal: empty input, a
    /// single item, a single key, items that emit nothing (`u32::MAX`), and enough items for
    /// all 16 chunks, each on 1 and 2 threads.
    #[test]
    fn counting_sort_is_the_stable_bucketing_for_any_thread_count() {
        for (n, keys) in [(0, 5), (1, 1), (1, 7), (300, 1), (300, 13), (50_000, 97)] {
            // two pairs per item: key (i·31 mod keys) and, for every third item, nothing
            let emit = |i: usize| {
                let skip = if i % 3 == 0 { u32::MAX } else { (i % keys) as u32 };
                [((i * 31 % keys) as u32, 2 * i as u32), (skip, 2 * i as u32 + 1)]
            };
            let mut expected = vec![Vec::new(); keys];
            for i in 0..n {
                for (key, value) in emit(i) {
                    if key != u32::MAX {
                        expected[key as usize].push(value);
                    }
                }
            }
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let (mut start, mut values, mut counts) = (Vec::new(), Vec::new(), Vec::new());
                pool.install(|| counting_sort(n, keys, emit, &mut start, &mut values, &mut counts));
                assert_eq!(start.len(), keys + 1);
                for (k, want) in expected.iter().enumerate() {
                    let got: Vec<u32> = values[start[k] as usize..start[k + 1] as usize]
                        .iter()
                        .map(|v| v.load(Ordering::Relaxed))
                        .collect();
                    assert_eq!(&got, want, "n {n}, keys {keys}, key {k}, {threads} threads");
                }
            }
        }
    }

    fn sum_is_identical_for(n: usize) {
        let f = |i: usize| ((i as f64) * 0.37).sin() * 1e3 + 1e-7 * i as f64;
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let a = one.install(|| sum(n, f));
        let b = two.install(|| sum(n, f));
        assert_eq!(a.to_bits(), b.to_bits());
        // And it is the sum (to rounding of ~n terms of size 1e3).
        let naive: f64 = (0..n).map(f).sum();
        assert!((a - naive).abs() < 1e-9 * n as f64 * 1e3);
    }
}
