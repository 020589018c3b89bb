//! The element's operators (theory §3): what a finite element — or a distributed implementation
//! of one — provides to L. Stress points with weights w_T, the strain operator ε = B u, its
//! transpose (the internal forces Bᵀσ), and the assembly of `Σ_T w_T B_Tᵀ C_T B_T` on a fixed
//! pattern. Nothing here knows the material, the obstacles or the loads: those are the problem's
//! data ([`crate::problem::lagrangian::Data`]).

use crate::linalg::distributed::{DistributedError, DistributedSpd};
use crate::problem::comm::{Comm, SERIAL};
use crate::problem::pattern::SymmetricPattern;
use crate::problem::tensor::{Sym, SymOp};
use std::fmt::Debug;

/// Number of rigid-body motions in 3D: three translations, three rotations.
pub const RIGID_BODY_MODES: usize = 6;

/// The rigid-body motions restricted to the free dofs, with the node each dof belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBodyModes {
    /// The node of every free dof: the dofs of one node form a block.
    pub node: Vec<u32>,
    /// Row-major `n × 6`: translations e_x, e_y, e_z and rotations ω × (x − x̄) about the axes
    /// through the centroid x̄ of the nodes.
    pub modes: Vec<f64>,
}

impl RigidBodyModes {
    /// The modes of the free dofs with nodes `node` and components `comp`, the nodes at `coords`.
    pub fn new(node: Vec<u32>, comp: &[u8], coords: &[[f64; 3]]) -> Self {
        let directions: Vec<[f64; 3]> =
            comp.iter().map(|&c| std::array::from_fn(|k| (k == c as usize) as u8 as f64)).collect();
        Self::along(node, &directions, coords)
    }

    /// The modes of the free dofs with nodes `node` along the unit `directions` (e_c, or a row of
    /// the node's frame, theory §14.4), the nodes at `coords`.
    pub fn along(node: Vec<u32>, directions: &[[f64; 3]], coords: &[[f64; 3]]) -> Self {
        let n = node.len();
        let mut centroid = [0.0; 3];
        for &nd in &node {
            for (c, x) in centroid.iter_mut().zip(coords[nd as usize]) {
                *c += x / n.max(1) as f64;
            }
        }
        let mut modes = vec![0.0; n * RIGID_BODY_MODES];
        for (d, row) in modes.chunks_exact_mut(RIGID_BODY_MODES).enumerate() {
            let x = coords[node[d] as usize];
            let [x, y, z] = [x[0] - centroid[0], x[1] - centroid[1], x[2] - centroid[2]];
            let v = directions[d];
            row[..3].copy_from_slice(&v);
            // v·(ω × x) for ω = e_x, e_y, e_z: ω × x = (0, −z, y), (z, 0, −x), (−y, x, 0)
            row[3] = -z * v[1] + y * v[2];
            row[4] = z * v[0] - x * v[2];
            row[5] = -y * v[0] + x * v[1];
        }
        Self { node, modes }
    }

    /// Number of free dofs.
    pub fn n(&self) -> usize {
        self.node.len()
    }
}

/// The element-constant pressure of an element whose volumetric strain is one value per element
/// (B̄, theory §10.1): `tr ε_q(u) = (B u)_e / |T_e|` at every stress point q of element e, with
/// B's row e = ∫_{T_e} div N_j. The stiffness then splits as K = A + Bᵀ C⁻¹ B, the volumetric
/// part of every point's tangent carried by the element's pressure (theory §10.1, the pressure
/// block): what a block preconditioner for nearly incompressible tangents needs.
#[derive(Clone, Debug, PartialEq)]
pub struct PressureRows {
    /// Row pointers of B (one row per element).
    pub ptr: Vec<usize>,
    /// Free dofs of each row.
    pub dof: Vec<u32>,
    /// ∫_T div N_j of each entry.
    pub val: Vec<f64>,
    /// |T_e|.
    pub volume: Vec<f64>,
    /// Stress points per element: those of row e are `points·e .. points·(e + 1)`.
    pub points: usize,
}

impl PressureRows {
    /// Number of rows (elements).
    pub fn n_rows(&self) -> usize {
        self.volume.len()
    }
}

/// The material of an assembly: one tensor for all points, or one per point.
#[derive(Clone, Copy, Debug)]
pub enum Material<'a> {
    /// The same 6×6 Mandel matrix at every point.
    Uniform(&'a SymOp),
    /// One matrix per stress point (consistent tangents).
    PerPoint(&'a [SymOp]),
}

impl Material<'_> {
    /// The matrix at point `i`.
    #[inline]
    pub fn at(&self, i: usize) -> &SymOp {
        match self {
            Material::Uniform(c) => c,
            Material::PerPoint(cs) => &cs[i],
        }
    }
}

/// The element's operators (theory §3): stress points and weights, ε = B u, Bᵀσ and the
/// assembly of Bᵀ C B. A new element implements this trait (and
/// [`crate::fem::Discretisation`] for output); so does a distributed implementation, whose
/// dofs and points are its rank's.
pub trait ElementOperators: Debug + Send + Sync {
    /// Number of free displacement dofs (the dimension of W_h).
    fn n_dofs(&self) -> usize;
    /// Number of stress points.
    fn n_points(&self) -> usize;
    /// Quadrature weights w_T of the stress points.
    fn weights(&self) -> &[f64];
    /// ε_T = (B u)_T at every point (theory §3).
    fn strain(&self, u: &[f64], eps: &mut [Sym]);
    /// f = Σ_T w_T B_Tᵀ σ_T: the internal forces of a stress field (Bᵀ of theory §3).
    fn divergence(&self, sigma: &[Sym], f: &mut [f64]);
    /// The strain operator B as explicit entries `(point, component, dof, value)`:
    /// `ε_T[c] = Σ value · u[dof]` (Mandel components), for solvers that need B as a matrix
    /// (conic formulations).
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)>;
    /// Sparsity pattern of assembled matrices (lower triangle).
    fn pattern(&self) -> &SymmetricPattern;
    /// values = Σ_T w_T B_Tᵀ C_T B_T on [`ElementOperators::pattern`].
    fn assemble(&self, material: Material<'_>, values: &mut [f64]);

    /// [`ElementOperators::assemble`] into `values` that hold the assembly of an earlier
    /// material equal to `reference` at every point of the elements not in `was_off` (empty:
    /// nothing known, everything assembled); `was_off` becomes the elements where `material`
    /// differs from `reference`. An element may keep the values that no element in either set
    /// touches (theory §4.2: a plastic tangent differs from the elastic one in the plastic zone
    /// only); the result is the full assembly's, bit for bit. The default assembles everything.
    fn reassemble(&self, material: Material<'_>, reference: &SymOp, was_off: &mut Vec<bool>, values: &mut [f64]) {
        let _ = reference;
        was_off.clear();
        self.assemble(material, values);
    }

    /// The rigid-body motions on the free dofs (the near-nullspace of the elastic stiffness,
    /// what a multigrid preconditioner must reproduce); `None` when the element has no nodal
    /// dofs.
    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        None
    }

    /// The element-constant volumetric strain as rows of B ([`PressureRows`]), for elements
    /// whose trace of ε is one value per element (B̄); `None` (the default) otherwise.
    fn pressure_rows(&self) -> Option<PressureRows> {
        None
    }

    /// The assembled matrix Σ_T w_T B_Tᵀ C_T B_T (values on the pattern).
    fn stiffness(&self, material: Material<'_>) -> Vec<f64> {
        let mut v = vec![0.0; self.pattern().nnz()];
        self.assemble(material, &mut v);
        v
    }

    /// The reductions over the ranks that share the problem (theory §12): the identity on one
    /// process. A distributed implementation holds a rank's points and owned dofs; its
    /// [`ElementOperators::pattern`] and [`ElementOperators::assemble`] are then those of the
    /// rank's elements over its owned and ghost dofs.
    fn comm(&self) -> &dyn Comm {
        &SERIAL
    }

    /// The distributed solver of matrices assembled on this pattern (theory §12), for a
    /// distributed implementation; `None` on one process, where solvers factor or precondition
    /// the assembled values themselves.
    fn distributed_solver(&self) -> Option<Result<Box<dyn DistributedSpd>, DistributedError>> {
        None
    }

    /// Whether this is a rank's part of a distributed problem (theory §12): solvers choose their
    /// distributed linear algebra by it, without building [`ElementOperators::distributed_solver`].
    fn is_distributed(&self) -> bool {
        false
    }
}
