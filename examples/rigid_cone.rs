//! Composing a problem in Rust: a rigid cone pressed into the elasto-plastic block of theory §6,
//! with the obstacle plugin written in this file, checked by the K conformance kit and then
//! solved by every solver — no scene file.
//!
//! ```text
//! cargo run --release --example rigid_cone              # 16×16×8 cells, a few seconds
//! cargo run --release --example rigid_cone -- 24 24 12  # other cell counts
//! ```
//!
//! The cone (apex c, axis e₃, half-angle β between axis and surface) sits below the contact face
//! and moves up by the extra unknown V under the force F. The distance of a point x to its
//! surface, in the half-plane of r = |(x − c)₁₂| and z = (x − c)₃, is `r cos β + z sin β` where
//! the nearest point is on the surface (r sin β ≥ z cos β) and `|x − c|` where it is the apex.
//! Its gradient at the reference configuration is the row's normal n_i, so (theory §8)
//!
//! `g_i(u, V) = n_i·(u_i − V e₃) + dist(x_i) ≥ 0`, load F·V,
//!
//! a row acting on all three dofs of its node (the normals are not an axis): Newton and the
//! penalty solve such rows in the coordinates of `saddle_solvers::row_basis`.

use saddle::core::{P1P0Element, kkt};
use saddle_contact::{conformance, zone};
use saddle_core::error::{ParameterError, check, join};
use saddle_core::{
    AdmissibleDisplacements, BoxMesh, ConstraintRows, ContactReport, Dirichlet, DiscreteProblem, DofMap, Elasticity,
    Region, SceneError, Silent, Solver, TetMesh, contact_set,
};
use saddle_solvers::{Newton, Penalty, Uzawa};
use saddle_yield::VonMises;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// `type = "rigid_cone"`: a rigid cone, apex `apex`, axis e₃, half-angle `beta` (degrees), pushed
/// up by `F` into the candidate zone `zone` (module docs).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct RigidCone {
    /// The apex (below the contact face).
    pub apex: [f64; 3],
    /// Angle between the axis and the surface, in degrees, in (0, 90).
    pub beta: f64,
    /// The upward force on the cone, > 0.
    pub F: f64,
    /// The candidate contact zone.
    pub zone: Region,
}

impl RigidCone {
    /// The distance of `x` to the cone's surface and its gradient (module docs).
    fn distance(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        let (sb, cb) = self.beta.to_radians().sin_cos();
        let d = [x[0] - self.apex[0], x[1] - self.apex[1], x[2] - self.apex[2]];
        let r = d[0].hypot(d[1]);
        if r * sb >= d[2] * cb && r > 0.0 {
            (r * cb + d[2] * sb, [cb * d[0] / r, cb * d[1] / r, sb])
        } else {
            let s = (r * r + d[2] * d[2]).sqrt();
            (s, [d[0] / s, d[1] / s, d[2] / s])
        }
    }

    /// The displaced position x_i + u_i − V e₃ of the node of row `i`.
    fn moved(&self, mesh: &TetMesh, dofs: &DofMap, node: usize, u: &[f64], v: f64) -> [f64; 3] {
        let x = mesh.nodes[node];
        [0, 1, 2].map(|k| x[k] + dofs.free(node, k).map_or(0.0, |j| u[j]) - if k == 2 { v } else { 0.0 })
    }
}

#[typetag::serde(name = "rigid_cone")]
impl AdmissibleDisplacements for RigidCone {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::finite_all(path, "apex", &self.apex)?;
        check::open_interval(path, "beta", self.beta, 0.0, 90.0)?;
        check::positive(path, "F", self.F)?;
        self.zone.validate(&join(path, "zone"))
    }

    fn extra_names(&self) -> Vec<String> {
        vec!["V".into()]
    }

    /// F·V.
    fn load(&self) -> Vec<f64> {
        vec![self.F]
    }

    /// `g_i = n_i·(u_i − V e₃) + dist(x_i)` on the zone's nodes (module docs).
    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let zone = zone::candidate_nodes(&self.zone, mesh, dofs, path)?;
        let mut rows = ConstraintRows::new(1);
        for &node in &zone.nodes {
            let (dist, n) = self.distance(mesh.nodes[node]);
            if dist < 0.0 {
                return Err(SceneError::Region {
                    field: join(path, "apex"),
                    message: format!("node {node} at {:?} lies inside the cone", mesh.nodes[node]),
                });
            }
            let entries: Vec<(usize, f64)> = (0..3).filter_map(|k| dofs.free(node, k).map(|j| (j, n[k]))).collect();
            rows.push(&entries, &[-n[2]], dist, node);
        }
        rows.warnings = zone.warnings;
        Ok(rows)
    }

    /// The exact distance of each displaced node to the moved cone.
    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], v: &[f64], out: &mut [f64]) {
        for (g, &node) in out.iter_mut().zip(&rows.node) {
            *g = self.distance(self.moved(mesh, dofs, node, u, v[0])).0;
        }
    }

    /// `V`, `force` = Σλ_i n_i·e₃ (= F at a solution), the contact nodes and their largest
    /// distance from the axis.
    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        let contact = contact_set(lambda);
        let force = (0..rows.n_rows()).map(|i| -rows.extra_row(i)[0] * lambda[i]).sum();
        let radius = contact
            .iter()
            .map(|&i| {
                let x = mesh.nodes[rows.node[i]];
                (x[0] - self.apex[0]).hypot(x[1] - self.apex[1])
            })
            .fold(0.0, f64::max);
        ContactReport {
            quantities: vec![("V".into(), extras[0]), ("force".into(), force)],
            contact_nodes: contact.len(),
            contact_radius: radius,
            warnings: vec![],
        }
    }
}

/// One solver's result on the cone problem.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The solver's `type`.
    pub solver: &'static str,
    /// It met its tolerance.
    pub converged: bool,
    /// Outer iterations.
    pub iterations: usize,
    /// The cone's displacement V.
    pub v: f64,
    /// Σλ_i n_i·e₃, to be F.
    pub force: f64,
    /// Contact nodes.
    pub contact_nodes: usize,
    /// Plastic elements.
    pub plastic: usize,
    /// The KKT residual recomputed from the solution.
    pub kkt: f64,
    /// Wall time of the solve.
    pub seconds: f64,
}

/// The block of theory §6 on (−1,1)²×(0,1) with `cells` (graded towards the centre), clamped
/// outside the square |x₁|, |x₂| ≤ 0.75 of the bottom face; E = 100, ν = 0.3, von Mises k₀ = 1,
/// h = 5; the cone with β = 80°, its apex 0.02 below the face, F = 0.3, on the disc of radius 0.5.
pub fn problem(cells: [usize; 3]) -> (TetMesh, Vec<Dirichlet>, RigidCone) {
    let mesh = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], cells).graded([0.0; 3], 3.0).mesh().expect("box mesh");
    let free = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] },
    ]);
    let dirichlet = vec![Dirichlet::clamped(Region::Not(Box::new(free)))];
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
    let cone = RigidCone { apex: [0.0, 0.0, -0.02], beta: 80.0, F: 0.3, zone };
    (mesh, dirichlet, cone)
}

/// Checks the plugin with the K kit, then solves the problem with every solver.
pub fn run(cells: [usize; 3]) -> Vec<Outcome> {
    let (mesh, dirichlet, cone) = problem(cells);
    // 1. the plugin against the K conformance kit: rows = linearisation of the exact gap, load
    //    and report consistent, projection onto K_h well defined
    let dofs = DofMap::new(&mesh, &dirichlet).expect("dofs");
    for seed in 0..3 {
        conformance::check_all(&cone, &mesh, &dofs, seed, 1e-3).unwrap_or_else(|e| panic!("K kit: {e}"));
    }
    // 2. L: elasticity, von Mises, the cone
    let l = DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &dirichlet).unwrap()),
        Elasticity::new(100.0, 0.3).expect("E, ν"),
        Some(Box::new(VonMises::new(1.0, 5.0).unwrap())),
        Some(Box::new(cone.clone()) as Box<dyn AdmissibleDisplacements>),
        &[],
    )
    .expect("problem");
    // 3. every solver
    let mut solvers: Vec<Box<dyn Solver>> =
        vec![Box::new(Newton::default()), Box::new(Penalty::default()), Box::new(Uzawa::default())];
    #[cfg(feature = "socp")]
    solvers.push(Box::new(saddle_solvers::Socp::default()));
    solvers
        .iter()
        .map(|s| {
            let t = Instant::now();
            let sol = s.solve(&l.lagrangian(), &mut Silent).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
            let seconds = t.elapsed().as_secs_f64();
            let report = cone.report(l.element.mesh(), l.lagrangian().data.rows, &sol.extras, &sol.lambda);
            let mut ws = saddle_core::Workspace::new(&l.lagrangian());
            Outcome {
                solver: s.name(),
                converged: sol.report.converged,
                iterations: sol.report.iterations,
                v: report.get("V").expect("the cone reports V"),
                force: report.get("force").expect("the cone reports its force"),
                contact_nodes: report.contact_nodes,
                plastic: sol.stress.n_plastic(),
                kkt: kkt(&l.lagrangian(), &sol.iterate(), &mut ws).max(),
                seconds,
            }
        })
        .collect()
}

#[allow(dead_code)]
fn main() {
    let args: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let cells = if args.len() == 3 { [args[0], args[1], args[2]] } else { [16, 16, 8] };
    println!("rigid cone (β = 80°, F = 0.3) on {}×{}×{} cells; the K kit passed", cells[0], cells[1], cells[2]);
    let out = run(cells);
    let v0 = out[0].v;
    println!("| solver | converged | iterations | V | V vs newton | Σλ n·e₃ | contact nodes | plastic | KKT | time |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for o in &out {
        println!(
            "| {} | {} | {} | {:.10e} | {:.1e} | {:.12} | {} | {} | {:.1e} | {:.2} s |",
            o.solver,
            o.converged,
            o.iterations,
            o.v,
            (o.v - v0).abs() / v0.abs(),
            o.force,
            o.contact_nodes,
            o.plastic,
            o.kkt,
            o.seconds
        );
    }
}
