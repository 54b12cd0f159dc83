//! `sweep` and `sweep-merge`: what-if runs of a design ([`crate::scene::design`]: a Cartesian
//! grid or a Latin hypercube / Monte Carlo sample) in parallel on the cached ROM, on one
//! machine or split into shards of a batch scheduler's array job; a tidy CSV (one row per
//! run, cylinder and analysis point), the JSON and pictures; for a sample also the probability
//! of every risk class and the rank sensitivity of the peaks to every varied key.
//!
//! A shard writes `part-I-of-N.json` into its part directory: the scene (path and BLAKE3 of
//! its text), the overrides, the design, the tool version and its runs (their CSV rows as
//! text, what the pictures need, and the full results). `sweep-merge` checks that all parts
//! come from the same study and hold every run exactly once, then writes what the unsharded
//! sweep writes, from the same code: the CSV rows are identical.

use super::rom::CacheOptions;
use crate::analysis::shards::{
    assemble, parse_part, runs_digest, Merged, Part, PartRun, PART_FORMAT,
};
use crate::analysis::study::{statistics, worst_peak, ProbabilityRow, RunLine, Sensitivities};
use crate::api::Variants;
use crate::error::{Error, Result};
use crate::files::{write_all_atomic, write_atomic, Filler, OutputDir};
pub use crate::report::study::SweepRun;
use crate::report::study::{
    csv, draw_key, draw_statistics, label, line_of, numeric, probabilities_csv, sweep_run,
};
use crate::scene::design::{Design, PartError, Shard};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `sweep` and `sweep-merge` return.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepReport {
    pub scene: String,
    pub keys: Vec<String>,
    pub design: Design,
    /// Full results of every run, in design order.
    pub runs: Vec<serde_json::Value>,
    #[serde(skip)]
    pub lines: Vec<RunLine>,
    /// ROMs used (distinct reduction inputs) and whether each was a cache hit.
    pub roms: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub probabilities: Option<Vec<ProbabilityRow>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensitivities: Option<Sensitivities>,
    /// With `--refine`: where each quantity's largest value lies ([`Maximum`]), by quantity
    /// (`peak_slap_force_n`, `peak_negative_m_s2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maximum: Option<std::collections::BTreeMap<&'static str, Maximum>>,
    pub seconds: f64,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
}

pub struct SweepRequest {
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub vary: Vec<String>,
    pub sample: Option<String>,
    pub ranges: Vec<String>,
    pub seed: Option<u64>,
    /// `I/N`; None: from the scheduler's environment, else unsharded.
    pub shard: Option<String>,
    /// Number of shards for a Kubernetes Indexed Job (JOB_COMPLETION_INDEX).
    pub shards: Option<usize>,
    pub out: Option<PathBuf>,
    pub cache: CacheOptions,
    /// `KEY=LO:HI`: place `runs` runs of one key adaptively ([`crate::analysis::refine`]).
    pub refine: Option<String>,
    pub runs: Option<usize>,
}

/// The files `sweep --out` and `sweep-merge` write.
pub const OUTPUTS: &[&str] = &[
    "sweep.csv",
    "sweep.json",
    "sweep_*.png",
    "probabilities.csv",
];

/// The file name of shard `s`'s part.
fn part_name(s: Shard) -> String {
    format!("part-{:05}-of-{:05}.json", s.index, s.count)
}

/// Writes shard `s`'s part (its runs, the design and the scene's digest, with the runs'
/// BLAKE3 over them so that `sweep-merge` finds an edited part) to `path`, atomically.
fn write_part(
    path: &Path,
    report: &SweepReport,
    (req, s, (scene_text, inputs)): (&SweepRequest, Shard, (&[u8], String)),
    started: Instant,
) -> Result<()> {
    let part = Part {
        format: PART_FORMAT.into(),
        tool: tool_version(),
        scene: report.scene.clone(),
        scene_blake3: blake3::hash(scene_text).to_hex().to_string(),
        inputs_blake3: inputs,
        sets: req.sets.clone(),
        design: report.design.clone(),
        shard: s,
        roms: report.roms.clone(),
        seconds: started.elapsed().as_secs_f64(),
        runs: report
            .lines
            .iter()
            .cloned()
            .zip(report.runs.iter().cloned())
            .map(|(line, run)| PartRun { line, run })
            .collect(),
        runs_blake3: String::new(),
    };
    let part = Part {
        runs_blake3: runs_digest(&part.runs),
        ..part
    };
    let text = serde_json::to_string(&part).expect("serialisable");
    write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}

/// Runs the sweep, or its shard.
pub fn run(req: &SweepRequest, started: Instant) -> Result<SweepReport> {
    if let Some(spec) = &req.refine {
        return refine(req, spec, started);
    }
    if req.runs.is_some() {
        return Err(Error::Argument {
            flag: "--runs".into(),
            msg: "belongs to --refine KEY=LO:HI".into(),
        });
    }
    let design = Design::from_args(&req.vary, req.sample.as_deref(), &req.ranges, req.seed)?;
    design.check_fixed(&req.sets)?;
    check_shard_flags(req)?;
    let shard = match &req.shard {
        Some(s) => Some(Shard::parse("--shard", s)?),
        None => Shard::from_env(&crate::scene::design::scheduler_var, req.shards)?,
    };
    if shard.is_some() && req.out.is_none() {
        return Err(Error::Argument {
            flag: "--shard".into(),
            msg: "a shard writes its part into a directory: give --out PART_DIR".into(),
        });
    }
    // the size is checked before any list of the runs is made
    let total = design.len();
    // the design's runs and the base design's
    // (saturating: a design of usize::MAX runs wrapped to 0 and passed the check)
    check_size(req, shard.map_or(total, |s| s.len(total)).saturating_add(1))?;
    let indices: Vec<usize> = match shard {
        Some(s) => s.runs(total),
        None => (0..total).collect(),
    };
    if let Some(s) = shard.filter(|_| indices.is_empty()) {
        log::warn!(
            "shard {}/{} of a design of {total} runs has no runs of its own (more shards than runs)",
            s.index,
            s.count
        );
    }
    let scene_text =
        crate::files::read_regular(&req.scene, crate::files::LIMIT_TEXT).map_err(|source| {
            crate::scene::SceneError::Io {
                path: req.scene.clone(),
                source,
            }
        })?;
    // the part directory is shared by the shards (one file each, checked writable before
    // any run); a whole sweep's output directory is staged and renamed into place
    let (stage, part_dir) = match (&req.out, shard) {
        (Some(o), None) => (Some(OutputDir::create(o, OUTPUTS)?), None),
        (Some(o), Some(s)) => {
            crate::files::check_output_names(o, &[&part_name(s)])?;
            // made now, removed again (when still empty) if this shard fails or is stopped
            let made = crate::files::NewDirs::create(o)?;
            crate::files::check_writable(o)?;
            (None, Some(made))
        }
        _ => (None, None),
    };
    let all = design.runs();
    let (lines, runs, roms, inputs) = execute(req, &design, (&all, &indices), shard.is_some())?;
    let mut report = SweepReport {
        scene: req.scene.display().to_string(),
        keys: design.keys(),
        design,
        runs,
        lines,
        roms,
        shard,
        probabilities: None,
        sensitivities: None,
        maximum: None,
        seconds: 0.0,
        files: vec![],
    };
    if let (Some(s), Some(dir)) = (shard, &req.out) {
        let path = dir.join(part_name(s));
        let inputs = inputs.expect("a shard's digest");
        write_part(&path, &report, (req, s, (&scene_text, inputs)), started)?;
        if let Some(made) = part_dir {
            made.keep();
        }
        report.files = vec![path.display().to_string()];
    } else {
        add_statistics(&mut report);
        if let Some(stage) = stage {
            finish(&mut report, stage)?;
        }
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Writes the outputs of a whole sweep into the staged directory and moves it into place.
fn finish(report: &mut SweepReport, stage: OutputDir) -> Result<()> {
    let files = write_outputs(stage.path(), report)?;
    report.files = files
        .iter()
        .map(|f| stage.final_path(Path::new(f)).display().to_string())
        .collect();
    stage.commit()?;
    Ok(())
}

fn tool_version() -> String {
    format!("linercav {}", env!("CARGO_PKG_VERSION"))
}

/// BLAKE3 of what the study's scenes read beside their text: the thresholds (a calibration
/// file's values), pressure curves and mesh decks with their includes of the base design's
/// scene and, where the design varies a file-valued key (`*_file`: `--vary
/// liner.mesh_file=a.inp,b.inp`), of each distinct combination of the design's files (`keys`,
/// and every run's values `all`), each file once in the order found, so that shards run on
/// different files are not merged as one study.
fn inputs_digest(req: &SweepRequest, keys: &[String], all: &[Vec<String>]) -> Result<String> {
    let file_keys: Vec<usize> = (0..keys.len())
        .filter(|&i| keys[i].ends_with("_file"))
        .collect();
    let mut combos: Vec<Vec<String>> = vec![Vec::new()];
    for run in all {
        let c: Vec<String> = file_keys
            .iter()
            .map(|&i| format!("{}={}", keys[i], run[i]))
            .collect();
        if !combos.contains(&c) {
            combos.push(c);
        }
    }
    let (mut roots, mut thresholds) = (Vec::new(), Vec::new());
    let mut files: Vec<(PathBuf, &str)> = Vec::new();
    for c in combos {
        let sets: Vec<String> = req.sets.iter().chain(&c).cloned().collect();
        let s = super::load_scene(&req.scene, &sets)?;
        let t = format!("{:?}", s.cavitation.thresholds);
        if !thresholds.contains(&t) {
            thresholds.push(t);
        }
        for (root, key, deck) in scene_files(&s) {
            // a deck's includes are read once per distinct deck
            if roots.contains(&root) {
                continue;
            }
            roots.push(root.clone());
            let mut found = if deck {
                crate::mesh::deck_files(&root)
            } else {
                vec![root.clone()]
            };
            // an include that is not there is the deck reader's to report, with the file and
            // line that name it
            found.retain(|p| *p == root || p.exists());
            for f in found {
                if !files.iter().any(|(g, _)| *g == f) {
                    files.push((f, key));
                }
            }
        }
    }
    let mut h = blake3::Hasher::new();
    for t in &thresholds {
        h.update(t.as_bytes());
    }
    for (f, key) in &files {
        crate::files::hash_files(&mut h, std::slice::from_ref(f), crate::files::LIMIT_MESH)
            .map_err(|(path, source)| crate::scene::SceneError::Field {
                path: req.scene.clone(),
                key: key.to_string(),
                msg: format!(
                    "cannot read {} (a file of the study's runs): {source}",
                    path.display()
                ),
            })?;
    }
    Ok(h.finalize().to_hex().to_string())
}

/// The files scene `s` reads beside its text, each with the key that names it and whether it
/// is a mesh deck (whose includes it reads too): its pressure curve and its mesh decks.
fn scene_files(s: &Scene) -> Vec<(PathBuf, &'static str, bool)> {
    use crate::scene::{CrankcaseSource, MeshSource, PressureSource};
    let mut files = Vec::new();
    if let Some(PressureSource::File(p)) = s.simulation.as_ref().map(|m| &m.operating.pressure) {
        files.push((p.clone(), "operating.pressure_file", false));
    }
    if let MeshSource::File(p) = &s.liner.source {
        files.push((p.clone(), "liner.mesh_file", true));
    }
    if let Some(CrankcaseSource::File(p)) = s.crankcase.as_ref().map(|c| &c.source) {
        files.push((p.clone(), "crankcase.mesh_file", true));
    }
    files
}

/// The runs' lines, full results, ROMs used and, for a shard, [`inputs_digest`].
type Executed = (
    Vec<RunLine>,
    Vec<serde_json::Value>,
    Vec<String>,
    Option<String>,
);

/// Runs `indices` of the design's runs `all`: their lines, full results and the ROMs used, and
/// for a shard (`sharded`) the digest of the files the base design and the design's runs read.
fn execute(
    req: &SweepRequest,
    design: &Design,
    (all, indices): (&[Vec<String>], &[usize]),
    sharded: bool,
) -> Result<Executed> {
    let keys = design.keys();
    let sets_of = |k: usize| -> Vec<String> {
        keys.iter()
            .zip(&all[k])
            .map(|(key, x)| format!("{key}={x}"))
            .collect()
    };
    let extra: Vec<Vec<String>> = indices.iter().map(|&k| sets_of(k)).collect();
    // a shard checks the other shards' runs too, as the whole sweep would: a bad value (a
    // pressure file of NaN) stops every shard before its runs, not only the shard it is in
    if sharded {
        let own: std::collections::HashSet<usize> = indices.iter().copied().collect();
        let others = (0..all.len()).filter(|k| !own.contains(k)).map(sets_of);
        super::check_variants_load(&req.scene, &req.sets, others)?;
    }
    // the base design (the scene without the design's values) runs too, last: every run's
    // change is measured against it (each shard runs it: the runs are deterministic)
    let mut extra = extra;
    extra.push(Vec::new());
    // the files of the base design and of every run of the design (the other shards' too),
    // before any ROM is built
    let inputs = match sharded {
        true => Some(inputs_digest(req, &keys, all)?),
        false => None,
    };
    let rom_progress = super::rom::RomProgress::default();
    let variants = Variants::prepare(&req.scene, &req.sets, &extra, &req.cache, &|m| {
        rom_progress.phase(m)
    })?;
    let bar = super::progress::Progress::counter(indices.len() as u64 + 1);
    let mut labels: Vec<String> = indices.iter().map(|&k| label(&keys, &all[k])).collect();
    labels.push("the base design".into());
    let mut results = variants.run(&labels, false, || bar.inc())?;
    drop(bar);
    let (base_res, base_seconds) = results.pop().expect("the base design's run");
    let nb = indices.len();
    let base_values = vec!["(scene)".to_string(); keys.len()];
    let base = sweep_run(
        &variants.scenes[nb],
        &variants.roms[variants.rom_of[nb]].rom,
        &base_values,
        &base_res,
        base_seconds,
    )?;
    let mut lines = Vec::with_capacity(nb);
    let mut runs = Vec::with_capacity(nb);
    for (k, (sc, (res, seconds))) in indices.iter().zip(variants.scenes.iter().zip(results)) {
        let ri = variants.rom_of[lines.len()];
        let mut run = sweep_run(sc, &variants.roms[ri].rom, &all[*k], &res, seconds)?;
        run.set_changes(&base);
        lines.push(line_of(*k, &run));
        runs.push(serde_json::to_value(&run).expect("serialisable"));
    }
    Ok((
        lines,
        runs,
        variants.roms.iter().map(|r| r.cache.to_string()).collect(),
        inputs,
    ))
}

/// Refuses `--shards` beside `--shard I/N` (one count too many), `--shards 0` (no shard),
/// and `--shards` outside an Indexed Job (no JOB_COMPLETION_INDEX) or beside a Slurm array:
/// `--shards` belongs to an Indexed Job's environment.
fn check_shard_flags(req: &SweepRequest) -> Result<()> {
    match (&req.shard, req.shards) {
        (Some(_), Some(_)) => {
            return Err(Error::Argument {
                flag: "--shards".into(),
                msg: "give either --shard I/N or --shards N (with JOB_COMPLETION_INDEX), not both"
                    .into(),
            })
        }
        (None, Some(0)) => {
            return Err(Error::Argument {
                flag: "--shards 0".into(),
                msg: "must be at least 1".into(),
            })
        }
        _ => {}
    }
    // --shards counts an Indexed Job's shards: without its index every pod would run the
    // whole sweep, and a Slurm array gives the count itself (the flag was ignored)
    let set = |k: &str| std::env::var_os(k).is_some();
    if let (None, Some(n)) = (&req.shard, req.shards) {
        let msg = if set("SLURM_ARRAY_TASK_ID") {
            "a Slurm array gives the shard count itself: leave --shards out"
        } else if !set("JOB_COMPLETION_INDEX") {
            "needs JOB_COMPLETION_INDEX (a Kubernetes Indexed Job sets it); elsewhere give --shard I/N"
        } else {
            return Ok(());
        };
        return Err(Error::Argument {
            flag: format!("--shards {n}"),
            msg: msg.into(),
        });
    }
    Ok(())
}

/// Refuses, before any scene is loaded for each run, a sweep whose `runs` would take longer
/// than `limits.max_hours` on this machine: runs x the base scene's transient estimate /
/// cores.
fn check_size(req: &SweepRequest, runs: usize) -> Result<()> {
    let base = super::load_scene(&req.scene, &req.sets)?;
    let Some(one) = crate::scene::budget::transient(&base) else {
        return Ok(());
    };
    // the runs share rayon's threads (RAYON_NUM_THREADS where a scheduler sets it), as
    // `Variants`' estimate of the runs together counts them
    let cores = rayon::current_num_threads().max(1) as f64;
    let est = crate::scene::budget::Estimate {
        what: "the sweep",
        // runs in parallel, plus each run's scene and results held until the end (~50 kB)
        memory: one.memory * cores + runs as f64 * 50e3,
        seconds: runs as f64 * one.seconds / cores,
        keys: "the design (fewer values or runs, or more shards), transient.step_deg or transient.cycles",
        detail: format!("{runs} runs of {}", one.detail),
    };
    crate::scene::budget::Limits::of(&base).check(&base, &est)?;
    Ok(())
}

/// For a sampled design: the probability of every risk class at every point and the rank
/// sensitivities of the peaks to the keys ([`statistics`]).
fn add_statistics(report: &mut SweepReport) {
    if !report.design.is_sample() || report.lines.is_empty() {
        return;
    }
    let (rows, sens) = statistics(&report.keys, &report.lines);
    report.probabilities = Some(rows);
    report.sensitivities = Some(sens);
}

fn write_outputs(dir: &Path, report: &SweepReport) -> Result<Vec<String>> {
    let csv_text = csv(&report.keys, &report.lines);
    let json = serde_json::to_string_pretty(report).expect("serialisable");
    let mut files: Vec<(PathBuf, Filler<'_>)> = vec![
        (
            dir.join("sweep.csv"),
            Box::new(move |w| w.write_all(csv_text.as_bytes())),
        ),
        (
            dir.join("sweep.json"),
            Box::new(move |w| w.write_all(json.as_bytes())),
        ),
    ];
    if let Some(rows) = &report.probabilities {
        let text = probabilities_csv(rows);
        files.push((
            dir.join("probabilities.csv"),
            Box::new(move |w| w.write_all(text.as_bytes())),
        ));
    }
    let mut names: Vec<String> = files.iter().map(|f| f.0.display().to_string()).collect();
    // PNGs first (each atomic), then the tables: a failure leaves no table behind
    let mut pngs = Vec::new();
    for (j, key) in report.keys.iter().enumerate() {
        let values: std::collections::BTreeSet<&str> =
            report.lines.iter().map(|l| l.values[j].as_str()).collect();
        if values.len() < 2 || values.iter().any(|x| numeric(x).is_none()) {
            continue;
        }
        let p = dir.join(format!("sweep_{}.png", key.replace('.', "_")));
        draw_key(
            &p,
            &report.keys,
            &report.lines,
            report.design.is_sample(),
            j,
        )?;
        pngs.push(p.display().to_string());
    }
    if let (Some(rows), Some(sens)) = (&report.probabilities, &report.sensitivities) {
        let p = dir.join("sweep_statistics.png");
        draw_statistics(&p, rows, sens)?;
        pngs.push(p.display().to_string());
    }
    write_all_atomic(std::mem::take(&mut files))?;
    names.extend(pngs);
    Ok(names)
}

/// Part files named on the command line: directories (their `part-*.json`) or files.
fn part_files(inputs: &[PathBuf]) -> std::result::Result<Vec<PathBuf>, PartError> {
    let mut files = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| PartError::Read {
                    path: p.clone(),
                    reason: e.to_string(),
                })?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("part-") && n.ends_with(".json"))
                })
                .collect();
            if found.is_empty() {
                return Err(PartError::NoParts { path: p.clone() });
            }
            found.sort();
            files.extend(found);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

/// `sweep-merge`: reads the parts, checks and assembles them into the unsharded sweep's runs
/// ([`assemble`]: one study, every shard exactly once, each holding its runs), then writes the
/// outputs of the unsharded sweep into `out`.
pub fn merge(inputs: &[PathBuf], out: &Path, started: Instant) -> Result<SweepReport> {
    let files = part_files(inputs)?;
    let mut parts: Vec<(PathBuf, Part)> = Vec::new();
    for f in files {
        let text =
            crate::files::read_text(&f, crate::files::LIMIT_PART).map_err(|e| PartError::Read {
                path: f.clone(),
                reason: e.to_string(),
            })?;
        let p = parse_part(&f, &text)?;
        parts.push((f, p));
    }
    let Merged { lines, runs, roms } = assemble(&parts)?;
    // the output directory is staged once every part has been read and checked
    let stage = OutputDir::create(out, OUTPUTS)?;
    let first = &parts[0].1;
    let mut report = SweepReport {
        scene: first.scene.clone(),
        keys: first.design.keys(),
        design: first.design.clone(),
        runs,
        lines,
        roms,
        shard: None,
        probabilities: None,
        sensitivities: None,
        maximum: None,
        seconds: 0.0,
        files: vec![],
    };
    add_statistics(&mut report);
    finish(&mut report, stage)?;
    // the study's time: its shards' (which ran elsewhere, maybe at once) and the merge's
    let shards: f64 = parts.iter().map(|(_, p)| p.seconds).sum();
    report.seconds = shards + started.elapsed().as_secs_f64();
    Ok(report)
}

impl SweepReport {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = format!(
            "{} runs of {} in {:.1} s (ROM: {}){}\n",
            self.lines.len(),
            self.scene,
            self.seconds,
            self.roms.join(", "),
            self.shard
                .map(|s| format!(
                    ", shard {}/{} of {} runs",
                    s.index,
                    s.count,
                    self.design.len()
                ))
                .unwrap_or_default()
        );
        for (name, m) in self.maximum.iter().flatten() {
            let _ = writeln!(
                s,
                "  largest {name}: {} +- {} at {} = {} +- {}",
                crate::text::num(m.value),
                crate::text::num(m.value_se),
                self.keys.first().map_or("", String::as_str),
                crate::text::num(m.at),
                crate::text::num(m.uncertainty)
            );
        }
        let many = self.lines.len() > 40;
        for r in self.lines.iter().take(if many { 20 } else { usize::MAX }) {
            let _ = write!(s, "  {:<40}", label(&self.keys, &r.values));
            for (ci, c) in r.cylinders.iter().enumerate() {
                let _ = write!(
                    s,
                    " c{} {:>5.0}/{:>5.1}kN",
                    c.cylinder,
                    worst_peak(r, ci),
                    c.slap_force_n / 1e3
                );
            }
            let _ = writeln!(s);
        }
        if many {
            let _ = writeln!(
                s,
                "  ... ({} more runs in the outputs)",
                self.lines.len() - 20
            );
        }
        if let Some(rows) = &self.probabilities {
            let _ = writeln!(
                s,
                "probability of the high-risk class (worst point, 95 % interval):"
            );
            let cyls: std::collections::BTreeSet<usize> = rows.iter().map(|r| r.cylinder).collect();
            for c in cyls {
                if let Some(r) = rows
                    .iter()
                    .filter(|r| r.cylinder == c && r.class == "high")
                    .max_by(|a, b| a.p.probability.total_cmp(&b.p.probability))
                {
                    let _ = writeln!(
                        s,
                        "  cylinder {c} point {}: {:.3} [{:.3}, {:.3}]",
                        r.point, r.p.probability, r.p.ci_low, r.p.ci_high
                    );
                }
            }
        }
        for f in &self.files {
            let _ = writeln!(s, "wrote {f}");
        }
        s
    }
}

pub use crate::analysis::refine::Maximum;

/// The refined quantities of a run: the engine's largest mean slap force and largest mean peak
/// negative acceleration, each with the standard error of the cylinder or point holding it.
fn quantities(run: &SweepRun) -> Vec<(f64, f64)> {
    let slap = run
        .cylinders
        .iter()
        .map(|c| (c.peak_slap_force_n, c.slap_force_se_n))
        .fold((f64::MIN, 0.0), |m, x| if x.0 > m.0 { x } else { m });
    let acc = run
        .cylinders
        .iter()
        .flat_map(|c| c.points.iter())
        .map(|p| (p.peak_negative_m_s2, p.peak_negative_se_m_s2))
        .fold((f64::MIN, 0.0), |m, x| if x.0 > m.0 { x } else { m });
    vec![slap, acc]
}

/// Names of [`quantities`] in `sweep.json`'s `maximum`.
const REFINED: [&str; 2] = ["peak_slap_force_n", "peak_negative_m_s2"];

/// Refuses, before any run, a `--refine` key the refinement cannot place runs on: the scene
/// is read with the key at a value inside the range that is no whole number (0.382 of the way
/// from LO to HI), as the refinement's midpoints will be. A key of whole numbers (a count such
/// as `piston.slices`) is refused there, naming `--vary` for it, instead of after the first
/// runs.
fn refine_probe(req: &SweepRequest, range: &crate::scene::design::Range) -> Result<()> {
    // the scene's own faults are its own
    Scene::load(&req.scene, &req.sets)?;
    let probe = range.lo + (range.hi - range.lo) * 0.381_966;
    let mut sets = req.sets.clone();
    sets.push(format!("{}={probe}", range.key));
    match Scene::load(&req.scene, &sets) {
        Ok(_) => Ok(()),
        Err(e) => Err(Error::Argument {
            flag: "--refine".into(),
            msg: format!(
                "{}={}:{}: the refinement places runs between the ends (such as {probe}), \
                 which the scene refuses: {e} (a key of whole numbers takes --vary with its \
                 values instead)",
                range.key,
                crate::text::exact(range.lo),
                crate::text::exact(range.hi)
            ),
        }),
    }
}

/// The key, range and run count of `sweep --refine`, refused by flag when misused.
fn refine_args(req: &SweepRequest, spec: &str) -> Result<(crate::scene::design::Range, usize)> {
    if !req.vary.is_empty() || req.sample.is_some() || !req.ranges.is_empty() || req.seed.is_some()
    {
        return Err(Error::Argument {
            flag: "--refine".into(),
            msg: "refines one key on its own: no --vary, --sample, --range or --seed with it"
                .into(),
        });
    }
    if req.shard.is_some() || req.shards.is_some() {
        return Err(Error::Argument {
            flag: "--refine".into(),
            msg: "each round depends on the last: it cannot be sharded".into(),
        });
    }
    let range = crate::scene::design::parse_range(spec).map_err(|e| Error::Argument {
        flag: "--refine".into(),
        msg: e.to_string().replacen("--range", "", 1).trim().to_string(),
    })?;
    // values that f64 cannot tell apart from their neighbours' would be dropped as repeats
    // (`refine::next_unsampled`: closer than 1e-12 of the interval), and the sweep would
    // return fewer runs than asked
    if range.hi - range.lo < 1e-9 * range.lo.abs().max(range.hi.abs()).max(1.0) {
        return Err(Error::Argument {
            flag: "--refine".into(),
            msg: format!(
                "{}={}:{}: the interval is too narrow to place runs in (at least 1e-9 of its \
                 values' size)",
                range.key,
                crate::text::exact(range.lo),
                crate::text::exact(range.hi)
            ),
        });
    }
    refine_probe(req, &range)?;
    let runs = match req.runs {
        Some(n) if (3..=1000).contains(&n) => n,
        other => {
            return Err(Error::Argument {
                flag: "--runs".into(),
                msg: format!(
                    "{}: --refine needs --runs N with 3 <= N <= 1000",
                    other.map_or("missing".to_string(), |n| n.to_string())
                ),
            })
        }
    };
    Ok((range, runs))
}

/// The lines, JSON runs and ROMs used of refined runs (value, run, ROM cache), by value.
fn refined_rows(
    done: &[(f64, SweepRun, String)],
) -> (Vec<RunLine>, Vec<serde_json::Value>, Vec<String>) {
    let mut lines = Vec::with_capacity(done.len());
    let mut out_runs = Vec::with_capacity(done.len());
    let mut roms: Vec<String> = Vec::new();
    for (k, (_, run, rom)) in done.iter().enumerate() {
        lines.push(line_of(k, run));
        out_runs.push(serde_json::to_value(run).expect("serialisable"));
        if roms.last() != Some(rom) {
            roms.push(rom.clone());
        }
    }
    (lines, out_runs, roms)
}

/// `sweep --refine KEY=LO:HI --runs N`: N runs of one key placed adaptively (two at a time, one
/// per core), then the outputs of a one-key grid over the values run, each run's change against
/// the base design (run with the first batch) with its standard error and verdict, and each
/// quantity's located maximum. Not shardable (each round depends on the last).
fn refine(req: &SweepRequest, spec: &str, started: Instant) -> Result<SweepReport> {
    use crate::analysis::refine::{initial, located, next_unsampled, Sample};
    let (range, runs) = refine_args(req, spec)?;
    let grid = |values: Vec<String>| Design::Grid {
        vary: vec![crate::scene::design::Vary {
            key: range.key.clone(),
            values,
        }],
    };
    grid(vec![]).check_fixed(&req.sets)?;
    check_size(req, runs)?;
    let stage = req
        .out
        .as_ref()
        .map(|o| OutputDir::create(o, OUTPUTS))
        .transpose()?;
    let (lo, hi) = (range.lo, range.hi);
    let mut done: Vec<(f64, SweepRun, String)> = Vec::new();
    let mut samples: Vec<Sample> = Vec::new();
    let mut batch = initial(lo, hi, runs);
    let mut round = 0;
    let mut base: Option<SweepRun> = None;
    while !batch.is_empty() {
        let values: Vec<String> = batch.iter().map(|x| format!("{x}")).collect();
        let mut extra: Vec<Vec<String>> = values
            .iter()
            .map(|v| vec![format!("{}={v}", range.key)])
            .collect();
        let mut labels: Vec<String> = extra.iter().map(|e| e[0].clone()).collect();
        if base.is_none() {
            // the base design (the scene's own value) with the first batch: every run's
            // change is measured against it, as in a grid sweep
            extra.push(Vec::new());
            labels.push("the base design".into());
        }
        let variants = Variants::prepare(&req.scene, &req.sets, &extra, &req.cache, &|_| {})?;
        let mut results = variants.run(&labels, false, || {})?;
        if base.is_none() {
            let nb = batch.len();
            let (res, seconds) = results.pop().expect("the base design's run");
            let rom = &variants.roms[variants.rom_of[nb]].rom;
            let own = vec!["(scene)".to_string()];
            base = Some(sweep_run(&variants.scenes[nb], rom, &own, &res, seconds)?);
        }
        for (i, ((res, seconds), x)) in results.into_iter().zip(&batch).enumerate() {
            let ri = variants.rom_of[i];
            let run = sweep_run(
                &variants.scenes[i],
                &variants.roms[ri].rom,
                &values[i..=i],
                &res,
                seconds,
            )?;
            samples.push(Sample {
                x: *x,
                y: quantities(&run),
            });
            done.push((*x, run, variants.roms[ri].cache.to_string()));
        }
        batch.clear();
        while done.len() + batch.len() < runs && batch.len() < 2 {
            let Some(x) = next_unsampled(&samples, &batch, &mut round, (lo, hi), runs) else {
                break;
            };
            batch.push(x);
        }
    }
    done.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(base) = &base {
        for (_, run, _) in &mut done {
            run.set_changes(base);
        }
    }
    let (lines, out_runs, roms) = refined_rows(&done);
    let maxima = REFINED
        .iter()
        .enumerate()
        .filter_map(|(q, name)| located(&samples, q).map(|m| (*name, m)))
        .collect();
    let mut report = SweepReport {
        scene: req.scene.display().to_string(),
        keys: vec![range.key.clone()],
        design: grid(done.iter().map(|d| format!("{}", d.0)).collect()),
        runs: out_runs,
        lines,
        roms,
        shard: None,
        probabilities: None,
        sensitivities: None,
        maximum: Some(maxima),
        seconds: 0.0,
        files: vec![],
    };
    if let Some(stage) = stage {
        finish(&mut report, stage)?;
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}
