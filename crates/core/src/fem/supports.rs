//! The supports of a problem (theory §14): the `[[dirichlet]]` entries, their prescribed
//! displacements as a lifting u_D (u = u_D + w with w = 0 on Γ_D, so that the dofs stay those of
//! the homogeneous conditions and no solver changes), and their reactions r = Bᵀσ − f at the
//! constrained dofs, summed per entry with their moment about the origin.

use crate::error::SceneError;
use crate::fem::Discretisation;
use crate::fem::loads::{Load, nodal_loads};
use crate::mesh::dofs::{Dirichlet, DofMap, nodal_supports};
use crate::mesh::frames::NodalSupport;
use crate::problem::fields::PlasticState;
use crate::problem::tensor::Sym;
use std::sync::OnceLock;

pub use crate::problem::lifting::Lifting;

/// The reaction of one `[[dirichlet]]` entry (theory §14): the resultant of r = Bᵀσ − f over the
/// dofs it constrains, and its moment about the origin.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Reaction {
    /// The entry's `name`, or `dirichlet[i]`.
    #[serde(skip)]
    pub key: String,
    /// Σ r.
    pub force: [f64; 3],
    /// Σ x × r.
    pub moment: [f64; 3],
}

/// The `[[dirichlet]]` entries of a problem with their lifting and what their reactions need.
#[derive(Debug)]
pub struct Supports {
    entries: Vec<Dirichlet>,
    /// The directions held at each node, each with the first entry holding it (theory §14.4).
    held: Vec<NodalSupport>,
    /// u_D per node at factor 1 (empty for homogeneous conditions).
    lifting: Vec<[f64; 3]>,
    /// ε(u_D) per point at factor 1 (empty as `lifting`).
    lifting_strain: Vec<Sym>,
    /// The loads' consistent nodal forces on every dof (3 per node), at factor 1.
    load: Vec<f64>,
    /// The element with every dof free, built on first use.
    unconstrained: OnceLock<Option<Box<dyn Discretisation>>>,
}

impl Supports {
    /// The supports `entries` of the problem on `element` with the loads `loads`. Errors name a
    /// prescribed value the element cannot carry (a distributed part).
    pub fn new(element: &dyn Discretisation, entries: &[Dirichlet], loads: &[Load]) -> Result<Self, SceneError> {
        let mesh = element.mesh();
        let held = nodal_supports(mesh, entries)?;
        let all_free = DofMap::from_fixed(&vec![[false; 3]; mesh.n_nodes()]);
        let load = if loads.is_empty() { Vec::new() } else { nodal_loads(mesh, &all_free, loads)? };
        let mut s = Self {
            entries: entries.to_vec(),
            held,
            lifting: Vec::new(),
            lifting_strain: Vec::new(),
            load,
            unconstrained: OnceLock::new(),
        };
        if let Some(i) = entries.iter().position(Dirichlet::is_inhomogeneous) {
            let values: Vec<[Option<f64>; 3]> = entries.iter().map(Dirichlet::prescribed).collect();
            // each held direction's value: a component's, or 0 along a normal
            let value = |e: u32, d: &[f64; 3]| (0..3).find(|&c| d[c] == 1.0).and_then(|c| values[e as usize][c]);
            s.lifting = (s.held.iter())
                .map(|h| {
                    let v: [f64; 3] = std::array::from_fn(|i| {
                        if i < h.n as usize { value(h.entry[i], &h.direction[i]).unwrap_or(0.0) } else { 0.0 }
                    });
                    h.lift(v)
                })
                .collect();
            let full = s.unconstrained(element).ok_or_else(|| SceneError::Region {
                field: format!("dirichlet[{i}].value"),
                message: "prescribed displacements other than zero are not available for this element yet".into(),
            })?;
            let u: Vec<f64> = s.lifting.iter().flatten().copied().collect();
            let mut strain = vec![Sym::zeros(); full.n_points()];
            full.strain(&u, &mut strain);
            s.lifting_strain = strain;
        }
        Ok(s)
    }

    fn unconstrained(&self, element: &dyn Discretisation) -> Option<&dyn Discretisation> {
        self.unconstrained.get_or_init(|| element.unconstrained()).as_deref()
    }

    /// The entries.
    pub fn entries(&self) -> &[Dirichlet] {
        &self.entries
    }

    /// The lifting at load factor `factor`.
    pub fn lifting(&self, factor: f64) -> Lifting<'_> {
        Lifting { nodal: &self.lifting, strain: &self.lifting_strain, factor }
    }

    /// True when some prescribed value is not zero.
    pub fn is_lifted(&self) -> bool {
        !self.lifting.is_empty()
    }

    /// The state the local law of w reads (theory §14): (ε_p − factor·ε(u_D), q_n), so that its
    /// trial C(ε(w) − ε_p + factor·ε(u_D)) is that of u. `state` unchanged without a lifting.
    pub fn shifted_state(&self, mut state: PlasticState, factor: f64) -> PlasticState {
        for (p, d) in state.plastic_strain.iter_mut().zip(&self.lifting_strain) {
            *p -= d * factor;
        }
        state
    }

    /// The first entry with a `normal` holding a direction at `node`.
    pub fn inclined_entry(&self, node: usize) -> Option<usize> {
        let inclined = |e: u32| self.entries[e as usize].normal.is_some();
        self.held[node].directions().map(|(e, _)| e).find(|&e| inclined(e)).map(|e| e as usize)
    }

    /// The mesh nodes where a prescribed value is not zero.
    pub fn lifted_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.lifting.iter().enumerate().filter(|(_, d)| d.iter().any(|x| *x != 0.0)).map(|(n, _)| n)
    }

    /// The reaction of every entry (theory §14) to the stresses `sigma` at load factor `factor`:
    /// r = Bᵀσ − factor·f on every dof, split at each node onto the directions held there
    /// (theory §14.4) and summed per entry holding them first. `None` when the element cannot
    /// give its unconstrained form (a distributed part).
    pub fn reactions(&self, element: &dyn Discretisation, sigma: &[Sym], factor: f64) -> Option<Vec<Reaction>> {
        let full = self.unconstrained(element)?;
        let mut r = vec![0.0; full.n_dofs()];
        full.divergence(sigma, &mut r);
        for (ri, f) in r.iter_mut().zip(&self.load) {
            *ri -= factor * f;
        }
        let nodes = &element.mesh().nodes;
        let mut out: Vec<Reaction> = (self.entries.iter().enumerate())
            .map(|(i, d)| Reaction { key: d.key(i), force: [0.0; 3], moment: [0.0; 3] })
            .collect();
        for (n, h) in self.held.iter().enumerate() {
            let x = nodes[n];
            let alpha = h.split([r[3 * n], r[3 * n + 1], r[3 * n + 2]]);
            for (i, (e, d)) in h.directions().enumerate() {
                let (f, e) = (d.map(|dc| alpha[i] * dc), &mut out[e as usize]);
                for c in 0..3 {
                    let (a, b) = ((c + 1) % 3, (c + 2) % 3);
                    e.force[c] += f[c];
                    // (x × f)_c
                    e.moment[c] += x[a] * f[b] - x[b] * f[a];
                }
            }
        }
        Some(out)
    }
}
