//! The files a glTF or GLB file refers to besides itself (its companions): the
//! buffers and images it names by a relative URI rather than a `data:` URI.
//!
//! - [`gltf_companions`] lists them, so that a command counts them among its
//!   inputs: no output may replace a glTF file's buffer.
//! - [`portable_gltf`] makes a copy that travels: the file with each companion
//!   renamed `STEM.bufferI.EXT` or `STEM.imageI.EXT` (`I` its index in the
//!   file's `buffers` or `images`), and the companions' contents, to be written
//!   beside the copy. A copy of a file without companions is the file itself.
//!
//! URIs are judged as the reader judges them ([`super::gltf_buffers`]): one the
//! reader refuses (another scheme, an absolute path, a name out of the file's
//! folder) is refused here too, naming the buffer or image.

use std::path::{Path, PathBuf};

use super::error::SurfaceError;
use super::gltf_buffers::{check, Resolved};
use super::read::owned;

/// The first 4 bytes of a GLB file.
const GLB_MAGIC: &[u8; 4] = b"glTF";
/// The type of a GLB's JSON chunk (`JSON` in little-endian ASCII).
const JSON_CHUNK_TYPE: u32 = 0x4E4F_534A;
/// The sizes of a GLB's header and of a chunk's header [bytes].
const GLB_HEADER: usize = 12;
const CHUNK_HEADER: usize = 8;

/// A file a glTF file names: where its URI is and what it decodes to.
struct Companion {
    /// `buffers` or `images`.
    array: &'static str,
    /// The index in that array.
    index: usize,
    /// The decoded name, relative to the glTF file's folder.
    name: String,
}

/// A glTF file as read: its JSON and, for a GLB, the bytes after its JSON chunk.
struct Parsed {
    json: serde_json::Value,
    /// `Some(rest)` for a GLB: the chunks after the JSON chunk (the BIN chunk).
    glb_rest: Option<Vec<u8>>,
}

/// Whether `path` is read as glTF: a GLB by its first bytes, or a name ending
/// in `.gltf` or `.glb`.
fn is_gltf(path: &Path, bytes: &[u8]) -> bool {
    bytes.starts_with(GLB_MAGIC)
        || path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

fn format_err(path: &Path, message: String) -> SurfaceError {
    SurfaceError::Format { path: owned(path), message }
}

fn parse(path: &Path, bytes: &[u8]) -> Result<Parsed, SurfaceError> {
    if !bytes.starts_with(GLB_MAGIC) {
        let json = serde_json::from_slice(bytes).map_err(|e| format_err(path, format!("glTF: {e}")))?;
        return Ok(Parsed { json, glb_rest: None });
    }
    let word = |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    let bad = |why: &str| format_err(path, format!("GLB: {why}"));
    let json_len = word(GLB_HEADER).ok_or_else(|| bad("shorter than its header and first chunk header"))? as usize;
    if word(GLB_HEADER + 4) != Some(JSON_CHUNK_TYPE) {
        return Err(bad("the first chunk is not JSON"));
    }
    let start = GLB_HEADER + CHUNK_HEADER;
    let json_bytes = start
        .checked_add(json_len)
        .and_then(|end| bytes.get(start..end))
        .ok_or_else(|| bad(&format!("a JSON chunk of {json_len} bytes runs past the end of the file")))?;
    let json = serde_json::from_slice(json_bytes).map_err(|e| format_err(path, format!("GLB JSON chunk: {e}")))?;
    Ok(Parsed { json, glb_rest: Some(bytes[start + json_len..].to_vec()) })
}

/// The companions of `json`, judged as the reader judges them.
fn companions(path: &Path, json: &serde_json::Value) -> Result<Vec<Companion>, SurfaceError> {
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for (array, what) in [("buffers", "buffer"), ("images", "image")] {
        let Some(items) = json.get(array).and_then(|a| a.as_array()) else {
            continue;
        };
        for (index, item) in items.iter().enumerate() {
            let Some(uri) = item.get("uri").and_then(|u| u.as_str()) else {
                continue;
            };
            if uri.starts_with("data:") {
                continue;
            }
            match check(folder, uri).map_err(|why| format_err(path, format!("glTF {what} {index}: {why}")))? {
                Resolved::File(name) => out.push(Companion { array, index, name }),
                Resolved::Data(_) => {}
            }
        }
    }
    Ok(out)
}

fn read_input(path: &Path) -> Result<Vec<u8>, SurfaceError> {
    crate::input::read(path).map_err(|source| SurfaceError::Read { path: owned(path), source })
}

/// The files the glTF or GLB file `path` names by relative URIs (its buffers
/// and images), as paths beside it; empty for a file that is not glTF (by its
/// content or its name) and for a glTF file whose buffers are all embedded.
pub fn gltf_companions(path: &Path) -> Result<Vec<PathBuf>, SurfaceError> {
    let bytes = read_input(path)?;
    if !is_gltf(path, &bytes) {
        return Ok(Vec::new());
    }
    let parsed = parse(path, &bytes)?;
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Ok(companions(path, &parsed.json)?.into_iter().map(|c| folder.join(c.name)).collect())
}

/// A copy of a glTF or GLB file that reads back wherever it is written with
/// its companions beside it ([`portable_gltf`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PortableGltf {
    /// The file's bytes, its companions' URIs renamed.
    pub bytes: Vec<u8>,
    /// Each companion: its new name (to be written in the copy's folder) and content.
    pub companions: Vec<(String, Vec<u8>)>,
}

/// The copy of the glTF or GLB file `path` whose companions are named
/// `STEM.bufferI.EXT` and `STEM.imageI.EXT` (`stem`: the copy's name without
/// its extension; `EXT` the companion's own, else `bin`). Without companions,
/// or for a file that is not glTF, the copy is the file's bytes unchanged.
pub fn portable_gltf(path: &Path, stem: &str) -> Result<PortableGltf, SurfaceError> {
    let bytes = read_input(path)?;
    if !is_gltf(path, &bytes) {
        return Ok(PortableGltf { bytes, companions: Vec::new() });
    }
    let Parsed { mut json, glb_rest } = parse(path, &bytes)?;
    let found = companions(path, &json)?;
    if found.is_empty() {
        return Ok(PortableGltf { bytes, companions: Vec::new() });
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut out = Vec::with_capacity(found.len());
    for c in found {
        let ext = Path::new(&c.name)
            .extension()
            .and_then(|e| e.to_str())
            .filter(|e| !e.is_empty() && e.chars().all(|ch| ch.is_ascii_alphanumeric()))
            .unwrap_or("bin");
        let kind = c.array.trim_end_matches('s');
        let new_name = format!("{stem}.{kind}{}.{ext}", c.index);
        let content = read_input(&folder.join(&c.name))?;
        json[c.array][c.index]["uri"] = serde_json::Value::String(percent_encode(&new_name));
        out.push((new_name, content));
    }
    let text = serde_json::to_vec(&json).map_err(|e| format_err(path, format!("glTF: {e}")))?;
    let bytes = match glb_rest {
        None => text,
        Some(rest) => glb(&text, &rest),
    };
    Ok(PortableGltf { bytes, companions: out })
}

/// A GLB of the JSON `text` (padded with spaces to 4 bytes) followed by the
/// chunks `rest`, as they were.
fn glb(text: &[u8], rest: &[u8]) -> Vec<u8> {
    let mut json = text.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = GLB_HEADER + CHUNK_HEADER + json.len() + rest.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&JSON_CHUNK_TYPE.to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(rest);
    out
}

/// `name` as a URI path segment: every byte but the unreserved ones
/// (`A-Z a-z 0-9 - . _ ~`) percent-encoded.
fn percent_encode(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~') {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const GLTF: &str = r#"{"asset":{"version":"2.0"},
        "buffers":[{"uri":"mesh%20data.bin","byteLength":4},{"uri":"data:application/octet-stream;base64,AAAAAA==","byteLength":4}],
        "images":[{"uri":"tex/skin.png"}]}"#;

    fn folder() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("tex")).unwrap();
        std::fs::write(dir.path().join("mesh data.bin"), [1u8, 2, 3, 4]).unwrap();
        std::fs::write(dir.path().join("tex/skin.png"), b"png").unwrap();
        std::fs::write(dir.path().join("a.gltf"), GLTF).unwrap();
        dir
    }

    #[test]
    fn companions_are_the_relative_uris() {
        let dir = folder();
        let found = gltf_companions(&dir.path().join("a.gltf")).unwrap();
        assert_eq!(found, [dir.path().join("mesh data.bin"), dir.path().join("tex/skin.png")]);
        std::fs::write(dir.path().join("a.obj"), "v 0 0 0\n").unwrap();
        assert!(gltf_companions(&dir.path().join("a.obj")).unwrap().is_empty());
    }

    #[test]
    fn a_portable_copy_renames_its_companions() {
        let dir = folder();
        let copy = portable_gltf(&dir.path().join("a.gltf"), "my tool").unwrap();
        let names: Vec<&str> = copy.companions.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["my tool.buffer0.bin", "my tool.image0.png"]);
        assert_eq!(copy.companions[0].1, [1, 2, 3, 4]);
        let json: serde_json::Value = serde_json::from_slice(&copy.bytes).unwrap();
        assert_eq!(json["buffers"][0]["uri"], "my%20tool.buffer0.bin");
        assert_eq!(json["buffers"][1]["uri"], "data:application/octet-stream;base64,AAAAAA==");
        assert_eq!(json["images"][0]["uri"], "my%20tool.image0.png");
    }

    #[test]
    fn a_glb_keeps_its_bin_chunk() {
        let dir = folder();
        let bin = [9u8, 9, 9, 9];
        let mut rest = Vec::new();
        rest.extend_from_slice(&4u32.to_le_bytes());
        rest.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        rest.extend_from_slice(&bin);
        let path = dir.path().join("b.glb");
        std::fs::write(&path, glb(GLTF.as_bytes(), &rest)).unwrap();
        let copy = portable_gltf(&path, "b").unwrap();
        assert_eq!(copy.companions.len(), 2);
        let parsed = parse(&path, &copy.bytes).unwrap();
        assert_eq!(parsed.json["buffers"][0]["uri"], "b.buffer0.bin");
        assert_eq!(parsed.glb_rest.unwrap(), rest);
        let total = u32::from_le_bytes(copy.bytes[8..12].try_into().unwrap()) as usize;
        assert_eq!(total, copy.bytes.len());
        assert_eq!(copy.bytes.len() % 4, 0);
    }

    #[test]
    fn a_uri_out_of_the_folder_is_refused() {
        let dir = folder();
        let path = dir.path().join("c.gltf");
        std::fs::write(&path, r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"../x.bin","byteLength":4}]}"#).unwrap();
        let err = gltf_companions(&path).unwrap_err().to_string();
        assert!(err.contains("c.gltf: glTF buffer 0: URI \"../x.bin\" leaves the glTF file's folder"), "{err}");
        assert!(portable_gltf(&path, "c").is_err());
    }
}
