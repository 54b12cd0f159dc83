//! Full-order reference window (placeholder while being written).

use crate::error::{Error, Result};

#[derive(Clone, Debug, serde::Serialize)]
pub struct WindowReport {
    pub rom_error_peak_negative: f64,
    pub speedup: f64,
}

pub fn compare(
    _scene: &crate::scene::Scene,
    _rom: &crate::reduce::rom::EngineRom,
    _piston: &crate::piston::Piston,
    _sim: &crate::scene::Simulation,
    _res: &crate::transient::cycle::CycleResult,
    _progress: &super::progress::Progress,
) -> Result<WindowReport> {
    Err(Error::Failure("--full-order is not available yet".into()))
}
