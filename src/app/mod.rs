//! Commands of the command-line tool as library functions: each takes a request, returns a
//! serialisable report, and writes its files atomically.

pub mod cavitation;

pub mod export;
pub mod full_modes;
pub mod full_order;
pub mod modes;
pub mod progress;
pub mod rom;
pub mod rom_tradeoff;
pub mod simulate;
pub mod summary;
pub mod sweep;

pub use crate::api::{load_part, load_scene, LoadedPart, ModelInput};
