//! The P1 displacement space W_h (SPEC §3): three degrees of freedom per node, those fixed by
//! Dirichlet conditions eliminated. A Dirichlet condition fixes chosen components on the nodes
//! of the selected facets (closure): all three is clamped, one is a roller.

use crate::error::SceneError;
use crate::mesh::TetMesh;
use crate::region::Region;
use serde::{Deserialize, Serialize};

/// A displacement component.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// x₁
    X,
    /// x₂
    Y,
    /// x₃
    Z,
}

impl Component {
    /// 0, 1 or 2.
    pub fn index(self) -> usize {
        self as usize
    }
}

fn all_components() -> Vec<Component> {
    vec![Component::X, Component::Y, Component::Z]
}

/// `[[dirichlet]]`: u_c = 0 for the listed components on the closure of the selected facets.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
    /// The facets (Γ₂ for clamping).
    pub on: Region,
    /// Fixed components; all three (clamped) by default.
    #[serde(default = "all_components")]
    pub components: Vec<Component>,
}

impl Dirichlet {
    /// Clamped on `on`.
    pub fn clamped(on: Region) -> Self {
        Self { on, components: all_components() }
    }

    /// A roller: only `c` fixed on `on`.
    pub fn roller(on: Region, c: Component) -> Self {
        Self { on, components: vec![c] }
    }
}

/// Marker of an eliminated (fixed) degree of freedom.
pub const FIXED: u32 = u32::MAX;

/// Numbering of the free degrees of freedom: node-major, components in order.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// `dof[node][c]` is the free index of component c of node, or [`FIXED`].
    pub dof: Vec<[u32; 3]>,
    /// Number of free degrees of freedom.
    pub n_free: usize,
}

impl DofMap {
    /// Applies the conditions to the mesh. Errors name the condition whose region selects no
    /// facet or a group that does not exist.
    pub fn new(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Self, SceneError> {
        let mut fixed = vec![[false; 3]; mesh.n_nodes()];
        for (i, c) in conditions.iter().enumerate() {
            let field = format!("dirichlet[{i}].on");
            c.on.validate(&field)?;
            let missing = c.on.missing_groups(mesh);
            if !missing.is_empty() {
                return Err(SceneError::Region {
                    field,
                    message: format!("no facet group named {:?}; the mesh has {:?}", missing, mesh.group_names()),
                });
            }
            let facets = c.on.facets(mesh);
            if facets.is_empty() {
                return Err(SceneError::Region { field, message: "selects no boundary facet".into() });
            }
            for f in facets {
                for &n in &mesh.boundary[f] {
                    for comp in &c.components {
                        fixed[n][comp.index()] = true;
                    }
                }
            }
        }
        let mut n_free = 0u32;
        let dof = fixed
            .iter()
            .map(|fx| {
                std::array::from_fn(|c| {
                    if fx[c] {
                        FIXED
                    } else {
                        n_free += 1;
                        n_free - 1
                    }
                })
            })
            .collect();
        Ok(Self { dof, n_free: n_free as usize })
    }

    /// The free index of component `c` of `node`, if free.
    #[inline]
    pub fn free(&self, node: usize, c: usize) -> Option<usize> {
        let d = self.dof[node][c];
        (d != FIXED).then_some(d as usize)
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.dof.len()
    }

    /// Nodal displacements from a vector of free values (fixed components are zero).
    pub fn nodal(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.dof.iter().map(|d| std::array::from_fn(|c| if d[c] == FIXED { 0.0 } else { u[d[c] as usize] })).collect()
    }

    /// Number of nodes with at least one fixed component.
    pub fn constrained_nodes(&self) -> usize {
        self.dof.iter().filter(|d| d.contains(&FIXED)).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::box_mesh::BoxMesh;

    #[test]
    fn clamped_and_roller_conditions() {
        let m = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
        let d = DofMap::new(&m, &[Dirichlet::clamped(Region::Group("zmax".into()))]).unwrap();
        assert_eq!(d.n_free, 3 * 27 - 3 * 9);
        let d = DofMap::new(
            &m,
            &[
                Dirichlet::roller(Region::Group("xmin".into()), Component::X),
                Dirichlet::roller(Region::Group("ymin".into()), Component::Y),
                Dirichlet::roller(Region::Group("zmax".into()), Component::Z),
            ],
        )
        .unwrap();
        assert_eq!(d.n_free, 3 * 27 - 27);
        // nodes on xmin ∪ ymin ∪ zmax: all but those with i > 0, j > 0, k < 2
        assert_eq!(d.constrained_nodes(), 27 - 8);
    }

    #[test]
    fn unknown_group_and_empty_region_are_named() {
        let m = BoxMesh::new([0.0; 3], [1.0; 3], [1, 1, 1]).mesh().unwrap();
        let e = DofMap::new(&m, &[Dirichlet::clamped(Region::Group("top".into()))]).unwrap_err();
        assert!(e.to_string().contains("dirichlet[0].on") && e.to_string().contains("top"), "{e}");
        let e = DofMap::new(&m, &[Dirichlet::clamped(Region::Disc { center: [5.0, 5.0], radius: 0.1 })]).unwrap_err();
        assert!(e.to_string().contains("selects no boundary facet"), "{e}");
    }
}
