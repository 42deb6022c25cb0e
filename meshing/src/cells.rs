//! A tet mesh under local edits: the cells, one tag per cell (a region, or
//! nothing), alive flags and each vertex's live cells (its *star*). Shared by
//! the edits that replace a few tets at a time: edge removal and star
//! insertion (`conforming/flip.rs`, `conforming/star.rs`), which kill cells and
//! add new ones, and longest-edge bisection (`envelope/fit.rs`,
//! `envelope/graded.rs`), which splits the cells around an edge in place.
//!
//! A killed cell keeps its slot, flagged dead, until [`CellStore::into_live`]
//! drops it, so cell indices stay valid during an edit. A star lists its
//! cells in the order the edits made them (a kill removes the cell, an add or
//! a split appends); the users' searches follow that order, so their results
//! depend on the edits alone, not on hashing or threads.

use std::collections::VecDeque;
use std::ops::Range;

/// The cells of a tet mesh under local edits (module docs). `R`: the tag each
/// cell carries (a region, `u16`, or `()` where there is none).
#[derive(Debug, Clone)]
pub(crate) struct CellStore<R: Copy = u16> {
    /// Corners of every cell made so far, dead ones included.
    pub cells: Vec<[u32; 4]>,
    /// Each cell's tag (same length as `cells`).
    pub regions: Vec<R>,
    /// Whether each cell is still in the mesh.
    pub alive: Vec<bool>,
    /// Each vertex's live cells, in the order they were made.
    pub star: Vec<Vec<u32>>,
}

impl<R: Copy> CellStore<R> {
    /// The store of `cells` (all alive; tags `regions`, same length) on
    /// `num_nodes` vertices.
    pub fn new(num_nodes: usize, cells: Vec<[u32; 4]>, regions: Vec<R>) -> Self {
        assert_eq!(cells.len(), regions.len(), "one tag per cell");
        let mut star = vec![Vec::new(); num_nodes];
        for (k, c) in cells.iter().enumerate() {
            for &v in c {
                star[v as usize].push(k as u32);
            }
        }
        let alive = vec![true; cells.len()];
        CellStore { cells, regions, alive, star }
    }

    /// A new vertex (no cells yet); its index.
    pub fn add_node(&mut self) -> u32 {
        self.star.push(Vec::new());
        self.star.len() as u32 - 1
    }

    /// The live cells with corners `a` and `b`, in `a`'s star order.
    pub fn around(&self, a: u32, b: u32) -> impl Iterator<Item = u32> + '_ {
        self.star[a as usize].iter().copied().filter(move |&k| self.cells[k as usize].contains(&b))
    }

    /// Takes cell `k` out of the mesh (its slot stays, dead).
    pub fn kill(&mut self, k: u32) {
        self.alive[k as usize] = false;
        for v in self.cells[k as usize] {
            self.star[v as usize].retain(|&j| j != k);
        }
    }

    /// A new live cell `t` tagged `region`; its index.
    pub fn add(&mut self, t: [u32; 4], region: R) -> u32 {
        let k = self.cells.len() as u32;
        self.cells.push(t);
        self.regions.push(region);
        self.alive.push(true);
        for v in t {
            self.star[v as usize].push(k);
        }
        k
    }

    /// Splits the edge `ab` at the vertex `m` (already added, on no cell yet)
    /// in each cell of `around` (the cells with corners `a` and `b`): cell `k`
    /// keeps its slot with `m` for `a`, and a new cell with `m` for `b` (same
    /// tag) is appended. The new cells' indices, in `around`'s order.
    pub fn bisect(&mut self, a: u32, b: u32, m: u32, around: &[u32]) -> Range<u32> {
        let first = self.cells.len() as u32;
        for &k in around {
            let c = self.cells[k as usize];
            let new = self.cells.len() as u32;
            self.cells[k as usize] = c.map(|v| if v == a { m } else { v });
            self.cells.push(c.map(|v| if v == b { m } else { v }));
            self.regions.push(self.regions[k as usize]);
            self.alive.push(true);
            // Cell k now holds m instead of a; the new cell holds a, m and the other two.
            self.star[a as usize].retain(|&x| x != k);
            self.star[a as usize].push(new);
            self.star[m as usize].push(k);
            self.star[m as usize].push(new);
            for &v in &c {
                if v != a && v != b {
                    self.star[v as usize].push(new);
                }
            }
        }
        first..self.cells.len() as u32
    }

    /// The live cells whose `quality` is under `bound`: those for which
    /// `first` holds first, then by increasing quality, then by index (the
    /// visiting order of edge removal and star insertion).
    pub fn bad_queue(
        &self,
        quality: impl Fn([u32; 4]) -> f64,
        first: impl Fn(u32) -> bool,
        bound: f64,
    ) -> VecDeque<u32> {
        let mut bad: Vec<(bool, f64, u32)> = (0..self.cells.len() as u32)
            .filter(|&k| self.alive[k as usize])
            .map(|k| (k, quality(self.cells[k as usize])))
            .filter(|&(_, q)| q < bound)
            .map(|(k, q)| (!first(k), q, k))
            .collect();
        bad.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        bad.into_iter().map(|(_, _, k)| k).collect()
    }

    /// The live cells and their tags, in slot order.
    pub fn into_live(self) -> (Vec<[u32; 4]>, Vec<R>) {
        let CellStore { cells, regions, alive, .. } = self;
        let live = |k: &usize| alive[*k];
        let kept_cells = (0..cells.len()).filter(live).map(|k| cells[k]).collect();
        let kept_regions = (0..regions.len()).filter(live).map(|k| regions[k]).collect();
        (kept_cells, kept_regions)
    }
}

/// A local edit that improves bad cells a few at a time (edge removal, star
/// insertion): what [`improve_in_rounds`] needs of it.
pub(crate) trait LocalEdit {
    /// What the edit counts (its refusals and sizes).
    type Stats;
    /// The cells under edit.
    fn store(&self) -> &CellStore;
    /// The quality of a cell with corners `cell` (bad: under the bound).
    fn quality(&self, cell: [u32; 4]) -> f64;
    /// Whether the live cell `k` is a cap (two or more boundary faces): caps
    /// are visited first.
    fn cap(&self, k: u32) -> bool;
    /// Tries to replace the bad live cell `k` and the cells around it by
    /// better ones, counting in `stats`; the new cells when it did.
    fn improve(&mut self, k: u32, bound: f64, stats: &mut Self::Stats) -> Option<Vec<u32>>;

    /// The number of live caps of quality under `bound`.
    fn bad_caps(&self, bound: f64) -> usize {
        let s = self.store();
        (0..s.cells.len() as u32)
            .filter(|&k| s.alive[k as usize] && self.quality(s.cells[k as usize]) < bound && self.cap(k))
            .count()
    }
}

/// Runs `edit` over the cells of quality under `bound`, in rounds of at most
/// `max_rounds`: each round visits them in [`CellStore::bad_queue`]'s order,
/// skipping those gone or no longer bad, and queues the bad cells each edit
/// makes behind them; the rounds stop after one that made no edit. The
/// rounds run and the edits made.
pub(crate) fn improve_in_rounds<E: LocalEdit>(
    edit: &mut E,
    stats: &mut E::Stats,
    max_rounds: usize,
    bound: f64,
) -> (usize, usize) {
    let (mut rounds, mut edits) = (0, 0);
    for _ in 0..max_rounds {
        rounds += 1;
        let mut queue = edit.store().bad_queue(|c| edit.quality(c), |k| edit.cap(k), bound);
        let mut made = 0;
        while let Some(k) = queue.pop_front() {
            let s = edit.store();
            if !s.alive[k as usize] || edit.quality(s.cells[k as usize]) >= bound {
                continue;
            }
            let Some(new) = edit.improve(k, bound, stats) else { continue };
            made += 1;
            for j in new {
                if edit.quality(edit.store().cells[j as usize]) < bound {
                    queue.push_back(j);
                }
            }
        }
        edits += made;
        if made == 0 {
            break;
        }
    }
    (rounds, edits)
}

/// The faces (sorted corners) of `cells`, four a cell, in cell order.
#[cfg(test)]
pub(crate) fn sorted_faces(cells: &[[u32; 4]]) -> Vec<[u32; 3]> {
    cells
        .iter()
        .flat_map(|t| {
            crate::conforming::FACE.map(|f| {
                let mut k = f.map(|j| t[j]);
                k.sort_unstable();
                k
            })
        })
        .collect()
}

/// The faces (sorted corners) of exactly one of `cells`, sorted.
#[cfg(test)]
pub(crate) fn outer_faces(cells: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let mut faces = sorted_faces(cells);
    faces.sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let j = (i..faces.len()).find(|&j| faces[j] != faces[i]).unwrap_or(faces.len());
        if j - i == 1 {
            out.push(faces[i]);
        }
        i = j;
    }
    out
}

/// `t` in positively oriented order (exact); panics on a flat tet (tests only).
#[cfg(test)]
pub(crate) fn positive(nodes: &[crate::predicates::Point], t: [u32; 4]) -> [u32; 4] {
    let q = t.map(|v| nodes[v as usize]);
    match crate::predicates::orient3d(q[0], q[1], q[2], q[3]) {
        1 => t,
        -1 => [t[1], t[0], t[2], t[3]],
        _ => panic!("flat tet {t:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tets on the edge 0-1: bisecting it at a new vertex 5 gives four
    /// cells, each old slot keeping its tag, the new ones taking it; the
    /// stars list exactly the live cells of each vertex; a kill empties the
    /// stars of the cell and `into_live` drops it.
    #[test]
    fn bisect_kill_and_stars_stay_consistent() {
        let mut s = CellStore::new(5, vec![[0, 1, 2, 3], [1, 0, 2, 4]], vec![7u16, 9]);
        let around: Vec<u32> = s.around(0, 1).collect();
        assert_eq!(around, [0, 1]);
        let m = s.add_node();
        assert_eq!(m, 5);
        assert_eq!(s.bisect(0, 1, m, &around), 2..4);
        assert_eq!(s.cells, [[5, 1, 2, 3], [1, 5, 2, 4], [0, 5, 2, 3], [5, 0, 2, 4]]);
        assert_eq!(s.regions, [7, 9, 7, 9]);
        let check = |s: &CellStore| {
            for (v, star) in s.star.iter().enumerate() {
                let mut want: Vec<u32> = (0..s.cells.len() as u32)
                    .filter(|&k| s.alive[k as usize] && s.cells[k as usize].contains(&(v as u32)))
                    .collect();
                let mut got = star.clone();
                want.sort_unstable();
                got.sort_unstable();
                assert_eq!(got, want, "vertex {v}");
            }
        };
        check(&s);
        assert_eq!(s.around(0, 1).count(), 0);
        s.kill(1);
        check(&s);
        let k = s.add([5, 1, 4, 3], 3);
        assert_eq!(k, 4);
        check(&s);
        let (cells, regions) = s.into_live();
        assert_eq!(cells, [[5, 1, 2, 3], [0, 5, 2, 3], [5, 0, 2, 4], [5, 1, 4, 3]]);
        assert_eq!(regions, [7, 7, 9, 3]);
    }

    /// The queue: the cells under the bound, `first` ones first, then by
    /// increasing quality, then by index; dead cells are left out.
    #[test]
    fn bad_queue_order() {
        // Cell k has corner 4 + k, which gives its quality.
        let q = [3.0, 1.0, 20.0, 1.0, 0.5];
        let cells = (0..5).map(|k| [0, 1, 2, 4 + k]).collect();
        let mut s = CellStore::new(9, cells, vec![0u16; 5]);
        s.kill(4);
        let queue = s.bad_queue(|c| q[c[3] as usize - 4], |k| k == 3, 10.0);
        assert_eq!(Vec::from(queue), [3, 1, 0]);
    }
}
