//! The step-error tolerance control: halve the step and run again while the estimate exceeds
//! the tolerance.

#[allow(unused_imports)]
use super::*;

/// Runs the engine ([`EngineRun::run`]) and, while the estimated step error of the mean peak
/// exceeds `settings.tolerance`, halves the step and runs again, at most `max_refinements`
/// times; returns the last run (its `stats.step_refinements` says how often it was halved).
pub fn run_with_tolerance(
    setup: &EngineSetup<'_>,
    mut settings: CycleSettings,
    max_refinements: usize,
    mut on_step: impl FnMut(usize, usize) + Send,
) -> Result<CycleResult, TransientError> {
    let mut refinements = 0;
    loop {
        let mut r = EngineRun::new(setup, settings.clone()).run(&mut on_step)?;
        r.stats.step_refinements = refinements;
        let within = settings
            .tolerance
            .is_none_or(|tol| !settings.step_error || r.stats.step_error_estimate <= tol);
        if within || refinements >= max_refinements {
            return Ok(r);
        }
        settings.step_deg *= 0.5;
        refinements += 1;
    }
}
