//! Fast-path regression: the default engine's per-cylinder, per-point peak accelerations,
//! side and slap forces pinned against `tests/baseline/default_engine.json`.
//!
//! Tolerance 1e-4 relative: the run is deterministic, and a relative perturbation of 4e-8 in
//! an input moved the peaks by 2e-7 (the slap amplifies roundoff about fivefold, no more), so
//! 1e-4 absorbs roundoff differences (ROM rebuilds, summation order) while any change of the
//! physics or numerics shows. To update the baseline on purpose:
//!   LINERCAV_UPDATE_BASELINE=1 cargo test --release --test baseline
//! and commit the file with the reason.

use linercav::app::rom::CacheOptions;
use linercav::app::simulate::{run, SimulateRequest};
use std::path::PathBuf;
use std::time::Instant;

const BASELINE: &str = "tests/baseline/default_engine.json";

#[test]
fn default_engine_peaks_match_the_baseline() {
    let req = SimulateRequest {
        scene: PathBuf::from("models/engine.toml"),
        sets: vec![],
        out: None,
        cache: CacheOptions::default(),
        full_order: false,
    };
    let report = run(&req, Instant::now()).unwrap();
    let now = serde_json::json!({
        "cylinders": report.cylinders,
    });
    if std::env::var_os("LINERCAV_UPDATE_BASELINE").is_some() {
        std::fs::write(BASELINE, serde_json::to_string_pretty(&now).unwrap() + "\n").unwrap();
        return;
    }
    let text = std::fs::read_to_string(BASELINE).expect("baseline file");
    let base: serde_json::Value = serde_json::from_str(&text).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-4 * b.abs().max(1.0);
    for (c, b) in now["cylinders"]
        .as_array()
        .unwrap()
        .iter()
        .zip(base["cylinders"].as_array().unwrap())
    {
        let cyl = &c["cylinder"];
        for key in [
            "peak_slap_force_n",
            "peak_side_force_n",
            "slap_crank_angle_deg",
            "side_force_crank_angle_deg",
        ] {
            let (x, y) = (c[key].as_f64().unwrap(), b[key].as_f64().unwrap());
            assert!(close(x, y), "cylinder {cyl}: {key} {x} vs baseline {y}");
        }
        for (p, q) in c["points"]
            .as_array()
            .unwrap()
            .iter()
            .zip(b["points"].as_array().unwrap())
        {
            for key in [
                "peak_negative_m_s2",
                "peak_positive_m_s2",
                "crank_angle_deg",
            ] {
                let (x, y) = (p[key].as_f64().unwrap(), q[key].as_f64().unwrap());
                assert!(
                    close(x, y),
                    "cylinder {cyl} point {}: {key} {x} vs baseline {y}",
                    p["point"]
                );
            }
        }
    }
}
