//! The P1 displacement space W_h (theory §3): three degrees of freedom per node, those fixed by
//! Dirichlet conditions eliminated. A Dirichlet condition fixes chosen components on the nodes
//! of the selected facets (closure): all three is clamped, one is a roller; `value` prescribes
//! a displacement other than zero (theory §14: a lifting, not a change of the dofs).

use crate::error::{ParameterError, SceneError, join};
use crate::mesh::TetMesh;
use crate::mesh::frames::NodalSupport;
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

/// All three components: a clamp.
const ALL: [Component; 3] = [Component::X, Component::Y, Component::Z];

/// `[[dirichlet]]`: u_c = value_c (0 by default) for the listed components on the closure of
/// the selected facets, or with `normal` no motion along n there (an inclined support, theory
/// §14.4); its reaction is reported under `name` (theory §14).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
    /// The facets (Γ₂ for clamping).
    pub on: Region,
    /// Fixed components; all three (clamped) when absent, none with `normal`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub components: Option<Vec<Component>>,
    /// The prescribed displacement, scaled by the load factor: `[ux, uy, uz]`, or one value per
    /// entry of `components`; zero when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Vec<f64>>,
    /// An inclined support: n·u = 0 at the selected nodes (theory §14.4), `[n1, n2, n3]` of any
    /// length but zero; excludes `components` and `value`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<Vec<f64>>,
    /// The key of this entry's reaction in reports (`dirichlet[i]` when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
}

impl Dirichlet {
    /// Clamped on `on`.
    pub fn clamped(on: Region) -> Self {
        Self { on, components: None, value: None, normal: None, name: None }
    }

    /// A roller: only `c` fixed on `on`.
    pub fn roller(on: Region, c: Component) -> Self {
        Self { components: Some(vec![c]), ..Self::clamped(on) }
    }

    /// An inclined support on `on`: no motion along `normal` (theory §14.4).
    pub fn inclined(on: Region, normal: [f64; 3]) -> Self {
        Self { normal: Some(normal.to_vec()), ..Self::clamped(on) }
    }

    /// The same condition with the prescribed displacement `value` (as the scene key).
    pub fn with_value(self, value: Vec<f64>) -> Self {
        Self { value: Some(value), ..self }
    }

    /// The fixed components: those listed, all three when absent, none for a `normal` entry.
    pub fn components(&self) -> &[Component] {
        match (&self.components, &self.normal) {
            (Some(c), _) => c,
            (None, None) => &ALL,
            (None, Some(_)) => &[],
        }
    }

    /// The directions the entry holds u along: e_c per fixed component, or its normal. The
    /// entry is taken as validated.
    pub fn directions(&self) -> Vec<[f64; 3]> {
        match &self.normal {
            Some(n) => vec![[n[0], n[1], n[2]]],
            None => self.components().iter().map(|c| std::array::from_fn(|k| (k == c.index()) as u8 as f64)).collect(),
        }
    }

    /// The prescribed value of each component at load factor 1 (`None`: not fixed by this
    /// entry). The entry is taken as validated.
    pub fn prescribed(&self) -> [Option<f64>; 3] {
        let mut out = [None; 3];
        let components = self.components();
        for (k, c) in components.iter().enumerate() {
            out[c.index()] = Some(match &self.value {
                None => 0.0,
                Some(v) if v.len() == components.len() => v[k],
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
    /// empty `components` fixes nothing, an error on `{path}.components`. A `normal` has three
    /// finite entries, not all zero, and goes with neither `components` nor `value`.
    pub fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.on.validate(&join(path, "on"))?;
        if let Some(n) = &self.normal {
            validate_normal(path, n)?;
            let excluded = match (&self.components, &self.value) {
                (Some(c), _) => Some(("components", format!("{c:?}"))),
                (None, Some(v)) => Some(("value", format!("{v:?}"))),
                (None, None) => None,
            };
            if let Some((field, value)) = excluded {
                return Err(ParameterError::new(
                    join(path, field),
                    value,
                    format!(
                        "cannot go with `normal` on the same entry: a `normal` support holds u along n = {n:?} \
                         only, with no displacement; put the {field} in an [[dirichlet]] entry of its own"
                    ),
                ));
            }
        }
        if self.components.as_ref().is_some_and(Vec::is_empty) {
            return Err(ParameterError::new(
                join(path, "components"),
                "[]",
                "fixes no component, so the condition would do nothing: list the fixed components (\"x\", \"y\", \
                 \"z\"), or omit the key to clamp all three",
            ));
        }
        if let Some(c) = self.components.as_ref().and_then(|c| (1..c.len()).find(|&i| c[..i].contains(&c[i]))) {
            let names: Vec<&str> = self.components().iter().map(|c| ["x", "y", "z"][c.index()]).collect();
            return Err(ParameterError::new(
                format!("{}[{c}]", join(path, "components")),
                format!("{names:?}"),
                "lists a component twice: name each fixed component once",
            ));
        }
        if let Some(v) = &self.value {
            let field = join(path, "value");
            let components = self.components();
            let n = components.len();
            if v.len() != 3 && v.len() != n {
                return Err(ParameterError::new(
                    &field,
                    format!("{v:?}"),
                    format!("has {} entries: give [ux, uy, uz] (3) or one value per component ({n})", v.len()),
                ));
            }
            crate::error::check::bounded_all(path, "value", v)?;
            let unconstrained = |c: &usize| v[*c] != 0.0 && !components.iter().any(|k| k.index() == *c);
            if let Some(c) = (0..3).filter(|_| v.len() == 3 && n != 3).find(unconstrained) {
                return Err(ParameterError::new(
                    format!("{field}[{c}]"),
                    crate::error::number(v[c]),
                    format!(
                        "prescribes component {:?}, which this entry does not constrain (components = {:?}): \
                             add it to `components`, or set it to 0",
                        ["x", "y", "z"][c],
                        components
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

/// `{path}.normal`: three finite numbers, not all zero.
fn validate_normal(path: &str, n: &[f64]) -> Result<(), ParameterError> {
    let field = join(path, "normal");
    if n.len() != 3 {
        return Err(ParameterError::new(
            &field,
            format!("{n:?}"),
            format!("has {} entries: give the normal of the support plane as [n1, n2, n3]", n.len()),
        ));
    }
    crate::error::check::finite_all(path, "normal", n)?;
    if n.iter().all(|x| *x == 0.0) {
        return Err(ParameterError::new(
            &field,
            format!("{n:?}"),
            "is zero, so it gives no direction: give the normal of the support plane (any length but zero)",
        ));
    }
    Ok(())
}

/// For every node the directions its displacement is held along, each with the first of
/// `conditions` that holds it (theory §14.4). Errors name the condition whose region selects
/// no facet or a group that does not exist.
pub fn nodal_supports(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Vec<NodalSupport>, SceneError> {
    let mut supports = vec![NodalSupport::default(); mesh.n_nodes()];
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
        let directions = c.directions();
        for f in facets {
            for n in mesh.facet_nodes(f) {
                for d in &directions {
                    supports[n].hold(i as u32, *d);
                }
            }
        }
    }
    Ok(supports)
}

/// Marker of an eliminated (fixed) degree of freedom.
pub const FIXED: u32 = u32::MAX;

/// No frame at the node (in [`DofMap`]): its dofs are the axes' components.
const NO_FRAME: u32 = u32::MAX;

/// Numbering of the free degrees of freedom: node-major, components in order. A node with an
/// inclined support has a frame R (theory §14.4): its dofs are the components R[k]·u, the
/// held ones first and fixed, so that the support is an ordinary fixed dof; every other node's
/// dofs are the axes' components.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// `dof[node][k]` is the free index of component k of node (in its frame, if any), or
    /// [`FIXED`].
    pub dof: Vec<[u32; 3]>,
    /// Number of free degrees of freedom.
    pub n_free: usize,
    /// The index in `frames` of each node's frame, or [`NO_FRAME`] (empty: no frames).
    frame_of: Vec<u32>,
    /// The nodal frames, rows R[k].
    frames: Vec<[[f64; 3]; 3]>,
}

impl DofMap {
    /// Applies homogeneous conditions on the axes to the mesh. Errors name the condition whose
    /// region selects no facet or a group that does not exist, a prescribed value other than
    /// zero and an inclined support: only a whole problem ([`crate::fem::DiscreteProblem`],
    /// through [`DofMap::with_values`]) carries its lifting and its frames (theory §14), a
    /// rank's part does not yet.
    pub fn new(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Self, SceneError> {
        let distributed = "not available in a distributed run yet: run on one machine";
        if let Some(i) = conditions.iter().position(Dirichlet::is_inhomogeneous) {
            return Err(ParameterError::new(
                format!("dirichlet[{i}].value"),
                format!("{:?}", conditions[i].value.as_deref().unwrap_or_default()),
                format!("prescribed displacements other than zero are {distributed}"),
            )
            .into());
        }
        if let Some(i) = conditions.iter().position(|c| c.normal.is_some()) {
            return Err(ParameterError::new(
                format!("dirichlet[{i}].normal"),
                format!("{:?}", conditions[i].normal.as_deref().unwrap_or_default()),
                format!("inclined supports are {distributed}"),
            )
            .into());
        }
        Self::with_values(mesh, conditions)
    }

    /// Applies the conditions to the mesh, prescribed values and inclined supports allowed
    /// (the dofs are the same as for zero values: the values enter as a lifting, theory §14).
    pub fn with_values(mesh: &TetMesh, conditions: &[Dirichlet]) -> Result<Self, SceneError> {
        Ok(Self::from_supports(&nodal_supports(mesh, conditions)?))
    }

    /// The numbering of the components not held by `supports` (per node): a node held along
    /// the axes only has its components, a node with an inclined direction its frame.
    pub fn from_supports(supports: &[NodalSupport]) -> Self {
        let fixed: Vec<[bool; 3]> =
            supports.iter().map(|s| s.axes().unwrap_or(std::array::from_fn(|k| k < s.n as usize))).collect();
        let mut map = Self::from_fixed(&fixed);
        // a node held in all three directions has no free component to give a frame to
        let inclined = |s: &NodalSupport| s.axes().is_none() && s.n < 3;
        if supports.iter().any(inclined) {
            map.frame_of = vec![NO_FRAME; supports.len()];
            for (n, s) in supports.iter().enumerate().filter(|(_, s)| inclined(s)) {
                map.frame_of[n] = map.frames.len() as u32;
                map.frames.push(s.frame());
            }
        }
        map
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
        Self { dof, n_free: n_free as usize, frame_of: Vec::new(), frames: Vec::new() }
    }

    /// The free index of component `c` of `node`, if free.
    #[inline]
    pub fn free(&self, node: usize, c: usize) -> Option<usize> {
        let d = self.dof[node][c];
        (d != FIXED).then_some(d as usize)
    }

    /// The frame of `node` (rows R[k]), if it has one (theory §14.4).
    #[inline]
    pub fn frame(&self, node: usize) -> Option<&[[f64; 3]; 3]> {
        let i = *self.frame_of.get(node)?;
        (i != NO_FRAME).then(|| &self.frames[i as usize])
    }

    /// Whether some node has a frame.
    pub fn has_frames(&self) -> bool {
        !self.frames.is_empty()
    }

    /// The direction of component k of `node`: e_k, or R[k] in a frame.
    pub fn direction(&self, node: usize, k: usize) -> [f64; 3] {
        self.frame(node).map_or(std::array::from_fn(|c| (c == k) as u8 as f64), |r| r[k])
    }

    /// A linear quantity of the unit displacement along component k of `node`, from its
    /// values `of(c)` for the axes e_c: `of(k)`, or Σ_c R[k][c]·of(c) in a frame.
    #[inline]
    pub fn along<T: std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>>(
        &self,
        node: usize,
        k: usize,
        of: impl Fn(usize) -> T,
    ) -> T {
        match self.frame(node) {
            None => of(k),
            Some(r) => of(0) * r[k][0] + of(1) * r[k][1] + of(2) * r[k][2],
        }
    }

    /// The components of the vector `v` (on the axes) in the dofs of `node`: R v in a frame.
    #[inline]
    pub fn to_local(&self, node: usize, v: [f64; 3]) -> [f64; 3] {
        self.frame(node).map_or(v, |r| r.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2]))
    }

    /// The displacement of `node` on the axes from the free values `u` (fixed components 0):
    /// Rᵀ of its components in a frame.
    #[inline]
    pub fn displacement(&self, u: &[f64], node: usize) -> [f64; 3] {
        let local = self.dof[node].map(|d| if d == FIXED { 0.0 } else { u[d as usize] });
        match self.frame(node) {
            None => local,
            Some(r) => std::array::from_fn(|c| r[0][c] * local[0] + r[1][c] * local[1] + r[2][c] * local[2]),
        }
    }

    /// The inverse numbering: the node and the component (0, 1, 2; in the node's frame, if
    /// any) of every free dof.
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

    /// Nodal displacements on the axes from a vector of free values (fixed components zero).
    pub fn nodal(&self, u: &[f64]) -> Vec<[f64; 3]> {
        (0..self.n_nodes()).map(|n| self.displacement(u, n)).collect()
    }

    /// An error naming the rigid-body motion the conditions leave free, if any (the elastic
    /// stiffness on the free space is then singular). Scenes check this before solving.
    pub fn check_rigid_motions(&self, mesh: &TetMesh) -> Result<(), SceneError> {
        match free_rigid_motion(mesh, self) {
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

/// A rigid-body motion r(x) = a + b × (x − x̄) that vanishes along every fixed direction of
/// `dofs`, described in words, or `None` when the conditions hold all six (the kernel of the
/// elastic stiffness on the free space is then trivial). The six modes are orthonormalised
/// over all nodes and the Gram matrix of their fixed components is tested for a null direction.
fn free_rigid_motion(mesh: &TetMesh, dofs: &DofMap) -> Option<String> {
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
    for (node, x) in mesh.nodes.iter().enumerate() {
        // Σ over the axes equals Σ over any orthonormal frame
        for c in 0..3 {
            let m = modes(x, c);
            all += m * m.transpose();
        }
        for k in (0..3).filter(|&k| dofs.dof[node][k] == FIXED) {
            let d = dofs.direction(node, k);
            let m = modes(x, 0) * d[0] + modes(x, 1) * d[1] + modes(x, 2) * d[2];
            held += m * m.transpose();
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
        let check = |c: &[Dirichlet]| DofMap::with_values(&m, c).unwrap().check_rigid_motions(&m);
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
        // three faces held along one inclined normal: the motions in the plane are free
        let n = [1.0, 0.0, 1.0];
        let parallel = ["xmin", "zmin", "xmax"].map(|g| Dirichlet::inclined(Region::Group(g.into()), n));
        let e = check(&parallel).unwrap_err().to_string();
        assert!(e.contains("rigid-body motion free"), "{e}");
        // three faces held along three independent inclined normals hold all six
        let normals = [[1.0, 0.2, 0.1], [0.1, 1.0, -0.3], [0.2, 0.1, 1.0]];
        let independent: Vec<Dirichlet> = (["xmin", "ymin", "zmin"].iter().zip(normals))
            .map(|(g, n)| Dirichlet::inclined(Region::Group((*g).into()), n))
            .collect();
        assert!(check(&independent).is_ok());
    }
}
