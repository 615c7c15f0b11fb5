//! Deterministic parallel loops.
//!
//! Rayon decides at run time which thread takes which item; a floating-point sum whose order depends
//! on that would differ between runs with 1 and 2 threads. Every reduction here therefore splits the
//! index range into chunks of a fixed size [`CHUNK`] (independent of the thread count), sums each chunk
//! in index order, and adds the chunk sums in chunk order. The result is bit-identical for any number
//! of threads.

use rayon::prelude::*;

/// Items per chunk of a deterministic reduction (large enough to amortise rayon's task cost).
pub const CHUNK: usize = 2048;

/// Σ_{i<n} f(i), bit-identical for every thread count.
pub fn sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let chunks: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut s = 0.0;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                s += f(i);
            }
            s
        })
        .collect();
    chunks.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sum_is_identical_for_one_and_two_threads() {
        let n = 10 * CHUNK + 17;
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
