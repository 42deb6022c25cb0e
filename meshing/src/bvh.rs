//! A bounding-volume hierarchy of axis-aligned boxes, for finding the pairs of
//! triangles whose boxes overlap (candidates for the exact intersection tests).
//!
//! Built top-down by median splits of the box centres along the widest axis, with
//! up to [`LEAF_SIZE`] boxes per leaf; queries are closed (touching boxes
//! overlap). The build and every query are deterministic.
//!
//! # Example
//!
//! ```
//! use meshing::bvh::{Aabb, Bvh};
//!
//! let boxes: Vec<Aabb> = (0..10)
//!     .map(|i| Aabb { lo: [i as f64, 0.0, 0.0], hi: [i as f64 + 1.0, 1.0, 1.0] })
//!     .collect();
//! let bvh = Bvh::new(&boxes);
//! let mut hits = Vec::new();
//! bvh.for_each_overlap(&Aabb { lo: [2.5, 0.5, 0.5], hi: [3.5, 0.5, 0.5] }, |i| hits.push(i));
//! hits.sort();
//! assert_eq!(hits, vec![2, 3]);
//! ```

/// Boxes per leaf at most.
pub const LEAF_SIZE: usize = 4;

/// A closed axis-aligned box [mm].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner [mm].
    pub lo: [f64; 3],
    /// Upper corner [mm].
    pub hi: [f64; 3],
}

impl Aabb {
    /// The empty box (contains nothing; the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb { lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] };

    /// The smallest box holding `points`.
    pub fn of_points(points: &[[f64; 3]]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, p| b.union(&Aabb { lo: *p, hi: *p }))
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            lo: std::array::from_fn(|k| self.lo[k].min(other.lo[k])),
            hi: std::array::from_fn(|k| self.hi[k].max(other.hi[k])),
        }
    }

    /// Whether the two closed boxes share a point.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        (0..3).all(|k| self.lo[k] <= other.hi[k] && other.lo[k] <= self.hi[k])
    }

    fn centre(&self, axis: usize) -> f64 {
        0.5 * (self.lo[axis] + self.hi[axis])
    }
}

#[derive(Debug, Clone)]
struct Node {
    bounds: Aabb,
    /// Leaf: `order[first..first + count]`; inner node: `count == 0`, children at
    /// `first` and `first + 1`.
    first: u32,
    count: u32,
}

/// A bounding-volume hierarchy over a list of boxes, answering "which boxes
/// overlap this one" by the boxes' indices in the list given to [`Bvh::new`].
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    boxes: Vec<Aabb>,
}

impl Bvh {
    /// Builds the hierarchy over `boxes` (indices must fit in `u32`).
    pub fn new(boxes: &[Aabb]) -> Bvh {
        assert!(boxes.len() < u32::MAX as usize, "Bvh::new: too many boxes");
        let mut bvh = Bvh { nodes: Vec::new(), order: (0..boxes.len() as u32).collect(), boxes: boxes.to_vec() };
        if !boxes.is_empty() {
            bvh.nodes.push(Node { bounds: Aabb::EMPTY, first: 0, count: 0 });
            bvh.build(0, 0, boxes.len());
        }
        bvh
    }

    fn build(&mut self, node: usize, start: usize, end: usize) {
        let bounds = self.order[start..end].iter().fold(Aabb::EMPTY, |b, &i| b.union(&self.boxes[i as usize]));
        self.nodes[node].bounds = bounds;
        if end - start <= LEAF_SIZE {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = (end - start) as u32;
            return;
        }
        // Split at the median centre along the widest axis of the centres.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &i in &self.order[start..end] {
            for k in 0..3 {
                let c = self.boxes[i as usize].centre(k);
                lo[k] = lo[k].min(c);
                hi[k] = hi[k].max(c);
            }
        }
        let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
        let mid = start + (end - start) / 2;
        let boxes = &self.boxes;
        self.order[start..end].select_nth_unstable_by(mid - start, |&i, &j| {
            boxes[i as usize].centre(axis).total_cmp(&boxes[j as usize].centre(axis)).then(i.cmp(&j))
        });
        let left = self.nodes.len();
        self.nodes.push(Node { bounds: Aabb::EMPTY, first: 0, count: 0 });
        self.nodes.push(Node { bounds: Aabb::EMPTY, first: 0, count: 0 });
        self.nodes[node].first = left as u32;
        self.nodes[node].count = 0;
        self.build(left, start, mid);
        self.build(left + 1, mid, end);
    }

    /// Calls `visit(i)` for every box `i` overlapping `query` (closed boxes), in an
    /// order that depends only on the boxes.
    pub fn for_each_overlap(&self, query: &Aabb, mut visit: impl FnMut(usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if !node.bounds.overlaps(query) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.first as usize + 1);
                stack.push(node.first as usize);
            } else {
                let first = node.first as usize;
                for &i in &self.order[first..first + node.count as usize] {
                    if self.boxes[i as usize].overlaps(query) {
                        visit(i as usize);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pseudo-random boxes (a fixed linear congruential sequence).
    fn boxes(n: usize) -> Vec<Aabb> {
        let mut state = 12345u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let lo = [next() * 10.0, next() * 10.0, next() * 10.0];
                let size = next();
                Aabb { lo, hi: [lo[0] + size, lo[1] + 2.0 * size * next(), lo[2] + size] }
            })
            .collect()
    }

    #[test]
    fn queries_match_brute_force() {
        let all = boxes(500);
        let bvh = Bvh::new(&all);
        for q in boxes(50) {
            let mut got = Vec::new();
            bvh.for_each_overlap(&q, |i| got.push(i));
            got.sort_unstable();
            let want: Vec<usize> = (0..all.len()).filter(|&i| all[i].overlaps(&q)).collect();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn empty_and_touching() {
        let bvh = Bvh::new(&[]);
        bvh.for_each_overlap(&Aabb { lo: [0.0; 3], hi: [1.0; 3] }, |_| panic!("no boxes"));
        let unit = Aabb { lo: [0.0; 3], hi: [1.0; 3] };
        let bvh = Bvh::new(&[unit]);
        let mut n = 0;
        bvh.for_each_overlap(&Aabb { lo: [1.0, 1.0, 1.0], hi: [2.0; 3] }, |_| n += 1);
        assert_eq!(n, 1, "closed boxes touching at a corner overlap");
    }
}
