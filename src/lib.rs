//! linercav: piston-slap-induced cavitation risk of wet cylinder liners.
//!
//! The pipeline (docs/physics.md): scene -> mesh -> FE matrices -> modal bases
//! -> reduced engine model -> slap transient -> analysis -> cavitation risk -> reports.
//! This crate is the library ([`api`] is its front door, the commands included); the binary
//! (`src/main.rs`, `src/cli/`) parses arguments, prints and shows progress (the `cli`
//! feature's crates, which the library does not use).

pub mod analysis;
pub mod api;
pub mod cavitation;
pub mod coolant;
pub mod eigen;
pub mod error;
pub mod fem;
pub mod files;
pub mod linalg;
pub mod machine;
pub mod mesh;
pub mod piston;
pub mod reduce;
pub mod report;
pub mod scene;
pub mod text;
pub mod transient;
