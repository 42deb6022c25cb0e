//! glTF 2.0, JSON (`.gltf`, with external or embedded buffers) or binary (`.glb`).
//!
//! The default scene (else the first) is walked from its root nodes; every node
//! holding a mesh places that mesh's triangle primitives with the node's global
//! transform (matrix or translation-rotation-scale, composed in f64). A transform
//! with a negative determinant mirrors the mesh; its triangles are then reversed
//! so that they keep facing outward (the specification's rule). Triangle lists,
//! strips and fans are read; points and lines have no area and are left out (and
//! counted in the warnings).
//!
//! Each mesh is a region named by the mesh's name (`mesh<index>` when unnamed; a
//! name two meshes share gets `#<index>` on the second); all instances of a mesh
//! belong to its region. Vertices at bit-identical positions after the transform
//! are merged: glTF repeats a vertex in every primitive that uses it and along
//! texture seams. Positions are metres by the specification (the default unit).
//!
//! Buffers are loaded by [`super::gltf_buffers`]: `data:` URIs and files inside
//! the glTF file's folder only.

use std::collections::HashMap;
use std::path::Path;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;

use super::error::{Location, SurfaceError};
use super::read::{owned, Builder, Raw};

/// An affine map, row-major: `p' = A[.., ..3] p + A[.., 3]`.
type Affine = [[f64; 4]; 3];

const IDENTITY: Affine = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    let format_err = |message: String| SurfaceError::Format { path: owned(path), message };
    let gltf = ::gltf::Gltf::from_slice(bytes).map_err(|e| format_err(format!("glTF: {e}")))?;
    let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let buffers = super::gltf_buffers::load_buffers(base, &gltf.document, gltf.blob.clone()).map_err(format_err)?;
    let document = &gltf.document;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| format_err("glTF: no scene to place the meshes".to_string()))?;

    let mut b = Builder::new(true);
    let mut region_of_mesh: HashMap<usize, u32> = HashMap::new();
    let mut names_taken: HashMap<String, usize> = HashMap::new();
    let mut skipped_primitives = 0usize;
    let num_nodes = document.nodes().count();

    let mut stack: Vec<(::gltf::Node, Affine, usize)> = scene.nodes().map(|n| (n, IDENTITY, 0)).collect();
    stack.reverse();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > num_nodes {
            return Err(format_err(format!("glTF: node {} is its own ancestor (a cycle)", node.index())));
        }
        let world = compose(&parent, &local_transform(&node));
        if let Some(mesh) = node.mesh() {
            let region = match region_of_mesh.get(&mesh.index()) {
                Some(&r) => r,
                None => {
                    let mut name = mesh.name().map(str::to_string).unwrap_or_else(|| format!("mesh{}", mesh.index()));
                    if names_taken.get(&name).is_some_and(|&m| m != mesh.index()) {
                        name = format!("{name}#{}", mesh.index());
                    }
                    names_taken.insert(name.clone(), mesh.index());
                    let r = b.region(&name);
                    region_of_mesh.insert(mesh.index(), r);
                    r
                }
            };
            let mesh_name = mesh.name().map(str::to_string).unwrap_or_else(|| format!("mesh{}", mesh.index()));
            for primitive in mesh.primitives() {
                let at = Location::Primitive { mesh: mesh_name.clone(), primitive: primitive.index() };
                if !read_primitive(path, &primitive, &buffers, &world, region, at, &mut b)? {
                    skipped_primitives += 1;
                }
            }
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }
    let mut warnings = Vec::new();
    if skipped_primitives > 0 {
        warnings.push(format!("{skipped_primitives} point or line primitives left out"));
    }
    Ok(b.finish(warnings))
}

/// Adds one primitive's triangles; `Ok(false)` when it has no triangles to give
/// (points, lines).
fn read_primitive(
    path: &Path,
    primitive: &::gltf::Primitive,
    buffers: &[::gltf::buffer::Data],
    world: &Affine,
    region: u32,
    at: Location,
    b: &mut Builder,
) -> Result<bool, SurfaceError> {
    let mode = primitive.mode();
    if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Ok(false);
    }
    let syntax = |message: String| SurfaceError::Syntax { path: owned(path), at: at.clone(), message };
    let accessor = primitive.get(&::gltf::Semantic::Positions).ok_or_else(|| syntax("no POSITION attribute".into()))?;
    if accessor.data_type() != DataType::F32 || accessor.dimensions() != Dimensions::Vec3 {
        return Err(syntax(format!(
            "POSITION is {:?} {:?}, expected float VEC3",
            accessor.data_type(),
            accessor.dimensions()
        )));
    }
    if accessor.count() == 0 {
        return Ok(true);
    }
    if let Some(indices) = primitive.indices() {
        let integer = matches!(indices.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
        if !integer || indices.dimensions() != Dimensions::Scalar || indices.count() == 0 {
            return Err(syntax(format!(
                "indices are {:?} {:?} x {}, expected unsigned integer SCALARs",
                indices.data_type(),
                indices.dimensions(),
                indices.count()
            )));
        }
    }
    let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(|d| &d.0[..]));
    let positions: Vec<[f32; 3]> =
        reader.read_positions().ok_or_else(|| syntax("POSITION data lies outside its buffer".into()))?.collect();
    if positions.len() != accessor.count() {
        return Err(syntax(format!("POSITION: {} of {} values readable", positions.len(), accessor.count())));
    }
    let mut local_to_global = Vec::with_capacity(positions.len());
    for p in &positions {
        let p = p.map(f64::from);
        if !p.iter().all(|x| x.is_finite()) {
            return Err(SurfaceError::NonFinite { path: owned(path), at: at.clone(), coordinates: p });
        }
        local_to_global.push(b.vertex(apply(world, p), || at.clone()));
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(read) => read.into_u32().collect(),
        None if primitive.indices().is_some() => return Err(syntax("indices lie outside their buffer".into())),
        None => (0..positions.len() as u32).collect(),
    };
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(SurfaceError::IndexOutOfRange {
            path: owned(path),
            at,
            index: i64::from(bad),
            num_vertices: positions.len(),
            relative: false,
        });
    }
    let mirrored = determinant(world) < 0.0;
    let g = |i: u32| local_to_global[i as usize];
    let mut add = |mut tri: [u32; 3]| {
        if mirrored {
            tri.swap(1, 2);
        }
        b.triangle(tri, region);
    };
    match mode {
        Mode::Triangles => indices.chunks_exact(3).for_each(|c| add([g(c[0]), g(c[1]), g(c[2])])),
        Mode::TriangleStrip => {
            for i in 0..indices.len().saturating_sub(2) {
                let (a, bb, c) = (indices[i], indices[i + 1], indices[i + 2]);
                add(if i % 2 == 0 { [g(a), g(bb), g(c)] } else { [g(bb), g(a), g(c)] });
            }
        }
        _ => {
            for i in 1..indices.len().saturating_sub(1) {
                add([g(indices[i]), g(indices[i + 1]), g(indices[0])]);
            }
        }
    }
    Ok(true)
}

fn local_transform(node: &::gltf::Node) -> Affine {
    match node.transform() {
        ::gltf::scene::Transform::Matrix { matrix } => {
            // Column-major: matrix[column][row].
            std::array::from_fn(|r| std::array::from_fn(|c| f64::from(matrix[c][r])))
        }
        ::gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let r = [
                [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
                [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
                [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
            ];
            let s = scale.map(f64::from);
            std::array::from_fn(|row| {
                [r[row][0] * s[0], r[row][1] * s[1], r[row][2] * s[2], f64::from(translation[row])]
            })
        }
    }
}

/// `a` after `b`: `p -> a(b(p))`.
fn compose(a: &Affine, b: &Affine) -> Affine {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let linear = (0..3).map(|k| a[r][k] * b[k][c]).sum::<f64>();
            if c == 3 {
                linear + a[r][3]
            } else {
                linear
            }
        })
    })
}

fn apply(m: &Affine, p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
}

fn determinant(m: &Affine) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_compose_parent_after_child() {
        let translate = [[1.0, 0.0, 0.0, 5.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
        let scale2 = [[2.0, 0.0, 0.0, 0.0], [0.0, 2.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0]];
        // Parent translates, child scales: the point is scaled first.
        let world = compose(&translate, &scale2);
        assert_eq!(apply(&world, [1.0, 1.0, 1.0]), [7.0, 2.0, 2.0]);
        assert_eq!(determinant(&world), 8.0);
    }
}
