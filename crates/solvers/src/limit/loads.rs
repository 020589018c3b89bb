//! Stage 1 of a limit analysis (theory §13.1): the reference loads ℓ that the multiplier
//! scales, and the obstacle rows that constrain a mechanism.

use super::LimitError;
use saddle_core::DiscreteProblem;
use saddle_core::problem::obstacles::OBSTACLE_PATH;

/// A row is closed in the reference configuration when its gap there is at most this fraction
/// of the body's size (Σ w_T)^{1/3}: the gaps of flat obstacles are 0 up to round-off.
const CLOSED_GAP: f64 = 1e-9;

/// The reference loads of theory §13.1 and the rows closed in the reference configuration.
#[derive(Clone, Debug)]
pub struct ReferenceLoads {
    /// The consistent nodal forces f_u on the free dofs (tractions, body forces).
    pub nodal: Vec<f64>,
    /// The loads f on the obstacles' extras (force-controlled obstacles).
    pub extras: Vec<f64>,
    /// With prescribed displacements: per row, the rate ċ_i of its offset per unit load factor,
    /// divided by max|ċ| (the load multiplier then has the units of a force: for a rigid punch,
    /// its force). `None` when no obstacle prescribes a displacement.
    pub rate: Option<Vec<f64>>,
    /// The rows closed in the reference configuration (gap c_i − ċ_i ≤ 0): only these constrain
    /// a mechanism, G v + H V + ċ τ ≥ 0.
    pub closed: Vec<usize>,
    /// The largest load coefficient, the force scale of the programme.
    pub scale: f64,
    /// Things the user should know (rows open in the reference configuration).
    pub warnings: Vec<String>,
}

impl ReferenceLoads {
    /// Stage 1 (theory §13.1): ℓ of `problem` — its nodal forces, its obstacles' loads and the
    /// rates of their prescribed displacements (each obstacle's rows at load factor 2 against
    /// those at 1, [`saddle_core::AdmissibleDisplacements::rows_at_factor`]) — and the rows
    /// closed at load factor 0. Errors: all loads zero; force loads together with a prescribed
    /// displacement (naming the obstacle).
    pub fn new(problem: &DiscreteProblem) -> Result<Self, LimitError> {
        let element = &*problem.element;
        let obstacles = &problem.obstacles;
        let rows = obstacles.rows();
        let n_dofs = element.n_dofs();
        let nodal = if problem.nodal_load.is_empty() { vec![0.0; n_dofs] } else { problem.nodal_load.clone() };
        let extras = obstacles.load().to_vec();
        // the rates ċ = c(2) − c(1) of every obstacle that can scale its load
        let mut rate = vec![0.0; rows.n_rows()];
        let mut prescribing = None;
        for (i, (o, part)) in obstacles.obstacles().iter().zip(obstacles.parts()).enumerate() {
            if o.k.scaled_load(1.0).is_none() {
                continue;
            }
            let path = obstacles.obstacles().path(OBSTACLE_PATH, i);
            let at2 = o.k.rows_at_factor(2.0, &part.rows, element.mesh(), element.dofs(), &path)?;
            for (r, (c2, c1)) in part.row_range.clone().zip(at2.offset.iter().zip(&part.rows.offset)) {
                rate[r] = c2 - c1;
            }
            if prescribing.is_none() && part.row_range.clone().any(|r| rate[r] != 0.0) {
                prescribing = Some(path);
            }
        }
        let length = element.weights().iter().sum::<f64>().cbrt();
        let closed: Vec<usize> =
            (0..rows.n_rows()).filter(|&r| rows.offset[r] - rate[r] <= CLOSED_GAP * length).collect();
        let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let (f_nodal, f_extras, c_max) = (max_abs(&nodal), max_abs(&extras), max_abs(&rate));
        let mut warnings = Vec::new();
        if closed.len() < rows.n_rows() {
            warnings.push(format!(
                "{} of {} obstacle rows are open in the reference configuration (gap > 0): they do not constrain the \
                 mechanism (small displacements: the contact set of a limit analysis is the initial one)",
                rows.n_rows() - closed.len(),
                rows.n_rows()
            ));
        }
        let rate = match prescribing {
            None => None,
            Some(obstacle) => {
                if f_nodal > 0.0 || f_extras > 0.0 {
                    let forces = match (f_nodal > 0.0, f_extras > 0.0) {
                        (true, true) => "tractions or body forces, and obstacle forces",
                        (true, false) => "tractions or body forces",
                        _ => "obstacle forces",
                    };
                    return Err(LimitError::MixedLoads { obstacle, forces: forces.into() });
                }
                Some(rate.iter().map(|c| c / c_max).collect())
            }
        };
        let scale = if rate.is_some() { 1.0 } else { f_nodal.max(f_extras) };
        if scale <= 0.0 || !scale.is_finite() {
            return Err(LimitError::NoLoad);
        }
        Ok(Self { nodal, extras, rate, closed, scale, warnings })
    }

    /// Number of load rows on the extras: the obstacles' extras and, with prescribed
    /// displacements, the one load factor τ of their rates.
    pub fn n_extra_rows(&self) -> usize {
        self.extras.len() + self.rate.is_some() as usize
    }
}
