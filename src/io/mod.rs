//! Reading and writing files: scene files in, `summary.json`, `solution.vtu` and plots out, and
//! the output folder a run owns. Nothing here runs a solver or a study ([`crate::app`],
//! [`crate::studies`] build on it).
//!
//! | module | files |
//! |---|---|
//! | [`scene`] | a scene file (TOML) read and validated into a typed [`scene::Scene`] |
//! | [`summary`] | `summary.json`: the numbers of a solve, with the locking indicator ([`summary::locking`]) |
//! | [`vtu`] | `solution.vtu`: the fields for ParaView |
//! | [`outdir`] | the output folder: claimed before a run, holding only the run's files after it |
//! | `plot` | PNG and SVG plots (feature `report`) |
//! | [`csv`] | CSV cells of the studies' tables |

pub mod csv;
pub mod outdir;
#[cfg(feature = "report")]
pub mod plot;
pub mod scene;
mod scene_de;
pub mod summary;
pub mod vtu;
