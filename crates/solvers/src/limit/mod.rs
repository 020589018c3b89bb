//! Limit analysis (theory §13): the collapse multiplier λ* of a scene's loads for its yield
//! surface taken perfectly plastic, as one conic programme solved by Clarabel — the static
//! problem (largest load multiplier carried by stresses in D, in equilibrium with the
//! obstacles' multipliers) and, as its dual, the kinematic problem (least dissipation of a
//! mechanism at unit external power).
//!
//! The library call is [`LimitAnalysis::solve`] on any [`DiscreteProblem`]: any element, any
//! yield surface with a conic form ([`AdmissibleStresses::cone`], the same description the
//! `socp` solver uses), any obstacles (their rows and extras are the kinematic constraints). In
//! stages:
//!
//! 1. [`ReferenceLoads::new`] (`loads.rs`): the reference loads ℓ — forces on u, loads on the
//!    extras, the rates of prescribed displacements — and the rows in contact in the reference
//!    configuration;
//! 2. [`StaticProgramme::build`] (`programme.rs`): the static problem in Clarabel's form — the
//!    yield surface's cones (`cones.rs`), the stress coordinates with B̄'s pressure merged per
//!    element (`lineality.rs`), the columns and rows;
//! 3. [`StaticProgramme::solve`]: Clarabel's interior point;
//! 4. [`Collapse::recover`] (`collapse.rs`): both bounds and the gap, the collapse stresses and
//!    contact forces (from x), the mechanism and its dissipation (from the dual z).
//!
//! Perfect plasticity: the hardening variables are fixed at 0, so D is the initial yield set. A
//! yield surface with hardening (a finite hardening metric) is analysed with its initial yield
//! set, with a warning naming the hardening ignored.

mod collapse;
mod cones;
mod lineality;
mod loads;
mod programme;

pub use collapse::Collapse;
pub use loads::ReferenceLoads;
pub use programme::StaticProgramme;

use saddle_core::{DiscreteProblem, SceneError};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use thiserror::Error;

/// Why a limit analysis failed; each names the offending value and where it comes from.
#[derive(Debug, Error)]
pub enum LimitError {
    /// No yield surface bounds the stresses: nothing collapses.
    #[error("yield: the scene is elastic ({what}): an elastic body has no collapse load; give a [yield] table")]
    Elastic {
        /// What the scene has (`no [yield] table`, `type = "elastic"`).
        what: String,
    },
    /// The yield surface has no conic form.
    #[error(
        "yield: type = {yield_surface:?} has no conic form, so its limit load cannot be posed as a conic programme: {why}"
    )]
    NoConicForm {
        /// The plugin's `type`.
        yield_surface: String,
        /// Why (the plugin's [`AdmissibleStresses::cone_unavailable`]).
        why: String,
    },
    /// A cone block of the yield surface is malformed.
    #[error("yield: type = {yield_surface:?}: cone block {block} is malformed: {message}")]
    BadCone {
        /// The plugin's `type`.
        yield_surface: String,
        /// The block's index.
        block: usize,
        /// What is wrong.
        message: String,
    },
    /// All reference loads are zero.
    #[error(
        "the scene's loads are all zero (tractions, body forces, obstacle forces, prescribed obstacle displacements): \
         there is nothing for the multiplier to scale"
    )]
    NoLoad,
    /// Force loads and prescribed displacements together.
    #[error(
        "{obstacle}: a prescribed displacement together with force loads ({forces}): the collapse multiplier scales \
         one kind of load; give forces only, or prescribed displacements only"
    )]
    MixedLoads {
        /// The path of the displacement-controlled obstacle (`obstacle`, `obstacle[1]`).
        obstacle: String,
        /// Which force loads are nonzero.
        forces: String,
    },
    /// The multiplier is unbounded: the loads cannot cause collapse.
    #[error(
        "the loads cannot cause collapse: the static multiplier is unbounded (Clarabel: {status}); stresses in the \
         yield set carry any multiple of them (e.g. a load taken by a support, or hydrostatic pressure on a \
         pressure-insensitive yield surface)"
    )]
    Unbounded {
        /// Clarabel's status.
        status: String,
    },
    /// Clarabel stopped without a solution.
    #[error(
        "limit analysis: Clarabel ended {status} after {iterations} iterations (gap {gap:e}, residuals {r_prim:e}, {r_dual:e})"
    )]
    NotSolved {
        /// Clarabel's status.
        status: String,
        /// Its iterations.
        iterations: usize,
        /// The relative gap reached.
        gap: f64,
        /// Its primal and dual residuals.
        r_prim: f64,
        /// Dual residual.
        r_dual: f64,
    },
    /// Friction rows (theory §8.3) have no place in the kinematic problem of §13.1.
    #[error(
        "obstacle: friction ({blocks} contact nodes with tangential rows): limit analysis (theory §13) poses \
         frictionless contact only; remove the obstacle's friction table or use `saddle run`/`saddle sweep`"
    )]
    Friction {
        /// How many nodes carry tangential rows.
        blocks: usize,
    },
    /// A setting is out of range.
    #[error("limit.{field} = {value}: {message}")]
    Setting {
        /// The setting.
        field: &'static str,
        /// Its value.
        value: String,
        /// The range.
        message: String,
    },
    /// Clarabel rejected the programme or its settings.
    #[error("limit analysis: Clarabel rejected {what}: {message}")]
    Rejected {
        /// The programme or the settings.
        what: &'static str,
        /// Clarabel's message.
        message: String,
    },
    /// An obstacle's rows at another load factor (for the rates of prescribed displacements).
    #[error(transparent)]
    Scene(#[from] SceneError),
}

/// The settings of a limit analysis (theory §13).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitAnalysis {
    /// Clarabel's relative (and absolute, non-dimensional) duality gap and feasibility
    /// tolerance: the relative gap between the two bounds is about this. On the 14k-dof strip
    /// punch 1e-5 takes 19 interior-point iterations (relative gap 1.6e-5), 1e-6 takes 41 (the
    /// last ones fighting the non-unique pointwise pressure of B̄, theory §13.3); on the 57k-dof
    /// one 1e-6 takes 24, 1e-8 35, for the same multiplier to 1e-6. A 1 % answer needs no
    /// more than 1e-3 (relative gap 1.5e-3, 14 iterations instead of 19 on the 14k-dof strip;
    /// docs/limit_analysis.md). Each KKT solve is refined to `tol`·1e-5.
    pub tol: f64,
    /// Clarabel's iteration budget.
    pub max_iter: usize,
    /// δ of the regularisation `½δ Σ_T (w_T/L³)|σ_T/S|²` of the static objective used when the
    /// interior point stalls without it (theory §13.3; 0: never). Where the static optimum is
    /// not unique — stresses the equilibrium rows do not see and the cones do not bound, as the
    /// pointwise pressure of B̄ under Drucker–Prager — the iterates drift along the optimal face
    /// and Clarabel may stop with `InsufficientProgress`; the regularisation picks the stresses
    /// of least norm. λ⁻ stays a static (lower) bound, but λ⁺ is then the dissipation of a
    /// mechanism off by O(δ) (a warning says so): on the homogeneous compression with P2,
    /// δ = 1e-4 leaves λ⁻ within 4e-9 and puts λ⁺ 1.6e-4 low.
    pub fallback_regularisation: f64,
    /// Clarabel's threads (0: Clarabel chooses).
    pub threads: usize,
    /// Clarabel's iteration log and, after the solve, its timers (`kkt update`: the
    /// factorisation; `kkt solve`: the triangular solves) on stdout.
    pub verbose: bool,
}

impl Default for LimitAnalysis {
    fn default() -> Self {
        Self { tol: 1e-5, max_iter: 200, fallback_regularisation: 1e-4, threads: 1, verbose: false }
    }
}

impl LimitAnalysis {
    /// `tol` in (0, 1), `max_iter` in [1, u32::MAX].
    pub fn validate(&self) -> Result<(), LimitError> {
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return Err(LimitError::Setting {
                field: "tol",
                value: self.tol.to_string(),
                message: "must lie in (0, 1)".into(),
            });
        }
        if self.max_iter == 0 || self.max_iter > u32::MAX as usize {
            return Err(LimitError::Setting {
                field: "max_iter",
                value: self.max_iter.to_string(),
                message: format!("must lie in [1, {}]", u32::MAX),
            });
        }
        Ok(())
    }

    /// The static programme of `problem` as JSON (`StaticProgramme::json`), for other conic
    /// solvers.
    pub fn programme_json(problem: &DiscreteProblem) -> Result<String, LimitError> {
        refuse_friction(problem)?;
        let loads = ReferenceLoads::new(problem)?;
        Ok(StaticProgramme::build(problem, &loads)?.json())
    }

    /// The collapse of `problem` (theory §13), in the stages of the module docs.
    pub fn solve(&self, problem: &DiscreteProblem) -> Result<Collapse, LimitError> {
        self.validate()?;
        refuse_friction(problem)?;
        let started = Instant::now();
        let loads = ReferenceLoads::new(problem)?;
        let prog = StaticProgramme::build(problem, &loads)?;
        let built = started.elapsed().as_secs_f64();
        let (ipm, regularised) = match prog.solve(self, 0.0) {
            Err(LimitError::NotSolved { ref status, .. })
                if status == "InsufficientProgress" && self.fallback_regularisation > 0.0 =>
            {
                (prog.solve(self, self.fallback_regularisation)?, true)
            }
            r => (r?, false),
        };
        let solved = started.elapsed().as_secs_f64();
        let mut collapse = Collapse::recover(problem, &loads, &prog, &ipm);
        if regularised {
            collapse.warnings.push(format!(
                "the interior point stalled on a non-unique static optimum and was rerun with the regularisation \
                 δ = {:e} (theory §13.3): λ⁻ is a static bound, λ⁺ is approximate to O(δ)",
                self.fallback_regularisation
            ));
        }
        collapse.phases = vec![
            ("programme".into(), built),
            ("interior_point".into(), solved - built),
            ("recover".into(), started.elapsed().as_secs_f64() - solved),
        ];
        collapse.wall_s = started.elapsed().as_secs_f64();
        Ok(collapse)
    }
}

/// Limit analysis knows frictionless contact only (theory §13.1): tangential rows are refused.
fn refuse_friction(problem: &DiscreteProblem) -> Result<(), LimitError> {
    let rows = problem.obstacles.rows();
    if rows.has_friction() {
        return Err(LimitError::Friction { blocks: rows.friction.blocks.len() });
    }
    Ok(())
}
