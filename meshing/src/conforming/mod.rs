//! Conforming (TetGen-equivalent) tetrahedralization: a mesh whose boundary
//! reproduces a clean, closed input surface exactly.
//!
//! Built in stages, each in its file:
//!
//! - `delaunay.rs`: incremental 3D Delaunay tetrahedralization (Bowyer–Watson)
//!   with exact predicates and symbolic perturbation (`perturb.rs`), points
//!   inserted in BRIO/Hilbert order (`order.rs`).

mod delaunay;
mod order;
mod perturb;

pub use delaunay::{Delaunay, DelaunayError, FACE, GHOST};
pub use perturb::insphere;
