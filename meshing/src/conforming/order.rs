//! Insertion order: biased randomized insertion order (BRIO, Amenta, Choi and
//! Rote 2003) with each round sorted along a Hilbert curve.
//!
//! A random order keeps the expected work of incremental Delaunay optimal; the
//! rounds (each the next doubling of the points inserted so far) sorted along a
//! space-filling curve keep consecutive points close, so the walking point
//! location from the previous insertion takes a few steps. The shuffle uses a
//! fixed-seed generator: the order, hence the work, is the same on every run.

use crate::predicates::Point;

/// A SplitMix64 generator (fixed seed: deterministic runs).
#[derive(Debug, Clone)]
pub(crate) struct SplitMix(pub u64);

impl SplitMix {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (n > 0; the small modulo bias does not matter here).
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// The indices `0..points.len()` in BRIO order, each round sorted along a Hilbert curve.
pub(crate) fn brio_hilbert(points: &[Point]) -> Vec<u32> {
    let n = points.len();
    let mut idx: Vec<u32> = (0..n as u32).collect();
    let mut rng = SplitMix(0x5EED_0FDE_1A0A_11CE);
    for i in (1..n).rev() {
        let j = rng.below(i + 1);
        idx.swap(i, j);
    }
    if n == 0 {
        return idx;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let span = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let scale = if span > 0.0 { ((1u64 << BITS) - 1) as f64 / span } else { 0.0 };
    let key = |i: u32| {
        let p = points[i as usize];
        let q = [0, 1, 2].map(|k| (((p[k] - lo[k]) * scale) as u64).min((1 << BITS) - 1) as u32);
        hilbert_index(q)
    };
    // Rounds: [0, n/2^k), ..., [n/4, n/2), [n/2, n); the first at least 64 points.
    let mut bounds = vec![n];
    let mut m = n;
    while m > 64 {
        m /= 2;
        bounds.push(m);
    }
    bounds.push(0);
    bounds.reverse();
    for w in bounds.windows(2) {
        let round = &mut idx[w[0]..w[1]];
        round.sort_by_cached_key(|&i| (key(i), i));
    }
    idx
}

const BITS: u32 = 16;

/// The position of the grid point `x` (coordinates below `2^BITS`) along the 3D
/// Hilbert curve (Skilling's transpose algorithm, "Programming the Hilbert
/// curve", 2004).
fn hilbert_index(mut x: [u32; 3]) -> u64 {
    let m = 1u32 << (BITS - 1);
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    for i in 1..3 {
        x[i] ^= x[i - 1];
    }
    let mut t = 0;
    let mut q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in &mut x {
        *v ^= t;
    }
    let mut h = 0u64;
    for b in (0..BITS).rev() {
        for v in &x {
            h = (h << 1) | ((v >> b) & 1) as u64;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hilbert_curve_visits_neighbours_in_turn() {
        // On a 2^BITS grid, consecutive indices along the curve are grid neighbours:
        // check on the first 4096 cells of an 16^3 block.
        let mut cells: Vec<([u32; 3], u64)> = Vec::new();
        let s = 1u32 << (BITS - 4);
        for i in 0..16 {
            for j in 0..16 {
                for k in 0..16 {
                    let x = [i * s, j * s, k * s];
                    cells.push((x, hilbert_index(x)));
                }
            }
        }
        cells.sort_by_key(|c| c.1);
        for w in cells.windows(2) {
            let d: u32 = (0..3).map(|k| w[0].0[k].abs_diff(w[1].0[k])).sum();
            assert_eq!(d, s, "{:?} -> {:?}", w[0].0, w[1].0);
        }
    }

    #[test]
    fn the_order_is_a_permutation() {
        let mut rng = SplitMix(1);
        let pts: Vec<Point> = (0..1000).map(|_| [0, 1, 2].map(|_| (rng.next_u64() % 1000) as f64)).collect();
        let mut o = brio_hilbert(&pts);
        o.sort_unstable();
        assert_eq!(o, (0..1000).collect::<Vec<u32>>());
    }
}
