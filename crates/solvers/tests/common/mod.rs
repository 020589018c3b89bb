//! Scenes shared by the solver tests: the default scene of theory §6 on a coarse graded mesh and
//! the homogeneous compression of theory §7.1; and [`Counting`], a P that counts the return
//! mappings it runs, for tests that must not trust a solver's own bookkeeping.
#![allow(dead_code)]

pub mod friction;

use saddle_contact::{Flat, Paraboloid, RigidPunch};
use saddle_core::P1P0Element;
use saddle_core::error::ParameterError;
use saddle_core::{
    AdmissibleDisplacements, AdmissibleStresses, BoxMesh, Component, ConeDescription, Dirichlet, DiscreteProblem,
    Elasticity, Region, StepInput, StepOutput, Sym,
};
use saddle_yield::VonMises;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Units of a scene: stresses (E, k₀, h) are multiplied by `stress`, lengths by `length`.
#[derive(Clone, Copy)]
pub struct Units {
    pub stress: f64,
    pub length: f64,
}

/// The scaled units of theory §6 (E = 100, lengths of order 1).
pub const SCALED: Units = Units { stress: 1.0, length: 1.0 };

/// The default scene of theory §6 (force F = 0.3) with `cells`; `k0_h = None` is elastic.
pub fn johnson(cells: [usize; 3], k0_h: Option<(f64, f64)>, units: Units) -> DiscreteProblem {
    johnson_with(cells, k0_h, units, punch)
}

/// The default scene of theory §6 in scaled units with the yield surface `p`.
pub fn johnson_yield(cells: [usize; 3], p: Box<dyn AdmissibleStresses>) -> DiscreteProblem {
    johnson_scene(cells, Some(p), SCALED, punch)
}

/// The paraboloid punch of theory §6 on `zone` with force `force` and radius `radius`.
fn punch(zone: Region, force: f64, radius: f64) -> Box<dyn AdmissibleDisplacements> {
    Box::new(RigidPunch::new(force, zone, Box::new(Paraboloid::new(radius))).unwrap())
}

/// The default scene of theory §6 with the obstacle made by `obstacle(zone Γ₀, force F, punch
/// radius R)` in the scene's units.
pub fn johnson_with(
    cells: [usize; 3],
    k0_h: Option<(f64, f64)>,
    units: Units,
    obstacle: impl FnOnce(Region, f64, f64) -> Box<dyn AdmissibleDisplacements>,
) -> DiscreteProblem {
    let p: Option<Box<dyn AdmissibleStresses>> =
        k0_h.map(|(k0, h)| Box::new(VonMises::new(k0 * units.stress, h * units.stress).unwrap()) as _);
    johnson_scene(cells, p, units, obstacle)
}

/// The default scene with the yield surface `p` (`None`: no P) and the obstacle of `obstacle`.
fn johnson_scene(
    cells: [usize; 3],
    p: Option<Box<dyn AdmissibleStresses>>,
    units: Units,
    obstacle: impl FnOnce(Region, f64, f64) -> Box<dyn AdmissibleDisplacements>,
) -> DiscreteProblem {
    let s = units.length;
    let mesh = BoxMesh::new([-s, -s, 0.0], [s, s, s], cells).graded([0.0; 3], 3.0).mesh().unwrap();
    let gamma1 = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75 * s, -0.75 * s, -s], max: [0.75 * s, 0.75 * s, s] },
    ]);
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 * s }]);
    DiscreteProblem::new(
        Box::new(P1P0Element::new(mesh, &[Dirichlet::clamped(Region::Not(Box::new(gamma1)))]).unwrap()),
        Elasticity::new(100.0 * units.stress, 0.3).unwrap(),
        p,
        Some(obstacle(zone, 0.3 * units.stress * s * s, 5.0 * s)),
        &[],
    )
    .unwrap()
}

/// Homogeneous compression of theory §7.1: the unit cube on rollers (u₁ = 0 on x₁ = 0, u₂ = 0 on
/// x₂ = 0, u₃ = 0 on x₃ = 1), a flat punch on the whole bottom face with force `f`; k₀ = 1, h = 5.
pub fn homogeneous(f: f64) -> DiscreteProblem {
    let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [3, 3, 3]).mesh().unwrap();
    let g = |name: &str| Region::Group(name.into());
    DiscreteProblem::new(
        Box::new(
            P1P0Element::new(
                mesh,
                &[
                    Dirichlet::roller(g("xmin"), Component::X),
                    Dirichlet::roller(g("ymin"), Component::Y),
                    Dirichlet::roller(g("zmax"), Component::Z),
                ],
            )
            .unwrap(),
        ),
        Elasticity::new(100.0, 0.3).unwrap(),
        Some(Box::new(VonMises::new(1.0, 5.0).unwrap())),
        saddle_core::Obstacles::one(Box::new(RigidPunch::new(f, g("zmin"), Box::new(Flat::default())).unwrap())),
        &[],
    )
    .unwrap()
}

/// A P that wraps another and counts the return mappings it runs: its calls of `local_law` and
/// `project`, counted where they run. Everything else is the wrapped P's.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Counting {
    inner: Box<dyn AdmissibleStresses>,
    /// Shared by the clones, so that a Lagrangian holding a copy still counts here.
    #[serde(skip)]
    calls: Arc<AtomicUsize>,
}

impl Counting {
    /// `inner`, counted, as a P; the counter is returned with it.
    pub fn wrap(inner: Box<dyn AdmissibleStresses>) -> (Box<dyn AdmissibleStresses>, Arc<AtomicUsize>) {
        let calls = Arc::new(AtomicUsize::new(0));
        (Box::new(Self { inner, calls: calls.clone() }), calls)
    }

    fn count(&self) {
        self.calls.fetch_add(1, Ordering::Relaxed);
    }
}

#[typetag::serde(name = "test_counting")]
impl AdmissibleStresses for Counting {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.inner.validate(path)
    }
    fn hardening_dim(&self) -> usize {
        self.inner.hardening_dim()
    }
    fn is_unbounded(&self) -> bool {
        self.inner.is_unbounded()
    }
    fn hardening_inner(&self, q: &[f64], r: &[f64]) -> f64 {
        self.inner.hardening_inner(q, r)
    }
    fn contains(&self, sigma: &Sym, q: &[f64], tol: f64) -> bool {
        self.inner.contains(sigma, q, tol)
    }
    fn project(&self, law: &Elasticity, sigma: &mut Sym, q: &mut [f64]) -> bool {
        self.count();
        self.inner.project(law, sigma, q)
    }
    fn step_law(&self, law: &Elasticity, step: StepInput<'_>, out: StepOutput<'_>) -> bool {
        self.count();
        self.inner.step_law(law, step, out)
    }
    /// The wrapped P's energy (for von Mises a closed form, no return mapping).
    fn energy(&self, law: &Elasticity, eps: &Sym) -> f64 {
        self.inner.energy(law, eps)
    }
    fn cone(&self) -> Option<ConeDescription> {
        self.inner.cone()
    }
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings()
    }
}
