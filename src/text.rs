//! Numbers in messages: a few significant digits, whatever the magnitude (`1e308`, not 309 digits).

/// Formats `x` with about four significant digits: plain notation between 1e-3 and 1e6,
/// scientific outside, integers as integers; `inf`, `-inf` and `NaN` as such.
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if x == x.trunc() && a < 1e6 {
        return format!("{}", x as i64);
    }
    if a == 0.0 || (1e-3..1e6).contains(&a) {
        let s = format!("{:.*}", (3 - a.log10().floor() as i32).max(0) as usize, x);
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.3e}");
        // 1.500e-7 -> 1.5e-7
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

/// Formats `x` exactly as read (the shortest form that reads back to it): plain notation
/// between 1e-3 and 1e6, scientific outside (`1e300`, not 301 digits). For values checked
/// against a bound, where [`num`]'s rounding could print 720.0004 as the bound itself.
pub fn exact(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() || a == 0.0 || (1e-3..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The message for a CSV row whose field count differs from the header's; more fields than
/// columns usually means decimal commas (`369,5` for 369.5), which would shift every value.
pub fn field_count_message(found: usize, header: usize) -> String {
    let hint = if found > header {
        ": decimal commas? write numbers with a decimal point (369.5, not 369,5)"
    } else {
        ""
    };
    format!("{found} fields, the header has {header}{hint}")
}

/// The first column name of a CSV header `names` that appears twice, among `wanted` (a second
/// `time_s` column was read silently, the first one winning).
pub fn repeated_column<'a>(names: &[&'a str], wanted: &[&str]) -> Option<&'a str> {
    names
        .iter()
        .enumerate()
        .find(|&(k, n)| wanted.contains(n) && names[..k].contains(n))
        .map(|(_, n)| *n)
}

/// The items' Display forms joined by `sep` (`[2, 5, 4]` with ", " reads "2, 5, 4"): lists in
/// user-facing text, never Rust's debug form.
pub fn joined<T: std::fmt::Display>(items: &[T], sep: &str) -> String {
    items
        .iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(sep)
}

/// At most `max` characters of `s` for a message, the rest counted: a one-line file (no line
/// ends it knows, e.g. CR-only) put its whole text, 100 MB, into a header message.
pub fn clipped(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        None => s.to_string(),
        Some((cut, _)) => format!("{}... ({} more bytes)", &s[..cut], s.len() - cut),
    }
}

/// Warnings said through [`warn`] in this process, in order: kept for the outputs that list
/// them (a ROM keeps those of its build in `RomInfo::warnings`, which `simulate --json` lists
/// even when the ROM comes from the cache).
static SAID: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

/// Says a warning about the model: `log::warn!` (standard error) and kept for [`said_since`].
pub fn warn(msg: String) {
    log::warn!("{msg}");
    SAID.lock().unwrap_or_else(|p| p.into_inner()).push(msg);
}

/// How many warnings [`warn`] has said so far: a mark for [`said_since`].
pub fn said_count() -> usize {
    SAID.lock().unwrap_or_else(|p| p.into_inner()).len()
}

/// The distinct warnings said since `mark` ([`said_count`]), in order.
pub fn said_since(mark: usize) -> Vec<String> {
    let said = SAID.lock().unwrap_or_else(|p| p.into_inner());
    let mut out: Vec<String> = Vec::new();
    for w in said.iter().skip(mark) {
        if !out.contains(w) {
            out.push(w.clone());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn few_significant_digits() {
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(1e-308), "1e-308");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(num(0.125), "0.125");
        assert_eq!(num(1234.5678), "1235");
        assert_eq!(num(1e9), "1e9");
        assert_eq!(num(16416000.0), "1.642e7");
        assert_eq!(num(-3.0), "-3");
        assert_eq!(num(9.223372036854776e18), "9.223e18");
        assert_eq!(num(1.0 / 3.0), "0.3333");
        assert_eq!(num(f64::NAN), "NaN");
        assert_eq!(num(1.5e-7), "1.5e-7");
    }
}
