//! The buffers of a glTF file, loaded here rather than by the gltf crate, so
//! that every URI is judged before anything is read.
//!
//! A buffer or image URI may be
//!
//! - a `data:` URI with base64 content (`data:application/octet-stream;base64,...`), or
//! - a relative reference, percent-decoded (`%20` is a space), that names a file
//!   inside the glTF file's folder (as [`crate::input::inside`] judges it:
//!   symlinks followed).
//!
//! Refused, naming the buffer or image and the reason: any other scheme
//! (`file:`, `http:`, ...), an absolute path, a `..` that climbs out of the
//! folder (also percent-encoded, `%2e%2e/`), a symlink out of it, a bad
//! percent escape or bytes that are not UTF-8 once decoded, and a file too
//! short for the buffer's `byteLength`. A buffer file is read as every input is
//! ([`crate::input::read`]). Images are not read (a surface has no use for
//! them), but their URIs are judged the same way, so that a surface that
//! passes holds no reference out of its folder. Messages quote the URI (part of
//! the file the user gave), never the content of the file it names.

use std::path::Path;

use ::gltf::buffer::{Data, Source};
use ::gltf::image::Source as ImageSource;
use ::gltf::Document;

use crate::input::inside;

/// The longest part of a URI quoted in a message [characters].
const QUOTED_CHARS: usize = 60;

/// The data of every buffer of `document`, in order: `blob` is a GLB's BIN
/// chunk, `folder` the glTF file's folder. Each buffer is padded with zeros to
/// a multiple of 4 bytes, as the gltf crate's loader does.
pub(crate) fn load_buffers(folder: &Path, document: &Document, blob: Option<Vec<u8>>) -> Result<Vec<Data>, String> {
    let mut blob = blob;
    for image in document.images() {
        if let ImageSource::Uri { uri, .. } = image.source() {
            check(folder, uri).map_err(|why| format!("glTF image {}: {why}", image.index()))?;
        }
    }
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let what = format!("glTF buffer {}", buffer.index());
        let mut data = match buffer.source() {
            Source::Bin => blob.take().ok_or_else(|| format!("{what}: refers to a GLB BIN chunk there is not"))?,
            Source::Uri(uri) => match check(folder, uri).map_err(|why| format!("{what}: {why}"))? {
                Resolved::Data(bytes) => bytes,
                Resolved::File(name) => crate::input::read(folder.join(&name))
                    .map_err(|e| format!("{what}: {}: cannot read: {e}", quote(&name)))?,
            },
        };
        if data.len() < buffer.length() {
            return Err(format!("{what}: {} bytes, fewer than its byteLength {}", data.len(), buffer.length()));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(Data(data));
    }
    Ok(buffers)
}

/// What a URI that passed refers to.
#[derive(Debug, PartialEq)]
pub(crate) enum Resolved {
    /// The decoded content of a `data:` URI.
    Data(Vec<u8>),
    /// A file, by its name relative to the glTF file's folder (decoded).
    File(String),
}

/// Judges `uri` (module docs).
pub(crate) fn check(folder: &Path, uri: &str) -> Result<Resolved, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, content) = rest
            .split_once(";base64,")
            .ok_or_else(|| "a data: URI that is not base64 (expected `data:MEDIA;base64,...`)".to_string())?;
        return base64::decode(content.trim_end())
            .map(Resolved::Data)
            .map_err(|e| format!("a data: URI whose base64 is broken: {e}"));
    }
    // RFC 3986: a scheme is the letters before the first `:`, ahead of any `/`, `?` or `#`.
    let head = uri.split(['/', '?', '#']).next().unwrap_or("");
    if let Some((scheme, _)) = head.split_once(':') {
        return Err(format!(
            "URI {} has the scheme {}; only data: URIs and files inside the glTF file's folder are read",
            quote(uri),
            quote(scheme)
        ));
    }
    let name = percent_decode(uri).map_err(|why| format!("URI {}: {why}", quote(uri)))?;
    if name.is_empty() || name.contains('\0') {
        return Err(format!("URI {}: not a file name", quote(uri)));
    }
    // A backslash is a separator on Windows: judged as one everywhere.
    let portable = name.replace('\\', "/");
    if portable.starts_with('/') || !inside(folder, &portable) || !inside(folder, &name) {
        return Err(format!("URI {} leaves the glTF file's folder", quote(uri)));
    }
    Ok(Resolved::File(name))
}

/// `s` with its `%XX` escapes decoded; a `%` not followed by two hex digits,
/// or bytes that are not UTF-8 once decoded, are refused.
fn percent_decode(s: &str) -> Result<String, String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
            let byte = hex.and_then(|h| u8::from_str_radix(h, 16).ok()).ok_or("a % not followed by two hex digits")?;
            out.push(byte);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| "its percent escapes do not decode to UTF-8".to_string())
}

/// `s` quoted for a message, cut to [`QUOTED_CHARS`] characters.
pub(crate) fn quote(s: &str) -> String {
    if s.chars().count() <= QUOTED_CHARS {
        format!("{s:?}")
    } else {
        format!("{:?}...", s.chars().take(QUOTED_CHARS).collect::<String>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_confined_to_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("model");
        std::fs::create_dir_all(folder.join("bin")).unwrap();
        std::fs::write(folder.join("a b.bin"), [0u8; 4]).unwrap();
        let file = |n: &str| Ok(Resolved::File(n.to_string()));
        assert_eq!(check(&folder, "a%20b.bin"), file("a b.bin"));
        assert_eq!(check(&folder, "bin/../a b.bin"), file("bin/../a b.bin"));
        assert_eq!(check(&folder, "missing.bin"), file("missing.bin"));
        assert_eq!(
            check(&folder, "data:application/octet-stream;base64,AAECAw=="),
            Ok(Resolved::Data(vec![0, 1, 2, 3]))
        );
        for (uri, why) in [
            ("../x.bin", "leaves the glTF file's folder"),
            ("%2e%2e/x.bin", "leaves the glTF file's folder"),
            ("%2E%2E%2Fx.bin", "leaves the glTF file's folder"),
            ("bin/..%5c..%5cx.bin", "leaves the glTF file's folder"),
            ("/etc/passwd", "leaves the glTF file's folder"),
            ("%2fetc/passwd", "leaves the glTF file's folder"),
            ("file:///etc/passwd", "has the scheme \"file\""),
            ("file:x.bin", "has the scheme \"file\""),
            ("https://example.com/x.bin", "has the scheme \"https\""),
            ("C:/x.bin", "has the scheme \"C\""),
            ("%FF%FE.bin", "do not decode to UTF-8"),
            ("%zz.bin", "a % not followed by two hex digits"),
            ("x.bin%", "a % not followed by two hex digits"),
            ("%00", "not a file name"),
            ("", "not a file name"),
            ("data:,hello", "not base64"),
            ("data:application/octet-stream;base64,@@@", "base64 is broken"),
        ] {
            let err = check(&folder, uri).unwrap_err();
            assert!(err.contains(why), "{uri}: {err}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_out_of_the_folder_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("model");
        std::fs::create_dir_all(&folder).unwrap();
        std::fs::write(dir.path().join("secret.bin"), [0u8; 4]).unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret.bin"), folder.join("x.bin")).unwrap();
        assert!(check(&folder, "x.bin").unwrap_err().contains("leaves the glTF file's folder"));
    }
}
