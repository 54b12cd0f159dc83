//! The engine cycle's numerical settings and the engine it runs.

#[allow(unused_imports)]
use super::*;

/// Numerical settings of the transient.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CycleSettings {
    pub scheme: Scheme,
    /// Base step [deg crank angle].
    pub step_deg: f64,
    /// Cycles run from rest.
    pub cycles: usize,
    /// The last this many cycles are averaged (1: the last cycle alone).
    pub averaged_cycles: usize,
    /// Halve failing steps.
    pub adaptive: bool,
    pub max_halvings: usize,
    /// Modal damping ratio of every system mode.
    pub damping_ratio: f64,
    /// Largest allowed penetration \[m\].
    pub max_penetration: f64,
    pub max_newton: usize,
    /// Use system modes up to this frequency only \[Hz\] (None: all of the ROM).
    pub modes_below_hz: Option<f64>,
    /// Static correction (residual flexibility) at the contact.
    pub static_correction: bool,
    /// How the cylinders' contacts are coupled within a step.
    pub coupling: Coupling,
    /// Skip the predictor's products over the modes at slices that an energy bound proves
    /// apart ([`crate::transient::modal`]); the results are the same bit for bit (false: every slice's
    /// prediction is formed, for verification).
    pub bound_predictions: bool,
    /// Restore the damper impulse the steps miss at contact onsets
    /// ([`contact::onset_impulses`]; false: the plain lagged damper, first order, for
    /// verification).
    pub onset_correction: bool,
    /// Sub-steps per base step while a slap is resolved (1: none). A base step in which a
    /// cylinder side comes into contact (no slice touching before, one after) is not
    /// committed but re-taken as this many equal sub-steps, and so are the base steps within
    /// `slap_span_deg` after it ([`EngineRun::advance`]).
    pub slap_substeps: usize,
    /// How long after a contact onset the base steps are sub-stepped [deg crank angle].
    pub slap_span_deg: f64,
    /// Largest acceptable estimated relative step error of the mean peak
    /// ([`mean_step_error`]); above it [`run_with_tolerance`] halves the step (None: no
    /// control).
    pub tolerance: Option<f64>,
    /// Estimate the step error of each cylinder's firing slap ([`StepError`]; the window run
    /// at h and h/2 costs about 0.46 cycles of work per cylinder).
    pub step_error: bool,
    /// Accelerations at the analysis points are reported in the band of the ROM \[Hz\]: the sum
    /// over every integrated mode plus the quasi-static (residual) response to the contact
    /// forces, low-passed by a zero-phase FIR over the cycle
    /// ([`crate::transient::signal::low_pass`]; the ROM is accurate up to about half its cut-off, and
    /// the modes above the band are kept for the contact response, not as outputs). None: the
    /// unfiltered sum.
    pub output_band_hz: Option<f64>,
    /// Map the averaged cycles' peak negative acceleration over every liner's wet outer
    /// surface ([`SurfacePeaks`]; false: the analysis points only).
    pub surface_maps: bool,
}

/// Coupling of the cylinders within one implicit step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Coupling {
    /// All pistons and the structure in one implicit contact solve (the exact discrete
    /// equations; cost grows with the square of the contact slices in touch).
    Monolithic,
    /// One implicit contact solve per cylinder; what the other cylinders' new contact forces
    /// do to this cylinder's liner within the same step (through the structure's step
    /// compliance and residual flexibility) is taken from the previous step. The state after
    /// the step includes every force exactly; the lag is measured (`Stats::coupling_lag_m`).
    PerCylinder,
}

/// The engine for the transient.
pub struct EngineSetup<'a> {
    pub rom: &'a EngineRom,
    pub piston: &'a Piston,
    pub firing_order: &'a [usize],
    /// Crank speed [rad/s].
    pub omega: f64,
    /// Height of the liner top in the liner frame \[m\].
    pub liner_top: f64,
}
