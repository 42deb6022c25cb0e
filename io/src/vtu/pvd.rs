use std::fmt::Write as _;
use std::path::Path;

use super::escape_attr;
use crate::atomic::write_atomic;
use crate::error::WriteError;
use crate::number::push_shortest;

/// The `.pvd` text of a time series: `(time [s], file)` pairs, files relative to
/// the `.pvd` (written with `/` separators).
pub fn pvd_string<P: AsRef<Path>>(entries: &[(f64, P)]) -> String {
    let mut x = String::from("<?xml version=\"1.0\"?>\n");
    x.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n");
    for (t, file) in entries {
        let name: Vec<String> =
            file.as_ref().components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
        x.push_str("    <DataSet timestep=\"");
        push_shortest(&mut x, *t);
        let _ = writeln!(x, "\" group=\"\" part=\"0\" file=\"{}\"/>", escape_attr(&name.join("/")));
    }
    x.push_str("  </Collection>\n</VTKFile>\n");
    x
}

/// Writes the `.pvd` collection `path` of `(time [s], file)` pairs, atomically.
pub fn write_pvd<P: AsRef<Path>>(path: impl AsRef<Path>, entries: &[(f64, P)]) -> Result<(), WriteError> {
    write_atomic(path, pvd_string(entries).as_bytes())
}
