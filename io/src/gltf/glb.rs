use std::path::Path;

use serde_json::{json, Value};

use super::colormap::{viridis_linear, COLORMAP};
use super::error::GltfError;
use super::scene::{AnimatedTool, GltfScene};
use crate::atomic::write_atomic;

/// glTF's length unit is the metre; the engine's the millimetre.
pub const METRES_PER_MM: f64 = 1e-3;

/// The most frames one file holds: each frame is a morph target, and the weights
/// animation stores `frames^2` numbers.
pub const MAX_FRAMES: usize = 1024;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_VERSION: u32 = 2;
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const TRIANGLES: u32 = 4;

/// The specimen's material (white, so that the vertex colours show as they are)
/// and the tools' (translucent grey, so that the specimen shows through).
const SPECIMEN_MATERIAL: usize = 0;
const TOOL_MATERIAL: usize = 1;

/// Writes `scene` as a binary glTF 2.0 file (`.glb`) at `path`, atomically; on
/// any error nothing is written.
pub fn write_glb(path: impl AsRef<Path>, scene: &GltfScene) -> Result<(), GltfError> {
    let bytes = glb_bytes(scene)?;
    write_atomic(path, &bytes)?;
    Ok(())
}

/// The bytes of the binary glTF 2.0 file of `scene` (see the module docs for
/// what it holds).
pub fn glb_bytes(scene: &GltfScene) -> Result<Vec<u8>, GltfError> {
    scene.validate()?;
    let specimen = &scene.specimen;
    if specimen.frames.len() > MAX_FRAMES {
        return Err(GltfError::invalid(
            specimen.label(),
            format!("{} frames; a file holds at most {MAX_FRAMES}", specimen.frames.len()),
        ));
    }
    let mut b = Builder::default();

    // ---- The specimen: reference shape, normals, colours; one morph target per frame.
    let n = specimen.positions_mm.len();
    let reference = &specimen.positions_mm;
    let base_normals = vertex_normals(reference, &specimen.triangles, None);
    let magnitudes: Vec<Vec<f64>> = specimen
        .frames
        .iter()
        .map(|f| f.displacement_mm.iter().map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()).collect())
        .collect();
    let max_mm = magnitudes.iter().flatten().copied().fold(0.0, f64::max);
    let colour = |magnitude: f64| viridis_linear(if max_mm > 0.0 { magnitude / max_mm } else { 0.0 });
    let base_colour = colour(0.0);

    let position = b.floats(&to_f32(reference, METRES_PER_MM, &specimen.label())?, 3, Some(ARRAY_BUFFER), true);
    let normal = b.floats(&flat(&base_normals), 3, Some(ARRAY_BUFFER), false);
    let colours = b.floats(&flat(&vec![base_colour; n]), 3, Some(ARRAY_BUFFER), false);
    let indices = b.indices(&specimen.triangles);
    let mut targets = Vec::with_capacity(specimen.frames.len());
    for (i, frame) in specimen.frames.iter().enumerate() {
        let deformed: Vec<[f64; 3]> = reference
            .iter()
            .zip(&frame.displacement_mm)
            .map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]])
            .collect();
        let normals = vertex_normals(&deformed, &specimen.triangles, Some(&base_normals));
        let d_position = to_f32(&frame.displacement_mm, METRES_PER_MM, &specimen.frame_label(i))?;
        let d_normal: Vec<[f64; 3]> = normals.iter().zip(&base_normals).map(|(a, b)| sub(*a, *b)).collect();
        let d_colour: Vec<[f64; 3]> = magnitudes[i].iter().map(|&m| sub(colour(m), base_colour)).collect();
        targets.push(json!({
            "POSITION": b.floats(&d_position, 3, Some(ARRAY_BUFFER), true),
            "NORMAL": b.floats(&flat(&d_normal), 3, Some(ARRAY_BUFFER), false),
            "COLOR_0": b.floats(&flat(&d_colour), 3, Some(ARRAY_BUFFER), false),
        }));
    }
    let target_names = specimen.target_names();
    let num_frames = specimen.frames.len();
    let one_hot = |i: usize| (0..num_frames).map(move |j| if i == j { 1.0f32 } else { 0.0 });
    let mut meshes = vec![json!({
        "name": specimen.name,
        "primitives": [{
            "attributes": { "POSITION": position, "NORMAL": normal, "COLOR_0": colours },
            "indices": indices,
            "material": SPECIMEN_MATERIAL,
            "mode": TRIANGLES,
            "targets": targets,
        }],
        // The pose shown without the animation: the first frame.
        "weights": one_hot(0).map(f64::from).collect::<Vec<f64>>(),
        "extras": { "targetNames": target_names },
    })];
    let mut nodes = vec![json!({ "name": specimen.name, "mesh": 0 })];

    // ---- The animation: the specimen's weights, one-hot at each frame, linear between.
    let times: Vec<f32> = specimen.frames.iter().map(|f| f.t_s as f32).collect();
    let frame_times = b.floats(&times, 1, None, true);
    let weights: Vec<f32> = (0..num_frames).flat_map(one_hot).collect();
    let weights = b.floats(&weights, 1, None, false);
    let mut samplers = vec![json!({ "input": frame_times, "output": weights, "interpolation": "LINEAR" })];
    let mut channels = vec![json!({ "sampler": 0, "target": { "node": 0, "path": "weights" } })];

    // ---- The tools: one node each, moved by translation and rotation channels.
    for tool in &scene.tools {
        let node = nodes.len();
        meshes.push(tool_mesh(&mut b, tool)?);
        let mut node_json = json!({ "name": tool.name, "mesh": meshes.len() - 1 });
        if let Some(first) = tool.keys.first() {
            node_json["translation"] = json!(first.translation_mm.map(|x| x * METRES_PER_MM));
            node_json["rotation"] = json!(unit_quaternion(first.rotation_xyzw));
            let times: Vec<f32> = tool.keys.iter().map(|k| k.t_s as f32).collect();
            let translations: Vec<[f64; 3]> = tool.keys.iter().map(|k| k.translation_mm).collect();
            let rotations: Vec<f32> =
                tool.keys.iter().flat_map(|k| unit_quaternion(k.rotation_xyzw)).map(|x| x as f32).collect();
            let input = b.floats(&times, 1, None, true);
            let translation = b.floats(&to_f32(&translations, METRES_PER_MM, &tool.label())?, 3, None, false);
            let rotation = b.floats(&rotations, 4, None, false);
            for (output, path) in [(translation, "translation"), (rotation, "rotation")] {
                channels.push(json!({ "sampler": samplers.len(), "target": { "node": node, "path": path } }));
                samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            }
        }
        nodes.push(node_json);
    }

    let named: serde_json::Map<String, Value> =
        specimen.frames.iter().enumerate().filter_map(|(i, f)| f.name.clone().map(|name| (name, json!(i)))).collect();
    let root = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("wagashi-io ", env!("CARGO_PKG_VERSION")),
            "extras": {
                "units": { "length": "m", "time": "s", "converted_from": "mm" },
                "colour_scale": {
                    "attribute": "COLOR_0",
                    "quantity": "displacement magnitude",
                    "colormap": COLORMAP,
                    "min_mm": 0.0,
                    "max_mm": max_mm,
                },
                "specimen": specimen.name,
                "tools": scene.tools.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(),
                "frames": specimen.frames.iter().zip(&target_names)
                    .map(|(f, name)| json!({ "t_s": f.t_s, "name": name }))
                    .collect::<Vec<_>>(),
                "named_frames": named,
                "run": scene.extras,
            },
        },
        "scene": 0,
        "scenes": [{ "name": "press", "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {
                "name": "specimen",
                "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7 },
            },
            {
                "name": "tool",
                "pbrMetallicRoughness": { "baseColorFactor": [0.72, 0.74, 0.78, 0.45], "metallicFactor": 0.2, "roughnessFactor": 0.4 },
                "alphaMode": "BLEND",
            },
        ],
        "animations": [{ "name": "press", "samplers": samplers, "channels": channels }],
        "buffers": [{ "byteLength": b.bin.len() }],
        "bufferViews": b.views,
        "accessors": b.accessors,
    });
    let root = if scene.tools.is_empty() { drop_tool_material(root) } else { root };
    let json = serde_json::to_vec(&root).map_err(|e| GltfError::invalid("glTF JSON", e.to_string()))?;
    glb_container(json, b.bin)
}

/// Without tools the tool material would be unused (the validator reports that).
fn drop_tool_material(mut root: Value) -> Value {
    if let Some(materials) = root["materials"].as_array_mut() {
        materials.truncate(TOOL_MATERIAL);
    }
    root
}

/// A tool's mesh: positions in its own frame, flat-enough normals, its material.
fn tool_mesh(b: &mut Builder, tool: &AnimatedTool) -> Result<Value, GltfError> {
    let normals = vertex_normals(&tool.vertices_mm, &tool.triangles, None);
    let position = b.floats(&to_f32(&tool.vertices_mm, METRES_PER_MM, &tool.label())?, 3, Some(ARRAY_BUFFER), true);
    let normal = b.floats(&flat(&normals), 3, Some(ARRAY_BUFFER), false);
    let indices = b.indices(&tool.triangles);
    Ok(json!({
        "name": tool.name,
        "primitives": [{
            "attributes": { "POSITION": position, "NORMAL": normal },
            "indices": indices,
            "material": TOOL_MATERIAL,
            "mode": TRIANGLES,
        }],
    }))
}

/// The GLB container: a 12-byte header, the JSON chunk padded with spaces and the
/// binary chunk padded with zeros, both to 4 bytes; little-endian throughout.
fn glb_container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>, GltfError> {
    pad(&mut json, b' ');
    pad(&mut bin, 0);
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total32 = u32::try_from(total)
        .map_err(|_| GltfError::invalid("scene", format!("{total} bytes; a .glb holds at most 4 GiB")))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&GLB_VERSION.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    for (kind, data) in [(CHUNK_JSON, &json), (CHUNK_BIN, &bin)] {
        if data.is_empty() {
            continue;
        }
        // The total fits in u32, so does each chunk.
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
    }
    Ok(out)
}

fn pad(bytes: &mut Vec<u8>, with: u8) {
    bytes.resize(bytes.len().next_multiple_of(4), with);
}

/// The binary buffer with its buffer views and accessors, one view per accessor,
/// each starting on a 4-byte boundary.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: impl IntoIterator<Item = [u8; 4]>, target: Option<u32>) -> usize {
        pad(&mut self.bin, 0);
        let offset = self.bin.len();
        for b in bytes {
            self.bin.extend_from_slice(&b);
        }
        let mut view = json!({ "buffer": 0, "byteOffset": offset, "byteLength": self.bin.len() - offset });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.views.push(view);
        self.views.len() - 1
    }

    /// A float accessor of `components` per element (1, 3 or 4), with its exact
    /// per-component min and max when `bounds` (required for POSITION and
    /// animation inputs).
    fn floats(&mut self, data: &[f32], components: usize, target: Option<u32>, bounds: bool) -> usize {
        let view = self.view(data.iter().map(|x| x.to_le_bytes()), target);
        let kind = match components {
            1 => "SCALAR",
            3 => "VEC3",
            _ => "VEC4",
        };
        let mut accessor = json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": data.len() / components,
            "type": kind,
        });
        if bounds {
            let mut lo = vec![f32::INFINITY; components];
            let mut hi = vec![f32::NEG_INFINITY; components];
            for element in data.chunks_exact(components) {
                for (k, &x) in element.iter().enumerate() {
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
            // f32 -> f64 is exact, and JSON keeps the f64: the bounds match the data bit for bit.
            accessor["min"] = json!(lo.iter().map(|&x| f64::from(x)).collect::<Vec<_>>());
            accessor["max"] = json!(hi.iter().map(|&x| f64::from(x)).collect::<Vec<_>>());
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let view = self.view(triangles.iter().flatten().map(|v| v.to_le_bytes()), Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": 3 * triangles.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }
}

/// `v * scale` as f32, refusing what f32 cannot hold.
fn to_f32(v: &[[f64; 3]], scale: f64, what: &str) -> Result<Vec<f32>, GltfError> {
    let mut out = Vec::with_capacity(3 * v.len());
    for (i, p) in v.iter().enumerate() {
        for &x in p {
            let y = (x * scale) as f32;
            if !y.is_finite() {
                return Err(GltfError::invalid(
                    what,
                    format!("value {x} mm of vertex {i} is too large for glTF's floats"),
                ));
            }
            out.push(y);
        }
    }
    Ok(out)
}

fn flat(v: &[[f64; 3]]) -> Vec<f32> {
    v.iter().flatten().map(|&x| x as f32).collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Area-weighted vertex normals of a triangle surface, unit length. A vertex with
/// no surrounding area takes `fallback`'s normal, or +y.
fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]], fallback: Option<&[[f64; 3]]>) -> Vec<[f64; 3]> {
    let mut sum = vec![[0.0; 3]; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &v in t {
            let s = &mut sum[v as usize];
            for k in 0..3 {
                s[k] += n[k];
            }
        }
    }
    sum.iter()
        .enumerate()
        .map(|(v, s)| {
            let length = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            if length > 0.0 && length.is_finite() {
                s.map(|x| x / length)
            } else {
                fallback.map_or([0.0, 1.0, 0.0], |f| f[v])
            }
        })
        .collect()
}

/// `q` normalized (its length was checked non-zero).
fn unit_quaternion(q: [f64; 4]) -> [f64; 4] {
    let length = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / length)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_of_a_square_point_up_and_fall_back() {
        let p = [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 0.0], [5.0, 5.0, 5.0]];
        let n = vertex_normals(&p, &[[0, 3, 2], [0, 2, 1]], None);
        for (v, normal) in n.iter().enumerate().take(4) {
            assert!((normal[1] - 1.0).abs() < 1e-15, "{v}: {normal:?}");
        }
        assert_eq!(n[4], [0.0, 1.0, 0.0], "a lone vertex gets +y");
        let n = vertex_normals(&p, &[[0, 3, 2], [0, 2, 1]], Some(&[[1.0, 0.0, 0.0]; 5]));
        assert_eq!(n[4], [1.0, 0.0, 0.0], "or the fallback");
    }

    #[test]
    fn the_container_is_aligned_and_sized() {
        let glb = glb_container(b"{}".to_vec(), vec![1, 2, 3, 4, 5]).unwrap();
        assert_eq!(&glb[0..4], b"glTF");
        assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
        assert_eq!(u32::from_le_bytes(glb[12..16].try_into().unwrap()), 4, "JSON padded to 4 bytes");
        assert_eq!(&glb[16..24], b"JSON{}  ");
        assert_eq!(u32::from_le_bytes(glb[24..28].try_into().unwrap()), 8, "BIN padded to 4 bytes");
        assert_eq!(&glb[28..32], b"BIN\0");
        assert_eq!(&glb[32..], &[1, 2, 3, 4, 5, 0, 0, 0]);
        assert_eq!(glb.len() % 4, 0);
    }

    #[test]
    fn bounds_are_exact_per_component() {
        let mut b = Builder::default();
        let a = b.floats(&[0.1, -2.0, 3.0, 0.5, 7.0, -1.0], 3, None, true);
        assert_eq!(b.accessors[a]["min"], json!([f64::from(0.1f32), -2.0, -1.0]));
        assert_eq!(b.accessors[a]["max"], json!([0.5, 7.0, 3.0]));
        assert_eq!(b.accessors[a]["count"], json!(2));
        b.floats(&[1.0], 1, None, false);
        assert_eq!(b.views[1]["byteOffset"], json!(24));
    }
}
