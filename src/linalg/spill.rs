//! A model's K, M and pattern rows (and mode shapes waiting for their certificate) put aside
//! on disk while a large factor is alive (out of core). The certified eigen-solve reads them only before and after each factorisation and
//! the Lanczos iteration ([`crate::eigen::modal`]); in between, the factor holds most of the
//! memory, so they wait in an unnamed temporary file and come back bit for bit.

use super::sparse::{Pattern, StiffnessMass};
use std::io::{Read, Seek, Write};

/// K, M and the row indices go to disk when the factor will hold at least this many bytes:
/// then the arrays are a fifth or less of the peak, and writing and reading them (page-cache
/// speed) costs a few per cent of one factorisation. Smaller models keep them: on the
/// 48k-DOF liner (factor 0.2 GB) the I/O would cost a tenth of the solve and save little.
pub const SPILL_FACTOR_BYTES: usize = 1 << 30;

thread_local! {
    /// [`SPILL_FACTOR_BYTES`] unless a test of this thread lowers it ([`spill_threshold`]).
    static SPILL_AT: std::cell::Cell<usize> = const { std::cell::Cell::new(SPILL_FACTOR_BYTES) };
}

/// The factor size from which K and M are put aside on this thread: [`SPILL_FACTOR_BYTES`]
/// (tests lower it to run the out-of-core path on small models).
pub fn spill_threshold() -> usize {
    SPILL_AT.with(|c| c.get())
}

/// Sets [`spill_threshold`] for the calling thread (tests).
#[cfg(test)]
pub fn set_spill_threshold(bytes: usize) {
    SPILL_AT.with(|c| c.set(bytes));
}

/// Whether the temporary directory (where [`StiffnessMass::put_aside`] writes) has `bytes`
/// free for an unprivileged writer, by `statvfs` (false when it cannot be asked).
pub fn room_for(bytes: usize) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(dir) = std::ffi::CString::new(std::env::temp_dir().as_os_str().as_bytes()) else {
        return false;
    };
    // SAFETY: statvfs writes only into the zeroed struct it is given; dir is NUL-terminated
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(dir.as_ptr(), &mut st) } != 0 {
        return false;
    }
    (st.f_bavail as u128) * (st.f_frsize as u128) >= bytes as u128
}

/// The arrays put aside: an unnamed temporary file (deleted when dropped) and their lengths.
pub struct Aside {
    file: std::fs::File,
    lens: [usize; 4],
}

impl StiffnessMass {
    /// Moves K, M, the pattern's row indices and `extra` (mode shapes waiting for their
    /// certificate, or nothing) into a temporary file, leaving them empty, and returns what
    /// [`StiffnessMass::take_back`] restores. None (the arrays stay in memory) when the file
    /// cannot be made or written: putting aside saves memory, never decides a result.
    pub fn put_aside(&mut self, extra: &mut Vec<f64>) -> Option<Aside> {
        let rows: &[usize] = &self.pattern.row_idx;
        let bytes = 8 * (self.k.len() + self.m.len() + rows.len() + extra.len());
        if !room_for(bytes) {
            log::debug!(
                "K and M stay in memory: the temporary directory has no room for {bytes} bytes"
            );
            return None;
        }
        let written = (|| -> std::io::Result<std::fs::File> {
            let mut file = tempfile::tempfile()?;
            file.write_all(bytemuck::cast_slice(&self.k))?;
            file.write_all(bytemuck::cast_slice(&self.m))?;
            file.write_all(bytemuck::cast_slice(rows))?;
            file.write_all(bytemuck::cast_slice(extra))?;
            Ok(file)
        })();
        match written {
            Ok(file) => {
                let lens = [
                    self.k.len(),
                    self.m.len(),
                    self.pattern.row_idx.len(),
                    extra.len(),
                ];
                self.k = Vec::new();
                self.m = Vec::new();
                self.pattern.row_idx = Vec::new();
                *extra = Vec::new();
                Some(Aside { file, lens })
            }
            Err(e) => {
                log::debug!("K and M stay in memory: the temporary file failed ({e})");
                None
            }
        }
    }

    /// Reads back what [`StiffnessMass::put_aside`] wrote (`extra` receives its array); an
    /// error when the file cannot be read back in full (the model is then incomplete and the
    /// solve must stop).
    pub fn take_back(&mut self, aside: Aside, extra: &mut Vec<f64>) -> std::io::Result<()> {
        let Aside { mut file, lens } = aside;
        file.rewind()?;
        let mut k = vec![0.0f64; lens[0]];
        file.read_exact(bytemuck::cast_slice_mut(&mut k))?;
        let mut m = vec![0.0f64; lens[1]];
        file.read_exact(bytemuck::cast_slice_mut(&mut m))?;
        let mut rows = vec![0usize; lens[2]];
        file.read_exact(bytemuck::cast_slice_mut(&mut rows))?;
        let mut more = vec![0.0f64; lens[3]];
        file.read_exact(bytemuck::cast_slice_mut(&mut more))?;
        (self.k, self.m, self.pattern.row_idx, *extra) = (k, m, rows, more);
        Ok(())
    }
}

/// The lower triangle (rows >= column) of K - sigma M on `km`'s pattern, on a pattern of its
/// own: what a factorisation of the lower side reads, at half the memory of both triangles.
pub fn lower_shifted(km: &StiffnessMass, sigma: f64) -> (Pattern, Vec<f64>) {
    let p = &km.pattern;
    let mut col_ptr = Vec::with_capacity(p.n + 1);
    col_ptr.push(0);
    let half = p.nnz() / 2 + p.n;
    let (mut row_idx, mut kept) = (Vec::with_capacity(half), Vec::with_capacity(half));
    for c in 0..p.n {
        for q in p.col_ptr[c]..p.col_ptr[c + 1] {
            if p.row_idx[q] >= c {
                row_idx.push(p.row_idx[q]);
                kept.push(km.k[q] - sigma * km.m[q]);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let lower = Pattern {
        n: p.n,
        col_ptr,
        row_idx,
    };
    (lower, kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Verification: the free space of the temporary directory is read, not assumed: a byte
    /// fits (the tests write there), usize::MAX bytes (16 EiB) do not.
    #[test]
    fn verification_the_room_for_putting_aside_is_read_from_the_disk() {
        assert!(room_for(1));
        assert!(!room_for(usize::MAX));
    }

    /// Verification: what is put aside comes back bit for bit, the arrays are empty meanwhile,
    /// and the lower triangle of K - sigma M keeps each column's rows at or below the diagonal.
    #[test]
    fn verification_put_aside_and_taken_back_bit_for_bit() {
        let pattern = Pattern {
            n: 3,
            col_ptr: vec![0, 2, 5, 7],
            row_idx: vec![0, 1, 0, 1, 2, 1, 2],
        };
        let k = vec![2.0, -1.0, -1.0, 2.0, -1.0, -1.0, 1.0 / 3.0];
        let m: Vec<f64> = k.iter().map(|v| v * std::f64::consts::PI).collect();
        let before = StiffnessMass { pattern, k, m };
        let mut km = before.clone();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let shapes: Vec<f64> = (0..7).map(|i| (i as f64).exp()).collect();
        let mut extra = shapes.clone();
        let aside = km
            .put_aside(&mut extra)
            .expect("the temporary directory is writable");
        assert!(km.k.is_empty() && km.m.is_empty() && km.pattern.row_idx.is_empty());
        assert!(extra.is_empty());
        km.take_back(aside, &mut extra).unwrap();
        assert_eq!(bits(&extra), bits(&shapes));
        assert_eq!(km.pattern, before.pattern);
        assert_eq!(bits(&km.k), bits(&before.k));
        assert_eq!(bits(&km.m), bits(&before.m));
        let (lower, vals) = lower_shifted(&km, 0.0);
        assert_eq!(lower.col_ptr, vec![0, 2, 4, 5]);
        assert_eq!(lower.row_idx, vec![0, 1, 1, 2, 2]);
        assert_eq!(vals, vec![2.0, -1.0, 2.0, -1.0, 1.0 / 3.0]);
    }
}
