//! Reader of Gmsh MSH 4.1 ASCII meshes.
//!
//! Solid elements: 4-node (type 4) and 10-node (11) tetrahedra, 8-node (5) and 20-node (17)
//! hexahedra; node order is Gmsh's, which is also ours. Lower-dimensional elements (points,
//! lines, triangles, quadrangles, of any order) only carry physical groups. Every physical group
//! becomes a node set (all nodes of its elements) named by `$PhysicalNames`, or `"<dim>:<tag>"`
//! when unnamed; volume groups also become element sets. Unknown sections are skipped.
//! Binary files and older format versions are refused with a message saying what to do.

use super::collect::DeckError;
use super::{ElementBlock, Mesh};
use crate::scene::spec::ElementKind;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Nodes per element for the Gmsh element types we accept as carriers of physical groups.
fn nodes_per_type(t: u32) -> Option<usize> {
    Some(match t {
        15 => 1,  // point
        1 => 2,   // line
        8 => 3,   // line3
        2 => 3,   // triangle
        9 => 6,   // triangle6
        3 => 4,   // quadrangle
        16 => 8,  // quadrangle8
        10 => 9,  // quadrangle9
        4 => 4,   // tetrahedron
        11 => 10, // tetrahedron10
        5 => 8,   // hexahedron
        17 => 20, // hexahedron20
        12 => 27, // hexahedron27 (refused below)
        6 => 6,   // prism
        7 => 5,   // pyramid
        _ => return None,
    })
}

struct Lines<'a> {
    path: &'a Path,
    it: std::iter::Enumerate<std::str::Lines<'a>>,
    line: usize,
    /// Number of lines in the file.
    total: usize,
}

impl<'a> Lines<'a> {
    fn err(&self, msg: impl Into<String>) -> DeckError {
        DeckError {
            path: self.path.to_path_buf(),
            line: self.line,
            msg: msg.into(),
        }
    }
    fn next_line(&mut self) -> Result<&'a str, DeckError> {
        for (i, l) in self.it.by_ref() {
            self.line = i + 1;
            let t = l.trim();
            if !t.is_empty() {
                return Ok(t);
            }
        }
        Err(self.err("unexpected end of file"))
    }
    fn numbers<T: std::str::FromStr>(&mut self, what: &str) -> Result<Vec<T>, DeckError> {
        let l = self.next_line()?;
        l.split_whitespace()
            .map(|w| {
                w.parse::<T>()
                    .map_err(|_| self.err(format!("expected {what}, found '{w}'")))
            })
            .collect()
    }
    /// Lines left after the current one (an upper bound of the records still to come).
    fn remaining(&self) -> usize {
        self.total.saturating_sub(self.line)
    }
    /// Checks a count read from the file against what the rest of the file can hold:
    /// non-negative, and at most the remaining lines divided by the lines each record takes.
    fn count(&self, value: i64, lines_each: usize, what: &str) -> Result<usize, DeckError> {
        if value < 0 {
            return Err(self.err(format!("{what} is {value}, expected a count >= 0")));
        }
        let room = self.remaining() / lines_each.max(1);
        if value as u64 > room as u64 {
            return Err(self.err(format!(
                "{what} is {value}, but only {} lines follow (a record takes {lines_each}): the count does not match the file",
                self.remaining()
            )));
        }
        Ok(value as usize)
    }
    fn expect(&mut self, tag: &str) -> Result<(), DeckError> {
        let l = self.next_line()?;
        if l != tag {
            return Err(self.err(format!("expected '{tag}', found '{l}'")));
        }
        Ok(())
    }
}

fn need<T: Copy>(v: &[T], n: usize, lines: &Lines, what: &str) -> Result<(), DeckError> {
    if v.len() < n {
        return Err(lines.err(format!("expected {n} numbers ({what}), found {}", v.len())));
    }
    Ok(())
}

/// Reads an MSH 4.1 file from disk (a regular file of at most [`crate::files::LIMIT_MESH`] bytes).
pub fn read(path: &Path) -> Result<Mesh, DeckError> {
    let text = super::collect::read_mesh_text(
        path,
        "the reader takes ASCII MSH 4.1 (binary MSH: save as ASCII, Gmsh -format msh41 with Mesh.Binary = 0)",
    )?;
    parse(path, &text)
}

/// What the sections of a file hold, before the mesh is assembled from them.
#[derive(Default)]
struct Sections {
    /// (dim, physical tag) -> name
    names: HashMap<(i32, i32), String>,
    /// (dim, entity tag) -> physical tags
    entity_phys: HashMap<(i32, i32), Vec<i32>>,
    /// Gmsh node tag -> our node index
    node_id: HashMap<usize, usize>,
    /// Tags of the solid elements read (a tag given twice is refused)
    solid_tags: std::collections::HashSet<usize>,
    nodes: Vec<[f64; 3]>,
    blocks: Vec<Block>,
    saw_format: bool,
    saw_nodes: bool,
    saw_elements: bool,
}

/// One element block: entity dimension and tag, Gmsh type, node indices, nodes per element.
struct Block {
    dim: i32,
    entity: i32,
    gmsh_type: u32,
    conn: Vec<usize>,
    nodes_per: usize,
    /// The line of each element (solid blocks only).
    lines: Vec<u32>,
}

/// Skips a section linercav does not read, from its header `h` to `$End...`; a file that ends
/// first is refused at the header, saying whether it is a section read here misspelt in
/// case (`$nodes`: the names are case-sensitive).
fn skip_section(lines: &mut Lines<'_>, h: &str) -> Result<(), DeckError> {
    let start = lines.line;
    let end = format!("$End{}", &h[1..]);
    loop {
        match lines.next_line() {
            Ok(l) if l == end => return Ok(()),
            Ok(_) => {}
            Err(_) => {
                lines.line = start;
                let known = [
                    "$MeshFormat",
                    "$PhysicalNames",
                    "$Entities",
                    "$Nodes",
                    "$Elements",
                ];
                let hint = known
                    .iter()
                    .find(|k| k.eq_ignore_ascii_case(h))
                    .map(|k| format!(" (section names are case-sensitive: '{k}')"))
                    .unwrap_or_default();
                return Err(lines.err(format!(
                    "section '{h}'{hint} has no '{end}' before the end of the file"
                )));
            }
        }
    }
}

/// Parses MSH 4.1 ASCII text; `path` is used in messages only.
pub fn parse(path: &Path, text: &str) -> Result<Mesh, DeckError> {
    let mut lines = Lines {
        path,
        it: text.lines().enumerate(),
        line: 0,
        total: text.lines().count(),
    };
    let mut s = Sections::default();
    while let Ok(l) = lines.next_line() {
        match l {
            "$MeshFormat" => read_format(&mut lines, &mut s)?,
            "$PhysicalNames" => read_physical_names(&mut lines, &mut s)?,
            "$Entities" => read_entities(&mut lines, &mut s)?,
            "$Nodes" => read_nodes(&mut lines, &mut s)?,
            "$Elements" => read_elements(&mut lines, &mut s)?,
            h if h.starts_with("$End") => {
                return Err(lines.err(format!("unexpected '{h}'")));
            }
            h if h.starts_with('$') => skip_section(&mut lines, h)?,
            other => {
                return Err(lines.err(format!(
                    "expected a section header like '$Nodes', found '{other}'"
                )));
            }
        }
    }
    let whole = |msg: &str| DeckError {
        path: path.to_path_buf(),
        line: 0,
        msg: msg.into(),
    };
    if !s.saw_format {
        return Err(whole("no $MeshFormat section: not a Gmsh MSH file"));
    }
    if !s.saw_nodes || !s.saw_elements {
        return Err(whole("the file needs both $Nodes and $Elements sections"));
    }
    Ok(assemble(s, path))
}

fn read_format(lines: &mut Lines, s: &mut Sections) -> Result<(), DeckError> {
    let h = lines.next_line()?;
    let f: Vec<&str> = h.split_whitespace().collect();
    if f.len() < 3 {
        return Err(lines.err("expected 'version file-type data-size'"));
    }
    if f[0] != "4.1" {
        return Err(lines.err(format!(
            "MSH version {} is not supported: save the mesh as MSH 4.1 (Gmsh: -format msh41)",
            f[0]
        )));
    }
    if f[1] != "0" {
        return Err(lines
            .err("binary MSH is not supported: save the mesh as ASCII MSH 4.1 (Mesh.Binary = 0)"));
    }
    lines.expect("$EndMeshFormat")?;
    s.saw_format = true;
    Ok(())
}

fn read_physical_names(lines: &mut Lines, s: &mut Sections) -> Result<(), DeckError> {
    let n = lines.numbers::<i64>("number of physical names")?;
    need(&n, 1, lines, "count")?;
    for _ in 0..lines.count(n[0], 1, "the number of physical names")? {
        let l = lines.next_line()?;
        let mut it = l.splitn(3, char::is_whitespace);
        let dim = it.next().and_then(|w| w.parse::<i32>().ok());
        let tag = it.next().and_then(|w| w.parse::<i32>().ok());
        let name = it.next().map(|w| w.trim().trim_matches('"').to_string());
        match (dim, tag, name) {
            (Some(d), Some(t), Some(nm)) => {
                s.names.insert((d, t), nm);
            }
            _ => return Err(lines.err("expected 'dim tag \"name\"'")),
        }
    }
    lines.expect("$EndPhysicalNames")
}

fn read_entities(lines: &mut Lines, s: &mut Sections) -> Result<(), DeckError> {
    let c = lines.numbers::<i64>("entity counts")?;
    need(&c, 4, lines, "numPoints numCurves numSurfaces numVolumes")?;
    for (dim, &count) in c.iter().take(4).enumerate() {
        for _ in 0..lines.count(count, 1, "an entity count")? {
            let v = lines.numbers::<f64>("entity record")?;
            // points: tag x y z nphys phys...; others: tag 6 bbox nphys phys...
            let at = if dim == 0 { 4 } else { 7 };
            need(&v, at + 1, lines, "entity record")?;
            let np = v[at];
            if !(np >= 0.0 && np.fract() == 0.0 && np <= (v.len() - at - 1) as f64) {
                return Err(lines.err(format!(
                    "the entity record gives {} physical tags but holds {} numbers after the count",
                    crate::text::num(np),
                    v.len() - at - 1
                )));
            }
            let np = np as usize;
            let tags = v[at + 1..at + 1 + np].iter().map(|&t| t as i32).collect();
            s.entity_phys.insert((dim as i32, v[0] as i32), tags);
        }
    }
    lines.expect("$EndEntities")
}

fn read_nodes(lines: &mut Lines, s: &mut Sections) -> Result<(), DeckError> {
    let h = lines.numbers::<i64>("'numEntityBlocks numNodes minTag maxTag'")?;
    need(
        &h,
        4,
        lines,
        "numEntityBlocks numNodes minNodeTag maxNodeTag",
    )?;
    // each node takes two lines (its tag, its coordinates); each block one more
    let total_nodes = lines.count(h[1], 2, "numNodes")?;
    s.nodes.reserve(total_nodes);
    for _ in 0..lines.count(h[0], 1, "numEntityBlocks")? {
        let b = lines.numbers::<i64>("node block header")?;
        need(
            &b,
            4,
            lines,
            "entityDim entityTag parametric numNodesInBlock",
        )?;
        let parametric = b[2] != 0;
        let count = lines.count(b[3], 2, "numNodesInBlock")?;
        let mut tags = Vec::with_capacity(count);
        for _ in 0..count {
            let t = lines.numbers::<usize>("node tag")?;
            need(&t, 1, lines, "node tag")?;
            tags.push(t[0]);
        }
        for tag in tags {
            let x = lines.numbers::<f64>("node coordinates")?;
            need(&x, if parametric { 4 } else { 3 }, lines, "x y z")?;
            if x.iter().any(|v| !v.is_finite()) {
                return Err(lines.err("node coordinate is not finite"));
            }
            if s.node_id.insert(tag, s.nodes.len()).is_some() {
                return Err(lines.err(format!("node tag {tag} defined twice")));
            }
            s.nodes.push([x[0], x[1], x[2]]);
        }
    }
    lines.expect("$EndNodes")?;
    s.saw_nodes = true;
    Ok(())
}

fn read_elements(lines: &mut Lines, s: &mut Sections) -> Result<(), DeckError> {
    let h = lines.numbers::<i64>("'numEntityBlocks numElements minTag maxTag'")?;
    need(
        &h,
        4,
        lines,
        "numEntityBlocks numElements minElementTag maxElementTag",
    )?;
    lines.count(h[1], 1, "numElements")?;
    for _ in 0..lines.count(h[0], 1, "numEntityBlocks")? {
        let b = lines.numbers::<i64>("element block header")?;
        need(
            &b,
            4,
            lines,
            "entityDim entityTag elementType numElementsInBlock",
        )?;
        let count = lines.count(b[3], 1, "numElementsInBlock")?;
        let (dim, entity) = (b[0] as i32, b[1] as i32);
        let et = u32::try_from(b[2])
            .map_err(|_| lines.err(format!("element type {} is not a Gmsh element type", b[2])))?;
        let nn = nodes_per_type(et)
            .ok_or_else(|| lines.err(format!("unsupported element type {et}")))?;
        if dim == 3 && ElementKind::from_gmsh_type(et).is_none() {
            return Err(lines.err(format!(
                "solid element type {et} is not supported: use 4- or 10-node tetrahedra (4, 11) or 8- or 20-node hexahedra (5, 17)"
            )));
        }
        let mut conn = Vec::with_capacity(count * nn);
        let mut at = Vec::with_capacity(if dim == 3 { count } else { 0 });
        for _ in 0..count {
            let v = lines.numbers::<usize>("element record")?;
            if dim == 3 {
                at.push(super::collect::small(lines.line));
                if !s.solid_tags.insert(v[0]) {
                    return Err(lines.err(format!("element tag {} defined twice", v[0])));
                }
            }
            if v.len() != nn + 1 {
                return Err(lines.err(format!(
                    "element of type {et} needs a tag and {nn} node tags, found {} numbers",
                    v.len()
                )));
            }
            for &t in &v[1..] {
                let id = *s.node_id.get(&t).ok_or_else(|| {
                    lines.err(format!("element refers to undefined node tag {t}"))
                })?;
                conn.push(id);
            }
        }
        s.blocks.push(Block {
            dim,
            entity,
            gmsh_type: et,
            conn,
            nodes_per: nn,
            lines: at,
        });
    }
    lines.expect("$EndElements")?;
    s.saw_elements = true;
    Ok(())
}

/// The mesh of the sections: solid blocks grouped by kind (global element numbering in kind
/// order), every physical group a node set, volume groups also element sets.
fn assemble(s: Sections, path: &Path) -> Mesh {
    let Sections {
        names,
        entity_phys,
        nodes,
        blocks,
        ..
    } = s;
    let name_of = |dim: i32, p: i32| {
        names
            .get(&(dim, p))
            .cloned()
            .unwrap_or_else(|| format!("{dim}:{p}"))
    };
    let mut by_kind: BTreeMap<ElementKind, Vec<usize>> = BTreeMap::new();
    let mut lines_by_kind: BTreeMap<ElementKind, Vec<u32>> = BTreeMap::new();
    // node lists per group, sorted and made unique at the end (a BTreeSet per group took
    // about a second for the 4.5M element nodes of a 1.1M-element casting)
    let mut set_nodes: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut vol_blocks: Vec<(ElementKind, i32, usize, usize)> = Vec::new(); // kind, entity, start, count
    for b in &blocks {
        let phys = entity_phys
            .get(&(b.dim, b.entity))
            .cloned()
            .unwrap_or_default();
        for p in &phys {
            set_nodes
                .entry(name_of(b.dim, *p))
                .or_default()
                .extend(b.conn.iter().copied());
        }
        if b.dim == 3 {
            let kind = ElementKind::from_gmsh_type(b.gmsh_type).expect("checked on reading");
            let list = by_kind.entry(kind).or_default();
            vol_blocks.push((
                kind,
                b.entity,
                list.len() / b.nodes_per,
                b.conn.len() / b.nodes_per,
            ));
            list.extend_from_slice(&b.conn);
            lines_by_kind
                .entry(kind)
                .or_default()
                .extend_from_slice(&b.lines);
        }
    }
    let mut offset: BTreeMap<ElementKind, usize> = BTreeMap::new();
    let mut acc = 0;
    for (kind, conn) in &by_kind {
        offset.insert(*kind, acc);
        acc += conn.len() / kind.num_nodes();
    }
    let mut mesh = Mesh {
        nodes,
        element_lines: Some(super::ElementLines {
            files: vec![path.to_path_buf()],
            at: lines_by_kind
                .into_values()
                .flatten()
                .map(|line| (0, line))
                .collect(),
            unit: super::MeshUnit::M,
            scopes: Vec::new(),
            scope: Vec::new(),
        }),
        ..Default::default()
    };
    for (kind, ent, start, count) in vol_blocks {
        for p in entity_phys.get(&(3, ent)).cloned().unwrap_or_default() {
            let o = offset[&kind] + start;
            mesh.element_sets
                .entry(name_of(3, p))
                .or_default()
                .extend(o..o + count);
        }
    }
    mesh.blocks = by_kind
        .into_iter()
        .map(|(kind, conn)| ElementBlock { kind, conn })
        .collect();
    mesh.node_sets = set_nodes
        .into_iter()
        .map(|(k, mut v)| {
            v.sort_unstable();
            v.dedup();
            (k, v)
        })
        .collect();
    mesh
}

/// Writes a mesh as MSH 4.1 ASCII: one volume entity per element block, one point entity per
/// node set holding its nodes as 1-node elements (so the sets survive a round trip as physical
/// groups of dimension 0).
pub fn write(mesh: &Mesh, out: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(out, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
    let sets: Vec<(&String, &Vec<usize>)> = mesh.node_sets.iter().collect();
    writeln!(out, "$PhysicalNames\n{}", sets.len() + 1)?;
    for (i, (name, _)) in sets.iter().enumerate() {
        writeln!(out, "0 {} \"{}\"", i + 1, name)?;
    }
    writeln!(out, "3 1 \"solid\"\n$EndPhysicalNames")?;
    writeln!(out, "$Entities\n{} 0 0 {}", sets.len(), mesh.blocks.len())?;
    for (i, _) in sets.iter().enumerate() {
        writeln!(out, "{} 0 0 0 1 {}", i + 1, i + 1)?;
    }
    for (b, _) in mesh.blocks.iter().enumerate() {
        writeln!(out, "{} 0 0 0 0 0 0 1 1 0", b + 1)?;
    }
    writeln!(out, "$EndEntities")?;
    let n = mesh.nodes.len();
    writeln!(out, "$Nodes\n1 {n} 1 {n}\n3 1 0 {n}")?;
    for i in 0..n {
        writeln!(out, "{}", i + 1)?;
    }
    for x in &mesh.nodes {
        writeln!(out, "{:.17e} {:.17e} {:.17e}", x[0], x[1], x[2])?;
    }
    writeln!(out, "$EndNodes")?;
    let n_point_elems: usize = sets.iter().map(|(_, v)| v.len()).sum();
    let total = mesh.num_elements() + n_point_elems;
    writeln!(
        out,
        "$Elements\n{} {total} 1 {total}",
        sets.len() + mesh.blocks.len()
    )?;
    let mut tag = 1;
    for (i, (_, v)) in sets.iter().enumerate() {
        writeln!(out, "0 {} 15 {}", i + 1, v.len())?;
        for &nd in v.iter() {
            writeln!(out, "{tag} {}", nd + 1)?;
            tag += 1;
        }
    }
    for (b, blk) in mesh.blocks.iter().enumerate() {
        writeln!(out, "3 {} {} {}", b + 1, blk.kind.gmsh_type(), blk.len())?;
        for e in 0..blk.len() {
            write!(out, "{tag}")?;
            for &nd in blk.element(e) {
                write!(out, " {}", nd + 1)?;
            }
            writeln!(out)?;
            tag += 1;
        }
    }
    writeln!(out, "$EndElements")
}
