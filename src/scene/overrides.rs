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
    #[error("--set '{key}' is given twice ('{first}', then '{second}'): give each key once")]
    Repeated {
        key: String,
        first: String,
        second: String,
    },
}

/// Refuses a key given twice among the user's overrides: `--set K=a --set K=b` would keep the
/// last without a word. Keys compare by their dotted parts, trimmed; an argument without `=`
/// is left to [`apply`] to refuse.
pub fn check_repeated(sets: &[String]) -> Result<(), OverrideError> {
    let mut seen: std::collections::HashMap<String, &str> = std::collections::HashMap::new();
    for arg in sets {
        let Some((key, value)) = arg.split_once('=') else {
            continue;
        };
        let key = key.split('.').map(str::trim).collect::<Vec<_>>().join(".");
        if let Some(first) = seen.insert(key.clone(), value.trim()) {
            return Err(OverrideError::Repeated {
                key,
                first: first.to_string(),
                second: value.trim().to_string(),
            });
        }
    }
    Ok(())
}

/// Parses the value part of an override.
pub fn parse_value(text: &str) -> Value {
    let probe = format!("v = {text}");
    match probe.parse::<Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| Value::String(text.to_string())),
        Err(_) => Value::String(text.to_string()),
    }
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
    table.insert(
        parts[parts.len() - 1].to_string(),
        parse_value(value.trim()),
    );
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
