//! Loading a scene: the TOML file, its `--set` overrides, the raw structs, validation and the
//! sanity review; the checker that names a key in every refusal.

#[allow(unused_imports)]
use super::*;

pub(super) fn check_guard_modes(c: &Checker<'_>, g: usize) -> Result<usize, SceneError> {
    if g > MAX_GUARD_MODES {
        return Err(c.err(
            "solver.guard_modes",
            format!("must be at most {MAX_GUARD_MODES} (a few find the spectral gap), got {g}"),
        ));
    }
    Ok(g)
}

impl Scene {
    /// Reads, overrides and validates a scene file.
    pub fn load(path: &Path, sets: &[String]) -> Result<Self, SceneError> {
        let text = crate::files::read_text(path, crate::files::LIMIT_TEXT).map_err(|source| {
            SceneError::Io {
                path: path.to_path_buf(),
                source,
            }
        })?;
        Self::from_str_with(path, &text, sets)
    }

    /// Parses scene text; `path` locates relative mesh files and names the file in errors.
    pub fn from_str_with(path: &Path, text: &str, sets: &[String]) -> Result<Self, SceneError> {
        let mut table: toml::Table =
            text.parse()
                .map_err(|e: toml::de::Error| SceneError::Syntax {
                    path: path.to_path_buf(),
                    msg: clipped(&e.to_string()),
                })?;
        for s in sets {
            overrides::apply(&mut table, s)?;
        }
        // tables read strictly: a struct takes a table only (`super::strict`)
        let de = super::strict::Strict(toml::Value::Table(table));
        let raw: RawScene =
            serde_path_to_error::deserialize(de).map_err(|e| SceneError::Field {
                path: path.to_path_buf(),
                // a field missing at the top level has the path "."
                key: match e.path().to_string().as_str() {
                    "." => "(the scene's top level)".to_string(),
                    p => p.to_string(),
                },
                msg: plain_message(&e.inner().to_string()),
            })?;
        let mut scene = validate(path, raw)?;
        scene.warnings = sanity::review(&scene)?;
        for w in &scene.warnings {
            log::warn!("{}: {w}", path.display());
        }
        Ok(scene)
    }

    /// The part called `name`.
    pub fn part(&self, name: &str) -> Option<&Part> {
        match name {
            "liner" => Some(&self.liner),
            _ => None,
        }
    }
}

/// Characters of a parser's message line that are kept ([`clipped`]).
const CLIP: usize = 200;

/// A parser's message with each line cut to [`CLIP`] characters (it quotes the offending
/// line, which may be a megabyte long). The quoted line and the caret line under it are cut to
/// the same window around the caret (after their "N | " gutter, the quoted line marked
/// "... "), so that the caret still points at the column the message names.
fn clipped(msg: &str) -> String {
    let lines: Vec<&str> = msg.lines().collect();
    let caret = lines.iter().position(|l| is_caret_line(l));
    let from = caret
        .and_then(|k| lines[k].chars().position(|c| c == '^'))
        .map_or(0, |c| c.saturating_sub(CLIP / 2));
    lines
        .iter()
        .enumerate()
        .map(|(k, l)| match caret {
            Some(c) if k == c => window(l, from, "    "),
            Some(c) if k + 1 == c => window(l, from, "... "),
            _ => window(l, 0, ""),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A parser's caret line: a gutter "|" followed by spaces and carets only.
fn is_caret_line(l: &str) -> bool {
    let t = l.trim_start();
    t.strip_prefix('|')
        .is_some_and(|r| r.contains('^') && r.chars().all(|c| c == ' ' || c == '^'))
}

/// `l` cut to [`CLIP`] characters from character `from` on, its "N | " gutter kept when the
/// window starts after it (`mark`, as wide on every line cut so, stands for what was left out
/// before; " ..." marks what was left out after).
fn window(l: &str, from: usize, mark: &str) -> String {
    let chars: Vec<char> = l.chars().collect();
    let gutter = l.find("| ").map_or(0, |b| l[..b + 2].chars().count());
    let (head, start) = if from > gutter {
        (
            format!("{}{mark}", chars[..gutter].iter().collect::<String>()),
            from,
        )
    } else {
        (String::new(), 0)
    };
    let end = (start + CLIP).min(chars.len());
    let tail = if end < chars.len() { " ..." } else { "" };
    format!(
        "{head}{}{tail}",
        chars[start.min(end)..end].iter().collect::<String>()
    )
}

/// A deserialiser's message for a user: its first line (the key is named already), with the
/// code's type names said as what they are in the scene ("struct RawOil": a table).
fn plain_message(msg: &str) -> String {
    let first = msg.lines().next().unwrap_or(msg).trim();
    let first = match first.find("expected struct Raw") {
        Some(at) => format!("{}expected a table", &first[..at]),
        None => first.to_string(),
    };
    [
        ("expected f64", "expected a number"),
        ("expected usize", "expected a whole number >= 0"),
        ("expected u64", "expected a whole number >= 0"),
        ("expected u32", "expected a whole number >= 0"),
        ("expected i64", "expected a whole number"),
        ("expected a map", "expected a table"),
        ("expected a sequence", "expected an array"),
    ]
    .iter()
    .fold(first, |m, (code, plain)| m.replace(code, plain))
}

pub(super) struct Checker<'a> {
    pub(super) path: &'a Path,
}

impl Checker<'_> {
    pub(super) fn err(&self, key: &str, msg: impl Into<String>) -> SceneError {
        SceneError::Field {
            path: self.path.to_path_buf(),
            key: key.to_string(),
            msg: msg.into(),
        }
    }
    /// A finite value > 0 (mm converted to m when `mm`).
    pub(super) fn positive(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("must be a positive number, got {}", crate::text::exact(v)),
            ))
        }
    }
    /// A finite value >= 0.
    pub(super) fn nonneg(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("must be a number >= 0, got {}", crate::text::exact(v)),
            ))
        }
    }
    /// A finite value.
    pub(super) fn finite(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("must be a finite number, got {}", crate::text::exact(v)),
            ))
        }
    }
    /// A finite value in [lo, hi] (a bound the physics of this engine class sets; the message
    /// gives the range).
    pub(super) fn within(
        &self,
        key: &str,
        v: f64,
        (lo, hi): (f64, f64),
    ) -> Result<f64, SceneError> {
        if v.is_finite() && (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!(
                    "must lie in [{}, {}], got {}",
                    num(lo),
                    num(hi),
                    crate::text::exact(v)
                ),
            ))
        }
    }
    /// A length given in mm, in metres: positive and within [`LENGTH_MM`] (1e-9 mm walls
    /// made degenerate elements named by no key, 1e308 mm lengths overflowed).
    pub(super) fn mm(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.positive(key, v)?;
        Ok(self.within(key, v, LENGTH_MM)? * 1e-3)
    }
}

/// Lengths a scene may give in mm: from 10 um (below any machined or cast feature) to 30 m
/// (a marine engine's block is ~20 m long).
pub(super) const LENGTH_MM: (f64, f64) = (1e-2, 3e4);

/// The analysis points must fit on the liner: first + (n - 1) spacing < length, checked before
/// their depths are listed (a count of 9e18 was allocated).
pub(super) fn check_analysis_points(c: &Checker<'_>, l: &raw::RawLiner) -> Result<(), SceneError> {
    c.positive("liner.length_mm", l.length_mm)?;
    c.positive("liner.analysis_spacing_mm", l.analysis_spacing_mm)?;
    // points closer than 1 mm are one point to the mesh (1e-9 mm gave four identical ones)
    let spacing = c.within(
        "liner.analysis_spacing_mm",
        l.analysis_spacing_mm,
        (1.0, LENGTH_MM.1),
    )?;
    let first = c.positive("liner.analysis_first_depth_mm", l.analysis_first_depth_mm)?;
    let fit = ((l.length_mm - first) / spacing).floor() + 1.0;
    if l.analysis_points as f64 > fit.max(0.0) {
        return Err(c.err(
            "liner.analysis_points",
            format!(
                "{} points {} mm apart from {} mm below the top do not fit on a {} mm liner (at most {})",
                l.analysis_points,
                num(spacing),
                num(first),
                num(l.length_mm),
                num(fit.max(0.0))
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// Regression: a parse error past column 200 of a long line lost its caret (each line was
    /// cut to its first 200 characters); the quoted line and the caret line are cut to the
    /// same window, and the caret stands under the offending text.
    #[test]
    fn regression_a_long_lines_caret_is_kept_under_the_error() {
        let values = vec!["1.0"; 300].join(", ");
        let text = format!("x = [{values}, 1.0.0, 2.0]\n");
        let err = toml::from_str::<toml::Value>(&text)
            .unwrap_err()
            .to_string();
        let out = super::clipped(&err);
        // the text under the caret, in the parser's message and in the clipped one
        let under = |msg: &str| {
            let lines: Vec<&str> = msg.lines().collect();
            let k = lines.iter().position(|l| super::is_caret_line(l)).unwrap();
            let col = lines[k].find('^').unwrap();
            lines[k - 1][col..col + 8].to_string()
        };
        assert_eq!(under(&out), under(&err), "{out}");
        assert!(under(&out).starts_with(".0, 2.0]"), "{out}");
        assert!(out.lines().all(|l| l.chars().count() <= 220), "{out}");
        // a short message is left as it is
        let short =
            "TOML parse error at line 1, column 5\n  |\n1 | x = 1.0.0\n  |     ^\ninvalid float";
        assert_eq!(super::clipped(short), short);
    }
}
