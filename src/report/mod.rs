//! Output writers: Matrix Market, VTU mode shapes, PNG charts and the report's figures.

pub mod figures;
pub mod mtx;
pub mod png;
pub mod study;
pub mod vtu;
