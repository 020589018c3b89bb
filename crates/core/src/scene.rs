//! Scenes: a whole problem in one TOML file, every plugin chosen by `type` (typetag), unknown
//! types and fields rejected with the list of known ones.
//!
//! ```toml
//! title = "Johnson 1977: elasto-plastic punch"
//! [mesh]                       # MeshSource: "box", "inline", "gmsh" (feature `gmsh`)
//! type = "box"
//! min = [-1.0, -1.0, 0.0]
//! max = [1.0, 1.0, 1.0]
//! cells = [24, 24, 12]
//! grading = { toward = [0.0, 0.0, 0.0], ratio = 4.0 }
//! [material]                   # isotropic elasticity
//! E = 100.0
//! nu = 0.3
//! [yield]                      # P; omit the table for an elastic body
//! type = "von_mises"
//! k0 = 1.0
//! h = 5.0
//! [[dirichlet]]                # u = 0 on the closure of the selected facets
//! on = { not = { all = [ { group = "zmin" }, { box = { min = [-0.75, -0.75, -1.0], max = [0.75, 0.75, 1.0] } } ] } }
//! [[load]]                     # optional: tractions and body forces
//! type = "traction"            # or: type = "body_force", b = [0.0, 0.0, -1e-3]
//! on = { group = "xmax" }
//! t = [0.0, 0.0, 0.01]
//! [obstacle]                   # K; omit for no contact
//! type = "rigid_punch"
//! F = 0.3
//! zone = { all = [ { group = "zmin" }, { disc = { center = [0.0, 0.0], radius = 0.5 } } ] }
//! gap = { type = "paraboloid", R = 5.0 }
//! [solver]                     # optional
//! type = "uzawa"
//! ```

use crate::displacements::AdmissibleDisplacements;
use crate::dofs::Dirichlet;
use crate::elasticity::Elasticity;
use crate::error::SceneError;
use crate::loads::Load;
use crate::mesh::MeshSource;
use crate::p1p0::P1P0Lagrangian;
use crate::solver::Solver;
use crate::stresses::AdmissibleStresses;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A problem as written in a scene file.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// A title for reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Where the mesh comes from.
    pub mesh: Box<dyn MeshSource>,
    /// Elasticity.
    pub material: Elasticity,
    /// P; absent for an elastic body (which then pays nothing for plasticity).
    #[serde(default, rename = "yield")]
    pub yield_surface: Option<Box<dyn AdmissibleStresses>>,
    /// Dirichlet conditions.
    #[serde(default)]
    pub dirichlet: Vec<Dirichlet>,
    /// Tractions and body forces (`[[load]]`).
    #[serde(default)]
    pub load: Vec<Load>,
    /// K; absent for no contact.
    #[serde(default)]
    pub obstacle: Option<Box<dyn AdmissibleDisplacements>>,
    /// The solver; the command line supplies a default when absent.
    #[serde(default)]
    pub solver: Option<Box<dyn Solver>>,
    /// The folder relative file names are resolved against.
    #[serde(skip)]
    pub base_dir: PathBuf,
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
        let mut scene = Self::from_toml(&text, path)?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(scene)
    }

    /// Parses and validates scene text; `origin` names it in error messages.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: origin.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Checks every parameter; errors name the field path and value.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.mesh.validate("mesh")?;
        self.material.validate("material")?;
        if let Some(p) = &self.yield_surface {
            p.validate("yield")?;
        }
        for (i, d) in self.dirichlet.iter().enumerate() {
            d.on.validate(&format!("dirichlet[{i}].on"))?;
        }
        for (i, l) in self.load.iter().enumerate() {
            l.validate(&format!("load[{i}]"))?;
        }
        if let Some(k) = &self.obstacle {
            k.validate("obstacle")?;
        }
        if let Some(s) = &self.solver {
            s.validate("solver")?;
        }
        Ok(())
    }

    /// Builds the mesh and assembles L; returns it with the scene's solver (if any).
    pub fn into_problem(self) -> Result<(P1P0Lagrangian, Option<Box<dyn Solver>>), SceneError> {
        let mesh = self.mesh.build(&self.base_dir)?;
        let l = P1P0Lagrangian::new(mesh, &self.dirichlet, self.material, self.yield_surface, self.obstacle)?
            .with_loads(&self.load)?;
        Ok((l, self.solver))
    }
}
