//! The files a bundle names stay inside its folder.
//!
//! Every file `experiment.toml` names (`data.force`, `data.markers`,
//! `specimen.surface`, `specimen.mesh`, `protocol.tool_surface`, `protocol.tools[i].surface`) is
//! taken relative to the bundle folder and must lie inside it: a bundle from
//! elsewhere cannot make wagashi read a file outside its folder, or copy one
//! into an output. A name is refused, as
//! `experiment.toml:LINE: KEY: path leaves the bundle folder`, when
//!
//! - it is absolute, or a `..` climbs above the folder (judged on the name), or
//! - the file exists and its canonical path (symlinks followed, in the name and
//!   in the folder's own path) is not inside the folder's canonical path.
//!
//! A file that does not exist is judged by its name alone; reading it then
//! reports it missing. The test is [`crate::input::inside`], which glTF buffer
//! and image URIs pass too.

use std::path::Path;

use super::experiment::Experiment;
use crate::error::BundleError;
use crate::input::inside;
use crate::source_map::SourceMap;

/// The cause of the refusal of a name that leaves the folder.
pub(crate) const LEAVES_THE_BUNDLE: &str = "path leaves the bundle folder";

/// Checks every file name of `e` against the bundle folder `dir`.
pub(crate) fn confine_paths(e: &Experiment, dir: &Path, map: &SourceMap) -> Result<(), BundleError> {
    let mut named: Vec<(String, &str)> = Vec::new();
    if let Some(data) = &e.data {
        named.extend(data.force.as_deref().map(|f| ("data.force".to_string(), f)));
        named.extend(data.markers.as_deref().map(|f| ("data.markers".to_string(), f)));
    }
    named.extend(e.specimen.surface.as_deref().map(|f| ("specimen.surface".to_string(), f)));
    named.extend(e.specimen.mesh.as_deref().map(|f| ("specimen.mesh".to_string(), f)));
    named.extend(e.protocol.tool_surface.as_deref().map(|f| ("protocol.tool_surface".to_string(), f)));
    for (i, t) in e.protocol.tools.iter().enumerate() {
        named.extend(t.surface.as_deref().map(|f| (format!("protocol.tools[{i}].surface"), f)));
    }
    for (field, name) in named {
        if !inside(dir, name) {
            return Err(map.invalid(&field, LEAVES_THE_BUNDLE));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_climb_out_or_are_absolute_leave_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let bundle = dir.path().join("b");
        std::fs::create_dir_all(bundle.join("sub")).unwrap();
        std::fs::write(dir.path().join("outside.csv"), "t_s,force_N\n").unwrap();
        std::fs::write(bundle.join("force.csv"), "t_s,force_N\n").unwrap();
        for name in ["force.csv", "./force.csv", "sub/../force.csv", "missing.csv", "sub/missing.csv"] {
            assert!(inside(&bundle, name), "{name}");
        }
        for name in ["../outside.csv", "sub/../../outside.csv", "..", "/etc/hostname", "../b/../outside.csv"] {
            assert!(!inside(&bundle, name), "{name}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_out_of_the_folder_leaves_it() {
        let dir = tempfile::tempdir().unwrap();
        let bundle = dir.path().join("b");
        std::fs::create_dir_all(&bundle).unwrap();
        std::fs::write(dir.path().join("outside.csv"), "t_s,force_N\n").unwrap();
        std::os::unix::fs::symlink(dir.path().join("outside.csv"), bundle.join("force.csv")).unwrap();
        std::os::unix::fs::symlink(dir.path(), bundle.join("up")).unwrap();
        assert!(!inside(&bundle, "force.csv"));
        assert!(!inside(&bundle, "up/outside.csv"));
        // A symlink that stays inside is fine, and so is a folder reached by one.
        std::fs::write(bundle.join("real.csv"), "t_s,force_N\n").unwrap();
        std::os::unix::fs::symlink("real.csv", bundle.join("alias.csv")).unwrap();
        assert!(inside(&bundle, "alias.csv"));
        let link = dir.path().join("link-to-b");
        std::os::unix::fs::symlink(&bundle, &link).unwrap();
        assert!(inside(&link, "real.csv"));
    }
}
