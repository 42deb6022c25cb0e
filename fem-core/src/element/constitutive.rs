use nalgebra::SMatrix;

/// How a cell's strain maps to stress, and the out-of-plane thickness in 2D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Formulation {
    /// 3D solid (tetrahedra).
    Solid,
    /// 2D plane stress with a thickness [mm] (the seed's choice).
    PlaneStress { thickness_mm: f64 },
    /// 2D plane strain with a thickness [mm] used for forces.
    PlaneStrain { thickness_mm: f64 },
    /// 2D axisymmetric about the y axis: triangles in the `r-y` half-plane
    /// (`r = x >= 0`), strains `[rr, yy, θθ, ry]` (`S = 4`), cell weight `2π r_c A`
    /// (see the module docs of [`crate::element`]).
    Axisymmetric,
}

impl Formulation {
    /// The number of strain components `S` of the formulation: 6, 3 or 4.
    pub fn num_strains(&self) -> usize {
        match self {
            Formulation::Solid => 6,
            Formulation::PlaneStress { .. } | Formulation::PlaneStrain { .. } => 3,
            Formulation::Axisymmetric => 4,
        }
    }

    /// Out-of-plane thickness that multiplies cell areas [mm]; 1 in 3D and for the
    /// axisymmetric formulation, whose weight `2π r_c` varies per cell (use
    /// [`super::cell_geometry_in`]).
    pub fn thickness(&self) -> f64 {
        match *self {
            Formulation::Solid | Formulation::Axisymmetric => 1.0,
            Formulation::PlaneStress { thickness_mm } | Formulation::PlaneStrain { thickness_mm } => thickness_mm,
        }
    }
}

/// The unit-Young constitutive matrix `C1(nu)` split into its Lamé parts,
/// `C1 = lambda1 m m^T + mu1 diag(2, .., 2, 1, .., 1)` (design.md 3.2), Voigt order
/// with engineering shears. Plane stress uses `lambda* = 2 lambda mu/(lambda + 2 mu)`.
/// The axisymmetric matrix (`S = 4`, `[rr, yy, θθ, ry]`) is the 3D one restricted
/// to those components: three normal strains and one shear.
///
/// Panics (a programmer error) when `S` is not the formulation's strain count.
pub fn unit_young_matrix<const S: usize>(formulation: Formulation, poisson: f64) -> SMatrix<f64, S, S> {
    assert_eq!(S, formulation.num_strains(), "{formulation:?} has {} strain components", formulation.num_strains());
    // Normal strain components: the shears follow them.
    let d = match formulation {
        Formulation::PlaneStress { .. } | Formulation::PlaneStrain { .. } => 2,
        Formulation::Solid | Formulation::Axisymmetric => 3,
    };
    let nu = poisson;
    let mu = 0.5 / (1.0 + nu);
    let lambda3 = nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let lambda = match formulation {
        Formulation::PlaneStress { .. } => 2.0 * lambda3 * mu / (lambda3 + 2.0 * mu),
        _ => lambda3,
    };
    let mut c = SMatrix::<f64, S, S>::zeros();
    for i in 0..d {
        for j in 0..d {
            c[(i, j)] = lambda;
        }
        c[(i, i)] += 2.0 * mu;
    }
    for k in d..S {
        c[(k, k)] = mu;
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniaxial stress: with the lateral stresses zero, s_yy / e_yy = E = 1 and the
    /// lateral strains are -nu e_yy, in 3D and in plane stress.
    #[test]
    fn uniaxial_response_is_unit_young() {
        let nu = 0.3746;
        let c = unit_young_matrix::<6>(Formulation::Solid, nu);
        let e = nalgebra::SVector::<f64, 6>::from([-nu, 1.0, -nu, 0.0, 0.0, 0.0]);
        let s = c * e;
        assert!((s[1] - 1.0).abs() < 1e-14 && s[0].abs() < 1e-14 && s[2].abs() < 1e-14);
        let c2 = unit_young_matrix::<3>(Formulation::PlaneStress { thickness_mm: 1.0 }, nu);
        let s2 = c2 * nalgebra::Vector3::new(-nu, 1.0, 0.0);
        assert!((s2[1] - 1.0).abs() < 1e-14 && s2[0].abs() < 1e-14);
    }

    /// The axisymmetric matrix is the 3D matrix restricted to `[xx, yy, zz, xy]`
    /// (= `[rr, yy, θθ, ry]`), entry by entry.
    #[test]
    fn axisymmetric_matrix_is_the_restricted_solid_matrix() {
        for nu in [-0.5, 0.0, 0.3746, 0.49] {
            let c3 = unit_young_matrix::<6>(Formulation::Solid, nu);
            let ca = unit_young_matrix::<4>(Formulation::Axisymmetric, nu);
            for i in 0..4 {
                for j in 0..4 {
                    assert_eq!(ca[(i, j)].to_bits(), c3[(i, j)].to_bits(), "nu = {nu}, ({i}, {j})");
                }
            }
        }
    }

    #[test]
    #[should_panic(expected = "strain components")]
    fn strain_count_must_match_the_formulation() {
        let _ = unit_young_matrix::<3>(Formulation::Axisymmetric, 0.3);
    }
}
