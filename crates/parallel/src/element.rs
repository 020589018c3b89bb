//! A rank's element operators with the ghost exchange inside (theory §12): ε = B u of the
//! rank's elements from its owned dofs (the ghosts' values fetched from their owners), and
//! Bᵀσ at its owned dofs (the ghosts' contributions added at their owners). Solvers see the
//! owned dofs only, and reduce through [`crate::MpiComm`]; assembly is the rank's elements' on
//! its local pattern, summed over the ranks by [`crate::PetscSpd`].

use crate::comm::MpiComm;
use crate::funneled::{Funneled, Session};
use crate::layout::Layout;
use crate::spd::PetscSpd;
use saddle_core::fem::{Discretisation, VtkCell};
use saddle_core::linalg::{DistributedError, DistributedSpd};
use saddle_core::mesh::TetMesh;
use saddle_core::mesh::dofs::DofMap;
use saddle_core::problem::comm::Comm;
use saddle_core::problem::operators::{ElementOperators, Material, RigidBodyModes};
use saddle_core::problem::pattern::SymmetricPattern;
use saddle_core::problem::tensor::Sym;
use saddle_mpi::GhostVector;
use std::cell::RefCell;
use std::sync::{Arc, Mutex};

/// A rank's element operators (module docs).
pub struct DistributedElement {
    element: Box<dyn Discretisation>,
    layout: Arc<Layout>,
    comm: MpiComm,
    session: Session,
    /// The exchange vector: three entries per local node.
    vector: Funneled<RefCell<GhostVector>>,
    /// The local free dofs' values (owned and ghost).
    local: Mutex<Vec<f64>>,
}

impl std::fmt::Debug for DistributedElement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "DistributedElement({:?}, {} owned dofs, rank {})",
            self.element.name(),
            self.layout.n_owned_dofs,
            self.comm.rank()
        )
    }
}

/// An internal PETSc failure of the ghost exchange: not a user error, and the trait methods
/// return nothing; the panic aborts every rank (`saddle-mpi`).
fn exchange_failed(e: saddle_mpi::Error) -> ! {
    panic!("ghost exchange failed: {e}")
}

impl DistributedElement {
    /// The operators of `element` (built on a rank's part of the mesh with its dof numbering)
    /// with `layout`; `session` must outlive the result. Collective.
    pub fn new(
        session: &saddle_mpi::Petsc,
        element: Box<dyn Discretisation>,
        layout: Arc<Layout>,
    ) -> saddle_mpi::Result<Self> {
        let vector = layout.vector(session)?;
        let local = vec![0.0; layout.n_local_dofs()];
        Ok(Self {
            element,
            comm: MpiComm::new(session),
            session: Session(session),
            vector: Funneled(RefCell::new(vector)),
            local: Mutex::new(local),
            layout,
        })
    }

    /// The layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The values of the owned dofs `owned` at every local dof, the ghosts' from their owners.
    /// Collective.
    pub fn ghosted(&self, owned: &[f64], local: &mut [f64]) {
        let mut v = self.vector.0.borrow_mut();
        {
            let mut form = v.local_mut().unwrap_or_else(|e| exchange_failed(e));
            form.iter_mut().for_each(|x| *x = 0.0);
            for (d, &x) in owned.iter().enumerate() {
                form[self.layout.dof_slot[d]] = x;
            }
        }
        v.update_ghosts().unwrap_or_else(|e| exchange_failed(e));
        let form = v.local().unwrap_or_else(|e| exchange_failed(e));
        for (x, &s) in local.iter_mut().zip(&self.layout.dof_slot) {
            *x = form[s];
        }
    }

    /// The sums at the owned dofs of the values `local` every rank holds at its local dofs.
    /// Collective.
    pub fn accumulated(&self, local: &[f64], owned: &mut [f64]) {
        let mut v = self.vector.0.borrow_mut();
        {
            let mut form = v.local_mut().unwrap_or_else(|e| exchange_failed(e));
            form.iter_mut().for_each(|x| *x = 0.0);
            for (&x, &s) in local.iter().zip(&self.layout.dof_slot) {
                form[s] += x;
            }
        }
        v.accumulate_ghosts().unwrap_or_else(|e| exchange_failed(e));
        let form = v.local().unwrap_or_else(|e| exchange_failed(e));
        for (d, x) in owned.iter_mut().enumerate() {
            *x = form[self.layout.dof_slot[d]];
        }
    }
}

impl ElementOperators for DistributedElement {
    /// The owned free dofs.
    fn n_dofs(&self) -> usize {
        self.layout.n_owned_dofs
    }
    /// The points of this rank's elements.
    fn n_points(&self) -> usize {
        self.element.n_points()
    }
    fn weights(&self) -> &[f64] {
        self.element.weights()
    }
    fn strain(&self, u: &[f64], eps: &mut [Sym]) {
        let mut local = self.local.lock().unwrap_or_else(|e| e.into_inner());
        self.ghosted(u, &mut local);
        self.element.strain(&local, eps);
    }
    fn divergence(&self, sigma: &[Sym], f: &mut [f64]) {
        let mut local = self.local.lock().unwrap_or_else(|e| e.into_inner());
        self.element.divergence(sigma, &mut local);
        self.accumulated(&local, f);
    }
    /// B's entries on this rank's local dofs (not its owned numbering: conic solvers, which
    /// need B whole, refuse distributed problems).
    fn strain_entries(&self) -> Vec<(usize, usize, usize, f64)> {
        self.element.strain_entries()
    }
    /// This rank's local pattern (owned and ghost dofs).
    fn pattern(&self) -> &SymmetricPattern {
        self.element.pattern()
    }
    /// This rank's elements' values on its local pattern.
    fn assemble(&self, material: Material<'_>, values: &mut [f64]) {
        self.element.assemble(material, values)
    }
    /// None: the distributed solver builds the near-null space itself.
    fn rigid_body_modes(&self) -> Option<RigidBodyModes> {
        None
    }
    fn comm(&self) -> &dyn Comm {
        &self.comm
    }
    fn is_distributed(&self) -> bool {
        true
    }
    fn distributed_solver(&self) -> Option<Result<Box<dyn DistributedSpd>, DistributedError>> {
        Some(
            PetscSpd::new(self.session.get(), self.layout.clone())
                .map(|s| Box::new(s) as Box<dyn DistributedSpd>)
                .map_err(|e| Box::new(e) as DistributedError),
        )
    }
}

impl Discretisation for DistributedElement {
    /// This rank's part of the mesh: its elements on its local nodes.
    fn mesh(&self) -> &TetMesh {
        self.element.mesh()
    }
    /// This rank's local dof numbering (owned dofs first, then the ghosts').
    fn dofs(&self) -> &DofMap {
        self.element.dofs()
    }
    fn name(&self) -> &'static str {
        self.element.name()
    }
    fn vtk_cell(&self) -> VtkCell {
        self.element.vtk_cell()
    }
    /// At every local node, the ghosts' values from their owners. Collective.
    fn nodal_vectors(&self, u: &[f64]) -> Vec<[f64; 3]> {
        let mut local = vec![0.0; self.layout.n_local_dofs()];
        self.ghosted(u, &mut local);
        self.element.nodal_vectors(&local)
    }
    fn points_per_element(&self) -> usize {
        self.element.points_per_element()
    }
    fn locks(&self) -> bool {
        self.element.locks()
    }
    fn degree(&self) -> usize {
        self.element.degree()
    }
}
