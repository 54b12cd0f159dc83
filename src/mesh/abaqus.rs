//! Reader of Abaqus input files (`.inp`): the solid mesh, its sets and its materials.
//!
//! Lines: keywords start with `*` (names and parameter keys case-insensitive, parameters after
//! commas, values may be quoted), comments with `**`; blank lines are skipped. Coordinates and
//! material constants are taken in the deck's own unit system (converted later).
//!
//! **Read:**
//! - `*INCLUDE, INPUT=file` (quoted or not, relative to the directory of the including file),
//!   nested up to 32 deep, read as if its lines stood in place of the keyword (so it may also
//!   hold the data lines of the keyword before it); records keep the included file and line.
//!   Missing files, cycles and deeper nesting are refused at the `*INCLUDE` line.
//! - `*NODE` (`NSET=`, `SYSTEM=R|C|S`: rectangular, cylindrical `r, theta, z` or spherical
//!   `r, theta, phi` with the angles in degrees, theta about Z from X and phi the latitude from
//!   the X-Y plane: x = r cos(phi) cos(theta), y = r cos(phi) sin(theta), z = r sin(phi)),
//!   after a `*SYSTEM` in that local system (data `x_a, y_a, z_a[, x_b, y_b, z_b]` and
//!   optionally `x_c, y_c, z_c` on a second line: origin a, b on the local x axis, c in the
//!   local x-y plane; without c the local z is the global Z and the local x is b - a projected
//!   onto the X-Y plane; without b a translation; a `*SYSTEM` without data lines, `*PART`,
//!   `*END PART` and `*END INSTANCE` return to the global system). `INPUT=` reads the data
//!   lines from a file, as `*INCLUDE`.
//! - `*ELEMENT, TYPE=` C3D4, C3D10, C3D8 or C3D20 with any formulation letters (C3D8R,
//!   C3D10MH, C3D20RH ...: read as their nodes; linercav integrates its own element) (`ELSET=`;
//!   an element's ids may continue on the next lines); other element types are refused.
//! - `*NSET, NSET=` and `*ELSET, ELSET=` with lists of positive ids or `GENERATE` lines
//!   `first, last[, step]`; at the assembly level `INSTANCE=i` takes the ids of instance i's
//!   part and names the set plainly. Every element set also becomes the node set of its
//!   elements' nodes (unless a node set has the name).
//! - `*PART, NAME=` ... `*END PART`, `*ASSEMBLY` ... `*END ASSEMBLY` and `*INSTANCE, NAME=,
//!   PART=` ... `*END INSTANCE` with the data lines `dx, dy, dz` and `x_a, y_a, z_a, x_b, y_b,
//!   z_b, angle` (translation, then rotation by the angle in degrees about the axis from a to
//!   b, right-handed, as Abaqus applies them). Each instance is its own body: its nodes and
//!   elements get fresh ids (after the largest id outside the parts, in instance order), so two
//!   instances never share a node. A part's set `s` becomes `i.s` for each instance i, and
//!   also `s` when a single instance carries a set of that name and the assembly has none. A
//!   part that is never instanced contributes nothing. A deck without `*PART` and
//!   `*ASSEMBLY` is flat: ids and set names as written.
//! - `*MATERIAL, NAME=` (names case-insensitive, kept in upper case) with `*ELASTIC` (no
//!   `TYPE=` or `TYPE=ISOTROPIC`; one data line `E, nu[, temperature ...]`) and `*DENSITY` (one
//!   data line `rho[, temperature ...]`); `*SOLID SECTION, ELSET=, MATERIAL=` gives the
//!   material to every element of the set (in a part: of every instance of it), the set and the
//!   material may be defined after the section. Only materials a section uses enter the mesh.
//!
//! **Ignored** with their data lines, as they cannot change the solid model's geometry,
//! material or connectivity: `*HEADING`, `*PREPRINT`, `*STEP`/`*END STEP`, the procedures
//! `*STATIC`, `*FREQUENCY`, `*BUCKLE`, loads and boundary conditions (`*BOUNDARY`, `*CLOAD`,
//! `*DLOAD`, `*DSLOAD`, `*TEMPERATURE`, `*INITIAL CONDITIONS`, `*AMPLITUDE`), output requests
//! (`*OUTPUT`, `*NODE OUTPUT`, `*ELEMENT OUTPUT`, `*ENERGY OUTPUT`, `*CONTACT OUTPUT`, `*NODE
//! PRINT`, `*EL PRINT`, `*ENERGY PRINT`, `*NODE FILE`, `*EL FILE`, `*ENERGY FILE`, `*FILE
//! FORMAT`, `*MONITOR`, `*PRINT`, `*RESTART`), `*CONTROLS`, `*SECTION CONTROLS`, `*SURFACE`,
//! `*PHYSICAL CONSTANTS`, `*TRANSFORM` (output directions), `*ORIENTATION` and `*DISTRIBUTION`
//! / `*DISTRIBUTION TABLE` (directions only: the materials read are isotropic), and in a
//! material `*EXPANSION`, `*CONDUCTIVITY`, `*SPECIFIC HEAT`, `*LATENT HEAT`, `*PLASTIC`,
//! `*DAMPING` and `*DEPVAR` (none enters a linear modal model about the unloaded state).
//!
//! **Refused** with the file, line and keyword: every other keyword (`*TIE`, `*COUPLING`,
//! `*MPC`, `*EQUATION`, `*RIGID BODY`, `*MASS`, shell, beam and membrane sections, springs,
//! contact, `*NGEN`/`*NCOPY`/`*ELGEN` ..., `*USER MATERIAL`, `*PARAMETER`, unknown keywords);
//! `*ELASTIC` of another `TYPE=` or with several data lines (temperature dependence), a
//! composite `*SOLID SECTION`, a section whose set or material is undefined or whose material
//! lacks `*ELASTIC` or `*DENSITY` (a modal model needs both), `*INSTANCE` of an undefined part
//! or importing one (`INSTANCE=`, `LIBRARY=`), nodes, elements or sections inside an
//! `*INSTANCE` block, `*PART` without `*ASSEMBLY`, ids <= 0, sets of sets, and an assembly
//! with more nodes, elements and set members than its files have bytes, sets holding more
//! than 4 ids per byte of the files.

use super::collect::{
    read_mesh_text, reorder, Collected, DeckError, Loc, HEX20_ABAQUS, TET10_DECK,
};
use super::Mesh;
use crate::scene::spec::Elastic;
use crate::scene::spec::ElementKind;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

const EXPECTED: &str = "expected an Abaqus input file (ASCII)";
/// Deepest nesting of `*INCLUDE` files read.
const MAX_DEPTH: usize = 32;

/// Reads an input file from disk.
pub fn read(path: &Path) -> Result<Mesh, DeckError> {
    let text = read_mesh_text(path, EXPECTED)?;
    parse(path, &text)
}

/// Parses an input file whose text is `text`; `path` names it in messages and is the base of
/// relative `*INCLUDE` paths.
pub fn parse(path: &Path, text: &str) -> Result<Mesh, DeckError> {
    let mut r = Reader::new(path, text.len());
    r.lines(0, text)?;
    r.finish()
}

type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// `a` scaled to unit length, if it has a finite nonzero length.
fn unit(a: V3) -> Option<V3> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| scale(a, 1.0 / n))
}

/// The coordinate form of `*NODE` data (`SYSTEM=`).
#[derive(Clone, Copy)]
enum Coord {
    /// x, y, z
    Rect,
    /// r, theta [deg], z
    Cyl,
    /// r, theta [deg], phi [deg] (latitude from the X-Y plane)
    Sph,
}

impl Coord {
    /// Rectangular coordinates of `x` given in this form.
    fn to_rect(self, x: V3) -> V3 {
        let (r, t) = (x[0], x[1].to_radians());
        match self {
            Coord::Rect => x,
            Coord::Cyl => [r * t.cos(), r * t.sin(), x[2]],
            Coord::Sph => {
                let p = x[2].to_radians();
                [r * p.cos() * t.cos(), r * p.cos() * t.sin(), r * p.sin()]
            }
        }
    }
}

/// A local rectangular system of `*SYSTEM`: global = origin + x1 axes[0] + x2 axes[1] +
/// x3 axes[2].
#[derive(Clone, Copy)]
struct Frame {
    origin: V3,
    axes: [V3; 3],
}

impl Frame {
    /// The system of `*SYSTEM` data `a`, `a, b` or `a, b, c` (9 values): origin a, b on the
    /// local x axis, c in the local x-y plane on the side of +y; without c the local z axis is
    /// the global Z and the local x axis b - a projected onto the X-Y plane; without b a
    /// translation. None for degenerate points.
    fn new(v: &[f64]) -> Option<Frame> {
        let p = |k: usize| -> Option<V3> { Some([*v.get(k)?, *v.get(k + 1)?, *v.get(k + 2)?]) };
        let a = p(0)?;
        let axes = match v.len() {
            3 => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            6 => {
                let d = sub(p(3)?, a);
                let x = unit([d[0], d[1], 0.0])?;
                let z = [0.0, 0.0, 1.0];
                [x, cross(z, x), z]
            }
            9 => {
                let x = unit(sub(p(3)?, a))?;
                let w = sub(p(6)?, a);
                let y = unit(sub(w, scale(x, dot(w, x))))?;
                [x, y, cross(x, y)]
            }
            _ => return None,
        };
        Some(Frame { origin: a, axes })
    }

    /// Global coordinates of local point `x`.
    fn to_global(self, x: V3) -> V3 {
        let mut g = self.origin;
        for (xa, axis) in x.iter().zip(&self.axes) {
            g = add(g, scale(*axis, *xa));
        }
        g
    }
}

/// The placement of an instance: translation, then rotation (point a on the axis, unit axis
/// a -> b, angle in radians) as Abaqus applies them.
#[derive(Clone, Copy, Default)]
struct Placement {
    translate: V3,
    rotate: Option<(V3, V3, f64)>,
}

impl Placement {
    /// Where the part's point `x` goes (Rodrigues' rotation about the axis through a).
    fn apply(&self, x: V3) -> V3 {
        let p = add(x, self.translate);
        let Some((a, k, angle)) = self.rotate else {
            return p;
        };
        let v = sub(p, a);
        let (s, c) = angle.sin_cos();
        let r = add(
            add(scale(v, c), scale(cross(k, v), s)),
            scale(k, dot(k, v) * (1.0 - c)),
        );
        add(a, r)
    }
}

/// A keyword line: its name (upper case, single spaces) and parameters (keys upper case,
/// values as written without surrounding quotes).
struct Keyword {
    name: String,
    params: Vec<(String, String)>,
}

impl Keyword {
    /// Parses a keyword line without its `*`; commas inside double quotes do not separate.
    fn parse(kw: &str) -> Keyword {
        let mut fields = Vec::new();
        let (mut cur, mut quoted) = (String::new(), false);
        for ch in kw.chars() {
            match ch {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                _ => cur.push(ch),
            }
        }
        fields.push(cur);
        let norm = |s: &str| {
            s.split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
                .to_ascii_uppercase()
        };
        let name = norm(&fields[0]);
        let params = fields[1..]
            .iter()
            .filter(|p| !p.trim().is_empty())
            .map(|p| match p.split_once('=') {
                Some((k, v)) => (norm(k), v.trim().to_string()),
                None => (norm(p), String::new()),
            })
            .collect();
        Keyword { name, params }
    }

    /// The value of parameter `key` (upper case).
    fn get(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// The data block being read: what the data lines of the last keyword are.
enum Block {
    Skip,
    Node {
        nset: Option<String>,
        coord: Coord,
    },
    Element {
        kind: ElementKind,
        abaqus: String,
        elset: Option<String>,
    },
    Set {
        nodes: bool,
        name: String,
        generate: bool,
        instance: Option<String>,
    },
    Instance {
        lines: usize,
    },
    System,
    /// `*ELASTIC` (`density` false) or `*DENSITY` of material `material` (upper case).
    Constants {
        density: bool,
        material: String,
        lines: usize,
        columns: usize,
    },
}

/// A `*SOLID SECTION`: element set name, material name, where.
struct Section {
    elset: String,
    material: String,
    loc: Loc,
}

/// Nodes, elements, sets and sections of one scope (a part, or the model: a flat deck's
/// contents or the assembly's own), by the scope's ids.
#[derive(Default)]
struct Scope {
    nodes: Vec<(i64, V3, Loc)>,
    elements: Vec<(i64, ElementKind, Vec<i64>, Loc)>,
    node_sets: BTreeMap<String, (Vec<i64>, Loc)>,
    element_sets: BTreeMap<String, (Vec<i64>, Loc)>,
    sections: Vec<Section>,
}

impl Scope {
    /// Its records and set members: what one instance of it adds.
    fn size(&self) -> usize {
        let sets = self.node_sets.values().chain(self.element_sets.values());
        let members: usize = sets.map(|(ids, _)| ids.len()).sum();
        self.nodes.len() + self.elements.len() + members
    }
}

/// A part: name as written, contents, where `*PART` is.
struct Part {
    name: String,
    scope: Scope,
    loc: Loc,
}

/// An `*INSTANCE`: name, part name, placement, where.
struct Instance {
    name: String,
    part: String,
    placement: Placement,
    loc: Loc,
}

/// An assembly-level set of an instance's ids (`INSTANCE=`): one data line.
struct BoundSet {
    nodes: bool,
    name: String,
    instance: String,
    ids: Vec<i64>,
    loc: Loc,
}

/// A `*MATERIAL`: (E, nu) of `*ELASTIC`, rho of `*DENSITY`, where it is defined.
struct MaterialDef {
    elastic: Option<(f64, f64)>,
    density: Option<f64>,
    loc: Loc,
}

/// Where the keywords being read are.
#[derive(Clone, Copy, PartialEq)]
enum Where {
    Model,
    Part(usize),
    Instance(usize),
}

/// Keywords whose data are skipped: they cannot change the solid model's geometry, material
/// or connectivity.
const IGNORED: &[&str] = &[
    "HEADING",
    "PREPRINT",
    "STEP",
    "END STEP",
    "STATIC",
    "FREQUENCY",
    "BUCKLE",
    "BOUNDARY",
    "CLOAD",
    "DLOAD",
    "DSLOAD",
    "TEMPERATURE",
    "INITIAL CONDITIONS",
    "AMPLITUDE",
    "OUTPUT",
    "NODE OUTPUT",
    "ELEMENT OUTPUT",
    "ENERGY OUTPUT",
    "CONTACT OUTPUT",
    "NODE PRINT",
    "EL PRINT",
    "ENERGY PRINT",
    "NODE FILE",
    "EL FILE",
    "ENERGY FILE",
    "FILE FORMAT",
    "MONITOR",
    "PRINT",
    "RESTART",
    "CONTROLS",
    "SECTION CONTROLS",
    "SURFACE",
    "PHYSICAL CONSTANTS",
    "TRANSFORM",
    "ORIENTATION",
    "DISTRIBUTION",
    "DISTRIBUTION TABLE",
];

/// Material options skipped: none enters a linear modal model about the unloaded state.
const MATERIAL_IGNORED: &[&str] = &[
    "EXPANSION",
    "CONDUCTIVITY",
    "SPECIFIC HEAT",
    "LATENT HEAT",
    "PLASTIC",
    "DAMPING",
    "DEPVAR",
];

/// The state of the reading: files, scopes, instances, materials and the current block.
struct Reader {
    /// Main file, then each included file once.
    files: Vec<PathBuf>,
    /// Canonical paths of the files being read, outermost first (cycle detection).
    stack: Vec<PathBuf>,
    /// Bytes read from all files (bounds GENERATE ranges and instanced records).
    bytes: usize,
    /// Members of all sets so far (at most [`SET_IDS_PER_BYTE`] per byte read).
    set_ids: usize,
    /// Files read so far, each include counted (at most [`super::DECK_FILES`]).
    reads: usize,
    model: Scope,
    parts: Vec<Part>,
    instances: Vec<Instance>,
    /// Indices of the parts and the names of the instances, by upper-case name (Abaqus names
    /// are case-insensitive; a deck of 60k instances was checked name by name, quadratically).
    part_index: std::collections::HashMap<String, usize>,
    instance_names: std::collections::HashSet<String>,
    bound: Vec<BoundSet>,
    /// Materials by upper-case name.
    materials: BTreeMap<String, MaterialDef>,
    at: Where,
    assembly: Option<Loc>,
    in_assembly: bool,
    block: Block,
    /// An element whose ids continue on the next line: (where it starts, numbers so far).
    pending: Option<(Loc, Vec<i64>)>,
    system: Option<Frame>,
    system_values: Vec<f64>,
    /// The material whose options are being read (upper case).
    material: Option<String>,
    /// The first `*BOUNDARY` (not applied: warned of once the deck is read).
    boundary: Option<Loc>,
}

impl Reader {
    fn new(path: &Path, bytes: usize) -> Reader {
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        Reader {
            files: vec![path.to_path_buf()],
            stack: vec![canonical],
            bytes,
            set_ids: 0,
            reads: 1,
            model: Scope::default(),
            parts: Vec::new(),
            instances: Vec::new(),
            part_index: Default::default(),
            instance_names: Default::default(),
            bound: Vec::new(),
            materials: BTreeMap::new(),
            at: Where::Model,
            assembly: None,
            in_assembly: false,
            block: Block::Skip,
            pending: None,
            system: None,
            system_values: Vec::new(),
            material: None,
            boundary: None,
        }
    }

    /// An error at `loc`.
    fn err(&self, loc: Loc, msg: String) -> DeckError {
        let path = self.files.get(loc.file).or(self.files.first());
        DeckError {
            path: path.cloned().unwrap_or_default(),
            line: loc.line,
            msg,
        }
    }

    /// The scope nodes, elements, sets and sections go to (never an instance: refused before).
    fn scope(&mut self) -> &mut Scope {
        match self.at {
            Where::Part(i) => &mut self.parts[i].scope,
            _ => &mut self.model,
        }
    }

    /// Reads the lines of file `file` (index into `files`).
    fn lines(&mut self, file: usize, text: &str) -> Result<(), DeckError> {
        for (i, raw) in text.lines().enumerate() {
            let loc = Loc { file, line: i + 1 };
            let l = raw.trim();
            if l.is_empty() || l.starts_with("**") {
                continue;
            }
            match l.strip_prefix('*') {
                Some(kw) => self.keyword(&Keyword::parse(kw), loc)?,
                None => self.data(l, loc)?,
            }
        }
        Ok(())
    }

    /// Reads file `input` (relative to the directory of the file of `loc`) in place of the
    /// keyword at `loc`: `*INCLUDE` and `INPUT=` of data keywords.
    fn include(&mut self, input: &str, loc: Loc) -> Result<(), DeckError> {
        let input = input.trim().trim_matches('"');
        if input.is_empty() {
            return Err(self.err(loc, "*INCLUDE without INPUT= (the file to read)".into()));
        }
        if self.stack.len() > MAX_DEPTH {
            return Err(self.err(
                loc,
                format!("*INCLUDE of '{input}': files nested more than {MAX_DEPTH} deep"),
            ));
        }
        self.reads += 1;
        if self.reads > super::DECK_FILES {
            let msg = format!(
                "*INCLUDE of '{input}': more than {} files read (each include counted)",
                super::DECK_FILES
            );
            return Err(self.err(loc, msg));
        }
        let base = self.files[loc.file].parent().unwrap_or(Path::new(""));
        let path = base.join(input);
        let canonical = std::fs::canonicalize(&path).map_err(|e| {
            self.err(
                loc,
                format!("*INCLUDE: cannot open '{}': {e}", path.display()),
            )
        })?;
        if let Some(k) = self.stack.iter().position(|p| *p == canonical) {
            let chain: Vec<String> = self.stack[k..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(self.err(
                loc,
                format!(
                    "*INCLUDE of '{input}' makes a cycle: {}",
                    chain.join(" -> ")
                ),
            ));
        }
        let text = read_mesh_text(&path, EXPECTED).map_err(|e| {
            if e.line > 0 {
                e
            } else {
                self.err(loc, format!("*INCLUDE of '{input}': {}", e.msg))
            }
        })?;
        self.bytes = self.bytes.saturating_add(text.len());
        if self.bytes as u64 > crate::files::LIMIT_MESH {
            return Err(self.err(
                loc,
                "*INCLUDE: the files read exceed the mesh size limit".into(),
            ));
        }
        let index = match self.files.iter().position(|p| *p == path) {
            Some(k) => k,
            None => {
                self.files.push(path);
                self.files.len() - 1
            }
        };
        self.stack.push(canonical);
        self.lines(index, &text)?;
        self.stack.pop();
        Ok(())
    }

    /// A keyword line: refuses a keyword inside an element's node list, then dispatches.
    fn keyword(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        if k.name == "INCLUDE" {
            return self.include(k.get("INPUT").unwrap_or(""), loc);
        }
        if let Some((first, _)) = &self.pending {
            let msg = format!(
                "*{}: the element started on line {} lacks nodes before this keyword",
                k.name, first.line
            );
            return Err(self.err(loc, msg));
        }
        self.block = Block::Skip;
        let name = k.name.as_str();
        let material_option =
            matches!(name, "ELASTIC" | "DENSITY" | "MATERIAL") || MATERIAL_IGNORED.contains(&name);
        if !material_option {
            self.material = None;
        }
        match name {
            "PART" | "END PART" | "ASSEMBLY" | "END ASSEMBLY" => self.structure(k, loc),
            "INSTANCE" | "END INSTANCE" => self.instance(k, loc),
            "NODE" | "ELEMENT" | "SYSTEM" => self.mesh_keyword(k, loc),
            "NSET" | "ELSET" => self.set_keyword(k, loc),
            "MATERIAL" | "ELASTIC" | "DENSITY" | "SOLID SECTION" => self.material_keyword(k, loc),
            "BOUNDARY" => {
                self.boundary.get_or_insert(loc);
                Ok(())
            }
            _ if material_option || IGNORED.contains(&name) => Ok(()),
            _ => Err(self.err(
                loc,
                format!("*{name} is not read by linercav (it may change the model's geometry, material or connectivity)"),
            )),
        }
    }

    /// `*PART`, `*END PART`, `*ASSEMBLY`, `*END ASSEMBLY`.
    fn structure(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let fail = |r: &Self, what: &str| Err(r.err(loc, format!("*{}: {what}", k.name)));
        self.system = None;
        match (k.name.as_str(), self.at) {
            ("PART", Where::Model) if !self.in_assembly => {
                let Some(name) = k.get("NAME").filter(|n| !n.is_empty()) else {
                    return fail(self, "expected NAME= (the part's name)");
                };
                if self.part(name).is_some() {
                    return fail(self, &format!("part '{name}' is defined twice"));
                }
                self.part_index
                    .insert(name.to_ascii_uppercase(), self.parts.len());
                self.parts.push(Part {
                    name: name.to_string(),
                    scope: Scope::default(),
                    loc,
                });
                self.at = Where::Part(self.parts.len() - 1);
            }
            ("PART", _) => {
                return fail(
                    self,
                    "inside a part or the assembly (expected *END PART or *END ASSEMBLY first)",
                )
            }
            ("END PART", Where::Part(_)) => self.at = Where::Model,
            ("END PART", _) => return fail(self, "without *PART"),
            ("ASSEMBLY", Where::Model) if self.assembly.is_none() => {
                self.assembly = Some(loc);
                self.in_assembly = true;
            }
            ("ASSEMBLY", _) => return fail(self, "a second assembly, or inside a part"),
            ("END ASSEMBLY", Where::Model) if self.in_assembly => self.in_assembly = false,
            _ => return fail(self, "without *ASSEMBLY, or inside an instance"),
        }
        Ok(())
    }

    /// The index of part `name` (case-insensitive, as Abaqus names).
    fn part(&self, name: &str) -> Option<usize> {
        self.part_index.get(&name.to_ascii_uppercase()).copied()
    }

    /// `*INSTANCE, NAME=, PART=` (its data lines follow) and `*END INSTANCE`.
    fn instance(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let fail = |r: &Self, what: &str| Err(r.err(loc, format!("*{}: {what}", k.name)));
        if k.name == "END INSTANCE" {
            if !matches!(self.at, Where::Instance(_)) {
                return fail(self, "without *INSTANCE");
            }
            self.at = Where::Model;
            self.system = None;
            return Ok(());
        }
        if !self.in_assembly || self.at != Where::Model {
            return fail(self, "outside *ASSEMBLY or inside another instance");
        }
        if k.get("INSTANCE").is_some() || k.get("LIBRARY").is_some() {
            return fail(self, "instances imported from a previous analysis (INSTANCE=, LIBRARY=) are not read: instance a part (PART=)");
        }
        let (Some(name), Some(part)) = (k.get("NAME"), k.get("PART")) else {
            return fail(self, "expected NAME= and PART=");
        };
        if !self.instance_names.insert(name.to_ascii_uppercase()) {
            return fail(self, &format!("instance '{name}' is defined twice"));
        }
        self.instances.push(Instance {
            name: name.to_string(),
            part: part.to_string(),
            placement: Placement::default(),
            loc,
        });
        self.at = Where::Instance(self.instances.len() - 1);
        self.block = Block::Instance { lines: 0 };
        Ok(())
    }

    /// `*NODE`, `*ELEMENT` and `*SYSTEM`.
    fn mesh_keyword(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let fail = |r: &Self, what: String| Err(r.err(loc, format!("*{}: {what}", k.name)));
        if let Where::Instance(i) = self.at {
            let msg = format!(
                "inside *INSTANCE '{}': define the nodes and elements in its part",
                self.instances[i].name
            );
            return fail(self, msg);
        }
        self.block = match k.name.as_str() {
            "NODE" => {
                let coord = match k.get("SYSTEM").map(|s| s.to_ascii_uppercase()).as_deref() {
                    None | Some("R") => Coord::Rect,
                    Some("C") => Coord::Cyl,
                    Some("S") => Coord::Sph,
                    Some(s) => return fail(self, format!("SYSTEM={s} (expected R, C or S)")),
                };
                Block::Node {
                    nset: k.get("NSET").map(str::to_string),
                    coord,
                }
            }
            "ELEMENT" => {
                let Some(t) = k.get("TYPE") else {
                    return fail(self, "without TYPE=".into());
                };
                let Some(kind) = solid_kind(t) else {
                    return fail(self, format!("element type {t} is not supported (expected C3D4, C3D10, C3D8 or C3D20, with formulation letters R, I, H, M; a mesher's surface and edge elements: write the volume elements only, in Gmsh a physical volume group with Mesh.SaveAll = 0)"));
                };
                Block::Element {
                    kind,
                    abaqus: t.to_ascii_uppercase(),
                    elset: k.get("ELSET").map(str::to_string),
                }
            }
            _ => {
                self.system = None;
                self.system_values.clear();
                Block::System
            }
        };
        match k.get("INPUT") {
            Some(input) if k.name != "SYSTEM" => self.include(input, loc),
            _ => Ok(()),
        }
    }

    /// `*NSET, NSET=` and `*ELSET, ELSET=` (`GENERATE`, `INSTANCE=` at the assembly level).
    fn set_keyword(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let nodes = k.name == "NSET";
        let Some(name) = k.get(&k.name).filter(|n| !n.is_empty()) else {
            let msg = format!("*{0} without {0}= (the set's name)", k.name);
            return Err(self.err(loc, msg));
        };
        let instance = match (self.at, k.get("INSTANCE")) {
            (Where::Instance(i), _) => Some(self.instances[i].name.clone()),
            (Where::Part(_), Some(_)) => {
                let msg = format!("*{}: INSTANCE= inside a *PART", k.name);
                return Err(self.err(loc, msg));
            }
            (_, i) => i.map(str::to_string),
        };
        if instance.is_none() {
            // a set with no data lines is defined, empty (a *SOLID SECTION may name it)
            let s = self.scope();
            let sets = if nodes {
                &mut s.node_sets
            } else {
                &mut s.element_sets
            };
            sets.entry(name.to_string()).or_insert((Vec::new(), loc));
        }
        self.block = Block::Set {
            nodes,
            name: name.to_string(),
            generate: k.params.iter().any(|(p, _)| p == "GENERATE"),
            instance,
        };
        match k.get("INPUT") {
            Some(input) => self.include(input, loc),
            None => Ok(()),
        }
    }

    /// `*MATERIAL`, `*ELASTIC`, `*DENSITY` and `*SOLID SECTION`.
    fn material_keyword(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let fail = |r: &Self, what: String| Err(r.err(loc, format!("*{}: {what}", k.name)));
        match k.name.as_str() {
            "MATERIAL" => {
                let Some(name) = k.get("NAME").filter(|n| !n.is_empty()) else {
                    return fail(self, "expected NAME= (the material's name)".into());
                };
                let key = name.to_ascii_uppercase();
                if self.materials.contains_key(&key) {
                    return fail(self, format!("material '{name}' is defined twice"));
                }
                let def = MaterialDef {
                    elastic: None,
                    density: None,
                    loc,
                };
                self.materials.insert(key.clone(), def);
                self.material = Some(key);
            }
            "SOLID SECTION" => return self.section(k, loc),
            _ => {
                let Some(material) = self.material.clone() else {
                    return fail(self, "outside a *MATERIAL".into());
                };
                let density = k.name == "DENSITY";
                if let Some(t) = k
                    .get("TYPE")
                    .filter(|t| !t.eq_ignore_ascii_case("ISOTROPIC"))
                {
                    return fail(self, format!("TYPE={t} of material '{material}' is not read (linercav takes isotropic elasticity: TYPE=ISOTROPIC)"));
                }
                if k.get("DISTRIBUTION").is_some() || k.get("INPUT").is_some() {
                    return fail(self, "DISTRIBUTION= and INPUT= are not read: give the constants on the data line".into());
                }
                let deps = k.get("DEPENDENCIES").and_then(|d| d.parse::<usize>().ok());
                let columns = (if density { 2 } else { 3 }) + deps.unwrap_or(0).min(8);
                self.block = Block::Constants {
                    density,
                    material,
                    lines: 0,
                    columns,
                };
            }
        }
        Ok(())
    }

    /// `*SOLID SECTION, ELSET=, MATERIAL=` (resolved at the end).
    fn section(&mut self, k: &Keyword, loc: Loc) -> Result<(), DeckError> {
        let fail = |r: &Self, what: &str| Err(r.err(loc, format!("*SOLID SECTION: {what}")));
        if matches!(self.at, Where::Instance(_)) {
            return fail(self, "inside *INSTANCE (give the section in the part)");
        }
        if k.get("COMPOSITE").is_some() {
            return fail(
                self,
                "COMPOSITE sections are not read (one material per section)",
            );
        }
        let (Some(elset), Some(material)) = (k.get("ELSET"), k.get("MATERIAL")) else {
            return fail(self, "expected ELSET= and MATERIAL=");
        };
        let section = Section {
            elset: elset.to_string(),
            material: material.to_string(),
            loc,
        };
        self.scope().sections.push(section);
        Ok(())
    }

    /// A data line of the current block.
    fn data(&mut self, l: &str, loc: Loc) -> Result<(), DeckError> {
        let mut block = std::mem::replace(&mut self.block, Block::Skip);
        let f: Vec<&str> = l
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let r = match &mut block {
            Block::Skip => Ok(()),
            Block::Node { nset, coord } => self.node(nset.as_deref(), *coord, &f, l, loc),
            Block::Element {
                kind,
                abaqus,
                elset,
            } => self.element(*kind, abaqus, elset.as_deref(), &f, loc),
            Block::Set {
                nodes,
                name,
                generate,
                instance,
            } => {
                let kw = if *nodes { "*NSET" } else { "*ELSET" };
                let at = |m: String| self.err(loc, format!("{kw} {name}: {m}"));
                let room = SET_IDS_PER_BYTE
                    .saturating_mul(self.bytes)
                    .saturating_sub(self.set_ids);
                let ids = set_ids(&f, *generate, l, room, &at);
                self.set_ids += ids.as_ref().map_or(0, Vec::len);
                ids.map(|ids| match instance {
                    Some(i) => self.bound.push(BoundSet {
                        nodes: *nodes,
                        name: name.clone(),
                        instance: i.clone(),
                        ids,
                        loc,
                    }),
                    None => {
                        let s = self.scope();
                        let sets = if *nodes {
                            &mut s.node_sets
                        } else {
                            &mut s.element_sets
                        };
                        sets.entry(name.clone())
                            .or_insert((Vec::new(), loc))
                            .0
                            .extend(ids);
                    }
                })
            }
            Block::Instance { lines } => {
                *lines += 1;
                self.placement(*lines, &f, l, loc)
            }
            Block::System => self.system_line(&f, l, loc),
            Block::Constants {
                density,
                material,
                lines,
                columns,
            } => {
                *lines += 1;
                self.constants(*density, material, *lines, *columns, &f, l, loc)
            }
        };
        self.block = block;
        r
    }

    /// The finite numbers of data fields `f` (of keyword `kw`, line `l`).
    fn reals(&self, f: &[&str], kw: &str, l: &str, loc: Loc) -> Result<Vec<f64>, DeckError> {
        f.iter()
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| {
                self.err(
                    loc,
                    format!("*{kw}: '{l}' holds a field that is not a finite number"),
                )
            })
    }

    /// A `*NODE` data line `id, x, y, z` (in the `SYSTEM=` form and the `*SYSTEM` in force).
    fn node(
        &mut self,
        nset: Option<&str>,
        coord: Coord,
        f: &[&str],
        l: &str,
        loc: Loc,
    ) -> Result<(), DeckError> {
        let fail = |r: &Self, m: String| Err(r.err(loc, format!("*NODE: {m}")));
        if f.len() < 4 {
            return fail(self, format!("expected 'id, x, y, z', found '{l}'"));
        }
        let Ok(id) = f[0].parse::<i64>() else {
            return fail(self, format!("node id '{}' is not an integer", f[0]));
        };
        if id <= 0 {
            return fail(self, format!("node id {id}: ids must be positive integers"));
        }
        let mut x = [0.0; 3];
        for (a, xa) in x.iter_mut().enumerate() {
            let w = f[1 + a];
            let Some(v) = w.parse::<f64>().ok().filter(|v| v.is_finite()) else {
                return fail(
                    self,
                    format!("node {id}: coordinate '{w}' is not a finite number"),
                );
            };
            *xa = v;
        }
        let mut x = coord.to_rect(x);
        if let Some(frame) = &self.system {
            x = frame.to_global(x);
        }
        if !x.iter().all(|v| v.is_finite()) {
            return fail(self, format!("node {id}: its global coordinates overflow"));
        }
        let s = self.scope();
        s.nodes.push((id, x, loc));
        if let Some(n) = nset {
            s.node_sets
                .entry(n.to_string())
                .or_insert((Vec::new(), loc))
                .0
                .push(id);
        }
        Ok(())
    }

    /// An `*ELEMENT` data line: the element's id and node ids, which may continue on the next
    /// lines.
    fn element(
        &mut self,
        kind: ElementKind,
        abaqus: &str,
        elset: Option<&str>,
        f: &[&str],
        loc: Loc,
    ) -> Result<(), DeckError> {
        let (first, mut got) = self.pending.take().unwrap_or((loc, Vec::new()));
        for w in f {
            let Ok(v) = w.parse::<i64>() else {
                return Err(self.err(loc, format!("*ELEMENT: '{w}' is not an integer id")));
            };
            got.push(v);
        }
        let need = 1 + kind.num_nodes();
        if got.len() < need {
            self.pending = Some((first, got));
            return Ok(());
        }
        if got.len() > need {
            let msg = format!(
                "*ELEMENT: element {} has {} node ids, {abaqus} has {}",
                got[0],
                got.len() - 1,
                kind.num_nodes()
            );
            return Err(self.err(loc, msg));
        }
        if got[0] <= 0 {
            let msg = format!(
                "*ELEMENT: element id {}: ids must be positive integers",
                got[0]
            );
            return Err(self.err(first, msg));
        }
        let ids = match kind {
            ElementKind::Tet10 => reorder(kind, &TET10_DECK, &got[1..]),
            ElementKind::Hex20 => reorder(kind, &HEX20_ABAQUS, &got[1..]),
            _ => got[1..].to_vec(),
        };
        let s = self.scope();
        s.elements.push((got[0], kind, ids, first));
        if let Some(e) = elset {
            s.element_sets
                .entry(e.to_string())
                .or_insert((Vec::new(), first))
                .0
                .push(got[0]);
        }
        Ok(())
    }

    /// Data line `n` of an `*INSTANCE`: 1 the translation, 2 the rotation.
    fn placement(&mut self, n: usize, f: &[&str], l: &str, loc: Loc) -> Result<(), DeckError> {
        let Where::Instance(i) = self.at else {
            return Ok(());
        };
        let v = self.reals(f, "INSTANCE", l, loc)?;
        let fail = |r: &Self, m: &str| Err(r.err(loc, format!("*INSTANCE: {m}, found '{l}'")));
        match (n, v.as_slice()) {
            (1, &[x, y, z]) => self.instances[i].placement.translate = [x, y, z],
            (2, &[ax, ay, az, bx, by, bz, angle]) => {
                if angle != 0.0 {
                    let Some(k) = unit(sub([bx, by, bz], [ax, ay, az])) else {
                        return fail(self, "points a and b of the rotation axis coincide");
                    };
                    self.instances[i].placement.rotate =
                        Some(([ax, ay, az], k, angle.to_radians()));
                }
            }
            (1, _) => {
                return fail(
                    self,
                    "expected the translation 'x, y, z' on the first data line",
                )
            }
            (2, _) => {
                return fail(
                    self,
                    "expected 'x_a, y_a, z_a, x_b, y_b, z_b, angle' on the second data line",
                )
            }
            _ => {
                return fail(
                    self,
                    "expected at most two data lines (translation, rotation)",
                )
            }
        }
        Ok(())
    }

    /// A `*SYSTEM` data line: `a[, b]` on the first, `c` on the second.
    fn system_line(&mut self, f: &[&str], l: &str, loc: Loc) -> Result<(), DeckError> {
        let v = self.reals(f, "SYSTEM", l, loc)?;
        if !matches!(
            (self.system_values.len(), v.len()),
            (0, 3) | (0, 6) | (6, 3)
        ) {
            return Err(self.err(loc, format!("*SYSTEM: expected 'x_a, y_a, z_a[, x_b, y_b, z_b]' on the first data line and 'x_c, y_c, z_c' on the second, found '{l}'")));
        }
        self.system_values.extend(v);
        let Some(frame) = Frame::new(&self.system_values) else {
            return Err(self.err(loc, "*SYSTEM: the points do not define a system (b - a is zero or along Z without c, or c lies on the local x axis)".into()));
        };
        self.system = Some(frame);
        Ok(())
    }

    /// Data line `n` of `*ELASTIC` (`E, nu`) or `*DENSITY` (`rho`) of `material`, at most
    /// `columns` values.
    #[allow(clippy::too_many_arguments)]
    fn constants(
        &mut self,
        density: bool,
        material: &str,
        n: usize,
        columns: usize,
        f: &[&str],
        l: &str,
        loc: Loc,
    ) -> Result<(), DeckError> {
        let (kw, form) = if density {
            ("DENSITY", "rho")
        } else {
            ("ELASTIC", "E, nu")
        };
        if n > 1 {
            return Err(self.err(loc, format!("*{kw} of material '{material}': a second data line (temperature- or field-dependent constants are not read: give one line '{form}')")));
        }
        let v = self.reals(f, kw, l, loc)?;
        let least = if density { 1 } else { 2 };
        if v.len() < least || v.len() > columns {
            return Err(self.err(
                loc,
                format!(
                    "*{kw} of material '{material}': expected '{form}[, temperature]', found '{l}'"
                ),
            ));
        }
        let given = self.materials.get(material).is_some_and(|m| {
            if density {
                m.density.is_some()
            } else {
                m.elastic.is_some()
            }
        });
        if given {
            let msg =
                format!("*{kw} of material '{material}' is given twice (one *{kw} per *MATERIAL)");
            return Err(self.err(loc, msg));
        }
        if let Some(m) = self.materials.get_mut(material) {
            if density {
                m.density = Some(v[0]);
            } else {
                m.elastic = Some((v[0], v[1]));
            }
        }
        Ok(())
    }

    /// Refuses a file that ends inside an element's node list, a part or an instance, and
    /// parts without an assembly.
    fn check_closed(&self) -> Result<(), DeckError> {
        if let Some((first, _)) = &self.pending {
            return Err(self.err(*first, "the file ends inside an element's node list".into()));
        }
        match self.at {
            Where::Part(i) => {
                let p = &self.parts[i];
                return Err(self.err(
                    p.loc,
                    format!("*PART '{}' is not closed by *END PART", p.name),
                ));
            }
            Where::Instance(i) => {
                let n = &self.instances[i];
                return Err(self.err(
                    n.loc,
                    format!("*INSTANCE '{}' is not closed by *END INSTANCE", n.name),
                ));
            }
            Where::Model => {}
        }
        if let (None, Some(p)) = (self.assembly, self.parts.first()) {
            return Err(self.err(
                p.loc,
                "*PART without *ASSEMBLY: parts are read through the *INSTANCEs of an *ASSEMBLY"
                    .into(),
            ));
        }
        Ok(())
    }

    /// The collected deck: the model scope as written, each instance with fresh ids, the
    /// assembly's sets of instances, the plain names of single-instance sets, the sections.
    fn finish(mut self) -> Result<Mesh, DeckError> {
        self.check_closed()?;
        if let Some(loc) = self.boundary {
            crate::text::warn(format!("{}", self.err(loc, "*BOUNDARY and the deck's other boundary conditions are not applied: linercav holds only the node sets named by --fix or a part's `fix` key".into())));
        }
        let mut c = Collected::new(&self.files[0]);
        c.files = self.files.clone();
        let model = std::mem::take(&mut self.model);
        let next_node = model
            .nodes
            .iter()
            .map(|n| n.0)
            .max()
            .unwrap_or(0)
            .checked_add(1);
        let next_element = model
            .elements
            .iter()
            .map(|e| e.0)
            .max()
            .unwrap_or(0)
            .checked_add(1);
        let (Some(next_node), Some(next_element)) = (next_node, next_element) else {
            let msg = format!(
                "a node or element id is {} (the largest an id can be): the parts' instances are numbered after the largest id, so ids must stay below it",
                i64::MAX
            );
            return Err(self.err(Loc::main(0), msg));
        };
        c.nodes = model.nodes;
        c.elements = model.elements;
        c.node_sets = model.node_sets;
        c.element_sets = model.element_sets;
        let mut carriers = [BTreeMap::new(), BTreeMap::new()];
        let maps = self.place_instances(&mut c, &mut carriers, [next_node, next_element])?;
        self.bound_sets(&mut c, &maps)?;
        aliases(&mut c, &carriers);
        for sec in &model.sections {
            let Some((list, _)) = find_set(&c.element_sets, &sec.elset) else {
                let msg = format!("*SOLID SECTION: element set '{}' is not defined", sec.elset);
                return Err(self.err(sec.loc, msg));
            };
            let list = list.clone();
            self.assign(&mut c, &list, sec)?;
        }
        c.into_mesh()
    }

    /// Every instance's nodes and elements with fresh ids from `next` (node, element), its
    /// sets `i.s` (recording in `carriers` which instances carry each plain name: node sets,
    /// element sets) and its part's sections; the id maps of the instances, in order.
    fn place_instances(
        &self,
        c: &mut Collected,
        carriers: &mut [BTreeMap<String, Vec<String>>; 2],
        mut next: [i64; 2],
    ) -> Result<Vec<Ids>, DeckError> {
        let mut all = Vec::with_capacity(self.instances.len());
        let mut made = 0usize;
        for inst in &self.instances {
            let Some(p) = self.part(&inst.part) else {
                let names: Vec<&str> = self.parts.iter().map(|p| p.name.as_str()).collect();
                let msg = format!(
                    "*INSTANCE '{}': part '{}' is not defined (the file defines: {})",
                    inst.name,
                    inst.part,
                    list_or_none(&names)
                );
                return Err(self.err(inst.loc, msg));
            };
            let part = &self.parts[p];
            made = made.saturating_add(part.scope.size());
            if made > self.bytes {
                let msg = format!("*INSTANCE '{}': the assembly would have more nodes, elements and set members than its files have bytes", inst.name);
                return Err(self.err(inst.loc, msg));
            }
            let ids = self.place(c, inst, part, &mut next)?;
            self.instance_sets(c, inst, part, &ids, carriers)?;
            for sec in &part.scope.sections {
                let Some((list, _)) = find_set(&part.scope.element_sets, &sec.elset) else {
                    let msg = format!(
                        "*SOLID SECTION: element set '{}' is not defined in part '{}'",
                        sec.elset, part.name
                    );
                    return Err(self.err(sec.loc, msg));
                };
                let what = format!("element set '{}' of part '{}'", sec.elset, part.name);
                let elements = self.map_ids(list, &ids.elements, sec.loc, &what, "element")?;
                self.assign(c, &elements, sec)?;
            }
            all.push(ids);
        }
        Ok(all)
    }

    /// Instance `inst` of `part`: its nodes (placed) and elements with fresh ids from `next`.
    fn place(
        &self,
        c: &mut Collected,
        inst: &Instance,
        part: &Part,
        next: &mut [i64; 2],
    ) -> Result<Ids, DeckError> {
        let mut ids = Ids::default();
        let overflow = || self.err(inst.loc, format!("*INSTANCE '{}': ids overflow", inst.name));
        let scope = u32::try_from(c.scopes.len()).unwrap_or(u32::MAX);
        c.scopes
            .push(format!("part '{}', instance '{}'", part.name, inst.name));
        for &(id, x, loc) in &part.scope.nodes {
            let g = fresh(&mut next[0]).ok_or_else(overflow)?;
            if ids.nodes.insert(id, g).is_some() {
                return Err(self.err(
                    loc,
                    format!("node {id} defined twice in part '{}'", part.name),
                ));
            }
            let y = inst.placement.apply(x);
            if !y.iter().all(|v| v.is_finite()) {
                return Err(self.err(
                    inst.loc,
                    format!(
                        "*INSTANCE '{}': node {id} placed beyond the finite numbers",
                        inst.name
                    ),
                ));
            }
            c.nodes.push((g, y, loc));
        }
        for (eid, kind, conn, loc) in &part.scope.elements {
            let what = format!("element {eid} of part '{}'", part.name);
            let conn = self.map_ids(conn, &ids.nodes, *loc, &what, "node")?;
            let g = fresh(&mut next[1]).ok_or_else(overflow)?;
            if ids.elements.insert(*eid, g).is_some() {
                return Err(self.err(
                    *loc,
                    format!("element {eid} defined twice in part '{}'", part.name),
                ));
            }
            c.elements.push((g, *kind, conn, *loc));
            c.element_scope.insert(g, scope);
        }
        Ok(ids)
    }

    /// The sets of `part` as `i.s` for instance `inst` (ids `ids`), recorded in `carriers`.
    fn instance_sets(
        &self,
        c: &mut Collected,
        inst: &Instance,
        part: &Part,
        ids: &Ids,
        carriers: &mut [BTreeMap<String, Vec<String>>; 2],
    ) -> Result<(), DeckError> {
        let s = &part.scope;
        for (nodes, sets, map) in [
            (true, &s.node_sets, &ids.nodes),
            (false, &s.element_sets, &ids.elements),
        ] {
            let kind = if nodes { "node" } else { "element" };
            for (name, (list, loc)) in sets {
                let what = format!("{kind} set '{name}' of part '{}'", part.name);
                let mapped = self.map_ids(list, map, *loc, &what, kind)?;
                let full = format!("{}.{name}", inst.name);
                let target = if nodes {
                    &mut c.node_sets
                } else {
                    &mut c.element_sets
                };
                target.insert(full.clone(), (mapped, *loc));
                carriers[usize::from(!nodes)]
                    .entry(name.clone())
                    .or_default()
                    .push(full);
            }
        }
        Ok(())
    }

    /// The assembly's `*NSET`/`*ELSET, INSTANCE=` sets, by the instances' id maps `maps`.
    fn bound_sets(&self, c: &mut Collected, maps: &[Ids]) -> Result<(), DeckError> {
        for b in &self.bound {
            let kind = if b.nodes { "node" } else { "element" };
            let found = self
                .instances
                .iter()
                .position(|x| x.name.eq_ignore_ascii_case(&b.instance));
            let Some(ids) = found.and_then(|i| maps.get(i)) else {
                let msg = format!(
                    "{kind} set '{}': INSTANCE={} is not defined",
                    b.name, b.instance
                );
                return Err(self.err(b.loc, msg));
            };
            let map = if b.nodes { &ids.nodes } else { &ids.elements };
            let what = format!("{kind} set '{}' of instance '{}'", b.name, b.instance);
            let mapped = self.map_ids(&b.ids, map, b.loc, &what, kind)?;
            let target = if b.nodes {
                &mut c.node_sets
            } else {
                &mut c.element_sets
            };
            target
                .entry(b.name.clone())
                .or_insert((Vec::new(), b.loc))
                .0
                .extend(mapped);
        }
        Ok(())
    }

    /// The fresh ids of a part's ids `list` (`what` refers to `kind`s, at `loc`).
    fn map_ids(
        &self,
        list: &[i64],
        map: &HashMap<i64, i64>,
        loc: Loc,
        what: &str,
        kind: &str,
    ) -> Result<Vec<i64>, DeckError> {
        list.iter()
            .map(|id| {
                map.get(id).copied().ok_or_else(|| {
                    self.err(
                        loc,
                        format!("{what} refers to {kind} {id}, which the part does not define"),
                    )
                })
            })
            .collect()
    }

    /// Gives the material of section `sec` to `elements` (deck ids): the material must be
    /// defined with `*ELASTIC` and `*DENSITY`, and no element may have two sections.
    fn assign(&self, c: &mut Collected, elements: &[i64], sec: &Section) -> Result<(), DeckError> {
        let fail = |m: String| Err(self.err(sec.loc, format!("*SOLID SECTION: {m}")));
        let key = sec.material.to_ascii_uppercase();
        let Some(m) = self.materials.get(&key) else {
            let names: Vec<&str> = self.materials.keys().map(String::as_str).collect();
            return fail(format!(
                "material '{}' is not defined (the file defines: {})",
                sec.material,
                list_or_none(&names)
            ));
        };
        let (Some((young, poisson)), Some(density)) = (m.elastic, m.density) else {
            let lacks = match (m.elastic, m.density) {
                (None, None) => "*ELASTIC and *DENSITY",
                (None, _) => "*ELASTIC",
                _ => "*DENSITY",
            };
            return fail(format!(
                "material '{}' has no {lacks} (a modal model needs both)",
                sec.material
            ));
        };
        c.materials.insert(
            key.clone(),
            (
                Elastic {
                    young,
                    poisson,
                    density,
                },
                m.loc,
            ),
        );
        for &e in elements {
            if let Some((_, prev)) = c.element_material.insert(e, (key.clone(), sec.loc)) {
                if prev != sec.loc {
                    let file = self
                        .files
                        .get(prev.file)
                        .map(|p| p.display().to_string())
                        .unwrap_or_default();
                    return fail(format!(
                        "element set '{}' shares elements with the *SOLID SECTION at {file}:{}",
                        sec.elset, prev.line
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Gives each part set carried by a single instance (`carriers`: plain name -> full names,
/// node sets then element sets) its plain name too, unless a set has that name.
fn aliases(c: &mut Collected, carriers: &[BTreeMap<String, Vec<String>>; 2]) {
    for (k, carriers) in carriers.iter().enumerate() {
        let target = if k == 0 {
            &mut c.node_sets
        } else {
            &mut c.element_sets
        };
        for (name, fulls) in carriers {
            if let [full] = fulls.as_slice() {
                if let (false, Some(set)) = (target.contains_key(name), target.get(full).cloned()) {
                    target.insert(name.clone(), set);
                }
            }
        }
    }
}

/// Fresh ids of one instance: part id -> deck-wide id, for nodes and elements.
#[derive(Default)]
struct Ids {
    nodes: HashMap<i64, i64>,
    elements: HashMap<i64, i64>,
}

/// The next fresh id of counter `n`, advancing it (None past i64::MAX).
fn fresh(n: &mut i64) -> Option<i64> {
    let g = *n;
    *n = n.checked_add(1)?;
    Some(g)
}

/// Set `name` of `sets`: exactly, else ignoring case (Abaqus names are case-insensitive).
fn find_set<'a>(
    sets: &'a BTreeMap<String, (Vec<i64>, Loc)>,
    name: &str,
) -> Option<&'a (Vec<i64>, Loc)> {
    sets.get(name).or_else(|| {
        sets.iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v)
    })
}

/// `names` joined by commas, or "none".
fn list_or_none(names: &[&str]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// The solid of an Abaqus element type: C3D4, C3D10, C3D8 or C3D20 followed by formulation
/// letters (R reduced integration, I incompatible modes, H hybrid, M modified), which change
/// how Abaqus integrates the element, not its nodes: linercav integrates its own element.
fn solid_kind(t: &str) -> Option<ElementKind> {
    let rest = t.to_ascii_uppercase();
    let rest = rest.strip_prefix("C3D")?;
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let letters = &rest[digits.len()..];
    if !letters.chars().all(|c| "RIHM".contains(c)) {
        return None;
    }
    match digits.as_str() {
        "4" => Some(ElementKind::Tet4),
        "10" => Some(ElementKind::Tet10),
        "8" => Some(ElementKind::Hex8),
        "20" => Some(ElementKind::Hex20),
        _ => None,
    }
}

/// Set members a deck may hold per byte of its files, over all its sets (a set's GENERATE
/// line is a few bytes for many ids; a deck whose sets hold more is refused before it takes
/// the memory: every node in several sets stays far below it).
const SET_IDS_PER_BYTE: usize = 4;

/// The ids of a set's data line `l` (fields `f`): positive ids, or `first, last[, step]` when
/// `generate` (at most `room` of them: the rest of the deck's [`SET_IDS_PER_BYTE`] bound).
fn set_ids(
    f: &[&str],
    generate: bool,
    l: &str,
    room: usize,
    at: &dyn Fn(String) -> DeckError,
) -> Result<Vec<i64>, DeckError> {
    let mut ids = Vec::new();
    if generate {
        let range = || at(format!("expected 'first, last[, step]', found '{l}'"));
        let n: Vec<i64> = f
            .iter()
            .map(|w| w.parse())
            .collect::<Result<_, _>>()
            .map_err(|_| range())?;
        let (a, b, s) = match n[..] {
            [a, b] => (a, b, 1),
            [a, b, s] => (a, b, s),
            _ => return Err(range()),
        };
        if a <= 0 || s <= 0 || b < a {
            return Err(at(format!(
                "GENERATE {a}, {b}, {s} is not a range of positive ids"
            )));
        }
        if (b - a) / s >= room as i64 {
            return Err(at(format!(
                "GENERATE {a}, {b}, {s}: the deck's sets would hold more than {SET_IDS_PER_BYTE} ids per byte of its files"
            )));
        }
        ids.extend((a..=b).step_by(s as usize));
    } else {
        for w in f {
            let id = w.parse::<i64>().map_err(|_| {
                at(format!(
                    "'{w}' is not an id (sets of sets are not read: list the ids)"
                ))
            })?;
            if id <= 0 {
                return Err(at(format!("id {id}: ids must be positive integers")));
            }
            ids.push(id);
        }
    }
    Ok(ids)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TET: &str = "** a unit tetrahedron\n*Heading\n x\n*NODE, NSET=all\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n*ELEMENT, TYPE=C3D4, ELSET=solid\n1, 1, 2,\n 3, 4\n*NSET, NSET=tip\n4\n*NSET, NSET=base, GENERATE\n1, 3, 1\n*ELSET, ELSET=again, generate\n1, 1\n*MATERIAL, NAME=steel\n*ELASTIC\n2e11, 0.3\n";

    /// The unit tetrahedron's nodes.
    const UNIT: [V3; 4] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]];

    /// A part of one unit tetrahedron (sets `tip`, `solid`) and an assembly of `instances`.
    fn assembly(instances: &str) -> String {
        format!("*Heading\n*Part, name=Tet\n*Node\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n*Element, type=C3D4, elset=solid\n7, 1, 2, 3, 4\n*Nset, nset=tip\n4\n*End Part\n*Part, name=unused\n*Node\n1, 9., 9., 9.\n*End Part\n*Assembly, name=Asm\n{instances}*End Assembly\n*Step\n*Frequency\n10\n*Boundary\ntip, 1, 3\n*End Step\n")
    }

    fn close(a: V3, b: V3) -> bool {
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn sets_generate_and_continued_elements() {
        let m = parse(Path::new("t.inp"), TET).unwrap();
        assert_eq!(m.nodes.len(), 4);
        assert_eq!(m.blocks[0].conn, vec![0, 1, 2, 3]);
        assert_eq!(m.node_sets["tip"], vec![3]);
        assert_eq!(m.node_sets["base"], vec![0, 1, 2]);
        assert_eq!(m.node_sets["all"], vec![0, 1, 2, 3]);
        assert_eq!(m.element_sets["solid"], vec![0]);
        assert_eq!(
            m.node_sets["solid"],
            vec![0, 1, 2, 3],
            "an element set's nodes"
        );
        assert_eq!(m.element_sets["again"], vec![0]);
        assert!(
            m.materials.is_empty(),
            "a material no section uses stays out"
        );
    }

    /// Regression: GENERATE lines were bounded one by one (a line's range by the file's
    /// bytes), so 2000 lines of `1, 60000, 1` in a 26 kB deck asked for 0.5 GB and aborted
    /// under a memory cap; the deck's sets together now hold at most 4 ids per byte.
    #[test]
    fn regression_generated_sets_are_bounded_together() {
        let lines = "1, 60, 1\n".repeat(2000);
        let deck = format!("{TET}*NSET, NSET=boom, GENERATE\n{lines}");
        let e = parse(Path::new("t.inp"), &deck).unwrap_err();
        assert!(e.msg.contains("4 ids per byte"), "{e}");
        // fewer lines of it are read
        let deck = format!(
            "{TET}*NSET, NSET=boom, GENERATE\n{}",
            "1, 3, 1\n".repeat(20)
        );
        assert!(parse(Path::new("t.inp"), &deck).is_ok());
    }

    /// Regression: a second `*ELASTIC` in one `*MATERIAL` replaced the first silently (a
    /// first elastic mode of 637 Hz instead of 8870 Hz).
    #[test]
    fn regression_a_material_constant_given_twice_is_refused() {
        for second in ["*ELASTIC\n2e9, 0.3\n", "*DENSITY\n7800.\n*DENSITY\n10.\n"] {
            let deck = format!("{TET}{second}");
            let e = parse(Path::new("t.inp"), &deck).unwrap_err();
            assert!(e.msg.contains("given twice"), "{e}");
        }
    }

    #[test]
    fn bad_input_names_the_line() {
        let p = Path::new("t.inp");
        let e = parse(p, &TET.replace("C3D4", "C3D6")).unwrap_err();
        assert!(e.line == 9 && e.msg.contains("C3D6"), "{e}");
        let e = parse(p, &TET.replace("2, 1., 0., 0.", "2, 1., zero, 0.")).unwrap_err();
        assert!(e.line == 6 && e.msg.contains("zero"), "{e}");
        let e = parse(p, &TET.replace("1, 1, 2,\n 3, 4", "1, 1, 2,\n 3, 9")).unwrap_err();
        assert!(e.line == 10 && e.msg.contains("node 9"), "{e}");
        let e = parse(p, &TET.replace("*Heading", "*INCLUDE, INPUT=x.inp")).unwrap_err();
        assert!(
            e.line == 2 && e.msg.contains("INCLUDE") && e.msg.contains("x.inp"),
            "{e}"
        );
        let e = parse(p, &TET.replace("1, 3, 1\n", "3, 1\n")).unwrap_err();
        assert!(e.msg.contains("not a range"), "{e}");
        let e = parse(p, &TET.replace("*NSET, NSET=tip\n4", "*NSET, NSET=tip\n0")).unwrap_err();
        assert!(e.line == 13 && e.msg.contains("positive"), "{e}");
    }

    #[test]
    fn the_meshio_fixtures_still_read() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        for f in ["block_hex20.inp", "block_tet10.inp", "liner_hex20.inp"] {
            let m = read(&dir.join(f)).unwrap();
            assert!(m.num_elements() > 0 && m.materials.is_empty(), "{f}");
        }
    }

    #[test]
    fn node_id_zero_is_refused_at_its_line() {
        let e = parse(
            Path::new("t.inp"),
            &TET.replace("1, 0., 0., 0.", "0, 0., 0., 0."),
        )
        .unwrap_err();
        assert!(
            e.line == 5 && e.msg.contains("*NODE") && e.msg.contains("positive"),
            "{e}"
        );
        let e = parse(
            Path::new("t.inp"),
            &TET.replace("1, 0., 0., 0.", "-3, 0., 0., 0."),
        )
        .unwrap_err();
        assert!(e.line == 5 && e.msg.contains("-3"), "{e}");
    }

    #[test]
    fn instances_are_disjoint_placed_bodies() {
        let deck = assembly("*Instance, name=A, part=Tet\n*End Instance\n*Instance, name=B, part=tet\n 10., 0., 0.\n*End Instance\n*Instance, name=C, part=Tet\n0., 0., 0.\n0., 0., 0., 0., 0., 1., 90.\n*End Instance\n*Nset, nset=pick, instance=B\n1\n*Elset, elset=both, instance=A\n7\n*Elset, elset=both, instance=C\n7\n");
        let m = parse(Path::new("a.inp"), &deck).unwrap();
        assert_eq!(
            m.nodes.len(),
            12,
            "three bodies of 4 nodes (the unused part adds nothing)"
        );
        assert_eq!(
            m.blocks[0].conn,
            (0..12).collect::<Vec<_>>(),
            "no node shared"
        );
        for (k, p) in UNIT.iter().enumerate() {
            assert!(close(m.nodes[k], *p), "A {k}: {:?}", m.nodes[k]);
            assert!(
                close(m.nodes[4 + k], [p[0] + 10.0, p[1], p[2]]),
                "B {k}: {:?}",
                m.nodes[4 + k]
            );
            assert!(
                close(m.nodes[8 + k], [-p[1], p[0], p[2]]),
                "C {k}: {:?}",
                m.nodes[8 + k]
            );
        }
        assert_eq!(m.node_sets["A.tip"], vec![3]);
        assert_eq!(m.node_sets["B.tip"], vec![7]);
        assert_eq!(m.node_sets["C.tip"], vec![11]);
        assert_eq!(m.element_sets["C.solid"], vec![2]);
        assert!(
            !m.node_sets.contains_key("tip"),
            "three instances carry 'tip'"
        );
        assert_eq!(
            m.node_sets["pick"],
            vec![4],
            "assembly set of instance B's node 1"
        );
        assert_eq!(m.element_sets["both"], vec![0, 2]);
    }

    #[test]
    fn a_single_instance_keeps_plain_set_names() {
        let m = parse(
            Path::new("a.inp"),
            &assembly("*Instance, name=Only, part=Tet\n*End Instance\n"),
        )
        .unwrap();
        assert_eq!(m.node_sets["tip"], vec![3]);
        assert_eq!(m.node_sets["Only.tip"], vec![3]);
        assert_eq!(m.element_sets["solid"], vec![0]);
    }

    #[test]
    fn assembly_errors_name_the_instance() {
        let p = Path::new("a.inp");
        let e = parse(
            p,
            &assembly("*Instance, name=X, part=Nope\n*End Instance\n"),
        )
        .unwrap_err();
        assert!(e.msg.contains("Nope") && e.msg.contains("Tet"), "{e}");
        let e = parse(
            p,
            &assembly("*Instance, name=X, instance=Old\n*End Instance\n"),
        )
        .unwrap_err();
        assert!(e.msg.contains("INSTANCE="), "{e}");
        let e = parse(
            p,
            &assembly("*Instance, name=X, part=Tet\n*Node\n1, 0., 0., 0.\n*End Instance\n"),
        )
        .unwrap_err();
        assert!(
            e.msg.contains("*NODE") && e.msg.contains("inside *INSTANCE"),
            "{e}"
        );
        let e = parse(p, "*Part, name=P\n*End Part\n").unwrap_err();
        assert!(e.line == 1 && e.msg.contains("*ASSEMBLY"), "{e}");
    }

    #[test]
    fn nested_includes_read_as_the_flat_file() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let (head, rest) = TET.split_at(TET.find("*ELEMENT").unwrap());
        let (nodes_head, nodes) = head.split_at(head.find("1, 0.").unwrap());
        std::fs::write(
            dir.path().join("main.inp"),
            format!("{nodes_head}*INCLUDE, INPUT=\"sub/a.inp\"\n{rest}"),
        )
        .unwrap();
        std::fs::write(
            sub.join("a.inp"),
            format!(
                "{}\n*include, input=b.inp\n",
                &nodes[..nodes.find("3, 0.").unwrap()]
            ),
        )
        .unwrap();
        std::fs::write(sub.join("b.inp"), &nodes[nodes.find("3, 0.").unwrap()..]).unwrap();
        // the same mesh; only where its elements were defined differs
        let mut m = read(&dir.path().join("main.inp")).unwrap();
        let mut flat = parse(Path::new("t.inp"), TET).unwrap();
        m.element_lines = None;
        flat.element_lines = None;
        assert_eq!(m, flat);
    }

    #[test]
    fn include_cycles_and_keywords_in_included_files_are_refused_there() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.inp"), dir.path().join("b.inp"));
        std::fs::write(&a, format!("{TET}*INCLUDE, INPUT=b.inp\n")).unwrap();
        std::fs::write(&b, "** b\n*INCLUDE, INPUT=a.inp\n").unwrap();
        let e = read(&a).unwrap_err();
        assert!(e.path == b && e.line == 2 && e.msg.contains("cycle"), "{e}");
        std::fs::write(&b, "** b\n*TIE, NAME=t\nx, y\n").unwrap();
        let e = read(&a).unwrap_err();
        assert!(
            e.path == b && e.line == 2 && e.msg.contains("*TIE is not read"),
            "{e}"
        );
    }

    #[test]
    fn cylindrical_spherical_and_local_systems_give_rectangular_coordinates() {
        let deck = TET
            .replace("*NODE, NSET=all\n1, 0., 0., 0.\n2, 1., 0., 0.", "*NODE, NSET=all, SYSTEM=C\n1, 0., 0., 0.\n2, 2., 90., 3.\n*NODE, SYSTEM=S\n5, 2., 0., 90.\n*SYSTEM\n1., 0., 0., 1., 1., 0.\n*NODE\n6, 1., 0., 0.\n*SYSTEM\n*NODE")
            .replace("*NSET, NSET=tip", "*NSET, NSET=extra\n5, 6\n*NSET, NSET=tip");
        let m = parse(Path::new("t.inp"), &deck).unwrap();
        assert!(close(m.nodes[1], [0.0, 2.0, 3.0]), "{:?}", m.nodes[1]);
        assert!(close(m.nodes[2], [0.0, 0.0, 2.0]), "{:?}", m.nodes[2]);
        assert!(
            close(m.nodes[3], [1.0, 1.0, 0.0]),
            "local x along global Y: {:?}",
            m.nodes[3]
        );
        assert!(
            close(m.nodes[4], [0.0, 1.0, 0.0]),
            "*SYSTEM without data resets: {:?}",
            m.nodes[4]
        );
    }

    #[test]
    fn two_sections_give_two_materials_per_element() {
        let deck = "*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n5, 1., 1., 1.\n*ELEMENT, TYPE=C3D4, ELSET=one\n1, 1, 2, 3, 4\n*SOLID SECTION, ELSET=two, MATERIAL=STEEL\n,\n*ELEMENT, TYPE=C3D4\n2, 2, 3, 4, 5\n*ELSET, ELSET=two\n2\n*Solid Section, elset=one, material=Alu\n*Material, name=steel\n*Density\n7.85e-9\n*Elastic\n210000., 0.3\n*Expansion\n1.2e-5\n*Material, name=alu\n*Elastic, type=isotropic\n70000., 0.33, 20.\n*Density\n2.7e-9\n";
        let m = parse(Path::new("t.inp"), deck).unwrap();
        let names: Vec<&str> = m.materials.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(names, ["ALU", "STEEL"]);
        assert_eq!(
            m.materials[0].elastic,
            Elastic {
                young: 70000.,
                poisson: 0.33,
                density: 2.7e-9
            }
        );
        assert_eq!(
            m.materials[1].elastic,
            Elastic {
                young: 210000.,
                poisson: 0.3,
                density: 7.85e-9
            }
        );
        assert_eq!(m.element_material, vec![0, 1]);
        let e = parse(Path::new("t.inp"), &deck.replace("*Density\n7.85e-9\n", "")).unwrap_err();
        assert!(
            e.line == 9 && e.msg.contains("*DENSITY") && e.msg.contains("STEEL"),
            "{e}"
        );
        let e = parse(
            Path::new("t.inp"),
            &deck.replace("ELSET=two, MATERIAL", "ELSET=three, MATERIAL"),
        )
        .unwrap_err();
        assert!(e.line == 9 && e.msg.contains("three"), "{e}");
        // an *ELSET with no data lines is defined, empty: its section assigns nothing (it was
        // refused as "not defined"); element 2 moved to set one takes its material
        let empty = deck.replace(
            "*ELSET, ELSET=two\n2\n",
            "*ELSET, ELSET=two\n*ELSET, ELSET=one\n2\n",
        );
        let m = parse(Path::new("t.inp"), &empty).unwrap();
        assert_eq!(m.element_material, vec![0, 0]);
    }

    #[test]
    fn a_part_section_applies_to_every_instance() {
        let deck = assembly("*Instance, name=A, part=Tet\n*End Instance\n*Instance, name=B, part=Tet\n1., 0., 0.\n*End Instance\n")
            .replace("*End Part\n*Part, name=unused", "*Solid Section, elset=solid, material=Steel\n*End Part\n*Part, name=unused")
            + "*Material, name=Steel\n*Elastic\n2e11, 0.3\n*Density\n7850.\n";
        let m = parse(Path::new("a.inp"), &deck).unwrap();
        assert_eq!(m.materials.len(), 1);
        assert_eq!(m.element_material, vec![0, 0]);
    }

    #[test]
    fn unread_keywords_and_material_forms_are_refused() {
        let p = Path::new("t.inp");
        let e = parse(
            p,
            &TET.replace("*ELASTIC\n", "*ELASTIC, TYPE=ORTHOTROPIC\n"),
        )
        .unwrap_err();
        assert!(e.line == 19 && e.msg.contains("ORTHOTROPIC"), "{e}");
        let e = parse(
            p,
            &TET.replace("2e11, 0.3\n", "2e11, 0.3, 20.\n1.9e11, 0.3, 200.\n"),
        )
        .unwrap_err();
        assert!(e.line == 21 && e.msg.contains("second data line"), "{e}");
        let e = parse(p, &format!("{TET}*TIE, NAME=t\na, b\n")).unwrap_err();
        assert!(e.line == 21 && e.msg == "*TIE is not read by linercav (it may change the model's geometry, material or connectivity)", "{e}");
        let e = parse(p, &TET.replace("*Heading", "*Frobnicate, x=1")).unwrap_err();
        assert!(e.line == 2 && e.msg.contains("*FROBNICATE"), "{e}");
        for kw in [
            "*MASS, ELSET=x",
            "*Kinematic Coupling, ref node=1",
            "*NGEN",
            "*Shell Section, elset=x",
        ] {
            let e = parse(p, &format!("{TET}{kw}\n")).unwrap_err();
            assert!(e.line == 21 && e.msg.contains("is not read"), "{kw}: {e}");
        }
    }
}
