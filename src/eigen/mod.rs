//! Generalised symmetric eigenproblem K phi = lambda M phi (lambda = omega^2) by ARPACK in
//! shift-invert mode, certified by residuals, M-orthonormality and a Sturm (inertia) count.

pub mod arpack;
pub mod certify;
pub mod dense_lanczos;
pub mod modal;
pub mod placement;
pub mod shift_invert;
pub mod subspace;
pub mod trial;

pub use shift_invert::{solve_modes, EigenError, EigenSettings, Modes};
