//! `type = "gmsh"`: a tetrahedral mesh T_h (theory §3) read from a Gmsh MSH 4.1 file, ASCII or
//! binary (cargo feature `gmsh`, on by default).
//!
//! ```toml
//! [mesh]
//! type = "gmsh"
//! file = "punch.msh"   # relative to the scene file's folder
//! scale = 1.0          # optional: multiplies every coordinate (e.g. 1e-3 for a mesh in mm)
//! ```
//!
//! What is read:
//!
//! * **Tetrahedra**: every 4-node tetrahedron (element type 4) or every 10-node tetrahedron
//!   (element type 11, order 2) of the file is an element of the body, whatever volume it
//!   belongs to. A file mixing the two orders is an error. Other volume elements (hexahedra,
//!   prisms, pyramids) and elements of order 3 and up (20-node tetrahedra, 10-node triangles, …)
//!   are errors: mesh with order 1 or 2 (`Mesh.ElementOrder`).
//! * **Second order**: the four corner nodes of a 10-node tetrahedron are its vertices, its six
//!   other nodes its edge nodes, which become the mesh's [`SecondOrder`] edge nodes (Gmsh's
//!   local order, edges (0,1), (1,2), (2,0), (3,0), (3,2), (3,1), is mapped to the order of
//!   [`TET_EDGES`]). The elements are straight-sided: every edge node is moved to the midpoint of
//!   its edge ([`TetMesh::with_edge_nodes`]). A file whose edge nodes lie off their midpoints by
//!   more than 10⁻⁶ of the edge's length (curved elements, e.g. on a cylinder) is read all the
//!   same, with a warning in [`GmshImport::warnings`]: the curved edges are straightened.
//! * **Facet groups**: the 3-node triangles (element type 2) of each *physical surface* form a
//!   named facet group — in a second-order mesh the 6-node triangles (element type 9) too, whose
//!   edge nodes must be those of the tetrahedra; a first-order mesh refuses 6-node triangles.
//!   The group's name comes from `$PhysicalNames`, or is `physical_<tag>` when the group is
//!   unnamed. A scene selects them with `{ group = "name" }` (see [`Region`]); every such
//!   triangle must be a boundary face of the tetrahedra. Physical points, curves and volumes are
//!   ignored (they are listed in [`GmshImport::ignored_groups`]); triangles outside any physical
//!   surface are ignored.
//! * **Nodes**: Gmsh's node tags become dense indices: the vertices in increasing tag order,
//!   then (second order) the edge nodes in increasing tag order; nodes on no tetrahedron are
//!   dropped. The tetrahedra are ordered by their first vertex (for memory locality), ties by
//!   tag. [`GmshImport::node_tags`] and [`GmshImport::element_tags`] map back.
//!
//! The node rules of the scene apply to groups as to any region: a node belongs to every group
//! one of whose facets it lies on, so the nodes on the rim between two physical surfaces belong
//! to both. A Dirichlet condition fixes the closure of its facets (theory §3: nodes on the closure
//! of Γ₂ are clamped), so a node shared by `clamped` and `free` is clamped; a contact zone
//! `{ group = "contact" }` holds its rim nodes shared with `free` (and drops with a warning any
//! node whose u₃ is clamped).
//!
//! `mshio` parses the file; it ignores `$PhysicalNames`, which is text even in binary files
//! (the format marks its fields "ASCII"), so that section is read here from the raw bytes. When
//! the node tags form one dense range mshio drops them; they are then read here from the raw
//! `$Nodes` section, so a dense but permuted numbering is still mapped correctly.
//!
//! [`Region`]: crate::mesh::region::Region
//! [`SecondOrder`]: crate::mesh::SecondOrder
//! [`TET_EDGES`]: crate::mesh::TET_EDGES

use crate::error::{MeshError, ParameterError, check, join};
use crate::mesh::{MeshSource, TRI_EDGES, TetMesh};
use mshio::{ElementBlock, ElementType, Elements, Entities, MshData, MshHeader, NodeBlock, Nodes};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// `type = "gmsh"`: a Gmsh MSH 4.1 file (ASCII or binary).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GmshMesh {
    /// The `.msh` file; a relative path is resolved against the scene file's folder.
    pub file: PathBuf,
    /// Factor applied to every coordinate (default 1).
    #[serde(default = "unit_scale")]
    pub scale: f64,
}

fn unit_scale() -> f64 {
    1.0
}

impl GmshMesh {
    /// The file `file` at scale 1.
    pub fn new(file: impl Into<PathBuf>) -> Self {
        Self { file: file.into(), scale: 1.0 }
    }

    /// The file's path: `file` if absolute, else `base_dir/file`.
    pub fn path(&self, base_dir: &Path) -> PathBuf {
        if self.file.is_absolute() { self.file.clone() } else { base_dir.join(&self.file) }
    }

    /// Reads the file with everything the import knows (tags, groups).
    pub fn read(&self, base_dir: &Path) -> Result<GmshImport, MeshError> {
        read_msh(&self.path(base_dir), self.scale)
    }
}

#[typetag::serde(name = "gmsh")]
impl MeshSource for GmshMesh {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        if self.file.as_os_str().is_empty() {
            return Err(ParameterError::new(join(path, "file"), "\"\"", "must name a Gmsh .msh file"));
        }
        check::positive(path, "scale", self.scale)?;
        Ok(())
    }

    fn build(&self, base_dir: &Path) -> Result<TetMesh, MeshError> {
        Ok(self.read(base_dir)?.mesh)
    }
}

/// A physical group of the file: its dimension (0 points, 1 curves, 2 surfaces, 3 volumes),
/// tag, name (`physical_<tag>` when unnamed) and number of elements in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhysicalGroup {
    /// Dimension of the group's entities.
    pub dim: i32,
    /// The physical tag.
    pub tag: i32,
    /// From `$PhysicalNames`, or `physical_<tag>`.
    pub name: String,
    /// Number of elements of the file in the group's entities (for surfaces: the triangles).
    pub elements: usize,
}

/// The result of reading an MSH file: the mesh and the map back to the file's numbering.
#[derive(Clone, Debug)]
pub struct GmshImport {
    /// The validated mesh; its facet groups are the physical surfaces.
    pub mesh: TetMesh,
    /// Gmsh node tag of each mesh node: the vertices' in increasing order, then (second order)
    /// the edge nodes' in increasing order.
    pub node_tags: Vec<u64>,
    /// Gmsh element tag of each tetrahedron.
    pub element_tags: Vec<u64>,
    /// The physical surfaces, which became the mesh's facet groups.
    pub surface_groups: Vec<PhysicalGroup>,
    /// Physical points, curves and volumes: not used.
    pub ignored_groups: Vec<PhysicalGroup>,
    /// Nodes of the file that lie on no tetrahedron (dropped).
    pub unused_nodes: usize,
    /// What the import changed and the user should know, in words: curved second-order
    /// elements straightened (their edge nodes moved to the midpoints, with the largest move
    /// relative to the edge's length). Empty for a file read as it is.
    pub warnings: Vec<String>,
}

/// Gmsh's local node of a 10-node tetrahedron (element type 11) on each edge of
/// [`TET_EDGES`](crate::mesh::TET_EDGES) (VTK's order): Gmsh puts nodes 4…9 on the edges
/// (0,1), (1,2), (2,0), (3,0), (3,2), (3,1), so the last two are swapped. (From the reference
/// coordinates of `gmsh.model.mesh.getElementProperties(11)`, gmsh 4.15.2; the unit test
/// `gmsh_tet10_edge_nodes_follow_the_reference_element` checks the map against them.)
const GMSH_TET10_EDGE_NODES: [usize; 6] = [4, 5, 6, 7, 9, 8];

/// Gmsh's local node of a 6-node triangle (element type 9) on each edge of [`TRI_EDGES`]: nodes
/// 3, 4, 5 on (0,1), (1,2), (2,0), the same order.
const GMSH_TRI6_EDGE_NODES: [usize; 3] = [3, 4, 5];

/// Edge nodes farther than this from their edge's midpoint, relative to the edge's length, make
/// the import warn that curved elements were straightened.
const CURVED_EDGE_TOLERANCE: f64 = 1e-6;

/// Reads a Gmsh MSH 4.1 file (ASCII or binary), multiplying coordinates by `scale`. Errors are
/// [`MeshError::File`] naming the file and what is wrong where (element and node tags of the
/// file).
pub fn read_msh(path: &Path, scale: f64) -> Result<GmshImport, MeshError> {
    let bytes = std::fs::read(path).map_err(|e| MeshError::File {
        path: path.to_path_buf(),
        message: format!("cannot read the Gmsh mesh file: {e}"),
    })?;
    parse_msh(&bytes, scale, path)
}

/// Reads MSH 4.1 content; `origin` names it in errors.
pub fn parse_msh(bytes: &[u8], scale: f64, origin: &Path) -> Result<GmshImport, MeshError> {
    import(bytes, scale).map_err(|message| MeshError::File { path: origin.to_path_buf(), message })
}

/// Hint appended to "no tetrahedra" errors.
const SAVE_HINT: &str = "when a model has physical groups Gmsh saves only their elements: put the volume in a \
                         physical group (e.g. \"body\") or set Mesh.SaveAll = 1";

/// The import in stages: the file's sections, its physical groups, its nodes, its elements by
/// dimension and order, the dense numbering of the tetrahedra's nodes, the tetrahedra, the
/// physical surfaces as facet groups, the mesh (checked by [`TetMesh::new`]), and at order 2
/// its edge nodes.
fn import(bytes: &[u8], scale: f64) -> Result<GmshImport, String> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!("scale = {scale}: must be a finite number > 0"));
    }
    let sections = Sections::read(bytes)?;
    let groups = PhysicalGroups::read(sections.entities, sections.names)?;
    let nodes = FileNodes::read(bytes, &sections.header, sections.binary, &sections.nodes, scale)?;
    let elements = FileElements::sort(&sections.elements, &groups)?;
    let second_order = elements.second_order();
    let numbering = Numbering::of_tetrahedra(&nodes, &elements.tets, second_order)?;
    let tets = Tetrahedra::numbered(&elements.tets, &nodes, &numbering, second_order);
    let surfaces = SurfaceFacets::read(&groups, &elements.triangles, &nodes, &numbering)?;
    let ignored_groups = groups.ignored(&elements.group_elements);
    let node_tags: Vec<u64> = numbering.order.iter().map(|&i| nodes.tags[i]).collect();
    let mesh = TetMesh::new(numbering.coords(&nodes), tets.vertices, surfaces.named)
        .map_err(|e| mesh_error(e, &tets.element_tags, &node_tags, &surfaces.facet_tags))?;
    let (mesh, warnings) = if second_order {
        let index = |n: &u64| numbering.index(&nodes, n);
        with_edge_nodes(mesh, tets.edges, &tets.element_tags, &node_tags, &surfaces.triangle_edges, &index)?
    } else {
        (mesh, Vec::new())
    };
    Ok(GmshImport {
        mesh,
        node_tags,
        element_tags: tets.element_tags,
        surface_groups: surfaces.groups,
        ignored_groups,
        unused_nodes: nodes.tags.len() - numbering.order.len(),
        warnings,
    })
}

/// The sections of an MSH file the import reads: the format, `$PhysicalNames` (read here) and
/// mshio's `$Entities`, `$Nodes` and `$Elements`.
struct Sections {
    /// The file is binary (else ASCII).
    binary: bool,
    /// The `$MeshFormat` header, as mshio read it.
    header: MshHeader,
    /// `$PhysicalNames`: (dim, physical tag) → name.
    names: BTreeMap<(i32, i32), String>,
    /// `$Entities`, if the file has it.
    entities: Option<Entities<i32, f64>>,
    /// `$Nodes`.
    nodes: Nodes<u64, i32, f64>,
    /// `$Elements`.
    elements: Elements<u64, i32>,
}

impl Sections {
    /// Checks the format, reads `$PhysicalNames` and parses the rest with mshio; `$Nodes` and
    /// `$Elements` must be there.
    fn read(bytes: &[u8]) -> Result<Self, String> {
        let binary = check_format(bytes)?;
        let names = physical_names(bytes)?;
        let msh = mshio::parse_msh_bytes(bytes).map_err(|e| parse_error(bytes, &e, binary))?;
        let missing = |section: &str| {
            let hint = if truncated(bytes) { TRUNCATED } else { "" };
            format!("the file has no {section} section{hint}")
        };
        let MshData { entities, nodes, elements, .. } = msh.data;
        let nodes = nodes.ok_or_else(|| missing("$Nodes"))?;
        let elements = elements.ok_or_else(|| missing("$Elements"))?;
        Ok(Self { binary, header: msh.header, names, entities, nodes, elements })
    }
}

/// The physical groups of the file: the physical tags of each entity, the groups they make and
/// the groups' names.
struct PhysicalGroups {
    /// Physical tags of every entity, by (dim, entity tag).
    of_entity: HashMap<(i32, i32), Vec<i32>>,
    /// Every group, (dim, physical tag), that some entity carries.
    tags: BTreeSet<(i32, i32)>,
    /// `$PhysicalNames`: (dim, physical tag) → name.
    names: BTreeMap<(i32, i32), String>,
}

impl PhysicalGroups {
    /// The groups of `$Entities`; every name of `$PhysicalNames` must name one of them.
    fn read(entities: Option<Entities<i32, f64>>, names: BTreeMap<(i32, i32), String>) -> Result<Self, String> {
        let mut of_entity: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
        if let Some(e) = entities {
            of_entity.extend(e.points.into_iter().map(|p| ((0, p.tag), p.physical_tags)));
            of_entity.extend(e.curves.into_iter().map(|c| ((1, c.tag), c.physical_tags)));
            of_entity.extend(e.surfaces.into_iter().map(|s| ((2, s.tag), s.physical_tags)));
            of_entity.extend(e.volumes.into_iter().map(|v| ((3, v.tag), v.physical_tags)));
        }
        let mut tags: BTreeSet<(i32, i32)> = BTreeSet::new();
        for (&(dim, _), physical) in &of_entity {
            tags.extend(physical.iter().map(|&t| (dim, t)));
        }
        for ((dim, tag), name) in &names {
            if !tags.contains(&(*dim, *tag)) {
                return Err(format!(
                    "$PhysicalNames: the name {name:?} (dimension {dim}, physical tag {tag}) refers to nothing: no {} \
                     of $Entities carries physical tag {tag}",
                    entity_kind(*dim)
                ));
            }
        }
        Ok(Self { of_entity, tags, names })
    }

    /// The physical tags of entity `entity` of dimension `dim` (none for an unknown entity).
    fn of(&self, dim: i32, entity: i32) -> &[i32] {
        self.of_entity.get(&(dim, entity)).map(Vec::as_slice).unwrap_or(&[])
    }

    /// A group's name: from `$PhysicalNames`, or `physical_<tag>`.
    fn name(&self, dim: i32, tag: i32) -> String {
        self.names.get(&(dim, tag)).cloned().unwrap_or_else(|| format!("physical_{tag}"))
    }

    /// The physical surfaces' tags, in increasing order.
    fn surfaces(&self) -> impl Iterator<Item = i32> + '_ {
        self.tags.iter().filter(|(d, _)| *d == 2).map(|&(_, t)| t)
    }

    /// The physical points, curves and volumes, with their numbers of elements.
    fn ignored(&self, elements: &BTreeMap<(i32, i32), usize>) -> Vec<PhysicalGroup> {
        self.tags
            .iter()
            .filter(|(d, _)| *d != 2)
            .map(|&(dim, tag)| PhysicalGroup {
                dim,
                tag,
                name: self.name(dim, tag),
                elements: elements.get(&(dim, tag)).copied().unwrap_or(0),
            })
            .collect()
    }
}

/// An entity of dimension `dim` in words.
fn entity_kind(dim: i32) -> &'static str {
    ["point", "curve", "surface", "volume"].get(dim as usize).unwrap_or(&"entity")
}

/// The nodes of `$Nodes` in file order: coordinates (scaled), tags, and each tag's position.
struct FileNodes {
    /// Coordinates times the scale.
    coords: Vec<[f64; 3]>,
    /// Gmsh node tags.
    tags: Vec<u64>,
    /// Node tag → position in file order.
    position: HashMap<u64, usize>,
}

impl FileNodes {
    /// Reads the node blocks, their tags from the raw section where mshio dropped them; the
    /// coordinates must be finite and the tags distinct.
    fn read(
        bytes: &[u8],
        header: &MshHeader,
        binary: bool,
        section: &Nodes<u64, i32, f64>,
        scale: f64,
    ) -> Result<Self, String> {
        let mut raw_tags = if section.node_blocks.iter().any(|b| b.node_tags.is_none()) {
            Some(raw_node_tags(bytes, header, binary)?)
        } else {
            None
        };
        let mut coords: Vec<[f64; 3]> = Vec::new();
        let mut tags: Vec<u64> = Vec::new();
        for (b, block) in section.node_blocks.iter().enumerate() {
            let block_tags = node_block_tags(b, block, raw_tags.as_mut().and_then(|r| r.get_mut(b)))?;
            for (tag, n) in block_tags.into_iter().zip(&block.nodes) {
                let x = [n.x, n.y, n.z];
                if x.iter().any(|c| !c.is_finite()) {
                    return Err(format!("node {tag} has a non-finite coordinate ({}, {}, {})", x[0], x[1], x[2]));
                }
                coords.push(x.map(|c| c * scale));
                tags.push(tag);
            }
        }
        let mut position: HashMap<u64, usize> = HashMap::with_capacity(tags.len());
        for (i, &tag) in tags.iter().enumerate() {
            if position.insert(tag, i).is_some() {
                return Err(format!("$Nodes: node tag {tag} appears twice"));
            }
        }
        Ok(Self { coords, tags, position })
    }
}

/// The tags of node block `b` in file order: mshio's map inverted, or else the raw section's
/// (`raw`, taken).
fn node_block_tags(b: usize, block: &NodeBlock<u64, i32, f64>, raw: Option<&mut Vec<u64>>) -> Result<Vec<u64>, String> {
    let tags = match &block.node_tags {
        Some(map) => {
            let mut tags = vec![0; block.nodes.len()];
            for (&tag, &i) in map {
                tags[i] = tag;
            }
            if map.len() != block.nodes.len() {
                return Err(format!(
                    "$Nodes: node block {} (entity of dimension {}, tag {}) repeats a node tag",
                    b + 1,
                    block.entity_dim,
                    block.entity_tag
                ));
            }
            tags
        }
        None => raw.map(std::mem::take).unwrap_or_default(),
    };
    if tags.len() != block.nodes.len() {
        return Err(format!("$Nodes: cannot read the node tags of node block {}", b + 1));
    }
    Ok(tags)
}

/// A tetrahedron as the file gives it: element tag, vertex tags, and the tags of its edge nodes
/// in the order of [`TET_EDGES`](crate::mesh::TET_EDGES) (zeros for a 4-node tetrahedron).
type FileTet = (u64, [u64; 4], [u64; 6]);

/// A triangle of a physical surface as the file gives it: element tag, corner node tags, and
/// for a 6-node triangle its edge node tags in the order of [`TRI_EDGES`].
type FileTriangle = (u64, [u64; 3], Option<[u64; 3]>);

/// The elements of `$Elements` by dimension and order: the tetrahedra, the triangles of the
/// physical surfaces, and counts of the rest.
#[derive(Default)]
struct FileElements {
    /// The tetrahedra.
    tets: Vec<FileTet>,
    /// The type of the tetrahedra and where its first block is (a file mixing orders is refused).
    tet_type: Option<(ElementType, String)>,
    /// The triangles of each physical surface, by physical tag.
    triangles: BTreeMap<i32, Vec<FileTriangle>>,
    /// The first block of 6-node triangles in a physical surface: (group, where, count).
    tri6: Option<(i32, String, usize)>,
    /// The number of elements of each group, by (dim, physical tag).
    group_elements: BTreeMap<(i32, i32), usize>,
    /// Elements not used, counted by kind in words.
    skipped: BTreeMap<String, usize>,
}

impl FileElements {
    /// Sorts the element blocks: tetrahedra of one order, triangles of physical surfaces, the
    /// rest skipped; refuses other volume elements, orders above 2, other facets of physical
    /// surfaces, a file without tetrahedra and 6-node facets on 4-node tetrahedra.
    fn sort(section: &Elements<u64, i32>, groups: &PhysicalGroups) -> Result<Self, String> {
        let mut sorted = Self::default();
        for block in &section.element_blocks {
            sorted.add_block(block, groups)?;
        }
        sorted.check_tetrahedra(groups)?;
        Ok(sorted)
    }

    /// True when the tetrahedra are 10-node ones.
    fn second_order(&self) -> bool {
        matches!(self.tet_type, Some((ElementType::Tet10, _)))
    }

    /// Adds one block of elements by its type, or refuses it.
    fn add_block(&mut self, block: &ElementBlock<u64, i32>, groups: &PhysicalGroups) -> Result<(), String> {
        let (dim, entity) = (block.entity_dim, block.entity_tag);
        let in_groups = groups.of(dim, entity);
        for &g in in_groups {
            *self.group_elements.entry((dim, g)).or_default() += block.elements.len();
        }
        let ty = block.element_type;
        let (shape, nodes) = describe(ty);
        let where_ = format!("{} {entity}", entity_kind(dim));
        match ty {
            ElementType::Tet4 | ElementType::Tet10 => self.add_tetrahedra(block, where_),
            ElementType::Tri3 | ElementType::Tri6 => {
                self.add_triangles(block, in_groups, where_);
                Ok(())
            }
            _ if dim >= 2 && beyond_second_order(ty) => Err(format!(
                "elements of order 3 and higher are not supported; mesh with order 1 or 2 (Gmsh: Mesh.ElementOrder = \
                 1 or 2, or `gmsh -3 -order 2`): the file has {nodes}-node {shape} (element type {}) in {where_}",
                ty as i32
            )),
            _ if dim == 3 => Err(format!(
                "only 4-node and 10-node tetrahedra are supported as volume elements: the file has {} {nodes}-node \
                 {shape} (element type {}) in {where_}",
                block.elements.len(),
                ty as i32
            )),
            _ if dim == 2 && !in_groups.is_empty() => Err(format!(
                "physical surface {:?} has {} {nodes}-node {shape} (element type {}) in {where_}: only 3-node \
                 triangles (and 6-node ones in a second-order mesh) can be facets of a tetrahedral mesh",
                groups.name(2, in_groups[0]),
                block.elements.len(),
                ty as i32
            )),
            _ => {
                *self.skipped.entry(format!("{nodes}-node {shape}")).or_default() += block.elements.len();
                Ok(())
            }
        }
    }

    /// Adds a block of 4-node or 10-node tetrahedra (in `where_`): all must have one order.
    fn add_tetrahedra(&mut self, block: &ElementBlock<u64, i32>, where_: String) -> Result<(), String> {
        let ty = block.element_type;
        match &self.tet_type {
            None => self.tet_type = Some((ty, where_)),
            Some((first, first_where)) if *first != ty => {
                return Err(format!(
                    "the file mixes first- and second-order tetrahedra: {}-node tetrahedra (element type {}) in \
                     {first_where} and {}-node tetrahedra (element type {}) in {where_}; all tetrahedra must have the \
                     same order (Gmsh: Mesh.ElementOrder = 1 or 2)",
                    describe(*first).1,
                    *first as i32,
                    describe(ty).1,
                    ty as i32
                ));
            }
            Some(_) => {}
        }
        let second = ty == ElementType::Tet10;
        self.tets.extend(block.elements.iter().map(|e| {
            let n = &e.nodes;
            let edges = if second { GMSH_TET10_EDGE_NODES.map(|k| n[k]) } else { [0; 6] };
            (e.element_tag, [n[0], n[1], n[2], n[3]], edges)
        }));
        Ok(())
    }

    /// Adds a block of 3-node or 6-node triangles (in `where_`) to each of its physical
    /// surfaces `in_groups`; outside any, it is skipped.
    fn add_triangles(&mut self, block: &ElementBlock<u64, i32>, in_groups: &[i32], where_: String) {
        let second = block.element_type == ElementType::Tri6;
        if in_groups.is_empty() {
            let nodes = describe(block.element_type).1;
            *self.skipped.entry(format!("{nodes}-node triangles outside physical surfaces")).or_default() +=
                block.elements.len();
        } else if second && self.tri6.is_none() {
            self.tri6 = Some((in_groups[0], where_, block.elements.len()));
        }
        for &g in in_groups {
            self.triangles.entry(g).or_default().extend(block.elements.iter().map(|e| {
                let n = &e.nodes;
                (e.element_tag, [n[0], n[1], n[2]], second.then(|| GMSH_TRI6_EDGE_NODES.map(|k| n[k])))
            }));
        }
    }

    /// Checks that there are tetrahedra, and 6-node triangles only on 10-node ones.
    fn check_tetrahedra(&self, groups: &PhysicalGroups) -> Result<(), String> {
        if self.tets.is_empty() {
            let n_triangles: usize = self.triangles.values().map(Vec::len).sum();
            let mut found: Vec<String> = self.skipped.iter().map(|(k, n)| format!("{n} {k}")).collect();
            if n_triangles > 0 {
                found.insert(0, format!("{n_triangles} triangle(s) of physical surfaces"));
            }
            let found = if found.is_empty() { "no elements".to_string() } else { found.join(", ") };
            return Err(format!(
                "the file has no tetrahedra (4-node or 10-node, element type 4 or 11), only {found}; {SAVE_HINT}; a \
                 2D mesh cannot be used"
            ));
        }
        if let (false, Some((g, where_, n))) = (self.second_order(), &self.tri6) {
            return Err(format!(
                "physical surface {:?} has {n} 6-node triangles (element type 9) in {where_}, but the tetrahedra are \
                 4-node (element type 4): the facets of a first-order mesh are 3-node triangles (mesh the surfaces \
                 and the volume with the same order)",
                groups.name(2, *g)
            ));
        }
        Ok(())
    }
}

/// Marks a file node on no tetrahedron in [`Numbering::dense`].
const NONE: usize = usize::MAX;

/// The dense numbering of the nodes of the tetrahedra: the vertices in increasing tag order,
/// then the edge nodes in increasing tag order; nodes on no tetrahedron are dropped.
struct Numbering {
    /// File position of each mesh node.
    order: Vec<usize>,
    /// Mesh index of each file node ([`NONE`] for a node on no tetrahedron).
    dense: Vec<usize>,
}

impl Numbering {
    /// Numbers the nodes of `tets` (their edge nodes too at `second_order`); every node tag
    /// must be in `$Nodes`.
    fn of_tetrahedra(nodes: &FileNodes, tets: &[FileTet], second_order: bool) -> Result<Self, String> {
        // what each node of the file is: 0 on no tetrahedron, 1 a vertex, 2 an edge node only (a
        // node that is both is a vertex, and `with_edge_nodes` refuses it as an edge node)
        let mut role = vec![0u8; nodes.tags.len()];
        for (etag, t, edges) in tets {
            for n in t {
                match nodes.position.get(n) {
                    Some(&i) => role[i] = 1,
                    None => return Err(dangling("tetrahedron", *etag, *n, "")),
                }
            }
            for n in edges.iter().filter(|_| second_order) {
                match nodes.position.get(n) {
                    Some(&i) if role[i] == 0 => role[i] = 2,
                    Some(_) => {}
                    None => return Err(dangling("tetrahedron", *etag, *n, "")),
                }
            }
        }
        let mut order: Vec<usize> = (0..nodes.tags.len()).filter(|&i| role[i] != 0).collect();
        order.sort_unstable_by_key(|&i| (role[i], nodes.tags[i]));
        let mut dense = vec![NONE; nodes.tags.len()];
        for (k, &i) in order.iter().enumerate() {
            dense[i] = k;
        }
        Ok(Self { order, dense })
    }

    /// The mesh index of the node tagged `tag`, a node of `$Nodes`.
    fn index(&self, nodes: &FileNodes, tag: &u64) -> usize {
        self.dense[nodes.position[tag]]
    }

    /// The coordinates of the mesh nodes.
    fn coords(&self, nodes: &FileNodes) -> Vec<[f64; 3]> {
        self.order.iter().map(|&i| nodes.coords[i]).collect()
    }
}

/// The tetrahedra in mesh indices, in the order of their first vertex (ties by tag).
struct Tetrahedra {
    /// Gmsh element tag of each tetrahedron.
    element_tags: Vec<u64>,
    /// The four vertices of each.
    vertices: Vec<[usize; 4]>,
    /// The six edge nodes of each, in the order of [`TET_EDGES`](crate::mesh::TET_EDGES)
    /// (empty at order 1).
    edges: Vec<[usize; 6]>,
}

impl Tetrahedra {
    /// Maps the file's tetrahedra to mesh indices and orders them by their first vertex (ties by
    /// tag): Gmsh lists them by geometric entity and in the mesher's order, scattered in memory
    /// against the nodes; the assembly visits the elements around each node in node order
    /// (unstructured 19.8k-dof mesh: Newton 1.24 s → 1.05 s). The edge nodes go with their
    /// tetrahedron (the vertices keep their local order, so edge k still joins the local vertices
    /// TET_EDGES[k]).
    fn numbered(tets: &[FileTet], nodes: &FileNodes, numbering: &Numbering, second_order: bool) -> Self {
        let index = |n: &u64| numbering.index(nodes, n);
        type Tet = (u64, [usize; 4], [usize; 6]);
        let mut tets: Vec<Tet> = tets
            .iter()
            .map(|(e, t, edges)| {
                (*e, t.map(|n| index(&n)), if second_order { edges.map(|n| index(&n)) } else { [0; 6] })
            })
            .collect();
        tets.sort_unstable_by_key(|(e, t, _)| (t.iter().min().copied(), *e));
        Self {
            element_tags: tets.iter().map(|t| t.0).collect(),
            vertices: tets.iter().map(|t| t.1).collect(),
            edges: if second_order { tets.iter().map(|t| t.2).collect() } else { Vec::new() },
        }
    }
}

/// A 6-node triangle of a physical surface, to check its edge nodes against the tetrahedra's:
/// (group, element tag, corners in mesh indices, edge node tags in the order of [`TRI_EDGES`]).
type TriangleEdges = (String, u64, [usize; 3], [u64; 3]);

/// The physical surfaces as facet groups in mesh indices, with what the later checks need.
struct SurfaceFacets {
    /// Each surface's name and facets.
    named: Vec<(String, Vec<[usize; 3]>)>,
    /// The element tag of each facet, by (group, sorted corners).
    facet_tags: HashMap<(String, [usize; 3]), u64>,
    /// The 6-node triangles.
    triangle_edges: Vec<TriangleEdges>,
    /// The physical surfaces.
    groups: Vec<PhysicalGroup>,
}

impl SurfaceFacets {
    /// Maps the triangles of each physical surface to mesh indices: every surface must have
    /// triangles, and their nodes must be nodes of the tetrahedra.
    fn read(
        groups: &PhysicalGroups,
        triangles: &BTreeMap<i32, Vec<FileTriangle>>,
        nodes: &FileNodes,
        numbering: &Numbering,
    ) -> Result<Self, String> {
        let mut surfaces =
            Self { named: Vec::new(), facet_tags: HashMap::new(), triangle_edges: Vec::new(), groups: Vec::new() };
        for g in groups.surfaces() {
            let name = groups.name(2, g);
            let list = triangles.get(&g).map(Vec::as_slice).unwrap_or(&[]);
            if list.is_empty() {
                return Err(format!(
                    "physical surface {name:?} (tag {g}) refers to nothing: the file has no triangles in its surfaces"
                ));
            }
            let mut facets = Vec::with_capacity(list.len());
            for (etag, t, edges) in list {
                let f = facet_corners(*etag, t, &name, nodes, numbering)?;
                if let Some(edges) = edges {
                    if let Some(n) = edges.iter().find(|n| !nodes.position.contains_key(n)) {
                        return Err(dangling("triangle", *etag, *n, &format!(" of physical surface {name:?}")));
                    }
                    surfaces.triangle_edges.push((name.clone(), *etag, f, *edges));
                }
                let mut key = f;
                key.sort_unstable();
                surfaces.facet_tags.insert((name.clone(), key), *etag);
                facets.push(f);
            }
            surfaces.groups.push(PhysicalGroup { dim: 2, tag: g, name: name.clone(), elements: list.len() });
            surfaces.named.push((name, facets));
        }
        Ok(surfaces)
    }
}

/// The corners of triangle `etag` (node tags `t`) of physical surface `name` in mesh indices:
/// each must be a node of the tetrahedra.
fn facet_corners(
    etag: u64,
    t: &[u64; 3],
    name: &str,
    nodes: &FileNodes,
    numbering: &Numbering,
) -> Result<[usize; 3], String> {
    let mut f = [0; 3];
    for (k, n) in t.iter().enumerate() {
        let Some(&i) = nodes.position.get(n) else {
            return Err(dangling("triangle", etag, *n, &format!(" of physical surface {name:?}")));
        };
        if numbering.dense[i] == NONE {
            return Err(format!(
                "triangle {etag} of physical surface {name:?} uses node {n}, which belongs to no tetrahedron: the \
                 surface is not part of the boundary of the meshed volume (mesh the surfaces and the volume \
                 together, e.g. after a boolean fragment, so that they share nodes)"
            ));
        }
        f[k] = numbering.dense[i];
    }
    Ok(f)
}

/// [`TetMesh::new`]'s error in the file's terms: element and node tags, the triangle's tag.
fn mesh_error(
    e: MeshError,
    element_tags: &[u64],
    node_tags: &[u64],
    facet_tags: &HashMap<(String, [usize; 3]), u64>,
) -> String {
    let tags = |t: &[usize]| t.iter().map(|&n| node_tags[n].to_string()).collect::<Vec<_>>().join(", ");
    match e {
        MeshError::Inverted { element, nodes, volume } => format!(
            "tetrahedron {} (nodes {}) is inverted: signed volume {volume:.3e} < 0 (index {element} in the imported \
             mesh); MSH tetrahedra must be positively oriented",
            element_tags[element],
            tags(&nodes)
        ),
        MeshError::Degenerate { element, nodes, volume } => format!(
            "tetrahedron {} (nodes {}) has zero volume ({volume:.3e}): the mesh is degenerate there (index {element} \
             in the imported mesh)",
            element_tags[element],
            tags(&nodes)
        ),
        MeshError::NotABoundaryFacet { group, facet } => {
            let mut key = facet;
            key.sort_unstable();
            let etag = facet_tags.get(&(group.clone(), key)).map_or("?".into(), u64::to_string);
            format!(
                "triangle {etag} (nodes {}) of physical surface {group:?} is not a boundary face of the \
                 tetrahedra: a physical surface used as a facet group must lie on the boundary of the meshed \
                 volume (an interior surface, such as the interface between two volumes of the body, cannot be \
                 one; and a surface meshed separately from the volume does not share its nodes)",
                tags(&facet)
            )
        }
        other => other.to_string(),
    }
}

/// The second-order mesh: `tet_edges` become its edge nodes ([`TetMesh::with_edge_nodes`],
/// which moves them to the midpoints), the 6-node triangles' edge nodes are checked against
/// them, and a warning says when curved elements were straightened.
fn with_edge_nodes(
    mesh: TetMesh,
    tet_edges: Vec<[usize; 6]>,
    element_tags: &[u64],
    node_tags: &[u64],
    triangle_edges: &[TriangleEdges],
    index: &dyn Fn(&u64) -> usize,
) -> Result<(TetMesh, Vec<String>), String> {
    let (mesh, moved) = mesh.with_edge_nodes(tet_edges).map_err(|e| match e {
        MeshError::BadEdgeNode { element, node, reason } => format!(
            "10-node tetrahedron {}: its edge node {} is unusable: {reason} (the 10-node tetrahedra must share one \
             node per edge, and no vertex can be an edge node)",
            element_tags[element],
            node_tags.get(node).map_or_else(|| format!("#{node}"), u64::to_string)
        ),
        other => other.to_string(),
    })?;
    check_triangle_edges(&mesh, triangle_edges, node_tags, index)?;
    let mut warnings = Vec::new();
    if moved > CURVED_EDGE_TOLERANCE {
        warnings.push(format!(
            "the 10-node tetrahedra are curved: an edge node lies {moved:.2e} of its edge's length off the edge's \
             midpoint (more than {CURVED_EDGE_TOLERANCE:.0e}); the elements are treated as straight-sided, every edge \
             node moved to its edge's midpoint, so the curved edges are straightened (a curved boundary becomes the \
             flat facets through its vertices)"
        ));
    }
    Ok((mesh, warnings))
}

/// Checks that the edge nodes of the 6-node triangles of the facet groups are the tetrahedra's:
/// `triangles` holds (group, element tag, corners, edge node tags in the order of
/// [`TRI_EDGES`]); `index` maps a node tag to its mesh index ([`NONE`] for a node on no
/// tetrahedron).
fn check_triangle_edges(
    mesh: &TetMesh,
    triangles: &[TriangleEdges],
    node_tags: &[u64],
    index: &dyn Fn(&u64) -> usize,
) -> Result<(), String> {
    let Some(so) = &mesh.second_order else { return Ok(()) };
    if triangles.is_empty() {
        return Ok(());
    }
    // the edge node of every boundary edge
    let mut edge_node: HashMap<(usize, usize), usize> = HashMap::with_capacity(3 * mesh.boundary.len());
    for (f, edges) in mesh.boundary.iter().zip(&so.facet_edges) {
        for (&[i, j], &n) in TRI_EDGES.iter().zip(edges) {
            edge_node.insert((f[i].min(f[j]), f[i].max(f[j])), n);
        }
    }
    for (group, etag, f, edges) in triangles {
        for (&[i, j], tag) in TRI_EDGES.iter().zip(edges) {
            let (a, b) = (f[i], f[j]);
            // the triangle is a boundary facet (TetMesh::new checked it), so its edges are known
            let Some(&expected) = edge_node.get(&(a.min(b), a.max(b))) else { continue };
            if index(tag) != expected {
                return Err(format!(
                    "6-node triangle {etag} of physical surface {group:?} has node {tag} on its edge from node {} to \
                     node {}, but the tetrahedra have node {} there: the surface's edge nodes must be those of the \
                     volume (mesh the surfaces and the volume together)",
                    node_tags[a], node_tags[b], node_tags[expected]
                ));
            }
        }
    }
    Ok(())
}

fn dangling(what: &str, element: u64, node: u64, context: &str) -> String {
    format!(
        "{what} {element}{context} refers to node {node}, but no node has tag {node} in $Nodes (element and node \
         tags of the file)"
    )
}

/// The kind of elements of type `ty`, in words, and its number of nodes.
fn describe(ty: ElementType) -> (&'static str, usize) {
    let name = format!("{ty:?}");
    let shape = match name.get(..3) {
        Some("Lin") => "lines",
        Some("Tri") => "triangles",
        Some("Qua") => "quadrangles",
        Some("Tet") => "tetrahedra",
        Some("Hex") => "hexahedra",
        Some("Pri") => "prisms",
        Some("Pyr") => "pyramids",
        Some("Pnt") => "points",
        _ => "elements",
    };
    (shape, ty.nodes().unwrap_or(0))
}

/// True for triangles and tetrahedra of order 3 and higher: more nodes than the 6-node
/// triangle or the 10-node tetrahedron (complete or not, e.g. the 9-node triangle, the 20-node
/// tetrahedron).
fn beyond_second_order(ty: ElementType) -> bool {
    match describe(ty) {
        ("triangles", nodes) => nodes > 6,
        ("tetrahedra", nodes) => nodes > 10,
        _ => false,
    }
}

/// Checks the `$MeshFormat` header: MSH version 4.1, ASCII (0) or binary (1), size_t of 4 or 8
/// bytes (mshio panics on other sizes). Returns whether the file is binary.
fn check_format(bytes: &[u8]) -> Result<bool, String> {
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(200)]);
    let mut lines = head.lines().map(str::trim).skip_while(|l| l.is_empty());
    match lines.next() {
        Some("$MeshFormat") => {}
        Some(l) if l.starts_with("$NOD") => {
            return Err("MSH version 1 found; only version 4.1 is read: re-export the mesh as MSH 4.1 \
                        (Gmsh: Mesh.MshFileVersion = 4.1, or `gmsh -format msh41`)"
                .into());
        }
        _ if bytes.is_empty() => return Err("the file is empty".into()),
        _ => return Err("not a Gmsh MSH file: it does not begin with $MeshFormat".into()),
    }
    let line = lines.next().unwrap_or("");
    let mut fields = line.split_whitespace();
    let version = fields.next().unwrap_or("(none)");
    if version.parse::<f64>() != Ok(4.1) {
        return Err(format!(
            "MSH version {version} found; only version 4.1 is read: re-export the mesh as MSH 4.1 \
             (Gmsh: Mesh.MshFileVersion = 4.1, or `gmsh -format msh41`)"
        ));
    }
    let binary = match fields.next() {
        Some("0") => false,
        Some("1") => true,
        other => return Err(format!("$MeshFormat: file type {other:?}: must be 0 (ASCII) or 1 (binary)")),
    };
    match fields.next() {
        Some("4" | "8") => Ok(binary),
        other => Err(format!("$MeshFormat: data size {other:?}: must be 4 or 8 (bytes of size_t)")),
    }
}

/// Position just after the line `tag` (the whole line, at the start of a line), if any.
fn find_line(bytes: &[u8], tag: &[u8]) -> Option<usize> {
    let mut from = 0;
    while let Some(p) = bytes[from..].windows(tag.len()).position(|w| w == tag) {
        let start = from + p;
        let end = start + tag.len();
        let at_line_start = start == 0 || bytes[start - 1] == b'\n';
        let rest = &bytes[end..];
        let eol = if rest.starts_with(b"\n") {
            Some(1)
        } else if rest.starts_with(b"\r\n") {
            Some(2)
        } else {
            None
        };
        if let (true, Some(n)) = (at_line_start, eol) {
            return Some(end + n);
        }
        from = start + 1;
    }
    None
}

/// The `$PhysicalNames` section: `(dim, tag) → name`. It is ASCII in binary files too.
fn physical_names(bytes: &[u8]) -> Result<BTreeMap<(i32, i32), String>, String> {
    let mut names = BTreeMap::new();
    let Some(start) = find_line(bytes, b"$PhysicalNames") else {
        return Ok(names);
    };
    let Some(len) = find_line(&bytes[start..], b"$EndPhysicalNames").map(|p| {
        let body = &bytes[start..start + p];
        body.len() - body.iter().rev().position(|&c| c == b'$').map_or(0, |q| q + 1)
    }) else {
        return Err("$PhysicalNames has no $EndPhysicalNames (is the file truncated?)".into());
    };
    let text = std::str::from_utf8(&bytes[start..start + len])
        .map_err(|_| "$PhysicalNames: the section is not text".to_string())?;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or_else(|| "$PhysicalNames: the first line must be the number of names".to_string())?;
    let mut n = 0;
    for line in lines {
        let bad = || format!("$PhysicalNames: cannot read {line:?}; expected: dimension tag \"name\"");
        let quote = line.find('"').ok_or_else(bad)?;
        let mut it = line[..quote].split_whitespace();
        let dim: i32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = it.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let name = line[quote..].trim_end().strip_prefix('"').and_then(|s| s.strip_suffix('"')).ok_or_else(bad)?;
        if it.next().is_some() {
            return Err(bad());
        }
        if !(0..=3).contains(&dim) {
            return Err(format!("$PhysicalNames: {line:?}: the dimension must be 0, 1, 2 or 3"));
        }
        names.insert((dim, tag), name.to_string());
        n += 1;
    }
    if n != count {
        return Err(format!("$PhysicalNames announces {count} names but lists {n}"));
    }
    Ok(names)
}

const TRUNCATED: &str = "; the file does not end with an $End… line: it is truncated";

/// True when the file does not end with a section's end line (`$EndElements`, …).
fn truncated(bytes: &[u8]) -> bool {
    let end = bytes.iter().rposition(|c| !c.is_ascii_whitespace()).map_or(0, |p| p + 1);
    let start = bytes[..end].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    !bytes[start..end].starts_with(b"$End")
}

/// A message for an mshio parse error: what failed, in which section, at which line (ASCII) or
/// byte (binary). (mshio's own `Display` appends a hex dump of the rest of the file.)
fn parse_error(bytes: &[u8], e: &mshio::MshParserError<&[u8]>, binary: bool) -> String {
    let trace = e.filtered_backtrace();
    let Some((rest, kind)) = trace.first() else {
        return "cannot parse the file as MSH 4.1 (is it truncated?)".into();
    };
    let contexts: Vec<String> =
        trace[1..].iter().rev().map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string)).collect();
    let offset = (rest.as_ptr() as usize).wrapping_sub(bytes.as_ptr() as usize).min(bytes.len());
    let at = if offset >= bytes.len() || bytes[offset..].iter().all(u8::is_ascii_whitespace) {
        "at the end of the file".to_string()
    } else if binary {
        format!("at byte {offset}")
    } else {
        format!("at line {}", bytes[..offset].iter().filter(|&&c| c == b'\n').count() + 1)
    };
    let hint = if truncated(bytes) { TRUNCATED } else { "" };
    let kind = kind.to_string();
    let kind = kind.trim_end_matches('.');
    let mut chars = kind.chars();
    let kind: String = chars.next().map(|c| c.to_lowercase().chain(chars).collect()).unwrap_or_default();
    if contexts.is_empty() {
        format!("cannot parse the file as MSH 4.1: {kind} {at}{hint}")
    } else {
        format!("cannot parse the file as MSH 4.1: {kind} {at} (in {}){hint}", contexts.join(" > "))
    }
}

/// The node tags of each node block in file order, from the raw `$Nodes` section (mshio drops
/// them when they form one dense range, which need not be in file order). mshio has already
/// parsed the section, so a failure here means an inconsistency.
fn raw_node_tags(bytes: &[u8], header: &MshHeader, binary: bool) -> Result<Vec<Vec<u64>>, String> {
    let fail = || "$Nodes: cannot read the node tags".to_string();
    let start = find_line(bytes, b"$Nodes").ok_or_else(fail)?;
    let body = &bytes[start..];
    let mut out = Vec::new();
    if !binary {
        let text = std::str::from_utf8(body).ok().and_then(|t| t.split("$EndNodes").next()).ok_or_else(fail)?;
        let mut tokens = text.split_ascii_whitespace();
        let int = |t: &mut std::str::SplitAsciiWhitespace<'_>| t.next().and_then(|t| t.parse::<u64>().ok());
        // numEntityBlocks numNodes minNodeTag maxNodeTag
        let blocks = int(&mut tokens).ok_or_else(fail)?;
        (0..3).try_for_each(|_| int(&mut tokens).map(drop)).ok_or_else(fail)?;
        for _ in 0..blocks {
            // entityDim entityTag parametric numNodesInBlock, the tags, then x y z per node
            // (parametric blocks are refused by mshio)
            (0..3).try_for_each(|_| tokens.next().map(drop)).ok_or_else(fail)?;
            let n = int(&mut tokens).ok_or_else(fail)?;
            out.push((0..n).map(|_| int(&mut tokens)).collect::<Option<Vec<u64>>>().ok_or_else(fail)?);
            (0..3 * n).try_for_each(|_| tokens.next().map(drop)).ok_or_else(fail)?;
        }
    } else {
        // the int 1 after the format line tells the byte order
        let format = find_line(bytes, b"$MeshFormat").ok_or_else(fail)?;
        let one = format + bytes[format..].iter().position(|&c| c == b'\n').ok_or_else(fail)? + 1;
        let little = bytes.get(one..one + 4) == Some(&[1, 0, 0, 0][..]);
        let mut r = Reader { bytes: body, pos: 0, little };
        let size = header.size_t_size;
        let blocks = r.size_t(size).ok_or_else(fail)?;
        r.skip(3 * size).ok_or_else(fail)?;
        for _ in 0..blocks {
            r.skip(12).ok_or_else(fail)?; // entityDim, entityTag, parametric (int)
            let n = r.size_t(size).ok_or_else(fail)?;
            out.push((0..n).map(|_| r.size_t(size)).collect::<Option<Vec<u64>>>().ok_or_else(fail)?);
            r.skip(24usize.checked_mul(n as usize).ok_or_else(fail)?).ok_or_else(fail)?;
        }
    }
    Ok(out)
}

/// A cursor over binary MSH data.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    little: bool,
}

impl Reader<'_> {
    fn skip(&mut self, n: usize) -> Option<()> {
        let end = self.pos.checked_add(n)?;
        (end <= self.bytes.len()).then(|| self.pos = end)
    }

    /// An unsigned integer of `size` (4 or 8) bytes.
    fn size_t(&mut self, size: usize) -> Option<u64> {
        let b = self.bytes.get(self.pos..self.pos.checked_add(size)?)?;
        self.pos += size;
        let mut v = [0u8; 8];
        if self.little {
            v[..size].copy_from_slice(b);
            Some(u64::from_le_bytes(v))
        } else {
            v[8 - size..].copy_from_slice(b);
            Some(u64::from_be_bytes(v))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sections of [`TINY`] and [`TINY_P2`] before `$Nodes`: the physical surface "bottom"
    /// (tag 1) on surface 1, the physical volume "body" (tag 2) on volume 1.
    macro_rules! tiny_head {
        () => {
            "$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 \"bottom\"
3 2 \"body\"
$EndPhysicalNames
$Entities
0 0 1 1
1 0 0 0 1 1 0 1 1 0
1 0 0 0 1 1 1 1 2 1 1
$EndEntities
"
        };
    }

    /// Two tetrahedra sharing the face (2, 3, 4): nodes 1..5, the triangle (1, 2, 3) on z = 0 in
    /// the physical surface "bottom", the volume in "body".
    const TINY: &str = concat!(
        tiny_head!(),
        "$Nodes
1 5 1 5
3 1 0 5
1
2
3
4
5
0 0 0
1 0 0
0 1 0
0 0 1
1 1 1
$EndNodes
$Elements
2 3 1 3
2 1 2 1
1 1 2 3
3 1 4 2
2 1 2 3 4
3 2 3 4 5
$EndElements
"
    );

    fn read(text: &str) -> Result<GmshImport, String> {
        parse_msh(text.as_bytes(), 1.0, Path::new("tiny.msh")).map_err(|e| {
            assert!(matches!(e, MeshError::File { .. }));
            let m = e.to_string();
            assert!(m.starts_with("tiny.msh: "), "{m}");
            m
        })
    }

    fn coords_by_tag(imp: &GmshImport) -> BTreeMap<u64, [f64; 3]> {
        imp.node_tags.iter().zip(&imp.mesh.nodes).map(|(&t, &x)| (t, x)).collect()
    }

    #[test]
    fn reads_tets_groups_and_tags() {
        let imp = read(TINY).unwrap();
        assert_eq!(imp.mesh.n_nodes(), 5);
        assert_eq!(imp.mesh.n_elements(), 2);
        assert_eq!(imp.node_tags, vec![1, 2, 3, 4, 5]);
        assert_eq!(imp.element_tags, vec![2, 3]);
        assert_eq!(imp.mesh.group_names(), vec!["bottom"]);
        let f = imp.mesh.groups["bottom"][0];
        assert_eq!(imp.mesh.facet_centroid(f)[2], 0.0);
        assert_eq!(imp.surface_groups, vec![PhysicalGroup { dim: 2, tag: 1, name: "bottom".into(), elements: 1 }]);
        assert_eq!(imp.ignored_groups, vec![PhysicalGroup { dim: 3, tag: 2, name: "body".into(), elements: 2 }]);
        assert_eq!(imp.unused_nodes, 0);
        assert_eq!(coords_by_tag(&imp)[&5], [1.0, 1.0, 1.0]);
    }

    #[test]
    fn tetrahedra_are_ordered_by_their_first_node_and_keep_their_tags() {
        // the file lists tetrahedron 3 (nodes 2 3 4 5) before tetrahedron 2 (nodes 1 2 3 4)
        let swapped = TINY.replace("2 1 2 3 4\n3 2 3 4 5\n", "3 2 3 4 5\n2 1 2 3 4\n");
        assert_ne!(swapped, TINY);
        let imp = read(&swapped).unwrap();
        assert_eq!(imp.element_tags, vec![2, 3]);
        let tags = |t: &[usize; 4]| t.map(|n| imp.node_tags[n]);
        assert_eq!(tags(&imp.mesh.tets[0]), [1, 2, 3, 4]);
        assert_eq!(tags(&imp.mesh.tets[1]), [2, 3, 4, 5]);
    }

    #[test]
    fn dense_permuted_and_sparse_node_tags_map_to_the_same_mesh() {
        let reference = coords_by_tag(&read(TINY).unwrap());
        // dense tags 1..5 listed out of order, coordinates with them
        let permuted = TINY.replace(
            "1\n2\n3\n4\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n",
            "3\n1\n5\n2\n4\n0 1 0\n0 0 0\n1 1 1\n1 0 0\n0 0 1\n",
        );
        assert_ne!(permuted, TINY);
        assert_eq!(coords_by_tag(&read(&permuted).unwrap()), reference);
        // sparse tags: node k is tag 10 k (mshio keeps the tags)
        let sparse = TINY
            .replace("1 5 1 5\n", "1 5 10 50\n")
            .replace("1\n2\n3\n4\n5\n0 0 0", "10\n20\n30\n40\n50\n0 0 0")
            .replace("1 1 2 3\n", "1 10 20 30\n")
            .replace("2 1 2 3 4\n3 2 3 4 5\n", "2 10 20 30 40\n3 20 30 40 50\n");
        let imp = read(&sparse).unwrap();
        assert_eq!(imp.node_tags, vec![10, 20, 30, 40, 50]);
        let by_tag: BTreeMap<u64, [f64; 3]> = coords_by_tag(&imp).into_iter().map(|(t, x)| (t / 10, x)).collect();
        assert_eq!(by_tag, reference);
        assert_eq!(imp.mesh.groups["bottom"].len(), 1);
    }

    #[test]
    fn unnamed_groups_scale_and_crlf() {
        let unnamed = TINY.replace("2\n2 1 \"bottom\"\n", "1\n");
        assert_eq!(read(&unnamed).unwrap().mesh.group_names(), vec!["physical_1"]);
        let imp = parse_msh(TINY.as_bytes(), 2.0, Path::new("x")).unwrap();
        assert_eq!(coords_by_tag(&imp)[&5], [2.0, 2.0, 2.0]);
        let crlf = TINY.replace('\n', "\r\n");
        assert_eq!(read(&crlf).unwrap().mesh.group_names(), vec!["bottom"]);
        let spaced = TINY.replace("2 1 \"bottom\"", "2  1\t\"the bottom face\"");
        assert_eq!(read(&spaced).unwrap().mesh.group_names(), vec!["the bottom face"]);
    }

    #[test]
    fn errors_name_the_problem() {
        let cases: Vec<(String, Vec<&str>)> = vec![
            (TINY.replace("4.1 0 8", "2.2 0 8"), vec!["MSH version 2.2 found", "only version 4.1"]),
            ("hello".into(), vec!["not a Gmsh MSH file"]),
            (String::new(), vec!["empty"]),
            (
                TINY.replace("2\n2 1 \"bottom\"\n", "3\n2 1 \"bottom\"\n2 7 \"ghost\"\n"),
                vec!["\"ghost\"", "refers to nothing", "physical tag 7"],
            ),
            (TINY.replace("1 1 2 3\n", "1 2 3 4\n"), vec!["triangle 1", "\"bottom\"", "not a boundary face"]),
            (TINY.replace("3 2 3 4 5\n", "3 2 3 4 9\n"), vec!["tetrahedron 3 refers to node 9"]),
            (
                TINY.replace("1 1 2 3\n", "1 1 2 8\n"),
                vec!["triangle 1 of physical surface \"bottom\" refers to node 8"],
            ),
            (TINY.replace("2 1 2 3 4\n", "2 1 3 2 4\n"), vec!["tetrahedron 2 (nodes 1, 3, 2, 4) is inverted"]),
            (TINY.replace("1 0 0\n0 1 0", "1e999 0 0\n0 1 0"), vec!["node 2 has a non-finite coordinate"]),
            (
                TINY.replace("2 3 1 3\n", "1 1 1 1\n").replace("3 1 4 2\n2 1 2 3 4\n3 2 3 4 5\n", ""),
                vec!["no tetrahedra", "1 triangle(s) of physical surfaces", "Mesh.SaveAll"],
            ),
            (
                TINY.replace(
                    "3 1 4 2\n2 1 2 3 4\n3 2 3 4 5\n",
                    "3 1 29 1\n2 1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4 1 2 3 4\n",
                )
                .replace("2 3 1 3\n", "2 2 1 2\n"),
                vec![
                    "elements of order 3 and higher are not supported; mesh with order 1 or 2",
                    "20-node tetrahedra (element type 29) in volume 1",
                ],
            ),
            (
                TINY.replace("2 1 2 1\n1 1 2 3\n", "2 1 21 1\n1 1 2 3 1 2 3 1 2 3 4\n"),
                vec!["order 3 and higher", "10-node triangles (element type 21) in surface 1"],
            ),
            (
                TINY.replace("3 1 4 2\n2 1 2 3 4\n3 2 3 4 5\n", "3 1 5 1\n2 1 2 3 4 5 1 2 3\n")
                    .replace("2 3 1 3\n", "2 2 1 2\n"),
                vec!["only 4-node and 10-node tetrahedra", "1 8-node hexahedra (element type 5) in volume 1"],
            ),
            (
                TINY.replace("2 1 2 1\n1 1 2 3\n", "2 1 3 1\n1 1 2 3 4\n"),
                vec!["physical surface \"bottom\" has 1 4-node quadrangles", "only 3-node triangles"],
            ),
            (TINY.replace("1 5 1 5\n", "1 5 1 5\n7\n"), vec!["cannot parse the file as MSH 4.1"]),
            (TINY.replace("2 1 \"bottom\"", "2 1 bottom"), vec!["$PhysicalNames: cannot read \"2 1 bottom\""]),
            (TINY.replace("$EndPhysicalNames\n", ""), vec!["$PhysicalNames has no $EndPhysicalNames"]),
            (TINY[..TINY.find("3 2 3 4 5").unwrap()].to_string(), vec!["truncated"]),
        ];
        for (text, expected) in cases {
            let err = read(&text).err().unwrap_or_else(|| panic!("no error for\n{text}"));
            for e in expected {
                assert!(err.contains(e), "error {err:?} lacks {e:?}");
            }
        }
    }

    #[test]
    fn missing_file_and_bad_scale() {
        let e = read_msh(Path::new("/no/such/dir/mesh.msh"), 1.0).unwrap_err().to_string();
        assert!(e.contains("/no/such/dir/mesh.msh") && e.contains("cannot read"), "{e}");
        let src = GmshMesh { file: "m.msh".into(), scale: 0.0 };
        assert!(src.validate("mesh").unwrap_err().to_string().contains("mesh.scale = 0"));
        assert!(src.validate("mesh").is_err());
        let src: Box<dyn MeshSource> = toml::from_str("type = \"gmsh\"\nfile = \"m.msh\"").unwrap();
        assert!(src.validate("mesh").is_ok());
        let e = toml::from_str::<Box<dyn MeshSource>>("type = \"gmsh\"\nfile = \"m.msh\"\nscal = 2.0").unwrap_err();
        assert!(e.to_string().contains("scal"), "{e}");
    }

    /// [`TINY`] at order 2: the two tetrahedra with their edge nodes, the bottom triangle a
    /// 6-node one. Vertices 1, 2, 3, 4 and 14 (the apex of the second tetrahedron); the edge
    /// nodes 6 (1–2), 7 (2–3), 8 (1–3), 9 (1–4), 10 (2–4), 11 (3–4), 12 (2–14), 13 (3–14) and
    /// 5 (4–14), at the midpoints; the elements list them in Gmsh's local order.
    const TINY_P2: &str = concat!(
        tiny_head!(),
        "$Nodes
1 14 1 14
3 1 0 14
1
2
3
4
5
6
7
8
9
10
11
12
13
14
0 0 0
1 0 0
0 1 0
0 0 1
0.5 0.5 1
0.5 0 0
0.5 0.5 0
0 0.5 0
0 0 0.5
0.5 0 0.5
0 0.5 0.5
1 0.5 0.5
0.5 1 0.5
1 1 1
$EndNodes
$Elements
2 3 1 3
2 1 9 1
1 1 2 3 6 7 8
3 1 11 2
2 1 2 3 4 6 7 8 9 11 10
3 2 3 4 14 7 11 10 12 5 13
$EndElements
"
    );

    fn tags_of(imp: &GmshImport, nodes: &[usize]) -> Vec<u64> {
        nodes.iter().map(|&n| imp.node_tags[n]).collect()
    }

    #[test]
    fn gmsh_tet10_edge_nodes_follow_the_reference_element() {
        // gmsh.model.mesh.getElementProperties(11)[4] and (9)[4], gmsh 4.15.2: the local nodes'
        // reference coordinates
        let tet10: [[f64; 3]; 10] = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.0],
            [0.0, 0.0, 0.5],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
        ];
        for (k, [i, j]) in crate::mesh::TET_EDGES.into_iter().enumerate() {
            let mid: [f64; 3] = std::array::from_fn(|c| 0.5 * (tet10[i][c] + tet10[j][c]));
            assert_eq!(tet10[GMSH_TET10_EDGE_NODES[k]], mid, "edge {k} ({i}, {j})");
        }
        let tri6: [[f64; 2]; 6] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]];
        for (k, [i, j]) in TRI_EDGES.into_iter().enumerate() {
            let mid: [f64; 2] = std::array::from_fn(|c| 0.5 * (tri6[i][c] + tri6[j][c]));
            assert_eq!(tri6[GMSH_TRI6_EDGE_NODES[k]], mid, "edge {k} ({i}, {j})");
        }
    }

    #[test]
    fn reads_second_order_tets_and_triangles() {
        let imp = read(TINY_P2).unwrap();
        let m = &imp.mesh;
        let so = m.second_order.as_ref().expect("a second-order mesh");
        assert_eq!((m.n_nodes(), m.n_elements(), so.n_vertices), (14, 2, 5));
        // the vertices first, then the edge nodes, each in tag order (edge node 5 after vertex 14)
        assert_eq!(imp.node_tags, vec![1, 2, 3, 4, 14, 5, 6, 7, 8, 9, 10, 11, 12, 13]);
        assert_eq!(imp.element_tags, vec![2, 3]);
        assert_eq!(imp.unused_nodes, 0);
        assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
        // the edge nodes in the order of TET_EDGES: (0,1), (1,2), (0,2), (0,3), (1,3), (2,3)
        assert_eq!(tags_of(&imp, &m.tets[0]), [1, 2, 3, 4]);
        assert_eq!(tags_of(&imp, &so.tet_edges[0]), [6, 7, 8, 9, 10, 11]);
        assert_eq!(tags_of(&imp, &m.tets[1]), [2, 3, 4, 14]);
        assert_eq!(tags_of(&imp, &so.tet_edges[1]), [7, 11, 10, 12, 13, 5]);
        let f = m.groups["bottom"][0];
        let (corners, edges) = (tags_of(&imp, &m.boundary[f]), tags_of(&imp, &so.facet_edges[f]));
        for (k, [i, j]) in TRI_EDGES.into_iter().enumerate() {
            let expected = match (corners[i].min(corners[j]), corners[i].max(corners[j])) {
                (1, 2) => 6,
                (2, 3) => 7,
                (1, 3) => 8,
                other => panic!("edge {other:?} is not on the bottom facet"),
            };
            assert_eq!(edges[k], expected);
        }
        // the vertices and tetrahedra of the first-order file
        let p1 = read(TINY).unwrap();
        assert_eq!(m.first_order().tets, p1.mesh.tets);
        assert_eq!(m.first_order().nodes, p1.mesh.nodes);
        assert_eq!(m.first_order().boundary, p1.mesh.boundary);
        // 3-node triangles name facets of a second-order mesh too
        let tri3 = TINY_P2.replace("2 1 9 1\n1 1 2 3 6 7 8\n", "2 1 2 1\n1 1 2 3\n");
        let imp3 = read(&tri3).unwrap();
        assert_eq!(imp3.mesh.second_order, imp.mesh.second_order);
        assert_eq!(imp3.mesh.groups, imp.mesh.groups);
    }

    #[test]
    fn curved_edge_nodes_are_straightened_with_a_warning() {
        // edge node 5 (the midpoint of 4 (0, 0, 1) and 14 (1, 1, 1)) lifted by 0.1: 0.1 / √2 of
        // its edge's length
        let curved = TINY_P2.replace("0.5 0.5 1\n", "0.5 0.5 1.1\n");
        assert_ne!(curved, TINY_P2);
        let imp = read(&curved).unwrap();
        assert_eq!(imp.warnings.len(), 1, "{:?}", imp.warnings);
        let w = &imp.warnings[0];
        assert!(w.contains("7.07e-2") && w.contains("straight"), "{w}");
        assert_eq!(coords_by_tag(&imp)[&5], [0.5, 0.5, 1.0]);
        assert_eq!(imp.mesh.nodes, read(TINY_P2).unwrap().mesh.nodes);
        // below the tolerance: no warning
        let nearly = TINY_P2.replace("0.5 0.5 1\n", "0.5 0.5 1.0000000001\n");
        assert!(read(&nearly).unwrap().warnings.is_empty());
    }

    #[test]
    fn second_order_errors_name_the_problem() {
        let cases: Vec<(String, Vec<&str>)> = vec![
            (
                // a 4-node and a 10-node tetrahedron
                TINY_P2
                    .replace("3 1 11 2\n2 1 2 3 4 6 7 8 9 11 10\n", "3 1 4 1\n2 1 2 3 4\n3 1 11 1\n")
                    .replace("2 3 1 3\n", "3 3 1 3\n"),
                vec![
                    "mixes first- and second-order tetrahedra",
                    "4-node tetrahedra (element type 4) in volume 1",
                    "10-node tetrahedra (element type 11) in volume 1",
                ],
            ),
            (
                // the same, the 10-node block first
                TINY_P2
                    .replace(
                        "3 1 11 2\n2 1 2 3 4 6 7 8 9 11 10\n3 2 3 4 14 7 11 10 12 5 13\n",
                        "3 1 11 1\n3 2 3 4 14 7 11 10 12 5 13\n3 1 4 1\n2 1 2 3 4\n",
                    )
                    .replace("2 3 1 3\n", "3 3 1 3\n"),
                vec!["10-node tetrahedra (element type 11) in volume 1 and 4-node tetrahedra (element type 4)"],
            ),
            (
                TINY.replace("2 1 2 1\n1 1 2 3\n", "2 1 9 1\n1 1 2 3 4 5 1\n"),
                vec!["physical surface \"bottom\" has 1 6-node triangles (element type 9)", "4-node"],
            ),
            (
                TINY_P2.replace("1 1 2 3 6 7 8\n", "1 1 2 3 6 8 7\n"),
                vec![
                    "6-node triangle 1 of physical surface \"bottom\" has node 8 on its edge from node 2 to node 3, \
                      but the tetrahedra have node 7 there",
                ],
            ),
            (
                TINY_P2.replace("1 1 2 3 6 7 8\n", "1 1 2 3 6 7 99\n"),
                vec!["triangle 1 of physical surface \"bottom\" refers to node 99"],
            ),
            (
                // edge 2–3 given node 7 by one tetrahedron and node 9 by the other
                TINY_P2.replace("3 2 3 4 14 7 11", "3 2 3 4 14 9 11"),
                vec!["10-node tetrahedron 3: its edge node 9 is unusable", "another element"],
            ),
            (
                TINY_P2.replace("3 2 3 4 14 7 11 10 12 5 13", "3 2 3 4 14 7 11 10 12 1 13"),
                vec!["10-node tetrahedron 3: its edge node 1 is unusable: it is a vertex"],
            ),
            (TINY_P2.replace("12 5 13\n", "12 5 77\n"), vec!["tetrahedron 3 refers to node 77"]),
        ];
        for (text, expected) in cases {
            let err = read(&text).err().unwrap_or_else(|| panic!("no error for\n{text}"));
            for e in expected {
                assert!(err.contains(e), "error {err:?} lacks {e:?}");
            }
        }
    }
}
