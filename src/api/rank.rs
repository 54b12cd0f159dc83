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
        let r = runs.len();
        if let Some(stopped) = stop_rule(&open, r, (spent, next, budget), resolution) {
            let n = open.len();
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

/// Where pooling stops, or None to pool another realisation: with the undecided pairs `open`
/// after `r` realisations, `spent` seconds of the `budget` used and `next` the expected cost
/// of one more, the realisations left are R' = floor((budget - spent) / next), and pooling
/// them shrinks the scatter by sqrt(r / (r + R')) (the step error stays). It stops when no
/// pair is open, when R' < 1 (the budget), or when no open pair is decidable even with that
/// shrink (`Decision::decidable_with`: the step error keeps it open). Returns the user's
/// sentence.
fn stop_rule(
    open: &[&Decision],
    r: usize,
    (spent, next, budget): (f64, f64, f64),
    resolution: f64,
) -> Option<String> {
    let more = ((budget - spent) / next).floor().max(0.0);
    let shrink = (r as f64 / (r as f64 + more)).sqrt();
    let hopeless = open.iter().all(|d| !d.decidable_with(shrink, resolution));
    let n = open.len();
    if n == 0 {
        Some(format!(
            "every neighbour pair decided after {r} realisation(s), {spent:.0} s"
        ))
    } else if more < 1.0 {
        Some(format!(
            "{n} pair(s) undecided: the time budget transient.max_seconds = {budget:.0} s reached after {r} realisation(s), {spent:.0} s (the next takes about {next:.0} s)"
        ))
    } else if hopeless {
        let e = open.iter().map(|d| d.step_error).fold(0.0, f64::max);
        Some(format!(
            "{n} pair(s) undecided after {r} realisation(s), {spent:.0} s: their step error (up to {e:.0} m/s^2, the change from the step to half of it) keeps them open, which the realisations left in the time budget transient.max_seconds = {budget:.0} s cannot change; a finer transient.step_deg can"
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An undecided pair with difference `d`, scatter `s`, step error `e` and that error's own
    /// scatter `se` (u = sqrt(s^2 + e^2)).
    fn pair(d: f64, s: f64, e: f64, se: f64) -> Decision {
        Decision {
            upper: 1,
            lower: 2,
            difference: d,
            uncertainty: (s * s + e * e).sqrt(),
            scatter: s,
            step_error: e,
            step_error_scatter: se,
            verdict: Verdict::Undecided,
        }
    }

    /// Verification of the stop rule against hand-computed verdicts, independent of the
    /// machine's speed: at resolution 20 a pair D = 30, s = 20, e = 2 (2u = 40.2) pools on
    /// while the budget holds one more realisation (one more alone, shrink sqrt(1/2),
    /// separates it: 2u = 28.6 < 30), stops on the budget when it holds none, and a pair whose step error alone keeps it open
    /// (e = 20: 2u >= 40 > 30 at any shrink) stops the run at once, naming the step, unless
    /// that error is mostly its estimate's own noise (u(e) = 19.9) or another pair can still
    /// be decided.
    #[test]
    fn verification_rank_stop_rule_pools_until_decided_budget_or_step_error() {
        let res = 20.0;
        let noisy = pair(30.0, 20.0, 2.0, 0.0);
        let stepped = pair(30.0, 20.0, 20.0, 0.0);
        let noisy_step = pair(30.0, 20.0, 20.0, 19.9);
        // room for exactly one more: pool
        assert_eq!(stop_rule(&[&noisy], 1, (10.0, 10.0, 20.0), res), None);
        assert_eq!(
            stop_rule(&[&noisy, &stepped], 1, (10.0, 10.0, 100.0), res),
            None
        );
        assert_eq!(stop_rule(&[&noisy_step], 1, (10.0, 10.0, 100.0), res), None);
        // no room
        let text = stop_rule(&[&noisy], 1, (10.0, 10.0, 19.9), res).unwrap();
        assert!(text.starts_with("1 pair(s) undecided"), "{text}");
        assert!(
            text.contains("the time budget transient.max_seconds = 20 s"),
            "{text}"
        );
        // the step error
        let text = stop_rule(&[&stepped], 3, (10.0, 1.0, 1e6), res).unwrap();
        assert!(text.starts_with("1 pair(s) undecided"), "{text}");
        assert!(text.contains("a finer transient.step_deg can"), "{text}");
        assert!(text.contains("up to 20 m/s^2") && text.contains("after 3 realisation(s)"));
        // decided
        let text = stop_rule(&[], 2, (10.0, 10.0, 100.0), res).unwrap();
        assert!(
            text.starts_with("every neighbour pair decided after 2"),
            "{text}"
        );
    }
}
