//! Friction laws (theory §8.3), plugins of [`saddle_core::FrictionLaw`] chosen by `type` in an
//! obstacle's `friction` table, one file per law: [`tresca`] (`type = "tresca"`, a given slip
//! bound g per area).

pub mod tresca;

pub use tresca::Tresca;
