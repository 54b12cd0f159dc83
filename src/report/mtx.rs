//! Matrix Market output of symmetric sparse matrices ("coordinate real symmetric": the lower
//! triangle, 1-based), readable by SciPy's `mmread`, MATLAB and Octave.

use crate::linalg::sparse::Pattern;
use std::io::Write;

/// Writes the lower triangle of the symmetric matrix `values` on `pattern`.
pub fn write_symmetric(
    pattern: &Pattern,
    values: &[f64],
    comment: &str,
    w: &mut dyn Write,
) -> std::io::Result<()> {
    let nnz = pattern.lower_entries(values).count();
    writeln!(w, "%%MatrixMarket matrix coordinate real symmetric")?;
    for line in comment.lines() {
        writeln!(w, "% {line}")?;
    }
    writeln!(w, "{} {} {}", pattern.n, pattern.n, nnz)?;
    let mut buf = ryu::Buffer::new();
    for (r, c, v) in pattern.lower_entries(values) {
        writeln!(w, "{} {} {}", r + 1, c + 1, buf.format(v))?;
    }
    Ok(())
}
