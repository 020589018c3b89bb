//! Friction laws (theory §8.3), plugins of [`saddle_core::FrictionLaw`] chosen by `type` in an
//! obstacle's `friction` table, one file per law: [`tresca`] (`type = "tresca"`, a given slip
//! bound g per area) and [`coulomb`] (`type = "coulomb"`, the bound μ λ_n).

pub mod coulomb;
pub mod tresca;

pub use coulomb::Coulomb;
pub use tresca::Tresca;
