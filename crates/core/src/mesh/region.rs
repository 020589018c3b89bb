//! Regions of the boundary chosen by simple predicates, for Dirichlet conditions and contact
//! zones: a named facet group, a box, a disc, and their intersections, unions and complements.
//!
//! A region selects *facets* (by group membership, and by the centroid for geometric tests) and
//! *nodes* (a node is in a group when it lies on one of its facets, edge nodes of a second-order
//! mesh included; geometric tests use the node's coordinates). Example, Γ₁ of the default scene:
//! `{ all = [ { group = "zmin" }, { box = { min = [-0.75, -0.75, -1], max = [0.75, 0.75, 1] } } ] }`.

use crate::error::{ParameterError, check, join};
use crate::mesh::TetMesh;
use serde::{Deserialize, Serialize};

/// A predicate on boundary facets and nodes.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// The whole boundary.
    Boundary,
    /// A named facet group of the mesh (`zmin` of the box mesher, a Gmsh physical name).
    Group(String),
    /// The closed box `min ≤ x ≤ max`.
    Box {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
    /// The vertical cylinder `(x₁−c₁)² + (x₂−c₂)² ≤ r²`: a disc on a horizontal face.
    Disc {
        /// Centre (x₁, x₂).
        center: [f64; 2],
        /// Radius.
        radius: f64,
    },
    /// All of the listed regions (intersection).
    All(Vec<Region>),
    /// Any of the listed regions (union).
    Any(Vec<Region>),
    /// The rest of the boundary (complement).
    Not(Box<Region>),
}

/// Relative tolerance of the geometric tests (closed sets include their rim).
const TOL: f64 = 1e-10;

impl Region {
    /// Checks numbers and lists; `path` names this region in the scene. An empty `all` or `any`
    /// is an error: the intersection of nothing is the whole boundary and the union of nothing
    /// selects nothing, neither what a scene means to write.
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        if let Region::All(rs) | Region::Any(rs) = self
            && rs.is_empty()
        {
            let key = if matches!(self, Region::All(_)) { "all" } else { "any" };
            return Err(ParameterError::new(
                join(path, key),
                "[]",
                "an empty list (`all` of nothing is the whole boundary, `any` of nothing selects nothing): list at \
                 least one region, or write \"boundary\" for the whole boundary",
            ));
        }
        match self {
            Region::Boundary | Region::Group(_) => Ok(()),
            Region::Box { min, max } => {
                let p = join(path, "box");
                check::finite_all(&p, "min", min)?;
                check::finite_all(&p, "max", max)?;
                Ok(())
            }
            Region::Disc { center, radius } => {
                let p = join(path, "disc");
                check::finite_all(&p, "center", center)?;
                check::positive(&p, "radius", *radius)?;
                Ok(())
            }
            Region::All(rs) => {
                rs.iter().enumerate().try_for_each(|(i, r)| r.validate(&format!("{}[{i}]", join(path, "all"))))
            }
            Region::Any(rs) => {
                rs.iter().enumerate().try_for_each(|(i, r)| r.validate(&format!("{}[{i}]", join(path, "any"))))
            }
            Region::Not(r) => r.validate(&join(path, "not")),
        }
    }

    /// Group names used by this region that the mesh lacks.
    pub fn missing_groups(&self, mesh: &TetMesh) -> Vec<String> {
        match self {
            Region::Group(g) if !mesh.groups.contains_key(g) => vec![g.clone()],
            Region::All(rs) | Region::Any(rs) => rs.iter().flat_map(|r| r.missing_groups(mesh)).collect(),
            Region::Not(r) => r.missing_groups(mesh),
            _ => vec![],
        }
    }

    fn contains_point(&self, x: &[f64; 3], scale: f64) -> Option<bool> {
        let eps = TOL * scale;
        match self {
            Region::Box { min, max } => Some((0..3).all(|k| x[k] >= min[k] - eps && x[k] <= max[k] + eps)),
            Region::Disc { center, radius } => {
                let d2 = (x[0] - center[0]).powi(2) + (x[1] - center[1]).powi(2);
                Some(d2.sqrt() <= radius + eps)
            }
            _ => None,
        }
    }

    /// True when boundary facet `f` belongs to the region (geometric tests at its centroid).
    pub fn contains_facet(&self, mesh: &TetMesh, f: usize, facet_groups: &FacetGroups) -> bool {
        match self {
            Region::Boundary => true,
            Region::Group(g) => facet_groups.facet_in(g, f),
            Region::All(rs) => rs.iter().all(|r| r.contains_facet(mesh, f, facet_groups)),
            Region::Any(rs) => rs.iter().any(|r| r.contains_facet(mesh, f, facet_groups)),
            Region::Not(r) => !r.contains_facet(mesh, f, facet_groups),
            geometric => geometric.contains_point(&mesh.facet_centroid(f), facet_groups.diameter).unwrap_or(false),
        }
    }

    /// True when boundary node `n` belongs to the region.
    pub fn contains_node(&self, mesh: &TetMesh, n: usize, facet_groups: &FacetGroups) -> bool {
        match self {
            Region::Boundary => facet_groups.on_boundary[n],
            Region::Group(g) => facet_groups.node_in(g, n),
            Region::All(rs) => rs.iter().all(|r| r.contains_node(mesh, n, facet_groups)),
            Region::Any(rs) => rs.iter().any(|r| r.contains_node(mesh, n, facet_groups)),
            Region::Not(r) => facet_groups.on_boundary[n] && !r.contains_node(mesh, n, facet_groups),
            geometric => {
                facet_groups.on_boundary[n]
                    && geometric.contains_point(&mesh.nodes[n], facet_groups.diameter).unwrap_or(false)
            }
        }
    }

    /// The selected boundary facets.
    pub fn facets(&self, mesh: &TetMesh) -> Vec<usize> {
        let fg = FacetGroups::new(mesh);
        (0..mesh.boundary.len()).filter(|&f| self.contains_facet(mesh, f, &fg)).collect()
    }

    /// The selected boundary nodes, sorted.
    pub fn nodes(&self, mesh: &TetMesh) -> Vec<usize> {
        let fg = FacetGroups::new(mesh);
        (0..mesh.n_nodes()).filter(|&n| self.contains_node(mesh, n, &fg)).collect()
    }
}

/// Membership tables of facets and nodes in the mesh's facet groups, and the mesh's diameter
/// (the scale of the geometric tests), computed once per selection: a test per node or facet
/// that recomputed it would make selecting a region quadratic in the mesh size.
pub struct FacetGroups {
    /// The mesh's diameter.
    diameter: f64,
    names: Vec<String>,
    facet_mask: Vec<Vec<bool>>,
    node_mask: Vec<Vec<bool>>,
    on_boundary: Vec<bool>,
}

impl FacetGroups {
    /// Tables for `mesh`.
    pub fn new(mesh: &TetMesh) -> Self {
        let mut on_boundary = vec![false; mesh.n_nodes()];
        for f in 0..mesh.boundary.len() {
            for n in mesh.facet_nodes(f) {
                on_boundary[n] = true;
            }
        }
        let mut names = Vec::new();
        let mut facet_mask = Vec::new();
        let mut node_mask = Vec::new();
        for (name, facets) in &mesh.groups {
            let mut fm = vec![false; mesh.boundary.len()];
            let mut nm = vec![false; mesh.n_nodes()];
            for &f in facets {
                fm[f] = true;
                for n in mesh.facet_nodes(f) {
                    nm[n] = true;
                }
            }
            names.push(name.clone());
            facet_mask.push(fm);
            node_mask.push(nm);
        }
        Self { diameter: mesh.diameter(), names, facet_mask, node_mask, on_boundary }
    }

    fn index(&self, g: &str) -> Option<usize> {
        self.names.iter().position(|n| n == g)
    }

    fn facet_in(&self, g: &str, f: usize) -> bool {
        self.index(g).is_some_and(|i| self.facet_mask[i][f])
    }

    fn node_in(&self, g: &str, n: usize) -> bool {
        self.index(g).is_some_and(|i| self.node_mask[i][n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::box_mesh::BoxMesh;

    #[test]
    fn gamma_one_and_contact_disc_of_the_default_scene() {
        let m = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 2]).mesh().unwrap();
        let gamma1: Region = toml::from_str::<toml::Value>(
            "r = { all = [ { group = \"zmin\" }, { box = { min = [-0.75, -0.75, -1.0], max = [0.75, 0.75, 1.0] } } ] }",
        )
        .unwrap()["r"]
            .clone()
            .try_into()
            .unwrap();
        // bottom cells of size 0.25: the open square |x|,|y| < 0.75 holds 6×6 cells, 2 facets each
        assert_eq!(gamma1.facets(&m).len(), 72);
        let clamped = Region::Not(Box::new(gamma1));
        assert_eq!(clamped.facets(&m).len(), m.boundary.len() - 72);
        let disc = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [0.0, 0.0], radius: 0.5 }]);
        // nodes of the 0.25 grid with x² + y² ≤ 0.25: 13 of them
        assert_eq!(disc.nodes(&m).len(), 13);
        assert!(Region::Group("nope".into()).missing_groups(&m) == vec!["nope".to_string()]);
        // validation errors carry the full TOML path
        let bad = Region::Not(Box::new(Region::All(vec![
            Region::Group("zmin".into()),
            Region::Disc { center: [0.0, f64::NAN], radius: 0.5 },
        ])));
        assert_eq!(bad.validate("obstacle.zone").unwrap_err().field, "obstacle.zone.not.all[1].disc.center[1]");
    }
}
