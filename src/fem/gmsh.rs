//! Reading and writing meshes in the gmsh 4.1 ASCII format (`.msh`).
//!
//! Only what the cell model needs: 6-node triangles (gmsh element type 9, whose local node
//! order is that of [`super::tri6`]) on surfaces tagged with the physical groups `nucleus`,
//! `cytoplasm` and `membrane` (case-insensitive). Points, lines and other element types
//! are ignored; linear triangles are refused.
//!
//! In 3-D ([`TetMesh::read_gmsh`]): 10-node tetrahedra (type 11, the local order of
//! [`super::tet10`]) in volumes of the physical groups `nucleus`, `cytoplasm`, `membrane`,
//! and 6-node triangles in surfaces of the physical group `outer`; other elements of the
//! usual types are skipped, linear tetrahedra in a cell volume are refused. The nodes the
//! tetrahedra use are renumbered compactly in the order of the file's `$Nodes`.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::Path;

use super::element::CellMesh;
use super::mesh::{Domain, Mesh, MeshError, MeshParams, MeshParts, TetMesh, TetMeshParams};
use super::tri6::EDGES;

/// gmsh element type of the 6-node triangle.
const TRIANGLE6: u32 = 9;
/// gmsh element type of the 3-node triangle.
const TRIANGLE3: u32 = 2;
/// gmsh element type of the 10-node tetrahedron.
const TET10: u32 = 11;
/// gmsh element type of the 4-node tetrahedron.
const TET4: u32 = 4;

/// Number of nodes of the gmsh element types a 3-D file may hold (first and second order
/// points, lines, triangles, quadrangles, tetrahedra, hexahedra, prisms, pyramids).
fn element_nodes(etype: u32) -> Option<usize> {
    Some(match etype {
        15 => 1,
        1 => 2,
        8 => 3,
        2 => 3,
        9 => 6,
        3 => 4,
        10 => 9,
        16 => 8,
        4 => 4,
        11 => 10,
        5 => 8,
        12 => 27,
        17 => 20,
        6 => 6,
        13 => 18,
        18 => 15,
        7 => 5,
        14 => 14,
        19 => 13,
        _ => return None,
    })
}

/// One section of the file: its name, its first content line (1-based) and its lines.
struct Section<'a> {
    name: &'a str,
    first_line: usize,
    lines: Vec<&'a str>,
}

/// Whitespace-separated tokens of a section with their line numbers.
struct Tokens<'a> {
    path: &'a str,
    toks: Vec<(&'a str, usize)>,
    pos: usize,
    end_line: usize,
}

impl<'a> Tokens<'a> {
    fn new(path: &'a str, sec: &Section<'a>) -> Self {
        let mut toks = Vec::new();
        for (i, l) in sec.lines.iter().enumerate() {
            for t in l.split_whitespace() {
                toks.push((t, sec.first_line + i));
            }
        }
        Self {
            path,
            toks,
            pos: 0,
            end_line: sec.first_line + sec.lines.len(),
        }
    }

    fn err(&self, line: usize, message: String) -> MeshError {
        MeshError::Format {
            path: self.path.to_string(),
            line,
            message,
        }
    }

    fn next<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, MeshError> {
        let Some(&(t, line)) = self.toks.get(self.pos) else {
            return Err(self.err(self.end_line, format!("section ends before {what}")));
        };
        self.pos += 1;
        t.parse()
            .map_err(|_| self.err(line, format!("cannot read {what} from `{t}`")))
    }

    fn line(&self) -> usize {
        self.toks.get(self.pos).map_or(self.end_line, |t| t.1)
    }
}

/// A gmsh file split into its sections, with what the cell model reads from each.
struct MshFile<'a> {
    path: &'a str,
    sections: Vec<Section<'a>>,
}

/// A cell triangle as read: its six node tags, its domain and the line it is on.
type TaggedTriangle = ([usize; 6], Domain, usize);

/// An entity of `$Entities`: its tag, its physical tags and its line.
type Entity = (i64, Vec<i64>, usize);

/// A physical group: dimension, tag, name (lower case) and the cell domain it names.
type PhysicalName = (u32, i64, String, Option<Domain>);

impl<'a> MshFile<'a> {
    /// Splits `text` into `$Name … $EndName` sections and checks its format.
    fn open(text: &'a str, path: &'a str) -> Result<Self, MeshError> {
        let err = |line: usize, message: String| MeshError::Format {
            path: path.to_string(),
            line,
            message,
        };
        let mut sections: Vec<Section> = Vec::new();
        let mut cur: Option<Section> = None;
        for (i, raw) in text.lines().enumerate() {
            let l = raw.trim();
            if let Some(name) = l.strip_prefix("$End") {
                match cur.take() {
                    Some(s) if s.name == name => sections.push(s),
                    _ => return Err(err(i + 1, format!("unexpected `{l}`"))),
                }
            } else if let Some(name) = l.strip_prefix('$') {
                if let Some(s) = &cur {
                    return Err(err(i + 1, format!("section ${} not closed", s.name)));
                }
                cur = Some(Section {
                    name,
                    first_line: i + 2,
                    lines: Vec::new(),
                });
            } else if let Some(s) = cur.as_mut() {
                s.lines.push(raw);
            }
        }
        if let Some(s) = cur {
            return Err(err(0, format!("section ${} not closed", s.name)));
        }
        let file = MshFile { path, sections };
        file.check_format()?;
        Ok(file)
    }

    fn err(&self, line: usize, message: String) -> MeshError {
        MeshError::Format {
            path: self.path.to_string(),
            line,
            message,
        }
    }

    fn find(&self, name: &str) -> Option<&Section<'a>> {
        self.sections.iter().find(|s| s.name == name)
    }

    /// `$MeshFormat`: version 4.1, ASCII.
    fn check_format(&self) -> Result<(), MeshError> {
        let fmt = self
            .find("MeshFormat")
            .ok_or_else(|| self.err(0, "no $MeshFormat".into()))?;
        let mut t = Tokens::new(self.path, fmt);
        let version: String = t.next("the format version")?;
        let file_type: u32 = t.next("the file type")?;
        if !version.starts_with("4.1") || file_type != 0 {
            return Err(self.err(
                fmt.first_line,
                format!("need gmsh format 4.1 ASCII, found {version} type {file_type}"),
            ));
        }
        Ok(())
    }

    /// `$PhysicalNames` (dim tag "name"), each with the cell domain its name is, if any.
    fn physical_names(&self) -> Result<Vec<PhysicalName>, MeshError> {
        let mut out = Vec::new();
        if let Some(sec) = self.find("PhysicalNames") {
            for (i, l) in sec.lines.iter().enumerate().skip(1) {
                let line = sec.first_line + i;
                let mut parts = l.splitn(3, char::is_whitespace);
                let dim = parts.next().and_then(|s| s.parse::<u32>().ok());
                let tag = parts.next().and_then(|s| s.parse::<i64>().ok());
                let name = parts
                    .next()
                    .map(|s| s.trim().trim_matches('"').to_lowercase());
                let (Some(dim), Some(tag), Some(name)) = (dim, tag, name) else {
                    return Err(self.err(line, format!("cannot read physical name `{l}`")));
                };
                let d = match name.as_str() {
                    "nucleus" => Some(Domain::Nucleus),
                    "cytoplasm" => Some(Domain::Cytoplasm),
                    "membrane" => Some(Domain::Membrane),
                    _ => None,
                };
                out.push((dim, tag, name, d));
            }
        }
        Ok(out)
    }

    /// `$PhysicalNames` (dim tag "name"): the 2-D physical tags of the three domains.
    fn physical_domains(&self) -> Result<HashMap<i64, Domain>, MeshError> {
        let mut phys_domain: HashMap<i64, Domain> = HashMap::new();
        for (dim, tag, _, d) in self.physical_names()? {
            if let (2, Some(d)) = (dim, d) {
                phys_domain.insert(tag, d);
            }
        }
        if phys_domain.len() < 3 {
            return Err(self.err(
                0,
                "need 2-D physical groups named nucleus, cytoplasm and membrane".into(),
            ));
        }
        Ok(phys_domain)
    }

    /// `$Elements`: the 6-node triangles on cell surfaces.
    fn cell_triangles(
        &self,
        surface_domain: &HashMap<i64, Domain>,
    ) -> Result<Vec<TaggedTriangle>, MeshError> {
        let mut tri_tags: Vec<TaggedTriangle> = Vec::new();
        let block = |dim: u32, tag: i64, etype: u32, line: usize| {
            if !matches!(etype, 1 | 2 | 3 | 8 | 9 | 15) {
                return Err(self.err(line, format!("unsupported element type {etype}")));
            }
            if etype == TRIANGLE3 {
                return Err(self.err(line, "3-node triangles: the model needs 6-node (P2)".into()));
            }
            if dim != 2 || etype != TRIANGLE6 {
                return Ok(None);
            }
            let d = surface_domain.get(&tag).ok_or_else(|| {
                self.err(
                    line,
                    format!("surface {tag} is in no cell domain physical group"),
                )
            })?;
            Ok(Some(*d))
        };
        self.elements(block, |d: &Domain, nodes, line| {
            tri_tags.push((std::array::from_fn(|k| nodes[k]), *d, line));
        })?;
        if tri_tags.is_empty() {
            return Err(self.err(0, "no 6-node triangles".into()));
        }
        Ok(tri_tags)
    }

    /// Renumbers the triangles' nodes: vertices first, then mid-nodes, in order of first
    /// use. Returns (nodes, number of vertices, elements, domains).
    #[allow(clippy::type_complexity)]
    fn renumber(
        &self,
        tri_tags: &[TaggedTriangle],
        coord: &HashMap<usize, [f64; 2]>,
    ) -> Result<(Vec<[f64; 2]>, usize, Vec<[usize; 6]>, Vec<Domain>), MeshError> {
        let mut vid: HashMap<usize, usize> = HashMap::new();
        let mut nodes: Vec<[f64; 2]> = Vec::new();
        let mut get = |tag: usize, line: usize, nodes: &mut Vec<[f64; 2]>| {
            if let Some(&i) = vid.get(&tag) {
                return Ok(i);
            }
            let p = coord
                .get(&tag)
                .ok_or_else(|| self.err(line, format!("element uses unknown node {tag}")))?;
            nodes.push(*p);
            vid.insert(tag, nodes.len() - 1);
            Ok(nodes.len() - 1)
        };
        let mut elements = Vec::with_capacity(tri_tags.len());
        let mut domains = Vec::with_capacity(tri_tags.len());
        for (tags, _, line) in tri_tags {
            let mut el = [0usize; 6];
            for k in 0..3 {
                el[k] = get(tags[k], *line, &mut nodes)?;
            }
            elements.push(el);
        }
        let n_vertices = nodes.len();
        for ((tags, d, line), el) in tri_tags.iter().zip(elements.iter_mut()) {
            for k in 3..6 {
                let i = get(tags[k], *line, &mut nodes)?;
                if i < n_vertices {
                    return Err(self.err(
                        *line,
                        format!("node {} is both vertex and mid-node", tags[k]),
                    ));
                }
                el[k] = i;
            }
            domains.push(*d);
        }
        Ok((nodes, n_vertices, elements, domains))
    }
}

/// A cell tetrahedron as read: its ten node tags, its domain and the line it is on.
type TaggedTet = ([usize; 10], Domain, usize);
/// An outer triangle as read: its six node tags and its line.
type TaggedFace = ([usize; 6], usize);

impl<'a> MshFile<'a> {
    /// `$PhysicalNames` of a 3-D cell mesh: the 3-D physical tags of the three domains, and
    /// the 2-D physical tags named `outer`.
    fn tet_physical_groups(&self) -> Result<(HashMap<i64, Domain>, HashSet<i64>), MeshError> {
        let mut domains: HashMap<i64, Domain> = HashMap::new();
        let mut outer: HashSet<i64> = HashSet::new();
        for (dim, tag, name, d) in self.physical_names()? {
            match (dim, d) {
                (3, Some(d)) => {
                    domains.insert(tag, d);
                }
                (2, None) if name == "outer" => {
                    outer.insert(tag);
                }
                _ => {}
            }
        }
        let found: HashSet<Domain> = domains.values().copied().collect();
        if found.len() < 3 {
            return Err(self.err(
                0,
                "need 3-D physical groups named nucleus, cytoplasm and membrane".into(),
            ));
        }
        if outer.is_empty() {
            return Err(self.err(0, "need a 2-D physical group named outer".into()));
        }
        Ok((domains, outer))
    }

    /// `$Entities` of all four dimensions: for each dimension, in file order, the entities'
    /// tags, their physical tags and their lines.
    fn entity_physicals(&self) -> Result<[Vec<Entity>; 4], MeshError> {
        let ent = self
            .find("Entities")
            .ok_or_else(|| self.err(0, "no $Entities".into()))?;
        let mut t = Tokens::new(self.path, ent);
        let counts: [usize; 4] = [
            t.next("the number of points")?,
            t.next("the number of curves")?,
            t.next("the number of surfaces")?,
            t.next("the number of volumes")?,
        ];
        let mut out: [Vec<Entity>; 4] = Default::default();
        for (dim, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                let line = t.line();
                let tag: i64 = t.next("an entity tag")?;
                let n_coords = if dim == 0 { 3 } else { 6 };
                for _ in 0..n_coords {
                    t.next::<f64>("an entity coordinate")?;
                }
                let n_phys: usize = t.next("the number of physical tags")?;
                let mut phys = Vec::with_capacity(n_phys);
                for _ in 0..n_phys {
                    phys.push(t.next::<i64>("a physical tag")?);
                }
                if dim > 0 {
                    let n_b: usize = t.next("the number of bounding entities")?;
                    for _ in 0..n_b {
                        t.next::<i64>("a bounding entity tag")?;
                    }
                }
                out[dim].push((tag, phys, line));
            }
        }
        Ok(out)
    }

    /// The cell domain of each entity of `entities` (one dimension's, from
    /// [`MshFile::entity_physicals`]) through its physical tags `phys_domain`; an entity in
    /// two domains is refused (`what` names the entities in the message).
    fn entity_domains(
        &self,
        entities: &[Entity],
        phys_domain: &HashMap<i64, Domain>,
        what: &str,
    ) -> Result<HashMap<i64, Domain>, MeshError> {
        let mut out = HashMap::new();
        for (tag, phys, line) in entities {
            let doms: HashSet<Domain> = phys
                .iter()
                .filter_map(|p| phys_domain.get(p))
                .copied()
                .collect();
            match doms.len() {
                0 => {}
                1 => out.extend(doms.into_iter().map(|d| (*tag, d))),
                _ => {
                    let message = format!("{what} {tag} is in more than one cell domain");
                    return Err(self.err(*line, message));
                }
            }
        }
        Ok(out)
    }

    /// `$Nodes` with three coordinates: (tag, x) in file order.
    fn node_coordinates(&self) -> Result<Vec<(usize, [f64; 3])>, MeshError> {
        let sec = self
            .find("Nodes")
            .ok_or_else(|| self.err(0, "no $Nodes".into()))?;
        let mut t = Tokens::new(self.path, sec);
        let n_blocks: usize = t.next("the number of node blocks")?;
        let n_nodes: usize = t.next("the number of nodes")?;
        let _min_tag: usize = t.next("the minimum node tag")?;
        let _max_tag: usize = t.next("the maximum node tag")?;
        let mut out = Vec::with_capacity(n_nodes.min(1 << 24));
        for _ in 0..n_blocks {
            let _dim: u32 = t.next("a block's entity dimension")?;
            let _tag: i64 = t.next("a block's entity tag")?;
            let parametric: u32 = t.next("the parametric flag")?;
            let n: usize = t.next("a block's node count")?;
            if parametric != 0 {
                return Err(self.err(t.line(), "parametric nodes are not supported".into()));
            }
            let mut tags = Vec::with_capacity(n.min(1 << 24));
            for _ in 0..n {
                tags.push(t.next::<usize>("a node tag")?);
            }
            for tag in tags {
                let line = t.line();
                let p = [
                    t.next::<f64>("a node x")?,
                    t.next::<f64>("a node y")?,
                    t.next::<f64>("a node z")?,
                ];
                if !p.iter().all(|v| v.is_finite()) {
                    return Err(self.err(line, format!("node {tag} has a non-finite coordinate")));
                }
                out.push((tag, p));
            }
        }
        Ok(out)
    }

    /// `$Elements`: the 10-node tetrahedra of the cell volumes and the 6-node triangles of
    /// the outer surfaces.
    fn cell_tets(
        &self,
        volume_domain: &HashMap<i64, Domain>,
        outer_surfaces: &HashSet<i64>,
    ) -> Result<(Vec<TaggedTet>, Vec<TaggedFace>), MeshError> {
        let mut tets: Vec<TaggedTet> = Vec::new();
        let mut faces: Vec<TaggedFace> = Vec::new();
        // Some(domain) for the tetrahedra of a cell volume, None for an outer surface.
        let block = |dim: u32, tag: i64, etype: u32, line: usize| {
            let dom = if dim == 3 {
                volume_domain.get(&tag).copied()
            } else {
                None
            };
            if dim == 3 && (etype == TET10 || etype == TET4) && dom.is_none() {
                return Err(self.err(
                    line,
                    format!("volume {tag} is in no cell domain physical group"),
                ));
            }
            if etype == TET4 && dom.is_some() {
                return Err(self.err(
                    line,
                    "4-node tetrahedra: the model needs 10-node (P2)".into(),
                ));
            }
            let is_face = dim == 2 && etype == TRIANGLE6 && outer_surfaces.contains(&tag);
            if dim == 2 && etype == TRIANGLE3 && outer_surfaces.contains(&tag) {
                return Err(self.err(line, "3-node triangles: the model needs 6-node (P2)".into()));
            }
            Ok(match dom {
                Some(d) if etype == TET10 => Some(Some(d)),
                _ => is_face.then_some(None),
            })
        };
        self.elements(block, |dom: &Option<Domain>, nodes, line| match dom {
            Some(d) => tets.push((nodes, *d, line)),
            None => faces.push((std::array::from_fn(|k| nodes[k]), line)),
        })?;
        if tets.is_empty() {
            return Err(self.err(0, "no 10-node tetrahedra in the cell volumes".into()));
        }
        if faces.is_empty() {
            return Err(self.err(0, "no 6-node triangles in the outer surface".into()));
        }
        Ok((tets, faces))
    }

    /// `$Elements`, block by block: `block(dimension, entity tag, element type, line)`
    /// refuses the block, or says whether its elements are wanted and as what (`K`); each
    /// wanted element's first ten node tags go to `element(kind, nodes, line)`.
    fn elements<K>(
        &self,
        mut block: impl FnMut(u32, i64, u32, usize) -> Result<Option<K>, MeshError>,
        mut element: impl FnMut(&K, [usize; 10], usize),
    ) -> Result<(), MeshError> {
        let sec = self
            .find("Elements")
            .ok_or_else(|| self.err(0, "no $Elements".into()))?;
        let mut t = Tokens::new(self.path, sec);
        let n_blocks: usize = t.next("the number of element blocks")?;
        for _ in 0..3 {
            t.next::<usize>("an element count or tag")?;
        }
        for _ in 0..n_blocks {
            let line = t.line();
            let dim: u32 = t.next("a block's entity dimension")?;
            let tag: i64 = t.next("a block's entity tag")?;
            let etype: u32 = t.next("a block's element type")?;
            let n: usize = t.next("a block's element count")?;
            let per = element_nodes(etype)
                .ok_or_else(|| self.err(line, format!("unsupported element type {etype}")))?;
            let kind = block(dim, tag, etype, line)?;
            for _ in 0..n {
                let eline = t.line();
                let _etag: usize = t.next("an element tag")?;
                let mut nodes = [0usize; 10];
                for k in 0..per {
                    let v: usize = t.next("an element node")?;
                    if let Some(slot) = nodes.get_mut(k) {
                        *slot = v;
                    }
                }
                if let Some(kind) = &kind {
                    element(kind, nodes, eline);
                }
            }
        }
        Ok(())
    }
}

/// Once the parameters' `validation` passed, the file at `path` parsed by
/// `parse(text, name for messages)`.
fn read_file<M>(
    path: &Path,
    validation: Result<(), MeshError>,
    parse: impl FnOnce(&str, &str) -> Result<M, MeshError>,
) -> Result<M, MeshError> {
    validation?;
    let pstr = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, &pstr),
        Err(source) => Err(MeshError::Io { path: pstr, source }),
    }
}

impl TetMesh {
    /// Reads a gmsh 4.1 ASCII mesh of 10-node tetrahedra with physical volume groups named
    /// `nucleus`, `cytoplasm`, `membrane` and the 6-node triangles of the physical surface
    /// `outer`, and completes it for the cell `params` (see [`super::mesh::quarter_cell`]: the checks
    /// against the cell, the symmetry planes, the named points, the Jacobians).
    pub fn read_gmsh(path: &Path, params: &TetMeshParams) -> Result<TetMesh, MeshError> {
        read_file(path, params.validate(), |text, name| {
            Self::parse_gmsh(text, name, params)
        })
    }

    /// As [`TetMesh::read_gmsh`], from the file's text (`path` is only used in messages).
    pub fn parse_gmsh(
        text: &str,
        path: &str,
        params: &TetMeshParams,
    ) -> Result<TetMesh, MeshError> {
        let file = MshFile::open(text, path)?;
        let (phys_domain, phys_outer) = file.tet_physical_groups()?;
        let entities = file.entity_physicals()?;
        let volume_domain = file.entity_domains(&entities[3], &phys_domain, "volume")?;
        let outer_surfaces: HashSet<i64> = entities[2]
            .iter()
            .filter(|(_, phys, _)| phys.iter().any(|p| phys_outer.contains(p)))
            .map(|(tag, _, _)| *tag)
            .collect();
        let coords = file.node_coordinates()?;
        let (tets, faces) = file.cell_tets(&volume_domain, &outer_surfaces)?;
        // Compact numbering of the nodes the tetrahedra use, in file order.
        let used: HashSet<usize> = tets.iter().flat_map(|t| t.0).collect();
        let mut index: HashMap<usize, usize> = HashMap::with_capacity(used.len());
        let mut nodes = Vec::with_capacity(used.len());
        for (tag, p) in coords {
            if used.contains(&tag) && !index.contains_key(&tag) {
                index.insert(tag, nodes.len());
                nodes.push(p);
            }
        }
        let lookup = |tag: usize, line: usize| {
            index
                .get(&tag)
                .copied()
                .ok_or_else(|| file.err(line, format!("element uses unknown node {tag}")))
        };
        let mut elements = Vec::with_capacity(tets.len());
        let mut domains = Vec::with_capacity(tets.len());
        for (tags, d, line) in &tets {
            let mut el = [0usize; 10];
            for k in 0..10 {
                el[k] = lookup(tags[k], *line)?;
            }
            if (0..4).any(|a| (a + 1..4).any(|b| el[a] == el[b])) {
                return Err(file.err(*line, "degenerate tetrahedron (repeated vertex)".into()));
            }
            elements.push(el);
            domains.push(*d);
        }
        let mut outer = Vec::with_capacity(faces.len());
        for (tags, line) in &faces {
            let mut f = [0usize; 6];
            for k in 0..6 {
                f[k] = index.get(&tags[k]).copied().ok_or_else(|| {
                    file.err(
                        *line,
                        format!(
                            "outer triangle node {} is not a node of the tetrahedra",
                            tags[k]
                        ),
                    )
                })?;
            }
            outer.push((f, *line));
        }
        TetMesh::from_parts(params, nodes, elements, domains, &outer, path)
    }
}

impl Mesh {
    /// Reads a gmsh 4.1 ASCII mesh of 6-node triangles with physical surface groups named
    /// `nucleus`, `cytoplasm`, `membrane`.
    ///
    /// `params` gives the geometry the mesh is meant to fit (centre and radii; the size
    /// fields are not used): the outer edges are the boundary edges with both end vertices
    /// within 1e-6 · r_c of the circle r = r_c; the symmetry nodes are those within that
    /// tolerance of x = c_x, and are snapped onto it exactly; the named points must be
    /// vertices within that tolerance of their positions. Elements given clockwise are
    /// reordered; every element's Jacobian is checked.
    pub fn read_gmsh(path: &Path, params: &MeshParams) -> Result<Mesh, MeshError> {
        read_file(path, params.validate(), |text, name| {
            Self::parse_gmsh(text, name, params)
        })
    }

    /// As [`Mesh::read_gmsh`], from the file's text (`path` is only used in messages).
    pub fn parse_gmsh(text: &str, path: &str, params: &MeshParams) -> Result<Mesh, MeshError> {
        let file = MshFile::open(text, path)?;
        let entities = file.entity_physicals()?;
        let surface_domain =
            file.entity_domains(&entities[2], &file.physical_domains()?, "surface")?;
        let coord: HashMap<usize, [f64; 2]> = file
            .node_coordinates()?
            .into_iter()
            .map(|(tag, p)| (tag, [p[0], p[1]]))
            .collect();
        let triangles = file.cell_triangles(&surface_domain)?;
        let (nodes, n_vertices, elements, domains) = file.renumber(&triangles, &coord)?;
        Self::assemble_from_elements(params, nodes, n_vertices, elements, domains, path)
    }

    /// Completes a mesh read from a file: orientation, snapping to x = c_x, boundary and
    /// interface edges, named points, Jacobian check.
    fn assemble_from_elements(
        params: &MeshParams,
        mut nodes: Vec<[f64; 2]>,
        n_vertices: usize,
        mut elements: Vec<[usize; 6]>,
        domains: Vec<Domain>,
        path: &str,
    ) -> Result<Mesh, MeshError> {
        let ferr = |message: String| MeshError::Format {
            path: path.to_string(),
            line: 0,
            message,
        };
        let c = params.center;
        let tol = 1e-6 * params.r_c;
        for el in elements.iter_mut() {
            let p = [nodes[el[0]], nodes[el[1]], nodes[el[2]]];
            let a2 = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
            if a2 < 0.0 {
                *el = [el[0], el[2], el[1], el[5], el[4], el[3]];
            }
        }
        for p in nodes.iter_mut() {
            if (p[0] - c[0]).abs() <= tol {
                p[0] = c[0];
            }
        }
        // Edges → (uses, mid-node, domains on each side).
        let mut edges: HashMap<(usize, usize), (usize, usize, Vec<Domain>)> = HashMap::new();
        for (el, d) in elements.iter().zip(&domains) {
            for ed in EDGES {
                let (a, b) = (el[ed[0]], el[ed[2]]);
                let entry = edges
                    .entry((a.min(b), a.max(b)))
                    .or_insert((0, el[ed[1]], Vec::new()));
                entry.0 += 1;
                entry.2.push(*d);
                if entry.1 != el[ed[1]] {
                    return Err(ferr(format!("edge {a}–{b} has two different mid-nodes")));
                }
            }
        }
        let ang = |n: usize| (nodes[n][1] - c[1]).atan2(nodes[n][0] - c[0]);
        let radius = |n: usize| (nodes[n][0] - c[0]).hypot(nodes[n][1] - c[1]);
        let ordered = |mut list: Vec<[usize; 3]>| {
            for e in list.iter_mut() {
                if ang(e[0]) > ang(e[2]) {
                    *e = [e[2], e[1], e[0]];
                }
            }
            list.sort_by(|a, b| ang(a[0]).total_cmp(&ang(b[0])));
            list
        };
        let mut outer = Vec::new();
        let mut nucleus = Vec::new();
        let mut inner = Vec::new();
        for (&(a, b), (uses, m, ds)) in &edges {
            let e = [a, *m, b];
            if *uses == 1 {
                if (radius(a) - params.r_c).abs() <= tol && (radius(b) - params.r_c).abs() <= tol {
                    outer.push(e);
                } else if !(nodes[a][0] == c[0] && nodes[b][0] == c[0]) {
                    return Err(ferr(format!(
                        "boundary edge {:?}–{:?} is neither on r = r_c nor on x = c_x",
                        nodes[a], nodes[b]
                    )));
                }
            } else if ds.contains(&Domain::Nucleus) && ds.contains(&Domain::Cytoplasm) {
                nucleus.push(e);
            } else if ds.contains(&Domain::Cytoplasm) && ds.contains(&Domain::Membrane) {
                inner.push(e);
            }
        }
        let circles = [ordered(outer), ordered(nucleus), ordered(inner)];
        Mesh::assemble(
            MeshParts::new(params, nodes, n_vertices, elements, domains, circles),
            |nodes, y, what| {
                (0..n_vertices)
                    .find(|&n| (nodes[n][0] - c[0]).abs() <= tol && (nodes[n][1] - y).abs() <= tol)
                    .ok_or_else(|| ferr(format!("no vertex at the {what} (x = {}, y = {y})", c[0])))
            },
        )
    }

    /// The mesh as gmsh 4.1 ASCII text: one surface per domain (tags 1, 2, 3 for nucleus,
    /// cytoplasm, membrane, with physical groups of the same names), all nodes in one
    /// block, 6-node triangles. [`Mesh::read_gmsh`] reads it back.
    pub fn to_gmsh(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "$MeshFormat\n4.1 0 8\n$EndMeshFormat");
        let _ = writeln!(
            s,
            "$PhysicalNames\n3\n2 1 \"nucleus\"\n2 2 \"cytoplasm\"\n2 3 \"membrane\"\n$EndPhysicalNames"
        );
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &self.nodes {
            for i in 0..2 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        let _ = writeln!(s, "$Entities\n0 0 3 0");
        for tag in 1..=3 {
            let _ = writeln!(
                s,
                "{tag} {:e} {:e} 0 {:e} {:e} 0 1 {tag} 0",
                lo[0], lo[1], hi[0], hi[1]
            );
        }
        let _ = writeln!(s, "$EndEntities");
        let n = self.nodes.len();
        let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}");
        for i in 1..=n {
            let _ = writeln!(s, "{i}");
        }
        for p in &self.nodes {
            // {:?} prints the shortest representation that round-trips exactly.
            let _ = writeln!(s, "{:?} {:?} 0", p[0], p[1]);
        }
        let _ = writeln!(s, "$EndNodes");
        let ne = self.elements.len();
        let _ = writeln!(s, "$Elements\n3 {ne} 1 {ne}");
        let mut tag = 0;
        for (k, d) in Domain::ALL.iter().enumerate() {
            let els = self.elements_of(*d);
            let _ = writeln!(s, "2 {} {TRIANGLE6} {}", k + 1, els.len());
            for e in els {
                tag += 1;
                let el = self.elements[e];
                let _ = writeln!(
                    s,
                    "{tag} {} {} {} {} {} {}",
                    el[0] + 1,
                    el[1] + 1,
                    el[2] + 1,
                    el[3] + 1,
                    el[4] + 1,
                    el[5] + 1
                );
            }
        }
        let _ = writeln!(s, "$EndElements");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::CellMesh;

    #[test]
    fn round_trip_through_gmsh_text() {
        let p = crate::fem::reference::mesh_params();
        let m = Mesh::generate(&p).expect("mesh");
        let text = m.to_gmsh();
        let r = Mesh::parse_gmsh(&text, "mem.msh", &p).expect("read back");
        assert_eq!(r.n_elements(), m.n_elements());
        assert_eq!(r.n_nodes(), m.n_nodes());
        assert_eq!(r.n_vertices, m.n_vertices);
        for d in Domain::ALL {
            let (a, b) = (r.area(Some(d)), m.area(Some(d)));
            assert!((a - b).abs() < 1e-12 * b, "{d}: {a} vs {b}");
            assert_eq!(r.elements_of(d).len(), m.elements_of(d).len());
        }
        let pos = |mesh: &Mesh, n: usize| mesh.nodes[n];
        assert_eq!(pos(&r, r.points.centre), pos(&m, m.points.centre));
        assert_eq!(pos(&r, r.points.cell_bottom), [0.0, -1.5]);
        assert_eq!(pos(&r, r.points.nucleus_top), [0.0, 13.5]);
        assert_eq!(r.symmetry_nodes.len(), m.symmetry_nodes.len());
        for (list_r, list_m) in [
            (&r.outer_edges, &m.outer_edges),
            (&r.nucleus_edges, &m.nucleus_edges),
            (&r.membrane_inner_edges, &m.membrane_inner_edges),
        ] {
            assert_eq!(list_r.len(), list_m.len());
            for (a, b) in list_r.iter().zip(list_m.iter()) {
                for k in 0..3 {
                    assert_eq!(r.nodes[a[k]], m.nodes[b[k]]);
                }
            }
        }
    }

    #[test]
    fn clockwise_elements_are_reoriented() {
        let p = crate::fem::reference::mesh_params();
        let m = Mesh::generate(&p).expect("mesh");
        // Flip every element's orientation in the file.
        let text = m.to_gmsh();
        let mut out = String::new();
        let mut in_elements = false;
        for l in text.lines() {
            if l == "$Elements" {
                in_elements = true;
            } else if l == "$EndElements" {
                in_elements = false;
            }
            let f: Vec<&str> = l.split(' ').collect();
            if in_elements && f.len() == 7 {
                let _ = writeln!(
                    out,
                    "{} {} {} {} {} {} {}",
                    f[0], f[1], f[3], f[2], f[6], f[5], f[4]
                );
            } else {
                let _ = writeln!(out, "{l}");
            }
        }
        let r = Mesh::parse_gmsh(&out, "flipped.msh", &p).expect("read");
        assert!(r.check_jacobians().is_ok());
        assert!((r.area(None) - m.area(None)).abs() < 1e-12 * m.area(None));
    }

    #[test]
    fn malformed_files_are_refused_with_a_line_number() {
        let p = crate::fem::reference::mesh_params();
        let m = Mesh::generate(&p).expect("mesh");
        let good = m.to_gmsh();
        // Wrong version.
        let bad = good.replacen("4.1 0 8", "2.2 0 8", 1);
        assert!(matches!(
            Mesh::parse_gmsh(&bad, "v.msh", &p),
            Err(MeshError::Format { line: 2, .. })
        ));
        // Missing physical group.
        let bad = good.replacen("2 3 \"membrane\"", "2 3 \"skin\"", 1);
        let e = Mesh::parse_gmsh(&bad, "g.msh", &p).expect_err("no membrane");
        assert!(e.to_string().contains("membrane"), "{e}");
        // A corrupt node coordinate: the message names its line.
        let line = good.lines().position(|l| l == "$EndNodes").expect("nodes") - 3;
        let mut lines: Vec<&str> = good.lines().collect();
        lines[line] = "0.5 oops 0";
        let bad = lines.join("\n");
        match Mesh::parse_gmsh(&bad, "n.msh", &p) {
            Err(MeshError::Format {
                line: l, message, ..
            }) => {
                assert_eq!(l, line + 1, "{message}");
                assert!(message.contains("oops"));
            }
            other => panic!("expected a format error, got {other:?}"),
        }
        // Linear triangles.
        let bad = good.replacen("2 1 9 ", "2 1 2 ", 1);
        let e = Mesh::parse_gmsh(&bad, "l.msh", &p).expect_err("linear");
        assert!(e.to_string().contains("6-node"), "{e}");
        // A mesh of another cell does not fit the parameters.
        let other = MeshParams { r_c: 10.5, ..p };
        assert!(Mesh::parse_gmsh(&good, "o.msh", &other).is_err());
        // Missing file.
        assert!(matches!(
            Mesh::read_gmsh(
                Path::new("/nonexistent/cell.msh"),
                &crate::fem::reference::mesh_params()
            ),
            Err(MeshError::Io { .. })
        ));
    }
}
