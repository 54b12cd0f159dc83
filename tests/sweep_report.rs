//! `sweep` and `report` end to end on the small test engine (2 cylinders, cached ROM in
//! tests/fixtures): the tidy CSV's shape and columns, the PNG set, and bad input refused
//! without output.

use std::path::Path;
mod common;
use common::linercav;

const SCENE: &str = "tests/fixtures/engine_small.toml";

/// The verdict a change `d` with standard error `s` must carry (`Change::of`: two standard
/// errors, two-sided).
fn change_verdict(d: f64, s: f64) -> &'static str {
    if d < -2.0 * s {
        "lower"
    } else if d > 2.0 * s {
        "higher"
    } else {
        "not distinguishable"
    }
}

fn is_png(p: &Path) -> bool {
    std::fs::read(p)
        .map(|b| b.len() > 1000 && &b[1..4] == b"PNG")
        .unwrap_or(false)
}

#[test]
fn contract_sweep_writes_the_cartesian_product_as_a_tidy_csv() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sw");
    let (code, _, err) = linercav(&[
        "sweep",
        SCENE,
        "--vary",
        "piston.clearance_um=60,100",
        "--vary",
        "piston.pin_offset_mm=0,1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..6],
        &[
            "piston.clearance_um",
            "piston.pin_offset_mm",
            "cylinder",
            "point",
            "peak_negative_m_s2",
            "peak_slap_force_n"
        ]
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    // 2 x 2 runs, 2 cylinders, 4 points
    assert_eq!(rows.len(), 4 * 2 * 4);
    let combos: std::collections::BTreeSet<(String, String)> =
        rows.iter().map(|r| (r[0].clone(), r[1].clone())).collect();
    assert_eq!(combos.len(), 4);
    for r in &rows {
        let a: f64 = r[4].parse().unwrap();
        assert!(a.is_finite() && a >= 0.0);
    }
    // the same run as `simulate` gives the same peaks (no hidden differences in the sweep path)
    let (code, sim, err) = linercav(&[
        "simulate",
        SCENE,
        "--set",
        "piston.clearance_um=100",
        "--set",
        "piston.pin_offset_mm=1",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&sim).unwrap();
    let c1p1 = v["cylinders"][0]["points"][0]["peak_negative_m_s2"]
        .as_f64()
        .unwrap();
    let row = rows
        .iter()
        .find(|r| r[0] == "100" && r[1] == "1" && r[3] == "1")
        .unwrap();
    let swept: f64 = row[4].parse().unwrap();
    assert!(
        (swept - c1p1).abs() <= 1e-3 * c1p1.max(1.0),
        "{swept} vs {c1p1}"
    );
    assert!(is_png(&out.join("sweep_piston_clearance_um.png")));
    assert!(is_png(&out.join("sweep_piston_pin_offset_mm.png")));
}

#[test]
fn contract_sweep_refuses_bad_keys_and_values_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sw");
    for (vary, needle) in [
        ("piston.clearance_um", "expected KEY=V1,V2"),
        ("piston.clearence_um=40,80", "clearence_um"),
        ("piston.clearance_um=40,-5", "clearance_um"),
    ] {
        let (code, _, err) = linercav(&[
            "sweep",
            SCENE,
            "--vary",
            vary,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{vary}: {err}");
        assert!(err.contains(needle), "{vary}: {err}");
        assert!(!out.join("sweep.csv").exists());
    }
}

#[test]
fn contract_report_writes_the_figure_set() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let (code, _, err) = linercav(&["report", SCENE, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "pressure.png",
        "acceleration.png",
        "spectra.png",
        "peaks.png",
        "modes_risk.png",
        "sweep_clearance.png",
        "sweep_pin_offset.png",
        "criteria.png",
        "speed_error.png",
        "frf.png",
        "liner_maps.png",
    ] {
        assert!(is_png(&out.join(f)), "{f}");
    }
    // the liner maps for ParaView: every field named, one value per surface node, and the
    // largest mean peak of each map at least its worst analysis point's (the points are
    // surface nodes)
    let vtu = std::fs::read_to_string(out.join("liner_maps.vtu")).unwrap();
    let points: usize = vtu
        .split("NumberOfPoints=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    for name in [
        "peak_negative_m_s2",
        "peak_negative_se_m_s2",
        "ca",
        "ca_se",
        "cavitating_fraction",
        "cavitating_fraction_se",
        "cylinder",
    ] {
        let body = vtu
            .split(&format!("Name=\"{name}\" format=\"ascii\">"))
            .nth(1)
            .unwrap_or_else(|| panic!("field {name}"));
        let values = body.split("</DataArray>").next().unwrap();
        assert_eq!(values.split_whitespace().count(), points, "{name}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let maps = json["liner_maps"].as_array().unwrap();
    assert_eq!(maps.len(), 2);
    for (m, c) in maps
        .iter()
        .zip(json["evaluation"]["cylinders"].as_array().unwrap())
    {
        let worst = c["peak_negative_m_s2"].as_f64().unwrap();
        assert!(
            m["peak_negative_m_s2"].as_f64().unwrap() >= worst * (1.0 - 1e-9),
            "{m}"
        );
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["evaluation"]["cylinders"].as_array().unwrap().len(), 2);
    // each sweep: the scene's own run (in the range) and eight more, at distinct values in the
    // range, ascending; each maximum located at one of them, within the range
    for (key, range) in [("clearance", (40.0, 120.0)), ("pin_offset", (-1.0, 1.0))] {
        let values: Vec<f64> = v[format!("{key}_sweep")]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["value"].as_f64().unwrap())
            .collect();
        assert_eq!(
            values.len(),
            linercav::api::REPORT_SWEEP_RUNS,
            "{key}: {values:?}"
        );
        assert!(values.windows(2).all(|w| w[1] > w[0]), "{key}: {values:?}");
        assert!(values[0] >= range.0 && *values.last().unwrap() <= range.1);
        for q in ["peak_slap_force_n", "peak_negative_m_s2"] {
            let m = &v[format!("{key}_maximum")][q];
            let at = m["at"].as_f64().unwrap();
            assert!(values.contains(&at), "{key} {q}: {m}");
            assert!(m["uncertainty"].as_f64().unwrap() > 0.0, "{key} {q}: {m}");
        }
    }
    // no skirt comparison unless the scene asks (`report.compare_lubrication`)
    assert!(v.get("skirt_comparison").is_none());
    assert!(!out.join("skirt_comparison.png").exists());
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(
        md.contains("The largest mean slap force over the pin offset sweep (-1.000 to 1.000 mm)"),
        "{md}"
    );
    assert!(md.contains("## Verdict") && md.contains("![peaks.png](peaks.png)"));
    // the report runs the whole-run step check and says so
    assert!(v["simulate"]["step_check"]["step_deg"].as_f64().unwrap() > 0.0);
    assert!(md.contains("Whole-run step check"), "{md}");
}

/// `simulate --check-step` adds the whole-run step check: the step of the repeated run is half
/// the run's, every point carries the repeated run's mean and standard error, and the text
/// output prints the check; without the flag none of it appears.
#[test]
fn contract_simulate_check_step_adds_the_half_step_run() {
    let args = ["simulate", SCENE, "--set", "transient.cycles=2", "--json"];
    let (code, plain, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");
    let plain: serde_json::Value = serde_json::from_str(&plain).unwrap();
    assert!(plain.get("step_check").is_none());
    assert!(plain["cylinders"][0]["points"][0]
        .get("peak_negative_half_step_m_s2")
        .is_none());
    // without the check the numerical uncertainty is the firing-slap estimate, and says so
    assert_eq!(plain["numerical_uncertainty_scope"], "firing_slaps");
    for c in plain["cylinders"].as_array().unwrap() {
        for p in c["points"].as_array().unwrap() {
            assert_eq!(
                p["peak_negative_numerical_uncertainty_m_s2"], p["peak_negative_step_error_m_s2"],
                "{p}"
            );
        }
    }
    let (code, checked, err) = linercav(&[&args[..], &["--check-step"]].concat());
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&checked).unwrap();
    let step = v["stats"]["dt_s"].as_f64().unwrap() * v["speed_rpm"].as_f64().unwrap() * 6.0;
    let half = v["step_check"]["step_deg"].as_f64().unwrap();
    assert!((half - step / 2.0).abs() < 1e-9, "{half} vs {step}");
    // the same run as without the check
    assert_eq!(
        v["cylinders"][0]["points"][0]["peak_negative_m_s2"],
        plain["cylinders"][0]["points"][0]["peak_negative_m_s2"]
    );
    for c in v["cylinders"].as_array().unwrap() {
        for p in c["points"].as_array().unwrap() {
            assert!(
                p["peak_negative_half_step_m_s2"].as_f64().unwrap() > 0.0,
                "{p}"
            );
            assert!(
                p["peak_negative_half_step_se_m_s2"].as_f64().unwrap() >= 0.0,
                "{p}"
            );
            // with it: the larger of the firing-slap estimate and 2 |P_h - P_h/2|
            let num = |k: &str| p[k].as_f64().unwrap();
            let run = 2.0 * (num("peak_negative_m_s2") - num("peak_negative_half_step_m_s2")).abs();
            let expected = run.max(num("peak_negative_step_error_m_s2"));
            assert_eq!(
                num("peak_negative_numerical_uncertainty_m_s2"),
                expected,
                "{p}"
            );
        }
    }
    assert_eq!(v["numerical_uncertainty_scope"], "whole_run");
    let (code, text, err) = linercav(&[
        "simulate",
        SCENE,
        "--set",
        "transient.cycles=2",
        "--check-step",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("whole-run step check"), "{text}");
}

/// `simulate --out` writes the last cycle's time series: one row per step of the 720 deg
/// cycle, per cylinder the liner points' and the facing jacket wall's accelerations, and
/// columns that agree with the JSON: with two averaged cycles the last cycle's most negative
/// acceleration at a point is one of the two cycle peaks, i.e. the largest (`_max`) or
/// 2 mean - max (to the CSV's 3 decimals), and the side-force column peaks at the JSON's value.
#[test]
fn contract_simulate_time_series_agrees_with_its_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let (code, stdout, err) = linercav(&[
        "simulate",
        SCENE,
        "--set",
        "transient.cycles=3",
        "--set",
        "transient.averaged_cycles=2",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let text = std::fs::read_to_string(out.join("time_series.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2880, "720 deg at 0.25 deg");
    let col = |name: &str| -> Vec<f64> {
        let j = header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("column {name} in {header:?}"));
        rows.iter().map(|r| r[j]).collect()
    };
    for c in json["cylinders"].as_array().unwrap() {
        let k = c["cylinder"].as_u64().unwrap();
        for p in c["points"].as_array().unwrap() {
            let n = p["point"].as_u64().unwrap();
            // the cycle's peak lies between the samples: the parabola's vertex through the
            // CSV's most negative sample and its neighbours (the same rule on the same series)
            let acc = col(&format!("c{k}_p{n}_acc_m_s2"));
            let min = -linercav::transient::signal::sampled_peak(&acc, 0..acc.len(), -1.0)
                .expect("a series")
                .0;
            let mean = p["peak_negative_m_s2"].as_f64().unwrap();
            let max = p["peak_negative_max_m_s2"].as_f64().unwrap();
            let other = 2.0 * mean - max;
            assert!(
                (-min - max).abs() < 2e-3 || (-min - other).abs() < 2e-3,
                "cylinder {k} point {n}: last cycle {} against cycle peaks {max} and {other}",
                -min
            );
            let wall = col(&format!("c{k}_p{n}_wall_acc_m_s2"));
            assert!(wall.iter().all(|a| a.is_finite()) && wall.iter().any(|a| *a != 0.0));
        }
        let side = col(&format!("c{k}_side_force_n"))
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max);
        let expected = c["peak_side_force_n"].as_f64().unwrap();
        assert!(
            (side - expected).abs() < 0.01,
            "side force {side} vs {expected}"
        );
    }
}

/// Each run's change against the base design (the scene as given): a run whose values are the
/// scene's own is the same deterministic run, so its change is exactly 0 at every point; with
/// several cycles every row carries the change's standard error sqrt(se_run^2 + se_base^2) >=
/// the run's own SE, and its verdict follows the 2-SE rule; with one cycle the standard error
/// is unknown and said so.
#[test]
fn verification_sweep_changes_against_the_base_design() {
    // the small engine averages one cycle; then again with three of four averaged
    for one_cycle in [true, false] {
        changes_against_the_base(one_cycle);
    }
}

fn changes_against_the_base(one_cycle: bool) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sw");
    let mut args = vec![
        "sweep",
        SCENE,
        "--vary",
        "piston.clearance_um=40,80",
        "--out",
        out.to_str().unwrap(),
    ];
    if !one_cycle {
        args.extend_from_slice(&[
            "--set",
            "transient.cycles=4",
            "--set",
            "transient.averaged_cycles=3",
        ]);
    }
    // 80 um is the small engine's own clearance
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("column {name} in {header:?}"))
    };
    let (se, change, change_se, verdict) = (
        col("peak_negative_se_m_s2"),
        col("change_m_s2"),
        col("change_se_m_s2"),
        col("change"),
    );
    col("peak_negative_numerical_uncertainty_m_s2");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 2 * 4);
    for r in &rows {
        let d: f64 = r[change].parse().unwrap();
        if r[0] == "80" {
            assert_eq!(d, 0.0, "the scene's own run against itself: {r:?}");
        }
        if one_cycle {
            // a single cycle's standard error is unknown, not zero
            assert_eq!((r[change_se], r[verdict]), ("", "unknown (one cycle)"));
            continue;
        }
        let s: f64 = r[change_se].parse().unwrap();
        let own: f64 = r[se].parse().unwrap();
        assert!(s >= own - 1e-3, "{r:?}");
        assert_eq!(r[verdict], change_verdict(d, s), "{r:?}");
    }
}

/// Regression (session 75's hostile sweep): a grid over `rom.cylinders` (`[]` and `[2]`)
/// panicked drawing its picture (exit 101, nothing written: the plot took every run to model
/// the first run's cylinders), in the other order it drew cylinder 1's values as cylinder 2's,
/// and a run of cylinder 2 alone was compared with the base design's cylinder 1. Now exit 0,
/// the picture written, and every row's change is its peak less the base design's peak of the
/// same cylinder and point (the base: the scene's own run, all cylinders at 80 um).
#[test]
fn regression_a_sweep_over_the_modelled_cylinders_compares_like_cylinders() {
    let dir = tempfile::tempdir().unwrap();
    for (k, order) in ["[2],[]", "[],[2]"].into_iter().enumerate() {
        let out = dir.path().join(format!("sw{k}"));
        let vary = format!("rom.cylinders={order}");
        let args = [
            "sweep",
            SCENE,
            "--vary",
            &vary,
            "--vary",
            "piston.clearance_um=40,80",
            "--out",
            out.to_str().unwrap(),
        ];
        let (code, _, err) = linercav(&args);
        assert_eq!(code, 0, "{order}: {err}");
        assert!(is_png(&out.join("sweep_piston_clearance_um.png")));
        let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
        let rows: Vec<Vec<String>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        // columns: rom.cylinders, clearance, cylinder, point, peak_negative_m_s2, ...
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let change = header.iter().position(|h| *h == "change_m_s2").unwrap();
        let base = |cyl: &str, point: &str| -> f64 {
            let r = rows
                .iter()
                .find(|r| r[0] == "[]" && r[1] == "80" && r[2] == cyl && r[3] == point)
                .expect("the base design's row");
            r[4].parse().unwrap()
        };
        let alone: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == "[2]").collect();
        assert!(
            !alone.is_empty() && alone.iter().all(|r| r[2] == "2"),
            "{alone:?}"
        );
        for r in &rows {
            let peak: f64 = r[4].parse().unwrap();
            let d: f64 = r[change].parse().unwrap();
            // the CSV carries 3 decimals of each
            assert!(
                (d - (peak - base(&r[2], &r[3]))).abs() < 2e-3,
                "{order}: {r:?}"
            );
        }
    }
}

/// `sweep --refine KEY=LO:HI --runs N` (issue 38): N distinct runs within [LO, HI], written as a
/// one-key grid; sweep.json's `maximum` names, for the largest slap force and the largest peak
/// acceleration, the run that holds it (checked against the runs' own records) with a location
/// uncertainty of half the larger spacing to its neighbours; every run carries its change
/// against the base design with a verdict. Misused, it is refused by flag.
#[test]
fn contract_sweep_refine_places_its_runs_and_locates_the_maxima() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("refine");
    let (code, _, err) = linercav(&[
        "sweep",
        SCENE,
        "--refine",
        "piston.pin_offset_mm=-1:1",
        "--runs",
        "7",
        "--set",
        "transient.cycles=3",
        "--set",
        "transient.averaged_cycles=2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let xs: Vec<f64> = v["design"]["vary"][0]["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().parse().unwrap())
        .collect();
    assert_eq!(xs.len(), 7);
    assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
    assert!(xs.iter().all(|x| (-1.0..=1.0).contains(x)), "{xs:?}");
    let runs = v["runs"].as_array().unwrap();
    // each run's change against the base design (the scene's 0 mm), per cylinder and point,
    // with its standard error and the verdict of the grid sweep's rule; the run at 0 mm is
    // the base itself
    for (r, x) in runs.iter().zip(&xs) {
        let changes = r["changes"].as_array().unwrap();
        assert_eq!(changes.len(), r["cylinders"].as_array().unwrap().len());
        for (c, cyl) in changes.iter().zip(r["cylinders"].as_array().unwrap()) {
            let points = cyl["points"].as_array().unwrap();
            assert_eq!(c.as_array().unwrap().len(), points.len());
            for ch in c.as_array().unwrap() {
                let d = ch["delta_m_s2"].as_f64().unwrap();
                if *x == 0.0 {
                    assert_eq!(d, 0.0, "the base against itself");
                }
                // one averaged cycle: no standard error, no verdict
                let Some(s) = ch["se_m_s2"].as_f64() else {
                    assert_eq!(ch["verdict"], "unknown (one cycle)", "{ch}");
                    continue;
                };
                assert_eq!(ch["verdict"], change_verdict(d, s), "{ch}");
            }
        }
    }
    // the largest of each quantity over the runs, from their own records
    let slap = |r: &serde_json::Value| {
        r["cylinders"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["peak_slap_force_n"].as_f64().unwrap())
            .fold(f64::MIN, f64::max)
    };
    let acc = |r: &serde_json::Value| {
        r["cylinders"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|c| c["points"].as_array().unwrap().iter())
            .map(|p| p["peak_negative_m_s2"].as_f64().unwrap())
            .fold(f64::MIN, f64::max)
    };
    for (name, f) in [
        (
            "peak_slap_force_n",
            &slap as &dyn Fn(&serde_json::Value) -> f64,
        ),
        ("peak_negative_m_s2", &acc),
    ] {
        let m = &v["maximum"][name];
        let k = (0..runs.len())
            .max_by(|&a, &b| f(&runs[a]).total_cmp(&f(&runs[b])))
            .unwrap();
        assert_eq!(m["at"].as_f64().unwrap(), xs[k], "{name}");
        assert_eq!(m["value"].as_f64().unwrap(), f(&runs[k]), "{name}");
        let spacing = [
            k.checked_sub(1).map(|j| xs[k] - xs[j]),
            xs.get(k + 1).map(|x| x - xs[k]),
        ]
        .into_iter()
        .flatten()
        .fold(0.0f64, f64::max);
        assert_eq!(m["uncertainty"].as_f64().unwrap(), 0.5 * spacing, "{name}");
    }
    for (extra, flag) in [
        (vec!["--refine", "piston.pin_offset_mm=-1:1"], "--runs"),
        (
            vec!["--refine", "piston.pin_offset_mm=-1:1", "--runs", "2"],
            "--runs",
        ),
        (
            vec!["--refine", "piston.pin_offset_mm=1:-1", "--runs", "5"],
            "--refine",
        ),
        (
            vec![
                "--refine",
                "piston.pin_offset_mm=-1:1",
                "--runs",
                "5",
                "--vary",
                "piston.clearance_um=60,80",
            ],
            "--refine",
        ),
        (
            vec![
                "--refine",
                "piston.pin_offset_mm=-1:1",
                "--runs",
                "5",
                "--shard",
                "1/2",
            ],
            "--refine",
        ),
        (
            vec!["--vary", "piston.clearance_um=60,80", "--runs", "5"],
            "--runs",
        ),
    ] {
        let mut args = vec!["sweep", SCENE];
        args.extend_from_slice(&extra);
        let (code, out, err) = linercav(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(out.is_empty() && err.contains(flag), "{extra:?}: {err}");
    }
}
