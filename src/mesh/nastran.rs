//! Reader of Nastran bulk data (`.bdf`, `.nas`): the solid mesh, its node sets, coordinate
//! systems and materials.
//!
//! **Sections.** In the main file everything before `BEGIN BULK` (when present: executive and
//! case control, `INCLUDE`s there too) is skipped; `ENDDATA` in any file ends the bulk data.
//! `INCLUDE 'file'` or `INCLUDE file` anywhere in the bulk section reads `file` (relative to
//! the directory of the including file) in its place; a quoted name may continue over several
//! lines (the pieces are joined, without the whitespace at the line breaks). Includes nest;
//! a cycle, a depth beyond 32, a missing file or more than [`LIMIT_MESH`] bytes in all are
//! refused at the `INCLUDE` line. Messages name the file (the included one for its cards) and
//! line.
//!
//! **Fields.** Small (8 columns; a line holding tabs has them expanded to the next multiple of
//! 8 columns first), large (`*` after the name, 16 columns, continuation lines starting with
//! `*`) and free (comma-separated, a large free card named with `*`; a 10th field is the
//! continuation field, whatever it holds); continuation lines start with `+` or `*`
//! or, in small field, with a blank name field; a line that ends a card early is continued by
//! the next such line; a continuation line with no card before it is refused. Reals in any
//! Nastran form: `1.5E-3`, `1.5D-3`, `1.5-3` (exponent without a letter), `.5`, `7.`.
//!
//! **Cards read.**
//! - GRID (ID, CP, X1-X3, CD): X blank is 0.0; the position is given in system CP (blank: the
//!   GRDSET default, else the basic system) and converted to the basic system. CD must be
//!   blank, 0, -1 or a defined system: linercav works in the basic system, so a nodal
//!   displacement system changes nothing it computes and is otherwise ignored, as are PS
//!   (permanent constraints: linercav sets its own) and SEID (superelement id).
//! - GRDSET: its CP and CD are the defaults of GRIDs with those fields blank (one GRDSET).
//! - CORD2R, CORD2C, CORD2S (CID, RID, A, B, C: A the origin, B on the local z axis, C in the
//!   local x-z plane, given in system RID, blank or 0 the basic one); chains of references are
//!   resolved after all cards are read, whatever their order; undefined references, cycles,
//!   degenerate points and ids <= 0 are refused; blank coordinates are 0.0 but the
//!   continuation with C1-C3 must be there. Rectangular (x, y, z), cylindrical
//!   (r, theta \[deg\], z) and spherical (r, theta \[deg\] from the z axis, phi \[deg\] in the x-y
//!   plane) coordinates. CORD1R/C/S (systems through grid points) are refused.
//! - CTETRA with 4 or 10 nodes, CHEXA with 8 or 20 nodes (CPENTA, CPYRA refused).
//! - SET1 (node ids, `THRU` ranges): node sets named by a HyperMesh comment
//!   `$HMSET  SID  TYPE "name"` anywhere in the deck, else by their id (`"7"`).
//! - MAT1 (MID, E, G, NU, RHO): E and NU as given; E blank: E = 2 (1 + NU) G; NU blank:
//!   NU = E / (2 G) - 1; RHO must be given and positive (the modes need mass); E > 0 and
//!   -1 < NU < 0.5. Named `MAT1 <mid>`, or by a HyperMesh comment `$HMNAME MAT <mid> "name"`.
//!   G given beside E and NU is not used (the solid is isotropic): refused when not positive,
//!   warned of when more than 1 % from E / (2 (1 + NU)). Other fields (expansion, damping,
//!   allowables) are ignored.
//! - PSOLID (PID, MID, ..., FCTN): every CTETRA/CHEXA with the property gets MAT1 MID (FCTN
//!   blank or SMECH; fluid elements refused). When the deck has a PSOLID, every element's
//!   property (a blank PID is the element id) must be one, and a PSOLID's MID a MAT1 of the
//!   deck; without a PSOLID no material is taken from the deck (the scene gives it).
//! - PARAM: ignored, except WTMASS other than 1 (mass scaling) which is refused.
//!
//! **Cards ignored** (they cannot change the solid model's geometry, material or
//! connectivity; see [`IGNORED`]): loads FORCE, FORCE1, FORCE2, MOMENT, MOMENT1, MOMENT2,
//! LOAD, PLOAD, PLOAD1, PLOAD2, PLOAD4, GRAV, ACCEL, ACCEL1, RFORCE, SLOAD, LSEQ, DEFORM,
//! temperatures TEMP, TEMPD, TEMPP1, dynamic loads DLOAD, RLOAD1, RLOAD2, TLOAD1, TLOAD2,
//! DAREA, DPHASE, DELAY and tables TABLED1-4, TABLEM1-4, TABDMP1, RANDPS, RANDT1, TABRND1;
//! constraints (linercav sets its own) SPC, SPC1, SPCADD, SPCD, SUPORT, SUPORT1 and reduction
//! sets ASET, ASET1, OMIT, OMIT1, QSET, QSET1, BSET, BSET1, CSET, CSET1; thermal materials
//! MAT4, MAT5, MATT4, MATT5; solution and output control EIGRL, EIGR, EIGC, EIGB, FREQ,
//! FREQ1-5, TSTEP, TSTEPNL, NLPARM, NLPCI, DTI, PLOTEL; comments (`$` first on a line).
//!
//! **Cards refused**, with file, line and name: every other card (shells, beams, springs,
//! masses CONM2 and CMASS*, rigid elements RBE2, RBE3, RBAR, MPCs, other properties, MAT2,
//! MAT8, MAT9, MAT10, MATS1, MATT1 and other materials, `BEGIN SUPER` sections, unknown cards
//! ...), since it may change the model's geometry, material or connectivity. Two materials
//! or two node sets with one name are refused, as are SET1s holding more than 4 ids per byte
//! of the deck in all (a hostile THRU range).
//!
//! Ids: node and element ids <= 0 are refused, as are set, property, material and coordinate
//! system ids <= 0. Element sets: the property id of the solid elements, `"PID<n>"` (none for
//! a blank PID without PSOLIDs). Coordinates are in the deck's unit (metres unless the scene
//! says millimetres), material constants in its unit system.

use super::collect::DeckError;
use super::collect::{read_mesh_text, reorder, Collected, Loc, HEX20_NASTRAN, TET10_DECK};
use super::Mesh;
use crate::files::LIMIT_MESH;
use crate::scene::spec::Elastic;
use crate::scene::spec::ElementKind;
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// Deepest nesting of INCLUDEs read.
const MAX_INCLUDE_DEPTH: usize = 32;

/// Ignored loads: static loads, accelerations, temperatures (temperature-dependent materials
/// are refused), dynamic loads and their tables.
const IGNORED_LOADS: &[&str] = &[
    "FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "LOAD", "PLOAD", "PLOAD1",
    "PLOAD2", "PLOAD4", "GRAV", "ACCEL", "ACCEL1", "RFORCE", "SLOAD", "LSEQ", "DEFORM", "TEMP",
    "TEMPD", "TEMPP1", "DLOAD", "RLOAD1", "RLOAD2", "TLOAD1", "TLOAD2", "DAREA", "DPHASE", "DELAY",
    "TABLED1", "TABLED2", "TABLED3", "TABLED4", "TABLEM1", "TABLEM2", "TABLEM3", "TABLEM4",
    "TABDMP1", "RANDPS", "RANDT1", "TABRND1",
];
/// Ignored constraints (linercav sets its own) and reduction sets.
const IGNORED_CONSTRAINTS: &[&str] = &[
    "SPC", "SPC1", "SPCADD", "SPCD", "SUPORT", "SUPORT1", "ASET", "ASET1", "OMIT", "OMIT1", "QSET",
    "QSET1", "BSET", "BSET1", "CSET", "CSET1",
];
/// Ignored thermal-only materials, solution control (eigenvalues, frequencies, time steps,
/// nonlinear iterations), direct table input and plot elements.
const IGNORED_CONTROL: &[&str] = &[
    "MAT4", "MAT5", "MATT4", "MATT5", "EIGRL", "EIGR", "EIGC", "EIGB", "FREQ", "FREQ1", "FREQ2",
    "FREQ3", "FREQ4", "FREQ5", "TSTEP", "TSTEPNL", "NLPARM", "NLPCI", "DTI", "PLOTEL",
];
/// Cards that cannot change the solid model's geometry, material or connectivity, read past.
pub const IGNORED: [&[&str]; 3] = [IGNORED_LOADS, IGNORED_CONSTRAINTS, IGNORED_CONTROL];

/// Reads a bulk-data file from disk, with the files it includes.
pub fn read(path: &Path) -> Result<Mesh, DeckError> {
    let text = read_mesh_text(path, "expected Nastran bulk data (ASCII)")?;
    parse(path, &text)
}

/// Parses bulk data: `text` is the content of `path`, whose directory is where relative
/// INCLUDEs are looked for (and which messages name).
pub fn parse(path: &Path, text: &str) -> Result<Mesh, DeckError> {
    let mut reader = Reader::new(path, text.len() as u64);
    reader.read(0, text, true)?;
    let mut c = Collected::new(path);
    c.files = std::mem::take(&mut reader.files);
    let mut m = Model {
        limit: reader.bytes,
        ..Default::default()
    };
    for card in &reader.cards {
        if let Some(msg) = refusal(&card.name) {
            return Err(c.err_at(card.loc, msg));
        }
        handle(card, &mut m, &mut c)
            .map_err(|msg| c.err_at(card.loc, format!("{}: {msg}", card.name)))?;
    }
    finish(m, &reader, &mut c)?;
    let constraints = ["SPC", "SPC1", "SPCADD", "SPCD", "SUPORT", "SUPORT1"];
    if let Some(card) = reader
        .cards
        .iter()
        .find(|k| constraints.contains(&k.name.as_str()))
    {
        crate::text::warn(format!("{}", c.err_at(card.loc, not_applied(&card.name))));
    }
    c.into_mesh()
}

/// The warning for a deck's constraint card `name`: read past, not applied (a user who
/// clamped the deck would otherwise get free-free modes, said only as "free-free" in the
/// output).
fn not_applied(name: &str) -> String {
    format!("{name} and the deck's other constraints are not applied: linercav holds only the node sets named by --fix or a part's `fix` key")
}

/// A message about a card, or its field (0-based data field `k`); the reader adds the file,
/// line and card name ([`read`]).
#[derive(Debug, Clone, PartialEq)]
struct CardError(String);

impl std::fmt::Display for CardError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl From<String> for CardError {
    fn from(msg: String) -> Self {
        CardError(msg)
    }
}

impl From<&str> for CardError {
    fn from(msg: &str) -> Self {
        CardError(msg.to_string())
    }
}

/// A card's result.
type R<T> = Result<T, CardError>;

/// One card: its name (upper case, without `*`), data fields and where it starts.
struct Card {
    name: String,
    fields: Vec<String>,
    loc: Loc,
}

/// The Nastran number of data field `k` (0-based): fields 2-9 of the first line, then of the
/// continuations.
fn field_no(k: usize) -> String {
    if k < 8 {
        format!("field {}", k + 2)
    } else {
        format!("field {} of continuation {}", k % 8 + 2, k / 8)
    }
}

impl Card {
    /// Data field `k`, trimmed ("" when absent).
    fn text(&self, k: usize) -> &str {
        self.fields.get(k).map_or("", |s| s.trim())
    }
    /// An integer field that may be blank.
    fn opt_int(&self, k: usize, what: &str) -> R<Option<i64>> {
        let f = self.text(k);
        if f.is_empty() {
            return Ok(None);
        }
        f.parse::<i64>()
            .map(Some)
            .map_err(|_| format!("{} ({what}) is '{f}', expected an integer", field_no(k)).into())
    }
    /// An integer field that must be given.
    fn int(&self, k: usize, what: &str) -> R<i64> {
        self.opt_int(k, what)?
            .ok_or_else(|| format!("{} ({what}) is blank, expected an integer", field_no(k)).into())
    }
    /// An id: a positive integer.
    fn id(&self, k: usize, what: &str) -> R<i64> {
        let v = self.int(k, what)?;
        if v <= 0 {
            return Err(format!(
                "{} ({what}) is {v}, expected a positive integer",
                field_no(k)
            )
            .into());
        }
        Ok(v)
    }
    /// A real field that may be blank.
    fn opt_real(&self, k: usize, what: &str) -> R<Option<f64>> {
        let f = self.text(k);
        if f.is_empty() {
            return Ok(None);
        }
        real(f).map(Some).ok_or_else(|| {
            format!("{} ({what}) is '{f}', expected a real number", field_no(k)).into()
        })
    }
}

/// Expands tabs to the next multiple of 8 columns.
fn expand_tabs(l: &str) -> String {
    let mut out = String::with_capacity(l.len() + 16);
    let mut col = 0;
    for ch in l.chars() {
        if ch == '\t' {
            let next = (col / 8 + 1) * 8;
            out.extend(std::iter::repeat_n(' ', next - col));
            col = next;
        } else {
            out.push(ch);
            col += 1;
        }
    }
    out
}

/// Splits a physical line into (name field, data fields, whether it is a continuation).
fn split_line(l: &str) -> (String, Vec<String>, bool) {
    if l.contains(',') {
        let mut parts: Vec<String> = l.split(',').map(|f| f.trim().to_string()).collect();
        let first = parts.remove(0);
        let cont = first.starts_with('+') || first.starts_with('*') || first.is_empty();
        let large = first.ends_with('*') || first.starts_with('*');
        // the 10th field of a small free-field line is its continuation field, whatever it
        // holds (a marker need not start with '+': `CHEXA,1,1,1,2,3,4,5,,6` read the marker
        // 6 as a node, in place of the blank G6)
        if !large && parts.len() == 9 {
            parts.pop();
        }
        return (first, parts, cont);
    }
    let expanded;
    let l = if l.contains('\t') {
        expanded = expand_tabs(l);
        expanded.as_str()
    } else {
        l
    };
    let chars: Vec<char> = l.chars().collect();
    let field = |a: usize, b: usize| -> String {
        chars
            .get(a.min(chars.len())..b.min(chars.len()))
            .map(|s| s.iter().collect::<String>().trim().to_string())
            .unwrap_or_default()
    };
    let first = field(0, 8);
    let large = first.ends_with('*') || first.starts_with('*');
    let width = if large { 16 } else { 8 };
    let count = if large { 4 } else { 8 };
    let fields = (0..count)
        .map(|k| field(8 + k * width, 8 + (k + 1) * width))
        .collect();
    let cont = first.starts_with('+') || first.starts_with('*') || first.is_empty();
    (first, fields, cont)
}

/// A Nastran real: `1.5E-3`, `1.5D-3`, `1.5-3`, `-.5+2`, `7.`.
fn real(s: &str) -> Option<f64> {
    let t = s.trim().replace(['D', 'd'], "E");
    if let Ok(v) = t.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    // an exponent sign without its letter, after the first character
    let b = t.as_bytes();
    let k = (1..b.len())
        .find(|&i| (b[i] == b'+' || b[i] == b'-') && b[i - 1] != b'E' && b[i - 1] != b'e')?;
    let v: f64 = format!("{}E{}", t.get(..k)?, t.get(k..)?).parse().ok()?;
    v.is_finite().then_some(v)
}

/// Reads the lines of the main file and of the files it includes into cards.
struct Reader {
    /// The main file, then every included file in reading order.
    files: Vec<PathBuf>,
    cards: Vec<Card>,
    /// SET1 id -> name (`$HMSET`).
    set_names: BTreeMap<i64, String>,
    /// MAT1 id -> name (`$HMNAME MAT`).
    mat_names: BTreeMap<i64, String>,
    /// The files being read (canonical paths), outermost first.
    stack: Vec<PathBuf>,
    /// Bytes of text read, all files.
    bytes: u64,
    /// Whether the next continuation line continues the last card.
    open: bool,
}

/// What a bulk line asks of the reader.
enum Flow {
    Go,
    End,
}

impl Reader {
    fn new(path: &Path, bytes: u64) -> Self {
        Reader {
            files: vec![path.to_path_buf()],
            cards: Vec::new(),
            set_names: BTreeMap::new(),
            mat_names: BTreeMap::new(),
            stack: vec![std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())],
            bytes,
            open: false,
        }
    }

    fn err(&self, file: usize, line: usize, msg: String) -> DeckError {
        DeckError {
            path: self.files.get(file).cloned().unwrap_or_default(),
            line,
            msg,
        }
    }

    /// Reads file number `file` (its `text`): the bulk section only for the main file.
    /// Returns [`Flow::End`] at `ENDDATA`.
    fn read(&mut self, file: usize, text: &str, main: bool) -> Result<Flow, DeckError> {
        let from = if main {
            text.lines().position(is_begin_bulk).map_or(0, |k| k + 1)
        } else {
            0
        };
        self.open = false;
        let mut lines = text.lines().enumerate().skip(from);
        while let Some((i, raw)) = lines.next() {
            let l = raw.trim_end();
            let t = l.trim_start();
            if let Some(c) = t.strip_prefix('$') {
                self.comment(c);
                continue;
            }
            if t.is_empty() || is_begin_bulk(t) {
                continue;
            }
            let upper: String = t.chars().take(8).collect::<String>().to_ascii_uppercase();
            if upper.starts_with("ENDDATA") {
                return Ok(Flow::End);
            }
            if let Some(rest) = include_rest(t) {
                let name = include_name(rest, &mut lines)
                    .map_err(|m| self.err(file, i + 1, format!("INCLUDE: {m}")))?;
                if let Flow::End = self.include(file, i + 1, &name)? {
                    return Ok(Flow::End);
                }
                self.open = false;
                continue;
            }
            if upper.starts_with("BEGIN") {
                return Err(self.err(file, i + 1, format!(
                    "'{}' is not read: linercav reads one bulk section (no part superelements or auxiliary models)",
                    clip(t)
                )));
            }
            self.line(file, i + 1, l)?;
        }
        Ok(Flow::Go)
    }

    /// A comment: `$HMSET SID TYPE "name"` names a SET1, `$HMNAME MAT MID"name"` a MAT1.
    fn comment(&mut self, c: &str) {
        let c = c.trim_start();
        if let Some(rest) = c.strip_prefix("HMSET") {
            let sid = rest.split_whitespace().next().and_then(|w| w.parse().ok());
            if let (Some(sid), Some(name)) = (sid, rest.split('"').nth(1)) {
                self.set_names.insert(sid, name.to_string());
            }
        } else if let Some(rest) = c.strip_prefix("HMNAME") {
            let Some(rest) = rest.trim_start().strip_prefix("MAT") else {
                return;
            };
            if !rest.starts_with([' ', '\t']) {
                return; // MATS, MATT ...
            }
            let mid = rest.split('"').next().and_then(|w| w.trim().parse().ok());
            if let (Some(mid), Some(name)) = (mid, rest.split('"').nth(1)) {
                self.mat_names.insert(mid, name.to_string());
            }
        }
    }

    /// A card's line or its continuation.
    fn line(&mut self, file: usize, line: usize, l: &str) -> Result<(), DeckError> {
        let (first, fields, cont) = split_line(l);
        match (cont, self.cards.last_mut()) {
            (true, Some(card)) if self.open => card.fields.extend(fields),
            (true, _) => {
                return Err(self.err(
                    file,
                    line,
                    format!("'{}' is a continuation line (its name field is blank or starts with '+' or '*') with no card before it to continue", clip(l)),
                ))
            }
            _ => {
                self.cards.push(Card {
                    name: first.trim_end_matches('*').to_ascii_uppercase(),
                    fields,
                    loc: Loc { file, line },
                });
                self.open = true;
            }
        }
        Ok(())
    }

    /// Reads the file `name` that file number `file` includes at `line`.
    fn include(&mut self, file: usize, line: usize, name: &str) -> Result<Flow, DeckError> {
        let shown = clip_to(name, 240);
        let at = |s: &Self, msg: String| s.err(file, line, format!("INCLUDE '{shown}': {msg}"));
        let dir = self
            .files
            .get(file)
            .and_then(|p| p.parent())
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let path = dir.join(name);
        let canon = std::fs::canonicalize(&path)
            .map_err(|e| at(self, format!("cannot open {}: {e}", path.display())))?;
        if self.stack.contains(&canon) {
            return Err(at(self, format!(
                "{} is already being read (an include cycle): a file cannot include itself, directly or through others",
                path.display()
            )));
        }
        if self.files.len() >= super::DECK_FILES {
            return Err(at(
                self,
                format!(
                    "more than {} files read (each include counted)",
                    super::DECK_FILES
                ),
            ));
        }
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(at(self, format!(
                "includes nest deeper than {MAX_INCLUDE_DEPTH} files: expected at most {MAX_INCLUDE_DEPTH} levels"
            )));
        }
        let size = std::fs::metadata(&canon).map(|m| m.len()).unwrap_or(0);
        if self.bytes.saturating_add(size) > LIMIT_MESH {
            return Err(at(self, format!(
                "the deck with its includes exceeds {LIMIT_MESH} bytes, the size accepted for a mesh"
            )));
        }
        let text = read_mesh_text(&path, "expected Nastran bulk data (ASCII)").map_err(|e| {
            if e.line > 0 {
                e
            } else {
                at(self, e.msg)
            }
        })?;
        self.bytes += text.len() as u64;
        self.files.push(path);
        self.stack.push(canon);
        let flow = self.read(self.files.len() - 1, &text, false);
        self.stack.pop();
        flow
    }
}

/// Whether a line is `BEGIN BULK` (any case and spacing).
fn is_begin_bulk(l: &str) -> bool {
    let mut w = l.split_whitespace().map(|w| w.to_ascii_uppercase());
    w.next().as_deref() == Some("BEGIN") && w.next().is_some_and(|b| b.starts_with("BULK"))
}

/// What follows the keyword of an `INCLUDE` line.
fn include_rest(t: &str) -> Option<&str> {
    let head = t.get(..7)?;
    if !head.eq_ignore_ascii_case("INCLUDE") {
        return None;
    }
    let rest = t.get(7..)?;
    (rest.is_empty() || rest.starts_with([' ', '\t', '\''])).then_some(rest)
}

/// The file name of an INCLUDE: `rest` (after the keyword), a quoted name continued on the
/// next `lines` while its quote is open (pieces joined without the whitespace at the line
/// breaks), or an unquoted word.
fn include_name<'a>(rest: &str, lines: &mut impl Iterator<Item = (usize, &'a str)>) -> R<String> {
    let rest = rest.trim();
    let name = if let Some(first) = rest.strip_prefix('\'') {
        let mut name = String::new();
        let mut piece = first.to_string();
        loop {
            if let Some(k) = piece.find('\'') {
                name.push_str(&piece[..k]);
                break;
            }
            name.push_str(piece.trim_end());
            let Some((_, l)) = lines.next() else {
                return Err("the quoted file name is not closed (expected a closing ')".into());
            };
            piece = l.trim().to_string();
        }
        name.trim().to_string()
    } else {
        rest.split_whitespace().next().unwrap_or("").to_string()
    };
    if name.is_empty() {
        return Err("no file name: expected INCLUDE 'file' or INCLUDE file".into());
    }
    Ok(name)
}

/// At most 24 characters of `s`, for messages.
fn clip(s: &str) -> String {
    clip_to(s, 24)
}

/// At most `n` characters of `s`, for messages.
fn clip_to(s: &str, n: usize) -> String {
    let t = s.trim();
    match t.char_indices().nth(n) {
        Some((k, _)) => format!("{}...", &t[..k]),
        None => t.to_string(),
    }
}

/// A GRID as given: position in system `cp`, displacement system `cd` (None: blank).
struct RawGrid {
    id: i64,
    cp: Option<i64>,
    x: [f64; 3],
    cd: Option<i64>,
    loc: Loc,
}

/// A solid element's property as given (None: blank).
struct ElementProperty {
    eid: i64,
    pid: Option<i64>,
    loc: Loc,
    card: &'static str,
}

/// The kind of a coordinate system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SysKind {
    /// x, y, z
    Rect,
    /// r, theta [deg], z
    Cyl,
    /// r, theta [deg] from the z axis, phi [deg] in the x-y plane from the x axis
    Sph,
}

impl SysKind {
    fn card(self) -> &'static str {
        match self {
            SysKind::Rect => "CORD2R",
            SysKind::Cyl => "CORD2C",
            SysKind::Sph => "CORD2S",
        }
    }
    /// The rectangular local coordinates of the point with coordinates `p` of this kind.
    fn rectangular(self, p: [f64; 3]) -> [f64; 3] {
        match self {
            SysKind::Rect => p,
            SysKind::Cyl => {
                let t = p[1].to_radians();
                [p[0] * t.cos(), p[0] * t.sin(), p[2]]
            }
            SysKind::Sph => {
                let (t, f) = (p[1].to_radians(), p[2].to_radians());
                [
                    p[0] * t.sin() * f.cos(),
                    p[0] * t.sin() * f.sin(),
                    p[0] * t.cos(),
                ]
            }
        }
    }
}

/// A CORD2R/C/S card as given: points A, B, C in system `rid`.
struct RawSystem {
    kind: SysKind,
    rid: i64,
    points: [[f64; 3]; 3],
    loc: Loc,
}

/// A resolved coordinate system: its origin and unit axes in the basic system.
#[derive(Clone, Copy, Debug)]
struct Frame {
    kind: SysKind,
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Frame {
    const BASIC: Frame = Frame {
        kind: SysKind::Rect,
        origin: [0.0; 3],
        axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    };

    /// The basic coordinates of the point with coordinates `p` in this system.
    fn to_basic(self, p: [f64; 3]) -> [f64; 3] {
        let l = self.kind.rectangular(p);
        let a = &self.axes;
        std::array::from_fn(|i| self.origin[i] + l[0] * a[0][i] + l[1] * a[1][i] + l[2] * a[2][i])
    }

    /// The system of `kind` through basic points A (origin), B (on the z axis), C (in the x-z
    /// plane): z along B - A, x along the part of C - A normal to z, y = z x x.
    fn through(kind: SysKind, [a, b, c]: [[f64; 3]; 3]) -> R<Frame> {
        if ![a, b, c].iter().flatten().all(|v| v.is_finite()) {
            return Err("the points A, B, C overflow in the basic system".into());
        }
        let z = sub(b, a);
        let nz = dot(z, z).sqrt();
        if !(nz > 0.0 && nz.is_finite()) {
            return Err(
                "A and B coincide: expected B on the system's z axis, away from its origin A"
                    .into(),
            );
        }
        let e3 = scale(z, 1.0 / nz);
        let ac = sub(c, a);
        let x = sub(ac, scale(e3, dot(ac, e3)));
        let nx = dot(x, x).sqrt();
        if !(nx > 1e-10 * dot(ac, ac).sqrt() && nx.is_finite()) {
            return Err("C lies on the z axis through A and B: expected C off the axis, in the system's x-z plane".into());
        }
        let e1 = scale(x, 1.0 / nx);
        Ok(Frame {
            kind,
            origin: a,
            axes: [e1, cross(e3, e1), e3],
        })
    }
}

/// What the cards define, before the coordinate systems and properties are resolved.
#[derive(Default)]
struct Model {
    /// Bytes of the deck: no THRU range of node ids can be longer.
    limit: u64,
    grids: Vec<RawGrid>,
    /// GRDSET's (CP, CD) and where.
    grdset: Option<(Option<i64>, Option<i64>, Loc)>,
    systems: BTreeMap<i64, RawSystem>,
    mat1: BTreeMap<i64, (Elastic, Loc)>,
    /// PSOLID id -> (material id, where)
    psolid: BTreeMap<i64, (i64, Loc)>,
    properties: Vec<ElementProperty>,
    sets: BTreeMap<i64, (Vec<i64>, Loc)>,
    /// Node ids in all sets so far (at most 4 per byte of the deck).
    set_ids: u64,
}

/// `file:line` of a record, for messages.
fn place(c: &Collected, loc: Loc) -> String {
    let path = c.files.get(loc.file).map(|p| p.display().to_string());
    format!("{}:{}", path.unwrap_or_default(), loc.line)
}

/// The cards read (not refused, not ignored).
const READ: &[&str] = &[
    "GRID", "GRDSET", "CTETRA", "CHEXA", "CPENTA", "CPYRA", "SET1", "MAT1", "PSOLID", "CORD2R",
    "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S", "PARAM",
];

/// The refusal of a card linercav neither reads nor ignores (None for the others).
fn refusal(name: &str) -> Option<String> {
    if READ.contains(&name) || IGNORED.iter().any(|g| g.contains(&name)) {
        return None;
    }
    Some(format!(
        "card {} is not read by linercav (it may change the model's geometry, material or connectivity): {}",
        clip(name),
        hint(name)
    ))
}

/// What to do about a refused card.
fn hint(name: &str) -> &'static str {
    let starts = |p: &[&str]| p.iter().any(|q| name.starts_with(q));
    if starts(&["CONM", "CMASS", "NSM"]) {
        "masses are not read: linercav takes the mass from the solid elements' density (MAT1 RHO)"
    } else if starts(&["RBE", "RBAR", "RROD", "RTRPLT", "RSPLINE", "RJOINT", "MPC"]) {
        "rigid elements and multi-point constraints are not read: connect the parts through shared nodes"
    } else if starts(&["MAT"]) {
        "only isotropic elastic MAT1 materials are read (thermal MAT4 and MAT5 are ignored)"
    } else if starts(&["CORD"]) {
        "coordinate systems are read from CORD2R, CORD2C and CORD2S"
    } else if starts(&[
        "PSHELL", "PCOMP", "PBAR", "PBEAM", "PROD", "PTUBE", "PBUSH", "PELAS", "PDAMP", "PMASS",
        "PGAP", "PSHEAR", "PWELD", "PFAST", "PVISC", "PLSOLID", "PSOLID",
    ]) {
        "properties other than PSOLID are not read: linercav reads solid elements only"
    } else if starts(&["C"]) {
        "linercav reads the solid elements CTETRA (4 or 10 nodes) and CHEXA (8 or 20 nodes) only: mesh the part with them or remove the card (a mesher's surface and edge elements: write the volume elements only, in Gmsh a physical volume group with Mesh.SaveAll = 0)"
    } else {
        "linercav does not know it: remove it if it does not belong to the solid model"
    }
}

/// Reads one card that [`refusal`] lets through into the model (elements straight into `c`).
fn handle(card: &Card, m: &mut Model, c: &mut Collected) -> R<()> {
    match card.name.as_str() {
        "GRID" => grid(card, m),
        "GRDSET" => grdset(card, m, c),
        "CTETRA" | "CHEXA" => element(card, m, c),
        "CPENTA" | "CPYRA" => Err(
            "pentahedra and pyramids are not supported: mesh with tetrahedra or hexahedra only"
                .into(),
        ),
        "SET1" => set1(card, m),
        "MAT1" => mat1(card, m, c),
        "PSOLID" => psolid(card, m, c),
        "CORD2R" | "CORD2C" | "CORD2S" => cord2(card, m, c),
        "CORD1R" | "CORD1C" | "CORD1S" => Err(
            "a coordinate system through grid points is not read: define the system with CORD2R/C/S"
                .into(),
        ),
        "PARAM" => param(card),
        _ => Ok(()),
    }
}

/// PARAM: WTMASS other than 1 scales the mass, which linercav does not; others are ignored.
fn param(card: &Card) -> R<()> {
    if card.text(0).eq_ignore_ascii_case("WTMASS") {
        if let Some(v) = card.opt_real(1, "WTMASS")? {
            if v != 1.0 {
                return Err(format!(
                    "WTMASS is {v}: linercav does not scale masses; expected RHO in consistent units and WTMASS 1 (or no WTMASS)"
                ).into());
            }
        }
    }
    Ok(())
}

/// A coordinate-system field of GRID or GRDSET: `min` (0 for CP, -1 for CD) or more, or blank.
fn system_field(card: &Card, k: usize, what: &str, min: i64) -> R<Option<i64>> {
    let v = card.opt_int(k, what)?;
    if let Some(v) = v.filter(|&v| v < min) {
        return Err(format!(
            "{} ({what}) is {v}, expected blank, {} or a coordinate system id",
            field_no(k),
            if min == 0 { "0" } else { "0, -1" }
        )
        .into());
    }
    Ok(v)
}

/// GRID: ID, CP, X1-X3 (blank: 0.0), CD; the position is converted once all systems are known.
fn grid(card: &Card, m: &mut Model) -> R<()> {
    let id = card.int(0, "node id")?;
    let node = |e: CardError| CardError(format!("node {id}: {e}"));
    let cp = system_field(card, 1, "CP, the system of the position", 0).map_err(node)?;
    let cd = system_field(card, 5, "CD, the displacement system", -1).map_err(node)?;
    let mut x = [0.0; 3];
    for (a, xa) in x.iter_mut().enumerate() {
        let what = format!("coordinate X{}", a + 1);
        *xa = card.opt_real(2 + a, &what).map_err(node)?.unwrap_or(0.0);
    }
    m.grids.push(RawGrid {
        id,
        cp,
        x,
        cd,
        loc: card.loc,
    });
    Ok(())
}

/// GRDSET: the default CP and CD of GRIDs (its PS and SEID are ignored, as GRID's are).
fn grdset(card: &Card, m: &mut Model, c: &Collected) -> R<()> {
    if let Some((_, _, loc)) = m.grdset {
        return Err(format!(
            "a second GRDSET (the first is at {}): expected at most one",
            place(c, loc)
        )
        .into());
    }
    let cp = system_field(card, 1, "CP", 0)?;
    let cd = system_field(card, 5, "CD", -1)?;
    m.grdset = Some((cp, cd, card.loc));
    Ok(())
}

/// CTETRA (4 or 10 nodes) and CHEXA (8 or 20 nodes): EID, PID, node ids.
fn element(card: &Card, m: &mut Model, c: &mut Collected) -> R<()> {
    let eid = card.int(0, "element id")?;
    let pid = card
        .opt_int(1, "property id")
        .map_err(|e| format!("element {eid}: {e}"))?;
    if let Some(p) = pid.filter(|&p| p <= 0) {
        return Err(format!(
            "element {eid}: field 3 (property id) is {p}, expected a positive integer or blank"
        )
        .into());
    }
    let ids: Vec<i64> = card
        .fields
        .get(2..)
        .unwrap_or_default()
        .iter()
        .map(|f| f.trim())
        .filter(|f| !f.is_empty())
        .map(|f| f.parse::<i64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("element {eid}: a node id is not an integer"))?;
    let (kind, name) = match (card.name.as_str(), ids.len()) {
        ("CTETRA", 4) => (ElementKind::Tet4, "CTETRA"),
        ("CTETRA", 10) => (ElementKind::Tet10, "CTETRA"),
        ("CHEXA", 8) => (ElementKind::Hex8, "CHEXA"),
        ("CHEXA", 20) => (ElementKind::Hex20, "CHEXA"),
        (n, k) => {
            let most = if n == "CTETRA" { 10 } else { 20 };
            // a card cut short lost its continuation lines
            let cut = if k < most {
                " (a continuation line missing, or the file cut short?)"
            } else {
                ""
            };
            return Err(format!(
                "element {eid} has {k} nodes; {n} is read with {}{cut}",
                if n == "CTETRA" { "4 or 10" } else { "8 or 20" }
            )
            .into());
        }
    };
    let ids = match kind {
        ElementKind::Tet10 => reorder(kind, &TET10_DECK, &ids),
        ElementKind::Hex20 => reorder(kind, &HEX20_NASTRAN, &ids),
        _ => ids,
    };
    c.elements.push((eid, kind, ids, card.loc));
    m.properties.push(ElementProperty {
        eid,
        pid,
        loc: card.loc,
        card: name,
    });
    Ok(())
}

/// SET1: SID, then node ids and `a THRU b` ranges (no longer than the deck has bytes).
fn set1(card: &Card, m: &mut Model) -> R<()> {
    let sid = card.id(0, "set id")?;
    let f: Vec<&str> = card
        .fields
        .get(1..)
        .unwrap_or_default()
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .collect();
    let entry = m.sets.entry(sid).or_insert((Vec::new(), card.loc));
    let mut k = 0;
    while let Some(w) = f.get(k) {
        let a: i64 = w
            .parse()
            .map_err(|_| format!("set {sid}: '{w}' is not a node id"))?;
        if f.get(k + 1).is_some_and(|w| w.eq_ignore_ascii_case("THRU")) {
            let b: i64 = f
                .get(k + 2)
                .and_then(|w| w.parse().ok())
                .ok_or_else(|| format!("set {sid}: THRU after {a} needs an end id"))?;
            // a deck defines fewer nodes than it has bytes: a longer range is hostile
            let n = match b.checked_sub(a) {
                Some(d) if d >= 0 => (d as u64).saturating_add(1),
                _ => u64::MAX,
            };
            if b < a || n > m.limit || m.set_ids.saturating_add(n) > 4 * m.limit {
                return Err(format!(
                    "set {sid}: {a} THRU {b} is not a range of this deck's node ids (or the sets hold more than 4 ids per byte of the deck)"
                ).into());
            }
            m.set_ids += n;
            entry.0.extend(a..=b);
            k += 3;
        } else {
            m.set_ids += 1;
            entry.0.push(a);
            k += 1;
        }
    }
    Ok(())
}

/// MAT1's E and NU: as given, or E = 2 (1 + NU) G, or NU = E / (2 G) - 1; and G when it is
/// given beside both (not used; [`given_shear_modulus`] checks it).
fn mat1_constants(card: &Card) -> R<(f64, f64, Option<f64>)> {
    let e = card.opt_real(1, "E")?;
    let g = card.opt_real(2, "G")?;
    let nu = card.opt_real(3, "NU")?;
    let (young, poisson, how) = match (e, g, nu) {
        (Some(e), _, Some(nu)) => (e, nu, ""),
        (None, Some(g), Some(nu)) => (2.0 * (1.0 + nu) * g, nu, " (2 (1 + NU) G)"),
        (Some(e), Some(g), None) => (e, e / (2.0 * g) - 1.0, " (E / (2 G) - 1)"),
        _ => {
            return Err(
                "E (field 3) and NU (field 5) are needed, or one of them with G (field 4)".into(),
            )
        }
    };
    if !(young.is_finite() && young > 0.0) {
        return Err(format!("Young's modulus is {young}{how}, expected a positive number").into());
    }
    if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
        return Err(
            format!("Poisson's ratio is {poisson}{how}, expected a number in (-1, 0.5)").into(),
        );
    }
    // G beside E and NU: not used, checked by `given_shear_modulus`
    let extra = g.filter(|_| e.is_some() && nu.is_some());
    Ok((young, poisson, extra))
}

/// A MAT1's G (field 4) given beside E and NU, which set the material (`young`, `poisson`):
/// refused when not positive, warned of (naming the line) when more than 1 % from
/// E / (2 (1 + NU)) (a database's rounding stays within that): the solid is isotropic and G
/// is not used, so a G that says otherwise is a material the deck does not get.
fn given_shear_modulus(
    card: &Card,
    (young, poisson, g): (f64, f64, Option<f64>),
    c: &Collected,
) -> R<()> {
    let Some(g) = g else {
        return Ok(());
    };
    if !(g.is_finite() && g > 0.0) {
        return Err(
            format!("G (field 4) is {g}, expected a positive shear modulus or a blank").into(),
        );
    }
    let isotropic = young / (2.0 * (1.0 + poisson));
    if (g - isotropic).abs() > 0.01 * isotropic {
        crate::text::warn(format!(
            "{}",
            c.err_at(
                card.loc,
                format!(
                    "MAT1: G = {} differs from E / (2 (1 + NU)) = {} by more than 1 %: the solid is isotropic, E and NU are used, G is not",
                    crate::text::num(g),
                    crate::text::num(isotropic)
                )
            )
        ));
    }
    Ok(())
}

/// MAT1: MID, E, G, NU, RHO (other fields ignored); RHO must be positive.
fn mat1(card: &Card, m: &mut Model, c: &Collected) -> R<()> {
    let mid = card.id(0, "material id")?;
    if let Some((_, loc)) = m.mat1.get(&mid) {
        return Err(format!(
            "material {mid} is defined twice (first at {})",
            place(c, *loc)
        )
        .into());
    }
    let mat = |e: CardError| CardError(format!("material {mid}: {e}"));
    let (young, poisson, g) = mat1_constants(card).map_err(mat)?;
    given_shear_modulus(card, (young, poisson, g), c).map_err(mat)?;
    let density = match card.opt_real(4, "RHO").map_err(mat)? {
        Some(r) if r > 0.0 => r,
        Some(r) => {
            return Err(mat(format!(
                "RHO (field 6) is {r}, expected a positive density"
            )
            .into()))
        }
        None => {
            return Err(mat(
                "RHO (field 6) is blank: expected the density (the modes need the mass)".into(),
            ))
        }
    };
    let elastic = Elastic {
        young,
        poisson,
        density,
    };
    m.mat1.insert(mid, (elastic, card.loc));
    Ok(())
}

/// PSOLID: PID, MID, ..., FCTN (blank or SMECH: a structural solid).
fn psolid(card: &Card, m: &mut Model, c: &Collected) -> R<()> {
    let pid = card.id(0, "property id")?;
    if let Some((_, loc)) = m.psolid.get(&pid) {
        return Err(format!(
            "property {pid} is defined twice (first at {})",
            place(c, *loc)
        )
        .into());
    }
    let mid = card
        .id(1, "material id")
        .map_err(|e| format!("property {pid}: {e}"))?;
    let fctn = card.text(6).to_ascii_uppercase();
    if !(fctn.is_empty() || fctn == "SMECH" || fctn == "SMEC") {
        return Err(format!(
            "property {pid}: field 8 (FCTN) is '{}': expected blank or SMECH (structural solids; fluid elements are not read)",
            clip(&fctn)
        ).into());
    }
    m.psolid.insert(pid, (mid, card.loc));
    Ok(())
}

/// CORD2R/C/S: CID, RID, A1-A3, B1-B3, C1-C3 (blank: 0.0; the continuation with C is needed).
fn cord2(card: &Card, m: &mut Model, c: &Collected) -> R<()> {
    let kind = match card.name.as_str() {
        "CORD2C" => SysKind::Cyl,
        "CORD2S" => SysKind::Sph,
        _ => SysKind::Rect,
    };
    let cid = card.id(0, "CID, the system's id")?;
    if let Some(s) = m.systems.get(&cid) {
        return Err(format!(
            "coordinate system {cid} is defined twice (first at {})",
            place(c, s.loc)
        )
        .into());
    }
    let sys = |e: CardError| CardError(format!("system {cid}: {e}"));
    let rid = card.opt_int(1, "RID, the reference system").map_err(sys)?;
    if let Some(r) = rid.filter(|&r| r < 0) {
        return Err(sys(format!(
            "field 3 (RID) is {r}, expected blank, 0 or a coordinate system id"
        )
        .into()));
    }
    if card.fields.iter().skip(8).all(|f| f.trim().is_empty()) {
        return Err(sys(
            "C1-C3 (the continuation) are missing: expected points A, B and C".into(),
        ));
    }
    let names = ["A1", "A2", "A3", "B1", "B2", "B3", "C1", "C2", "C3"];
    let mut points = [[0.0; 3]; 3];
    for (k, n) in names.iter().enumerate() {
        points[k / 3][k % 3] = card.opt_real(2 + k, n).map_err(sys)?.unwrap_or(0.0);
    }
    let raw = RawSystem {
        kind,
        rid: rid.unwrap_or(0),
        points,
        loc: card.loc,
    };
    m.systems.insert(cid, raw);
    Ok(())
}

/// Resolves every coordinate system to the basic one, following RID chains (without
/// recursion); undefined references, cycles and degenerate points are refused at the card.
fn resolve_systems(
    systems: &BTreeMap<i64, RawSystem>,
    c: &Collected,
) -> Result<BTreeMap<i64, Frame>, DeckError> {
    let at = |id: i64, s: &RawSystem, msg: String| {
        c.err_at(s.loc, format!("{}: system {id}: {msg}", s.kind.card()))
    };
    let mut done: BTreeMap<i64, Frame> = BTreeMap::new();
    for (&cid, first) in systems {
        // the chain of references up to the basic system or a resolved one
        let mut chain: Vec<(i64, &RawSystem)> = Vec::new();
        let mut seen = HashSet::new();
        let (mut cur, mut s) = (cid, first);
        while cur != 0 && !done.contains_key(&cur) {
            if !seen.insert(cur) {
                let (id, last) = chain.last().copied().unwrap_or((cid, first));
                return Err(at(id, last, format!(
                    "the reference systems (RID, field 3) form a cycle through system {cur}: expected a chain ending at the basic system"
                )));
            }
            chain.push((cur, s));
            let next = s.rid;
            match systems.get(&next) {
                Some(n) => (cur, s) = (next, n),
                None if next == 0 || done.contains_key(&next) => cur = next,
                None => return Err(at(cur, s, format!(
                    "reference system {next} (RID, field 3) is not defined: expected blank, 0 or the id of a CORD2R, CORD2C or CORD2S card"
                ))),
            }
        }
        for &(id, s) in chain.iter().rev() {
            let parent = match s.rid {
                0 => Frame::BASIC,
                r => match done.get(&r) {
                    Some(f) => *f,
                    None => return Err(at(id, s, format!("reference system {r} is not resolved"))),
                },
            };
            let pts = s.points.map(|p| parent.to_basic(p));
            let f = Frame::through(s.kind, pts).map_err(|e| at(id, s, e.0))?;
            done.insert(id, f);
        }
    }
    Ok(done)
}

/// The nodes of the GRIDs, converted from their systems (CP, else GRDSET's) to the basic one;
/// an undefined CP or CD is refused at the GRID.
fn place_grids(
    m: &Model,
    frames: &BTreeMap<i64, Frame>,
    c: &Collected,
) -> Result<Vec<(i64, [f64; 3], Loc)>, DeckError> {
    let (dcp, dcd) = m.grdset.map_or((None, None), |(p, d, _)| (p, d));
    let mut nodes = Vec::with_capacity(m.grids.len());
    for g in &m.grids {
        let at = |msg: String| c.err_at(g.loc, format!("GRID: node {}: {msg}", g.id));
        let (cp, cd) = (g.cp.or(dcp).unwrap_or(0), g.cd.or(dcd).unwrap_or(0));
        let dflt = |f: Option<i64>| if f.is_none() { ", blank: GRDSET's" } else { "" };
        let x = if cp == 0 {
            g.x
        } else {
            let frame = frames.get(&cp).ok_or_else(|| at(format!(
                "its position is given in coordinate system {cp} (CP, field 3{}), which the deck does not define: expected blank, 0 or the id of a CORD2R, CORD2C or CORD2S card",
                dflt(g.cp)
            )))?;
            frame.to_basic(g.x)
        };
        if cd > 0 && !frames.contains_key(&cd) {
            return Err(at(format!(
                "its displacement system is coordinate system {cd} (CD, field 7{}), which the deck does not define: expected blank, 0, -1 or the id of a CORD2R, CORD2C or CORD2S card",
                dflt(g.cd)
            )));
        }
        if !x.iter().all(|v| v.is_finite()) {
            return Err(at("its coordinates overflow in the basic system".into()));
        }
        nodes.push((g.id, x, g.loc));
    }
    Ok(nodes)
}

/// The MAT1 materials by name (`$HMNAME MAT` or `MAT1 <mid>`, distinct) into `c`; MID ->
/// name.
fn materials(
    m: &Model,
    hm: &BTreeMap<i64, String>,
    c: &mut Collected,
) -> Result<BTreeMap<i64, String>, DeckError> {
    let mut names: BTreeMap<i64, String> = BTreeMap::new();
    let mut taken: BTreeMap<String, i64> = BTreeMap::new();
    for (&mid, &(elastic, loc)) in &m.mat1 {
        let name = hm
            .get(&mid)
            .cloned()
            .unwrap_or_else(|| format!("MAT1 {mid}"));
        if let Some(other) = taken.insert(name.clone(), mid) {
            return Err(c.err_at(loc, format!(
                "MAT1: material {mid} is named '{name}', as material {other} is: expected distinct names ($HMNAME MAT comments)"
            )));
        }
        c.materials.insert(name.clone(), (elastic, loc));
        names.insert(mid, name);
    }
    Ok(names)
}

/// Each solid element's material through its PSOLID (when the deck has PSOLIDs: a blank PID
/// is the element id) and its element set `PID<n>`.
fn properties(m: &Model, hm: &BTreeMap<i64, String>, c: &mut Collected) -> Result<(), DeckError> {
    let add_set = |c: &mut Collected, pid: i64, p: &ElementProperty| {
        let set = c.element_sets.entry(format!("PID{pid}"));
        set.or_insert((Vec::new(), p.loc)).0.push(p.eid);
    };
    if m.psolid.is_empty() {
        for p in &m.properties {
            if let Some(pid) = p.pid {
                add_set(c, pid, p);
            }
        }
        return Ok(());
    }
    let names = materials(m, hm, c)?;
    for (&pid, &(mid, loc)) in &m.psolid {
        if !names.contains_key(&mid) {
            return Err(c.err_at(loc, format!(
                "PSOLID: property {pid}: material {mid} (MID, field 3) is not a MAT1 of the deck: expected the id of a MAT1 card"
            )));
        }
    }
    for p in &m.properties {
        let pid = p.pid.unwrap_or(p.eid);
        let found = m
            .psolid
            .get(&pid)
            .and_then(|(mid, l)| Some((names.get(mid)?, l)));
        let Some((name, &ploc)) = found else {
            return Err(c.err_at(p.loc, format!(
                "{}: element {}: property {pid}{} is not a PSOLID of the deck: expected the id of a PSOLID card (the deck defines PSOLIDs, so every solid element needs one)",
                p.card,
                p.eid,
                if p.pid.is_none() { " (PID blank: the element id)" } else { "" }
            )));
        };
        c.element_material.insert(p.eid, (name.clone(), ploc));
        add_set(c, pid, p);
    }
    Ok(())
}

/// Resolves what the cards define into `c`: coordinate systems, nodes, materials and
/// properties, node sets (named by `$HMSET`, else by id; names must be distinct).
fn finish(m: Model, r: &Reader, c: &mut Collected) -> Result<(), DeckError> {
    let frames = resolve_systems(&m.systems, c)?;
    let nodes = place_grids(&m, &frames, c)?;
    c.nodes = nodes;
    properties(&m, &r.mat_names, c)?;
    for (sid, (ids, loc)) in m.sets {
        let name = r
            .set_names
            .get(&sid)
            .cloned()
            .unwrap_or_else(|| sid.to_string());
        if c.node_sets.contains_key(&name) {
            return Err(c.err_at(loc, format!(
                "SET1: set {sid} is named '{name}', as another set is: expected distinct names ($HMSET comments)"
            )));
        }
        c.node_sets.insert(name, (ids, loc));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nastran_reals_in_every_form() {
        for (s, v) in [
            ("1.5E-3", 1.5e-3),
            ("1.5D-3", 1.5e-3),
            ("1.5-3", 1.5e-3),
            ("-.5+2", -50.0),
            ("7.", 7.0),
            (".7E1", 7.0),
            ("70.-1", 7.0),
            ("1.23456789012E+0", 1.23456789012),
        ] {
            assert!((real(s).unwrap() - v).abs() < 1e-12 * v.abs(), "{s}");
        }
        assert_eq!(real("abc"), None);
        assert_eq!(real(""), None);
    }

    /// Regression (session 70's hostile sweep): in `CHEXA,1,1,1,2,3,4,5,,6`, the 10th field
    /// (the continuation marker `6`) was read as a node and the blank G6 squeezed out.
    #[test]
    fn regression_a_free_field_continuation_marker_is_no_node() {
        let grids: String = (1..=8)
            .map(|k| format!("GRID,{k},,{}.,{}.,{}.\n", k % 2, k / 2 % 2, k / 4))
            .collect();
        let p = Path::new("t.bdf");
        let e = parse(p, &format!("{grids}CHEXA,1,1,1,2,3,4,5,,6\n+,7,8\n")).unwrap_err();
        assert!(e.msg.contains("element 1 has 7 nodes"), "{e}");
        // the same marker after six nodes continues the card
        let c = parse(p, &format!("{grids}CHEXA,1,1,1,2,3,4,5,6,A1\n+A1,7,8\n")).unwrap();
        assert_eq!(c.num_elements(), 1);
    }

    #[test]
    fn small_large_and_free_fields_with_continuations_read_alike() {
        // one unit tetrahedron, written three ways, with a named set
        let small = "BEGIN BULK\n$HMSET        7       1 \"tip\"\nGRID    1               0.      0.      0.\nGRID    2               1.      0.      0.\nGRID    3               0.      1.0     0.\nGRID    4               0.      0.      1.-0\nCTETRA  1       1       1       2       3       4\nSET1    7       4\nENDDATA\n";
        // the small-field element's fourth node on a continuation (marker in columns 73-80)
        let large = format!(
            "GRID*   1                               0.0             0.0\n*       0.0\nGRID*   2                               1.0D+0          0.0\n*       0.0\nGRID*   3                               0.0             1.0\n*       0.0\nGRID*   4                               0.0             0.0\n*       1.0\n{:<72}+C1\n+C1     4\nSET1    7       4\n$HMSET 7 1 \"tip\"\n",
            "CTETRA  1       1       1       2       3"
        );
        let free = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nCTETRA,1,1,1,2,3,\n+,4\nSET1,7,1,THRU,4\n$HMSET 7 1 \"tip\"\n";
        let p = Path::new("t.bdf");
        let a = parse(p, small).unwrap();
        let b = parse(p, &large).unwrap();
        let c = parse(p, free).unwrap();
        for m in [&a, &b, &c] {
            assert_eq!(m.nodes.len(), 4);
            assert_eq!(m.nodes[3], [0.0, 0.0, 1.0]);
            assert_eq!(m.nodes[1], [1.0, 0.0, 0.0]);
            assert_eq!(m.blocks[0].conn, vec![0, 1, 2, 3]);
            assert_eq!(m.element_sets["PID1"], vec![0]);
        }
        assert_eq!(a.node_sets["tip"], vec![3]);
        assert_eq!(b.node_sets["tip"], vec![3]);
        assert_eq!(c.node_sets["tip"], vec![0, 1, 2, 3]);
    }

    #[test]
    fn bad_cards_name_the_line_and_field() {
        let p = Path::new("t.bdf");
        let e = parse(p, "GRID,1,,0.,x,0.\n").unwrap_err();
        assert!(
            e.line == 1 && e.msg.contains("X2") && e.msg.contains("'x'"),
            "{e}"
        );
        let e = parse(p, "GRID,1,5,0.,0.,0.\n").unwrap_err();
        assert!(e.msg.contains("coordinate system 5"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCTETRA,1,1,1,2,3\n").unwrap_err();
        assert!(e.line == 2 && e.msg.contains("3 nodes"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCTETRA,1,1,1,2,3,9\n").unwrap_err();
        assert!(e.line == 2 && e.msg.contains("node 2"), "{e}");
        let e = parse(p, "GRID,1,,0.,0.,0.\nCPENTA,1,1,1,2,3,4,5,6\n").unwrap_err();
        assert!(e.msg.contains("pentahedra"), "{e}");
    }

    /// Four nodes of a unit tetrahedron (free field) and `rest`.
    fn tet(rest: &str) -> String {
        format!("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n{rest}")
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn nested_includes_with_a_split_name_read_as_the_flat_deck() {
        let dir = tempfile::tempdir().unwrap();
        let grids = "GRID    1               0.      0.      0.\nGRID    2               1.      0.      0.\n";
        let more = "GRID    3               0.      1.      0.\nGRID,4,,0.,0.,1.\n$HMSET 7 1 \"tip\"\nSET1,7,4\n";
        let tail = "CTETRA  1       1       1       2       3       4\n";
        // an include before BEGIN BULK belongs to the case control: skipped
        let main = format!(
            "SOL 103\nINCLUDE 'case_control_only.dat'\nCEND\nBEGIN BULK\nINCLUDE 'sub/no\n    des.bdf'\n{tail}ENDDATA\nGRID,9,,0.,0.,0.\n"
        );
        write(
            dir.path(),
            "sub/nodes.bdf",
            &format!("{grids}include more.bdf\n"),
        );
        write(dir.path(), "sub/more.bdf", more);
        let path = write(dir.path(), "main.bdf", &main);
        let mut m = read(&path).unwrap();
        let mut flat = parse(Path::new("flat.bdf"), &format!("{grids}{more}{tail}")).unwrap();
        // the same mesh; only where its elements were defined differs
        m.element_lines = None;
        flat.element_lines = None;
        assert_eq!(m, flat);
        assert_eq!(m.nodes.len(), 4);
        assert_eq!(m.node_sets["tip"], vec![3]);
    }

    #[test]
    fn include_cycles_depth_and_missing_files_are_refused_at_the_include() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = write(d, "a.bdf", &tet("INCLUDE 'b.bdf'\n"));
        let b = write(d, "b.bdf", "$ b\nINCLUDE 'a.bdf'\n");
        let e = read(&a).unwrap_err();
        assert!(e.path == b && e.line == 2 && e.msg.contains("cycle"), "{e}");
        assert!(e.msg.contains("a.bdf"), "{e}");
        let m = write(d, "m.bdf", &tet("\n  INCLUDE nope.bdf\n"));
        let e = read(&m).unwrap_err();
        assert!(
            e.path == m && e.line == 6 && e.msg.contains("nope.bdf"),
            "{e}"
        );
        // 40 files deep
        for k in 0..40 {
            write(
                d,
                &format!("n{k}.bdf"),
                &format!("INCLUDE 'n{}.bdf'\n", k + 1),
            );
        }
        write(d, "n40.bdf", "");
        let e = read(&write(d, "deep.bdf", &tet("INCLUDE 'n0.bdf'\n"))).unwrap_err();
        assert!(e.msg.contains("deeper than 32") && e.line == 1, "{e}");
        let e = parse(&d.join("q.bdf"), "INCLUDE 'open\nGRID,1\n").unwrap_err();
        assert!(e.line == 1 && e.msg.contains("not closed"), "{e}");
    }

    #[test]
    fn a_card_of_an_included_file_is_refused_with_that_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let sub = write(
            dir.path(),
            "parts/shell.bdf",
            "$ shells\nGRID,5,,0.,0.,2.\nCQUAD4,9,1,1,2,3,5\n",
        );
        let main = write(
            dir.path(),
            "main.bdf",
            &tet("CTETRA,1,1,1,2,3,4\nINCLUDE 'parts/shell.bdf'\n"),
        );
        let e = read(&main).unwrap_err();
        assert!(e.path == sub && e.line == 3, "{e}");
        assert!(e.msg.contains("card CQUAD4 is not read by linercav"), "{e}");
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-12 * b[i].abs().max(1.0))
    }

    #[test]
    fn grids_in_cord2c_cord2s_and_chained_cord2r_systems_are_converted_to_basic() {
        // GRIDs before the systems they use (order does not matter)
        let deck = "\
GRID,1,1,2.,90.,5.
GRID,2,3,1.,2.,3.
GRID,3,4,2.,90.,90.
GRID,4,,0.,0.,0.,7
CORD2C,1,,1.,2.,3.,1.,2.,4.,+
+,1.,3.,3.
CORD2R,3,2,0.,0.,5.,1.,0.,5.
,0.,1.,5.
CORD2R,2,0,10.,0.,0.,10.,0.,1.
,10.,1.,0.
CORD2S,4,,0.,0.,0.,0.,0.,1.
,1.,0.,0.
CORD2R,7,3,0.,0.,0.,0.,0.,1.
,1.,0.,0.
CTETRA,1,,1,2,3,4
";
        let m = parse(Path::new("c.bdf"), deck).unwrap();
        // system 1: origin (1,2,3), z = +z, x = +y, y = z x x = -x: (r, theta, z) = (2, 90, 5)
        // is local (0, 2, 5), basic (1,2,3) + 2 (-1,0,0) + 5 (0,0,1)
        assert!(close(m.nodes[0], [-1.0, 2.0, 8.0]), "{:?}", m.nodes[0]);
        // system 2: origin (10,0,0), z = +z, x = +y, y = -x: (x,y,z) -> (10 - y, x, z);
        // system 3 in 2: A (10,0,5), B (10,1,5), C (9,0,5): z = +y, x = -x, y = +z
        assert!(close(m.nodes[1], [9.0, 3.0, 7.0]), "{:?}", m.nodes[1]);
        // spherical (r, theta, phi) = (2, 90, 90): (0, 2, 0)
        assert!(close(m.nodes[2], [0.0, 2.0, 0.0]), "{:?}", m.nodes[2]);
        assert_eq!(m.nodes[3], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn undefined_systems_ids_and_cord1_are_refused_at_their_card() {
        let p = Path::new("t.bdf");
        let e = parse(p, &tet("GRID,5,,0.,0.,0.,7\nCTETRA,1,1,1,2,3,4\n")).unwrap_err();
        assert!(
            e.line == 5 && e.msg.contains("node 5") && e.msg.contains("system 7"),
            "{e}"
        );
        let e = parse(p, &tet("GRID,-1,,0.,0.,0.\nCTETRA,1,1,1,2,3,4\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("-1"), "{e}");
        let e = parse(p, &tet("GRID,5,2,0.,0.,0.\nCTETRA,1,1,1,2,3,4\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("coordinate system 2"), "{e}");
        let cyc = "CORD2R,1,2,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nCORD2R,2,1,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nCTETRA,1,1,1,2,3,4\n";
        let e = parse(p, &tet(cyc)).unwrap_err();
        assert!(
            e.msg.contains("cycle") && (e.line == 5 || e.line == 7),
            "{e}"
        );
        let e = parse(p, &tet("CORD2R,1,9,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("reference system 9"), "{e}");
        let e = parse(p, &tet("CORD2R,1,0,0.,0.,0.,0.,0.,1.\n,0.,0.,2.\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("z axis"), "{e}");
        let e = parse(p, &tet("CORD2C,0,0,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("positive"), "{e}");
        let e = parse(p, &tet("CORD1R,3,1,2,3\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("CORD2R/C/S"), "{e}");
        let e = parse(p, &tet("SET1,0,1\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("set id"), "{e}");
        let e = parse(p, &tet("CTETRA,1,-2,1,2,3,4\n")).unwrap_err();
        assert!(e.line == 5 && e.msg.contains("property id"), "{e}");
    }

    #[test]
    fn two_mat1_psolid_pairs_give_each_element_its_material() {
        let deck = "\
GRID,5,,0.,0.,-1.
$HMNAME MAT                    2\"cast iron\"
MAT1,1,210000.,,0.3,7.85-9
MAT1,2,,40000.,0.25,7.2-9
PSOLID,10,1
PSOLID,3,2
CTETRA,1,10,1,2,3,4
CTETRA,3,,1,3,2,5
";
        let m = parse(Path::new("m.bdf"), &tet(deck)).unwrap();
        let names: Vec<&str> = m.materials.iter().map(|d| d.name.as_str()).collect();
        assert_eq!(names, ["MAT1 1", "cast iron"]);
        let steel = &m.materials[0].elastic;
        assert_eq!(
            (steel.young, steel.poisson, steel.density),
            (210000.0, 0.3, 7.85e-9)
        );
        let iron = &m.materials[1].elastic;
        // E = 2 (1 + NU) G
        assert!((iron.young - 100000.0).abs() < 1e-9 && iron.density == 7.2e-9);
        // element 3 has a blank PID: property 3
        assert_eq!(m.element_material, vec![0, 1]);
        assert_eq!(m.element_sets["PID10"], vec![0]);
        assert_eq!(m.element_sets["PID3"], vec![1]);
        // NU from E and G
        let m = parse(
            Path::new("m.bdf"),
            &tet("MAT1,1,100.,40.,,1.\nPSOLID,1,1\nCTETRA,1,1,1,2,3,4\n"),
        )
        .unwrap();
        assert!((m.materials[0].elastic.poisson - 0.25).abs() < 1e-15);
        // no PSOLID: no materials
        let m = parse(
            Path::new("m.bdf"),
            &tet("MAT1,1,1.,,.3,1.\nCTETRA,1,1,1,2,3,4\n"),
        )
        .unwrap();
        assert!(m.materials.is_empty() && m.element_material.is_empty());
    }

    #[test]
    fn bad_materials_and_properties_are_refused_at_their_card() {
        let p = Path::new("t.bdf");
        let ok = "PSOLID,1,1\nCTETRA,1,1,1,2,3,4\n";
        for (deck, line, what) in [
            (format!("MAT1,1,2.1+5,,0.3\n{ok}"), 5, "RHO"),
            (format!("MAT1,1,2.1+5,,0.3,0.\n{ok}"), 5, "RHO"),
            (format!("MAT1,1,2.1+5,,,7.8-9\n{ok}"), 5, "NU"),
            (format!("MAT1,1,,,0.3,7.8-9\n{ok}"), 5, "E (field 3)"),
            (format!("MAT1,1,2.1+5,,0.5,7.8-9\n{ok}"), 5, "Poisson"),
            (format!("MAT1,-1,2.1+5,,0.3,7.8-9\n{ok}"), 5, "material id"),
            (
                "MAT1,1,1.,,.3,1.\nPSOLID,1,2\nCTETRA,1,1,1,2,3,4\n".into(),
                6,
                "not a MAT1",
            ),
            (
                "MAT1,1,1.,,.3,1.\nPSOLID,1,1\nCTETRA,1,2,1,2,3,4\n".into(),
                7,
                "property 2 is not a PSOLID",
            ),
            (
                "MAT1,1,1.,,.3,1.\nPSOLID,1,1\nCTETRA,2,,1,2,3,4\n".into(),
                7,
                "PID blank",
            ),
            ("MAT1,1,1.,,.3,1.\nPSOLID,0,1\n".into(), 6, "property id"),
            (
                "MAT1,1,1.,,.3,1.\nPSOLID,1,1,,,,,PFLUID\n".into(),
                6,
                "FCTN",
            ),
            ("MAT8,1,1.,1.,.3\n".into(), 5, "card MAT8 is not read"),
            ("PARAM,WTMASS,0.00259\n".into(), 5, "WTMASS"),
        ] {
            let e = parse(p, &tet(&deck)).unwrap_err();
            assert!(e.line == line && e.msg.contains(what), "{deck}: {e}");
        }
    }

    #[test]
    fn cards_that_may_change_the_model_are_refused_and_others_ignored() {
        let p = Path::new("t.bdf");
        for (card, what) in [
            (
                "CQUAD4,2,1,1,2,3,4",
                "card CQUAD4 is not read by linercav (it may change",
            ),
            ("CONM2,2,1,,1.", "card CONM2 is not read"),
            ("RBE2,2,1,123456,2", "card RBE2 is not read"),
            ("FOOBAR,1", "card FOOBAR is not read"),
            ("BEGIN SUPER=1", "superelements"),
        ] {
            let deck = format!("$ c\n{card}\nCTETRA,1,1,1,2,3,4\n");
            let e = parse(p, &tet(&deck)).unwrap_err();
            assert!(e.line == 6 && e.msg.contains(what), "{card}: {e}");
        }
        let e = parse(p, &format!("BEGIN BULK\n+C1,5\n{}", tet(""))).unwrap_err();
        assert!(e.line == 2 && e.msg.contains("no card before it"), "{e}");
        // GRDSET's CP is the default of the GRIDs with a blank CP
        let e = parse(p, &tet("GRDSET,,3\nCTETRA,1,1,1,2,3,4\n")).unwrap_err();
        assert!(
            e.line == 1 && e.msg.contains("system 3") && e.msg.contains("GRDSET"),
            "{e}"
        );
        let sys = "GRDSET,,3\nCORD2R,3,,1.,0.,0.,1.,0.,1.\n,2.,0.,0.\nGRID,5,0,0.,0.,-1.\n";
        let m = parse(p, &tet(&format!("{sys}CTETRA,1,1,1,2,3,5\n"))).unwrap();
        assert_eq!(
            (m.nodes[1], m.nodes[4]),
            ([2.0, 0.0, 0.0], [0.0, 0.0, -1.0])
        );
        let ignored = "SPC1,1,123,1\nFORCE,2,4,,1.,0.,0.,1.\nEIGRL,1,,,10\nPARAM,POST,-1\nPARAM,WTMASS,1.\nMAT4,1,40.\nTEMPD,1,20.\n";
        let m = parse(p, &tet(&format!("{ignored}CTETRA,1,1,1,2,3,4\n"))).unwrap();
        assert_eq!(m.num_elements(), 1);
    }

    #[test]
    fn a_tab_separated_small_field_deck_reads() {
        let deck = "BEGIN BULK\nGRID\t1\t\t0.\t0.\t0.\nGRID\t2\t\t1.\t0.\t0.\nGRID\t3\t\t0.\t1.\t0.\nGRID\t4\t\t0.\t0.\t1.\nCTETRA\t1\t1\t1\t2\t3\t4\nSET1\t7\t1\tTHRU\t4\nENDDATA\n";
        let m = parse(Path::new("tab.bdf"), deck).unwrap();
        assert_eq!(m.nodes[1], [1.0, 0.0, 0.0]);
        assert_eq!(m.nodes[3], [0.0, 0.0, 1.0]);
        assert_eq!(m.node_sets["7"], vec![0, 1, 2, 3]);
        assert_eq!(expand_tabs("ab\tc"), "ab      c");
    }

    #[test]
    fn the_meshio_fixtures_read() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        for f in [
            "block_hex20.bdf",
            "block_tet10.bdf",
            "liner_hex20.bdf",
            "block_hex20_free.nas",
            "block_tet10_free.nas",
            "liner_hex20_free.nas",
        ] {
            let m = read(&dir.join(f)).unwrap();
            assert!(m.num_elements() > 0 && m.materials.is_empty(), "{f}");
        }
    }
}
