//! Scenes shared by the solver tests: the default scene of SPEC §6 on a coarse graded mesh and
//! the homogeneous compression of SPEC §7.
#![allow(dead_code)]

use saddle_contact::{Flat, Paraboloid, RigidPunch};
use saddle_core::{
    AdmissibleDisplacements, AdmissibleStresses, BoxMesh, Component, Dirichlet, Elasticity, P1P0Lagrangian, Region,
};
use saddle_yield::VonMises;

/// Units of a scene: stresses (E, k₀, h) are multiplied by `stress`, lengths by `length`.
#[derive(Clone, Copy)]
pub struct Units {
    pub stress: f64,
    pub length: f64,
}

/// The scaled units of SPEC §6 (E = 100, lengths of order 1).
pub const SCALED: Units = Units { stress: 1.0, length: 1.0 };

/// The default scene of SPEC §6 (force F = 0.3) with `cells`; `k0_h = None` is elastic.
pub fn johnson(cells: [usize; 3], k0_h: Option<(f64, f64)>, units: Units) -> P1P0Lagrangian {
    johnson_with(cells, k0_h, units, |zone, force, radius| {
        Box::new(RigidPunch::new(force, zone, Box::new(Paraboloid::new(radius))))
    })
}

/// The default scene of SPEC §6 with the obstacle made by `obstacle(zone Γ₀, force F, punch
/// radius R)` in the scene's units.
pub fn johnson_with(
    cells: [usize; 3],
    k0_h: Option<(f64, f64)>,
    units: Units,
    obstacle: impl FnOnce(Region, f64, f64) -> Box<dyn AdmissibleDisplacements>,
) -> P1P0Lagrangian {
    let s = units.length;
    let mesh = BoxMesh::new([-s, -s, 0.0], [s, s, s], cells).graded([0.0; 3], 3.0).mesh().unwrap();
    let gamma1 = Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75 * s, -0.75 * s, -s], max: [0.75 * s, 0.75 * s, s] },
    ]);
    let zone = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 * s }]);
    let p: Option<Box<dyn AdmissibleStresses>> =
        k0_h.map(|(k0, h)| Box::new(VonMises::new(k0 * units.stress, h * units.stress)) as _);
    P1P0Lagrangian::new(
        mesh,
        &[Dirichlet::clamped(Region::Not(Box::new(gamma1)))],
        Elasticity::new(100.0 * units.stress, 0.3).unwrap(),
        p,
        Some(obstacle(zone, 0.3 * units.stress * s * s, 5.0 * s)),
    )
    .unwrap()
}

/// Homogeneous compression of SPEC §7: the unit cube on rollers (u₁ = 0 on x₁ = 0, u₂ = 0 on
/// x₂ = 0, u₃ = 0 on x₃ = 1), a flat punch on the whole bottom face with force `f`; k₀ = 1, h = 5.
pub fn homogeneous(f: f64) -> P1P0Lagrangian {
    let mesh = BoxMesh::new([0.0; 3], [1.0; 3], [3, 3, 3]).mesh().unwrap();
    let g = |name: &str| Region::Group(name.into());
    P1P0Lagrangian::new(
        mesh,
        &[
            Dirichlet::roller(g("xmin"), Component::X),
            Dirichlet::roller(g("ymin"), Component::Y),
            Dirichlet::roller(g("zmax"), Component::Z),
        ],
        Elasticity::new(100.0, 0.3).unwrap(),
        Some(Box::new(VonMises::new(1.0, 5.0))),
        Some(Box::new(RigidPunch::new(f, g("zmin"), Box::new(Flat::default())))),
    )
    .unwrap()
}
