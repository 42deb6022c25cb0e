//! `wagashi demo`: the seed paper's material 1 trial end to end, with no input.
//!
//! The bundle `examples/paper/mat1` is compiled into the binary and simulated
//! through the same code path as `wagashi press` ([`crate::press::press_bundle`]),
//! with 3 mm elements: a 58 x 59.5 x 12 mm block, glued to the plate and the
//! floor, pushed at 0.2 mm/s for 28.87 s, held until 210.93 s, released and left
//! to recover until 400 s, with the seed's Table II x_force parameters.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use wagashi_io::{read_bundle_from_str, Bundle};

use crate::press::{press_bundle, print_results, IntegratorArg, PressOptions};

/// The folder the embedded bundle comes from (named in messages).
pub const DEMO_BUNDLE_DIR: &str = "examples/paper/mat1";
/// `examples/paper/mat1/experiment.toml`, compiled in.
pub const DEMO_EXPERIMENT: &str = include_str!("../../examples/paper/mat1/experiment.toml");
/// The demo's element size [mm].
pub const DEMO_SIZE_MM: f64 = 3.0;

const DEMO_AFTER_HELP: &str = "\
Example:
  wagashi demo                 # writes demo-out/
  wagashi demo -o /tmp/mat1    # writes /tmp/mat1/

The same run from the bundle on disk (from the repository root):
  wagashi press examples/paper/mat1 -o demo-out --size-mm 3 --force";

/// `wagashi demo [-o DIR]`.
#[derive(Debug, Args)]
#[command(
    about = "Simulate the seed paper's material 1 trial (no input needed)",
    long_about = "Simulate the seed paper's material 1 trial with no input: the bundle \
examples/paper/mat1 (compiled into the binary; Table I protocol, Table II x_force five-element \
parameters, a 3D block glued to the plate and the floor) at 3 mm elements, through the same code path \
as `wagashi press`. Writes the same files as `press` into DIR; a previous wagashi output there is \
replaced, any other existing folder is refused.",
    after_help = DEMO_AFTER_HELP
)]
pub struct DemoArgs {
    /// The output folder.
    #[arg(short = 'o', long = "output", value_name = "DIR", default_value = "demo-out")]
    pub output: PathBuf,
}

/// The embedded bundle.
pub fn demo_bundle() -> Result<Bundle, wagashi_io::BundleError> {
    read_bundle_from_str(Path::new(DEMO_BUNDLE_DIR), DEMO_EXPERIMENT, &Default::default())
}

/// `wagashi demo`.
pub fn run(args: &DemoArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let bundle = demo_bundle()?;
    let options = PressOptions {
        size_mm: Some(DEMO_SIZE_MM),
        size_origin: "the demo's size",
        integrator: IntegratorArg::Implicit,
        rtol: fem_core::press::Settings::default().rtol,
        dt_s: None,
        output_dt_s: 0.1,
        pvd: None,
        output: args.output.clone(),
        replace: true,
        volumetric: fem_core::press::Volumetric::Standard,
        allow_large: false,
        other_inputs: Vec::new(),
    };
    writeln!(out, "The seed paper's material 1 trial (embedded {DEMO_BUNDLE_DIR}), 3D, x_force parameters")?;
    let summary = press_bundle(&bundle, &options, out)?;
    print_results(&summary, out)?;
    writeln!(out)?;
    writeln!(out, "Open the results in {}:", args.output.display())?;
    writeln!(out, "  force.svg             the force curve: open it in a web browser")?;
    writeln!(
        out,
        "  keep.vtu, final.vtu   the keep and final shapes: open them in ParaView, apply Filters > Warp By Vector"
    )?;
    writeln!(out, "  summary.json          the numbers (and force.csv, steps.csv, for scripts)")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use wagashi_io::bundle::{Contact, Shape};
    use wagashi_io::Model;

    /// The embedded bundle is the seed's material 1 trial (Table I) with the
    /// x_force parameters (Table II).
    #[test]
    fn the_demo_is_the_seed_material_1_trial() {
        let b = demo_bundle().unwrap();
        let e = &b.experiment;
        assert_eq!(e.dimension, 3);
        assert_eq!(e.specimen.shape, Shape::Block);
        assert_eq!(e.specimen.block_size(), Some([58.0, 59.5, 12.0]));
        assert_eq!(e.specimen.material.as_deref(), Some("mat1"));
        let p = &e.protocol;
        assert_eq!((p.tool_contact, p.support), (Contact::Glued, Contact::Glued));
        let (t_p, t_k) = (28.87, 182.06);
        assert_eq!(p.waypoints.len(), 3);
        let expected = [[0.0, 0.0], [t_p, 0.2 * t_p], [t_p + t_k, 0.2 * t_p]];
        for (w, x) in p.waypoints.iter().zip(expected) {
            // Decimal literals in the file, sums and products here: 1e-12 relative.
            assert!((w[0] - x[0]).abs() <= 1e-12 * x[0].max(1.0) && (w[1] - x[1]).abs() <= 1e-12, "{w:?}");
        }
        assert!((p.release_s - (t_p + t_k)).abs() < 1e-12 * 211.0);
        assert_eq!(p.end_s, 400.0);
        let m = &e.materials["mat1"];
        assert_eq!(m.model, Model::FiveElement);
        assert_eq!(
            (m.poisson, m.e1_mpa, m.e2_mpa, m.c1_mpa_s, m.c2_mpa_s, m.c3_mpa_s),
            (Some(0.3746), Some(0.0349), Some(0.0221), Some(0.0071), Some(0.1869), Some(29.719))
        );
        assert_eq!(e.materials["mat1-shape"].c3_mpa_s, Some(1.4951));
    }
}
