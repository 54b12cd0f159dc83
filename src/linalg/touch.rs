//! Zeroed buffers whose pages are first touched on all cores.
//!
//! A fresh allocation's pages are mapped by the kernel on first write, each zeroed there (and
//! on a virtual machine backed by the host at that moment): on the 2-core development VM that
//! ran at 0.5-1.7 GB/s on one thread (`clear_page_erms` was 13 % of the ROM build's samples,
//! the 1.7 GB Craig-Bampton block and the 0.4 GB factors zeroed by one thread). Writing the
//! zeros from every core maps the pages in parallel; the values are the same (zeros), so the
//! results are the same to the bit.

use faer::Mat;
use rayon::prelude::*;

/// Elements per parallel chunk: one 2 MiB (huge) page of f64.
const CHUNK: usize = 1 << 18;

/// Below this many elements (16 MiB) one thread zeroes the buffer.
const PARALLEL_FROM: usize = 1 << 21;

/// A vector of `len` zeros, its pages first touched on all cores.
pub fn zeros(len: usize) -> Vec<f64> {
    if len < PARALLEL_FROM {
        return vec![0.0; len];
    }
    let mut v: Vec<f64> = Vec::with_capacity(len);
    v.spare_capacity_mut()
        .par_chunks_mut(CHUNK)
        .for_each(|c| c.iter_mut().for_each(|x| _ = x.write(0.0)));
    // SAFETY: the first `len` elements were written above.
    unsafe { v.set_len(len) };
    v
}

/// An `nrows` x `ncols` matrix of zeros, its pages first touched on all cores.
pub fn zeros_mat(nrows: usize, ncols: usize) -> Mat<f64> {
    if nrows.saturating_mul(ncols) < PARALLEL_FROM {
        return Mat::zeros(nrows, ncols);
    }
    let mut m = Mat::<f64>::with_capacity(nrows, ncols);
    // SAFETY: within the capacity reserved above; every element in bounds is written below
    // before the matrix is read or returned.
    unsafe { m.set_dims(nrows, ncols) };
    let cols = (CHUNK / nrows.max(1)).max(1);
    m.as_mut().par_col_chunks_mut(cols).for_each(|c| {
        let (rows, stride, base) = (c.nrows(), c.col_stride(), c.as_ptr_mut());
        for j in 0..c.ncols() {
            // SAFETY: column j of the chunk: `rows` contiguous elements (unit row stride, as
            // allocated) inside the matrix's allocation; written, not read
            unsafe { std::ptr::write_bytes(base.offset(j as isize * stride), 0, rows) };
        }
    });
    m
}

#[cfg(test)]
mod tests {
    /// Verification: every element is zero, at sizes on both sides of the parallel threshold
    /// and with ragged last chunks.
    #[test]
    fn verification_touched_buffers_are_zero() {
        for len in [
            0,
            7,
            super::PARALLEL_FROM - 1,
            super::PARALLEL_FROM + 12_345,
        ] {
            let v = super::zeros(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0));
        }
        for (r, c) in [(0, 0), (3, 5), (100_003, 23), (1 << 19, 5)] {
            let m = super::zeros_mat(r, c);
            assert_eq!((m.nrows(), m.ncols()), (r, c));
            assert!((0..c).all(|j| m.col(j).iter().all(|&x| x == 0.0)));
        }
    }
}
