//! Tangential rows and the rigid body's motion across its direction (theory §8.3), shared by the
//! rigid obstacles with friction (the sphere and the punches).
//!
//! A rigid obstacle moving along the unit direction d may carry a friction law (`friction`) and
//! then move across d too, by `W = W_x e₁ + W_y e₂` with (e₁, e₂) ⊥ d ([`tangential_axes`]):
//! prescribed (`W = [Wx, Wy]`), or extras `Ux`, `Uy` loaded by the force `Q = [Qx, Qy]` (the
//! load term Qx Ux + Qy Uy). Each contact node's normal row is followed by its two tangential
//! rows, the slip `t_k·(u_i − motion)` of the node against the body in its tangent plane
//! (t₁, t₂ of [`frame`]), and a friction block naming them with the node's weight.
//! Without `friction`, `Q` and `W` nothing here runs: the rows are the frictionless ones.

use saddle_core::error::{check, join};
use saddle_core::problem::displacements::contact_status;
use saddle_core::problem::friction::ContactStatus;
use saddle_core::{ConstraintRows, DofMap, FrictionBlock, FrictionLaw, LoadFactors, ParameterError, SceneError};

/// The tangential fields of a rigid obstacle's table: `friction`, `Q`, `W` (theory §8.3).
#[derive(Clone, Copy, Debug)]
pub struct Tangential<'a> {
    /// The friction law; `None`: frictionless.
    pub friction: Option<&'a (dyn FrictionLaw + 'static)>,
    /// The tangential force [Qx, Qy] (extras `Ux`, `Uy`).
    pub q: Option<[f64; 2]>,
    /// The prescribed tangential motion [Wx, Wy].
    pub w: Option<[f64; 2]>,
}

impl<'a> Tangential<'a> {
    /// The fields `friction`, `Q`, `W` of an obstacle's table.
    pub fn new(friction: &'a Option<Box<dyn FrictionLaw>>, q: Option<[f64; 2]>, w: Option<[f64; 2]>) -> Self {
        Self { friction: friction.as_deref(), q, w }
    }

    /// Checks `friction`, `Q` and `W` (theory §8.3): the law's own parameters under
    /// `{path}.friction`; Q and W finite and bounded, not both, and neither without a friction
    /// law. `body` names the obstacle in messages ("the sphere").
    pub fn validate(&self, path: &str, body: &str) -> Result<(), ParameterError> {
        if let Some(law) = self.friction {
            law.validate(&join(path, "friction"))?;
        }
        for (field, value) in [("Q", self.q), ("W", self.w)] {
            let Some(value) = value else { continue };
            check::bounded_all(path, field, &value)?;
            if self.friction.is_none() {
                return Err(ParameterError::new(
                    join(path, field),
                    format!("[{}, {}]", value[0], value[1]),
                    format!(
                        "moves {body} across its direction, which needs a friction law: give {} (e.g. {{ type = \
                         \"tresca\", g = 0.1 }}) or remove {}",
                        join(path, "friction"),
                        join(path, field)
                    ),
                ));
            }
        }
        if let (Some(q), Some(w)) = (self.q, self.w) {
            return Err(ParameterError::new(
                join(path, "Q"),
                format!("[{}, {}]", q[0], q[1]),
                format!(
                    "cannot be given together with {} = [{}, {}]: give exactly one of the tangential force and the \
                     prescribed tangential motion",
                    join(path, "W"),
                    w[0],
                    w[1]
                ),
            ));
        }
        Ok(())
    }

    /// Q and W each multiplied by its own factor (theory §11.2).
    pub fn scaled(&self, factors: &LoadFactors) -> (Option<[f64; 2]>, Option<[f64; 2]>) {
        (self.q.map(|q| q.map(|x| x * factors.of("Q"))), self.w.map(|w| w.map(|x| x * factors.of("W"))))
    }

    /// Those of `Q`, `W` that are given: the loads a load path may give factors of their own.
    pub fn load_names(&self) -> impl Iterator<Item = String> {
        [("Q", self.q.is_some()), ("W", self.w.is_some())].into_iter().filter(|g| g.1).map(|g| g.0.to_string())
    }

    /// `Ux`, `Uy` under a tangential force Q; none otherwise.
    pub fn extra_names(&self) -> impl Iterator<Item = String> {
        self.q.iter().flat_map(|_| ["Ux".to_string(), "Uy".to_string()])
    }

    /// The load's coefficients of `Ux`, `Uy`: Qx, Qy under Q; none otherwise.
    pub fn load(&self) -> impl Iterator<Item = f64> {
        self.q.into_iter().flatten()
    }

    /// The body's motion across d: W e (prescribed), or the extras `across` = (Ux, Uy) (under Q),
    /// or 0; `axes` = (e₁, e₂).
    pub fn across(&self, axes: ([f64; 3], [f64; 3]), across: &[f64]) -> [f64; 3] {
        let w = match (self.w, self.q) {
            (Some(w), _) => w,
            (None, Some(_)) => [across[0], across[1]],
            (None, None) => return [0.0; 3],
        };
        let (e1, e2) = axes;
        std::array::from_fn(|k| w[0] * e1[k] + w[1] * e2[k])
    }

    /// The prescribed part of the motion across d: W e under W, else 0.
    pub fn prescribed(&self, axes: ([f64; 3], [f64; 3])) -> [f64; 3] {
        if self.w.is_some() { self.across(axes, &[]) } else { [0.0; 3] }
    }

    /// Appends the H entries of (Ux, Uy) of a row of direction `a`: −a·e₁, −a·e₂ under Q.
    pub fn extra_entries(&self, a: [f64; 3], axes: ([f64; 3], [f64; 3]), out: &mut Vec<f64>) {
        if self.q.is_some() {
            let (e1, e2) = axes;
            out.extend([-dot(a, e1), -dot(a, e2)]);
        }
    }
}

/// (e₁, e₂): the axes of the motion across the unit direction d, orthonormal and ⊥ d. e₁ is the
/// first of the coordinate axes x₁, x₂ not within 25° of d, made orthogonal to d; e₂ = d × e₁.
/// For d = e₃: (e₁, e₂) = (x₁, x₂).
pub fn tangential_axes(d: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let a = if d[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let e1 = unit(sub(a, scaled(d, dot(a, d))));
    (e1, cross(d, e1))
}

/// (t₁, t₂): the tangent plane at a node of normal `n`, orthonormal, ⊥ n: t₁ the body's e₁
/// (else e₂, if e₁ is within 25° of n) made orthogonal to n, t₂ = n × t₁ (theory §8.3).
pub fn frame(axes: ([f64; 3], [f64; 3]), n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let (e1, e2) = axes;
    let a = if dot(e1, n).abs() < 0.9 { e1 } else { e2 };
    let t1 = unit(sub(a, scaled(n, dot(a, n))));
    (t1, cross(n, t1))
}

/// One node's tangential rows (theory §8.3): the node, its frame and weight, and its normal row.
#[derive(Clone, Copy, Debug)]
pub struct TangentialPair {
    /// The mesh node.
    pub node: usize,
    /// (t₁, t₂) of its normal ([`frame`]).
    pub frame: ([f64; 3], [f64; 3]),
    /// Its normal row's index.
    pub normal: usize,
    /// Its share of the contact face.
    pub weight: f64,
}

/// Appends the two tangential rows of `pair` after its normal row and their block:
/// `t_k·(u_n − motion)` on the node's free dofs, H entries from `entries(t_k, h)`, the offset
/// `−t_k·motion` (`motion` the prescribed motion of the body's points). A node with a fixed
/// component gets none (its three rows would not be independent): returns false.
pub fn push_tangential(
    rows: &mut ConstraintRows,
    dofs: &DofMap,
    pair: TangentialPair,
    motion: [f64; 3],
    entries: impl Fn([f64; 3], &mut Vec<f64>),
    h: &mut Vec<f64>,
) -> bool {
    let TangentialPair { node: n, frame: (t1, t2), normal, weight } = pair;
    let on_free = |t: [f64; 3]| {
        let mut e = [(0, 0.0); 3];
        let mut k = 0;
        for (c, &tc) in t.iter().enumerate() {
            if let (Some(j), true) = (dofs.free(n, c), tc != 0.0) {
                e[k] = (j, tc);
                k += 1;
            }
        }
        (e, k)
    };
    // the node's three rows (normal, t₁, t₂) are independent only on three free components: with
    // one fixed they are not (a curved obstacle over a roller-supported face gives rows on u₃
    // alone), so such a node gets no tangential rows
    if (0..3).any(|c| dofs.free(n, c).is_none()) {
        return false;
    }
    let ((e1, k1), (e2, k2)) = (on_free(t1), on_free(t2));
    let tangent = rows.n_rows();
    for (t, e, k) in [(t1, e1, k1), (t2, e2, k2)] {
        entries(t, h);
        rows.push(&e[..k], h, -dot(t, motion), n);
    }
    rows.friction.blocks.push(FrictionBlock { law: 0, normal, tangent, weight });
    true
}

/// After the rows of an obstacle with the friction law `law` at `{path}.friction`: the law
/// registered on `rows`, a warning for the `without_plane` nodes that got no tangential rows,
/// and an error when no node got any (the rows have no tangent plane, theory §8.3).
pub fn finish_friction(
    rows: &mut ConstraintRows,
    law: &(dyn FrictionLaw + 'static),
    without_plane: usize,
    path: &str,
) -> Result<(), SceneError> {
    if rows.friction.is_empty() {
        return Err(SceneError::Parameter(ParameterError::new(
            join(path, "friction"),
            format!("type = {:?}", law.name()),
            format!(
                "no node of {} can slip: at every one a displacement component is fixed by the Dirichlet \
                 conditions, so the rows have no tangent plane for the friction law (theory §8.3)",
                join(path, "zone")
            ),
        )));
    }
    rows.friction.laws.push(dyn_clone::clone_box(law));
    if without_plane > 0 {
        rows.warnings.push(format!(
            "{}: {without_plane} zone node(s) have a fixed displacement component and carry no friction rows",
            join(path, "friction")
        ));
    }
    Ok(())
}

/// The direction of every row: `normal(node)` for a normal row, t₁, t₂ of [`frame`] for its
/// tangential rows.
pub fn row_directions(
    rows: &ConstraintRows,
    axes: ([f64; 3], [f64; 3]),
    normal: impl Fn(usize) -> [f64; 3],
) -> Vec<[f64; 3]> {
    let mut a: Vec<[f64; 3]> = rows.node.iter().map(|&n| normal(n)).collect();
    for b in &rows.friction.blocks {
        let (t1, t2) = frame(axes, a[b.normal]);
        (a[b.tangent], a[b.tangent + 1]) = (t1, t2);
    }
    a
}

/// The report's friction quantities (theory §8.3): `Ux`, `Uy` (the motion `across` along e₁,
/// e₂), `force_x`, `force_y` = Σλ_i a_i·e₁, Σλ_i a_i·e₂ with the rows' `directions` (= Q at a
/// solution), `stick_nodes` and `slip_nodes` ([`contact_status`]).
pub fn friction_quantities(
    rows: &ConstraintRows,
    lambda: &[f64],
    directions: &[[f64; 3]],
    axes: ([f64; 3], [f64; 3]),
    across: [f64; 3],
) -> Vec<(String, f64)> {
    let (e1, e2) = axes;
    let resultant = |e: [f64; 3]| -> f64 { lambda.iter().zip(directions).map(|(&l, &a)| l * dot(a, e)).sum() };
    let status = contact_status(rows, lambda);
    let count = |s: ContactStatus| status.iter().filter(|x| x.1 == s).count();
    let (stick, slip) = (count(ContactStatus::Stick), count(ContactStatus::Slip));
    vec![
        ("Ux".into(), dot(across, e1)),
        ("Uy".into(), dot(across, e2)),
        ("force_x".into(), resultant(e1)),
        ("force_y".into(), resultant(e2)),
        ("stick_nodes".into(), stick as f64),
        ("slip_nodes".into(), slip as f64),
    ]
}

pub(crate) fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| a[k] + b[k])
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| a[k] - b[k])
}

fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    scaled(a, 1.0 / norm(a))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
