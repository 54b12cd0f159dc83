//! Decided rankings (`simulate --rank`, `report`): realisations of the scene's run and its
//! whole-run step check, pooled until every neighbour pair of cylinders is separated or tied
//! at the resolution, within the scene's time budget (`transient.max_seconds`).
//!
//! A realisation repeats the run with the damping ratio perturbed by r 1e-6 (relative): the
//! slap history decorrelates (the cycles are chaotic) while the physics stays the same to
//! that level, so realisations are independent draws of the same statistics
//! (`benches/realisations.sh` checks the reported standard errors against their spread).
//! Pooling shrinks both the cycles' scatter and the scatter of the step check's estimate,
//! which is what left every neighbour pair of the default engine tied.

use super::{Error, Result};
use crate::analysis::ranking::{
    decide, estimates, rank_of, DecidedRanking, Decision, PeakEstimate, Verdict, PERTURBATION,
    RESOLUTION,
};
use crate::piston::Piston;
use crate::reduce::rom::EngineRom;
use crate::scene::Scene;
use crate::transient::cycle::CycleResult;
use crate::transient::engine::{run_cycle, run_half_step, settings_of};
use std::time::Instant;

/// The first realisation (the scene's run `base` and its half-step check `half`), `spent`
/// seconds of the budget already used and `next` the expected cost of another realisation,
/// and as many more as an undecided pair needs and the scene's
/// `transient.max_seconds` allows (the next expected to take as long as the last); it stops
/// early when no undecided pair could be decided even with the scatter of every realisation
/// the budget allows (the step error then keeps them open). `phase` hears each realisation.
pub fn decided_ranking(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    first: (&CycleResult, &CycleResult),
    (spent, next): (f64, f64),
    phase: &dyn Fn(&str),
) -> Result<DecidedRanking> {
    let sim = crate::piston::setup::simulation(scene)?;
    let budget = sim.transient.max_seconds;
    let (base, half) = first;
    let cylinders: Vec<usize> = base.peaks.iter().map(|c| c.cylinder).collect();
    let step_deg = base.stats.dt_s * scene.engine.speed_rpm * 6.0;
    let mut runs = vec![estimates(base, half)];
    let (mut spent, mut next) = (spent, next);
    loop {
        let (order, resolution) = rank_of(&runs, &cylinders);
        let ranked: Vec<(usize, PeakEstimate)> = order
            .iter()
            .map(|w| (w.cylinder, w.peak_negative))
            .collect();
        let pairs = decide(&ranked, resolution);
        let open: Vec<&Decision> = pairs
            .iter()
            .filter(|d| d.verdict == Verdict::Undecided)
            .collect();
        // what the realisations the budget still allows could do: the scatter shrinks as
        // 1 / sqrt(R), the step error does not
        let r = runs.len();
        let more = ((budget - spent) / next).floor().max(0.0);
        let shrink = (r as f64 / (r as f64 + more)).sqrt();
        let hopeless = open.iter().all(|d| !d.decidable_with(shrink, resolution));
        if open.is_empty() || more < 1.0 || hopeless {
            let n = open.len();
            let stopped = if n == 0 {
                format!("every neighbour pair decided after {r} realisation(s), {spent:.0} s")
            } else if more < 1.0 {
                format!(
                    "{n} pair(s) undecided: the time budget transient.max_seconds = {budget:.0} s reached after {r} realisation(s), {spent:.0} s (the next takes about {next:.0} s)"
                )
            } else {
                let e = open.iter().map(|d| d.step_error).fold(0.0, f64::max);
                format!(
                    "{n} pair(s) undecided after {r} realisation(s), {spent:.0} s: their step error (up to {e:.0} m/s^2, the change from the step to half of it) keeps them open, which the realisations left in the time budget transient.max_seconds = {budget:.0} s cannot change; a finer transient.step_deg can"
                )
            };
            return Ok(DecidedRanking {
                order,
                pairs,
                resolution_fraction: RESOLUTION,
                resolution_m_s2: resolution,
                realisations: r,
                cycles_averaged: r * base.stats.cycles_averaged,
                seconds: spent,
                max_seconds: budget,
                decided: n == 0,
                stopped,
            });
        }
        let open = open.len();
        phase(&format!(
            "ranking: realisation {} ({open} pair(s) undecided)",
            r + 1
        ));
        let t = Instant::now();
        let mut settings = settings_of(sim, scene.rom.band_hz);
        settings.damping_ratio *= 1.0 + PERTURBATION * r as f64;
        settings.step_deg = step_deg;
        settings.tolerance = None;
        let transient = |source| Error::Transient {
            path: scene.path.clone(),
            source,
        };
        // the run and its check side by side (each deterministic on its own)
        let (b, h) = rayon::join(
            || run_cycle(scene, rom, piston, settings.clone(), |_, _| {}),
            || run_half_step(scene, rom, piston, settings.clone(), step_deg, |_, _| {}),
        );
        runs.push(estimates(&b.map_err(transient)?, &h.map_err(transient)?));
        let took = t.elapsed().as_secs_f64();
        spent += took;
        next = took;
    }
}
