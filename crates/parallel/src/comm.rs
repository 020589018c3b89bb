//! Core's reductions on MPI's world (theory §12). A reduction is reduced over every rank and
//! then broadcast from rank 0, so that every rank holds the same bits and takes the same
//! decision on it (MPI's all-reduce does not promise identical results everywhere).

use crate::funneled::Funneled;
use saddle_core::problem::comm::Comm;
use saddle_mpi::mpi::collective::SystemOperation;
use saddle_mpi::mpi::datatype::Equivalence;
use saddle_mpi::mpi::topology::SimpleCommunicator;
use saddle_mpi::mpi::traits::{Communicator, CommunicatorCollectives, Root};

/// MPI's world as a [`Comm`].
pub struct MpiComm {
    world: Funneled<SimpleCommunicator>,
}

impl std::fmt::Debug for MpiComm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MpiComm(rank {} of {})", self.rank(), self.size())
    }
}

impl MpiComm {
    /// The world of `session`.
    pub fn new(session: &saddle_mpi::Petsc) -> Self {
        Self { world: Funneled(session.world().duplicate()) }
    }

    /// The communicator.
    pub fn world(&self) -> &SimpleCommunicator {
        &self.world.0
    }

    /// `op` of `values` over the ranks, entrywise, the same on every rank.
    fn reduce<T: Equivalence + Copy>(&self, values: &mut [T], op: SystemOperation) {
        let send = values.to_vec();
        self.world.0.all_reduce_into(&send[..], values, op);
        self.world.0.process_at_rank(0).broadcast_into(values);
    }
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.world.0.rank() as usize
    }

    fn size(&self) -> usize {
        self.world.0.size() as usize
    }

    fn sum(&self, x: f64) -> f64 {
        let mut v = [x];
        self.reduce(&mut v, SystemOperation::sum());
        v[0]
    }

    fn sum_in_place(&self, x: &mut [f64]) {
        self.reduce(x, SystemOperation::sum());
    }

    fn sum_count(&self, x: usize) -> usize {
        let mut v = [x as u64];
        self.reduce(&mut v, SystemOperation::sum());
        v[0] as usize
    }

    fn max(&self, x: f64) -> f64 {
        if self.any(x.is_nan()) {
            return f64::NAN;
        }
        let mut v = [x];
        self.reduce(&mut v, SystemOperation::max());
        v[0]
    }

    fn min(&self, x: f64) -> f64 {
        if self.any(x.is_nan()) {
            return f64::NAN;
        }
        let mut v = [x];
        self.reduce(&mut v, SystemOperation::min());
        v[0]
    }

    fn any(&self, b: bool) -> bool {
        let mut v = [b as u8];
        self.reduce(&mut v, SystemOperation::max());
        v[0] != 0
    }
}
