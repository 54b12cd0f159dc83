//! Single-vector solves with a supernodal Cholesky factor on both cores, split along the
//! elimination tree.
//!
//! A single right-hand side is bound by reading the factor (each entry is used once), and
//! one core reads memory at about half the rate two do (9.7 against 19 GB/s measured on the
//! 2-core machine), so a solve that reads the factor from two threads at once runs up to twice
//! as fast. The elimination tree of a nested-dissection order makes that possible: the
//! subtrees below the top separators are independent.
//!
//! [`TreePlan`] splits the supernodal elimination tree into *tasks* (whole subtrees) and the
//! *top* (the separators above them), by taking the heaviest subtree apart at its root until
//! each task holds at most 1/16 (`TASKS`) of the factor's entries. The forward solve L y = b runs
//! the tasks in parallel, each on a local copy of its rows, gathering its updates of the top
//! rows, -sum L_ts y_s, in a buffer of its own; the rows and buffers are written back in task
//! order, then the top supernodes run in order. The backward solve L^T x = y runs the top in reverse order, then the tasks in
//! parallel (they only read the top rows). The split depends on the factor's structure only,
//! and every sum runs in the same order on any number of threads, so the result is the same
//! to the last bit on 1 or 2 cores (the property the ROM builds rely on; see
//! [`super::thread_count_invariant`]).

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, ColMut, MatRef, Par};
use rayon::prelude::*;

/// The largest task holds at most 1/TASKS of the factor's entries: enough tasks to balance
/// two cores (rayon steals them), few enough that their update buffers stay small.
const TASKS: usize = 16;

/// Marks a row of the top in [`TreePlan::owner`].
const TOP: u32 = u32::MAX;

/// One task: a subtree of supernodes and the top rows it updates.
struct Task {
    /// Supernodes of the subtree, ascending (children before parents).
    supernodes: Vec<usize>,
    /// Its rows (columns of its supernodes, one supernode after the other): the global row
    /// of each entry of its local vector.
    rows: Vec<usize>,
    /// The top rows its supernodes update, ascending.
    outside: Vec<usize>,
}

/// The split of a supernodal factor's elimination tree (see the module doc).
pub struct TreePlan {
    tasks: Vec<Task>,
    /// Supernodes above the tasks, ascending.
    top: Vec<usize>,
    /// For each row (column of L): its task, or [`TOP`].
    owner: Vec<u32>,
    /// For each row of a task: its place in the task's local vector (its supernodes' columns
    /// one after the other).
    local: Vec<usize>,
}

impl TreePlan {
    /// Splits the elimination tree of `sym`: the parent of supernode s is the supernode that
    /// holds the first row of its off-diagonal pattern.
    pub fn new(sym: &SymbolicSupernodalCholesky<usize>) -> Self {
        let ns = sym.n_supernodes();
        let (begin, end) = (sym.supernode_begin(), sym.supernode_end());
        let owner_of = |row: usize| begin.partition_point(|&b| b <= row) - 1;
        let mut weight: Vec<usize> = (0..ns)
            .map(|s| {
                let width = end[s] - begin[s];
                width * (width + sym.supernode(s).pattern().len())
            })
            .collect();
        let mut children = vec![Vec::new(); ns];
        let mut roots = Vec::new();
        for s in 0..ns {
            match sym.supernode(s).pattern().first() {
                Some(&row) => {
                    let p = owner_of(row);
                    weight[p] += weight[s];
                    children[p].push(s);
                }
                None => roots.push(s),
            }
        }
        let total: usize = roots.iter().map(|&r| weight[r]).sum();
        let (mut task_roots, mut top) = (Vec::new(), Vec::new());
        let mut open = roots;
        while let Some(i) = (0..open.len()).max_by_key(|&i| (weight[open[i]], open[i])) {
            let r = open.swap_remove(i);
            if weight[r] * TASKS > total && !children[r].is_empty() {
                top.push(r);
                open.extend(children[r].iter().copied());
            } else {
                task_roots.push(r);
            }
        }
        top.sort_unstable();
        task_roots.sort_unstable();
        let mut owner = vec![TOP; sym.nrows()];
        let mut local = vec![0; sym.nrows()];
        let tasks = task_roots
            .iter()
            .enumerate()
            .map(|(t, &r)| {
                let mut supernodes = vec![r];
                let mut k = 0;
                while k < supernodes.len() {
                    supernodes.extend(children[supernodes[k]].iter().copied());
                    k += 1;
                }
                supernodes.sort_unstable();
                let rows: Vec<usize> = supernodes.iter().flat_map(|&s| begin[s]..end[s]).collect();
                for (i, &row) in rows.iter().enumerate() {
                    owner[row] = t as u32;
                    local[row] = i;
                }
                Task {
                    supernodes,
                    rows,
                    outside: Vec::new(),
                }
            })
            .collect::<Vec<_>>();
        let tasks = tasks
            .into_iter()
            .enumerate()
            .map(|(t, mut task)| {
                let mut outside: Vec<usize> = task
                    .supernodes
                    .iter()
                    .flat_map(|&s| sym.supernode(s).pattern().iter().copied())
                    .filter(|&row| owner[row] != t as u32)
                    .collect();
                outside.sort_unstable();
                outside.dedup();
                task.outside = outside;
                task
            })
            .collect();
        Self {
            tasks,
            top,
            owner,
            local,
        }
    }

    /// Solves L L^T x = b in place (x in the factor's order, `values` the factor L).
    pub fn solve(&self, sym: &SymbolicSupernodalCholesky<usize>, values: &[f64], x: &mut [f64]) {
        let node = |s: usize| Supernode::new(sym, values, s);
        let begin = sym.supernode_begin();
        let everywhere = |row: usize| Some(row);
        // forward: the tasks on their local vectors, each gathering its updates of the top
        let done: Vec<(Vec<f64>, Vec<f64>)> = (0..self.tasks.len())
            .into_par_iter()
            .map(|t| {
                let task = &self.tasks[t];
                let mut loc = self.gather(t, x);
                let mut buffer = vec![0.0; task.outside.len()];
                let locate = |row: usize| (self.owner[row] == t as u32).then(|| self.local[row]);
                for &s in &task.supernodes {
                    let at = self.local[begin[s]];
                    node(s).forward(&mut loc, at, &locate, &mut |row, v| {
                        let i = task.outside.binary_search(&row).expect("listed");
                        buffer[i] -= v;
                    });
                }
                (loc, buffer)
            })
            .collect();
        for (t, (loc, buffer)) in done.iter().enumerate() {
            self.scatter(t, loc, x);
            for (&row, v) in self.tasks[t].outside.iter().zip(buffer) {
                x[row] += v;
            }
        }
        for &s in &self.top {
            node(s).forward(x, begin[s], &everywhere, &mut |_, _| {
                unreachable!("the top updates only its own rows")
            });
        }
        // backward: the top, then the tasks reading the top's final values
        for &s in self.top.iter().rev() {
            node(s).backward(x, begin[s], &everywhere, &[]);
        }
        let done: Vec<Vec<f64>> = (0..self.tasks.len())
            .into_par_iter()
            .map(|t| {
                let mut loc = self.gather(t, x);
                let locate = |row: usize| (self.owner[row] == t as u32).then(|| self.local[row]);
                for &s in self.tasks[t].supernodes.iter().rev() {
                    node(s).backward(&mut loc, self.local[begin[s]], &locate, x);
                }
                loc
            })
            .collect();
        for (t, loc) in done.iter().enumerate() {
            self.scatter(t, loc, x);
        }
    }

    /// Task t's rows of x as its local vector.
    fn gather(&self, t: usize, x: &[f64]) -> Vec<f64> {
        self.tasks[t].rows.iter().map(|&row| x[row]).collect()
    }

    /// Writes task t's local vector back to its rows of x.
    fn scatter(&self, t: usize, loc: &[f64], x: &mut [f64]) {
        for (&row, &v) in self.tasks[t].rows.iter().zip(loc) {
            x[row] = v;
        }
    }
}

/// One supernode's block of L: the diagonal block L_ss (lower triangular) over the rows below
/// it, L_ps, whose rows are `pattern`.
struct Supernode<'a> {
    l_ss: MatRef<'a, f64>,
    l_ps: MatRef<'a, f64>,
    pattern: &'a [usize],
}

impl<'a> Supernode<'a> {
    fn new(sym: &'a SymbolicSupernodalCholesky<usize>, values: &'a [f64], s: usize) -> Self {
        let width = sym.supernode_end()[s] - sym.supernode_begin()[s];
        let pattern = sym.supernode(s).pattern();
        let vals = &values[sym.col_ptr_for_val()[s]..sym.col_ptr_for_val()[s + 1]];
        let block = MatRef::from_column_major_slice(vals, width + pattern.len(), width);
        let (l_ss, l_ps) = block.split_at_row(width);
        Self {
            l_ss,
            l_ps,
            pattern,
        }
    }

    /// Forward step: y_s = L_ss^-1 b_s, then b_p -= L_ps y_s for the rows p below. `loc` holds
    /// the supernode's rows from `at`; `locate` gives a row's place in `loc`, or None for a
    /// row elsewhere, whose update goes to `outside(row, value)` (to subtract).
    fn forward(
        &self,
        loc: &mut [f64],
        at: usize,
        locate: &dyn Fn(usize) -> Option<usize>,
        outside: &mut dyn FnMut(usize, f64),
    ) {
        let width = self.l_ss.ncols();
        let mut y = ColMut::from_slice_mut(&mut loc[at..at + width]);
        solve_lower_triangular_in_place(self.l_ss, y.as_mut().as_mat_mut(), Par::Seq);
        let mut tmp = vec![0.0; self.pattern.len()];
        matmul(
            ColMut::from_slice_mut(&mut tmp).as_mat_mut(),
            Accum::Replace,
            self.l_ps,
            y.as_ref().as_mat(),
            1.0,
            Par::Seq,
        );
        for (&row, v) in self.pattern.iter().zip(tmp) {
            match locate(row) {
                Some(i) => loc[i] -= v,
                None => outside(row, v),
            }
        }
    }

    /// Backward step: x_s = L_ss^-T (y_s - L_ps^T x_p); rows `locate` does not place in `loc`
    /// are read from `above` (final there).
    fn backward(
        &self,
        loc: &mut [f64],
        at: usize,
        locate: &dyn Fn(usize) -> Option<usize>,
        above: &[f64],
    ) {
        let width = self.l_ss.ncols();
        let tmp: Vec<f64> = self
            .pattern
            .iter()
            .map(|&row| locate(row).map_or_else(|| above[row], |i| loc[i]))
            .collect();
        let mut x = ColMut::from_slice_mut(&mut loc[at..at + width]);
        matmul(
            x.as_mut().as_mat_mut(),
            Accum::Add,
            self.l_ps.transpose(),
            faer::ColRef::from_slice(&tmp).as_mat(),
            -1.0,
            Par::Seq,
        );
        solve_upper_triangular_in_place(self.l_ss.transpose(), x.as_mat_mut(), Par::Seq);
    }
}

#[cfg(test)]
mod tests {
    use crate::linalg::factor::Analysis;
    use crate::linalg::ordering::nested_dissection;
    use crate::linalg::sparse::Pattern;

    /// The 7-point Laplacian of an m^3 grid plus the identity (SPD), both triangles stored.
    fn grid(m: usize) -> (Pattern, Vec<f64>, Vec<usize>, Vec<usize>) {
        let n = m * m * m;
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        let (mut xadj, mut adjncy) = (vec![0], Vec::new());
        for c in 0..n {
            let (i, j, k) = (c / (m * m), (c / m) % m, c % m);
            let mut rows = vec![(c, 7.0)];
            for (d, lim) in [(m * m, i), (m, j), (1, k)] {
                if lim > 0 {
                    rows.push((c - d, -1.0));
                }
                if lim + 1 < m {
                    rows.push((c + d, -1.0));
                }
            }
            rows.sort_by_key(|r| r.0);
            for &(r, v) in &rows {
                row_idx.push(r);
                values.push(v);
                if r != c {
                    adjncy.push(r);
                }
            }
            col_ptr.push(row_idx.len());
            xadj.push(adjncy.len());
        }
        let fwd = nested_dissection(&xadj, &adjncy).unwrap();
        let mut inv = vec![0; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        (
            Pattern {
                n,
                col_ptr,
                row_idx,
            },
            values,
            fwd,
            inv,
        )
    }

    /// Verification against faer's serial supernodal solve of the same factor: the same
    /// arithmetic in another order, so they agree to roundoff (1e-12 relative: the matrix's
    /// condition number is below 10 here); and the result is the same to the last bit on one
    /// thread as on two (the split depends on the structure only).
    #[test]
    fn verification_tree_solve_matches_the_serial_solve_and_ignores_the_thread_count() {
        let (pattern, values, fwd, inv) = grid(18);
        let analysis = Analysis::new(&pattern, &fwd, &inv).unwrap();
        let llt = analysis.llt(&pattern, &values).unwrap();
        let b: Vec<f64> = (0..pattern.n)
            .map(|i| ((i * 7919) % 101) as f64 - 50.0)
            .collect();
        let mut serial = b.clone();
        let n = serial.len();
        llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut serial, n, 1));
        let mut tree = b.clone();
        llt.solve_vec(&mut tree);
        let scale = serial.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let diff = serial
            .iter()
            .zip(&tree)
            .fold(0.0f64, |a, (s, t)| a.max((s - t).abs()));
        assert!(diff <= 1e-12 * scale, "difference {diff} of {scale}");
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut single = b.clone();
        one.install(|| llt.solve_vec(&mut single));
        assert_eq!(single, tree);
    }
}
