//! Linear algebra: the shared sparse K/M pattern, METIS ordering, faer factorisations, and the
//! dense vector kernels and small dense LU of the transient.

pub mod dense;
pub mod factor;
pub mod kernels;
pub mod lu;
pub mod ordering;
pub mod sparse;
pub mod spill;
pub mod touch;
pub mod tree_solve;
pub mod tripled;

/// Makes faer's dense operations that take no explicit parallelism (products by `*`, dense
/// Cholesky and eigen-decompositions) run on the calling thread, once per process. Their
/// parallel kernels sum in an order that depends on the number of threads, so a ROM built by a
/// 1-CPU scheduler task differed in the last bits from one built on 2 cores, and the slap
/// transient amplifies such bits into different peaks. The heavy kernels keep both cores with
/// an explicit, split-independent parallelism: the sparse factorisation (tree-parallel; the
/// same bits on 1 and 2 threads, checked) and the block solves and projections, parallel over
/// column blocks that each run serially. Called by every ROM build.
pub fn thread_count_invariant() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| faer::set_global_parallelism(faer::Par::Seq));
}
