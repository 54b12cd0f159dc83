//! Building the engine ROM from a scene: meshes, interface fields, one liner reduction reused
//! for every modelled cylinder, the crankcase reduction, assembly, system modes, static
//! correction and preload.
//!
//! `inputs` (what the build reads, interface fields, rows), `build` (the reduction, assembly and
//! system phase), `model` (the stored ROM and its checks).

mod build;
mod inputs;
mod model;

pub use build::*;
pub use inputs::*;
pub use model::*;

/// Version of the ROM layout; part of the cache key (5: matrices stored as ndarray arrays;
/// 9: residual vectors and residual flexibility from the dropped modes' exact flexibility;
/// 10: a crankcase deck's guide bore reaching below the liner's bottom no longer replaced by
/// its deck bore, so an engine ROM built from such decks is not read again; 11: the build's
/// warnings kept in `RomInfo::warnings`; 12: a crankcase deck off the frame by less than its
/// mesh tolerance centred on the liners (`FoundInterfaces::crankcase_shift_xy`); 13: the
/// liner's wet surface ends at the deck plate's underside, which moves the coolant layer's
/// mass and the maps' rows).
pub const ROM_FORMAT: u32 = 13;
