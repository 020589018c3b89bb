//! Loads on the displacements (Neumann data): surface tractions and pressures on boundary facets
//! and body forces, assembled into consistent nodal forces f_u. They enter the primal energy as
//! `J = Σ_T |T| ψ(ε_T(u)) − f_u·u − f·V` and equilibrium as `Bᵀσ = Gᵀλ + f_u` (theory §3 with
//! the load term of (1.11) extended to u).

use crate::error::{ParameterError, SceneError, check, join};
use crate::mesh::TetMesh;
use crate::mesh::dofs::DofMap;
use crate::mesh::region::Region;
use serde::{Deserialize, Serialize};

/// `[[load]]`: a load on the body.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Load {
    /// A constant traction t (force per area) on the selected boundary facets.
    Traction {
        /// The facets.
        on: Region,
        /// t.
        t: [f64; 3],
    },
    /// A pressure p (force per area) on the selected boundary facets: the traction −p n along
    /// each facet's outward normal n of the reference configuration (theory §14.3).
    Pressure {
        /// The facets.
        on: Region,
        /// p (positive pushes into the body).
        p: f64,
    },
    /// A constant body force b (force per volume) on the whole body.
    BodyForce {
        /// b.
        b: [f64; 3],
    },
}

impl Load {
    /// The same load multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        match self {
            Load::Traction { on, t } => Load::Traction { on: on.clone(), t: t.map(|x| x * factor) },
            Load::Pressure { on, p } => Load::Pressure { on: on.clone(), p: p * factor },
            Load::BodyForce { b } => Load::BodyForce { b: b.map(|x| x * factor) },
        }
    }

    /// Checks the numbers (finite, magnitudes within [`check::MAX_MAGNITUDE`]: a load enters the
    /// solvers' products with the moduli and lengths); `path` names this load (`load[0]`).
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        match self {
            Load::Traction { on, t } => {
                on.validate(&join(path, "on"))?;
                check::bounded_all(path, "t", t)
            }
            Load::Pressure { on, p } => {
                on.validate(&join(path, "on"))?;
                check::bounded(path, "p", *p).map(|_| ())
            }
            Load::BodyForce { b } => check::bounded_all(path, "b", b),
        }
    }
}

/// The consistent nodal forces of a traction `traction(n)` (n the facet's outward unit normal),
/// constant on each facet selected by `on`, through `add(node, force, share)` (`path` names the
/// load, `what` its value). A nonzero traction that lands on no free dof is an error on
/// `{path}.on`.
fn facet_loads(
    mesh: &TetMesh,
    on: &Region,
    path: &str,
    what: &str,
    add: &mut impl FnMut(usize, [f64; 3], f64) -> bool,
    traction: impl Fn([f64; 3]) -> [f64; 3],
) -> Result<(), SceneError> {
    let field = join(path, "on");
    let missing = on.missing_groups(mesh);
    if !missing.is_empty() {
        return Err(SceneError::Region {
            field,
            message: format!("no facet group named {:?}; the mesh has {:?}", missing, mesh.group_names()),
        });
    }
    let facets = on.facets(mesh);
    if facets.is_empty() {
        return Err(SceneError::Region { field, message: "selects no boundary facet".into() });
    }
    let n_facets = facets.len();
    let (mut landed, mut nonzero) = (false, false);
    for fi in facets {
        let [a, b, c] = mesh.boundary[fi].map(|n| mesh.nodes[n]);
        let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let area = 0.5 * norm;
        let t = traction(n.map(|x| x / norm));
        nonzero |= t.iter().any(|x| *x != 0.0);
        // ∫N over a flat triangle: ⅓|F| for P1; 0 at the vertices and ⅓|F| at the edge nodes
        // for P2 (whose facets are flat: edge nodes at the midpoints, TetMesh::SecondOrder)
        landed |= match &mesh.second_order {
            None => mesh.boundary[fi].iter().fold(false, |l, &node| add(node, t, area / 3.0) | l),
            Some(so) => so.facet_edges[fi].iter().fold(false, |l, &node| add(node, t, area / 3.0) | l),
        };
    }
    if !landed && nonzero {
        return Err(SceneError::Region {
            field,
            message: format!(
                "{what} acts on {n_facets} facet(s) whose nodes are all fixed by the [[dirichlet]] conditions in \
                 every loaded component: the load would do nothing; load facets that are free to move, or release \
                 them"
            ),
        });
    }
    Ok(())
}

/// The consistent nodal forces f_u of `loads` on the free dofs (fixed dofs take none): ∫N·t and
/// ∫N·b for constant data. On P1 elements each node of a facet receives a third of the facet's
/// force, each node of a tetrahedron a quarter of its force; on a second-order mesh (P2) the
/// edge nodes of a facet receive a third each and its vertices none, and a tetrahedron gives
/// −1/20 of its force to each vertex and 1/5 to each edge node.
///
/// A nonzero traction none of whose components reaches a free dof of its facets (every node
/// fixed in every loaded component: the load would do nothing) is an error on `load[i].on`.
pub fn nodal_loads(mesh: &TetMesh, dofs: &DofMap, loads: &[Load]) -> Result<Vec<f64>, SceneError> {
    let mut f = vec![0.0; dofs.n_free];
    // adds a share of `force` to the free dofs of `node`; true when a nonzero component landed
    let mut add = |node: usize, force: [f64; 3], share: f64| {
        let mut landed = false;
        // the force's components in the node's dofs (its frame, theory §14.4)
        for (k, fk) in dofs.to_local(node, force).iter().enumerate() {
            if let Some(j) = dofs.free(node, k) {
                f[j] += share * fk;
                landed |= *fk != 0.0;
            }
        }
        landed
    };
    for (i, load) in loads.iter().enumerate() {
        let path = format!("load[{i}]");
        match load {
            Load::Traction { on, t } => {
                facet_loads(mesh, on, &path, &format!("the traction t = {t:?}"), &mut add, |_| *t)?
            }
            // the boundary facets are oriented outward (TetMesh: each is a face of exactly one
            // positively oriented tetrahedron, its vertices ordered so that (b − a) × (c − a)
            // points away from the tetrahedron's fourth vertex)
            Load::Pressure { on, p } => {
                facet_loads(mesh, on, &path, &format!("the pressure p = {p:?}"), &mut add, |n| n.map(|x| -p * x))?
            }
            Load::BodyForce { b } => {
                for (e, tet) in mesh.tets.iter().enumerate() {
                    let vol = mesh.volume(e);
                    // ∫N over a tetrahedron: ¼|T| for P1; −|T|/20 at the vertices and |T|/5 at
                    // the edge nodes for P2
                    match &mesh.second_order {
                        None => tet.iter().for_each(|&node| {
                            add(node, *b, vol / 4.0);
                        }),
                        Some(so) => {
                            tet.iter().for_each(|&node| {
                                add(node, *b, -vol / 20.0);
                            });
                            so.tet_edges[e].iter().for_each(|&node| {
                                add(node, *b, vol / 5.0);
                            });
                        }
                    }
                }
            }
        }
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::box_mesh::BoxMesh;

    #[test]
    fn p2_loads_integrate_quadratic_fields_exactly() {
        // f·u = ∫ t·u dA + ∫ b·u dV for u quadratic: the P2 shares are ∫N exactly
        let m = BoxMesh::new([0.0; 3], [2.0, 1.0, 1.0], [3, 2, 2]).graded([0.0; 3], 2.0).mesh().unwrap().second_order();
        let dofs = DofMap::new(&m, &[]).unwrap();
        let loads = [
            Load::Traction { on: Region::Group("xmax".into()), t: [0.0, 0.0, 3.0] },
            Load::BodyForce { b: [1.0, 0.0, 0.0] },
        ];
        let f = nodal_loads(&m, &dofs, &loads).unwrap();
        // u = (x², 0, y²): ∫_box x² = 8/3, ∫_{x=2} 3y² = 1
        let work: f64 = (0..m.n_nodes())
            .map(|n| {
                let x = m.nodes[n];
                f[dofs.free(n, 0).unwrap()] * x[0] * x[0] + f[dofs.free(n, 2).unwrap()] * x[1] * x[1]
            })
            .sum();
        assert!((work - (8.0 / 3.0 + 1.0)).abs() < 1e-12, "{work}");
    }

    #[test]
    fn resultants_equal_traction_times_area_and_body_force_times_volume() {
        let m = BoxMesh::new([0.0; 3], [2.0, 1.0, 1.0], [4, 3, 2]).graded([0.0; 3], 2.0).mesh().unwrap();
        let dofs = DofMap::new(&m, &[]).unwrap();
        let loads = [
            Load::Traction { on: Region::Group("xmax".into()), t: [0.0, 0.0, 3.0] },
            Load::BodyForce { b: [1.0, 0.0, 0.0] },
        ];
        let f = nodal_loads(&m, &dofs, &loads).unwrap();
        let total = |c: usize| (0..m.n_nodes()).map(|n| f[dofs.free(n, c).unwrap()]).sum::<f64>();
        assert!((total(2) - 3.0 * 1.0).abs() < 1e-12, "traction resultant {}", total(2));
        assert!((total(0) - 2.0).abs() < 1e-12, "body force resultant {}", total(0));
        assert!(total(1).abs() < 1e-14);
        let e = nodal_loads(&m, &dofs, &[Load::Traction { on: Region::Group("top".into()), t: [0.0; 3] }]).unwrap_err();
        assert!(e.to_string().contains("load[0].on"), "{e}");
        // the values are validated once, when a scene is read (Load::validate), not again here
        let e = Load::BodyForce { b: [f64::NAN, 0.0, 0.0] }.validate("load[0]").unwrap_err();
        assert!(e.to_string().contains("load[0].b[0]"), "{e}");
    }

    #[test]
    fn pressure_pushes_along_the_inward_normal_of_every_facet() {
        for m in [BoxMesh::new([0.0; 3], [2.0, 1.0, 1.0], [3, 2, 2]).graded([0.0; 3], 2.0).mesh().unwrap()] {
            for m in [m.clone(), m.second_order()] {
                let dofs = DofMap::new(&m, &[]).unwrap();
                let total = |f: &[f64], c: usize| (0..m.n_nodes()).map(|n| f[dofs.free(n, c).unwrap()]).sum::<f64>();
                // on x = 2 (area 1): the resultant −p e_x; on the closed surface: zero
                let f = nodal_loads(&m, &dofs, &[Load::Pressure { on: Region::Group("xmax".into()), p: 3.0 }]).unwrap();
                assert!((total(&f, 0) + 3.0).abs() < 1e-12 && total(&f, 1).abs() < 1e-12, "{}", total(&f, 0));
                let all: Vec<Load> = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]
                    .map(|g| Load::Pressure { on: Region::Group(g.into()), p: 3.0 })
                    .into();
                let f = nodal_loads(&m, &dofs, &all).unwrap();
                assert!((0..3).all(|c| total(&f, c).abs() < 1e-12));
                // the work on u = x is −p times the volume: ∫ −p n·x dA = −3p|Ω|
                let work: f64 = (0..m.n_nodes())
                    .map(|n| (0..3).map(|c| f[dofs.free(n, c).unwrap()] * m.nodes[n][c]).sum::<f64>())
                    .sum();
                assert!((work + 3.0 * 3.0 * 2.0).abs() < 1e-12, "{work}");
            }
        }
        let e = Load::Pressure { on: Region::Group("a".into()), p: f64::INFINITY }.validate("load[2]").unwrap_err();
        assert!(e.to_string().contains("load[2].p"), "{e}");
    }

    #[test]
    fn scene_syntax() {
        let l: Load = toml::from_str("type = \"traction\"\non = { group = \"zmax\" }\nt = [0.0, 0.0, -1.0]").unwrap();
        assert!(matches!(l, Load::Traction { .. }));
        assert!(toml::from_str::<Load>("type = \"body_force\"\nb = [0.0, 0.0, -1.0]\nt = 1").is_err());
    }
}
