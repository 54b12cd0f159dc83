//! Analysis of the transient: spectra, FRFs of the modal model, correlation of crankcase
//! mode-shape coefficients with per-cylinder risk.

pub mod correlation;
pub mod frf;
pub mod ranking;
pub mod refine;
pub mod shards;
pub mod spectrum;
pub mod study;
