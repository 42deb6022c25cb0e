//! `shape.svg`: the specimen's outline at the start, at the keep time and at the
//! end, to scale in mm, for a user without ParaView.
//!
//! - Triangles (plane stress or strain): the mesh's boundary edges, deformed.
//! - Axisymmetric triangles: the `r-y` section's boundary and its mirror image
//!   (`-r`), the axis itself left out: the cylinder's cut through its axis.
//! - Tetrahedra: the section through the middle of the specimen's depth
//!   (`z` halfway between its least and greatest `z` at rest). The cut is made
//!   in the reference configuration: each tetrahedron crossing the plane gives
//!   the points where its edges cross it, the faces crossing it a segment each,
//!   and the segments of the faces on the body's boundary (those of one
//!   tetrahedron only) form the outline. It follows the material, so the
//!   deformed outline is that of the same particles at every time, drawn in
//!   `x-y` (the view along `z`).

use std::collections::HashMap;

use anyhow::anyhow;
use fem_core::mesh::{TetMesh, TriMesh};
use fem_core::press::{AnyPress, Snapshot};
use plotters::prelude::*;

/// A point of the outline: a node, or the point a fraction `t` of the way
/// along the edge from node `a` to node `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Point {
    Node(u32),
    OnEdge(u32, u32, f64),
}

/// An outline: segments between points, and how to place them.
#[derive(Debug)]
pub struct Outline {
    segments: Vec<[Point; 2]>,
    /// Also draw each segment mirrored in `x` (the axisymmetric section).
    mirrored: bool,
    /// What the drawing shows (the section for a 3D body).
    what: String,
}

impl Outline {
    /// The outline of `problem`'s body (module docs).
    pub fn of(problem: &AnyPress) -> Self {
        match problem {
            AnyPress::Plane(p) => {
                Self { segments: boundary_edges(&p.mesh, None), mirrored: false, what: "outline".into() }
            }
            AnyPress::Axisymmetric(p) => Self {
                segments: boundary_edges(&p.mesh, Some(1e-9 * extent(&p.mesh.nodes))),
                mirrored: true,
                what: "section through the axis".into(),
            },
            AnyPress::Solid(p) => {
                let (z0, segments) = mid_section(&p.mesh);
                Self { segments, mirrored: false, what: format!("section z = {z0:.3} mm") }
            }
        }
    }

    /// The segments' end points `[x, y]` [mm] with the nodal displacements
    /// `displacement` (`dim` per node) added to the nodes `nodes` (`dim` each).
    fn placed(&self, nodes: &[f64], displacement: &[f64], dim: usize) -> Vec<[[f64; 2]; 2]> {
        let at = |n: u32| {
            let i = n as usize * dim;
            [nodes[i] + displacement[i], nodes[i + 1] + displacement[i + 1]]
        };
        let place = |p: Point| match p {
            Point::Node(n) => at(n),
            Point::OnEdge(a, b, t) => {
                let (pa, pb) = (at(a), at(b));
                [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
            }
        };
        let mut out: Vec<[[f64; 2]; 2]> = self.segments.iter().map(|s| [place(s[0]), place(s[1])]).collect();
        if self.mirrored {
            let mirror: Vec<[[f64; 2]; 2]> = out.iter().map(|s| [[-s[0][0], s[0][1]], [-s[1][0], s[1][1]]]).collect();
            out.extend(mirror);
        }
        out
    }

    /// The total length of the outline at rest [mm] (its mirror included).
    #[cfg(test)]
    fn length_at_rest(&self, nodes: &[f64], dim: usize) -> f64 {
        let zero = vec![0.0; nodes.len()];
        self.placed(nodes, &zero, dim).iter().map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1])).sum()
    }
}

/// The largest coordinate magnitude of a set of nodes (a length scale).
fn extent<const D: usize>(nodes: &[[f64; D]]) -> f64 {
    nodes.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The edges of one triangle only; with `axis`, those with both nodes within
/// `axis` of `x = 0` are left out.
fn boundary_edges(mesh: &TriMesh, axis: Option<f64>) -> Vec<[Point; 2]> {
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for c in &mesh.cells {
        for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])] {
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let on_axis = |n: u32| axis.is_some_and(|tol| mesh.nodes[n as usize][0].abs() <= tol);
    let mut edges: Vec<(u32, u32)> =
        count.into_iter().filter(|&((a, b), k)| k == 1 && !(on_axis(a) && on_axis(b))).map(|(e, _)| e).collect();
    edges.sort_unstable();
    edges.into_iter().map(|(a, b)| [Point::Node(a), Point::Node(b)]).collect()
}

/// A section segment by the two edges (node pairs) its ends lie on.
type SegmentKey = ((u32, u32), (u32, u32));

/// The plane `z = z0` through the middle of the body's depth (nudged off any
/// node by a millionth of the depth) and the outline of the body's section by
/// it (module docs).
fn mid_section(mesh: &TetMesh) -> (f64, Vec<[Point; 2]>) {
    let (lo, hi) =
        mesh.nodes.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[2]), hi.max(p[2])));
    let mut z0 = 0.5 * (lo + hi) + 1e-6 * (hi - lo);
    if mesh.nodes.iter().any(|p| p[2] == z0) {
        z0 += 1e-6 * (hi - lo);
    }
    let d = |n: u32| mesh.nodes[n as usize][2] - z0;
    let crossing = |a: u32, b: u32| -> Option<Point> {
        let (da, db) = (d(a), d(b));
        ((da < 0.0) != (db < 0.0)).then(|| {
            // Oriented from the lower node index, so both cells sharing a face
            // compute the same point bit for bit.
            let (a, b, da, db) = if a < b { (a, b, da, db) } else { (b, a, db, da) };
            Point::OnEdge(a, b, da / (da - db))
        })
    };
    let key = |p: &Point| match *p {
        Point::OnEdge(a, b, _) => (a, b),
        Point::Node(n) => (n, n),
    };
    let mut count: HashMap<SegmentKey, ([Point; 2], usize)> = HashMap::new();
    for c in &mesh.cells {
        for face in [[c[1], c[2], c[3]], [c[0], c[2], c[3]], [c[0], c[1], c[3]], [c[0], c[1], c[2]]] {
            let points: Vec<Point> = [(face[0], face[1]), (face[1], face[2]), (face[2], face[0])]
                .into_iter()
                .filter_map(|(a, b)| crossing(a, b))
                .collect();
            if let [p, q] = points[..] {
                let (kp, kq) = (key(&p), key(&q));
                let k = if kp < kq { (kp, kq) } else { (kq, kp) };
                count.entry(k).or_insert(([p, q], 0)).1 += 1;
            }
        }
    }
    let mut outline: Vec<(SegmentKey, [Point; 2])> =
        count.into_iter().filter(|(_, (_, k))| *k == 1).map(|(key, (s, _))| (key, s)).collect();
    outline.sort_unstable_by_key(|(key, _)| *key);
    (z0, outline.into_iter().map(|(_, s)| s).collect())
}

/// The drawing's width [px]; its height follows the shapes' aspect.
const WIDTH: u32 = 900;
/// Margin, caption and label areas [px].
const MARGIN: u32 = 16;
const CAPTION: u32 = 40;
const X_LABELS: u32 = 48;
const Y_LABELS: u32 = 64;
/// The legend's height and more [px].
const LEGEND_PX: f64 = 80.0;

/// The SVG text of `shape.svg`: `outline` at each `(label, snapshot)`, in
/// `x-y` [mm] to scale, titled `title`.
pub fn shape_svg(
    title: &str,
    problem: &AnyPress,
    outline: &Outline,
    shapes: &[(&str, &Snapshot)],
) -> anyhow::Result<String> {
    let (nodes, dim): (Vec<f64>, usize) = match problem {
        AnyPress::Plane(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 2),
        AnyPress::Axisymmetric(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 2),
        AnyPress::Solid(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 3),
    };
    let placed: Vec<Vec<[[f64; 2]; 2]>> =
        shapes.iter().map(|(_, s)| outline.placed(&nodes, &s.displacement, dim)).collect();
    let points = placed.iter().flatten().flatten();
    let (x0, x1, y0, y1) = points.fold((f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY), |b, p| {
        (b.0.min(p[0]), b.1.max(p[0]), b.2.min(p[1]), b.3.max(p[1]))
    });
    if !(x1 > x0 && y1 > y0) {
        return Err(anyhow!("shape.svg: the outline has no extent"));
    }
    let pad = 0.05 * (x1 - x0).max(y1 - y0);
    let inner_w = WIDTH - 2 * MARGIN - Y_LABELS;
    // Room above the shapes for the legend (its height in mm at the drawing's scale).
    let legend_mm = LEGEND_PX * (x1 - x0 + 2.0 * pad) / inner_w as f64;
    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad + legend_mm);
    // The plot area's pixels per mm alike in x and y: its height follows its width.
    let inner_h = ((inner_w as f64) * (y1 - y0) / (x1 - x0)).round().clamp(120.0, 2400.0) as u32;
    let height = inner_h + 2 * MARGIN + CAPTION + X_LABELS;
    let colours = [RGBColor(128, 128, 128), RGBColor(31, 119, 180), RGBColor(214, 39, 40)];
    let draw_err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow!("drawing shape.svg: {e}");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{title}: {}", outline.what), ("sans-serif", 20))
            .margin(MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("x [mm]")
            .y_desc("y [mm]")
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(BLACK.mix(0.0))
            .draw()
            .map_err(draw_err)?;
        for (i, ((label, _), segments)) in shapes.iter().zip(&placed).enumerate() {
            let colour = colours[i % colours.len()];
            let width = if i == 0 { 1 } else { 2 };
            chart
                .draw_series(segments.iter().map(|s| {
                    PathElement::new(vec![(s[0][0], s[0][1]), (s[1][0], s[1][1])], colour.stroke_width(width))
                }))
                .map_err(draw_err)?
                .label(*label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2)));
        }
        crate::plot::legend_and_present(&mut chart, &root).map_err(draw_err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fem_core::material::Material;
    use fem_core::mesh;
    use fem_core::press::{AxisymmetricPress, PlanePress, Protocol, SolidPress};

    fn protocol() -> Protocol {
        Protocol::ramp_hold_release(0.1, 1.0, 2.0, 3.0)
    }

    /// At rest the outlines are the shapes' perimeters: a rectangle's, a block's
    /// mid-depth section (its front face's), and a cylinder's section through
    /// the axis (two heights and two diameters).
    #[test]
    fn outlines_at_rest_are_the_perimeters() {
        let m = Material::seed_mat1_force();
        let plane = AnyPress::Plane(
            PlanePress::new_2d(mesh::rectangle(20.0, 10.0, 2.5, "m").unwrap(), 5.0, vec![m.clone()], protocol())
                .unwrap(),
        );
        let solid = AnyPress::Solid(
            SolidPress::new_3d(mesh::block([20.0, 10.0, 6.0], 2.0, "m").unwrap(), vec![m.clone()], protocol()).unwrap(),
        );
        let section = mesh::axisymmetric_section(4.0, 9.0, 1.0, "m").unwrap();
        let axi = AnyPress::Axisymmetric(AxisymmetricPress::new_axisymmetric(section, vec![m], protocol()).unwrap());
        for (problem, want) in [(&plane, 60.0), (&solid, 60.0), (&axi, 2.0 * 9.0 + 2.0 * 8.0)] {
            let outline = Outline::of(problem);
            let (nodes, dim): (Vec<f64>, usize) = match problem {
                AnyPress::Plane(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 2),
                AnyPress::Axisymmetric(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 2),
                AnyPress::Solid(p) => (p.mesh.nodes.iter().flatten().copied().collect(), 3),
            };
            let length = outline.length_at_rest(&nodes, dim);
            assert!((length - want).abs() < 1e-9 * want, "{}: length {length} against {want}", outline.what);
        }
        let svg = shape_svg(
            "t",
            &solid,
            &Outline::of(&solid),
            &[(
                "start",
                &Snapshot {
                    t_s: 0.0,
                    displacement: vec![
                        0.0;
                        3 * match &solid {
                            AnyPress::Solid(p) => p.mesh.nodes.len(),
                            _ => unreachable!(),
                        }
                    ],
                    cell_stress: Vec::new(),
                },
            )],
        )
        .unwrap();
        assert!(svg.contains("x [mm]") && svg.contains("section z = "));
    }
}
