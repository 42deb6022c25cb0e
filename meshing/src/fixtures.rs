//! Test fixtures shared by the modules' unit tests.

use crate::predicates::{orient3d, Point};

/// The eight tets of the octahedron with corners at +-1 on the axes (nodes 1
/// to 6) about the interior node 0 at `centre`, each positively oriented
/// (exact `orient3d`). Used by the smoothing tests of both meshing modes.
pub(crate) fn octahedron_star(centre: Point) -> (Vec<Point>, Vec<[u32; 4]>) {
    let nodes: Vec<Point> = vec![
        centre,
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut cells = Vec::new();
    for x in [1u32, 2] {
        for y in [3u32, 4] {
            for z in [5u32, 6] {
                let c = [0, x, y, z];
                let q = c.map(|v| nodes[v as usize]);
                cells.push(if orient3d(q[0], q[1], q[2], q[3]) == 1 { c } else { [0, y, x, z] });
            }
        }
    }
    (nodes, cells)
}
