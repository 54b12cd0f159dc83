//! Model reduction: Craig-Bampton per part with interface fields, the assembled engine ROM,
//! and its on-disk cache.

pub mod cache;
pub mod craig_bampton;
pub mod engine;
pub mod full;
pub mod interface;
pub mod part_cache;
pub mod rom;
pub mod scene_rom;
pub mod substructure;
