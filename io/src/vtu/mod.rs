//! VTK XML output for ParaView: one `.vtu` (UnstructuredGrid) per kept state and
//! a `.pvd` collection for a time series.
//!
//! ## What a `.vtu` holds
//!
//! - Points: the reference coordinates by default, with the displacement as a
//!   point field so that ParaView's *Warp By Vector* shows the deformed shape;
//!   [`Coordinates::Deformed`] writes `x + u` instead. 2D points get z = 0.
//! - Cells: triangles (VTK type 5) or tetrahedra (VTK type 10), nodes in VTK
//!   order (fem-core's order).
//! - Point data `displacement` [mm]: 3 components (z = 0 in 2D).
//! - Cell data `region` (Int32, the index into the mesh's region names, which are
//!   listed in an XML comment) and `stress` [MPa]: a **6-component symmetric
//!   tensor in VTK's order `XX, YY, ZZ, XY, YZ, XZ`** (component names written),
//!   converted from fem-core's Voigt order `[xx, yy, zz, xy, xz, yz]` (stress
//!   shears, not engineering). In 2D fem-core's `[xx, yy, xy]` is written with
//!   `ZZ = YZ = XZ = 0`, exact for plane stress (plane strain's `zz` is not
//!   in the cell stress and is written as 0 too).
//!   An axisymmetric section (4 stresses per cell, fem-core's `[rr, yy, θθ, ry]`)
//!   is written as the tensor at the section's plane, x = r and z the hoop
//!   direction: `XX = rr, YY = yy, ZZ = θθ, XY = ry`, `YZ = XZ = 0`, with the
//!   component names `RR, YY, TT, RY, YT, RT` (and an XML comment saying so).
//!
//! ASCII, numbers in their shortest round-trip form.
//!
//! ## Why by hand
//!
//! The crate for this, `vtkio`, has as its latest stable release 0.6.3, which
//! depends on nom 3, quick-xml 0.22 and base64 0.13 and by default builds the
//! lz4 and xz C libraries; its successor exists only as a release candidate
//! (0.7.0-rc2). The XML we need is one element per array, so it is written here
//! directly (about a hundred lines), with no dependency.

mod pvd;
mod unstructured;

pub use pvd::{pvd_string, write_pvd};
pub use unstructured::{vtu_string, write_vtu, Coordinates, VtuFields, VTK_TETRA, VTK_TRIANGLE};

/// Escapes text for an XML attribute value.
pub(crate) fn escape_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}
