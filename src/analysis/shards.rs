//! A sharded study's parts: what a shard of a batch-scheduler array job writes
//! (`part-I-of-N.json`: the scene and its BLAKE3, the overrides, the design, the tool version
//! and the shard's runs), and the checks that turn the parts back into the unsharded study's
//! runs: one study, every shard exactly once, each holding exactly its runs with the design's
//! values.

use super::study::RunLine;
use crate::scene::design::{Design, PartError, Shard};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Format tag of a shard's part file.
pub const PART_FORMAT: &str = "linercav-sweep-part 4";

/// A shard's part file.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Part {
    /// [`PART_FORMAT`].
    pub format: String,
    /// The tool's name and version that ran the shard.
    pub tool: String,
    /// The scene's path and the BLAKE3 hash of its text.
    pub scene: String,
    pub scene_blake3: String,
    /// BLAKE3 of what the study's scenes (the base design's and every run's) read beside their
    /// text (pressure curves, calibration, mesh decks; `api::sweep`). Absent from an older
    /// format's part, which its format refuses.
    #[serde(default)]
    pub inputs_blake3: String,
    /// The `--set` overrides of the study.
    pub sets: Vec<String>,
    pub design: Design,
    /// Which shard (I of N) this is.
    pub shard: Shard,
    /// The ROMs the shard used.
    pub roms: Vec<String>,
    /// Wall time of the shard \[s\].
    pub seconds: f64,
    /// The shard's runs: design runs k with k mod N = I - 1, in order.
    pub runs: Vec<PartRun>,
    /// BLAKE3 of the runs' JSON ([`runs_digest`]): a part whose results were edited, or
    /// damaged, after the shard wrote them is refused.
    pub runs_blake3: String,
}

/// The BLAKE3 hex digest of `runs` as compact JSON (floats in their shortest round-trip form,
/// so the digest of parsed runs equals the writer's).
pub fn runs_digest(runs: &[PartRun]) -> String {
    let text = serde_json::to_string(runs).expect("serialisable");
    blake3::hash(text.as_bytes()).to_hex().to_string()
}

/// One run of a part: its CSV and picture record, and its full results.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct PartRun {
    pub line: RunLine,
    pub run: serde_json::Value,
}

/// Parses the part file `path` (its `text`) and checks what it says of itself: format, shard
/// numbers, that it holds exactly its shard's runs of its design, k mod N = I - 1 (their
/// values are checked by [`assemble`], once every shard is there).
pub fn parse_part(path: &Path, text: &str) -> Result<Part, PartError> {
    let not_a_part = |reason: String| PartError::NotAPart {
        path: path.to_path_buf(),
        reason,
    };
    let part: Part = serde_json::from_str(text).map_err(|e| not_a_part(e.to_string()))?;
    if part.format != PART_FORMAT {
        return Err(not_a_part(format!(
            "format '{}', expected '{PART_FORMAT}'",
            part.format
        )));
    }
    let Shard { index, count } = part.shard;
    if count == 0 || index == 0 || index > count {
        return Err(not_a_part(format!("shard {index}/{count}")));
    }
    let total = part.design.len();
    let runs_problem = |problem: String| PartError::Runs {
        path: path.to_path_buf(),
        index,
        count,
        total,
        problem,
    };
    // k mod N = I - 1, in order, without listing the design's runs
    let expected = (index - 1..total).step_by(count);
    if part.runs.len() != part.shard.len(total)
        || !part.runs.iter().map(|r| r.line.index).eq(expected)
    {
        return Err(runs_problem(format!("it holds {} runs", part.runs.len())));
    }
    if runs_digest(&part.runs) != part.runs_blake3 {
        return Err(not_a_part(
            "its runs differ from what the shard wrote (their BLAKE3 is not runs_blake3): edited or damaged after the run; run the shard again".into(),
        ));
    }
    Ok(part)
}

/// Checks that `p` (from `path`) belongs to the study of `first` (from `first_path`): tool,
/// scene text, overrides, design and shard count.
pub fn same_study(path: &Path, p: &Part, first_path: &Path, first: &Part) -> Result<(), PartError> {
    let differ = |what: &'static str, theirs: String, ours: String| PartError::Differs {
        path: path.to_path_buf(),
        first: first_path.to_path_buf(),
        what,
        theirs,
        ours,
    };
    if p.tool != first.tool {
        return Err(differ("tool", p.tool.clone(), first.tool.clone()));
    }
    if p.scene_blake3 != first.scene_blake3 {
        return Err(differ(
            "scene text (BLAKE3)",
            p.scene_blake3.clone(),
            first.scene_blake3.clone(),
        ));
    }
    if p.inputs_blake3 != first.inputs_blake3 {
        return Err(differ(
            "files the study's scenes read (pressure curves, calibration, mesh decks; BLAKE3)",
            p.inputs_blake3.clone(),
            first.inputs_blake3.clone(),
        ));
    }
    if p.sets != first.sets {
        return Err(differ(
            "--set overrides",
            format!("'{}'", p.sets.join(" ")),
            format!("'{}'", first.sets.join(" ")),
        ));
    }
    if p.design != first.design {
        return Err(differ(
            "design",
            format!("'{}'", p.design.describe()),
            format!("'{}'", first.design.describe()),
        ));
    }
    if p.shard.count != first.shard.count {
        return Err(differ(
            "shard count",
            p.shard.count.to_string(),
            first.shard.count.to_string(),
        ));
    }
    Ok(())
}

/// The unsharded study's runs assembled from its parts, in design order.
pub struct Merged {
    pub lines: Vec<RunLine>,
    pub runs: Vec<serde_json::Value>,
    /// The ROMs the parts used, consecutive repeats removed.
    pub roms: Vec<String>,
}

/// Checks that the `parts` (each with the path it was read from; at least one) come from one
/// study ([`same_study`]), that every shard is there exactly once and that each run holds the
/// design's values, then puts the runs in design order.
pub fn assemble(parts: &[(PathBuf, Part)]) -> Result<Merged, PartError> {
    let (first_path, first) = &parts[0];
    let count = first.shard.count;
    let mut shard_seen: BTreeMap<usize, &Path> = BTreeMap::new();
    for (path, p) in parts {
        same_study(path, p, first_path, first)?;
        if let Some(other) = shard_seen.insert(p.shard.index, path) {
            return Err(PartError::Twice {
                path: path.clone(),
                index: p.shard.index,
                count,
                other: other.to_path_buf(),
            });
        }
    }
    if shard_seen.len() < count {
        let missing: Vec<String> = (1..=count)
            .filter(|i| !shard_seen.contains_key(i))
            .take(10)
            .map(|i| format!("{i}/{count}"))
            .collect();
        let more = count - shard_seen.len() - missing.len();
        let more = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        return Err(PartError::Missing(format!("{}{more}", missing.join(", "))));
    }
    // every shard holds its runs: the design's runs are as many as the parts hold
    let design_runs = first.design.runs();
    let mut lines: Vec<Option<(RunLine, serde_json::Value)>> = vec![None; design_runs.len()];
    for (path, p) in parts {
        for r in &p.runs {
            if r.line.values != design_runs[r.line.index] {
                return Err(PartError::Runs {
                    path: path.clone(),
                    index: p.shard.index,
                    count,
                    total: design_runs.len(),
                    problem: format!(
                        "run {} has the values {:?}, the design gives {:?}",
                        r.line.index, r.line.values, design_runs[r.line.index]
                    ),
                });
            }
            lines[r.line.index] = Some((r.line.clone(), r.run.clone()));
        }
    }
    let (lines, runs): (Vec<RunLine>, Vec<serde_json::Value>) = lines
        .into_iter()
        .map(|l| l.expect("every shard present"))
        .unzip();
    let mut roms: Vec<String> = parts.iter().flat_map(|(_, p)| p.roms.clone()).collect();
    roms.dedup();
    Ok(Merged { lines, runs, roms })
}
