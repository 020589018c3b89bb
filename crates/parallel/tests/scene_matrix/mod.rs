//! The scene matrix of issue 24 for a distributed solver: each scene solved distributed over
//! the ranks of `mpirun -n N` agrees with the serial solve of the same solver every rank also
//! runs: every extra and J to 1e-8 relative, the force Σλ to 1e-8, the contact and plastic
//! counts exactly (points whose trial stress lies within 1e-6 of the yield surface named
//! instead), the KKT residual (recomputed globally) within the solver's tolerance. The scenes:
//! the small default scene (theory §6), the same with P2 elements, a tilting punch loaded off
//! centre, two named punches, Drucker–Prager, a three-step load path (load, hold, unload;
//! theory §11), and a rigid sphere pushed 15° off the axis, whose rows act on all three dofs of
//! their nodes (general rows: theory §8.1, §12.2). Newton's fallbacks on the penalty method
//! (theory §4.2.1) are counted alike. [`agree_with_serial_on`] takes other scenes, such as the
//! perfectly plastic strip on which Newton falls back ([`Geometry::Strip`]).

// shared by the test binaries, each of which uses a part
#![allow(dead_code)]

use saddle_contact::{Flat, Paraboloid, RigidPunch, RigidPunchDisplacement, RigidSphere, TiltingPunch};
use saddle_core::fem::FiniteElement;
use saddle_core::mesh::dofs::Component;
use saddle_core::problem::comm::Comm;
use saddle_core::{
    AdmissibleStresses, BoxMesh, Dirichlet, DiscreteProblem, Elasticity, Evolution, Lagrangian, NamedObstacle,
    Obstacles, P1, P2, Region, Silent, Solution, Solver, TetMesh, Workspace, kkt,
};
use saddle_parallel::distribute;
use saddle_parallel::saddle_mpi::Petsc;
use saddle_yield::{DruckerPrager, VonMises};

/// A scene: its geometry, element, yield surface, obstacles.
pub struct Scene {
    pub name: &'static str,
    pub geometry: Geometry,
    pub element: Box<dyn FiniteElement>,
    pub stresses: Box<dyn AdmissibleStresses>,
    pub obstacles: Obstacles,
    /// Load factors of a path (empty: one stationary solve).
    pub path: Vec<f64>,
}

/// A mesh of so many cells and its supports.
#[derive(Clone, Copy)]
pub enum Geometry {
    /// The default scene's block [−1, 1]² × [0, 1] graded toward the punch, clamped but on the
    /// bottom face's middle (theory §6).
    Block([usize; 3]),
    /// `examples/strip_punch.toml`'s plane-strain strip [−2, 2] × [0, 0.25] × [0, 2]: rollers on
    /// the faces y = const, clamped at the top and the sides; the punch on |x| ≤ 0.5.
    Strip([usize; 3]),
}

fn mesh(geometry: Geometry) -> TetMesh {
    match geometry {
        Geometry::Block(cells) => BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], cells)
            .graded([0.0; 3], 3.0)
            .aligned(0, &[-0.75, 0.75])
            .aligned(1, &[-0.75, 0.75]),
        Geometry::Strip(cells) => BoxMesh::new([-2.0, 0.0, 0.0], [2.0, 0.25, 2.0], cells).aligned(0, &[-0.5, 0.5]),
    }
    .mesh()
    .unwrap()
}

fn dirichlet(geometry: Geometry) -> Vec<Dirichlet> {
    let group = |g: &str| Region::Group(g.into());
    match geometry {
        Geometry::Block(_) => {
            let gamma1 =
                Region::All(vec![group("zmin"), Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] }]);
            vec![Dirichlet::clamped(Region::Not(Box::new(gamma1)))]
        }
        Geometry::Strip(_) => vec![
            Dirichlet::roller(group("ymin"), Component::Y),
            Dirichlet::roller(group("ymax"), Component::Y),
            Dirichlet::clamped(Region::Any(vec![group("zmax"), group("xmin"), group("xmax")])),
        ],
    }
}

/// The strip's flat punch on |x| ≤ 0.5 of the bottom face, moved by `u`.
pub fn strip_punch(u: f64) -> Obstacles {
    let zone = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.5, -1.0, -1e-9], max: [0.5, 1.0, 1e-9] },
    ]);
    Obstacles::one(Box::new(RigidPunchDisplacement::new(u, zone, Box::new(Flat::default())).unwrap()))
}

fn disc(x: f64, r: f64) -> Region {
    Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [x, 0.0], radius: r }])
}

fn punch(force: f64) -> Obstacles {
    Obstacles::one(Box::new(RigidPunch::new(force, disc(0.0, 0.5), Box::new(Paraboloid::new(5.0))).unwrap()))
}

pub fn law() -> Elasticity {
    Elasticity::new(100.0, 0.3).unwrap()
}

pub fn von_mises() -> Box<dyn AdmissibleStresses> {
    Box::new(VonMises::new(1.0, 5.0).unwrap())
}

fn scenes() -> Vec<Scene> {
    let tilting =
        TiltingPunch::new(0.3, disc(0.0, 0.5), Box::new(Paraboloid::new(5.0))).unwrap().at([0.1, -0.05]).unwrap();
    let two = |name: &str, f: f64, x: f64| {
        let gap = Paraboloid { R: 5.0, center: [x, 0.0] };
        NamedObstacle::new(name, Box::new(RigidPunch::new(f, disc(x, 0.3), Box::new(gap)).unwrap()))
    };
    let tilt = 15f64.to_radians();
    let sphere = RigidSphere::pushed([0.0, 0.0, -5.0], 5.0, [tilt.sin(), 0.0, tilt.cos()], 0.3, disc(0.0, 0.5));
    vec![
        Scene {
            name: "default (p1)",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: von_mises(),
            obstacles: punch(0.3),
            path: vec![],
        },
        Scene {
            name: "default, p2",
            geometry: Geometry::Block([6, 6, 3]),
            element: Box::new(P2::default()),
            stresses: von_mises(),
            obstacles: punch(0.3),
            path: vec![],
        },
        Scene {
            name: "tilting punch off centre",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: von_mises(),
            obstacles: Obstacles::one(Box::new(tilting)),
            path: vec![],
        },
        Scene {
            name: "two named punches",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: von_mises(),
            obstacles: Obstacles::new(vec![two("left", 0.1, -0.35), two("right", 0.25, 0.35)]).unwrap(),
            path: vec![],
        },
        Scene {
            name: "Drucker-Prager",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: Box::new(DruckerPrager::new(1.0, 0.1, 5.0).unwrap()),
            obstacles: punch(0.3),
            path: vec![],
        },
        Scene {
            name: "load path 1, 1, 0",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: von_mises(),
            obstacles: punch(0.3),
            path: vec![1.0, 1.0, 0.0],
        },
        Scene {
            name: "rigid sphere 15° off the axis",
            geometry: Geometry::Block([12, 12, 6]),
            element: Box::new(P1::default()),
            stresses: von_mises(),
            obstacles: Obstacles::one(Box::new(sphere)),
            path: vec![],
        },
    ]
}

/// Contact rows (λ_i > 1e-8 max λ, the max over every rank's rows) and Σλ.
fn contact(comm: &dyn Comm, lambda: &[f64]) -> (usize, f64) {
    let lmax = comm.max(lambda.iter().copied().fold(0.0, f64::max));
    let count = comm.sum_count(lambda.iter().filter(|&&l| lmax > 0.0 && l > 1e-8 * lmax).count());
    (count, comm.sum(lambda.iter().sum()))
}

/// What is compared of a solution: the extras (null when undetermined), J, Σλ, contact rows,
/// plastic points, and the recomputed KKT residual; per point of the whole mesh (in its
/// order), whether it is plastic and whether its trial stress lies within 1e-6 of the yield
/// surface (where round-off decides the flag).
#[derive(Debug)]
pub struct Numbers {
    extras: Vec<Option<f64>>,
    j: f64,
    force: f64,
    contact: usize,
    pub plastic: usize,
    kkt: f64,
    iterations: usize,
    /// Solves of the distributed linear solver (the counter `distributed_solves`; 0 without).
    distributed_solves: usize,
    /// Newton's fallbacks on the penalty method (the counter `fallbacks`; 0 without).
    pub fallbacks: usize,
    flags: Vec<(bool, bool)>,
}

/// `l`'s solution `s`; `global_point` maps local points to the whole mesh's (`n` of them).
fn numbers(l: &Lagrangian<'_>, s: &Solution, global_point: &dyn Fn(usize) -> usize, n: usize) -> Numbers {
    let comm = l.comm();
    let (contact, force) = contact(comm, &s.lambda);
    // the trial C(ε − ε_p) with q_n against D, inflated and deflated by 1e-6
    let p = l.data.plasticity().expect("plastic scenes");
    let mut eps = vec![saddle_core::Sym::zeros(); l.n_points()];
    l.strain(&s.u, &mut eps);
    let (mut plastic, mut near) = (vec![0.0; n], vec![0.0; n]);
    for (i, e) in eps.iter().enumerate() {
        let (ep, qn) = match l.data.state {
            Some(st) => (st.plastic_strain[i], st.q(i).to_vec()),
            None => (saddle_core::Sym::zeros(), vec![0.0; p.hardening_dim()]),
        };
        let trial = l.data.elasticity.stress(&(e - ep));
        let g = global_point(i);
        plastic[g] = s.stress.plastic[i] as u8 as f64;
        near[g] = (p.contains(&trial, &qn, 1e-6) != p.contains(&trial, &qn, -1e-6)) as u8 as f64;
    }
    comm.sum_in_place(&mut plastic);
    comm.sum_in_place(&mut near);
    Numbers {
        extras: s.extras.iter().enumerate().map(|(k, v)| (!s.undetermined.contains(&k)).then_some(*v)).collect(),
        j: saddle_core::energy(l, &s.u, &s.extras, &mut Workspace::new(l)),
        force,
        contact,
        plastic: comm.sum_count(s.stress.n_plastic()),
        kkt: kkt(l, &s.iterate(), &mut Workspace::new(l)).max(),
        iterations: s.report.iterations,
        distributed_solves: s.report.counters.get("distributed_solves").map_or(0, |x| *x as usize),
        fallbacks: s.report.counters.get("fallbacks").map_or(0, |x| *x as usize),
        flags: plastic.iter().zip(&near).map(|(a, b)| (*a > 0.5, *b > 0.5)).collect(),
    }
}

/// Solves `problem` (a path's steps, or once) and the numbers of every solution.
fn solve(
    problem: &DiscreteProblem,
    path: &[f64],
    solver: &dyn Solver,
    global_point: &dyn Fn(usize) -> usize,
    n: usize,
) -> Vec<Numbers> {
    if path.is_empty() {
        let l = problem.lagrangian();
        let sol = solver.solve(&l, &mut Silent).unwrap();
        assert!(sol.report.converged, "{:?}", sol.report.stop_reason);
        return vec![numbers(&l, &sol, global_point, n)];
    }
    let mut evolution = Evolution::new(problem);
    path.iter()
        .map(|&f| {
            let step = evolution.step(f, solver, &mut Silent).unwrap();
            assert!(step.converged(), "factor {f}");
            numbers(&step.problem.lagrangian(), &step.solution, global_point, n)
        })
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()).max(1e-300)
}

/// `solver` on every scene of the matrix, distributed over the session's ranks, against the
/// same solver on one process (the module docs' comparisons); rank 0 prints a line per step.
pub fn agree_with_serial(session: &Petsc, solver: &dyn Solver) {
    agree_with_serial_on(session, solver, scenes());
}

/// [`agree_with_serial`] on `scenes`; the serial numbers of every scene's steps.
pub fn agree_with_serial_on(session: &Petsc, solver: &dyn Solver, scenes: Vec<Scene>) -> Vec<Vec<Numbers>> {
    let name = solver.name();
    let rank = session.rank();
    let mut serial_numbers = Vec::new();
    for scene in scenes {
        let m = mesh(scene.geometry);
        let dirichlet = dirichlet(scene.geometry);
        let element = scene.element.build(m.clone(), &dirichlet).unwrap();
        let serial =
            DiscreteProblem::new(element, law(), Some(scene.stresses.clone()), scene.obstacles.clone(), &[]).unwrap();
        let n_points = serial.element.n_points();
        let reference = solve(&serial, &scene.path, solver, &|i| i, n_points);
        let rp = distribute(
            session,
            (rank == 0).then_some(m),
            scene.element.as_ref(),
            &dirichlet,
            law(),
            Some(scene.stresses.clone()),
            scene.obstacles.clone(),
            &[],
        )
        .unwrap();
        let k = rp.problem.element.points_per_element();
        let global_point = |i: usize| rp.elements[i / k] * k + i % k;
        let distributed = solve(&rp.problem, &scene.path, solver, &global_point, n_points);
        assert!(
            distributed.iter().any(|d| d.distributed_solves > 0),
            "{}: not solved by the distributed solver",
            scene.name
        );
        let size = rp.comm.size();
        for (k, (d, r)) in distributed.iter().zip(&reference).enumerate() {
            if rank == 0 {
                let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
                let worst =
                    d.extras.iter().zip(&r.extras).filter_map(|(a, b)| Some(rel((*a)?, (*b)?))).fold(0.0, f64::max);
                println!(
                    "{name}, {size} ranks, {}, step {k}: extras {:?} (serial, largest difference {worst:.1e}), J {:.12e} ({:.1e}), \
                     force {:.12e}, contact {} ({}), plastic {} ({}), KKT {:.1e}, iterations {} ({}), fallbacks {} ({})",
                    scene.name,
                    r.extras,
                    d.j,
                    rel(d.j, r.j),
                    d.force,
                    d.contact,
                    r.contact,
                    d.plastic,
                    r.plastic,
                    d.kkt,
                    d.iterations,
                    r.iterations,
                    d.fallbacks,
                    r.fallbacks
                );
            }
            assert_eq!(d.extras.len(), r.extras.len());
            for (a, b) in d.extras.iter().zip(&r.extras) {
                match (a, b) {
                    (Some(a), Some(b)) => assert!(close(*a, *b, 1e-8), "{}: extra {a} vs {b}", scene.name),
                    (None, None) => {}
                    _ => panic!("{}: extras {:?} vs {:?}", scene.name, d.extras, r.extras),
                }
            }
            assert!(close(d.j, r.j, 1e-8), "{}: J {} vs {}", scene.name, d.j, r.j);
            assert!((d.force - r.force).abs() <= 1e-8 * r.force.abs().max(1e-12), "{}: force", scene.name);
            assert_eq!(d.contact, r.contact, "{}: contact rows", scene.name);
            // the plastic sets agree but at points whose trial lies within 1e-6 of the yield
            // surface (a step that holds the load puts every plastic point there), named
            let differ: Vec<usize> = (0..n_points).filter(|&i| d.flags[i].0 != r.flags[i].0).collect();
            let unexplained: Vec<usize> = differ.iter().copied().filter(|&i| !d.flags[i].1 && !r.flags[i].1).collect();
            if rank == 0 && !differ.is_empty() {
                println!(
                    "    plastic flags differ at {} points, all within 1e-6 of the yield surface: {differ:?}",
                    differ.len()
                );
            }
            assert!(
                unexplained.is_empty(),
                "{}: plastic flags differ away from the surface at {unexplained:?}",
                scene.name
            );
            if differ.is_empty() {
                assert_eq!(d.plastic, r.plastic, "{}: plastic points", scene.name);
            }
            assert!(d.kkt <= solver.tolerance(), "{}: recomputed KKT {}", scene.name, d.kkt);
            assert_eq!(d.fallbacks, r.fallbacks, "{}: fallbacks", scene.name);
        }
        serial_numbers.push(reference);
    }
    serial_numbers
}
