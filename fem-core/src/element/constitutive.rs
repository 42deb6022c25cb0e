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
}

impl Formulation {
    /// Out-of-plane thickness that multiplies cell areas [mm]; 1 in 3D.
    pub fn thickness(&self) -> f64 {
        match *self {
            Formulation::Solid => 1.0,
            Formulation::PlaneStress { thickness_mm } | Formulation::PlaneStrain { thickness_mm } => thickness_mm,
        }
    }
}

/// The unit-Young constitutive matrix `C1(nu)` split into its Lamé parts,
/// `C1 = lambda1 m m^T + mu1 diag(2, .., 2, 1, .., 1)` (design.md 3.2), Voigt order
/// with engineering shears. Plane stress uses `lambda* = 2 lambda mu/(lambda + 2 mu)`.
pub fn unit_young_matrix<const S: usize>(formulation: Formulation, poisson: f64) -> SMatrix<f64, S, S> {
    let d = match S {
        3 => 2,
        6 => 3,
        _ => panic!("unsupported strain size {S}"),
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
}
