//! The dense matrix that crosses module boundaries: `ndarray::Array2<f64>` in standard
//! (row-major) layout, serialisable with the ROM cache. faer and nalgebra stay inside the
//! numerics that need their factorisations.

pub use ndarray::Array2;

/// Row-major dense matrix [rows x cols].
pub type Dense = Array2<f64>;

/// A copy of a faer matrix.
pub fn from_faer(m: &faer::Mat<f64>) -> Dense {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)])
}

/// A matrix of `rows` x `cols` from row-major `data` (`data.len()` must be rows x cols).
pub fn from_rows(rows: usize, cols: usize, data: Vec<f64>) -> Dense {
    Array2::from_shape_vec((rows, cols), data).expect("rows x cols values")
}

/// A matrix whose rows are `rows` (all of one length; no rows: 0 x 0).
pub fn from_row_vecs(rows: Vec<Vec<f64>>) -> Dense {
    let cols = rows.first().map_or(0, Vec::len);
    let n = rows.len();
    from_rows(n, cols, rows.into_iter().flatten().collect())
}

/// Row `i` of a standard-layout matrix as a slice (the inner loops of the transient read
/// contiguous rows).
pub fn row(m: &Dense, i: usize) -> &[f64] {
    let n = m.ncols();
    &m.as_slice().expect("standard layout")[i * n..(i + 1) * n]
}

/// All values in row-major order.
pub fn values(m: &Dense) -> &[f64] {
    m.as_slice().expect("standard layout")
}

/// All values in row-major order, mutable.
pub fn values_mut(m: &mut Dense) -> &mut [f64] {
    m.as_slice_mut().expect("standard layout")
}

/// Serialises a matrix as a list of its rows (JSON: `[[..], [..]]`, the shape a reader of a
/// table expects), for `#[serde(serialize_with = "...")]` on result fields.
pub fn serialize_rows<S: serde::Serializer>(m: &Dense, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeSeq;
    let mut seq = s.serialize_seq(Some(m.nrows()))?;
    for r in m.rows() {
        seq.serialize_element(&r.to_vec())?;
    }
    seq.end()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_row_major_slices() {
        let m = from_rows(2, 3, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(row(&m, 1), &[4.0, 5.0, 6.0]);
        assert_eq!(m[[0, 2]], 3.0);
        let f = faer::Mat::<f64>::from_fn(2, 3, |i, j| (3 * i + j + 1) as f64);
        assert_eq!(from_faer(&f), m);
        // the cache's round trip keeps the layout
        let bytes = bincode::serialize(&m).unwrap();
        let back: Dense = bincode::deserialize(&bytes).unwrap();
        assert_eq!(row(&back, 0), &[1.0, 2.0, 3.0]);
        // a table for JSON readers: its rows
        let mut out = Vec::new();
        serialize_rows(&m, &mut serde_json::Serializer::new(&mut out)).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "[[1.0,2.0,3.0],[4.0,5.0,6.0]]"
        );
    }
}
