//! `linercav report`: the report of a scene. At this stage of the project it holds the
//! certified liner modes (`liner_modes.json`) and a `summary.md`; the engine ROM, slap
//! transient, spectra and cavitation sections join it as those stages land.

use super::modes::{self, ModesReport, ModesRequest};
use super::ModelInput;
use crate::error::{Error, Result};
use crate::report::atomic;
use std::path::Path;
use std::time::Instant;

/// Writes the report of `scene` into `out`; returns the liner modal result.
pub fn run(scene: &Path, sets: &[String], out: &Path, count: usize) -> Result<ModesReport> {
    let started = Instant::now();
    let req = ModesRequest {
        input: ModelInput::Scene {
            scene: scene.to_path_buf(),
            part: "liner".into(),
            sets: sets.to_vec(),
        },
        count,
        extra_fix: vec![],
        vtu: None,
        shift_hz: None,
    };
    let r = modes::run(&req, started)?;
    std::fs::create_dir_all(out).map_err(|e| {
        Error::Input(format!(
            "{}: cannot create the output directory: {e}",
            out.display()
        ))
    })?;
    let json = serde_json::to_string_pretty(&r).expect("serialisable");
    let md = format!(
        "# linercav report: {}\n\n## Liner modes (free-free)\n\n```\n{}```\n\nReproduce: `linercav report {} --out {}`\n",
        scene.display(),
        r.to_text().replace(&format!("{:.2} s", r.seconds), "(see liner_modes.json) s"),
        scene.display(),
        out.display()
    );
    atomic::write_all_atomic(vec![
        (
            out.join("liner_modes.json"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(json.as_bytes())),
        ),
        (
            out.join("summary.md"),
            Box::new(move |w: &mut dyn std::io::Write| w.write_all(md.as_bytes())),
        ),
    ])?;
    Ok(r)
}
