//! Cavitation: coolant properties, the criteria and risk classes, and the calibration of the
//! acceleration criterion from rig data.

pub mod calibration;
pub mod criteria;
pub mod evaluate;
pub mod maps;

use crate::coolant::Coolant;
use crate::scene::CavitationSpec;
use criteria::Thresholds;

/// What the criteria need, resolved from the scene: the coolant's properties, the gap \[m\] and
/// the risk thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    pub coolant: Coolant,
    pub gap: f64,
    pub thresholds: Thresholds,
}

impl Setup {
    /// Resolves the scene's thresholds (module doc of [`criteria`]); the error says which
    /// threshold is out of order.
    pub fn new(spec: &CavitationSpec) -> Result<Self, criteria::ThresholdError> {
        Ok(Setup {
            coolant: spec.coolant,
            gap: spec.gap,
            thresholds: Thresholds::resolve(&spec.thresholds, &spec.coolant, spec.gap)?,
        })
    }
}
