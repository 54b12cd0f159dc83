//! Single-vector solves with a supernodal Cholesky factor on both cores, split along the
//! elimination tree.
//!
//! A single right-hand side is bound by reading the factor (each entry is used once), and
//! one core reads memory at about half the rate two do (8-10 against 16-19 GB/s measured on
//! the 2-core machine, on different days), so a solve that reads the factor from two threads at once runs up to twice
//! as fast. The elimination tree of a nested-dissection order makes that possible: the
//! subtrees below the top separators are independent.
//!
//! [`TreePlan`] splits the supernodal elimination tree into *tasks* (whole subtrees) and the
//! *top* (the separators above them), by taking the heaviest subtree apart at its root until
//! each task holds at most 1/16 (`TASKS`) of the factor's entries. The forward solve L y = b runs
//! the tasks in parallel, each on a local copy of its rows, gathering its updates of the top
//! rows, -sum L_ts y_s, in a buffer of its own; the rows and buffers are written back in task
//! order, then the top supernodes run in order. The backward solve L^T x = y runs the top in reverse order, then the tasks in
//! parallel (they only read the top rows). The top's supernodes, the separators of the first
//! few dissections (a fifth to two fifths of the factor's entries on the casting and the
//! liner), are each split in turn: their products L_ps y and L_ps^T x by halves of rows or
//! columns, their triangles L_ss recursively into [A 0; B C] where faer's triangular solve
//! splits them, with the product by B in halves (`lower_solve`, `lower_transposed_solve`),
//! the halves run by `rayon::join` (the tasks' supernodes use the same kernels, which
//! are faer's single call below the split sizes); every entry is still summed by faer's kernel in faer's
//! order, so the top gives the bits it gave on one core. The split depends on the factor's
//! structure only, and every sum runs in the same order on any number of threads, so the
//! result is the same to the last bit on 1 or 2 cores (the property the ROM builds rely on;
//! see [`super::thread_count_invariant`]).

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
    /// The top rows its supernodes update, ascending (the rows of its buffer added to x).
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
    /// one after the other); for each row of the top: its place among the top's rows.
    local: Vec<usize>,
    /// Rows of the top (the length of a task's buffer of updates to them).
    top_rows: usize,
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
        // the top's rows in order: their slots in the tasks' buffers
        let mut top_rows = 0;
        for &s in &top {
            for row in begin[s]..end[s] {
                local[row] = top_rows;
                top_rows += 1;
            }
        }
        Self {
            tasks,
            top,
            owner,
            local,
            top_rows,
        }
    }

    /// Solves L L^T x = b in place (x in the factor's order, `values` the factor L).
    pub fn solve(&self, sym: &SymbolicSupernodalCholesky<usize>, values: &[f64], x: &mut [f64]) {
        let node = |s: usize| Supernode::new(sym, values, s);
        let begin = sym.supernode_begin();
        // forward: the tasks on their local vectors, each gathering its updates of the top in
        // a buffer over the top's rows (a task's rows reach only its own rows and the top's)
        let done: Vec<(Vec<f64>, Vec<f64>)> = (0..self.tasks.len())
            .into_par_iter()
            .map(|t| {
                let task = &self.tasks[t];
                let mut loc = self.gather(t, x);
                let mut buffer = vec![0.0; self.top_rows];
                let mut tmp = Vec::new();
                for &s in &task.supernodes {
                    let (node, at) = (node(s), self.local[begin[s]]);
                    node.forward(&mut loc[at..at + node.width()], &mut tmp);
                    for (&row, &v) in node.pattern.iter().zip(&tmp) {
                        let target = if self.owner[row] == t as u32 {
                            &mut loc
                        } else {
                            &mut buffer
                        };
                        target[self.local[row]] -= v;
                    }
                }
                (loc, buffer)
            })
            .collect();
        for (t, (loc, buffer)) in done.iter().enumerate() {
            self.scatter(t, loc, x);
            for &row in &self.tasks[t].outside {
                x[row] += buffer[self.local[row]];
            }
        }
        // the top on the whole vector: every row it updates is in x
        let mut tmp = Vec::new();
        for &s in &self.top {
            let node = node(s);
            node.forward(&mut x[begin[s]..begin[s] + node.width()], &mut tmp);
            for (&row, &v) in node.pattern.iter().zip(&tmp) {
                x[row] -= v;
            }
        }

        // backward: the top, then the tasks reading the top's final values
        for &s in self.top.iter().rev() {
            let node = node(s);
            tmp.clear();
            tmp.extend(node.pattern.iter().map(|&row| x[row]));
            node.backward(&mut x[begin[s]..begin[s] + node.width()], &tmp);
        }
        let done: Vec<Vec<f64>> = (0..self.tasks.len())
            .into_par_iter()
            .map(|t| {
                let mut loc = self.gather(t, x);
                let mut tmp = Vec::new();
                for &s in self.tasks[t].supernodes.iter().rev() {
                    let (node, at) = (node(s), self.local[begin[s]]);
                    tmp.clear();
                    tmp.extend(node.pattern.iter().map(|&row| {
                        if self.owner[row] == t as u32 {
                            loc[self.local[row]]
                        } else {
                            x[row]
                        }
                    }));
                    node.backward(&mut loc[at..at + node.width()], &tmp);
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

    /// Columns of the supernode.
    fn width(&self) -> usize {
        self.l_ss.ncols()
    }

    /// Forward step: y_s = L_ss^-1 b_s in place (`y` holds b_s), and `tmp` = L_ps y_s, the
    /// amounts to subtract from the rows `pattern` below; the triangle and the product split
    /// on both cores where they are large ([`lower_solve`], [`mul_add`]: the top separators),
    /// faer's single call otherwise, with the same bits either way.
    fn forward(&self, y: &mut [f64], tmp: &mut Vec<f64>) {
        lower_solve(self.l_ss, y);
        tmp.clear();
        tmp.resize(self.pattern.len(), 0.0);
        mul_add(tmp, Accum::Replace, self.l_ps, y, 1.0);
    }

    /// Backward step: x_s = L_ss^-T (y_s - L_ps^T x_p) in place (`x` holds y_s), `above` the
    /// final x_p of the rows `pattern`; split as [`Supernode::forward`].
    fn backward(&self, x: &mut [f64], above: &[f64]) {
        mul_transposed_add(x, self.l_ps, above, -1.0);
        lower_transposed_solve(self.l_ss, x);
    }
}

/// A product is split while its block holds more than this many entries (256 kB: the
/// halves' `rayon::join` costs microseconds against their tens of microseconds of reading).
const SPLIT_ENTRIES: usize = 1 << 15;

/// A triangle is split while it is wider than this.
const SPLIT_WIDTH: usize = 128;

fn column(v: &[f64]) -> MatRef<'_, f64> {
    faer::ColRef::from_slice(v).as_mat()
}

fn column_mut(v: &mut [f64]) -> faer::MatMut<'_, f64> {
    ColMut::from_slice_mut(v).as_mat_mut()
}

/// y = alpha A x (`Accum::Replace`) or y += alpha A x (`Accum::Add`), A's rows split in
/// halves while the block is larger than [`SPLIT_ENTRIES`]: each row's sum is formed by one
/// call of faer's kernel as over the whole block, so the result does not depend on the split
/// or the number of threads.
fn mul_add(y: &mut [f64], accum: Accum, a: MatRef<'_, f64>, x: &[f64], alpha: f64) {
    let (m, k) = a.shape();
    if m * k <= SPLIT_ENTRIES || m < 2 {
        matmul(column_mut(y), accum, a, column(x), alpha, Par::Seq);
        return;
    }
    let h = m / 2;
    let (top, bottom) = a.split_at_row(h);
    let (y1, y2) = y.split_at_mut(h);
    rayon::join(
        || mul_add(y1, accum, top, x, alpha),
        || mul_add(y2, accum, bottom, x, alpha),
    );
}

/// y += alpha A^T x, A's columns (y's rows) split in halves as in [`mul_add`].
fn mul_transposed_add(y: &mut [f64], a: MatRef<'_, f64>, x: &[f64], alpha: f64) {
    let (m, k) = a.shape();
    if m * k <= SPLIT_ENTRIES || k < 2 {
        matmul(
            column_mut(y),
            Accum::Add,
            a.transpose(),
            column(x),
            alpha,
            Par::Seq,
        );
        return;
    }
    let h = k / 2;
    let (left, right) = a.split_at_col(h);
    let (y1, y2) = y.split_at_mut(h);
    rayon::join(
        || mul_transposed_add(y1, left, x, alpha),
        || mul_transposed_add(y2, right, x, alpha),
    );
}

/// Where faer's triangular solve splits a triangle of order n (its `block_size`): the first
/// block holds n minus n / 2 rounded up to a multiple of 16 (of 8, 4 for smaller n).
/// [`lower_solve`] and [`lower_transposed_solve`] split at the same place, so their sums run
/// as faer's do and a solve gives the bits it gave on one core.
fn faer_block(n: usize) -> usize {
    let half = n / 2;
    n - if n >= 32 {
        half.div_ceil(16) * 16
    } else if n >= 16 {
        half.div_ceil(8) * 8
    } else if n >= 8 {
        half.div_ceil(4) * 4
    } else {
        half
    }
}

/// y <- L^-1 y for a lower triangular L = [A 0; B C] (A of order h = [`faer_block`]):
/// A y_1 = b_1, then C y_2 = b_2 - B y_1, the product B y_1 split ([`mul_add`]); recursively
/// while wider than [`SPLIT_WIDTH`].
fn lower_solve(l: MatRef<'_, f64>, y: &mut [f64]) {
    let w = l.nrows();
    if w <= SPLIT_WIDTH {
        solve_lower_triangular_in_place(l, column_mut(y), Par::Seq);
        return;
    }
    let h = faer_block(w);
    let (y1, y2) = y.split_at_mut(h);
    lower_solve(l.submatrix(0, 0, h, h), y1);
    mul_add(y2, Accum::Add, l.submatrix(h, 0, w - h, h), y1, -1.0);
    lower_solve(l.submatrix(h, h, w - h, w - h), y2);
}

/// x <- L^-T x for L = [A 0; B C] with C of order h = [`faer_block`] (faer solves L^T from
/// its last row up): C^T x_2 = y_2, then A^T x_1 = y_1 - B^T x_2.
fn lower_transposed_solve(l: MatRef<'_, f64>, x: &mut [f64]) {
    let w = l.nrows();
    if w <= SPLIT_WIDTH {
        solve_upper_triangular_in_place(l.transpose(), column_mut(x), Par::Seq);
        return;
    }
    let h = w - faer_block(w);
    let (x1, x2) = x.split_at_mut(h);
    lower_transposed_solve(l.submatrix(h, h, w - h, w - h), x2);
    mul_transposed_add(x1, l.submatrix(h, 0, w - h, h), x2, -1.0);
    lower_transposed_solve(l.submatrix(0, 0, h, h), x1);
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
        let (pattern, values, fwd, inv) = grid(26);
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

    /// Verification that the top's split kernels do faer's arithmetic: the triangle split where
    /// faer's own recursion splits it, the products by halves of rows or columns, each result
    /// equal to the last bit to faer's serial kernel on the same block (so the tree solve gives
    /// the bits it gave with the top on one core), at orders below, at and well above the
    /// split width, odd and even.
    #[test]
    fn verification_split_top_kernels_give_faers_bits() {
        use super::*;
        let rows = 900;
        for w in [100usize, 129, 300, 701, 1500] {
            let l = faer::Mat::<f64>::from_fn(w, w, |i, j| match i.cmp(&j) {
                std::cmp::Ordering::Equal => 2.0 + (i % 7) as f64 * 0.1,
                std::cmp::Ordering::Greater => ((i * 31 + j * 17) % 13) as f64 * 0.01 - 0.06,
                std::cmp::Ordering::Less => 0.0,
            });
            let a = faer::Mat::<f64>::from_fn(rows, w, |i, j| {
                ((i * 7 + j * 3) % 11) as f64 * 0.013 - 0.07
            });
            let b: Vec<f64> = (0..w).map(|i| ((i * 13) % 17) as f64 - 8.0).collect();
            let c: Vec<f64> = (0..rows).map(|i| ((i * 5) % 9) as f64 - 4.0).collect();
            let (mut faer_y, mut y) = (b.clone(), b.clone());
            solve_lower_triangular_in_place(l.as_ref(), column_mut(&mut faer_y), Par::Seq);
            lower_solve(l.as_ref(), &mut y);
            assert_eq!(y, faer_y, "L^-1 b, order {w}");
            let (mut faer_x, mut x) = (b.clone(), b.clone());
            let lt = l.as_ref().transpose();
            solve_upper_triangular_in_place(lt, column_mut(&mut faer_x), Par::Seq);
            lower_transposed_solve(l.as_ref(), &mut x);
            assert_eq!(x, faer_x, "L^-T b, order {w}");
            for (accum, start, alpha) in [(Accum::Add, 0.5, -1.0), (Accum::Replace, 0.0, 1.0)] {
                let (mut faer_p, mut p) = (vec![start; rows], vec![start; rows]);
                let col = column(&b);
                matmul(
                    column_mut(&mut faer_p),
                    accum,
                    a.as_ref(),
                    col,
                    alpha,
                    Par::Seq,
                );
                mul_add(&mut p, accum, a.as_ref(), &b, alpha);
                assert_eq!(p, faer_p, "A b, {rows} x {w}, {accum:?}");
            }
            let (mut faer_q, mut q) = (b.clone(), b.clone());
            let at = a.as_ref().transpose();
            matmul(
                column_mut(&mut faer_q),
                Accum::Add,
                at,
                column(&c),
                -1.0,
                Par::Seq,
            );
            mul_transposed_add(&mut q, a.as_ref(), &c, -1.0);
            assert_eq!(q, faer_q, "A^T c, {rows} x {w}");
        }
    }
}
