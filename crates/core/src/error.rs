//! Typed errors. Each carries the offending value and where it came from (field path, element,
//! node, file), so that a message alone tells the user what to fix.

use std::fmt::Display;
use std::path::PathBuf;
use thiserror::Error;

/// A parameter outside its admissible range: `field` is the full path in the scene
/// (`material.E`, `yield.h`, `obstacle.gap.R`), `value` what was given.
#[derive(Debug, Clone, Error, PartialEq)]
#[error("{field} = {value}: {requirement}")]
pub struct ParameterError {
    /// Path of the field in the scene file.
    pub field: String,
    /// The offending value as written.
    pub value: String,
    /// What the value must satisfy.
    pub requirement: String,
}

impl ParameterError {
    /// An error for `field` holding `value`, which must satisfy `requirement`.
    pub fn new(field: impl Into<String>, value: impl Display, requirement: impl Into<String>) -> Self {
        Self { field: field.into(), value: value.to_string(), requirement: requirement.into() }
    }
}

/// A number as an error shows it: as written for ordinary magnitudes (`0.3`, `-100`), in
/// scientific notation beyond (`1e308`, not 309 digits).
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() > 16 { format!("{x:e}") } else { plain }
}

/// Joins a table path and a field name: `join("material", "E") == "material.E"`.
pub fn join(path: &str, field: &str) -> String {
    if path.is_empty() { field.to_string() } else { format!("{path}.{field}") }
}

/// Checks for scene parameters: every numeric field rejects NaN and infinities first.
pub mod check {
    use super::{ParameterError, join, number};

    /// `value` is a finite number.
    pub fn finite(path: &str, field: &str, value: f64) -> Result<f64, ParameterError> {
        if value.is_finite() {
            Ok(value)
        } else {
            Err(ParameterError::new(join(path, field), number(value), "must be a finite number"))
        }
    }

    /// `value` is finite and > 0.
    pub fn positive(path: &str, field: &str, value: f64) -> Result<f64, ParameterError> {
        finite(path, field, value)?;
        if value > 0.0 { Ok(value) } else { Err(ParameterError::new(join(path, field), number(value), "must be > 0")) }
    }

    /// `value` is finite and ≥ 0.
    pub fn non_negative(path: &str, field: &str, value: f64) -> Result<f64, ParameterError> {
        finite(path, field, value)?;
        if value >= 0.0 {
            Ok(value)
        } else {
            Err(ParameterError::new(join(path, field), number(value), "must be >= 0"))
        }
    }

    /// `lo < value < hi`.
    pub fn open_interval(path: &str, field: &str, value: f64, lo: f64, hi: f64) -> Result<f64, ParameterError> {
        finite(path, field, value)?;
        if value > lo && value < hi {
            Ok(value)
        } else {
            Err(ParameterError::new(
                join(path, field),
                number(value),
                format!("must lie in the open interval ({lo}, {hi})"),
            ))
        }
    }

    /// A count (iterations, cells) is at least 1.
    pub fn at_least_one(path: &str, field: &str, value: usize) -> Result<usize, ParameterError> {
        if value >= 1 { Ok(value) } else { Err(ParameterError::new(join(path, field), value, "must be >= 1")) }
    }

    /// Every entry of a coordinate array is finite.
    pub fn finite_all(path: &str, field: &str, values: &[f64]) -> Result<(), ParameterError> {
        for (i, v) in values.iter().enumerate() {
            finite(path, &format!("{field}[{i}]"), *v)?;
        }
        Ok(())
    }

    /// The largest magnitude of a scene's physical parameter (a modulus, a force, a
    /// displacement, a yield stress, a coordinate). The solvers form products of up to about six
    /// of them (σ = Cε with ε from F/(E L²), then |σ|², E·|ε|² in the energies and residual
    /// norms): with every factor within [1e-50, 1e50] each such product lies within
    /// [1e-300, 1e300], inside f64's range (2.2e-308 to 1.8e308), so valid input never
    /// overflows to the "NaN or infinite entries" of a matrix. Physical data in any consistent
    /// unit system lie tens of decades inside (steel: E ≈ 2e11 Pa).
    pub const MAX_MAGNITUDE: f64 = 1e50;

    /// The smallest scale ([`scale`]): 1/[`MAX_MAGNITUDE`].
    pub const MIN_SCALE: f64 = 1e-50;

    /// `value` is finite with |value| ≤ [`MAX_MAGNITUDE`].
    pub fn bounded(path: &str, field: &str, value: f64) -> Result<f64, ParameterError> {
        finite(path, field, value)?;
        if value.abs() <= MAX_MAGNITUDE {
            Ok(value)
        } else {
            Err(ParameterError::new(
                join(path, field),
                number(value),
                format!(
                    "must lie in [-{MAX_MAGNITUDE:e}, {MAX_MAGNITUDE:e}] (larger magnitudes overflow the solvers' \
                     products; rescale the units)"
                ),
            ))
        }
    }

    /// Every entry of an array is finite with magnitude ≤ [`MAX_MAGNITUDE`].
    pub fn bounded_all(path: &str, field: &str, values: &[f64]) -> Result<(), ParameterError> {
        for (i, v) in values.iter().enumerate() {
            bounded(path, &format!("{field}[{i}]"), *v)?;
        }
        Ok(())
    }

    /// A scale whose inverse enters the solvers too (a modulus: the compliance A = C⁻¹, the
    /// hardening metric ξη/h; a radius of curvature: φ = r²/2R): finite, in
    /// [[`MIN_SCALE`], [`MAX_MAGNITUDE`]], or exactly 0 when `zero_allowed` (no hardening).
    pub fn scale(path: &str, field: &str, value: f64, zero_allowed: bool) -> Result<f64, ParameterError> {
        finite(path, field, value)?;
        if (zero_allowed && value == 0.0) || (MIN_SCALE..=MAX_MAGNITUDE).contains(&value) {
            return Ok(value);
        }
        let zero = if zero_allowed { "0 or " } else { "" };
        Err(ParameterError::new(
            join(path, field),
            number(value),
            format!(
                "must be {zero}in [{MIN_SCALE:e}, {MAX_MAGNITUDE:e}] (it and its inverse enter the solvers' \
                 products; rescale the units)"
            ),
        ))
    }
}

/// A mesh that cannot be used: the message names the element, node or file.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum MeshError {
    /// A tetrahedron with (numerically) zero volume.
    #[error("element {element} (nodes {nodes:?}) has zero volume ({volume:e}); the mesh is degenerate there")]
    Degenerate { element: usize, nodes: [usize; 4], volume: f64 },
    /// A tetrahedron with negative orientation.
    #[error("element {element} (nodes {nodes:?}) is inverted: signed volume {volume:e} < 0")]
    Inverted { element: usize, nodes: [usize; 4], volume: f64 },
    /// An element refers to a node that does not exist.
    #[error("element {element} refers to node {node}, but the mesh has only {n_nodes} nodes")]
    DanglingNode { element: usize, node: usize, n_nodes: usize },
    /// A node coordinate is NaN or infinite.
    #[error("node {node} has a non-finite coordinate {coords:?}")]
    NonFiniteNode { node: usize, coords: [f64; 3] },
    /// No tetrahedra at all.
    #[error("the mesh has no tetrahedra")]
    Empty,
    /// A facet of a named group is not a boundary facet of the tetrahedra.
    #[error("facet {facet:?} of group `{group}` is not a boundary face of any tetrahedron")]
    NotABoundaryFacet { group: String, facet: [usize; 3] },
    /// A file could not be read or parsed.
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
    /// An edge node of a 10-node tetrahedron that does not fit the mesh.
    #[error("element {element}: edge node {node} is unusable: {reason}")]
    BadEdgeNode { element: usize, node: usize, reason: &'static str },
}

/// Anything that stops a scene from being built: bad parameters, a bad mesh, an empty region,
/// a TOML error. The message always names the field or the file.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// TOML syntax, an unknown field, or an unknown plugin `type`.
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// A parameter out of range.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The mesh is unusable.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// A region selects nothing where something is required.
    #[error("{field}: {message}")]
    Region { field: String, message: String },
}
