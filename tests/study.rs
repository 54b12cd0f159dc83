//! Sharded sweeps, their merge and sampled designs end to end on the small test engine:
//! the merged outputs equal the unsharded ones, the scheduler's variables choose the shard,
//! parts of different studies or with runs missing are refused, a sample writes its
//! probabilities and sensitivities, and shards on an empty cache build the ROM once.

use std::path::Path;
mod common;
use common::{linercav, linercav_output};

const SCENE: &str = "tests/fixtures/engine_small.toml";
const GRID: [&str; 4] = [
    "--vary",
    "piston.clearance_um=60,100",
    "--vary",
    "piston.pin_offset_mm=-1,0,1",
];

fn sweep(extra: &[&str], out: &Path) -> (i32, String, String) {
    let mut args = vec!["sweep", SCENE];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().unwrap()]);
    linercav(&args)
}

/// `sweep-merge` of the part directories `parts` into `out`, refused (exit 2): its stderr.
fn refused_merge(parts: &[&Path], out: &Path) -> String {
    let mut args = vec!["sweep-merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap()]);
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 2, "{err}");
    err
}

/// sweep.json without what legitimately differs between runs of the same study: wall times
/// and the written file names.
fn json_without_timing(p: &Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    let o = v.as_object_mut().unwrap();
    o.remove("seconds");
    o.remove("files");
    for r in o["runs"].as_array_mut().unwrap() {
        r.as_object_mut().unwrap().remove("seconds");
    }
    v
}

#[test]
fn verification_merged_shards_equal_the_unsharded_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (full, parts, merged) = (
        dir.path().join("full"),
        dir.path().join("parts"),
        dir.path().join("merged"),
    );
    let (code, _, err) = sweep(&GRID, &full);
    assert_eq!(code, 0, "{err}");
    // 6 runs over 4 shards: shards of 2, 2, 1 and 1 runs
    for i in 1..=4 {
        let shard = format!("{i}/4");
        let mut args = GRID.to_vec();
        args.extend_from_slice(&["--shard", &shard]);
        let (code, out, err) = sweep(&args, &parts);
        assert_eq!(code, 0, "{err}");
        assert!(
            out.contains(&format!("part-0000{i}-of-00004.json")),
            "{out}"
        );
    }
    // merging before every part is there is refused, naming the missing shard
    let last = parts.join("part-00004-of-00004.json");
    let kept = std::fs::read(&last).unwrap();
    std::fs::remove_file(&last).unwrap();
    let (code, _, err) = linercav(&[
        "sweep-merge",
        parts.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("4/4 missing"), "{err}");
    assert!(!merged.exists(), "no output from a refused merge");
    std::fs::write(&last, kept).unwrap();
    let (code, _, err) = linercav(&[
        "sweep-merge",
        parts.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read_to_string(full.join("sweep.csv")).unwrap(),
        std::fs::read_to_string(merged.join("sweep.csv")).unwrap(),
        "CSV rows identical"
    );
    assert_eq!(
        json_without_timing(&full.join("sweep.json")),
        json_without_timing(&merged.join("sweep.json"))
    );
    for png in [
        "sweep_piston_clearance_um.png",
        "sweep_piston_pin_offset_mm.png",
    ] {
        assert!(merged.join(png).exists(), "{png}");
    }
}

#[test]
fn contract_parts_of_different_studies_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let mut one = GRID.to_vec();
    one.extend_from_slice(&["--shard", "1/2"]);
    assert_eq!(sweep(&one, &a).0, 0);
    // shard 2 of the same grid with another fixed override: not the same study
    let mut two = GRID.to_vec();
    two.extend_from_slice(&["--shard", "2/2", "--set", "operating.load=0.8"]);
    assert_eq!(sweep(&two, &b).0, 0);
    let err = refused_merge(&[&a, &b], &dir.path().join("m"));
    assert!(err.contains("--set overrides"), "{err}");
    // the same shard twice
    let (code, _, err) = linercav(&[
        "sweep-merge",
        a.to_str().unwrap(),
        a.join("part-00001-of-00002.json").to_str().unwrap(),
        "--out",
        dir.path().join("m").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("given twice"), "{err}");
    // forged parts: a shard number out of range, a run taken out
    let part = a.join("part-00001-of-00002.json");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&part).unwrap()).unwrap();
    // (regression, issue 40: an edited result was merged as if the shard had computed it)
    for (forge, needle) in [
        ("shard", "shard 5/2"),
        ("runs", "does not hold its runs"),
        ("result", "edited or damaged"),
    ] {
        let mut f = v.clone();
        if forge == "shard" {
            f["shard"]["index"] = 5.into();
        } else if forge == "runs" {
            f["runs"].as_array_mut().unwrap().pop();
        } else {
            // one peak of the run's record lowered by 10 %, as a hand edit would
            let v = &mut f["runs"][0]["line"]["cylinders"][0]["peak_negative_m_s2"][0];
            *v = (v.as_f64().unwrap() * 0.9).into();
        }
        let forged = dir.path().join(format!("forged-{forge}.json"));
        std::fs::write(&forged, serde_json::to_string(&f).unwrap()).unwrap();
        let (code, _, err) = linercav(&[
            "sweep-merge",
            forged.to_str().unwrap(),
            "--out",
            dir.path().join("m").to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{forge}: {err}");
        assert!(err.contains(needle), "{forge}: {err}");
    }
}

/// Regression: shards run on different pressure curves (the scene's text the same, the file it
/// reads changed between them) were merged as one study, and the merged trend was the curves'
/// difference; a part now carries a digest of the files its scenes read.
#[test]
fn regression_shards_on_different_input_files_are_not_merged() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("pressure.csv");
    let curve = |peak_bar: f64| -> String {
        let rows: String = (0..=720)
            .step_by(6)
            .map(|a| {
                let x = f64::from(a) - 370.0;
                format!("{a},{}\n", 1.0 + peak_bar * (-x * x / 800.0).exp())
            })
            .collect();
        format!("crank_angle_deg,pressure_bar\n{rows}")
    };
    let set = format!("operating.pressure_file=\"{}\"", csv.display());
    // shard `shard` of a two-cycle study with `design` (--vary / --set arguments) into `out`
    let shard_of = |design: &[&str], shard: &str, out: &Path| {
        let mut args = design.to_vec();
        args.extend([
            "--set",
            "transient.cycles=2",
            "--set",
            "transient.averaged_cycles=1",
        ]);
        args.extend(["--shard", shard]);
        let (code, _, err) = sweep(&args, out);
        assert_eq!(code, 0, "{err}");
    };
    let study = |shard: &str, out: &Path| {
        shard_of(
            &["--vary", "piston.clearance_um=60,100", "--set", &set],
            shard,
            out,
        )
    };
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    std::fs::write(&csv, curve(150.0)).unwrap();
    study("1/2", &a);
    std::fs::write(&csv, curve(60.0)).unwrap();
    study("2/2", &b);
    let err = refused_merge(&[&a, &b], &dir.path().join("m"));
    assert!(err.contains("files the study's scenes read"), "{err}");
    assert!(!dir.path().join("m").exists());
    // a design that varies the file: each shard runs one curve, and the other's file changing
    // between the shards was not seen (the digest held the base scene's files only)
    let (one, two) = (dir.path().join("one.csv"), dir.path().join("two.csv"));
    let vary = format!(
        "operating.pressure_file={},{}",
        one.display(),
        two.display()
    );
    let varied = |shard: &str, out: &Path| shard_of(&["--vary", &vary], shard, out);
    let (c, d) = (dir.path().join("c"), dir.path().join("d"));
    std::fs::write(&one, curve(150.0)).unwrap();
    std::fs::write(&two, curve(60.0)).unwrap();
    varied("1/2", &c);
    std::fs::write(&two, curve(90.0)).unwrap();
    varied("2/2", &d);
    let err = refused_merge(&[&c, &d], &dir.path().join("n"));
    assert!(err.contains("files the study's scenes read"), "{err}");
    // the same files again: the shards merge
    std::fs::write(&two, curve(60.0)).unwrap();
    let e = dir.path().join("e");
    varied("2/2", &e);
    let (code, _, err) = linercav(&[
        "sweep-merge",
        c.to_str().unwrap(),
        e.to_str().unwrap(),
        "--out",
        dir.path().join("n").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn contract_the_scheduler_chooses_the_shard() {
    let dir = tempfile::tempdir().unwrap();
    let run = |env: &[(&str, &str)], extra: &[&str], out: &Path| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_linercav"));
        c.args(["sweep", SCENE]).args(GRID).args(extra);
        c.args(["--out", out.to_str().unwrap()]);
        for k in [
            "SLURM_ARRAY_TASK_ID",
            "SLURM_ARRAY_TASK_MIN",
            "SLURM_ARRAY_TASK_MAX",
            "SLURM_ARRAY_TASK_COUNT",
            "SLURM_ARRAY_TASK_STEP",
            "JOB_COMPLETION_INDEX",
        ] {
            c.env_remove(k);
        }
        c.envs(env.iter().copied());
        let o = c.output().unwrap();
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    // --array=0-2 and --array=1-3: the same three shards
    for (lo, hi) in [("0", "2"), ("1", "3")] {
        let out = dir.path().join(format!("slurm{lo}"));
        let first: u32 = lo.parse().unwrap();
        for id in first..first + 3 {
            let id = id.to_string();
            let (code, err) = run(
                &[
                    ("SLURM_ARRAY_TASK_ID", &id),
                    ("SLURM_ARRAY_TASK_MIN", lo),
                    ("SLURM_ARRAY_TASK_MAX", hi),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                ],
                &[],
                &out,
            );
            assert_eq!(code, 0, "{err}");
        }
        for i in 1..=3 {
            assert!(out.join(format!("part-0000{i}-of-00003.json")).exists());
        }
    }
    // Kubernetes: the index with the count given; without the count, refused
    let k8s = dir.path().join("k8s");
    let (code, err) = run(&[("JOB_COMPLETION_INDEX", "1")], &["--shards", "2"], &k8s);
    assert_eq!(code, 0, "{err}");
    assert!(k8s.join("part-00002-of-00002.json").exists());
    let (code, err) = run(&[("JOB_COMPLETION_INDEX", "1")], &[], &k8s);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("JOB_COMPLETION_INDEX") && err.contains("--shards"),
        "{err}"
    );
}

#[test]
fn contract_a_sample_writes_probabilities_and_sensitivities() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lhs");
    let design = [
        "--sample",
        "lhs:24",
        "--range",
        "piston.clearance_um=40:120",
        "--range",
        "piston.pin_offset_mm=-1:1",
        "--seed",
        "3",
    ];
    let (code, _, err) = sweep(&design, &out);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("probabilities.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("cylinder,point,class,probability,ci_low,ci_high")
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    // 2 cylinders x 4 points x 3 classes; the classes of a point sum to one, each
    // probability inside its interval
    assert_eq!(rows.len(), 2 * 4 * 3);
    for point in rows.chunks(3) {
        let p: Vec<f64> = point.iter().map(|r| r[3].parse().unwrap()).collect();
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 2e-4, "{point:?}");
        for r in point {
            let (p, lo, hi): (f64, f64, f64) = (
                r[3].parse().unwrap(),
                r[4].parse().unwrap(),
                r[5].parse().unwrap(),
            );
            assert!(lo <= p && p <= hi && lo >= 0.0 && hi <= 1.0, "{r:?}");
        }
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let rho = json["sensitivities"]["spearman"].as_array().unwrap();
    assert_eq!(rho.len(), 2, "one row per key");
    assert!(out.join("sweep_statistics.png").exists());
    // the same seed gives the same runs (a shard elsewhere draws the same design)
    let again = dir.path().join("again");
    assert_eq!(sweep(&design, &again).0, 0);
    assert_eq!(
        std::fs::read_to_string(out.join("sweep.csv")).unwrap(),
        std::fs::read_to_string(again.join("sweep.csv")).unwrap()
    );
}

#[test]
fn contract_bad_designs_are_refused_before_any_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad");
    for (args, needle) in [
        (vec!["--sample", "lhs:10"], "--range"),
        (
            vec![
                "--sample",
                "lhs:10",
                "--range",
                "piston.clearance_um=120:40",
            ],
            "LO is not below HI",
        ),
        (
            vec![
                "--sample",
                "grid:10",
                "--range",
                "piston.clearance_um=40:120",
            ],
            "unknown method",
        ),
        (
            vec!["--sample", "mc:10", "--range", "piston.clearence_um=40:120"],
            "clearence_um",
        ),
        (
            vec!["--vary", "piston.clearance_um=60,100", "--shard", "3/2"],
            "--shard '3/2'",
        ),
        // regression: the same value twice ran the same point twice without a word, and a
        // range in --vary was "invalid type: string, expected f64" without a hint
        (
            vec!["--vary", "piston.clearance_um=60,60"],
            "the value '60' is given twice",
        ),
        (
            vec!["--vary", "piston.clearance_um=40:120"],
            "ranges belong to --sample",
        ),
    ] {
        let (code, _, err) = sweep(&args, &out);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.join("sweep.csv").exists());
    }
    let o = linercav_output(&[
        "sweep",
        SCENE,
        "--vary",
        "piston.clearance_um=60,100",
        "--shard",
        "1/2",
    ]);
    assert_eq!(o.status.code(), Some(2), "a shard without --out");
}

#[test]
fn contract_shards_starting_together_on_an_empty_cache_build_the_rom_once() {
    let dir = tempfile::tempdir().unwrap();
    let (cache, parts) = (dir.path().join("cache"), dir.path().join("parts"));
    let children: Vec<std::process::Child> = (1..=3)
        .map(|i| {
            std::process::Command::new(env!("CARGO_BIN_EXE_linercav"))
                .args(["sweep", SCENE])
                .args(GRID)
                .args(["--shard", &format!("{i}/3"), "--json"])
                .args(["--cache-dir", cache.to_str().unwrap()])
                .args(["--out", parts.to_str().unwrap()])
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut how = Vec::new();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        how.push(v["roms"][0].as_str().unwrap().to_string());
    }
    // one builder ("miss"); the others waited for it and loaded its entry (or, started after
    // it had finished, found it: "hit")
    assert_eq!(how.iter().filter(|h| *h == "miss").count(), 1, "{how:?}");
    assert!(
        how.iter()
            .all(|h| ["miss", "waited", "hit"].contains(&h.as_str())),
        "{how:?}"
    );
}
