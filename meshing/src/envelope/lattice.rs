//! The body-centred cubic (BCC) lattice of isosurface stuffing.
//!
//! Spacing `h` [mm]: the **black** vertices are the corners of a grid of cubes of
//! side `h`, the **red** vertices their centres. Coordinates are kept in doubled
//! integer units (black `(2i, 2j, 2k)`, red `(2i+1, 2j+1, 2k+1)`), position =
//! `origin + coords * h / 2`. Edges: **long** ones (length `h`, axis-parallel,
//! black-black or red-red) and **short** ones (length `h √3 / 2`, red-black).
//! Tetrahedra: for each pair of cubes sharing a square face and each of that
//! face's 4 edges `(a, b)`, the tet `(c1, c2, a, b)` of the two centres and the
//! edge: 12 tets per cube, volume `h³ / 12`, each with two (opposite) long edges
//! and four short ones. They tile the box of the red vertices' hull.

/// A box of `n[0] x n[1] x n[2]` cubes of side `h` with corner `origin`.
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    pub origin: [f64; 3],
    pub h: f64,
    pub n: [usize; 3],
}

impl Lattice {
    pub fn num_black(&self) -> usize {
        (self.n[0] + 1) * (self.n[1] + 1) * (self.n[2] + 1)
    }

    pub fn num_red(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    pub fn num_vertices(&self) -> usize {
        self.num_black() + self.num_red()
    }

    pub fn black(&self, i: usize, j: usize, k: usize) -> u32 {
        (i + (self.n[0] + 1) * (j + (self.n[1] + 1) * k)) as u32
    }

    pub fn red(&self, i: usize, j: usize, k: usize) -> u32 {
        (self.num_black() + i + self.n[0] * (j + self.n[1] * k)) as u32
    }

    /// Doubled integer coordinates of vertex `v`.
    pub fn coords(&self, v: u32) -> [i64; 3] {
        let v = v as usize;
        let nb = self.num_black();
        if v < nb {
            let i = v % (self.n[0] + 1);
            let r = v / (self.n[0] + 1);
            let j = r % (self.n[1] + 1);
            let k = r / (self.n[1] + 1);
            [2 * i as i64, 2 * j as i64, 2 * k as i64]
        } else {
            let v = v - nb;
            let i = v % self.n[0];
            let r = v / self.n[0];
            let j = r % self.n[1];
            let k = r / self.n[1];
            [2 * i as i64 + 1, 2 * j as i64 + 1, 2 * k as i64 + 1]
        }
    }

    pub fn is_red(&self, v: u32) -> bool {
        v as usize >= self.num_black()
    }

    pub fn position(&self, v: u32) -> [f64; 3] {
        let c = self.coords(v);
        let s = 0.5 * self.h;
        [self.origin[0] + c[0] as f64 * s, self.origin[1] + c[1] as f64 * s, self.origin[2] + c[2] as f64 * s]
    }

    /// The vertex at doubled coordinates `c`, if it is in the lattice.
    #[cfg(test)]
    pub fn at(&self, c: [i64; 3]) -> Option<u32> {
        let odd = c[0] & 1;
        if c.iter().any(|&x| x & 1 != odd || x < 0) {
            return None;
        }
        if odd == 0 {
            let (i, j, k) = ((c[0] / 2) as usize, (c[1] / 2) as usize, (c[2] / 2) as usize);
            (i <= self.n[0] && j <= self.n[1] && k <= self.n[2]).then(|| self.black(i, j, k))
        } else {
            let (i, j, k) = ((c[0] / 2) as usize, (c[1] / 2) as usize, (c[2] / 2) as usize);
            (i < self.n[0] && j < self.n[1] && k < self.n[2]).then(|| self.red(i, j, k))
        }
    }

    /// Whether edge `(a, b)` is long (axis-parallel) rather than short (diagonal).
    pub fn is_long(&self, a: u32, b: u32) -> bool {
        self.is_red(a) == self.is_red(b)
    }

    /// The tetrahedra, in a fixed order: for each axis `d`, each cube with a
    /// neighbour across its `+d` face, the 4 edges of that face.
    pub fn tets(&self) -> Vec<[u32; 4]> {
        let [nx, ny, nz] = self.n;
        let mut out = Vec::with_capacity(12 * nx * ny * nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    for d in 0..3 {
                        if c[d] + 1 >= self.n[d] {
                            continue;
                        }
                        let mut c2 = c;
                        c2[d] += 1;
                        let r1 = self.red(c[0], c[1], c[2]);
                        let r2 = self.red(c2[0], c2[1], c2[2]);
                        let (d1, d2) = ((d + 1) % 3, (d + 2) % 3);
                        // Face corners: coordinate c[d] + 1 along d, c[d1] + {0, 1}, c[d2] + {0, 1}.
                        let corner = |u: usize, w: usize| {
                            let mut p = [0usize; 3];
                            p[d] = c[d] + 1;
                            p[d1] = c[d1] + u;
                            p[d2] = c[d2] + w;
                            self.black(p[0], p[1], p[2])
                        };
                        let (v00, v10, v11, v01) = (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1));
                        for (a, b) in [(v00, v10), (v10, v11), (v11, v01), (v01, v00)] {
                            out.push([r1, r2, a, b]);
                        }
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn volume(p: [[f64; 3]; 4]) -> f64 {
        let d = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let (u, v, w) = (d(p[1], p[0]), d(p[2], p[0]), d(p[3], p[0]));
        (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]))
            / 6.0
    }

    #[test]
    fn tets_tile_the_hull_of_the_centres_with_two_long_edges_each() {
        let l = Lattice { origin: [0.5, -1.0, 2.0], h: 0.5, n: [3, 4, 2] };
        let tets = l.tets();
        // 4 tets per square face between two cubes.
        let inner_faces = 2 * 4 * 2 + 3 * 3 * 2 + 3 * 4;
        assert_eq!(tets.len(), 4 * inner_faces);
        // Conforming: every triangle in at most two tets.
        let mut faces = std::collections::BTreeMap::<[u32; 3], usize>::new();
        for t in &tets {
            for i in 0..4 {
                let mut f = [t[(i + 1) % 4], t[(i + 2) % 4], t[(i + 3) % 4]];
                f.sort_unstable();
                *faces.entry(f).or_default() += 1;
            }
        }
        assert!(faces.values().all(|&n| n <= 2));
        for t in &tets {
            let v = volume(t.map(|x| l.position(x))).abs();
            assert!((v - 0.125 / 12.0).abs() < 1e-12);
            let mut long = 0;
            for a in 0..4 {
                for b in a + 1..4 {
                    if l.is_long(t[a], t[b]) {
                        long += 1;
                    }
                }
            }
            assert_eq!(long, 2);
        }
        for v in 0..l.num_vertices() as u32 {
            assert_eq!(l.at(l.coords(v)), Some(v));
        }
    }
}
