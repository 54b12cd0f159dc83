//! Isotropic linear-elastic material.
//!
//! Lame constants: lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)).
