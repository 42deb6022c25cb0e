//! # wagashi io
//!
//! wagashi's file formats, kept apart from the engine (fem-core knows no file
//! format; this crate knows no solver internals):
//!
//! - **Experiment bundles** ([`bundle`]), the contract of experiment-format.md v1:
//!   a folder with `experiment.toml` and the CSV files it names. [`read_bundle`]
//!   reads and checks one into a [`Bundle`]; every refusal names the file, the
//!   line and the field (`trials/a/experiment.toml:12: specimen.size_mm: ...`).
//!   [`Bundle::to_press`] builds fem-core's press problem; [`write_bundle`] writes a
//!   simulation's results in the same form, so it reads back as if measured.
//! - **VTK output** ([`vtu`]): `.vtu` meshes with displacement, region and stress,
//!   and `.pvd` time series for ParaView.
//! - **glTF export** ([`gltf`]): animated binary glTF 2.0 (`.glb`) of a press run,
//!   the specimen's surface as morph targets and the tools as moving nodes, in metres.
//! - **Surface import** ([`surface`]): OBJ, STL (binary and ASCII) and glTF/GLB
//!   triangle surfaces into [`meshing::Surface`] in mm, with named regions;
//!   [`surface::read_surface`], and [`surface::write_stl`].
//! - **Tetrahedral meshes** ([`tetmesh`]): TetGen `.node`/`.ele`/`.face` and Gmsh
//!   MSH 4.1 ASCII, read and written, regions kept.
//! - **Atomic outputs** ([`atomic`]): [`write_atomic`] for files, [`AtomicDir`] for
//!   output folders; every writer here uses them.
//!
//! Units are the bundle's (mm, s, N, MPa, MPa s, g, g/cm^3), every key naming its
//! unit; the only conversion is density, g/cm^3 to the engine's t/mm^3 (x 1e-9).
//!
//! ## Errors
//!
//! [`BundleError`] for reading and converting, [`WriteError`] for writing; no
//! input makes this crate panic.
//!
//! ## Example
//!
//! ```
//! use wagashi_io::{read_bundle, write_bundle, BundleWrite, ForceSample, ForceSeries};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let dir = tempfile::tempdir()?;
//! std::fs::write(dir.path().join("experiment.toml"), r#"
//! format = "wagashi-experiment/1"
//! name = "mat1-uniform"
//! dimension = 2
//!
//! [specimen]
//! shape = "block"
//! size_mm = [58.0, 59.5, 12.0]
//! material = "mat1"
//!
//! [materials.mat1]
//! model = "five-element"
//! poisson = 0.3746
//! E1_MPa = 0.0349
//! E2_MPa = 0.0221
//! c1_MPa_s = 0.0071
//! c2_MPa_s = 0.1869
//! c3_MPa_s = 29.719
//!
//! [protocol]
//! tool = "plate"
//! tool_contact = "glued"
//! support = "glued"
//! waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]
//! release_s = 210.93
//! end_s = 400.0
//! "#)?;
//!
//! // 1. Read and check the bundle.
//! let bundle = read_bundle(dir.path())?;
//! assert_eq!(bundle.experiment.specimen.block_size(), Some([58.0, 59.5, 12.0]));
//!
//! // 2. Build the engine's problem: plane stress, 10 mm elements.
//! let problem = bundle.to_press(10.0)?;
//! assert!(matches!(problem, fem_core::press::AnyPress::Plane(_)));
//!
//! // 3. Write results as a bundle, and read them back.
//! let force = ForceSeries { samples: vec![ForceSample { t_s: 0.0, force_n: 0.0 }, ForceSample { t_s: 28.87, force_n: 5.1 }] };
//! let out = dir.path().join("sim");
//! write_bundle(&out, &BundleWrite::simulated(&bundle, "mat1-uniform-sim", &force, &[]))?;
//! let back = read_bundle(&out)?;
//! assert_eq!(back.force, Some(force));
//! assert_eq!(back.experiment.materials, bundle.experiment.materials);
//! # Ok(()) }
//! ```

pub mod atomic;
pub mod bundle;
mod error;
pub mod gltf;
pub mod input;
mod number;
mod source_map;
pub mod surface;
pub mod tetmesh;
pub mod texture;
pub mod vtu;

pub use crate::gltf::{write_glb, GltfError, GltfScene};
pub use atomic::{write_atomic, AtomicDir};
pub use bundle::{
    read_bundle, read_bundle_from_str, read_bundle_with, read_materials_file, write_bundle, Bundle, BundleWrite,
    Experiment, ForceSample, ForceSeries, MarkerSample, MarkerSeries, MaterialSpec, Model, SurfaceMeshing,
};
pub use error::{BundleError, SurfaceMeshError, WriteError};
