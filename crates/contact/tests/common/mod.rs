//! The small default-scene setup shared by the tests (theory §6 on a coarse box mesh).
#![allow(dead_code)]

use saddle_contact::{EllipticParaboloid, Flat, GapShape, Paraboloid};
use saddle_core::{BoxMesh, Dirichlet, DofMap, Region, TetMesh};

/// [-1, 1]² × [0, 1] with 8 × 8 × 4 cells: node spacing 0.25 in x₁, x₂.
pub fn mesh() -> TetMesh {
    BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 4]).mesh().unwrap()
}

/// Clamped everywhere except the bottom face with |x₁|, |x₂| < 0.75 (Γ₂ of theory §6).
pub fn clamped() -> Dirichlet {
    Dirichlet::clamped(Region::Not(Box::new(Region::All(vec![
        Region::Group("zmin".into()),
        Region::Box { min: [-0.75, -0.75, -1.0], max: [0.75, 0.75, 1.0] },
    ]))))
}

pub fn dofs(mesh: &TetMesh) -> DofMap {
    DofMap::new(mesh, &[clamped()]).unwrap()
}

/// The bottom disc of radius r about the origin.
pub fn disc(r: f64) -> Region {
    Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: r }])
}

/// Bottom-face nodes with x₁² + x₂² ≤ r², counted from the coordinates.
pub fn bottom_nodes_in_disc(mesh: &TetMesh, r: f64) -> Vec<usize> {
    (0..mesh.n_nodes())
        .filter(|&n| {
            let x = mesh.nodes[n];
            x[2].abs() < 1e-12 && x[0] * x[0] + x[1] * x[1] <= r * r + 1e-12
        })
        .collect()
}

/// The node at (x₁, x₂, 0).
pub fn node_at(mesh: &TetMesh, x1: f64, x2: f64) -> usize {
    (0..mesh.n_nodes())
        .find(|&n| {
            let x = mesh.nodes[n];
            (x[0] - x1).abs() < 1e-12 && (x[1] - x2).abs() < 1e-12 && x[2].abs() < 1e-12
        })
        .unwrap()
}

/// The three gap shapes (the elliptic one off centre).
pub fn shapes() -> Vec<Box<dyn GapShape>> {
    vec![
        Box::new(Paraboloid::new(5.0)),
        Box::new(EllipticParaboloid { R1: 2.0, R2: 8.0, c1: 0.25, c2: -0.125 }),
        Box::new(Flat::default()),
    ]
}
