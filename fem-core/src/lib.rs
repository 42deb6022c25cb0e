//! # wagashi fem-core
//!
//! The engine of wagashi: linear simplex finite elements in 2D (triangles, plane
//! stress with thickness as in the seed paper, plane strain, or axisymmetric:
//! the `r-y` section of a cylinder, one hoop strain more) and 3D (tetrahedra),
//! written once over the dimension ([`element`] lists the formulations and
//! their formulas); the seed's three-, four- and
//! five-element rheology imposed through the Lamé split; parallel, deterministic
//! sparse assembly; faer sparse Cholesky; quasi-static, dynamic and the seed's own
//! time stepping; the seed's plate-press boundary conditions with release.
//!
//! Units inside the engine, stated once: mm, s, N, MPa, t (tonne), t/mm^3, mJ.
//! Nothing in this crate converts units or knows a file format.
//!
//! Linear algebra: faer owns every factorization (sparse Cholesky, symbolic once
//! per constraint set, numeric when the step size changes); global matrices are
//! kept in our own CSR ([`assembly::CsrMatrix`]) whose values are assembled in
//! parallel and summed in a fixed order; sprs is used only as an independent
//! reference in tests.
//!
//! ## Principal types
//! - [`mesh::SimplexMesh`] ([`mesh::TriMesh`], [`mesh::TetMesh`]) and the generators in [`mesh`].
//! - [`material::Material`]: a [`material::Rheology`] chain and a Poisson ratio.
//! - [`press::PressProblem`]: a mesh, materials per region, a [`press::Protocol`];
//!   [`press::simulate`] runs it and returns a [`press::PressResult`].
//!   [`press::AnyPress`] holds a plane, solid or axisymmetric problem
//!   ([`press::AxisymmetricPress`] on [`mesh::axisymmetric_section`]).
//!
//! ## Example
//! ```
//! use fem_core::{material::Material, mesh, press};
//! let mesh = mesh::rectangle(58.0, 59.5, 10.0, "mat1").unwrap();
//! let problem = press::PressProblem::new_2d(
//!     mesh,
//!     12.0,
//!     vec![Material::seed_mat1_force()],
//!     press::Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0),
//! ).unwrap();
//! let result = press::simulate(&problem, &press::Settings::default(), &mut |_| {}).unwrap();
//! assert!(result.peak_force() > 0.0);
//! ```

// Index loops mirror the formulas (sums over nodes a, components k) and are the
// clearer form in kernels; `!(x > 0.0)` is deliberate: it also refuses NaN.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod analytic;
pub mod assembly;
pub mod effects;
pub mod element;
pub mod material;
pub mod mesh;
pub mod ordering;
pub mod parallel;
pub mod press;
pub mod solve;
