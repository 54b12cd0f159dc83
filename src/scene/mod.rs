//! Scenes: one TOML file describes the engine, its parts, materials and solver settings.
//!
//! Loading goes text -> TOML tree -> `--set` overrides -> raw structs (serde, unknown keys
//! rejected) -> validated [`Scene`] in SI units. Every error names the file and the key.

pub mod budget;
pub mod design;
pub mod overrides;
pub mod raw;
pub mod sanity;
pub mod spec;
mod strict;

use crate::text::num;
use raw::RawScene;
use spec::Elastic;
use spec::ElementKind;
pub use spec::ThresholdSpec;
use spec::{CrankcaseGeometry, CrankcaseMeshing};
use spec::{LinerGeometry, LinerMeshing};
use std::path::{Path, PathBuf};

mod load;
mod model;
mod validate;
pub use validate::{CUTOFF_FACTOR_MAX, MAX_STATIC_KPA};

#[allow(unused_imports)]
use load::*;
pub use model::*;
use validate::*;

/// A scene that cannot be used, with the file and key at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Io {
        path: PathBuf,
        source: crate::files::ReadError,
    },
    #[error("{}: not valid TOML: {msg}", path.display())]
    Syntax { path: PathBuf, msg: String },
    #[error("{}: key '{key}': {msg}", path.display())]
    Field {
        path: PathBuf,
        key: String,
        msg: String,
    },
    #[error(transparent)]
    Override(#[from] overrides::OverrideError),
    /// Work beyond the machine or `[limits]` (see [`budget`]).
    #[error("{}: {msg}", path.display())]
    TooLarge { path: PathBuf, msg: String },
}
