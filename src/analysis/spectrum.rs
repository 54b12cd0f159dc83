//! Windowed amplitude spectra: made by the transient stage, which averages them over the cycles
//! as it runs ([`crate::transient::spectrum`]); the analysis and report stages read them here.

pub use crate::transient::spectrum::*;
