use std::path::Path;

use super::error::{finite, GltfError};
use crate::atomic::write_atomic;

/// The first eight bytes of a frames file.
pub const FRAMES_MAGIC: &[u8; 8] = b"WGFRAMES";
/// The version of the layout below.
pub const FRAMES_VERSION: u32 = 1;

/// Nodal displacements of a subset of a mesh's nodes at a few times: what
/// `wagashi press --gltf` keeps in its output folder (`frames.bin`) so that
/// `wagashi export` rebuilds the same animation.
///
/// # File layout (`frames.bin`, version 1, little-endian, no padding)
///
/// | bytes            | what                                                       |
/// |------------------|------------------------------------------------------------|
/// | 8                | `WGFRAMES`                                                 |
/// | u32              | version, 1                                                 |
/// | u32              | `dim`: displacement components per node (2 or 3)           |
/// | u32              | `num_nodes`: the mesh's number of nodes                    |
/// | u32              | `k`: number of nodes stored                                |
/// | u32              | `m`: number of frames                                      |
/// | k x u32          | the stored nodes, strictly increasing, `< num_nodes`       |
/// | per frame: f64   | `t_s` [s]                                                  |
/// | u32, bytes       | the frame's name in UTF-8, its length first (0: no name)   |
/// | dim x k x f64    | the displacement of each stored node [mm], node-major      |
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSeries {
    /// Displacement components per node: 2 or 3.
    pub dim: usize,
    /// The mesh's number of nodes.
    pub num_nodes: usize,
    /// The nodes stored, strictly increasing (e.g. the surface's).
    pub nodes: Vec<u32>,
    /// The frames, in time order.
    pub frames: Vec<NodalFrame>,
}

/// One time of a [`FrameSeries`].
#[derive(Debug, Clone, PartialEq)]
pub struct NodalFrame {
    /// Time [s].
    pub t_s: f64,
    /// `keep`, `final`, or none.
    pub name: Option<String>,
    /// `dim` values per stored node [mm], in the order of `FrameSeries::nodes`.
    pub displacement_mm: Vec<f64>,
}

impl FrameSeries {
    /// The series of `nodes` from full nodal displacement vectors
    /// (`dim * num_nodes` values each, as in a snapshot): `(t_s, name, displacement)`.
    pub fn from_nodal<'a>(
        dim: usize,
        num_nodes: usize,
        nodes: Vec<u32>,
        frames: impl IntoIterator<Item = (f64, Option<&'a str>, &'a [f64])>,
    ) -> Result<Self, GltfError> {
        let mut out = Vec::new();
        for (i, (t_s, name, u)) in frames.into_iter().enumerate() {
            if u.len() != dim * num_nodes {
                return Err(GltfError::LengthMismatch {
                    what: format!("frame {i} (t = {t_s} s): nodal displacement"),
                    item: "values",
                    found: u.len(),
                    expected: dim * num_nodes,
                });
            }
            if let Some(&node) = nodes.iter().find(|&&n| n as usize >= num_nodes) {
                return Err(GltfError::invalid("frames", format!("node {node} out of range ({num_nodes} nodes)")));
            }
            let displacement_mm = nodes.iter().flat_map(|&n| &u[dim * n as usize..dim * (n as usize + 1)]).copied();
            out.push(NodalFrame { t_s, name: name.map(str::to_string), displacement_mm: displacement_mm.collect() });
        }
        let series = Self { dim, num_nodes, nodes, frames: out };
        series.validate(Path::new("frames"))?;
        Ok(series)
    }

    /// Frame `i`'s displacement of every node of the mesh (`dim * num_nodes`
    /// values; zero at the nodes not stored).
    pub fn nodal(&self, i: usize) -> Vec<f64> {
        let d = self.dim;
        let mut u = vec![0.0; d * self.num_nodes];
        for (j, &n) in self.nodes.iter().enumerate() {
            u[d * n as usize..d * (n as usize + 1)]
                .copy_from_slice(&self.frames[i].displacement_mm[d * j..d * (j + 1)]);
        }
        u
    }

    /// The file's bytes (see the layout above).
    pub fn to_bytes(&self) -> Result<Vec<u8>, GltfError> {
        self.validate(Path::new("frames"))?;
        let u32_of = |x: usize, what: &str| {
            u32::try_from(x).map_err(|_| GltfError::invalid("frames", format!("{what} = {x} does not fit in 32 bits")))
        };
        let mut b =
            Vec::with_capacity(28 + 4 * self.nodes.len() + self.frames.len() * (16 + 8 * self.dim * self.nodes.len()));
        b.extend_from_slice(FRAMES_MAGIC);
        for (x, what) in [
            (FRAMES_VERSION as usize, "version"),
            (self.dim, "dim"),
            (self.num_nodes, "num_nodes"),
            (self.nodes.len(), "stored nodes"),
            (self.frames.len(), "frames"),
        ] {
            b.extend_from_slice(&u32_of(x, what)?.to_le_bytes());
        }
        for n in &self.nodes {
            b.extend_from_slice(&n.to_le_bytes());
        }
        for f in &self.frames {
            b.extend_from_slice(&f.t_s.to_le_bytes());
            let name = f.name.as_deref().unwrap_or("");
            b.extend_from_slice(&u32_of(name.len(), "name length")?.to_le_bytes());
            b.extend_from_slice(name.as_bytes());
            for x in &f.displacement_mm {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        Ok(b)
    }

    /// Writes the series to `path`, atomically.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), GltfError> {
        write_atomic(path, &self.to_bytes()?)?;
        Ok(())
    }

    /// Reads a series written by [`write`](Self::write); errors name the file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, GltfError> {
        let path = path.as_ref();
        let bytes = crate::input::read(path).map_err(|source| GltfError::Read { path: path.to_path_buf(), source })?;
        Self::from_bytes(&bytes, path)
    }

    /// Parses the bytes of a frames file; `path` is only for the messages.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, GltfError> {
        let mut r = Reader { bytes, at: 0, path };
        if r.take(8)? != FRAMES_MAGIC {
            return Err(GltfError::bad_file(path, "not a wagashi frames file (it does not start with WGFRAMES)"));
        }
        let version = r.u32()?;
        if version != FRAMES_VERSION {
            return Err(GltfError::bad_file(path, format!("version {version}; this wagashi reads version 1")));
        }
        let dim = r.u32()? as usize;
        let num_nodes = r.u32()? as usize;
        let k = r.u32()? as usize;
        let m = r.u32()? as usize;
        // Refuse counts the file cannot hold before allocating for them.
        let need = 4 * k as u128 + m as u128 * (12 + 8 * dim as u128 * k as u128);
        if need > (bytes.len() - r.at) as u128 {
            return Err(GltfError::bad_file(
                path,
                format!("truncated: {k} nodes and {m} frames need {need} more bytes"),
            ));
        }
        let nodes = (0..k).map(|_| r.u32()).collect::<Result<Vec<u32>, _>>()?;
        let mut frames = Vec::with_capacity(m);
        for _ in 0..m {
            let t_s = r.f64()?;
            let len = r.u32()? as usize;
            let name = std::str::from_utf8(r.take(len)?)
                .map_err(|_| GltfError::bad_file(path, "a frame name is not UTF-8"))?
                .to_string();
            let displacement_mm = (0..dim * k).map(|_| r.f64()).collect::<Result<Vec<f64>, _>>()?;
            frames.push(NodalFrame { t_s, name: (!name.is_empty()).then_some(name), displacement_mm });
        }
        if r.at != bytes.len() {
            return Err(GltfError::bad_file(path, format!("{} bytes after the last frame", bytes.len() - r.at)));
        }
        let series = Self { dim, num_nodes, nodes, frames };
        series.validate(path)?;
        Ok(series)
    }

    /// dim 2 or 3, nodes strictly increasing and in range, frames in time order
    /// with finite values of the right length.
    fn validate(&self, path: &Path) -> Result<(), GltfError> {
        let bad = |cause: String| Err(GltfError::bad_file(path, cause));
        if !(self.dim == 2 || self.dim == 3) {
            return bad(format!("dim = {}; 2 or 3 expected", self.dim));
        }
        if let Some(w) = self.nodes.windows(2).find(|w| w[1] <= w[0]) {
            return bad(format!("stored nodes not strictly increasing ({} then {})", w[0], w[1]));
        }
        if let Some(&n) = self.nodes.last().filter(|&&n| n as usize >= self.num_nodes) {
            return bad(format!("stored node {n}, but the mesh has {} nodes", self.num_nodes));
        }
        let mut previous = f64::NEG_INFINITY;
        for (i, f) in self.frames.iter().enumerate() {
            finite(f.t_s, || format!("{}: frame {i}: t_s", path.display()))?;
            if f.t_s <= previous {
                return bad(format!("frame {i} at t = {} s is not after the previous frame ({previous} s)", f.t_s));
            }
            previous = f.t_s;
            if f.displacement_mm.len() != self.dim * self.nodes.len() {
                return bad(format!(
                    "frame {i} has {} values, expected {}",
                    f.displacement_mm.len(),
                    self.dim * self.nodes.len()
                ));
            }
            if let Some(x) = f.displacement_mm.iter().find(|x| !x.is_finite()) {
                return bad(format!("frame {i} (t = {} s) holds a non-finite displacement ({x})", f.t_s));
            }
        }
        Ok(())
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], GltfError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| {
            GltfError::bad_file(self.path, format!("truncated: {n} bytes expected at offset {}", self.at))
        })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self) -> Result<u32, GltfError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    fn f64(&mut self) -> Result<f64, GltfError> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series() -> FrameSeries {
        let u0 = [0.0; 8];
        let u1: Vec<f64> = (0..8).map(|i| 0.1 * i as f64 - 1e-300).collect();
        FrameSeries::from_nodal(2, 4, vec![1, 3], [(0.0, None, &u0[..]), (1.5, Some("keep"), &u1[..])]).unwrap()
    }

    #[test]
    fn round_trips_bit_for_bit() {
        let s = series();
        let u = |i: usize| 0.1 * i as f64 - 1e-300;
        assert_eq!(s.frames[1].displacement_mm, vec![u(2), u(3), u(6), u(7)], "nodes 1 and 3, two values each");
        let bytes = s.to_bytes().unwrap();
        let back = FrameSeries::from_bytes(&bytes, Path::new("f.bin")).unwrap();
        assert_eq!(back, s);
        let full = back.nodal(1);
        assert_eq!(full.len(), 8);
        assert_eq!((full[0], full[2], full[6]), (0.0, u(2), u(6)));
    }

    #[test]
    fn damaged_files_are_refused_naming_the_file() {
        let bytes = series().to_bytes().unwrap();
        for cut in [0, 7, 20, 30, bytes.len() - 1] {
            let err = FrameSeries::from_bytes(&bytes[..cut], Path::new("out/frames.bin")).unwrap_err();
            assert!(err.to_string().starts_with("out/frames.bin: "), "{err}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(FrameSeries::from_bytes(&longer, Path::new("f")).unwrap_err().to_string().contains("after the last"));
        let mut wrong = bytes.clone();
        wrong[0] = b'X';
        assert!(FrameSeries::from_bytes(&wrong, Path::new("f")).unwrap_err().to_string().contains("WGFRAMES"));
        // A huge frame count in the header is refused before any allocation.
        let mut huge = bytes;
        huge[24..28].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(FrameSeries::from_bytes(&huge, Path::new("f")).unwrap_err().to_string().contains("truncated"));
    }

    #[test]
    fn bad_series_are_refused() {
        let u = [0.0; 8];
        let two = [(1.0, None, &u[..]), (1.0, None, &u[..])];
        assert!(FrameSeries::from_nodal(2, 4, vec![0], two).is_err(), "times must increase");
        assert!(FrameSeries::from_nodal(2, 4, vec![0], [(0.0, None, &u[..7])]).is_err(), "length");
        assert!(FrameSeries::from_nodal(2, 4, vec![4], [(0.0, None, &u[..])]).is_err(), "node range");
        let nan = [f64::NAN; 8];
        assert!(FrameSeries::from_nodal(2, 4, vec![0], [(0.0, None, &nan[..])]).is_err(), "NaN");
    }
}
