//! The library's top-level error: every stage's typed error, classified for the exit code
//! (2 = bad input the user can fix, 1 = numerical or system failure).

use crate::fem::model::ModelError;
use crate::files::WriteError;
use crate::mesh::checks::MeshError;
use crate::mesh::collect::DeckError;
use crate::scene::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Msh(#[from] DeckError),
    #[error("{}: {source}", file.as_deref().unwrap_or("mesh"))]
    Mesh {
        file: Option<String>,
        #[source]
        source: MeshError,
    },
    /// A command-line argument the command cannot use: the flag (or "part", "scene") and why.
    #[error("{flag}: {msg}")]
    Argument { flag: String, msg: String },
    #[error(transparent)]
    Calibration(#[from] crate::cavitation::calibration::CalibrationError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Write(#[from] WriteError),
    /// One run of several (a sweep's, the report's) failed: which, and why.
    #[error("run {name}: {source}")]
    Run {
        name: String,
        #[source]
        source: Box<Error>,
    },
    /// A ROM built for shapes or a trade-off did not keep the bases it was asked to keep (a
    /// defect of the code, not of the input).
    #[error("the ROM build did not keep its bases")]
    NoBases,
    /// The full coupled reference's own Sturm check failed (a mode may be missing from the
    /// reference a comparison needs).
    #[error("{}: the full model's Sturm check failed (a mode may be missing)", path.display())]
    ReferenceUncertified { path: std::path::PathBuf },
    #[error(transparent)]
    Rom(#[from] crate::reduce::rom::RomError),
    #[error(transparent)]
    Cache(#[from] crate::reduce::cache::CacheReadError),
    #[error(transparent)]
    Modal(#[from] crate::eigen::modal::ModalError),
    #[error(transparent)]
    Design(#[from] crate::scene::design::DesignError),
    #[error(transparent)]
    Part(#[from] crate::scene::design::PartError),
    #[error(transparent)]
    SceneRom(#[from] crate::reduce::scene_rom::SceneRomError),
    #[error(transparent)]
    Verify(#[from] crate::transient::verify::VerifyError),
    #[error(transparent)]
    Piston(#[from] crate::piston::setup::PistonSetupError),
    #[error("{}: {source}", path.display())]
    Transient {
        path: std::path::PathBuf,
        #[source]
        source: crate::transient::error::TransientError,
    },
    #[error("cavitation thresholds: {0}")]
    Thresholds(#[from] crate::cavitation::criteria::ThresholdError),
    #[error(transparent)]
    Certification(#[from] crate::eigen::certify::CertificationError),
}

impl Error {
    /// 2 for input the user can correct, 1 for failures of the computation or the system.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Scene(_)
            | Error::Msh(_)
            | Error::Mesh { .. }
            | Error::Argument { .. }
            | Error::Calibration(_) => 2,
            // an output that cannot be written, a cache file that cannot be read: the user's
            // to fix (a path, a permission, a full disk)
            Error::Write(_)
            | Error::Cache(_)
            | Error::Thresholds(_)
            | Error::Design(_)
            | Error::Part(_)
            | Error::Piston(_) => 2,
            Error::Model(ModelError::Set(_)) | Error::Model(ModelError::NoDofs) => 2,
            Error::Modal(e) => e.exit_code(),
            Error::Rom(e) => e.exit_code(),
            Error::SceneRom(e) => e.exit_code(),
            Error::Verify(e) => e.exit_code(),
            Error::Run { source, .. } => source.exit_code(),
            Error::Model(_)
            | Error::NoBases
            | Error::ReferenceUncertified { .. }
            | Error::Transient { .. }
            | Error::Certification(_) => 1,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
