//! The lifting u_D of prescribed displacements (theory §14): u = u_D + w, w = 0 on Γ_D; the
//! problem's data carries it so that the local law sees the strain of u.

use crate::problem::tensor::Sym;

/// The lifting of a problem at its load factor (theory §14): nodal values u_D and their strain
/// ε(u_D) at factor 1, and the factor. Empty for homogeneous conditions.
#[derive(Clone, Copy, Debug)]
pub struct Lifting<'a> {
    /// u_D per node at factor 1 (empty: none).
    pub nodal: &'a [[f64; 3]],
    /// ε(u_D) per stress point at factor 1 (empty: none).
    pub strain: &'a [Sym],
    /// The load factor the lifting is taken at.
    pub factor: f64,
}

impl Default for Lifting<'_> {
    fn default() -> Self {
        Self { nodal: &[], strain: &[], factor: 1.0 }
    }
}

impl Lifting<'_> {
    /// eps += factor · ε(u_D): the strain of w made the strain of u.
    pub fn add_strain(&self, eps: &mut [Sym]) {
        for (e, d) in eps.iter_mut().zip(self.strain) {
            *e += d * self.factor;
        }
    }

    /// nodal += factor · u_D: nodal values of w made those of u.
    pub fn add_nodal(&self, nodal: &mut [[f64; 3]]) {
        for (x, d) in nodal.iter_mut().zip(self.nodal) {
            for c in 0..3 {
                x[c] += self.factor * d[c];
            }
        }
    }
}
