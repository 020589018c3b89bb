//! Symmetric 3×3 tensors in Mandel notation (theory §1–§2).
//!
//! A symmetric tensor `a` is stored as `(a11, a22, a33, √2 a23, √2 a13, √2 a12)`. With this
//! scaling the Euclidean dot product of two vectors is the double contraction `a:b`, the
//! Euclidean norm is the Frobenius norm `|a|` of theory §1, and fourth-order tensors with the
//! minor symmetries are plain symmetric 6×6 matrices.

use nalgebra::{Matrix3, Matrix6, Vector6};

/// A symmetric second-order tensor (stress or strain) in Mandel notation.
pub type Sym = Vector6<f64>;
/// A fourth-order tensor with minor symmetries (elasticity, tangent) as a 6×6 Mandel matrix.
pub type SymOp = Matrix6<f64>;

/// √2, the Mandel weight of the off-diagonal components.
pub const SQRT2: f64 = std::f64::consts::SQRT_2;

/// The identity tensor I.
pub fn identity() -> Sym {
    Sym::new(1.0, 1.0, 1.0, 0.0, 0.0, 0.0)
}

/// tr a.
#[inline]
pub fn trace(a: &Sym) -> f64 {
    a[0] + a[1] + a[2]
}

/// dev a = a − (tr a / 3) I.
#[inline]
pub fn deviator(a: &Sym) -> Sym {
    let m = trace(a) / 3.0;
    Sym::new(a[0] - m, a[1] - m, a[2] - m, a[3], a[4], a[5])
}

/// The von Mises equivalent stress sqrt(3/2) |dev σ|.
#[inline]
pub fn von_mises(sigma: &Sym) -> f64 {
    (1.5f64).sqrt() * deviator(sigma).norm()
}

/// The deviatoric projector I_dev (dev a = I_dev a).
pub fn deviatoric_projector() -> SymOp {
    SymOp::identity() - volumetric_projector()
}

/// The volumetric projector (1/3) I ⊗ I.
pub fn volumetric_projector() -> SymOp {
    let i = identity();
    i * i.transpose() / 3.0
}

/// The 3×3 matrix of a Mandel vector.
pub fn to_matrix(a: &Sym) -> Matrix3<f64> {
    let s = 1.0 / SQRT2;
    Matrix3::new(a[0], s * a[5], s * a[4], s * a[5], a[1], s * a[3], s * a[4], s * a[3], a[2])
}

/// The Mandel vector of the symmetric part of a 3×3 matrix.
pub fn from_matrix(m: &Matrix3<f64>) -> Sym {
    let s = SQRT2 / 2.0;
    Sym::new(
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        s * (m[(1, 2)] + m[(2, 1)]),
        s * (m[(0, 2)] + m[(2, 0)]),
        s * (m[(0, 1)] + m[(1, 0)]),
    )
}

/// Components in VTK's order for symmetric tensors: xx, yy, zz, xy, yz, xz.
pub fn to_vtk(a: &Sym) -> [f64; 6] {
    let s = 1.0 / SQRT2;
    [a[0], a[1], a[2], s * a[5], s * a[3], s * a[4]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mandel_dot_is_double_contraction() {
        let a = Matrix3::new(1.0, 2.0, 3.0, 2.0, -4.0, 5.0, 3.0, 5.0, 6.0);
        let b = Matrix3::new(0.5, -1.0, 2.0, -1.0, 3.0, 0.25, 2.0, 0.25, -2.0);
        let contraction: f64 = a.component_mul(&b).sum();
        assert!((from_matrix(&a).dot(&from_matrix(&b)) - contraction).abs() < 1e-12);
        assert!((to_matrix(&from_matrix(&a)) - a).norm() < 1e-14);
        assert!((from_matrix(&a).norm() - a.norm()).abs() < 1e-12);
    }

    #[test]
    fn deviator_is_traceless_and_projector_agrees() {
        let a = Sym::new(1.0, 2.0, 7.0, 0.3, -0.2, 0.1);
        assert!(trace(&deviator(&a)).abs() < 1e-14);
        assert!((deviatoric_projector() * a - deviator(&a)).norm() < 1e-14);
        // uniaxial stress: von Mises equals |σ11|
        assert!((von_mises(&Sym::new(-3.0, 0.0, 0.0, 0.0, 0.0, 0.0)) - 3.0).abs() < 1e-14);
    }
}
