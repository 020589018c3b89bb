//! The structured box mesher: a box split into `cells` hexahedra, each cut into 6 tetrahedra
//! along its main diagonal (Kuhn's subdivision, conforming), optionally graded toward a point;
//! or with the subdivision mirrored about that point (`subdivision = "mirrored"`), so that a grid
//! symmetric about it gives a mesh with its reflection symmetries.
//! Its facet groups are the six faces `xmin`, `xmax`, `ymin`, `ymax`, `zmin`, `zmax`.

use crate::error::{MeshError, ParameterError, check, join};
use crate::mesh::{MeshSource, TetMesh, signed_volume};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The most tetrahedra a box mesh may have: 1e8, far beyond what one machine solves (the
/// default scene, 98 304 elements, peaks at 246 MB with newton: 2.5 KB per element, so 1e8
/// would need 250 GB), so that a mistyped cell count is refused instead of exhausting the memory.
pub const MAX_ELEMENTS: f64 = 1e8;

/// `type = "box"`: the box `min ≤ x ≤ max` with `cells` hexahedra per axis.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxMesh {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
    /// Number of cells along x, y, z.
    pub cells: [usize; 3],
    /// Optional geometric grading toward a point.
    #[serde(default)]
    pub grading: Option<Grading>,
    /// Coordinates, per axis, that must be grid lines: the nearest node is moved there (for
    /// boundaries of regions such as Γ₁, so that they are resolved alike on every mesh).
    #[serde(default)]
    pub align: [Vec<f64>; 3],
    /// How each hexahedron is cut into tetrahedra (default `"kuhn"`).
    #[serde(default)]
    pub subdivision: Subdivision,
    /// The coarsest level of a mesh family (theory §7.3): with `base`, `cells` must be `k·base`
    /// (one k on every axis) and the grid is the base grid — graded and aligned — with each of
    /// its cells cut into k equal ones. Every level of the family then has the same grading and
    /// alignment (the same piecewise affine map of a uniform grid), and levels k and 2k are
    /// nested. Without it, `cells` sets the grading and the alignment moves nodes anew at every
    /// count, so two counts are different families.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<[usize; 3]>,
}

/// `subdivision = "kuhn" | "mirrored"`: the 6 tetrahedra of each hexahedron.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Subdivision {
    /// Kuhn's subdivision along the main diagonal of every cell (the same in every cell). The
    /// mesh is not invariant under reflections: a symmetric problem has a slightly asymmetric
    /// discrete solution (a punch pressed at its centre carries a small moment).
    #[default]
    Kuhn,
    /// Kuhn's subdivision reflected, along each axis, in the cells below the grading point (the
    /// box's centre without grading): conforming, and invariant under the reflections about
    /// that point that map the grid onto itself, so symmetric problems have symmetric discrete
    /// solutions.
    Mirrored,
}

/// Geometric grading: along each axis the cells grow geometrically away from the coordinate of
/// `toward`, the largest being `ratio` times the smallest; with `core`, the cells within `core`
/// of `toward` are uniform and the growth starts beyond them (theory §7.3).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grading {
    /// The point the cells shrink toward (clamped into the box).
    pub toward: [f64; 3],
    /// Largest over smallest cell size along each side of `toward` (≥ 1).
    pub ratio: f64,
    /// Half-width of a uniform core around `toward` (theory §7.3): along each side, the fewest
    /// equal cells of size h that reach `core`, then cells h·q, h·q², …, h·q^m = ratio·h to the
    /// box's end. Absent: the plain geometric grading (which is the core of one cell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core: Option<f64>,
}

impl BoxMesh {
    /// An ungraded box.
    pub fn new(min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> Self {
        Self { min, max, cells, grading: None, align: Default::default(), subdivision: Subdivision::Kuhn, base: None }
    }

    /// The same box as level `k` of the family whose coarsest level has `base` cells (the
    /// `base` field): `cells = k·base`.
    pub fn family(mut self, base: [usize; 3], k: usize) -> Self {
        self.base = Some(base);
        self.cells = base.map(|n| k * n);
        self
    }

    /// The refinement factor k of a family level (`cells = k·base`); `None` without `base` or
    /// when `cells` is not one multiple of `base` on every axis.
    pub fn family_level(&self) -> Option<usize> {
        let base = self.base?;
        let k = self.cells[0] / base[0].max(1);
        (k >= 1 && (0..3).all(|a| base[a] >= 1 && self.cells[a] == k * base[a])).then_some(k)
    }

    /// The same box graded toward `toward` with size ratio `ratio`.
    pub fn graded(mut self, toward: [f64; 3], ratio: f64) -> Self {
        self.grading = Some(Grading { toward, ratio, core: None });
        self
    }

    /// The same box with a uniform core of half-width `core` in its grading (theory §7.3); a
    /// box without grading is returned unchanged.
    pub fn cored(mut self, core: f64) -> Self {
        if let Some(g) = &mut self.grading {
            g.core = Some(core);
        }
        self
    }

    /// The same box cut by `subdivision`.
    pub fn subdivided(mut self, subdivision: Subdivision) -> Self {
        self.subdivision = subdivision;
        self
    }

    /// The same box with grid lines at `coords` along axis `axis`.
    pub fn aligned(mut self, axis: usize, coords: &[f64]) -> Self {
        self.align[axis] = coords.to_vec();
        self
    }

    /// The node coordinates along axis `k`: of the base grid cut k times with `base` (see
    /// [`BoxMesh::base`]), else graded and aligned at `cells`.
    pub fn axis_nodes(&self, k: usize) -> Vec<f64> {
        if let (Some(base), Some(m)) = (self.base, self.family_level()) {
            let coarse = Self { cells: base, base: None, ..self.clone() }.axis_nodes(k);
            let mut xs: Vec<f64> = coarse
                .windows(2)
                .flat_map(|w| (0..m).map(move |i| w[0] + (w[1] - w[0]) * i as f64 / m as f64))
                .collect();
            xs.push(self.max[k]);
            return xs;
        }
        let (a, b, n) = (self.min[k], self.max[k], self.cells[k]);
        let mut xs = match &self.grading {
            None => (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect(),
            Some(g) => graded_axis(a, b, n, g.toward[k].clamp(a, b), g.ratio, g.core.unwrap_or(0.0)),
        };
        // the nearest interior node moves onto each aligned coordinate; it stays between its
        // neighbours because it was the nearest one
        for &c in &self.align[k] {
            if c > a && c < b {
                let i = (1..n).min_by(|&i, &j| (xs[i] - c).abs().total_cmp(&(xs[j] - c).abs())).unwrap_or(0);
                if i > 0 {
                    xs[i] = c;
                }
            }
        }
        xs
    }

    /// The grading's `core` (at `path`): finite, ≥ 0, and on every side of `toward` of the grid
    /// the grading is applied to (the base grid of a family) leaving at least one graded cell.
    fn validate_core(&self, path: &str, g: &Grading, core: f64) -> Result<(), ParameterError> {
        check::finite(path, "core", core)?;
        if core < 0.0 {
            return Err(ParameterError::new(join(path, "core"), core, "must be ≥ 0"));
        }
        let cells = self.base.unwrap_or(self.cells);
        for (k, &n) in cells.iter().enumerate() {
            let (a, b) = (self.min[k], self.max[k]);
            let c = g.toward[k].clamp(a, b);
            for (len, m) in [c - a, b - c].into_iter().zip(side_cells(a, b, n, c)) {
                if m > 0 && core > 0.0 && core_cells(len, m, g.ratio, core) >= m {
                    return Err(ParameterError::new(
                        join(path, "core"),
                        core,
                        format!(
                            "leaves no graded cell along axis {k} (a side of length {len} with {m} cells{}): \
                             use a smaller core or more cells",
                            if self.base.is_some() { " in the family's base" } else { "" }
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Builds the mesh (infallible for validated parameters).
    pub fn mesh(&self) -> Result<TetMesh, MeshError> {
        let xs: [Vec<f64>; 3] = std::array::from_fn(|k| self.axis_nodes(k));
        let [nx, ny, nz] = self.cells;
        let id = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    nodes.push([xs[0][i], xs[1][j], xs[2][k]]);
                }
            }
        }
        // Kuhn: one tetrahedron per permutation of the axes, along the path 000 → 111.
        const PERMS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        let mut tets = Vec::with_capacity(6 * nx * ny * nz);
        // the mirror point: cells below it along an axis run Kuhn's path downward along that axis
        let centre: [f64; 3] = match &self.grading {
            Some(g) => std::array::from_fn(|a| g.toward[a].clamp(self.min[a], self.max[a])),
            None => std::array::from_fn(|a| 0.5 * (self.min[a] + self.max[a])),
        };
        let flipped = |axis: usize, cell: usize| {
            self.subdivision == Subdivision::Mirrored && 0.5 * (xs[axis][cell] + xs[axis][cell + 1]) < centre[axis]
        };
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let flip = [flipped(0, i), flipped(1, j), flipped(2, k)];
                    for p in PERMS {
                        let mut c = [i, j, k];
                        for a in 0..3 {
                            c[a] += flip[a] as usize;
                        }
                        let mut t = [id(c[0], c[1], c[2]), 0, 0, 0];
                        for (s, axis) in p.iter().enumerate() {
                            if flip[*axis] {
                                c[*axis] -= 1;
                            } else {
                                c[*axis] += 1;
                            }
                            t[s + 1] = id(c[0], c[1], c[2]);
                        }
                        if signed_volume(&nodes, &t) < 0.0 {
                            t.swap(1, 2);
                        }
                        tets.push(t);
                    }
                }
            }
        }
        let mut faces: Vec<(String, Vec<[usize; 3]>)> = Vec::new();
        let grid = |n: usize| [n % (nx + 1), (n / (nx + 1)) % (ny + 1), n / ((nx + 1) * (ny + 1))];
        let probe = TetMesh::new(nodes.clone(), tets.clone(), vec![])?;
        for (axis, name_lo, name_hi) in [(0, "xmin", "xmax"), (1, "ymin", "ymax"), (2, "zmin", "zmax")] {
            let last = self.cells[axis];
            let on = |f: &[usize; 3], v: usize| f.iter().all(|&n| grid(n)[axis] == v);
            faces.push((name_lo.into(), probe.boundary.iter().filter(|f| on(f, 0)).copied().collect()));
            faces.push((name_hi.into(), probe.boundary.iter().filter(|f| on(f, last)).copied().collect()));
        }
        TetMesh::new(nodes, tets, faces)
    }
}

/// The number of cells on each side of `c` in [a, b] with `n` cells: proportional to the sides'
/// lengths, at least one on a side of positive length.
fn side_cells(a: f64, b: f64, n: usize, c: f64) -> [usize; 2] {
    let (l1, l2) = (c - a, b - c);
    let mut n1 = ((n as f64) * l1 / (l1 + l2)).round() as usize;
    if l1 > 0.0 && n1 == 0 {
        n1 = 1;
    }
    if l2 > 0.0 && n1 == n {
        n1 = n - 1;
    }
    [n1, n - n1]
}

/// The relative cell sizes of a side of `m` cells whose first `core` cells are uniform: 1 (core
/// times), then q, q², …, q^{m−core} = `ratio` (theory §7.3).
fn side_sizes(m: usize, core: usize, ratio: f64) -> impl Iterator<Item = f64> {
    let q = if m > core { ratio.powf(1.0 / (m - core) as f64) } else { 1.0 };
    (0..m).map(move |k| if k < core { 1.0 } else { q.powi((k + 1 - core) as i32) })
}

/// The fewest uniform cells at the start of a side of length `len` and `m` cells that reach
/// `core` (capped at `len`): `m` when only the whole side does (theory §7.3).
fn core_cells(len: f64, m: usize, ratio: f64, core: f64) -> usize {
    (1..m)
        .find(|&c| {
            let total: f64 = side_sizes(m, c, ratio).sum();
            c as f64 * len / total >= core.min(len)
        })
        .unwrap_or(m)
}

/// Nodes on [a, b] with `n` cells, growing geometrically away from `c` with max/min size `ratio`
/// beyond a uniform core of half-width `core` (0: the core of one cell, the plain grading).
fn graded_axis(a: f64, b: f64, n: usize, c: f64, ratio: f64, core: f64) -> Vec<f64> {
    let [n1, n2] = side_cells(a, b, n, c);
    let side = |len: f64, m: usize| -> Vec<f64> {
        // offsets from c of the m nodes after c
        if m == 0 {
            return vec![];
        }
        // an invalid core (refused by validation) keeps one graded cell
        let uniform = core_cells(len, m, ratio, core).min(m - 1).max(1);
        let sizes: Vec<f64> = side_sizes(m, uniform, ratio).collect();
        let total: f64 = sizes.iter().sum();
        let mut acc = 0.0;
        sizes
            .iter()
            .enumerate()
            .map(|(k, s)| {
                acc += s;
                if k + 1 == m { len } else { len * acc / total }
            })
            .collect()
    };
    let mut xs: Vec<f64> = side(c - a, n1).into_iter().rev().map(|d| c - d).collect();
    xs.push(c);
    xs.extend(side(b - c, n2).into_iter().map(|d| c + d));
    xs[0] = a;
    *xs.last_mut().unwrap() = b;
    xs
}

#[typetag::serde(name = "box")]
impl MeshSource for BoxMesh {
    fn cells(&self) -> Option<[usize; 3]> {
        Some(self.cells)
    }

    fn family_base(&self) -> Option<[usize; 3]> {
        self.base
    }

    fn with_cells(&self, cells: [usize; 3]) -> Option<Box<dyn MeshSource>> {
        Some(Box::new(Self { cells, ..self.clone() }))
    }

    /// Corners within [`check::MAX_MAGNITUDE`] with max > min, cells ≥ 1 and at most
    /// [`MAX_ELEMENTS`] tetrahedra in all, the grading (its ratio in [1, 1e6]), then every
    /// aligned coordinate inside [min, max] and resolvable (the grading first: the aligned grid
    /// lines are placed on the graded axis).
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        check::bounded_all(path, "min", &self.min)?;
        check::bounded_all(path, "max", &self.max)?;
        for k in 0..3 {
            if self.max[k] <= self.min[k] {
                return Err(ParameterError::new(
                    join(path, &format!("max[{k}]")),
                    self.max[k],
                    format!("must exceed min[{k}] = {}", self.min[k]),
                ));
            }
            check::at_least_one(path, &format!("cells[{k}]"), self.cells[k])?;
        }
        let elements = 6.0 * self.cells.iter().map(|&n| n as f64).product::<f64>();
        if elements > MAX_ELEMENTS {
            return Err(ParameterError::new(
                join(path, "cells"),
                format!("{:?}", self.cells),
                format!("makes {elements:e} tetrahedra (6 per cell), more than the {MAX_ELEMENTS:e} a mesh may have"),
            ));
        }
        if let Some(base) = self.base {
            for (a, &n) in base.iter().enumerate() {
                check::at_least_one(path, &format!("base[{a}]"), n)?;
            }
            if self.family_level().is_none() {
                let k = (self.cells[0] / base[0]).max(1);
                return Err(ParameterError::new(
                    join(path, "cells"),
                    format!("{:?}", self.cells),
                    format!(
                        "is not a level of the mesh family with base = {base:?}: a level has k·base cells, one k on \
                         every axis (e.g. {:?} or {:?}), so that every level has the same grading and alignment",
                        base.map(|n| k * n),
                        base.map(|n| (k + 1) * n)
                    ),
                ));
            }
        }
        if let Some(g) = &self.grading {
            let p = join(path, "grading");
            check::bounded_all(&p, "toward", &g.toward)?;
            check::finite(&p, "ratio", g.ratio)?;
            if !(1.0..=1e6).contains(&g.ratio) {
                return Err(ParameterError::new(join(&p, "ratio"), g.ratio, "must lie in [1, 1e6]"));
            }
            if let Some(core) = g.core {
                self.validate_core(&p, g, core)?;
            }
        }
        for (k, coords) in self.align.iter().enumerate() {
            check::finite_all(path, &format!("align[{k}]"), coords)?;
            if let Some(c) = coords.iter().find(|c| !(self.min[k]..=self.max[k]).contains(*c)) {
                return Err(ParameterError::new(
                    join(path, &format!("align[{k}]")),
                    format!("{coords:?}"),
                    format!(
                        "{c} lies outside the box's [{}, {}] along this axis: it cannot become a grid line",
                        self.min[k], self.max[k]
                    ),
                ));
            }
            let xs = self.axis_nodes(k);
            for &c in coords.iter().filter(|c| **c > self.min[k] && **c < self.max[k]) {
                if !xs.contains(&c) {
                    return Err(ParameterError::new(
                        join(path, &format!("align[{k}]")),
                        format!("{coords:?}"),
                        format!(
                            "{c} cannot be a grid line: two aligned coordinates share the nearest node; use more cells"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn build(&self, _base_dir: &Path) -> Result<TetMesh, MeshError> {
        self.mesh()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_add_up_and_faces_are_tagged() {
        let m = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [3, 4, 2]).mesh().unwrap();
        assert_eq!(m.n_elements(), 6 * 24);
        let vol: f64 = (0..m.n_elements()).map(|e| m.volume(e)).sum();
        assert!((vol - 4.0).abs() < 1e-12);
        // each face of the box: 2 triangles per cell face
        assert_eq!(m.groups["zmin"].len(), 2 * 12);
        assert_eq!(m.groups["xmax"].len(), 2 * 8);
        let tagged: usize = m.groups.values().map(|g| g.len()).sum();
        assert_eq!(tagged, m.boundary.len(), "every boundary facet lies on one face");
        for &f in &m.groups["zmin"] {
            assert!(m.facet_centroid(f)[2].abs() < 1e-15);
        }
    }

    #[test]
    fn aligned_coordinates_become_grid_lines() {
        let b = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [32, 32, 16])
            .graded([0.0; 3], 4.0)
            .aligned(0, &[-0.75, 0.75])
            .aligned(1, &[-0.75, 0.75]);
        b.validate("mesh").unwrap();
        for k in 0..2 {
            let x = b.axis_nodes(k);
            assert!(x.contains(&-0.75) && x.contains(&0.75) && x.windows(2).all(|w| w[1] > w[0]));
        }
        // without alignment the graded grid misses ±0.75
        assert!(!BoxMesh::new([-1.0; 3], [1.0; 3], [32, 32, 16]).graded([0.0; 3], 4.0).axis_nodes(0).contains(&0.75));
        // two coordinates competing for one node are an error naming the field
        let e = BoxMesh::new([0.0; 3], [1.0; 3], [2, 2, 2]).aligned(2, &[0.4, 0.6]).validate("mesh").unwrap_err();
        assert_eq!(e.field, "mesh.align[2]");
    }

    #[test]
    fn levels_of_a_family_are_nested_and_keep_grading_and_alignment() {
        let base = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 4])
            .graded([0.0; 3], 4.0)
            .aligned(0, &[-0.75, 0.75])
            .aligned(1, &[-0.75, 0.75]);
        let level = |k| base.clone().family([8, 8, 4], k);
        let coarse = base.axis_nodes(0);
        assert_eq!(level(1).axis_nodes(0), coarse, "level 1 is the base grid");
        for k in [2, 3, 4] {
            let b = level(k);
            b.validate("mesh").unwrap();
            let x = b.axis_nodes(0);
            assert_eq!(x.len(), 8 * k + 1);
            // every base node is a node of level k, at index k·i, and the cells between are equal
            for (i, &c) in coarse.iter().enumerate() {
                assert_eq!(x[k * i], c);
            }
            for w in x.chunks(k).zip(coarse.windows(2)) {
                let h = (w.1[1] - w.1[0]) / k as f64;
                assert!(w.0.windows(2).all(|p| ((p[1] - p[0]) - h).abs() < 1e-15));
            }
            assert!(x.contains(&0.75) && x.contains(&-0.75));
            let m = b.mesh().unwrap();
            let vol: f64 = (0..m.n_elements()).map(|e| m.volume(e)).sum();
            // round-off of the sum of 6·256·k³ volumes (measured 1.0e-12 at k = 2)
            assert!((vol - 4.0).abs() < 1e-10, "{vol}");
        }
        // levels 2 and 4 are nested: every node of level 2 is one of level 4
        let (x2, x4) = (level(2).axis_nodes(1), level(4).axis_nodes(1));
        assert!(x2.iter().all(|c| x4.contains(c)));
        // a count that is not k·base is refused, naming the field, with levels that are
        let e = BoxMesh { cells: [11, 11, 5], ..level(1) }.validate("mesh").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("mesh.cells", "[11, 11, 5]"));
        assert!(e.requirement.contains("[8, 8, 4]") && e.requirement.contains("[16, 16, 8]"), "{}", e.requirement);
        let e = BoxMesh { cells: [16, 16, 4], ..level(1) }.validate("mesh").unwrap_err();
        assert_eq!(e.field, "mesh.cells");
    }

    #[test]
    fn grading_refines_toward_the_point() {
        let b = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [20, 20, 10]).graded([0.0, 0.0, 0.0], 4.0);
        let x = b.axis_nodes(0);
        assert_eq!(x.len(), 21);
        assert!(x.windows(2).all(|w| w[1] > w[0]));
        assert!((x[10]).abs() < 1e-15, "the focus is a node");
        let small = x[11] - x[10];
        let large = x[20] - x[19];
        assert!((large / small - 4.0).abs() < 1e-9);
        let z = b.axis_nodes(2);
        assert!((z[0]).abs() < 1e-15 && (z[10] - 1.0).abs() < 1e-15);
        assert!(((z[10] - z[9]) / (z[1] - z[0]) - 4.0).abs() < 1e-9);
        let m = b.mesh().unwrap();
        let vol: f64 = (0..m.n_elements()).map(|e| m.volume(e)).sum();
        assert!((vol - 4.0).abs() < 1e-12);
    }

    #[test]
    fn the_mirrored_subdivision_is_conforming_and_symmetric() {
        let b = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [6, 6, 3]).graded([0.0; 3], 3.0);
        let kuhn = b.mesh().unwrap();
        let mirrored = b.clone().subdivided(Subdivision::Mirrored).mesh().unwrap();
        // conforming: as many boundary facets as Kuhn's (a mismatched interior face would add
        // two), the same volume
        assert_eq!(mirrored.boundary.len(), kuhn.boundary.len());
        let volume = |m: &TetMesh| m.tets.iter().map(|t| signed_volume(&m.nodes, t)).sum::<f64>();
        assert!((volume(&mirrored) - 4.0).abs() < 1e-12 && (volume(&kuhn) - 4.0).abs() < 1e-12);
        // symmetric: each reflection x₁ → −x₁, x₂ → −x₂ maps the set of tetrahedra onto itself
        let key = |m: &TetMesh, t: &[usize; 4], s: [f64; 2]| {
            let mut v: Vec<[i64; 3]> = t
                .iter()
                .map(|&n| {
                    let x = m.nodes[n];
                    [
                        (s[0] * x[0] * 1e9).round() as i64,
                        (s[1] * x[1] * 1e9).round() as i64,
                        (x[2] * 1e9).round() as i64,
                    ]
                })
                .collect();
            v.sort_unstable();
            v
        };
        for s in [[-1.0, 1.0], [1.0, -1.0]] {
            let mut a: Vec<_> = mirrored.tets.iter().map(|t| key(&mirrored, t, [1.0, 1.0])).collect();
            let mut r: Vec<_> = mirrored.tets.iter().map(|t| key(&mirrored, t, s)).collect();
            a.sort_unstable();
            r.sort_unstable();
            assert!(a == r, "mirrored mesh not symmetric under {s:?}");
            let mut a: Vec<_> = kuhn.tets.iter().map(|t| key(&kuhn, t, [1.0, 1.0])).collect();
            let mut r: Vec<_> = kuhn.tets.iter().map(|t| key(&kuhn, t, s)).collect();
            a.sort_unstable();
            r.sort_unstable();
            assert!(a != r, "Kuhn's mesh is not symmetric (the reason for the mirrored one)");
        }
    }

    #[test]
    fn a_core_is_uniform_then_grows_geometrically_to_the_ratio() {
        // one side [0, 6] of 10 cells, ratio 20, core 0.5, computed from the definition: with c
        // core cells of size h = 6/(c + Σ_{k=1}^{10−c} q^k), q = 20^{1/(10−c)}, the fewest c
        // with c·h ≥ 0.5
        let (len, m, ratio, core) = (6.0_f64, 10usize, 20.0_f64, 0.5);
        let h = |c: usize| {
            let q = ratio.powf(1.0 / (m - c) as f64);
            len / (c as f64 + (1..=m - c).map(|k| q.powi(k as i32)).sum::<f64>())
        };
        let c = (1..m).find(|&c| c as f64 * h(c) >= core).unwrap();
        assert!(c >= 2 && (c - 1) as f64 * h(c - 1) < core, "the case has a core of several cells");
        let b = BoxMesh::new([0.0, -6.0, 0.0], [6.0, 6.0, 6.0], [10, 20, 10]).graded([0.0; 3], ratio).cored(core);
        b.validate("mesh").unwrap();
        for axis in [0, 2] {
            let x = b.axis_nodes(axis);
            let q = ratio.powf(1.0 / (m - c) as f64);
            let mut expected = 0.0;
            for (i, &xi) in x.iter().enumerate().take(m) {
                assert!((xi - expected).abs() < 1e-13, "node {i}: {xi} against {expected}");
                expected += if i < c { h(c) } else { h(c) * q.powi((i + 1 - c) as i32) };
            }
            assert!((x[m] - len).abs() < 1e-15 && (expected - len).abs() < 1e-12);
            assert!(x[c] >= core, "the core reaches {core}: {:?}", &x[..=c]);
            let size = |i: usize| x[i + 1] - x[i];
            assert!(((size(m - 1) / size(0)) - ratio).abs() < 1e-9);
        }
        // a side on either side of the point: the same on both (the y axis is [−6, 6], 20 cells)
        let y = b.axis_nodes(1);
        let x = b.axis_nodes(0);
        assert!((0..=10).all(|i| (y[10 + i] - x[i]).abs() < 1e-13 && (y[10 - i] + x[i]).abs() < 1e-13));
    }

    #[test]
    fn without_a_core_the_grading_is_unchanged() {
        // the plain grading is the core of one cell: a core smaller than the first cell gives
        // the same grid bit for bit, the grading of `grading_refines_toward_the_point`
        let plain = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [20, 20, 10]).graded([0.0; 3], 4.0);
        let first = plain.axis_nodes(0)[11];
        for core in [0.0, 0.5 * first] {
            let cored = plain.clone().cored(core);
            assert!((0..3).all(|k| cored.axis_nodes(k) == plain.axis_nodes(k)), "core {core}");
        }
        // and the sizes of the plain grading are q^k, q = 4^{1/9}, from its definition
        let x = plain.axis_nodes(0);
        let q = 4.0_f64.powf(1.0 / 9.0);
        let h = 1.0 / (0..10).map(|k| q.powi(k)).sum::<f64>();
        assert!((0..10).all(|k| ((x[11 + k] - x[10 + k]) - h * q.powi(k as i32)).abs() < 1e-15));
    }

    #[test]
    fn a_cored_family_is_nested_and_keeps_its_core_uniform() {
        let base = BoxMesh::new([0.0; 3], [6.0; 3], [5, 5, 5]).graded([0.0; 3], 30.0).cored(0.3).aligned(2, &[1.5]);
        base.validate("mesh").unwrap();
        let coarse = base.axis_nodes(0);
        let core = (1..5).find(|&i| coarse[i] >= 0.3).unwrap();
        assert!(core >= 2, "{coarse:?}");
        let level = |k| base.clone().family([5, 5, 5], k);
        for k in [2, 4] {
            let b = level(k);
            b.validate("mesh").unwrap();
            let x = b.axis_nodes(0);
            // the core's k·core cells are equal
            let h = coarse[1] / k as f64;
            assert!(x[..=k * core].windows(2).all(|w| ((w[1] - w[0]) - h).abs() < 1e-14), "{x:?}");
            assert!(b.axis_nodes(2).contains(&1.5), "the alignment holds on every level");
        }
        // levels 2 and 4 are nested on every axis
        assert!((0..3).all(|a| level(2).axis_nodes(a).iter().all(|c| level(4).axis_nodes(a).contains(c))));
    }

    #[test]
    fn a_bad_core_is_refused_naming_the_field() {
        let b = BoxMesh::new([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], [8, 8, 4]).graded([0.0; 3], 4.0);
        for core in [-0.1, f64::NAN, f64::INFINITY] {
            let e = b.clone().cored(core).validate("mesh").unwrap_err();
            assert_eq!(e.field, "mesh.grading.core", "{core}");
        }
        // the core reaching the box's end along z (4 cells on [0, 1]), or filling all cells
        let e = b.clone().cored(1.0).validate("mesh").unwrap_err();
        assert_eq!((e.field.as_str(), e.value.as_str()), ("mesh.grading.core", "1"));
        assert!(e.requirement.contains("axis 0"), "{}", e.requirement);
        assert!(b.clone().cored(0.9).validate("mesh").is_err());
        // a family is checked on its base grid: 2 cells per side at level 1
        let f = BoxMesh::new([-1.0; 3], [1.0; 3], [2, 2, 2]).graded([0.0; 3], 4.0).cored(0.5).family([2, 2, 2], 4);
        let e = f.validate("mesh").unwrap_err();
        assert!(e.requirement.contains("base"), "{}", e.requirement);
        b.cored(0.3).validate("mesh").unwrap();
    }
}
