//! The P1 displacement space W_h (theory §3): three degrees of freedom per node, those fixed by
//! Dirichlet conditions eliminated. A Dirichlet condition fixes chosen components on the nodes
//! of the selected facets (closure): all three is clamped, one is a roller; `value` prescribes
//! a displacement other than zero (theory §14: a lifting, not a change of the dofs).

use crate::error::{ParameterError, SceneError, join};
use crate::mesh::TetMesh;
use crate::mesh::region::Region;
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

/// `[[dirichlet]]`: u_c = value_c (0 by default) for the listed components on the closure of
/// the selected facets; its reaction is reported under `name` (theory §14).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
    /// The facets (Γ₂ for clamping).
    pub on: Region,
    /// Fixed components; all three (clamped) by default.
    #[serde(default = "all_components")]
    pub components: Vec<Component>,
    /// The prescribed displacement, scaled by the load factor: `[ux, uy, uz]`, or one value per
    /// entry of `components`; zero when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Vec<f64>>,
    /// The key of this entry's reaction in reports (`dirichlet[i]` when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
}

impl Dirichlet {
    /// Clamped on `on`.
    pub fn clamped(on: Region) -> Self {
        Self { on, components: all_components(), value: None, name: None }
    }

    /// A roller: only `c` fixed on `on`.
    pub fn roller(on: Region, c: Component) -> Self {
        Self { on, components: vec![c], value: None, name: None }
    }

    /// The same condition with the prescribed displacement `value` (as the scene key).
    pub fn with_value(self, value: Vec<f64>) -> Self {
        Self { value: Some(value), ..self }
    }

    /// The prescribed value of each component at load factor 1 (`None`: not fixed by this
    /// entry). The entry is taken as validated.
    pub fn prescribed(&self) -> [Option<f64>; 3] {
        let mut out = [None; 3];
        for (k, c) in self.components.iter().enumerate() {
            out[c.index()] = Some(match &self.value {
                None => 0.0,
                Some(v) if v.len() == self.components.len() => v[k],
                Some(v) => v[c.index()],
            });
        }
        out
    }

    /// True when some prescribed value is not zero.
    pub fn is_inhomogeneous(&self) -> bool {
        self.value.as_ref().is_some_and(|v| v.iter().any(|x| *x != 0.0))
    }

    /// The key of the entry's reaction: its `name`, or `dirichlet[i]`.
    pub fn key(&self, i: usize) -> String {
        self.name.clone().unwrap_or_else(|| format!("dirichlet[{i}]"))
    }

    /// Checks the region's numbers (`{path}.on`) and that at least one component is fixed: an
    /// empty `components` fixes nothing, an error on `{path}.components`.
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.on.validate(&join(path, "on"))?;
        if self.components.is_empty() {
            return Err(ParameterError::new(
                join(path, "components"),
                "[]",
                "fixes no component, so the condition would do nothing: list the fixed components (\"x\", \"y\", \
                 \"z\"), or omit the key to clamp all three",
            ));
        }
        if let Some(v) = &self.value {
            let field = join(path, "value");
            let n = self.components.len();
            if v.len() != 3 && v.len() != n {
                return Err(ParameterError::new(
                    &field,
                    format!("{v:?}"),
                    format!("has {} entries: give [ux, uy, uz] (3) or one value per component ({n})", v.len()),
                ));
            }
            crate::error::check::bounded_all(path, "value", v)?;
            let unconstrained = |c: &usize| v[*c] != 0.0 && !self.components.iter().any(|k| k.index() == *c);
            if let Some(c) = (0..3).filter(|_| v.len() == 3 && n != 3).find(unconstrained) {
                return Err(ParameterError::new(
                    format!("{field}[{c}]"),
                    crate::error::number(v[c]),
                    format!(
                        "prescribes component {:?}, which this entry does not constrain (components = {:?}): \
                             add it to `components`, or set it to 0",
                        ["x", "y", "z"][c],
                        self.components
                    ),
                ));
            }
        }
        if let Some(name) = self.name.as_ref().filter(|n| n.trim().is_empty()) {
            return Err(ParameterError::new(join(path, "name"), format!("{name:?}"), "must not be empty"));
        }
        Ok(())
    }
}

/// No entry fixes the dof (in [`fixing_entries`]).
pub const FREE: u32 = u32::MAX;

/// For every node and component, the first of `conditions` that fixes it, or [`FREE`]. Errors
/// name the condition whose region selects no facet or a group that does not exist.
pub fn fixing_entries(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Vec<[u32; 3]>, SceneError> {
    let mut owner = vec![[FREE; 3]; mesh.n_nodes()];
    for (i, c) in conditions.iter().enumerate() {
        c.validate(&format!("dirichlet[{i}]"))?;
        let field = format!("dirichlet[{i}].on");
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
            for n in mesh.facet_nodes(f) {
                for comp in &c.components {
                    let o = &mut owner[n][comp.index()];
                    if *o == FREE {
                        *o = i as u32;
                    }
                }
            }
        }
    }
    Ok(owner)
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
    /// Applies homogeneous conditions to the mesh. Errors name the condition whose region
    /// selects no facet or a group that does not exist, and a prescribed value other than zero:
    /// only a whole problem ([`crate::fem::DiscreteProblem`], through
    /// [`DofMap::with_values`]) carries its lifting (theory §14), a rank's part does not yet.
    pub fn new(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Self, SceneError> {
        if let Some(i) = conditions.iter().position(Dirichlet::is_inhomogeneous) {
            return Err(ParameterError::new(
                format!("dirichlet[{i}].value"),
                format!("{:?}", conditions[i].value.as_deref().unwrap_or_default()),
                "prescribed displacements other than zero are not available in a distributed run yet: run on \
                 one machine",
            )
            .into());
        }
        Self::with_values(mesh, conditions)
    }

    /// Applies the conditions to the mesh, prescribed values allowed (the dofs are the same as
    /// for zero values: the values enter as a lifting, theory §14).
    pub fn with_values(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Self, SceneError> {
        let fixed: Vec<[bool; 3]> = fixing_entries(mesh, conditions)?.iter().map(|o| o.map(|e| e != FREE)).collect();
        Ok(Self::from_fixed(&fixed))
    }

    /// The numbering of the components not `fixed` (per node, per component), node-major.
    pub fn from_fixed(fixed: &[[bool; 3]]) -> Self {
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
        Self { dof, n_free: n_free as usize }
    }

    /// The free index of component `c` of `node`, if free.
    #[inline]
    pub fn free(&self, node: usize, c: usize) -> Option<usize> {
        let d = self.dof[node][c];
        (d != FIXED).then_some(d as usize)
    }

    /// The inverse numbering: the node and the component (0, 1, 2) of every free dof.
    pub fn owners(&self) -> (Vec<u32>, Vec<u8>) {
        let mut node = vec![0u32; self.n_free];
        let mut comp = vec![0u8; self.n_free];
        for (n, d) in self.dof.iter().enumerate() {
            for c in 0..3 {
                if d[c] != FIXED {
                    node[d[c] as usize] = n as u32;
                    comp[d[c] as usize] = c as u8;
                }
            }
        }
        (node, comp)
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.dof.len()
    }

    /// Nodal displacements from a vector of free values (fixed components are zero).
    pub fn nodal(&self, u: &[f64]) -> Vec<[f64; 3]> {
        self.dof.iter().map(|d| std::array::from_fn(|c| if d[c] == FIXED { 0.0 } else { u[d[c] as usize] })).collect()
    }

    /// An error naming the rigid-body motion the conditions leave free, if any (the elastic
    /// stiffness on the free space is then singular). Scenes check this before solving.
    pub fn check_rigid_motions(&self, mesh: &TetMesh) -> Result<(), SceneError> {
        let fixed: Vec<[bool; 3]> = self.dof.iter().map(|d| d.map(|x| x == FIXED)).collect();
        match free_rigid_motion(mesh, &fixed) {
            None => Ok(()),
            Some(motion) => Err(SceneError::Region {
                field: "dirichlet".into(),
                message: format!(
                    "the conditions leave a rigid-body motion free ({motion}): the stiffness would be singular. \
                     Clamp the body on a surface, or fix enough components (three non-collinear nodes clamped \
                     at least)"
                ),
            }),
        }
    }

    /// Number of nodes with at least one fixed component.
    pub fn constrained_nodes(&self) -> usize {
        self.dof.iter().filter(|d| d.contains(&FIXED)).count()
    }
}

/// A rigid-body motion r(x) = a + b × (x − x̄) that vanishes on every fixed component, described
/// in words, or `None` when the conditions hold all six (the kernel of the elastic stiffness on
/// the free space is then trivial). The six modes are orthonormalised over all nodes and the
/// Gram matrix of their fixed components is tested for a null direction.
fn free_rigid_motion(mesh: &TetMesh, fixed: &[[bool; 3]]) -> Option<String> {
    use nalgebra::{Matrix6, SymmetricEigen, Vector6};
    let n = mesh.n_nodes().max(1) as f64;
    let centre = mesh.nodes.iter().fold([0.0; 3], |c, x| std::array::from_fn(|k| c[k] + x[k] / n));
    let size = mesh.nodes.iter().flat_map(|x| (0..3).map(move |k| (x[k] - centre[k]).abs())).fold(0.0, f64::max);
    let size = if size > 0.0 { size } else { 1.0 };
    // mode values of component c at x: translations e_c, rotations e_k × (x − x̄) / size
    let modes = |x: &[f64; 3], c: usize| -> Vector6<f64> {
        let d: [f64; 3] = std::array::from_fn(|k| (x[k] - centre[k]) / size);
        let mut m = Vector6::zeros();
        m[c] = 1.0;
        // (e_k × d)_c for k = 0, 1, 2
        m[3] = [0.0, -d[2], d[1]][c];
        m[4] = [d[2], 0.0, -d[0]][c];
        m[5] = [-d[1], d[0], 0.0][c];
        m
    };
    let (mut all, mut held) = (Matrix6::<f64>::zeros(), Matrix6::<f64>::zeros());
    for (x, fx) in mesh.nodes.iter().zip(fixed) {
        for (c, &is_fixed) in fx.iter().enumerate() {
            let m = modes(x, c);
            let mm = m * m.transpose();
            all += mm;
            if is_fixed {
                held += mm;
            }
        }
    }
    // generalised eigenproblem held v = λ all v through all = LLᵀ
    let l = all.cholesky()?.l();
    let l_inv = l.try_inverse()?;
    let reduced = l_inv * held * l_inv.transpose();
    let eig = SymmetricEigen::new(reduced);
    let (k, &lambda) = eig.eigenvalues.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    if lambda > 1e-10 {
        return None;
    }
    let v = l_inv.transpose() * eig.eigenvectors.column(k);
    let describe = |w: [f64; 3]| {
        let norm = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        format!("({:.2}, {:.2}, {:.2})", w[0] / norm, w[1] / norm, w[2] / norm)
    };
    let (t, r) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
    let (tn, rn) = (t.iter().map(|a| a * a).sum::<f64>().sqrt(), r.iter().map(|a| a * a).sum::<f64>().sqrt());
    Some(if rn < 1e-6 * tn.max(1e-300) {
        format!("a translation along {}", describe(t))
    } else {
        format!("a rotation about the axis {}", describe(r))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::box_mesh::BoxMesh;

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

    #[test]
    fn rigid_body_motion_left_free_is_an_error_naming_it() {
        let m = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).mesh().unwrap();
        // nothing fixed: a translation is free
        let check = |c: &[Dirichlet]| DofMap::new(&m, c).unwrap().check_rigid_motions(&m);
        let e = check(&[]).unwrap_err().to_string();
        assert!(e.contains("dirichlet") && e.contains("rigid-body motion free"), "{e}");
        // z fixed on the bottom only: x, y translations and the rotation about z are free
        let e = check(&[Dirichlet::roller(Region::Group("zmin".into()), Component::Z)]).unwrap_err();
        assert!(e.to_string().contains("rigid-body"), "{e}");
        // rollers on three orthogonal faces (x on xmin, y on ymin, z on zmin) hold every rigid motion
        let rollers = [
            Dirichlet::roller(Region::Group("xmin".into()), Component::X),
            Dirichlet::roller(Region::Group("ymin".into()), Component::Y),
            Dirichlet::roller(Region::Group("zmin".into()), Component::Z),
        ];
        assert!(check(&rollers).is_ok());
        // the bottom clamped
        let bottom_only = [Dirichlet::clamped(Region::Group("zmin".into()))];
        assert!(check(&bottom_only).is_ok());
        // only x fixed everywhere on xmin: translation along y free, named as such
        let e = check(&[Dirichlet::roller(Region::Group("xmin".into()), Component::X)]).unwrap_err();
        assert!(e.to_string().contains("rigid-body"), "{e}");
    }
}
