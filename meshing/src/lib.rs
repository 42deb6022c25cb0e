//! # wagashi meshing
//!
//! Triangle surfaces ([`Surface`]): validation and repair, tetrahedralization into
//! fem-core's [`fem_core::mesh::TetMesh`], mesh quality, regions.
//!
//! Lengths are mm throughout. This crate reads no file format (that is `io`'s job)
//! and runs no simulation.

pub mod bvh;
mod cells;
pub mod conforming;
pub mod distance;
pub mod envelope;
#[cfg(test)]
mod fixtures;
pub mod layers;
pub mod predicates;
pub mod quality;
pub mod repair;
pub mod surface;
mod topology;
pub mod validate;
pub mod winding;

pub use repair::{repair, RepairOptions, RepairReport, Repaired};
pub use surface::Surface;
pub use validate::{validate, Defect, InvalidSurface, MalformedSurface, SurfaceReport, ValidateOptions};
pub use winding::WindingNumber;
