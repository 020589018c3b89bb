//! The contracts: what a problem is, independent of how it is discretised or solved.
//!
//! * [`stresses`] — **P**, the admissible generalised stresses (a yield surface, theory §1–§2);
//! * [`displacements`] — **K**, the admissible displacements with their extra unknowns (an
//!   obstacle, theory §1, §3, §8), and rows recombined from nodal rows (theory §10.1);
//! * [`obstacles`] — several obstacles, K = K₁ ∩ K₂ ∩ … (theory §8): rows and extras
//!   concatenated, each obstacle reporting on its own part;
//! * [`comm`] — reductions over the ranks of a distributed problem (the identity on one process);
//! * [`operators`] — the element's operators: stress points, ε = B u, Bᵀσ, assembly (theory §3);
//! * [`lagrangian`] — **L**, the discrete saddle problem every solver consumes (theory §3): the
//!   element's operators with the problem's data;
//! * [`energies`], [`kkt`] — the energies and KKT residuals of any iterate, free functions of L;
//! * [`fields`] — fields at the stress points: stresses σ̂ and the plastic state a load step
//!   starts from (theory §11);
//! * [`return_mapping`] — the steps yield surfaces' return mappings share;
//! * [`slip`] — the friction rows' slip history along a load path (theory §11.6);
//! * [`solver`] — the solver interface: [`solver::Solver`], [`solver::Solution`], the report;
//! * [`tensor`], [`elasticity`] — symmetric tensors in Mandel notation and Hooke's law;
//! * [`pattern`] — the sparsity pattern of assembled matrices, as plain data.

pub mod comm;
pub mod displacements;
pub mod elasticity;
pub mod energies;
pub mod fields;
pub mod friction;
pub mod kkt;
pub mod lagrangian;
pub mod lifting;
pub mod load_factors;
pub mod obstacles;
pub mod operators;
pub mod pattern;
pub mod return_mapping;
pub mod slip;
pub mod solver;
pub mod stresses;
pub mod tensor;
