//! Linear elasticity (P1 tetrahedra) on a cantilever box, assembled per rank from METIS parts and
//! solved through PETSc, against a serial sparse Cholesky solve of the same system (saddle-core's
//! faer factorisation), at any number of ranks (`mpirun -n N`; .ci/run-mpi-tests).
//!
//! The cantilever [0, 4] × [0, 1] × [0, 1] (24 × 6 × 6 cells, 3675 unknowns) is clamped at x = 0
//! and loaded by its weight (0, 0, −1); E = 1, ν = 0.3.

mod common;

use common::distributed::{Case, Distribution, ensure, run};
use saddle_core::TetMesh;
use saddle_core::linalg::{LowerCsc, SparseCholesky};
use saddle_mpi::{GhostVector, Index, Ksp, Matrix, Method, Petsc, Settings, SolveReport, sum_in_place};
use std::collections::BTreeMap;
use std::process::ExitCode;

const LENGTH: f64 = 4.0;
const NU: f64 = 0.3;

/// Agreement with the serial direct solve (issue 24's 1e-8): CG stops at a relative residual of
/// 1e-12; the measured relative errors are ≤ 1.6e-12 for every method at 1, 2 and 3 ranks (MUMPS
/// against the serial Cholesky too: the system's condition number times the rounding).
const AGREEMENT: f64 = 1e-8;

/// The problem every case solves, with its serial reference solutions.
struct Beam {
    mesh: TetMesh,
    dist: Distribution,
    /// Clamped nodes (old numbering).
    fixed: Vec<bool>,
    /// Young's modulus per element: uniform, and stiffened ×2 on x < L/2 (the changed matrix).
    uniform: Vec<f64>,
    stiffened: Vec<f64>,
    reference: Vec<f64>,
    reference_stiffened: Vec<f64>,
}

impl Beam {
    fn new(petsc: &Petsc) -> Self {
        let mesh = common::box_mesh([LENGTH, 1.0, 1.0], [24, 6, 6]);
        let dist = Distribution::new(&mesh, petsc.size(), petsc.rank());
        let fixed = mesh.nodes.iter().map(|p| p[0] == 0.0).collect();
        let uniform = vec![1.0; mesh.tets.len()];
        let stiffened = (0..mesh.tets.len())
            .map(|e| {
                let cx: f64 = mesh.tets[e].iter().map(|&n| mesh.nodes[n][0]).sum::<f64>() / 4.0;
                if cx < LENGTH / 2.0 { 2.0 } else { 1.0 }
            })
            .collect();
        let mut beam = Self { mesh, dist, fixed, uniform, stiffened, reference: vec![], reference_stiffened: vec![] };
        beam.reference = beam.serial_solve(&beam.uniform);
        beam.reference_stiffened = beam.serial_solve(&beam.stiffened);
        beam
    }

    /// The element stiffness V BᵀDB (12 × 12, row-major) of element `e` and its volume.
    fn element(&self, e: usize, young: f64) -> ([f64; 144], f64) {
        let x: Vec<[f64; 3]> = self.mesh.tets[e].iter().map(|&n| self.mesh.nodes[n]).collect();
        let j: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| x[c + 1][r] - x[0][r]));
        let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
            + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
        // rows of J⁻¹ are the gradients of the barycentric coordinates λ₁, λ₂, λ₃
        let inv = |r: usize, c: usize| {
            let (r1, r2, c1, c2) = ((c + 1) % 3, (c + 2) % 3, (r + 1) % 3, (r + 2) % 3);
            (j[r1][c1] * j[r2][c2] - j[r1][c2] * j[r2][c1]) / det
        };
        let rows: [[f64; 3]; 3] = std::array::from_fn(|a| std::array::from_fn(|k| inv(a, k)));
        let grad = [std::array::from_fn(|k| -(rows[0][k] + rows[1][k] + rows[2][k])), rows[0], rows[1], rows[2]];
        let (lambda, mu) = (young * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)), young / (2.0 * (1.0 + NU)));
        let mut b = [[0.0; 12]; 6];
        for (a, g) in grad.iter().enumerate() {
            for k in 0..3 {
                b[k][3 * a + k] = g[k];
            }
            b[3][3 * a + 1] = g[2];
            b[3][3 * a + 2] = g[1];
            b[4][3 * a] = g[2];
            b[4][3 * a + 2] = g[0];
            b[5][3 * a] = g[1];
            b[5][3 * a + 1] = g[0];
        }
        let d = |r: usize, c: usize| match (r < 3, c < 3) {
            (true, true) => lambda + if r == c { 2.0 * mu } else { 0.0 },
            (false, false) if r == c => mu,
            _ => 0.0,
        };
        let volume = det.abs() / 6.0;
        let mut k = [0.0; 144];
        for p in 0..12 {
            for q in 0..12 {
                let mut s = 0.0;
                for r in 0..6 {
                    for c in 0..6 {
                        s += b[r][p] * d(r, c) * b[c][q];
                    }
                }
                k[12 * p + q] = volume * s;
            }
        }
        (k, volume)
    }

    /// The serial solution (old node numbering, 3 per node) by sparse Cholesky, clamped
    /// unknowns eliminated (identity rows).
    fn serial_solve(&self, young: &[f64]) -> Vec<f64> {
        let n = 3 * self.mesh.nodes.len();
        let fixed = |dof: usize| self.fixed[dof / 3];
        let mut lower: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        let mut rhs = vec![0.0; n];
        for (e, t) in self.mesh.tets.iter().enumerate() {
            let (k, volume) = self.element(e, young[e]);
            let dofs: Vec<usize> = t.iter().flat_map(|&v| (0..3).map(move |c| 3 * v + c)).collect();
            for (p, &r) in dofs.iter().enumerate() {
                rhs[r] -= if r % 3 == 2 { volume / 4.0 } else { 0.0 };
                for (q, &c) in dofs.iter().enumerate() {
                    if r >= c && !fixed(r) && !fixed(c) {
                        *lower.entry((c, r)).or_default() += k[12 * p + q];
                    }
                }
            }
        }
        for i in (0..n).filter(|&i| fixed(i)) {
            lower.insert((i, i), 1.0);
            rhs[i] = 0.0;
        }
        let mut col_ptr = vec![0; n + 1];
        for &(c, _) in lower.keys() {
            col_ptr[c + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = lower.keys().map(|&(_, r)| r).collect();
        let values: Vec<f64> = lower.values().copied().collect();
        let mut chol = SparseCholesky::analyse(LowerCsc::new(n, &col_ptr, &row_idx), "beam").expect("analyse");
        chol.factorise(&values).expect("positive definite");
        chol.solve(&mut rhs);
        rhs
    }

    /// The distributed index of unknown c of old node n.
    fn dof(&self, n: usize, c: usize) -> Index {
        (3 * self.dist.new_of_old[n] + c) as Index
    }

    /// The owned clamped rows.
    fn fixed_rows(&self) -> Vec<Index> {
        let owned = self.dist.owned();
        (0..self.mesh.nodes.len())
            .filter(|&n| self.fixed[n] && owned.contains(&self.dist.new_of_old[n]))
            .flat_map(|n| (0..3).map(move |c| (n, c)))
            .map(|(n, c)| self.dof(n, c))
            .collect()
    }

    /// Adds this rank's element matrices into `a`, assembles it and clamps the fixed rows.
    fn assemble_into(&self, a: &mut Matrix, young: &[f64]) -> Result<(), String> {
        for e in self.dist.my_elements() {
            let (k, _) = self.element(e, young[e]);
            let dofs: Vec<Index> = self.mesh.tets[e]
                .iter()
                .flat_map(|&n| (0..3).map(move |c| (n, c)))
                .map(|(n, c)| self.dof(n, c))
                .collect();
            a.add_values(&dofs, &dofs, &k).map_err(|e| e.to_string())?;
        }
        a.assemble().map_err(|e| e.to_string())?;
        a.zero_rows_columns(&self.fixed_rows(), 1.0).map_err(|e| e.to_string())
    }

    /// The stiffness matrix, with or without the rigid-body near-null space.
    fn matrix(&self, petsc: &Petsc, young: &[f64], near_null_space: bool) -> Result<Matrix, String> {
        let owned = self.dist.owned();
        let (d, o) = self.dist.preallocation(&self.mesh, 3);
        let mut a = Matrix::new(petsc, 3 * owned.len(), 3, &d, &o).map_err(|e| e.to_string())?;
        a.set_symmetric().map_err(|e| e.to_string())?;
        ensure(a.owned_rows() == (3 * owned.start..3 * owned.end), format!("rows {:?}", a.owned_rows()))?;
        self.assemble_into(&mut a, young)?;
        if near_null_space {
            let mut old_of_new = vec![0; self.mesh.nodes.len()];
            for (old, &new) in self.dist.new_of_old.iter().enumerate() {
                old_of_new[new] = old;
            }
            let coords: Vec<f64> = owned.map(|new| old_of_new[new]).flat_map(|n| self.mesh.nodes[n]).collect();
            a.set_rigid_body_near_null_space(petsc, &coords).map_err(|e| e.to_string())?;
        }
        Ok(a)
    }

    /// The load vector (weight, lumped) assembled through the ghosts, zero on clamped rows; the
    /// solution vector with the same layout.
    fn vectors(&self, petsc: &Petsc) -> Result<(GhostVector, GhostVector), String> {
        let owned = self.dist.owned();
        let ghosts = self.dist.ghost_nodes(&self.mesh);
        let ghost_dofs: Vec<Index> = ghosts.iter().flat_map(|&g| (0..3).map(move |c| (3 * g + c) as Index)).collect();
        let mut b = GhostVector::new(petsc, 3 * owned.len(), &ghost_dofs).map_err(|e| e.to_string())?;
        let local_of = |new: usize| match owned.contains(&new) {
            true => 3 * (new - owned.start),
            false => 3 * owned.len() + 3 * ghosts.binary_search(&new).expect("a ghost"),
        };
        {
            let mut local = b.local_mut().map_err(|e| e.to_string())?;
            local.fill(0.0);
            for e in self.dist.my_elements() {
                let (_, volume) = self.element(e, 1.0);
                for &n in &self.mesh.tets[e] {
                    local[local_of(self.dist.new_of_old[n]) + 2] -= volume / 4.0;
                }
            }
        }
        b.accumulate_ghosts().map_err(|e| e.to_string())?;
        {
            let mut local = b.local_mut().map_err(|e| e.to_string())?;
            for row in self.fixed_rows() {
                local[row as usize - 3 * owned.start] = 0.0;
            }
        }
        let x = b.duplicate().map_err(|e| e.to_string())?;
        Ok((b, x))
    }

    /// The distributed solution in the old numbering, on every rank.
    fn gather(&self, petsc: &Petsc, x: &GhostVector) -> Result<Vec<f64>, String> {
        let owned = self.dist.owned();
        let local = x.local().map_err(|e| e.to_string())?;
        let mut global = vec![0.0; 3 * self.mesh.nodes.len()];
        for (old, &new) in self.dist.new_of_old.iter().enumerate() {
            if owned.contains(&new) {
                global[3 * old..3 * old + 3].copy_from_slice(&local[3 * (new - owned.start)..][..3]);
            }
        }
        sum_in_place(petsc.world(), &mut global);
        Ok(global)
    }

    /// Solves with `method` on `a` and returns the report and the relative error against
    /// `reference`.
    fn solve(
        &self,
        petsc: &Petsc,
        a: &Matrix,
        method: Method,
        reference: &[f64],
    ) -> Result<(SolveReport, f64, Vec<f64>), String> {
        let (b, mut x) = self.vectors(petsc)?;
        let mut ksp =
            Ksp::new(petsc, &Settings { method, rtol: 1e-12, ..Settings::default() }).map_err(|e| e.to_string())?;
        ksp.set_operator(a).map_err(|e| e.to_string())?;
        let report = ksp.solve(&b, &mut x).map_err(|e| e.to_string())?;
        let u = self.gather(petsc, &x)?;
        Ok((report, relative_error(&u, reference), u))
    }
}

fn relative_error(u: &[f64], reference: &[f64]) -> f64 {
    let diff: f64 = u.iter().zip(reference).map(|(a, b)| (a - b).powi(2)).sum();
    let norm: f64 = reference.iter().map(|b| b * b).sum();
    (diff / norm).sqrt()
}

fn say(petsc: &Petsc, line: String) {
    if petsc.rank() == 0 {
        println!("    {line}");
    }
}

/// CG + GAMG with the rigid-body modes agrees with the direct serial solve, in fewer iterations
/// than without them.
fn gamg_near_null_space(petsc: &Petsc, beam: &Beam) -> Result<(), String> {
    let with = beam.matrix(petsc, &beam.uniform, true)?;
    let (report, error, _) = beam.solve(petsc, &with, Method::CgGamg, &beam.reference)?;
    let without = beam.matrix(petsc, &beam.uniform, false)?;
    let (plain, plain_error, _) = beam.solve(petsc, &without, Method::CgGamg, &beam.reference)?;
    say(
        petsc,
        format!(
            "GAMG with rigid-body modes: {} iterations ({}), relative error {error:.2e}",
            report.iterations, report.reason
        ),
    );
    say(
        petsc,
        format!("GAMG without: {} iterations ({}), relative error {plain_error:.2e}", plain.iterations, plain.reason),
    );
    ensure(error <= AGREEMENT && plain_error <= AGREEMENT, format!("errors {error:e}, {plain_error:e}"))?;
    ensure(
        report.iterations < plain.iterations,
        format!("GAMG with the near-null space took {} iterations, without {}", report.iterations, plain.iterations),
    )
}

/// MUMPS (direct) agrees with the serial solve and with CG + GAMG.
fn mumps_agrees(petsc: &Petsc, beam: &Beam) -> Result<(), String> {
    let a = beam.matrix(petsc, &beam.uniform, true)?;
    let (direct, error, u_direct) = beam.solve(petsc, &a, Method::Mumps, &beam.reference)?;
    let (_, _, u_cg) = beam.solve(petsc, &a, Method::CgGamg, &beam.reference)?;
    let against_cg = relative_error(&u_cg, &u_direct);
    say(
        petsc,
        format!(
            "MUMPS: {} ({} iterations), relative error {error:.2e}, against CG+GAMG {against_cg:.2e}",
            direct.reason, direct.iterations
        ),
    );
    ensure(error <= AGREEMENT && against_cg <= AGREEMENT, format!("MUMPS error {error:e}, against CG {against_cg:e}"))
}

/// CG + BoomerAMG agrees with the serial solve.
fn boomeramg_agrees(petsc: &Petsc, beam: &Beam) -> Result<(), String> {
    let a = beam.matrix(petsc, &beam.uniform, false)?;
    let (report, error, _) = beam.solve(petsc, &a, Method::CgBoomerAmg, &beam.reference)?;
    say(petsc, format!("BoomerAMG: {} iterations ({}), relative error {error:.2e}", report.iterations, report.reason));
    ensure(error <= AGREEMENT, format!("BoomerAMG error {error:e}"))
}

/// The matrix's values change (E doubled on x < L/2), same pattern: the solver set again on it
/// keeps the old preconditioner when asked, rebuilds it otherwise; both solve the new system.
fn changed_values(petsc: &Petsc, beam: &Beam) -> Result<(), String> {
    let mut a = beam.matrix(petsc, &beam.uniform, true)?;
    let (b, mut x) = beam.vectors(petsc)?;
    let settings = Settings { rtol: 1e-12, ..Settings::default() };
    let mut kept = Ksp::new(petsc, &settings).map_err(|e| e.to_string())?;
    kept.set_operator(&a).map_err(|e| e.to_string())?;
    let first = kept.solve(&b, &mut x).map_err(|e| e.to_string())?;
    let first_error = relative_error(&beam.gather(petsc, &x)?, &beam.reference);
    a.zero_entries().map_err(|e| e.to_string())?;
    beam.assemble_into(&mut a, &beam.stiffened)?;
    kept.set_operator(&a).map_err(|e| e.to_string())?;
    kept.reuse_preconditioner(true).map_err(|e| e.to_string())?;
    let reused = kept.solve(&b, &mut x).map_err(|e| e.to_string())?;
    let reused_error = relative_error(&beam.gather(petsc, &x)?, &beam.reference_stiffened);
    let mut fresh = Ksp::new(petsc, &settings).map_err(|e| e.to_string())?;
    fresh.set_operator(&a).map_err(|e| e.to_string())?;
    let rebuilt = fresh.solve(&b, &mut x).map_err(|e| e.to_string())?;
    let rebuilt_error = relative_error(&beam.gather(petsc, &x)?, &beam.reference_stiffened);
    say(petsc, format!("first matrix: {} iterations, error {first_error:.2e}", first.iterations));
    say(petsc, format!("stiffened, preconditioner kept: {} iterations, error {reused_error:.2e}", reused.iterations));
    say(
        petsc,
        format!("stiffened, preconditioner rebuilt: {} iterations, error {rebuilt_error:.2e}", rebuilt.iterations),
    );
    ensure(
        first_error <= AGREEMENT && reused_error <= AGREEMENT && rebuilt_error <= AGREEMENT,
        format!("errors {first_error:e}, {reused_error:e}, {rebuilt_error:e}"),
    )
}

fn main() -> ExitCode {
    let petsc = Petsc::initialize().expect("MPI and PETSc initialise");
    let beam = Beam::new(&petsc);
    let cases: [Case; 4] = [
        ("gamg_with_rigid_body_modes_agrees_and_beats_without", &|p| gamg_near_null_space(p, &beam)),
        ("mumps_agrees_with_serial_and_cg", &|p| mumps_agrees(p, &beam)),
        ("boomeramg_agrees_with_serial", &|p| boomeramg_agrees(p, &beam)),
        ("changed_values_kept_or_rebuilt_preconditioner", &|p| changed_values(p, &beam)),
    ];
    let code = run(&petsc, &cases);
    drop(beam);
    drop(petsc);
    code
}
