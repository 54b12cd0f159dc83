//! Cavitation commands end to end: `coolant` against hand values, `calibrate` on synthetic rig
//! data made here from a physical model with known thresholds, and bad data refused cleanly.

use std::fmt::Write as _;
use std::path::Path;
mod common;
use common::linercav;

/// `linercav calibrate` of `csv` for the reference coolant (4.7 mm, 240 kPa, 90 C) with JSON
/// on stdout and the figure at `png`.
fn calibrate_reference(csv: &Path, png: &Path) -> (i32, String, String) {
    calibrate_at(csv, "240", &["--json", "--png", png.to_str().unwrap()])
}

/// `linercav calibrate` of `csv` at 4.7 mm, 90 C and `static_kpa`, with `extra` arguments.
fn calibrate_at(csv: &Path, static_kpa: &str, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "calibrate",
        "--data",
        csv.to_str().unwrap(),
        "--gap-mm",
        "4.7",
    ];
    args.extend_from_slice(&["--static-kpa", static_kpa, "--temp-c", "90"]);
    args.extend_from_slice(extra);
    linercav(&args)
}

/// Reference coolant by hand (steam tables, 90 C): p_v = 70.18 kPa, rho = 965.3 kg/m^3,
/// c = 1550.4 m/s; Vccv = (240 - 70.18) kPa / (965.3 x 1550.4) = 0.1135 m/s.
#[test]
fn verification_coolant_json_matches_hand_values() {
    let (code, out, err) = linercav(&[
        "coolant",
        "--temp-c",
        "90",
        "--static-kpa",
        "240",
        "--gap-mm",
        "4.7",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let get = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k} in {out}"));
    assert!((get("vapour_pressure_kpa") - 70.18).abs() < 0.01);
    assert!((get("density_kg_m3") - 965.3).abs() < 0.1);
    assert!((get("speed_of_sound_m_s") - 1550.4).abs() < 0.5);
    assert!((get("vccv_m_s") - 0.1135).abs() < 3e-4);
    // Ca = 1 with the reference k_p lands on the study's 1189 m/s^2
    assert!((get("threshold_m_s2") - 1189.0).abs() < 0.5);
    // the layer's mass per area: 965.3 kg/m^3 x 4.7 mm = 4.537 kg/m^2
    assert!((get("layer_mass_kg_m2") - 4.537).abs() < 1e-3);
    let (code, _, err) = linercav(&["coolant", "--temp-c", "130", "--static-kpa", "150"]);
    assert_eq!(code, 2);
    assert!(err.contains("boils"), "{err}");
}

/// Synthetic rig record from a physical model, written independently of the code under test:
/// events every 10 ms, each a decaying 1850 Hz ring (time constant 1 ms) whose negative peak
/// runs evenly from `neg_lo` to `neg_hi` m/s^2 (the ring's envelope at the negative peak,
/// 3/4 period in, is exp(-0.405) = 0.667 of its start amplitude);
/// the wall pressure follows p = p_s + k_i a with a per-event transfer k_i cycling through
/// 7 values in [110, 170] Pa/(m/s^2) (what scatters real events: gas content, local gap),
/// and cannot fall below p_v (+0.5 kPa) once vapour forms. Small uniform noise on both.
/// An event cavitates (Ca < 1 at the liner) iff |a| > (p_s - p_v)/(k_i + rho h), so the
/// true thresholds are onset = (p_s - p_v)/(k_max + rho h), high = (p_s - p_v)/(k_min + rho h).
fn synthetic(path: &Path, neg_lo: f64, neg_hi: f64, n: usize) -> (f64, f64, f64) {
    let (ps, pv, rho, h) = (240.0e3, 70.18e3, 965.3, 4.7e-3);
    let ks: Vec<f64> = (0..7).map(|j| 110.0 + 10.0 * j as f64).collect();
    let fs = 50_000.0;
    let mut seed: u64 = 12345;
    let mut noise = move |scale: f64| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        scale * (((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0)
    };
    let mut s = String::from("time_s,acceleration_m_s2,pressure_kpa\n");
    let per = (0.010 * fs) as usize;
    for i in 0..n {
        let neg = neg_lo + (neg_hi - neg_lo) * i as f64 / (n - 1).max(1) as f64;
        let amp = neg / (-0.75 / (1.85 * 1.0_f64)).exp();
        let k = ks[i % ks.len()];
        for j in 0..per {
            let t = j as f64 / fs;
            let a = if t < 0.006 {
                amp * (-t / 0.001).exp() * (2.0 * std::f64::consts::PI * 1850.0 * t).sin()
            } else {
                0.0
            };
            let p = (ps + k * a).max(pv + 0.5e3);
            let time = (i * per + j) as f64 / fs;
            writeln!(
                s,
                "{time:.7},{:.4},{:.4}",
                a + noise(2.0),
                p / 1e3 + noise(0.1)
            )
            .unwrap();
        }
    }
    std::fs::write(path, s).unwrap();
    let onset = (ps - pv) / (ks[6] + rho * h);
    let high = (ps - pv) / (ks[0] + rho * h);
    let mean_k = ks.iter().sum::<f64>() / ks.len() as f64;
    (onset, high, mean_k)
}

/// Regression (session 75's hostile sweep): rig data recorded at 240 kPa calibrated with
/// `--static-kpa 600` exited 0 with k_p = -61.7 Pa/(m/s^2) (R^2 -1.28) and a negative model
/// threshold, a JSON the scene then refused; `--static-kpa 1e9` was taken although the scene
/// key stops at 10000 kPa. Both are refused, exit 2, naming the static pressure.
#[test]
fn regression_calibrate_refuses_a_static_pressure_the_record_contradicts() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("rig.csv");
    synthetic(&csv, 300.0, 2000.0, 40);
    for (kpa, shown) in [
        ("600", "static pressure 600.0 kPa"),
        ("1e9", "--static-kpa"),
    ] {
        let (code, out, err) = calibrate_at(&csv, kpa, &[]);
        assert_eq!(code, 2, "{kpa}: {out} {err}");
        assert!(err.contains(shown), "{kpa}: {err}");
        assert!(out.is_empty(), "{out}");
    }
}

/// Regression (session 75's hostile sweep): the missing-column message quoted the whole
/// header line, and a file with no line end it knows (CR only, or one line) is all header: a
/// 100 MB file gave a 100 MB message. The header is cut at 200 characters, the rest counted.
#[test]
fn regression_a_one_line_file_gives_a_short_message() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("cr.csv");
    let mut text = String::from("time_s,acceleration_m_s2,pressure_kpa");
    for i in 0..50_000 {
        text.push_str(&format!("\r{i},1,240"));
    }
    std::fs::write(&csv, &text).unwrap();
    let (code, _, err) = calibrate_at(&csv, "240", &[]);
    assert_eq!(code, 2, "{}", &err[..err.len().min(500)]);
    assert!(
        err.len() < 1000 && err.contains("more bytes"),
        "{} bytes: {}",
        err.len(),
        &err[..err.len().min(500)]
    );
}

/// Regression: rig data saved with a byte-order mark and CRLF line ends (a spreadsheet's "CSV
/// UTF-8") were refused with "missing column 'time_s'" while the message listed it; they read
/// as the plain file does.
#[test]
fn regression_a_byte_order_mark_and_crlf_read_as_plain_csv() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.csv");
    synthetic(&plain, 300.0, 2000.0, 40);
    let text = std::fs::read_to_string(&plain).unwrap();
    let marked = dir.path().join("marked.csv");
    std::fs::write(&marked, format!("\u{feff}{}", text.replace('\n', "\r\n"))).unwrap();
    let (c1, out1, e1) = calibrate_reference(&plain, &dir.path().join("a.png"));
    let (c2, out2, e2) = calibrate_reference(&marked, &dir.path().join("b.png"));
    assert_eq!((c1, c2), (0, 0), "{e1} {e2}");
    let (v1, v2): (serde_json::Value, serde_json::Value) = (
        serde_json::from_str(&out1).unwrap(),
        serde_json::from_str(&out2).unwrap(),
    );
    for key in ["events", "onset_m_s2", "high_risk_m_s2", "k_p_pa_per_m_s2"] {
        assert_eq!(v1[key], v2[key], "{key}");
        assert!(!v1[key].is_null(), "{key} in the output");
    }
}

/// Tolerance 5 % (the floor): amplitudes step by 4.9 m/s^2 and a given k_i recurs every 7
/// events, so the nearest event with the extreme k_i is within 34 m/s^2 (< 3.5 %) of each
/// true threshold; peak sampling at 27 samples per period (< 0.7 %) and noise (< 0.3 %) add
/// less. k_p: the A^2-weighted mean of the cycling k_i, within 5 % of their mean.
#[test]
fn verification_calibration_recovers_known_thresholds() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("rig.csv");
    let png = dir.path().join("cal.png");
    let (onset, high, k_mean) = synthetic(&csv, 300.0, 2000.0, 350);
    let (code, out, err) = calibrate_reference(&csv, &png);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let get = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k} in output"));
    assert_eq!(v["events"].as_u64(), Some(350));
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(
        rel(get("onset_m_s2"), onset) < 0.05,
        "onset {} vs {onset}",
        get("onset_m_s2")
    );
    assert!(
        rel(get("high_risk_m_s2"), high) < 0.05,
        "high {} vs {high}",
        get("high_risk_m_s2")
    );
    assert!(
        rel(get("k_p_pa_per_m_s2"), k_mean) < 0.05,
        "k_p {} vs {k_mean}",
        get("k_p_pa_per_m_s2")
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
}

fn refused(dir: &Path, name: &str, text: &str, needle: &str) {
    let csv = dir.join(name);
    std::fs::write(&csv, text).unwrap();
    let png = dir.join(format!("{name}.png"));
    let (code, out, err) = calibrate_reference(&csv, &png);
    assert_eq!(code, 2, "{name}: {err}");
    assert!(err.contains(needle), "{name}: '{err}' lacks '{needle}'");
    assert!(
        err.contains(csv.to_str().unwrap()),
        "{name}: {err} does not name the file"
    );
    assert!(out.is_empty(), "{name}: printed {out}");
    assert!(!png.exists(), "{name}: wrote a PNG");
    let stray = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .count();
    assert_eq!(stray, 0, "{name}: left a temporary file");
}

#[test]
fn contract_bad_rig_data_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    refused(
        d,
        "nocol.csv",
        "time_s,acceleration_m_s2\n0,1\n",
        "missing column 'pressure_kpa'",
    );
    let mut rows = String::from("time_s,acceleration_m_s2,pressure_kpa\n");
    for i in 0..40 {
        writeln!(
            rows,
            "{},{},240",
            i as f64 * 1e-4,
            if i == 20 {
                "NaN".to_string()
            } else {
                "0".into()
            }
        )
        .unwrap();
    }
    refused(d, "nan.csv", &rows, ":22:");
    let back = "time_s,acceleration_m_s2,pressure_kpa\n".to_string()
        + &(0..40)
            .map(|i| format!("{},0,240\n", if i == 30 { 0.0 } else { i as f64 }))
            .collect::<String>();
    refused(d, "time.csv", &back, "does not increase");
    let quiet = rows.replace("NaN", "0");
    refused(d, "quiet.csv", &quiet, "no events found");
    let all = d.join("all.csv");
    synthetic(&all, 2000.0, 2500.0, 20);
    let text = std::fs::read_to_string(&all).unwrap();
    refused(d, "all_cav.csv", &text, "all 20 events cavitate");
}
