//! Set-ups shared by the contact test files (`contact.rs`, `compliance.rs`,
//! `material_point_contact.rs`, `adhesion.rs`): the block in the three
//! formulations, effects and protocol swapped in, the plate replaced by a plate
//! tool, the cohesive series closed form.
//!
//! Each test file includes this module as its own copy, and not every file uses
//! every helper: unused ones would fail `-D warnings` (dead_code), as in the io
//! and cli test modules.
#![allow(dead_code)]

use fem_core::effects::Effects;
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{
    AnyPress, Attachment, AxisymmetricPress, PlanePress, PressProblem, Protocol, SolidPress, Tool, ToolContact,
};

/// A linear elastic material (`e_mpa` [MPa], Poisson's ratio `nu`).
pub fn elastic(e_mpa: f64, nu: f64) -> Material {
    Material::new(Rheology::Elastic { e_mpa }, nu).unwrap()
}

/// A `w` x `h` [mm] block of material `m` under `protocol`: in plane stress
/// (thickness `t` [mm], 2.5 mm cells), axisymmetric (a cylinder of radius `w/2`,
/// 2.5 mm cells) and 3D (`w` x `h` x `t`, 5 mm cells), named `plane`,
/// `axisymmetric` and `solid`.
pub fn problems(m: &Material, protocol: &Protocol, [w, h, t]: [f64; 3]) -> Vec<(&'static str, AnyPress)> {
    vec![
        (
            "plane",
            AnyPress::Plane(
                PlanePress::new_2d(mesh::rectangle(w, h, 2.5, "m").unwrap(), t, vec![m.clone()], protocol.clone())
                    .unwrap(),
            ),
        ),
        (
            "axisymmetric",
            AnyPress::Axisymmetric(
                AxisymmetricPress::new_axisymmetric(
                    mesh::axisymmetric_section(w / 2.0, h, 2.5, "m").unwrap(),
                    vec![m.clone()],
                    protocol.clone(),
                )
                .unwrap(),
            ),
        ),
        (
            "solid",
            AnyPress::Solid(
                SolidPress::new_3d(mesh::block([w, h, t], 5.0, "m").unwrap(), vec![m.clone()], protocol.clone())
                    .unwrap(),
            ),
        ),
    ]
}

/// Replaces the problem's effects.
pub fn set_effects(p: &mut AnyPress, effects: &Effects) {
    match p {
        AnyPress::Plane(p) => p.effects = effects.clone(),
        AnyPress::Solid(p) => p.effects = effects.clone(),
        AnyPress::Axisymmetric(p) => p.effects = effects.clone(),
    }
}

/// Replaces the problem's protocol.
pub fn set_protocol(p: &mut AnyPress, protocol: &Protocol) {
    match p {
        AnyPress::Plane(p) => p.protocol = protocol.clone(),
        AnyPress::Solid(p) => p.protocol = protocol.clone(),
        AnyPress::Axisymmetric(p) => p.protocol = protocol.clone(),
    }
}

/// Ramp 1.5 mm in 10 s, hold to 30 s, release, recover to 60 s.
pub fn ramp_hold_release(plate: Attachment, support: Attachment) -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.15, 10.0, 30.0, 60.0);
    p.plate = plate;
    p.support = support;
    p
}

/// The plane-stress problem of `p` (which must be one).
pub fn as_plane(p: AnyPress) -> PlanePress {
    match p {
        AnyPress::Plane(p) => p,
        _ => panic!("not a plane-stress problem"),
    }
}

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

/// The plate force (compression positive) of a spring `k` in series with the
/// rigid-linear cohesive law (strength `s` N, critical opening `dc`) at the plate
/// displacement `d` (down positive), on the loading path: bonded while
/// `k d >= -s`; then `F = -k (s + S d)/(k - S)` with `S = s/dc` (stable: `k > S`)
/// until the opening `-d` reaches `dc`; zero beyond.
pub fn series_force(k: f64, s: f64, dc: f64, d: f64) -> f64 {
    let stiffness = s / dc;
    if k * d >= -s {
        k * d
    } else if -d < dc {
        -k * (s + stiffness * d) / (k - stiffness)
    } else {
        0.0
    }
}
