//! `--set key=value` overrides applied to the parsed TOML tree before validation, so any field
//! of a scene can be changed from the command line (`--set liner.mesh.circumferential=64`).
//! The value is read as a TOML value (`64`, `1.5e9`, `"hex20"`, `[1, 2]`, `true`); anything
//! that is not valid TOML is taken as a string.

use toml::{Table, Value};

/// A malformed override.
#[derive(Debug, thiserror::Error)]
pub enum OverrideError {
    #[error("--set '{0}': expected key=value (for example liner.mesh.radial=3)")]
    Syntax(String),
    #[error(
        "--set '{arg}': '{prefix}' is a value, not a table, so '{key}' cannot be set below it"
    )]
    NotATable {
        arg: String,
        prefix: String,
        key: String,
    },
    #[error("--set '{arg}': {msg}")]
    Value { arg: String, msg: String },
    #[error("--set '{key}' is given twice ('{first}', then '{second}'): give each key once")]
    Repeated {
        key: String,
        first: String,
        second: String,
    },
}

/// Refuses a key given twice among the user's overrides: `--set K=a --set K=b` would keep the
/// last without a word, and so would a table and a key inside it (`--set a={b=1} --set a.b=2`:
/// which one holds depends on their order). Keys compare by their dotted parts, trimmed; an
/// argument without `=` is left to [`apply`] to refuse.
pub fn check_repeated(sets: &[String]) -> Result<(), OverrideError> {
    let mut seen: Vec<(String, &str)> = Vec::new();
    for arg in sets {
        let Some((key, value)) = arg.split_once('=') else {
            continue;
        };
        let key = key.split('.').map(str::trim).collect::<Vec<_>>().join(".");
        let clash = seen
            .iter()
            .find(|(k, _)| within(k, &key) || within(&key, k));
        if let Some((first_key, first)) = clash {
            return Err(OverrideError::Repeated {
                key: if first_key.len() <= key.len() {
                    key.clone()
                } else {
                    first_key.clone()
                },
                first: first.to_string(),
                second: value.trim().to_string(),
            });
        }
        seen.push((key, value.trim()));
    }
    Ok(())
}

/// Whether dotted key `inner` is `outer` or lies inside the table `outer`.
pub fn within(outer: &str, inner: &str) -> bool {
    inner == outer
        || inner
            .strip_prefix(outer)
            .is_some_and(|r| r.starts_with('.'))
}

/// Parses the value part of an override: a TOML value, a number where the text is one that
/// TOML does not read (`80.`, `1e400`, 100000000000000000000), or the text as a string. A value that brings more than itself is refused (TOML after it on another line, or a
/// comment: `--set 'a=1\n[b]\nc=2'` set a and dropped the rest without a word).
pub fn parse_value(text: &str) -> Result<Value, String> {
    if text.contains(['\n', '\r']) {
        return Err("a value is one line: give each key its own --set".into());
    }
    let probe = format!("v = {text}");
    match probe.parse::<Table>() {
        Ok(mut t) => {
            let v = t
                .remove("v")
                .unwrap_or_else(|| Value::String(text.to_string()));
            if has_comment(text, &v) {
                return Err("a comment after the value (#) is not taken: remove it".into());
            }
            Ok(v)
        }
        // a number TOML does not write so (`80.`, an integer beyond 64 bits) is the number,
        // which the key's own check then judges, not a string ("invalid type: string")
        Err(_) => Ok(match text.trim().parse::<f64>() {
            Ok(x) => Value::Float(x),
            Err(_) => Value::String(text.to_string()),
        }),
    }
}

/// Whether the value text `text` (read as `v`) ends in a comment: some '#' of it is where the
/// same value ends (the text before it reads as `v` too), not a character of a string.
fn has_comment(text: &str, v: &Value) -> bool {
    text.match_indices('#').any(|(i, _)| {
        format!("v = {}", &text[..i])
            .parse::<Table>()
            .is_ok_and(|t| t.get("v") == Some(v))
    })
}

/// Applies one `key.path=value` override to `root`.
pub fn apply(root: &mut Table, arg: &str) -> Result<(), OverrideError> {
    let (key, value) = arg
        .split_once('=')
        .ok_or_else(|| OverrideError::Syntax(arg.to_string()))?;
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    if key.is_empty() || parts.iter().any(|p| p.is_empty()) {
        return Err(OverrideError::Syntax(arg.to_string()));
    }
    let mut table = root;
    for (i, part) in parts[..parts.len() - 1].iter().enumerate() {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        table = match entry {
            Value::Table(t) => t,
            _ => {
                return Err(OverrideError::NotATable {
                    arg: arg.to_string(),
                    prefix: parts[..=i].join("."),
                    key: key.to_string(),
                })
            }
        };
    }
    let value = parse_value(value.trim()).map_err(|msg| OverrideError::Value {
        arg: arg.to_string(),
        msg,
    })?;
    table.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_given_twice_is_refused_with_both_values() {
        let sets = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(check_repeated(&sets(&["a.b=1", "a.c=1", "b=2"])).is_ok());
        let e = check_repeated(&sets(&["a.b=1", "x=0", " a . b = 2"])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--set 'a.b' is given twice ('1', then '2'): give each key once"
        );
    }

    /// Regression: a table and a key inside it, both set, were not refused (which one held
    /// depended on the order of the flags).
    #[test]
    fn regression_a_table_and_a_key_inside_it_are_refused() {
        let sets = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        for order in [["a.b.c=1", "a.b={c=2}"], ["a.b={c=2}", "a.b.c=1"]] {
            let e = check_repeated(&sets(&order)).unwrap_err().to_string();
            assert!(e.contains("'a.b.c' is given twice"), "{e}");
        }
        assert!(check_repeated(&sets(&["a.b=1", "a.bc=2"])).is_ok());
    }

    /// Regression: a value followed by more TOML (another line) or by a comment kept the value
    /// and dropped the rest silently.
    #[test]
    fn regression_a_value_with_more_after_it_is_refused() {
        let mut t: Table = "[a]\nb = 1\n".parse().unwrap();
        for arg in ["a.b=100\n[engine]\ncylinders=3", "a.b=100 # was 80"] {
            let e = apply(&mut t, arg).unwrap_err().to_string();
            assert!(e.starts_with("--set '"), "{e}");
        }
        assert_eq!(t["a"]["b"].as_integer(), Some(1));
        // a comment after a string that holds '#' too
        assert!(apply(&mut t, "a.s=\"#\" # comment").is_err());
        // a '#' inside a string is the string's
        apply(&mut t, "a.s=\"x # y\"").unwrap();
        assert_eq!(t["a"]["s"].as_str(), Some("x # y"));
        apply(&mut t, "a.s=free text").unwrap();
        assert_eq!(t["a"]["s"].as_str(), Some("free text"));
    }

    #[test]
    fn sets_nested_values_with_toml_types() {
        let mut t: Table = "[a]\nb = 1\n".parse().unwrap();
        apply(&mut t, "a.b=2.5").unwrap();
        apply(&mut t, "a.c.d=hex20").unwrap();
        apply(&mut t, "e=[1, 2]").unwrap();
        assert_eq!(t["a"]["b"].as_float(), Some(2.5));
        assert_eq!(t["a"]["c"]["d"].as_str(), Some("hex20"));
        assert_eq!(t["e"].as_array().unwrap().len(), 2);
    }

    /// Regression (session 74's hostile sweep): `80.` and an integer beyond 64 bits were taken
    /// as strings ("invalid type: string", naming no number); they are the numbers, and a
    /// word stays a string.
    #[test]
    fn regression_numbers_toml_does_not_write_are_numbers() {
        let mut t = Table::new();
        apply(&mut t, "a=80.").unwrap();
        apply(&mut t, "b=100000000000000000000").unwrap();
        apply(&mut t, "c=hex20").unwrap();
        assert_eq!(t["a"].as_float(), Some(80.0));
        assert_eq!(t["b"].as_float(), Some(1e20));
        assert_eq!(t["c"].as_str(), Some("hex20"));
    }

    #[test]
    fn rejects_bad_syntax_and_paths_through_values() {
        let mut t: Table = "a = 1\n".parse().unwrap();
        assert!(matches!(
            apply(&mut t, "novalue"),
            Err(OverrideError::Syntax(_))
        ));
        assert!(matches!(
            apply(&mut t, "a..b=1"),
            Err(OverrideError::Syntax(_))
        ));
        assert!(matches!(
            apply(&mut t, "a.b=1"),
            Err(OverrideError::NotATable { .. })
        ));
    }
}
