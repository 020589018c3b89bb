//! The conformance kit: what every K plugin ([`AdmissibleDisplacements`]) must satisfy on a
//! mesh for the solvers of theory §4 to be right about it. A plugin author calls [`check_all`]
//! from a test with a mesh, its Dirichlet conditions, a seed and a displacement scale (the
//! size of the random displacements and extras, comparable to the gaps φ in the zone):
//!
//! ```
//! use saddle_contact::{RigidPunch, Paraboloid, conformance::check_all};
//! use saddle_core::{BoxMesh, Dirichlet, DofMap, Region};
//! let mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [4, 4, 2]).mesh().unwrap();
//! let dofs = DofMap::new(&mesh, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap();
//! let zone = Region::Group("zmin".into());
//! let punch = RigidPunch::new(0.3, zone, Box::new(Paraboloid::new(5.0))).unwrap();
//! check_all(&punch, &mesh, &dofs, 1, 0.01).unwrap();
//! ```
//!
//! The checks, in the order [`check_all`] runs them, with the [`KitFailure::check`] name each
//! failure carries:
//!
//! * `setup` — the scale is finite and > 0; `validate` — `validate("obstacle")` succeeds;
//!   `discretise` — `discretise(mesh, dofs, "obstacle")` succeeds.
//! * `rows` (d): the rows are well formed (CSR pointers, columns below the number of free
//!   dofs, nodes of the mesh, one H column per [`AdmissibleDisplacements::extra_names`]), there is
//!   at least one row, every entry is finite, and no row is identically zero in u and V (a
//!   constant constraint is either void or infeasible).
//! * `gap_derivative`, `gap_value` (a): the rows are the linearisation of
//!   [`AdmissibleDisplacements::gap`] at the reference configuration (u, V) = (0, 0). Central
//!   finite differences of `gap()` equal G·du and H·dV for every row: along each free
//!   displacement component (du = e_x, e_y, e_z of the node's free dofs) of every node that
//!   has rows (a random sample of [`COMPONENT_NODES`] of them on larger zones), along each extra
//!   unknown separately (dV = e_k), and along random directions in u, then in V. The offsets
//!   equal gap(0, 0); and at random (u, V) of the given scale the rows and
//!   `gap()` agree to round-off (an affine gap, the polyhedral K_h of theory §3) or at least to
//!   second order: the difference must drop by 8 or more when (u, V) is quartered (a curved
//!   gap; a first-order disagreement drops by 4 only).
//! * `load`, `force`, `report` (b): [`AdmissibleDisplacements::load`] has one finite entry per
//!   extra unknown. The kit then builds multipliers λ ≥ 0 that balance it, Hᵀλ = −f (the KKT
//!   condition on the extras, theory §3; Σλ = F for the punch): the point closest to a random
//!   λ̃ ≥ 0 on that set, found by the dense QP of `saddle_core::linalg::dense_qp` (with a
//!   regularised least-squares fallback when its least-norm start is not ≥ 0). Without extras
//!   any λ ≥ 0 will do. No such λ is a `load` failure: the discrete problem has no solution.
//!   For this λ and random extras, a reported quantity `force` must equal the resultant on the
//!   first extra unknown, −(Hᵀλ)₀ (`force`): Σλ for the punches (H column −1), Σλ_i n_i·d for
//!   the rigid sphere (theory §8), = f₀ = F for balanced λ. Without extras (a prescribed
//!   displacement) the kit cannot know the direction of motion and only checks that `force` is
//!   linear in λ (additive and homogeneous); the plugin's own tests must check its value. The
//!   report must count [`saddle_core::contact_set`]`(λ)` as its contact nodes, have a finite
//!   contact radius ≥ 0 and finite quantities, report every extra unknown it names by its
//!   value, and for λ = 0 have no contact node, radius 0 and force 0 (`report`).
//! * `projection`, `projection_feasible`, `projection_idempotent`, `projection_vi` (c):
//!   [`project_euclidean`] of random points succeeds, gives points feasible both for the rows
//!   and for `gap()` (g ≥ −tol), is idempotent, and satisfies the variational inequality of
//!   the projection, (z − Pz)·(w − Pz) ≤ tol for feasible w (the projections of the other
//!   random points).
//! * `scaled_load` (e): when the plugin can scale its load
//!   ([`AdmissibleDisplacements::scaled_load`], for sweeps and load paths), factor 1 gives the
//!   same load term and rows, and factor 2 doubles the load term and keeps the number of rows
//!   and extra unknowns.
//! * `rows_at_factor` (f): the rows a load step gets from the obstacle's own rows
//!   ([`AdmissibleDisplacements::rows_at_factor`]) are those of the scaled obstacle discretised
//!   afresh, at factors 0, ½ and 2.
//!
//! * `friction` (g), for an obstacle with a friction law (theory §8.3): every block's two
//!   tangential rows belong to its normal row's node, are orthonormal and orthogonal to the
//!   normal row where the node's dofs are all free; the weights are finite and > 0; the law
//!   validates under `obstacle.friction`, and its projection ([`saddle_core::FrictionLaw::project`])
//!   lands in the disc of its radius, is idempotent, leaves the disc's points alone, and its
//!   derivative matches central differences at random points. (The tangential rows are the
//!   linearisation of `gap()`, the slips, in (a); (b) counts the normal rows' contact set; (c)
//!   projects onto the normal rows alone, the tangential ones not being constraints on w.)
//!
//! Tolerances are relative: g is compared to 1e-9 × (max|c| + scale × the largest row norm).

use crate::projection::{Projected, project_euclidean};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng, rngs::StdRng};
use saddle_core::linalg::DenseQp;
use saddle_core::{AdmissibleDisplacements, ConstraintRows, DofMap, TetMesh, normal_contact_set};
use thiserror::Error;

/// A failed conformance check: which (`check`, one of [`CHECKS`]) and what, with numbers.
#[derive(Clone, Debug, Error, PartialEq)]
#[error("conformance check `{check}` failed: {message}")]
pub struct KitFailure {
    /// The name of the failed check.
    pub check: &'static str,
    /// What went wrong, with the numbers.
    pub message: String,
}

/// The names of the checks, in the order [`check_all`] runs them (see the module docs).
pub const CHECKS: [&str; 16] = [
    "setup",
    "validate",
    "discretise",
    "rows",
    "gap_derivative",
    "gap_value",
    "load",
    "force",
    "report",
    "projection",
    "projection_feasible",
    "projection_idempotent",
    "projection_vi",
    "scaled_load",
    "rows_at_factor",
    "friction",
];

/// Random samples per check.
const SAMPLES: usize = 6;

/// Most row nodes whose displacement components are each differentiated in `gap_derivative`
/// (a random sample of them when there are more): bounds the cost of the check on big zones.
pub const COMPONENT_NODES: usize = 24;

/// Where a central difference of gap() and the rows disagree most.
struct Mismatch {
    /// The row.
    row: usize,
    /// The central difference of gap() there.
    fd: f64,
    /// G du + H dV there.
    lin: f64,
    /// |fd − lin|.
    err: f64,
    /// The tolerance it exceeds.
    tol: f64,
}

fn fail(check: &'static str, message: String) -> Result<(), KitFailure> {
    Err(KitFailure { check, message })
}

/// Runs every check of the kit: `validate`, then [`check_rows`], [`check_linearisation`],
/// [`check_load`] and [`check_projection`]. `scale` is the size of the random displacements
/// and extras (comparable to the gaps in the zone, e.g. 0.01 for the default scene).
pub fn check_all(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
    scale: f64,
) -> Result<(), KitFailure> {
    if let Err(e) = k.validate("obstacle") {
        return fail("validate", e.to_string());
    }
    check_rows(k, mesh, dofs, seed, scale)?;
    check_linearisation(k, mesh, dofs, seed, scale)?;
    check_load(k, mesh, dofs, seed, scale)?;
    check_projection(k, mesh, dofs, seed, scale)?;
    check_scaled_load(k, mesh, dofs)?;
    check_rows_at_factor(k, mesh, dofs)?;
    check_friction(k, mesh, dofs, seed)
}

/// (g) `friction`: the tangential rows and weights of every friction block, and the law's
/// projection and its derivative (module docs). Nothing to check without friction.
pub fn check_friction(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
) -> Result<(), KitFailure> {
    let rows =
        k.discretise(mesh, dofs, "obstacle").map_err(|e| KitFailure { check: "discretise", message: e.to_string() })?;
    let fr = &rows.friction;
    let dense = |i: usize| -> Vec<(usize, f64)> {
        let (c, v) = rows.row(i);
        c.iter().copied().zip(v.iter().copied()).collect()
    };
    let inner = |a: &[(usize, f64)], b: &[(usize, f64)]| -> f64 {
        a.iter().map(|(j, x)| b.iter().filter(|(k, _)| k == j).map(|(_, y)| x * y).sum::<f64>()).sum()
    };
    for (bi, b) in fr.blocks.iter().enumerate() {
        let (n, t1, t2) = (b.normal, b.tangent, b.tangent + 1);
        if t2 >= rows.n_rows() || rows.node[t1] != rows.node[n] || rows.node[t2] != rows.node[n] {
            return fail("friction", format!("block {bi}: tangential rows {t1}, {t2} are not rows of row {n}'s node"));
        }
        if !(b.weight.is_finite() && b.weight > 0.0) || b.law >= fr.laws.len() {
            return fail("friction", format!("block {bi}: weight {} (must be finite, > 0), law {}", b.weight, b.law));
        }
        let (gn, g1, g2) = (dense(n), dense(t1), dense(t2));
        if [&gn, &g1, &g2].iter().all(|g| g.len() == 3) {
            let products =
                [inner(&g1, &g1) - 1.0, inner(&g2, &g2) - 1.0, inner(&g1, &g2), inner(&gn, &g1), inner(&gn, &g2)];
            if products.iter().any(|p| !le(p.abs(), 1e-12)) {
                return fail(
                    "friction",
                    format!(
                        "block {bi} ({}): the tangential rows are not an orthonormal basis of the normal row's tangent \
                         plane: |t₁|² − 1, |t₂|² − 1, t₁·t₂, n·t₁, n·t₂ = {products:?}",
                        rows.node[n]
                    ),
                );
            }
        }
    }
    let mut rng = StdRng::seed_from_u64(seed);
    for law in &fr.laws {
        if let Err(e) = law.validate("obstacle.friction") {
            return fail("friction", e.to_string());
        }
        for s in 0..SAMPLES {
            let (w, ln) = (rng.random_range(0.1..2.0), rng.random_range(0.0..2.0));
            let r = law.radius(w, ln);
            let t = [rng.random_range(-3.0..3.0) * r.max(1e-3), rng.random_range(-3.0..3.0) * r.max(1e-3)];
            let p = law.project(w, ln, t);
            let q = law.project(w, ln, p);
            let inside = [0.5 * p[0], 0.5 * p[1]];
            let tol = 1e-12 * (1.0 + r + t[0].hypot(t[1]));
            if !le(p[0].hypot(p[1]), r + tol)
                || !le((q[0] - p[0]).hypot(q[1] - p[1]), tol)
                || law.project(w, ln, inside) != inside
            {
                return fail(
                    "friction",
                    format!(
                        "sample {s}: {:?}.project({w}, {ln}, {t:?}) = {p:?} for radius {r}: not the disc's projection",
                        law.name()
                    ),
                );
            }
            let (dt, dn) = law.project_derivative(w, ln, t);
            let h = 1e-6 * (1.0 + t[0].hypot(t[1]));
            for k in 0..3 {
                let step = |sign: f64| {
                    let mut tt = t;
                    let mut l = ln;
                    if k < 2 {
                        tt[k] += sign * h
                    } else {
                        l += sign * h
                    }
                    law.project(w, l, tt)
                };
                let (pp, pm) = (step(1.0), step(-1.0));
                for i in 0..2 {
                    let fd = (pp[i] - pm[i]) / (2.0 * h);
                    let an = if k < 2 { dt[i][k] } else { dn[i] };
                    // central differences of a map smooth away from the rim: O(h²) + round-off/h
                    if !le((fd - an).abs(), 1e-6 * (1.0 + an.abs())) {
                        return fail(
                            "friction",
                            format!(
                                "sample {s}: ∂P_{i}/∂{} = {an:e}, central difference {fd:e}",
                                ["t₁", "t₂", "λ_n"][k]
                            ),
                        );
                    }
                }
            }
        }
    }
    Ok(())
}

/// (f) `rows_at_factor` (when the plugin can scale its load): the rows a load step at factors
/// 0, ½ and 2 gets from the obstacle's own rows are those of the scaled obstacle discretised
/// afresh — bit for bit: a step's rows must not depend on whether they were remade.
pub fn check_rows_at_factor(k: &dyn AdmissibleDisplacements, mesh: &TetMesh, dofs: &DofMap) -> Result<(), KitFailure> {
    let Ok(rows) = k.discretise(mesh, dofs, "obstacle") else { return Ok(()) };
    for factor in [0.0, 0.5, 2.0] {
        let Some(scaled) = k.scaled_load(factor) else { return Ok(()) };
        let fresh = match scaled.discretise(mesh, dofs, "obstacle") {
            Ok(r) => r,
            Err(e) => return fail("rows_at_factor", format!("scaled_load({factor}) does not discretise: {e}")),
        };
        match k.rows_at_factor(factor, &rows, mesh, dofs, "obstacle") {
            Ok(r) if *r == fresh => {}
            Ok(r) => {
                let worst = (0..r.n_rows().min(fresh.n_rows()))
                    .map(|i| (r.offset[i] - fresh.offset[i]).abs())
                    .fold(0.0, f64::max);
                return fail(
                    "rows_at_factor",
                    format!(
                        "rows_at_factor({factor}) differs from scaled_load({factor}).discretise(): {} rows against {}, \
                         largest offset difference {worst:e}",
                        r.n_rows(),
                        fresh.n_rows()
                    ),
                );
            }
            Err(e) => return fail("rows_at_factor", format!("rows_at_factor({factor}) fails: {e}")),
        }
    }
    Ok(())
}

/// (e) `scaled_load` (when the plugin has it): factor 1 gives the same obstacle (the same load
/// term and the same rows), factor 2 doubles the load term and keeps the number of rows and
/// of extra unknowns, and factor 0 (the ends of a load path) discretises with no load.
pub fn check_scaled_load(k: &dyn AdmissibleDisplacements, mesh: &TetMesh, dofs: &DofMap) -> Result<(), KitFailure> {
    let (Some(one), Some(two)) = (k.scaled_load(1.0), k.scaled_load(2.0)) else { return Ok(()) };
    let rows = |k: &dyn AdmissibleDisplacements| k.discretise(mesh, dofs, "obstacle");
    let (r, r1, r2) = match (rows(k), rows(one.as_ref()), rows(two.as_ref())) {
        (Ok(a), Ok(b), Ok(c)) => (a, b, c),
        (a, b, c) => {
            let e = [a.err(), b.err(), c.err()].into_iter().flatten().next().map(|e| e.to_string());
            return fail("scaled_load", format!("the scaled obstacle does not discretise: {e:?}"));
        }
    };
    if one.load() != k.load() || r1 != r {
        return fail("scaled_load", "scaled_load(1) differs from the obstacle (load term or rows)".into());
    }
    let doubled: Vec<f64> = k.load().iter().map(|f| 2.0 * f).collect();
    if two.load() != doubled {
        return fail("scaled_load", format!("scaled_load(2).load() = {:?}, not 2 × {:?}", two.load(), k.load()));
    }
    // factor 0 (the start and end of a load path, theory §11.3) discretises too, with no load
    let Some(zero) = k.scaled_load(0.0) else {
        return fail("scaled_load", "scaled_load(0) is None while scaled_load(1) is not".into());
    };
    let r0 = match rows(zero.as_ref()) {
        Ok(r) => r,
        Err(e) => return fail("scaled_load", format!("scaled_load(0) does not discretise: {e}")),
    };
    if zero.load().iter().any(|f| *f != 0.0) || (r0.n_rows(), r0.n_extras) != (r.n_rows(), r.n_extras) {
        return fail(
            "scaled_load",
            format!(
                "scaled_load(0) has load {:?}, {} rows and {} extras; expected zero load, {} and {}",
                zero.load(),
                r0.n_rows(),
                r0.n_extras,
                r.n_rows(),
                r.n_extras
            ),
        );
    }
    // the rows at factor 2 may differ (a prescribed displacement moves a curved obstacle, whose
    // normals change), but not in number or in extra unknowns
    if (r2.n_rows(), r2.n_extras) != (r.n_rows(), r.n_extras) {
        return fail(
            "scaled_load",
            format!(
                "scaled_load(2) has {} rows and {} extras, not {} and {}",
                r2.n_rows(),
                r2.n_extras,
                r.n_rows(),
                r.n_extras
            ),
        );
    }
    Ok(())
}

/// (d) The rows are well formed, finite and none is identically zero in u and V.
pub fn check_rows(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
    scale: f64,
) -> Result<(), KitFailure> {
    Ctx::new(k, mesh, dofs, seed, scale).map(|_| ())
}

/// (a) The rows are the linearisation of `gap()` at (0, 0): derivatives along random
/// directions (`gap_derivative`), then values (`gap_value`).
pub fn check_linearisation(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
    scale: f64,
) -> Result<(), KitFailure> {
    let mut ctx = Ctx::new(k, mesh, dofs, seed, scale)?;
    ctx.derivatives()?;
    ctx.values()
}

/// (b) The load term, the force and the rest of the report for balanced multipliers.
pub fn check_load(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
    scale: f64,
) -> Result<(), KitFailure> {
    Ctx::new(k, mesh, dofs, seed, scale)?.load()
}

/// (c) The Euclidean projection onto K_h: feasible, idempotent, the variational inequality.
pub fn check_projection(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    seed: u64,
    scale: f64,
) -> Result<(), KitFailure> {
    Ctx::new(k, mesh, dofs, seed, scale)?.projection()
}

/// The obstacle discretised on the mesh, with a random source and tolerances.
struct Ctx<'a> {
    k: &'a dyn AdmissibleDisplacements,
    mesh: &'a TetMesh,
    dofs: &'a DofMap,
    rows: ConstraintRows,
    rng: StdRng,
    scale: f64,
    /// Absolute tolerance on g.
    tol: f64,
}

/// (max |x_i|, argmax); NaN counts as +∞.
fn max_abs(x: impl IntoIterator<Item = f64>) -> (f64, usize) {
    let mut best = (0.0, 0);
    for (i, v) in x.into_iter().enumerate() {
        let a = if v.is_nan() { f64::INFINITY } else { v.abs() };
        if a > best.0 {
            best = (a, i);
        }
    }
    best
}

/// (argmin, min); NaN counts as −∞.
fn min_at(g: &[f64]) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for (i, &v) in g.iter().enumerate() {
        if v.is_nan() || v < best.1 {
            best = (i, v);
        }
    }
    best
}

/// a ≤ b; false when either is NaN, so that a NaN fails every check.
fn le(a: f64, b: f64) -> bool {
    a <= b
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl<'a> Ctx<'a> {
    fn new(
        k: &'a dyn AdmissibleDisplacements,
        mesh: &'a TetMesh,
        dofs: &'a DofMap,
        seed: u64,
        scale: f64,
    ) -> Result<Self, KitFailure> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(KitFailure {
                check: "setup",
                message: format!("the displacement scale must be finite and > 0, got {scale}"),
            });
        }
        let rows = k
            .discretise(mesh, dofs, "obstacle")
            .map_err(|e| KitFailure { check: "discretise", message: e.to_string() })?;
        shape(k, mesh, dofs, &rows)?;
        entries(&rows)?;
        let row_norm = (0..rows.n_rows())
            .map(|i| rows.row(i).1.iter().chain(rows.extra_row(i)).map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let tol = 1e-9 * (max_abs(rows.offset.iter().copied()).0 + scale * row_norm);
        Ok(Self { k, mesh, dofs, rows, rng: StdRng::seed_from_u64(seed), scale, tol })
    }

    /// The normal rows alone (all rows without friction): the constraints of K_h on (w, V).
    fn normal_rows(&self) -> ConstraintRows {
        if !self.rows.has_friction() {
            return self.rows.clone();
        }
        let tangential = self.rows.friction.tangential_mask(self.rows.n_rows());
        let mut rows = ConstraintRows::new(self.rows.n_extras);
        for i in (0..self.rows.n_rows()).filter(|&i| !tangential[i]) {
            let (c, v) = self.rows.row(i);
            let e: Vec<(usize, f64)> = c.iter().copied().zip(v.iter().copied()).collect();
            rows.push(&e, self.rows.extra_row(i), self.rows.offset[i], self.rows.node[i]);
        }
        rows
    }

    fn n_free(&self) -> usize {
        self.dofs.n_free
    }

    fn n_extras(&self) -> usize {
        self.rows.n_extras
    }

    /// n entries uniform in (−s, s).
    fn random(&mut self, n: usize, s: f64) -> Vec<f64> {
        (0..n).map(|_| s * self.rng.random_range(-1.0..1.0)).collect()
    }

    /// g from the plugin's `gap()`.
    fn kgap(&self, u: &[f64], v: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; self.rows.n_rows()];
        self.k.gap(self.mesh, self.dofs, &self.rows, u, v, &mut g);
        g
    }

    /// g from the rows.
    fn rgap(&self, u: &[f64], v: &[f64]) -> Vec<f64> {
        let mut g = vec![0.0; self.rows.n_rows()];
        self.rows.gap(u, v, &mut g);
        g
    }

    /// G du + H dv.
    fn linear(&self, du: &[f64], dv: &[f64]) -> Vec<f64> {
        (0..self.rows.n_rows()).map(|i| self.rows.row_times(i, du) + dot(self.rows.extra_row(i), dv)).collect()
    }

    fn where_(&self, i: usize) -> String {
        let n = self.rows.node[i];
        let x = self.mesh.nodes[n];
        format!("row {i} (node {n} at ({}, {}, {}))", x[0], x[1], x[2])
    }

    /// Central differences of gap() at (0, 0) (step `h`) along (du, dv) against G du + H dv, for
    /// every row; `None` when they agree.
    fn fd_mismatch(&self, du: &[f64], dv: &[f64], h: f64) -> Option<Mismatch> {
        let scaled = |x: &[f64], t: f64| x.iter().map(|v| t * v).collect::<Vec<_>>();
        let plus = self.kgap(&scaled(du, h), &scaled(dv, h));
        let minus = self.kgap(&scaled(du, -h), &scaled(dv, -h));
        let fd: Vec<f64> = plus.iter().zip(&minus).map(|(p, m)| (p - m) / (2.0 * h)).collect();
        let lin = self.linear(du, dv);
        let (err, i) = max_abs(fd.iter().zip(&lin).map(|(a, b)| a - b));
        let mag = max_abs(lin.iter().copied()).0.max(max_abs(fd.iter().copied()).0);
        let gmag = max_abs(plus.iter().chain(&minus).copied()).0;
        let tol = 1e-6 * mag + 1e2 * f64::EPSILON * gmag / h;
        (!le(err, tol)).then(|| Mismatch { row: i, fd: fd[i], lin: lin[i], err, tol })
    }

    /// At most [`COMPONENT_NODES`] distinct row nodes, all of them when there are few, else a
    /// random sample.
    fn sample_nodes(&mut self) -> Vec<usize> {
        let mut nodes = self.rows.node.clone();
        nodes.sort_unstable();
        nodes.dedup();
        if nodes.len() > COMPONENT_NODES {
            // partial Fisher–Yates
            for i in 0..COMPONENT_NODES {
                let j = self.rng.random_range(i..nodes.len());
                nodes.swap(i, j);
            }
            nodes.truncate(COMPONENT_NODES);
            nodes.sort_unstable();
        }
        nodes
    }

    /// Central differences of gap() at (0, 0) against G du and H dV: along each free
    /// displacement component of (a sample of) the row nodes, along each extra unknown, then
    /// along random directions.
    fn derivatives(&mut self) -> Result<(), KitFailure> {
        let h = 1e-3 * self.scale;
        let names = self.k.extra_names();
        let zero_v = vec![0.0; self.n_extras()];
        let mut du = vec![0.0; self.n_free()];
        for n in self.sample_nodes() {
            for (c, axis) in ["x₁", "x₂", "x₃"].iter().enumerate() {
                let Some(j) = self.dofs.free(n, c) else { continue };
                du[j] = 1.0;
                if let Some(m) = self.fd_mismatch(&du, &zero_v, h) {
                    return fail(
                        "gap_derivative",
                        format!(
                            "∂g/∂u along {axis} of node {n} (free dof {j}, du = e_{j}), {}: the central difference of gap() \
                             (step {h:e}) is {:.6e}, the rows' G·du is {:.6e}: difference {:.3e} > tolerance {:.1e}",
                            self.where_(m.row),
                            m.fd,
                            m.lin,
                            m.err,
                            m.tol
                        ),
                    );
                }
                du[j] = 0.0;
            }
        }
        let zero_u = vec![0.0; self.n_free()];
        for (k, name) in names.iter().enumerate() {
            let mut dv = zero_v.clone();
            dv[k] = 1.0;
            if let Some(m) = self.fd_mismatch(&zero_u, &dv, h) {
                return fail(
                    "gap_derivative",
                    format!(
                        "∂g/∂V along the extra `{name}` (dV = e_{k}), {}: the central difference of gap() (step {h:e}) is \
                         {:.6e}, the rows' H·dV is {:.6e}: difference {:.3e} > tolerance {:.1e}",
                        self.where_(m.row),
                        m.fd,
                        m.lin,
                        m.err,
                        m.tol
                    ),
                );
            }
        }
        for s in 0..SAMPLES {
            for in_u in [true, false] {
                if !in_u && self.n_extras() == 0 {
                    continue;
                }
                let (du, dv) = if in_u {
                    (self.random(self.n_free(), 1.0), vec![0.0; self.n_extras()])
                } else {
                    (vec![0.0; self.n_free()], self.random(self.n_extras(), 1.0))
                };
                if let Some(m) = self.fd_mismatch(&du, &dv, h) {
                    let (what, term) = if in_u { ("∂g/∂u", "G·du") } else { ("∂g/∂V", "H·dV") };
                    return fail(
                        "gap_derivative",
                        format!(
                            "{what} along random direction {s}, {}: the central difference of gap() (step {h:e}) is {:.6e}, \
                             the rows' {term} is {:.6e}: difference {:.3e} > tolerance {:.1e}",
                            self.where_(m.row),
                            m.fd,
                            m.lin,
                            m.err,
                            m.tol
                        ),
                    );
                }
            }
        }
        Ok(())
    }

    /// Offsets = gap(0, 0); rows and gap() agree at random (u, V), at least to second order.
    fn values(&mut self) -> Result<(), KitFailure> {
        let g0 = self.kgap(&vec![0.0; self.n_free()], &vec![0.0; self.n_extras()]);
        let (e0, i) = max_abs(g0.iter().zip(&self.rows.offset).map(|(a, b)| a - b));
        if !le(e0, self.tol) {
            return fail(
                "gap_value",
                format!(
                    "at (u, V) = 0, {}: the offset c = {:.6e} but gap() = {:.6e} (difference {e0:.3e} > tolerance {:.1e}); \
                     the offsets must be g(0, 0)",
                    self.where_(i),
                    self.rows.offset[i],
                    g0[i],
                    self.tol
                ),
            );
        }
        for s in 0..SAMPLES {
            let u = self.random(self.n_free(), self.scale);
            let v = self.random(self.n_extras(), self.scale);
            let diff = |ctx: &Self, t: f64| {
                let (ut, vt): (Vec<f64>, Vec<f64>) =
                    (u.iter().map(|x| t * x).collect(), v.iter().map(|x| t * x).collect());
                let (r, g) = (ctx.rgap(&ut, &vt), ctx.kgap(&ut, &vt));
                let (e, i) = max_abs(r.iter().zip(&g).map(|(a, b)| a - b));
                (e, i, r[i], g[i])
            };
            let (e1, i, r, g) = diff(self, 1.0);
            if e1 <= self.tol {
                continue;
            }
            let (e4, ..) = diff(self, 0.25);
            if !le(e4, e1 / 8.0 + self.tol) {
                return fail(
                    "gap_value",
                    format!(
                        "at random (u, V) {s} of size {:e}, {}: the rows give {r:.6e} and gap() {g:.6e} (difference {e1:.3e} > \
                         tolerance {:.1e}); at a quarter of that (u, V) they still differ by {e4:.3e}, more than the \
                         second-order {:.3e}: the rows are not the linearisation of gap()",
                        self.scale,
                        self.where_(i),
                        self.tol,
                        e1 / 16.0
                    ),
                );
            }
        }
        Ok(())
    }

    /// Load entries, balanced multipliers, force = Σλ and report consistency.
    fn load(&mut self) -> Result<(), KitFailure> {
        let f = self.k.load();
        let names = self.k.extra_names();
        if f.len() != names.len() {
            return fail(
                "load",
                format!("load() has {} entries for the {} extra unknowns {names:?}", f.len(), names.len()),
            );
        }
        if let Some(j) = f.iter().position(|v| !v.is_finite()) {
            return fail("load", format!("load()[{j}] (on extra `{}`) = {} is not finite", names[j], f[j]));
        }
        let lambda = self.balanced(&f)?;
        let extras = self.random(self.n_extras(), self.scale);
        let report = self.k.report(self.mesh, &self.rows, &extras, &lambda);
        if let Some(force) = report.get("force") {
            self.force(&f, &names, &lambda, &extras, force)?;
        }
        let expected = normal_contact_set(&self.rows, &lambda).len();
        if report.contact_nodes != expected {
            return fail(
                "report",
                format!("the report counts {} contact nodes, contact_set(λ) has {expected}", report.contact_nodes),
            );
        }
        if !(report.contact_radius.is_finite() && report.contact_radius >= 0.0) {
            return fail("report", format!("the contact radius {} is not finite and >= 0", report.contact_radius));
        }
        if let Some((name, v)) = report.quantities.iter().find(|(_, v)| !v.is_finite()) {
            return fail("report", format!("the reported quantity {name} = {v} is not finite"));
        }
        for (name, &x) in names.iter().zip(&extras) {
            if let Some(v) = report.get(name)
                && !le((v - x).abs(), 1e-12 * x.abs())
            {
                return fail(
                    "report",
                    format!("the report gives {name} = {v:e}, but the extra unknown {name} is {x:e}"),
                );
            }
        }
        let zero = vec![0.0; self.rows.n_rows()];
        let report = self.k.report(self.mesh, &self.rows, &extras, &zero);
        let force = report.get("force").unwrap_or(0.0);
        if report.contact_nodes != 0 || report.contact_radius != 0.0 || force != 0.0 {
            return fail(
                "report",
                format!(
                    "for λ = 0 the report gives {} contact nodes, contact radius {} and force {force}; expected 0, 0 and 0",
                    report.contact_nodes, report.contact_radius
                ),
            );
        }
        Ok(())
    }

    /// The reported `force` for the balanced λ: with extras, the resultant on the first one,
    /// −(Hᵀλ)₀ (Σλ for the punches, whose H column is −1); without extras, linear in λ.
    fn force(
        &mut self,
        f: &[f64],
        names: &[String],
        lambda: &[f64],
        extras: &[f64],
        force: f64,
    ) -> Result<(), KitFailure> {
        let sum: f64 = lambda.iter().sum();
        if self.n_extras() > 0 {
            let (resultant, size) = lambda.iter().enumerate().fold((0.0, 0.0), |(r, s), (i, &l)| {
                let t = -l * self.rows.extra_row(i)[0];
                (r + t, s + t.abs())
            });
            if !le((force - resultant).abs(), 1e-12 * size + f64::MIN_POSITIVE) {
                return fail(
                    "force",
                    format!(
                        "for multipliers λ ≥ 0 balancing the load f = {f:?} (Hᵀλ = −f), the report gives force = \
                         {force:.12e}, but the resultant on the extra `{}` is −(Hᵀλ)₀ = {resultant:.12e} (Σλ = {sum:.12e})",
                        names[0]
                    ),
                );
            }
            return Ok(());
        }
        let other: Vec<f64> = (0..lambda.len()).map(|_| self.rng.random_range(0.0..1.0)).collect();
        let of = |l: &[f64]| self.k.report(self.mesh, &self.rows, extras, l).get("force").unwrap_or(f64::NAN);
        let f_other = of(&other);
        let f_sum = of(&lambda.iter().zip(&other).map(|(a, b)| a + b).collect::<Vec<_>>());
        let f_double = of(&lambda.iter().map(|a| 2.0 * a).collect::<Vec<_>>());
        let tol = 1e-10 * (force.abs() + f_other.abs()) + f64::MIN_POSITIVE;
        if !le((f_sum - force - f_other).abs(), tol) || !le((f_double - 2.0 * force).abs(), tol) {
            return fail(
                "force",
                format!(
                    "the reported force is not linear in the multipliers: force(λ) = {force:.12e}, force(λ') = \
                     {f_other:.12e}, force(λ + λ') = {f_sum:.12e}, force(2λ) = {f_double:.12e} (Σλ = {sum:.12e})"
                ),
            );
        }
        Ok(())
    }

    /// λ ≥ 0 with Hᵀλ = −f, closest to a random λ̃ ≥ 0 (any random λ̃ without extras).
    /// With friction the tangential multipliers have either sign (theory §8.3): each
    /// tangential row enters twice, as itself and negated, both with λ ≥ 0, and its λ is the
    /// difference.
    fn balanced(&mut self, f: &[f64]) -> Result<Vec<f64>, KitFailure> {
        let rows = self.rows.n_rows();
        let tangential = self.rows.friction.tangential_mask(rows);
        let negated: Vec<usize> = (0..rows).filter(|&i| tangential[i]).collect();
        let n = rows + negated.len();
        let m = self.n_extras();
        let fold = |x: &[f64]| -> Vec<f64> {
            let mut l = x[..rows].to_vec();
            negated.iter().enumerate().for_each(|(k, &i)| l[i] -= x[rows + k]);
            l
        };
        let mut lt: Vec<f64> =
            (0..n).map(|_| if self.rng.random_bool(0.25) { 0.0 } else { self.rng.random_range(0.0..1.0) }).collect();
        if m == 0 {
            return Ok(fold(&lt));
        }
        let h = DMatrix::from_fn(n, m, |i, k| {
            if i < rows { self.rows.extra_row(i)[k] } else { -self.rows.extra_row(negated[i - rows])[k] }
        });
        let fv = DVector::from_column_slice(f);
        // bring λ̃ to the size of the load
        let ht_lt = h.transpose() * DVector::from_column_slice(&lt);
        if ht_lt.amax() > 0.0 {
            let s = fv.amax() / ht_lt.amax();
            lt.iter_mut().for_each(|v| *v *= s);
        }
        let lt = DVector::from_vec(lt);
        // min ½|λ − λ̃|² subject to Hᵀλ = −f, λ ≥ 0
        let exact = DenseQp::new(DMatrix::identity(n, n), h.transpose(), -&fv)
            .and_then(|mut qp| qp.solve(&(-&lt)).map(|s| s.x.clone()));
        let lambda = match exact {
            Ok(x) => x,
            Err(_) => {
                // least-norm start not ≥ 0: min ½|Hᵀλ + f|² + ½ε|λ − λ̃|² over λ ≥ 0
                let hht = &h * h.transpose();
                let eps = 1e-10 * hht.diagonal().amax().max(f64::MIN_POSITIVE);
                let s = hht + DMatrix::identity(n, n) * eps;
                let q = &h * &fv - &lt * eps;
                let mut qp = DenseQp::new(s, DMatrix::zeros(0, n), DVector::zeros(0))
                    .map_err(|e| KitFailure { check: "load", message: format!("balancing the load: {e}") })?;
                let x = qp
                    .solve(&q)
                    .map_err(|e| KitFailure { check: "load", message: format!("balancing the load: {e}") })?;
                x.x.clone()
            }
        };
        let res = h.transpose() * &lambda + &fv;
        let tol = 1e-8 * fv.amax().max((h.transpose() * &lambda).amax());
        if !le(res.amax(), tol) || lambda.iter().any(|v| *v < 0.0) {
            return Err(KitFailure {
                check: "load",
                message: format!(
                    "no multipliers λ ≥ 0 balance the load f = {f:?}: the best found leaves |Hᵀλ + f| = {:.3e} (tolerance \
                     {tol:.1e}); the KKT condition Hᵀλ = −f on the extra unknowns (theory §3) cannot hold, so the discrete \
                     problem has no solution",
                    res.amax()
                ),
            });
        }
        Ok(fold(lambda.as_slice()))
    }

    /// Projections of random points: feasible, idempotent, the variational inequality.
    fn projection(&mut self) -> Result<(), KitFailure> {
        let normal = self.normal_rows();
        let mut points = Vec::with_capacity(SAMPLES);
        for s in 0..SAMPLES {
            let z = self.random(self.n_free(), self.scale);
            let zv = self.random(self.n_extras(), self.scale);
            let Projected { u: w, extras: wv, .. } = project_euclidean(&normal, &z, &zv).map_err(|e| KitFailure {
                check: "projection",
                message: format!("projecting random point {s}: {e}"),
            })?;
            let tangential = self.rows.friction.tangential_mask(self.rows.n_rows());
            for (which, mut g) in [("the rows", self.rgap(&w, &wv)), ("gap()", self.kgap(&w, &wv))] {
                // the tangential rows are slips, not constraints (theory §8.3)
                g.iter_mut().zip(&tangential).filter(|(_, t)| **t).for_each(|(x, _)| *x = f64::INFINITY);
                let (i, gmin) = min_at(&g);
                if !le(-self.tol, gmin) {
                    return fail(
                        "projection_feasible",
                        format!(
                            "the projection of random point {s} violates {}: {which} give g = {gmin:.6e} < −{:.1e}",
                            self.where_(i),
                            self.tol
                        ),
                    );
                }
            }
            let Projected { u: w2, extras: wv2, .. } = project_euclidean(&normal, &w, &wv).map_err(|e| KitFailure {
                check: "projection",
                message: format!("re-projecting random point {s}: {e}"),
            })?;
            let moved = max_abs(w2.iter().zip(&w).chain(wv2.iter().zip(&wv)).map(|(a, b)| a - b)).0;
            let size = max_abs(w.iter().chain(&wv).copied()).0 + self.scale;
            if !le(moved, 1e-9 * size) {
                return fail(
                    "projection_idempotent",
                    format!(
                        "projecting the projection of random point {s} again moves it by {moved:.3e} (size {size:.3e})"
                    ),
                );
            }
            points.push(([z, zv].concat(), [w, wv].concat()));
        }
        for (a, (z, p)) in points.iter().enumerate() {
            let r: Vec<f64> = z.iter().zip(p).map(|(x, y)| x - y).collect();
            for (b, (_, w)) in points.iter().enumerate().filter(|(b, _)| *b != a) {
                let d: Vec<f64> = w.iter().zip(p).map(|(x, y)| x - y).collect();
                let vi = dot(&r, &d);
                let tol = 1e-9 * dot(&r, &r).sqrt() * dot(&d, &d).sqrt();
                if !le(vi, tol) {
                    return fail(
                        "projection_vi",
                        format!(
                            "(z − Pz)·(w − Pz) = {vi:.3e} > {tol:.1e} for z = random point {a} and the feasible w = P(point {b}): \
                             Pz is not the closest point of K_h"
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

/// Structure of the rows against the mesh, the dofs and the extra unknowns.
fn shape(
    k: &dyn AdmissibleDisplacements,
    mesh: &TetMesh,
    dofs: &DofMap,
    rows: &ConstraintRows,
) -> Result<(), KitFailure> {
    let n = rows.n_rows();
    let names = k.extra_names();
    let problem = if n == 0 {
        Some("discretise returned no rows; the kit needs a mesh on which the obstacle has at least one row".to_string())
    } else if rows.n_extras != names.len() {
        Some(format!("the rows have {} extra columns (H), but extra_names() gives {names:?}", rows.n_extras))
    } else if rows.row_ptr.len() != n + 1
        || rows.row_ptr[0] != 0
        || rows.row_ptr.windows(2).any(|w| w[1] < w[0])
        || rows.row_ptr[n] != rows.col.len()
        || rows.col.len() != rows.val.len()
    {
        Some(format!(
            "malformed CSR: {} rows, {} row pointers ending at {:?}, {} columns, {} values",
            n,
            rows.row_ptr.len(),
            rows.row_ptr.last(),
            rows.col.len(),
            rows.val.len()
        ))
    } else if rows.extra.len() != n * rows.n_extras {
        Some(format!("H has {} entries for {n} rows × {} extras", rows.extra.len(), rows.n_extras))
    } else if rows.node.len() != n {
        Some(format!("{} row nodes for {n} rows", rows.node.len()))
    } else if let Some(&j) = rows.col.iter().find(|&&j| j >= dofs.n_free) {
        Some(format!("a row refers to dof {j}, but there are {} free dofs", dofs.n_free))
    } else {
        rows.node
            .iter()
            .find(|&&v| v >= mesh.n_nodes())
            .map(|v| format!("a row belongs to node {v}, but the mesh has {} nodes", mesh.n_nodes()))
    };
    match problem {
        Some(message) => fail("rows", message),
        None => Ok(()),
    }
}

/// Every entry finite, no row identically zero in u and V.
fn entries(rows: &ConstraintRows) -> Result<(), KitFailure> {
    for i in 0..rows.n_rows() {
        let (cols, vals) = rows.row(i);
        let h = rows.extra_row(i);
        let c = rows.offset[i];
        if vals.iter().chain(h).chain([&c]).any(|v| !v.is_finite()) {
            return fail(
                "rows",
                format!("row {i} (node {}) has a non-finite entry: G {vals:?}, H {h:?}, c = {c}", rows.node[i]),
            );
        }
        // sum duplicate columns before deciding that the u part vanishes
        let mut g: Vec<(usize, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
        g.sort_by_key(|e| e.0);
        let mut u_part = false;
        for run in g.chunk_by(|a, b| a.0 == b.0) {
            u_part |= run.iter().map(|e| e.1).sum::<f64>() != 0.0;
        }
        if !u_part && h.iter().all(|v| *v == 0.0) {
            return fail(
                "rows",
                format!(
                    "row {i} (node {}) is identically zero in u and V: the constant constraint c = {c} ≥ 0",
                    rows.node[i]
                ),
            );
        }
    }
    Ok(())
}
