//! Stage 2a of a limit analysis (theory §13.1): the yield surface's set D as cone blocks on the
//! unknowns of a point, (σ, a) — second-order cones (`AdmissibleStresses::cone`) or, with the
//! feature `sdp`, semidefinite blocks with auxiliary variables a
//! (`AdmissibleStresses::semidefinite_cone`) — with the hardening variables fixed at 0.

use super::LimitError;
use clarabel::solver::{SecondOrderConeT, SupportedConeT};
use saddle_core::{AdmissibleStresses, DiscreteProblem};

/// The kind of a cone block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum BlockKind {
    /// A second-order cone of this dimension.
    SecondOrder(usize),
    /// The scaled upper triangle of an n × n positive-semidefinite matrix.
    Semidefinite(usize),
}

/// One block: `offset + map·(σ, a)` lies in the cone `kind`.
#[derive(Clone, Debug)]
pub(super) struct YieldBlock {
    /// The cone.
    pub kind: BlockKind,
    /// Constant part, one entry per row.
    pub offset: Vec<f64>,
    /// Linear part, rows × width row-major, on (σ Mandel, a).
    pub map: Vec<f64>,
}

impl YieldBlock {
    /// The cone for Clarabel.
    pub fn cone(&self) -> SupportedConeT<f64> {
        match self.kind {
            BlockKind::SecondOrder(dim) => SecondOrderConeT(dim),
            #[cfg(feature = "sdp")]
            BlockKind::Semidefinite(n) => clarabel::solver::PSDTriangleConeT(n),
            #[cfg(not(feature = "sdp"))]
            BlockKind::Semidefinite(_) => unreachable!("semidefinite blocks are refused without the feature sdp"),
        }
    }
}

/// D's blocks, the width of a point's unknowns (6 + auxiliary variables) and warnings.
pub(super) struct YieldCones {
    /// The blocks.
    pub blocks: Vec<YieldBlock>,
    /// Entries of (σ, a) per point.
    pub width: usize,
    /// Hardening ignored.
    pub warnings: Vec<String>,
}

impl YieldCones {
    /// Stage 2a (theory §13.1): the cone blocks of the scene's yield surface, each block's map on
    /// (σ, a) alone (the hardening columns dropped: q = 0), checked; errors for an elastic scene
    /// or a yield surface without a conic form (or with a semidefinite one in a build without
    /// the feature `sdp`). Warns when a hardening variable has a finite metric (hardening
    /// ignored: the limit load of the initial yield set).
    pub fn new(problem: &DiscreteProblem) -> Result<Self, LimitError> {
        let Some(p) = problem.stresses.as_deref() else {
            return Err(LimitError::Elastic { what: "no [yield] table".into() });
        };
        if p.is_unbounded() {
            return Err(LimitError::Elastic { what: format!("type = {:?} bounds no stress", p.name()) });
        }
        let m = p.hardening_dim();
        let (raw, auxiliary) = raw_blocks(p)?;
        let width = 6 + auxiliary;
        let full = 6 + m + auxiliary;
        let mut blocks = Vec::with_capacity(raw.len());
        for (k, (kind, offset, map)) in raw.into_iter().enumerate() {
            let bad = |message: String| LimitError::BadCone { yield_surface: p.name().into(), block: k, message };
            let rows = match kind {
                BlockKind::SecondOrder(dim) => dim,
                BlockKind::Semidefinite(n) => n * (n + 1) / 2,
            };
            if rows == 0 || offset.len() != rows || map.len() != rows * full {
                return Err(bad(format!(
                    "{rows} rows, {} offsets, {} map entries (expected ≥ 1 rows, as many offsets, rows × {full} map \
                     entries)",
                    offset.len(),
                    map.len()
                )));
            }
            if offset.iter().chain(&map).any(|v| !v.is_finite()) {
                return Err(bad("non-finite entries".into()));
            }
            let map = map.chunks_exact(full).flat_map(|row| row[..6].iter().chain(&row[6 + m..]).copied()).collect();
            blocks.push(YieldBlock { kind, offset, map });
        }
        Ok(Self { blocks, width, warnings: hardening_warning(p) })
    }
}

/// Type of the blocks as the plugin gives them: (kind, offset, map on (σ, q, a)).
type RawBlock = (BlockKind, Vec<f64>, Vec<f64>);

/// The plugin's second-order cones, else its semidefinite blocks (with the feature `sdp`), with
/// the number of auxiliary variables; else the error naming why there is no conic form.
fn raw_blocks(p: &dyn AdmissibleStresses) -> Result<(Vec<RawBlock>, usize), LimitError> {
    if let Some(cone) = p.cone() {
        let blocks = cone.blocks.into_iter().map(|b| (BlockKind::SecondOrder(b.dim), b.offset, b.map)).collect();
        return Ok((blocks, 0));
    }
    let no_form = |why: String| LimitError::NoConicForm { yield_surface: p.name().into(), why };
    let Some(sdp) = p.semidefinite_cone() else {
        return Err(no_form(p.cone_unavailable()));
    };
    if !cfg!(feature = "sdp") {
        return Err(no_form(format!(
            "{}; that semidefinite form needs saddle built with the feature `sdp` (Clarabel's semidefinite cones, \
             which link BLAS and LAPACK: `cargo build --release --features saddle/sdp`)",
            p.cone_unavailable()
        )));
    }
    let blocks = sdp.blocks.into_iter().map(|b| (BlockKind::Semidefinite(b.n), b.offset, b.map)).collect();
    Ok((blocks, sdp.auxiliary))
}

/// The warning when a hardening variable has a finite metric.
fn hardening_warning(p: &dyn AdmissibleStresses) -> Vec<String> {
    let m = p.hardening_dim();
    let unit = |k: usize| -> Vec<f64> { (0..m).map(|j| (j == k) as usize as f64).collect() };
    let hardening: Vec<usize> = (0..m).filter(|&k| p.hardening_inner(&unit(k), &unit(k)).is_finite()).collect();
    if hardening.is_empty() {
        return Vec::new();
    }
    let names: Vec<&str> = p.hardening_fields().iter().map(|(n, _)| *n).collect();
    vec![format!(
        "yield: type = {:?} hardens ({} with a finite hardening metric, e.g. h > 0): the hardening is ignored, the \
         limit load is that of the initial yield set taken perfectly plastic (theory §13.1)",
        p.name(),
        names.join(", ")
    )]
}
