//! Set-ups shared by the contact test files.

use fem_core::press::{AnyPress, PressProblem, Tool, ToolContact};

/// The same problem with the protocol's plate replaced by a plate tool.
pub fn with_plate_tool(problem: &AnyPress, contact: ToolContact) -> AnyPress {
    fn swap<const D: usize, const N: usize, const S: usize>(
        p: &PressProblem<D, N, S>,
        contact: ToolContact,
    ) -> PressProblem<D, N, S>
    where
        fem_core::element::Simplex<D, N>: fem_core::element::ReferenceSimplex<D, N>,
    {
        let (lo, hi) = p.mesh.bounding_box();
        let lo3 = std::array::from_fn(|k| if k < D { lo[k] } else { 0.0 });
        let hi3 = std::array::from_fn(|k| if k < D { hi[k] } else { 0.0 });
        let tool = Tool::plate_above("plate", lo3, hi3, &p.protocol.waypoints, contact, p.protocol.release_s);
        let mut q = p.clone();
        q.tools = vec![tool];
        q
    }
    match problem {
        AnyPress::Plane(p) => AnyPress::Plane(swap(p, contact)),
        AnyPress::Solid(p) => AnyPress::Solid(swap(p, contact)),
        AnyPress::Axisymmetric(p) => AnyPress::Axisymmetric(swap(p, contact)),
    }
}
