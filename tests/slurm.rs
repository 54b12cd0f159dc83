//! A sharded sweep through a real Slurm: the repository's `examples/slurm/submit.sh` chains
//! the component array job (liner and crankcase reduced as two tasks), the ROM job that
//! assembles the engine from them, a 3-task array job and the merge job on a single-node Slurm that
//! `scripts/slurm-local.sh` installs (Debian's slurmctld, slurmd and munge), configures and
//! starts; the merged `sweep.csv` must equal the unsharded sweep's byte for byte.
//!
//! The test changes nothing on the machine: it runs when asked (under CI, where `.ci/run`
//! starts the Slurm first, or with `LINERCAV_TEST_SLURM=1` after
//! `sudo bash scripts/slurm-local.sh start`), and then a missing Slurm fails it; otherwise it
//! is skipped with a message.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};
mod common;
use common::linercav;

const SCENE: &str = "tests/fixtures/engine_small.toml";
const DESIGN: [&str; 4] = [
    "--vary",
    "piston.clearance_um=60,100",
    "--vary",
    "piston.pin_offset_mm=-1,0,1",
];

fn node_state() -> Option<String> {
    let o = Command::new("sinfo")
        .args(["-h", "-N", "-o", "%t"])
        .output()
        .ok()?;
    let s = String::from_utf8_lossy(&o.stdout).trim().to_string();
    (o.status.success() && !s.is_empty()).then_some(s)
}

/// A Slurm that takes jobs (its node idle or mixed). The test never installs or starts one:
/// `.ci/run` does (`scripts/slurm-local.sh start`), and on a developer's machine so does that
/// script when run by hand.
fn slurm() -> Result<(), String> {
    match node_state() {
        Some(s) if s.starts_with("idle") || s.starts_with("mix") => Ok(()),
        Some(s) => Err(format!("the Slurm node is '{s}', not idle")),
        None => Err("sinfo finds no Slurm (start one: bash scripts/slurm-local.sh start)".into()),
    }
}

/// Asked for: under CI (`CI` set) or with `LINERCAV_TEST_SLURM=1`.
fn asked() -> bool {
    std::env::var_os("CI").is_some() || std::env::var("LINERCAV_TEST_SLURM").is_ok_and(|v| v == "1")
}

/// Waits for job `id` to finish: its final JobState (a pending job whose dependency can never
/// be met counts as finished).
fn wait_for(id: &str, limit: Duration) -> String {
    let t = Instant::now();
    loop {
        let o = Command::new("scontrol")
            .args(["show", "job", id])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let field = |k: &str| {
            text.split_whitespace()
                .find_map(|w| w.strip_prefix(k))
                .unwrap_or("")
                .to_string()
        };
        let state = field("JobState=");
        if [
            "COMPLETED",
            "FAILED",
            "CANCELLED",
            "TIMEOUT",
            "NODE_FAIL",
            "OUT_OF_MEMORY",
        ]
        .contains(&state.as_str())
            || field("Reason=") == "DependencyNeverSatisfied"
        {
            return format!("{state} ({})", field("Reason="));
        }
        assert!(
            t.elapsed() < limit,
            "job {id} still {state} after {limit:?}"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
}

#[test]
fn validation_sharded_sweep_through_real_slurm_equals_the_unsharded_sweep() {
    if !asked() {
        eprintln!("skipped: runs under CI or with LINERCAV_TEST_SLURM=1 (and a running Slurm)");
        return;
    }
    if let Err(why) = slurm() {
        panic!("this test needs a running Slurm: {why}");
    }
    // under /tmp: the jobs run as root on this node and must reach the binary and the files
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    let mut args = vec!["sweep", SCENE];
    args.extend_from_slice(&DESIGN);
    args.extend_from_slice(&["--out", full.to_str().unwrap()]);
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");

    let merged = dir.path().join("merged");
    let o = Command::new("bash")
        .arg("examples/slurm/submit.sh")
        .arg(SCENE)
        .arg(&merged)
        .args(DESIGN)
        .env("SHARDS", "3")
        .env("CPUS", "1")
        .env("LINERCAV", env!("CARGO_BIN_EXE_linercav"))
        .output()
        .unwrap();
    let ids = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "submit: {ids} {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let ids: Vec<&str> = ids.split_whitespace().collect();
    assert_eq!(
        ids.len(),
        4,
        "component, ROM, array and merge job ids: {ids:?}"
    );
    let state = wait_for(ids[3], Duration::from_secs(600));
    let logs = dir.path().join("merged.work/logs");
    let log_text = || {
        std::fs::read_dir(&logs)
            .map(|d| {
                d.filter_map(|e| e.ok())
                    .map(|e| {
                        format!(
                            "== {}\n{}",
                            e.path().display(),
                            std::fs::read_to_string(e.path()).unwrap_or_default()
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("\n")
            })
            .unwrap_or_default()
    };
    assert!(
        state.starts_with("COMPLETED"),
        "merge job {state}\n{}",
        log_text()
    );
    // the components were reduced by their tasks and the ROM job assembled the engine from
    // the component cache
    let cache = dir.path().join("merged.work/cache");
    for part in ["liner", "crankcase"] {
        let found = std::fs::read_dir(&cache).unwrap().any(|e| {
            e.unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with(&format!("part-{part}-"))
        });
        assert!(
            found,
            "no {part} component in {}\n{}",
            cache.display(),
            log_text()
        );
    }
    let rom_log = log_text();
    assert!(
        rom_log.contains("component 1/2 (liner)") && rom_log.contains("component 2/2 (crankcase)"),
        "{rom_log}"
    );
    assert_eq!(
        rom_log.matches("from the component cache").count(),
        2,
        "the ROM job must find both components cached\n{rom_log}"
    );
    // three shards, two runs each
    for i in 1..=3 {
        let part = dir
            .path()
            .join(format!("merged.work/parts/part-0000{i}-of-00003.json"));
        assert!(part.exists(), "{}", part.display());
    }
    assert_eq!(
        std::fs::read_to_string(full.join("sweep.csv")).unwrap(),
        std::fs::read_to_string(merged.join("sweep.csv")).unwrap(),
        "merged CSV equals the unsharded one"
    );
    assert!(Path::new(&merged.join("sweep_piston_clearance_um.png")).exists());
}
