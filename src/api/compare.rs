//! The report's runs with another skirt model (`report.compare_lubrication`): the scene and
//! every value of its clearance and pin-offset sweeps run again with
//! `piston.lubrication` set to that model, on the ROMs already loaded (the skirt does not
//! enter the reduction).

use super::rom::CacheOptions;
use super::{evaluate_scene, Swept, Variants};
use crate::error::Result;
use crate::report::comparison::SkirtComparison;
use crate::report::figures::SweepPoint;
use crate::scene::spec::Lubrication;
use crate::scene::Scene;
use crate::transient::cycle::CycleResult;
use std::path::Path;

/// The scene's run, its evaluation and its sweeps' points under its own skirt model.
pub struct SceneSide<'a> {
    pub base: &'a CycleResult,
    pub evaluation: &'a crate::cavitation::evaluate::Evaluation,
    pub clearance: &'a [SweepPoint],
    pub pin_offset: &'a [SweepPoint],
}

/// The overrides of one comparison run: the other model, and those of the sweep point it
/// repeats (none for the scene's own run).
fn comparison_sets(other: Lubrication, swept: Swept) -> Vec<String> {
    let mut sets = vec![format!("piston.lubrication={}", other.name())];
    sets.extend(swept.sets());
    sets
}

/// Runs the comparison of `scene` (from `path` with `sets`) with the skirt model `other` on
/// `variants`' ROMs, in parallel: the scene, then each sweep value other than the scene's
/// own (that point is the scene's run). Returns the variants (their ROMs kept) and the
/// comparison, each sweep point's change set against the scene model's at the same value.
pub fn compare_skirts(
    variants: Variants,
    scene: &Scene,
    (path, sets): (&Path, &[String]),
    cache: &CacheOptions,
    other: Lubrication,
    side: &SceneSide<'_>,
) -> Result<(Variants, SkirtComparison)> {
    // per job: the sweep (0 clearance, 1 pin offset) and the point's index, None: the scene
    let mut jobs: Vec<Option<(usize, usize)>> = vec![None];
    let mut extra = vec![comparison_sets(other, Swept::Scene)];
    let sweeps = [side.clearance, side.pin_offset];
    let swept = |s: usize, v: f64| match s {
        0 => Swept::Clearance(v),
        _ => Swept::PinOffset(v),
    };
    for (s, pts) in sweeps.into_iter().enumerate() {
        // the scene's own point (no change against itself) is the scene's run
        for (i, p) in pts.iter().enumerate().filter(|(_, p)| p.change.is_some()) {
            jobs.push(Some((s, i)));
            extra.push(comparison_sets(other, swept(s, p.value)));
        }
    }
    let names: Vec<String> = extra.iter().map(|e| e.join(" ")).collect();
    let variants = variants.then(path, sets, &extra, cache, &|_| {})?;
    let results: Vec<CycleResult> = variants
        .run(&names, false, || {})?
        .into_iter()
        .map(|(r, _)| r)
        .collect();
    let other_scene = &variants.scenes[0];
    let rom = &variants.roms[variants.rom_of[0]].rom;
    let evaluation = evaluate_scene(other_scene, rom, &results[0])?;
    let point = |s: usize, i: usize| -> SweepPoint {
        let own = [side.clearance, side.pin_offset][s];
        let k = jobs.iter().position(|j| *j == Some((s, i)));
        let mut p = SweepPoint::of(own[i].value, k.map_or(&results[0], |k| &results[k]));
        p.set_change(&own[i]);
        p
    };
    let sweeps = (
        (0..side.clearance.len()).map(|i| point(0, i)).collect(),
        (0..side.pin_offset.len()).map(|i| point(1, i)).collect(),
    );
    let models = [model_of(scene), other];
    let comparison = SkirtComparison::new(
        models,
        [side.base, &results[0]],
        [side.evaluation, &evaluation],
        sweeps,
    );
    Ok((variants, comparison))
}

/// The skirt model `report.compare_lubrication` asks to compare with, refused (exit 2, naming
/// the key) when it is the scene's own.
pub fn checked_request(scene: &Scene) -> Result<Option<Lubrication>> {
    let Some(other) = scene.report.compare_lubrication else {
        return Ok(None);
    };
    let own = model_of(scene);
    if other == own {
        return Err(crate::scene::SceneError::Field {
            path: scene.path.clone(),
            key: "report.compare_lubrication".into(),
            msg: format!(
                "\"{}\" is the scene's own piston.lubrication; expected another of \"dry\", \"squeeze\", \"mixed\"",
                own.name()
            ),
        }
        .into());
    }
    Ok(Some(other))
}

/// The skirt model a scene runs.
pub fn model_of(scene: &Scene) -> Lubrication {
    scene
        .simulation
        .as_ref()
        .map_or(Lubrication::Dry, |s| s.piston.lubrication())
}
