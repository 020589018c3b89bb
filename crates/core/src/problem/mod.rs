//! The contracts: what a problem is, independent of how it is discretised or solved.
//!
//! * [`stresses`] — **P**, the admissible generalised stresses (a yield surface, theory §1–§2);
//! * [`displacements`] — **K**, the admissible displacements with their extra unknowns (an
//!   obstacle, theory §1, §3, §8);
//! * [`obstacles`] — several obstacles, K = K₁ ∩ K₂ ∩ … (theory §8): rows and extras
//!   concatenated, each obstacle reporting on its own part;
//! * [`lagrangian`] — **L**, the discrete saddle problem every solver consumes (theory §3), with
//!   the energies and KKT residuals of any iterate;
//! * [`state`] — the plastic state a load step starts from (theory §11);
//! * [`solver`] — the solver interface: [`solver::Solver`], [`solver::Solution`], the report;
//! * [`tensor`], [`elasticity`] — symmetric tensors in Mandel notation and Hooke's law;
//! * [`pattern`] — the sparsity pattern of assembled matrices, as plain data.

pub mod displacements;
pub mod elasticity;
pub mod lagrangian;
pub mod obstacles;
pub mod pattern;
pub mod solver;
pub mod state;
pub mod stresses;
pub mod tensor;
