//! Finite elements: reference shapes, quadrature, element matrices, assembly, constraints and
//! the static solve.

pub mod assembly;
pub mod dofs;
pub mod element;
pub mod fields;
pub mod material;
pub mod model;
pub mod quadrature;
pub mod shape;
pub mod statics;
pub mod surface;
