//! Hostile input and faults (regression tests of issue 23, and fuzzing): every case exits 2
//! (bad input, unwritable output) or 1 (numerical or system failure) with one message on
//! stderr and nothing on stdout, never a panic, an abort or a runaway; outputs are
//! all-or-nothing, also when a signal stops the process.

use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{linercav, refused};

const SMALL: &str = "tests/fixtures/engine_small.toml";
const MESH: &str = "tests/fixtures/block_tet10.msh";
const STEEL: [&str; 6] = ["--youngs", "210e9", "--poisson", "0.3", "--density", "7850"];

/// The fixture mesh with line `line` (1-based) replaced.
fn mesh_with(dir: &Path, name: &str, line: usize, text: &str) -> PathBuf {
    let src = std::fs::read_to_string(MESH).unwrap();
    let mut lines: Vec<&str> = src.lines().collect();
    lines[line - 1] = text;
    let p = dir.join(name);
    std::fs::write(&p, lines.join("\n")).unwrap();
    p
}

/// Regression: Gmsh counts that are negative or huge were allocated before they were
/// checked (capacity overflow, a 24 PB allocation, a slice-index panic); a device was read
/// until memory ran out; one bad byte was "binary MSH, line 0".
#[test]
fn regression_hostile_gmsh_files_are_refused_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (mesh_with(d, "a.msh", 41, "1 -1 1 2618"), ":41", "numNodes"),
        (
            mesh_with(d, "b.msh", 41, "1 1000000000000000 1 2618"),
            ":41",
            "numNodes",
        ),
        (
            mesh_with(d, "c.msh", 42, "0 1 0 -1"),
            ":42",
            "numNodesInBlock",
        ),
        (
            mesh_with(d, "d.msh", 2662, "0 7 15 9223372036854775807"),
            ":2662",
            "numElementsInBlock",
        ),
        (
            mesh_with(d, "e.msh", 19, "7 0.2 0.1 0.05 99999999999999 3"),
            ":19",
            "the entity record gives 1e14 physical tags",
        ),
        (
            mesh_with(d, "f.msh", 19, "7 0.2 0.1 0.05 1e300 3"),
            ":19",
            "the entity record gives 1e300 physical tags",
        ),
        // session 70: a section name in the wrong case was skipped to the end of the file
        // ("unexpected end of file" at the last line)
        (
            mesh_with(d, "g.msh", 40, "$nodes"),
            ":40",
            "section '$nodes' (section names are case-sensitive: '$Nodes') has no '$Endnodes'",
        ),
    ];
    for (p, line, what) in &cases {
        let mut args = vec!["modes", "--mesh", p.to_str().unwrap(), "--count", "10"];
        args.extend(STEEL);
        refused(&args, 2, &format!("{line}: {what}"));
    }
    let bad = d.join("byte.msh");
    std::fs::write(&bad, b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\xff\n").unwrap();
    let zero = d.join("zero.msh");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    for (p, needle) in [(&bad, ":4: byte 0xff"), (&zero, "not a regular file")] {
        let mut args = vec!["modes", "--mesh", p.to_str().unwrap(), "--count", "10"];
        args.extend(STEEL);
        refused(&args, 2, needle);
    }
}

/// Regression: scene values that panicked (capacity overflow), allocated until killed, or
/// were accepted silently. Each is refused before any work (no ROM is built: the cache
/// directory stays empty) with the key and a number of a few digits.
#[test]
fn regression_hostile_scene_values_are_refused_before_work() {
    let cache = tempfile::tempdir().unwrap();
    let cache_dir = cache.path().to_str().unwrap();
    let order: String = (1..=1000)
        .map(|k| k.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let cyl_order = format!("engine.firing_order=[{order}]");
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        (
            "simulate",
            vec!["transient.step_deg=1e-308"],
            "transient.step_deg",
        ),
        (
            "simulate",
            vec!["transient.step_deg=5"],
            "transient.step_deg",
        ),
        (
            "simulate",
            vec!["transient.step_deg=1e-4"],
            "transient.step_deg",
        ),
        (
            "simulate",
            vec!["liner.analysis_points=9223372036854775807"],
            "liner.analysis_points",
        ),
        ("simulate", vec!["piston.slices=1000000"], "piston.slices"),
        // session 70's hostile sweep: accepted with every peak 0, or failed as numerical
        // trouble named by no key
        (
            "simulate",
            vec!["piston.barrel_um=1e308"],
            "piston.barrel_um",
        ),
        (
            "simulate",
            vec!["engine.rod_length_mm=219000"],
            "engine.rod_length_mm",
        ),
        (
            "simulate",
            vec!["crankcase.front_wall_mm=14000"],
            "crankcase.front_wall_mm",
        ),
        (
            "simulate",
            vec!["crankcase.deck_thickness_mm=1e-9"],
            "crankcase.deck_thickness_mm",
        ),
        (
            "simulate",
            vec!["crankcase.flange_clamp_kn=107000"],
            "crankcase.flange_clamp_kn",
        ),
        (
            "simulate",
            vec!["rom.cutoff_factor=1e308"],
            "rom.cutoff_factor",
        ),
        ("simulate", vec!["crankcase.fix=[]"], "crankcase.fix"),
        (
            "simulate",
            vec!["operating.combustion.duration_deg=50000"],
            "operating.combustion.duration_deg",
        ),
        // session 78: no piston of this bore (each ran with exit 0 or failed in the solver)
        ("simulate", vec!["piston.mass_kg=1e-308"], "piston.mass_kg"),
        (
            "simulate",
            vec!["piston.tilt_inertia_kg_m2=4000"],
            "piston.tilt_inertia_kg_m2",
        ),
        (
            "simulate",
            vec!["piston.contact_damping_n_s_per_m=1e308"],
            "piston.contact_damping_n_s_per_m",
        ),
        // session 78: 0.01 deg fell between the curve's integration steps (the motored
        // curve's peak, exit 0)
        (
            "simulate",
            vec!["operating.combustion.duration_deg=0.01"],
            "operating.combustion.duration_deg",
        ),
        (
            "simulate",
            vec!["liner.analysis_spacing_mm=1e-9"],
            "liner.analysis_spacing_mm",
        ),
        (
            "simulate",
            vec!["transient.slap_substeps=0"],
            "transient.slap_substeps",
        ),
        (
            "simulate",
            vec!["transient.slap_substeps=100000"],
            "transient.slap_substeps",
        ),
        (
            "simulate",
            vec!["transient.slap_span_deg=-1"],
            "transient.slap_span_deg",
        ),
        (
            "simulate",
            vec!["piston.skirt_length_mm=300"],
            "piston.skirt_length_mm",
        ),
        ("simulate", vec!["cavitation.gap_mm=1e-308"], "1e-308 mm"),
        // a clearance of a kilometre ran and printed "-0" peaks (the piston never touched)
        (
            "simulate",
            vec!["piston.clearance_um=1e9"],
            "piston.clearance_um",
        ),
        // a pin or centre of gravity outside the piston ended in "deep penetration" (exit 1)
        (
            "simulate",
            vec!["piston.pin_offset_mm=-60"],
            "piston.pin_offset_mm",
        ),
        (
            "simulate",
            vec!["piston.cg_offset_mm=500"],
            "piston.cg_offset_mm",
        ),
        (
            "rom",
            vec!["liner.mesh.radial=9223372036854775807"],
            "liner.mesh",
        ),
        (
            "rom",
            vec!["liner.mesh.circumferential=100000"],
            "GB of memory",
        ),
        (
            "rom",
            vec!["rom.interface_harmonics=1000000"],
            "rom.interface_harmonics",
        ),
        (
            "rom",
            vec!["engine.cylinders=1000", &cyl_order],
            "GB of memory",
        ),
        (
            "rom",
            vec!["solver.guard_modes=1000000000"],
            "solver.guard_modes",
        ),
        ("rom", vec!["limits.max_hours=0.000001"], "limits.max_hours"),
        // an oil whose viscosity overflowed or vanished ran and then blamed the supply (exit 1)
        (
            "simulate",
            vec!["piston.lubrication=squeeze", "piston.oil.vogel_b_c=1e6"],
            "piston.oil.vogel_a_mpa_s / vogel_b_c / vogel_c_c",
        ),
        (
            "simulate",
            vec![
                "piston.lubrication=squeeze",
                "piston.oil.vogel_a_mpa_s=1e-300",
            ],
            "outside the 0.1 to 1e7 mPa s of engine oils",
        ),
        (
            "simulate",
            vec![
                "piston.lubrication=mixed",
                "piston.oil.asperity_modulus_gpa=1e300",
            ],
            "piston.oil.asperity_modulus_gpa",
        ),
        // oil data of a dry skirt were not read (a report may compare it with a film)
        (
            "simulate",
            vec!["piston.oil.supply_um=-3"],
            "piston.oil.supply_um",
        ),
        // 50,000 rpm (235 m/s of mean piston speed) ended in "deep penetration" (exit 1)
        (
            "simulate",
            vec!["engine.speed_rpm=50000"],
            "mean piston speed of 235 m/s",
        ),
        // a friction coefficient of 50 ended in "deep penetration" (exit 1)
        (
            "simulate",
            vec!["piston.pin_friction=50"],
            "piston.pin_friction",
        ),
        ("simulate", vec!["piston.friction=1e300"], "piston.friction"),
        (
            "simulate",
            vec!["piston.pin_slip_rad_s=1e-300"],
            "piston.pin_slip_rad_s",
        ),
        (
            "simulate",
            vec!["piston.pin_diameter_mm=1e-300"],
            "piston.pin_diameter_mm",
        ),
        // these named another key (transient.step_deg, liner.inner_diameter_mm, the derived
        // onset), or reached the solver and ended in exit 1
        ("simulate", vec!["engine.speed_rpm=1"], "engine.speed_rpm"),
        ("simulate", vec!["rom.band_hz=1e308"], "rom.band_hz"),
        ("simulate", vec!["engine.bore_mm=0.115"], "engine.bore_mm"),
        (
            "simulate",
            vec!["cavitation.high_risk_m_s2=1e308"],
            "cavitation.high_risk_m_s2",
        ),
        (
            "simulate",
            vec!["operating.combustion.wiebe_a=1e308"],
            "operating.combustion.wiebe_a",
        ),
        (
            "simulate",
            vec!["operating.combustion.wiebe_m=1e6"],
            "operating.combustion.wiebe_m",
        ),
        (
            "simulate",
            vec!["piston.contact_stiffness_n_per_m=1e308"],
            "piston.contact_stiffness_n_per_m",
        ),
    ];
    for (cmd, sets, needle) in cases {
        let mut args = vec![cmd, SMALL, "--cache-dir", cache_dir];
        for s in &sets {
            args.extend(["--set", s]);
        }
        refused(&args, 2, needle);
        // numbers the tool computes come with a few digits (1e308 had 309)
        let (_, _, err) = linercav(&args);
        let longest = err
            .split(|c: char| !c.is_ascii_digit())
            .map(str::len)
            .max()
            .unwrap_or(0);
        assert!(longest <= 20, "{sets:?}: long number: {err}");
    }
    assert_eq!(std::fs::read_dir(cache.path()).unwrap().count(), 0);
}

/// Regression: a ROM whose band holds no mode was cached and `simulate` panicked on it; a
/// material so soft that every mode falls into the band ran until killed.
#[test]
fn regression_a_band_without_modes_or_with_all_of_them_is_refused() {
    let cache = tempfile::tempdir().unwrap();
    let dir = cache.path().to_str().unwrap();
    refused(
        &[
            "simulate",
            SMALL,
            "--cache-dir",
            dir,
            "--set",
            "rom.band_hz=1e-308",
        ],
        2,
        "rom.band_hz",
    );
    refused(
        &[
            "rom",
            SMALL,
            "--cache-dir",
            dir,
            "--set",
            "materials.boron_cast_iron.youngs_pa=1e3",
        ],
        2,
        "lower rom.band_hz",
    );
    let (_, _, err) = linercav(&[
        "rom",
        SMALL,
        "--cache-dir",
        dir,
        "--set",
        "materials.boron_cast_iron.youngs_pa=1e3",
    ]);
    assert!(err.contains("warning: ") && err.contains("Young's modulus 1000 Pa"));
    // no engine ROM is stored; the component cache may hold the parts whose reductions
    // completed (both parts of the first case, the crankcase of the second): valid results of
    // their own inputs, reused after the fix
    assert!(!std::fs::read_dir(cache.path()).unwrap().any(|e| e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .starts_with("rom-")));
}

/// Regression: an unwritable cache directory was found after a full build; an unreadable
/// cache file was a silent miss. Both exit 2 before any work.
#[test]
fn regression_unwritable_cache_and_unreadable_entry_stop_before_the_build() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("plain");
    std::fs::write(&file, "x").unwrap();
    // a cache "directory" below a regular file can never be created (also as root)
    let below = file.join("cache");
    let t = Instant::now();
    refused(
        &["rom", SMALL, "--cache-dir", below.to_str().unwrap()],
        2,
        "cannot write",
    );
    // the build of the small engine takes seconds; the refusal comes first
    assert!(t.elapsed() < Duration::from_secs(60));
    // a directory where the cache file should be
    let dir = tmp.path().join("c");
    let key = {
        let sc = linercav::scene::Scene::load(Path::new(SMALL), &[]).unwrap();
        linercav::reduce::cache::key_of(&linercav::reduce::scene_rom::key_description(&sc).unwrap())
    };
    std::fs::create_dir_all(dir.join(format!("rom-{key}.bin"))).unwrap();
    refused(
        &["rom", SMALL, "--cache-dir", dir.to_str().unwrap()],
        2,
        "cannot read the ROM cache file",
    );
}

/// Regression: a pressure curve with decimal commas (`369,190,3`) was read as 190 bar.
#[test]
fn regression_decimal_comma_csv_is_refused() {
    let text = "crank_angle_deg,pressure_bar\n0,1.0\n369,190,3\n";
    let Err(e) = linercav::piston::pressure::PressureCurve::parse(Path::new("p.csv"), text) else {
        panic!("refused")
    };
    let msg = e.to_string();
    assert!(
        msg.contains("line 3") && msg.contains("decimal commas"),
        "{msg}"
    );
    let rig = "time_s,acceleration_m_s2,pressure_kpa\n0,1,100\n0.001,2,5,3\n";
    let Err(e) = linercav::cavitation::calibration::RigData::parse("r.csv", rig) else {
        panic!("refused")
    };
    assert!(e.to_string().contains("decimal commas"), "{e}");
}

/// Regression (session 74's hostile sweep): a scene given as `/dev/stdin` with the file
/// redirected to the process took `/dev` as its directory: its relative mesh path was looked
/// for in /dev and its ROM cache went to /dev/.linercav-cache. The file's own directory is
/// used, as when it is named: the liner mesh beside it is found and the modes solved.
#[test]
fn regression_a_scene_redirected_to_stdin_keeps_its_own_directory() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("engine.toml");
    std::fs::copy(SMALL, &scene).unwrap();
    std::fs::copy(
        "tests/fixtures/liner_hex20.msh",
        dir.path().join("liner.msh"),
    )
    .unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let run = |path: &str, stdin: std::process::Stdio| {
        let out = Command::new(env!("CARGO_BIN_EXE_linercav"))
            .args(["modes", path, "--part", "liner", "--count", "4"])
            .args(["--set", "liner.mesh_file=\"liner.msh\"", "--json"])
            .current_dir(elsewhere.path())
            .stdin(stdin)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{path}: {err}");
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (json["dofs"].clone(), json["frequencies_hz"].clone())
    };
    let redirected = run("/dev/stdin", std::fs::File::open(&scene).unwrap().into());
    let named = run(scene.to_str().unwrap(), std::process::Stdio::null());
    assert_eq!(redirected, named);
}

/// Regression: one output name taken by a directory let the other files be written; now
/// nothing is written and the exit code is 2 (as for every unwritable output).
#[test]
fn regression_a_taken_output_name_writes_nothing() {
    let cache = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    std::fs::create_dir(out.path().join("simulate.json")).unwrap();
    refused(
        &[
            "simulate",
            SMALL,
            "--cache-dir",
            cache.path().to_str().unwrap(),
            "--out",
            out.path().to_str().unwrap(),
        ],
        2,
        "simulate.json",
    );
    let names: Vec<String> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        vec!["simulate.json".to_string()],
        "nothing else left"
    );
}

/// Regression (session 70's hostile sweep): an output file or directory that could not be
/// written was found only after the work (`modes --vtu` into a directory after its solve,
/// `export-matrices --out` onto a file after the assembly); both are refused first, exit 2,
/// and a given material's FE model is never assembled (nothing on stdout).
#[test]
fn regression_an_unwritable_output_stops_the_command_first() {
    let dir = tempfile::tempdir().unwrap();
    let taken = dir.path().join("shapes.vtu");
    std::fs::create_dir(&taken).unwrap();
    let file = dir.path().join("afile");
    std::fs::write(&file, "x").unwrap();
    let mut modes = vec!["modes", "--mesh", MESH, "--count", "3"];
    modes.extend(STEEL);
    modes.extend(["--vtu", taken.to_str().unwrap()]);
    refused(&modes, 2, "shapes.vtu");
    let mut export = vec!["export-matrices", "--mesh", MESH];
    export.extend(STEEL);
    export.extend(["--out", file.to_str().unwrap()]);
    refused(&export, 2, "afile");
}

/// A cache directory holding the test engine's ROM (kept while the directory lives), and its
/// path.
fn small_rom_cache() -> (tempfile::TempDir, String) {
    let cache = tempfile::tempdir().unwrap();
    let cache_dir = cache.path().to_str().unwrap().to_string();
    let (c, _, err) = linercav(&["rom", SMALL, "--cache-dir", &cache_dir]);
    assert_eq!(c, 0, "{err}");
    (cache, cache_dir)
}

/// Regression (session 75's hostile sweep): a pipe (FIFO) at a ROM entry's lock path made
/// `simulate` wait forever, silently (opening it for writing waits for a reader). It is
/// refused at once, exit 2, naming the lock file; the pipe is left as it was. (Killed after
/// 60 s so that a regression fails instead of hanging the suite.)
#[test]
fn regression_a_pipe_at_the_cache_lock_is_refused_not_waited_on() {
    let (_cache, dir) = small_rom_cache();
    let roms: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("rom-"))
        .collect();
    assert_eq!(roms.len(), 1, "{roms:?}");
    std::fs::remove_file(&roms[0]).unwrap();
    let lock = roms[0].with_extension("lock");
    let made = Command::new("mkfifo").arg(&lock).status().unwrap();
    assert!(made.success());
    let mut child = Command::new(env!("CARGO_BIN_EXE_linercav"))
        .args(["simulate", SMALL, "--cache-dir", &dir])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("simulate still waiting on the pipe after 60 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(2), "{err}");
    assert!(
        err.contains(&*lock.to_string_lossy()) && err.contains("not a regular file"),
        "{err}"
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&lock)
        .unwrap()
        .file_type()
        .is_fifo());
}

/// Regression (session 70's hostile sweep): a run into a directory that an earlier run of the
/// command filled left that run's other files beside its own without a word (`--maps`
/// images beside a run without maps); they are named as an earlier run's, and left.
#[test]
fn regression_outputs_of_an_earlier_run_are_named() {
    let (_cache, cache_dir) = small_rom_cache();
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["simulate", SMALL, "--cache-dir", &cache_dir, "--out", o];
        args.extend([
            "--set",
            "transient.cycles=2",
            "--set",
            "transient.averaged_cycles=1",
        ]);
        args.extend(extra);
        let (code, _, err) = linercav(&args);
        assert_eq!(code, 0, "{err}");
        err
    };
    let first = run(&["--maps"]);
    assert!(!first.contains("earlier"), "{first}");
    let second = run(&[]);
    assert!(
        second.contains("liner_maps.png, liner_maps.vtu not written by this run"),
        "{second}"
    );
    assert!(out.path().join("liner_maps.png").exists(), "left in place");
}

/// Names in a directory with their contents (directories as "<dir>").
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .map(|e| {
                let e = e.unwrap();
                let name = e.file_name().to_string_lossy().into_owned();
                let bytes = std::fs::read(e.path()).unwrap_or_else(|_| b"<dir>".to_vec());
                (name, bytes)
            })
            .collect(),
        Err(_) => vec![],
    };
    v.sort();
    v
}

/// A signal at any moment of `simulate --out`, `sweep --out` or `report --out` leaves the
/// directory as it was, or complete; no temporary file or directory is left behind. The
/// moments are spread over the whole run (measured first), including the writing at its end.
#[test]
fn verification_a_signal_leaves_outputs_as_they_were_or_complete() {
    let (_cache, cache_dir) = small_rom_cache();
    let commands: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["simulate", SMALL],
            vec!["simulate.json", "time_series.csv"],
        ),
        (
            vec!["sweep", SMALL, "--vary", "piston.clearance_um=60,100"],
            vec!["sweep.csv", "sweep.json", "sweep_piston_clearance_um.png"],
        ),
        (
            vec!["report", SMALL],
            vec!["summary.json", "summary.md", "peaks.png"],
        ),
    ];
    for (args, expected) in commands {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("keep.txt"), "a file of the user's").unwrap();
        for name in &expected {
            std::fs::write(out.join(name), "old").unwrap();
        }
        let before = snapshot(&out);
        let run = |kill_after: Option<Duration>| {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_linercav"));
            cmd.args(&args)
                .args(["--cache-dir", &cache_dir, "--out", out.to_str().unwrap()])
                .env("OPENBLAS_NUM_THREADS", "1")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null());
            let mut child = cmd.spawn().unwrap();
            let t = Instant::now();
            if let Some(d) = kill_after {
                std::thread::sleep(d);
                // SAFETY: kill(2) on our own child's pid
                unsafe {
                    libc::kill(child.id() as i32, libc::SIGTERM);
                }
            }
            let status = child.wait().unwrap();
            (status, t.elapsed())
        };
        let (status, full) = run(None);
        assert!(status.success(), "{args:?} must run");
        let complete = snapshot(&out);
        for name in &expected {
            let f = complete.iter().find(|(n, _)| n == name).unwrap();
            assert_ne!(f.1, b"old", "{name} rewritten");
        }
        // restore the old state, then stop runs at 12 moments over the run and its end
        let restore = || {
            std::fs::remove_dir_all(&out).unwrap();
            std::fs::create_dir(&out).unwrap();
            for (name, bytes) in &before {
                std::fs::write(out.join(name), bytes).unwrap();
            }
        };
        restore();
        for k in 0..12 {
            let at = full.mul_f64((k as f64 + 0.5) / 11.0);
            run(Some(at));
            let now = snapshot(&out);
            let same_names = |s: &[(String, Vec<u8>)]| {
                s.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>()
                    == now.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>()
            };
            let as_before = now == before;
            let is_complete = same_names(&complete)
                && expected.iter().all(|name| {
                    now.iter()
                        .find(|(n, _)| n == name)
                        .is_some_and(|(_, b)| b != b"old")
                });
            assert!(
                as_before || is_complete,
                "{args:?} stopped at {at:?}: left {:?}",
                now.iter().map(|(n, _)| n).collect::<Vec<_>>()
            );
            assert!(
                std::fs::read_dir(root.path()).unwrap().all(|e| !e
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .starts_with('.')),
                "a temporary left beside the output"
            );
            if is_complete {
                restore();
            }
        }
    }
}

/// A signal in the first milliseconds of `simulate --out`, while the staging directory is made
/// and registered and the signal handler's thread runs beside the working one, leaves no
/// temporary behind. Before the registry's lock covered both making and registering, about 1
/// in 200 such stops left the staging directory (6 of 1,200 in a scripted run); 400 stops spread
/// over the first 30 ms would then miss the race with a chance of about (1 - 1/200)^400 = 13 %.
#[test]
fn verification_a_signal_at_start_up_leaves_no_temporary() {
    let (_cache, cache_dir) = small_rom_cache();
    let out = tempfile::tempdir().unwrap();
    std::fs::write(out.path().join("keep.txt"), "a file of the user's").unwrap();
    let before = snapshot(out.path());
    for k in 0..400u32 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_linercav"))
            .args(["simulate", SMALL, "--cache-dir", &cache_dir, "--out"])
            .arg(out.path())
            .env("OPENBLAS_NUM_THREADS", "1")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_micros(75 * u64::from(k)));
        // SAFETY: kill(2) on our own child's pid
        unsafe {
            libc::kill(child.id() as i32, libc::SIGTERM);
        }
        child.wait().unwrap();
        let now = snapshot(out.path());
        assert!(
            now.iter().all(|(n, _)| !n.starts_with('.')),
            "stopped after {} us: left {:?}",
            75 * k,
            now.iter().map(|(n, _)| n).collect::<Vec<_>>()
        );
        if now != before {
            // the run completed before the signal: back to the user's state
            for (n, _) in &now {
                if n != "keep.txt" {
                    std::fs::remove_file(out.path().join(n)).unwrap();
                }
            }
        }
    }
}

fn fixture_text(p: &str) -> String {
    std::fs::read_to_string(p).unwrap()
}

/// A hostile value for a number in a file or a scene.
fn hostile_number() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("-1".to_string()),
        Just("0".to_string()),
        Just("9223372036854775807".to_string()),
        Just("18446744073709551616".to_string()),
        Just("1e308".to_string()),
        Just("-1e308".to_string()),
        Just("1e-308".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("x".to_string()),
        Just(String::new()),
        (-1e6f64..1e6).prop_map(|v| format!("{v}")),
        (0u64..100_000).prop_map(|v| v.to_string()),
    ]
}

/// A mutation of a text: replace a word, delete, duplicate or truncate a line, or insert
/// bytes.
#[derive(Clone, Debug)]
enum Mutation {
    Word(usize, usize, String),
    Delete(usize),
    Duplicate(usize),
    Truncate(usize),
    Insert(usize, String),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), any::<usize>(), hostile_number())
            .prop_map(|(l, w, v)| Mutation::Word(l, w, v)),
        1 => any::<usize>().prop_map(Mutation::Delete),
        1 => any::<usize>().prop_map(Mutation::Duplicate),
        1 => any::<usize>().prop_map(Mutation::Truncate),
        1 => (any::<usize>(), "[ -~]{0,12}").prop_map(|(l, s)| Mutation::Insert(l, s)),
    ]
}

fn apply(text: &str, muts: &[Mutation]) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    for m in muts {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match m {
            Mutation::Word(l, w, v) => {
                let mut words: Vec<String> =
                    lines[l % n].split_whitespace().map(String::from).collect();
                if !words.is_empty() {
                    let k = w % words.len();
                    words[k] = v.clone();
                    lines[l % n] = words.join(" ");
                }
            }
            Mutation::Delete(l) => {
                lines.remove(l % n);
            }
            Mutation::Duplicate(l) => {
                let d = lines[l % n].clone();
                lines.insert(l % n, d);
            }
            Mutation::Truncate(l) => lines.truncate(l % n),
            Mutation::Insert(l, s) => lines.insert(l % n, s.clone()),
        }
    }
    lines.join("\n")
}

/// Each case must finish within this time: the fixture parses in milliseconds, so seconds
/// mean a runaway (a huge count honoured, a loop that does not end).
const CASE_LIMIT: Duration = Duration::from_secs(5);

/// Runs one fuzz case on its own thread and waits at most [`CASE_LIMIT`] for it: a case that
/// runs away fails the test instead of hanging it (its thread is left behind), a case that
/// panics fails it, and a case's own check (`Err(message)`) fails it with the message.
fn bounded(
    case: impl FnOnce() -> Result<(), String> + Send + 'static,
) -> Result<(), proptest::test_runner::TestCaseError> {
    use proptest::test_runner::TestCaseError;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(case());
    });
    match rx.recv_timeout(CASE_LIMIT) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(msg)) => Err(TestCaseError::fail(msg)),
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => Err(TestCaseError::fail(format!(
            "the case ran past {CASE_LIMIT:?}"
        ))),
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            Err(TestCaseError::fail("the case panicked"))
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    /// Fuzz (400 cases): mutated Gmsh files are read and checked (`gmsh::parse`, then the
    /// mesh checks) without a panic and in bounded time.
    #[test]
    fn fuzz_mutated_gmsh_files_never_panic(muts in prop::collection::vec(mutation(), 1..4)) {
        let text = apply(&fixture_text(MESH), &muts);
        bounded(move || {
            if let Ok(mut mesh) = linercav::mesh::gmsh::parse(Path::new("fuzz.msh"), &text) {
                let _ = linercav::fem::element::check_mesh(&mut mesh);
            }
            Ok(())
        })?;
    }

    /// Fuzz (400 cases each): mutated Nastran and Abaqus decks (meshio-written fixtures) are
    /// read and checked without a panic and in bounded time.
    #[test]
    fn fuzz_mutated_nastran_and_abaqus_decks_never_panic(
        muts in prop::collection::vec(mutation(), 1..4)
    ) {
        for (file, nastran) in [
            ("tests/fixtures/block_hex20.bdf", true),
            ("tests/fixtures/block_hex20_free.nas", true),
            ("tests/fixtures/block_hex20.inp", false),
        ] {
            let text = apply(&fixture_text(file), &muts);
            bounded(move || {
                let read = if nastran {
                    linercav::mesh::nastran::parse(Path::new(file), &text)
                } else {
                    linercav::mesh::abaqus::parse(Path::new(file), &text)
                };
                if let Ok(mut mesh) = read {
                    let _ = linercav::fem::element::check_mesh(&mut mesh);
                }
                Ok(())
            })?;
        }
    }

    /// Fuzz (400 cases): a hostile value at a random place of the small engine's scene is
    /// refused or accepted by the loader, and the size estimates of what it accepts are
    /// finite, without a panic.
    #[test]
    fn fuzz_mutated_scenes_never_panic(muts in prop::collection::vec(mutation(), 1..3)) {
        let text = apply(&fixture_text(SMALL), &muts);
        bounded(move || {
            let path = Path::new(SMALL);
            if let Ok(sc) = linercav::scene::Scene::from_str_with(path, &text, &[]) {
                use linercav::scene::budget;
                for e in [budget::rom_build(&sc, budget::Split::of(&sc)), budget::transient(&sc)].into_iter().flatten() {
                    if e.memory.is_nan() || e.seconds.is_nan() {
                        return Err(format!("an estimate is not a number: {e:?}"));
                    }
                    let _ = budget::Limits::of(&sc).check(&sc, &e);
                }
            }
            Ok(())
        })?;
    }

    /// Fuzz (400 cases): mutated pressure curves and rig data CSVs never panic; each is read
    /// (a pressure curve finite and positive over the cycle) or refused naming its file, within
    /// the case limit.
    #[test]
    fn fuzz_mutated_csvs_never_panic(muts in prop::collection::vec(mutation(), 1..4)) {
        let pressure: String = std::iter::once("crank_angle_deg,pressure_bar".to_string())
            .chain((0..72).map(|k| format!("{},{}", k * 10, 1.0 + (k as f64 * 0.3).sin().abs() * 50.0)))
            .collect::<Vec<_>>()
            .join("\n");
        let comma = |s: String| s.replace(' ', ",");
        let p_text = comma(apply(&pressure.replace(',', " "), &muts));
        let rig: String = std::iter::once("time_s,acceleration_m_s2,pressure_kpa".to_string())
            .chain((0..200).map(|k| format!("{},{},{}", k as f64 * 1e-4, (k as f64).sin() * 500.0, 150.0 + (k as f64).cos())))
            .collect::<Vec<_>>()
            .join("\n");
        let r_text = comma(apply(&rig.replace(',', " "), &muts));
        bounded(move || {
            match linercav::piston::pressure::PressureCurve::parse(Path::new("p.csv"), &p_text) {
                // a table read is a usable curve: finite and positive everywhere
                Ok(c) => {
                    let usable = (0..72).map(|k| c.at(10.0 * k as f64 + 5.0)).all(|p| p.is_finite() && p > 0.0);
                    if !usable {
                        return Err("a curve read that is not finite and positive".into());
                    }
                }
                // a refusal names the file
                Err(e) if !e.to_string().contains("p.csv") => return Err(e.to_string()),
                Err(_) => {}
            }
            match linercav::cavitation::calibration::RigData::parse("r.csv", &r_text) {
                Err(e) if !e.to_string().contains("r.csv") => Err(e.to_string()),
                _ => Ok(()),
            }
        })?;
    }
}

/// Keys of the small engine's scene that do not change the ROM (so each run reuses the cached
/// one), with their values there.
const RUN_KEYS: [(&str, f64); 24] = [
    ("engine.speed_rpm", 1900.0),
    ("piston.mass_kg", 2.6),
    ("piston.pin_mass_kg", 0.9),
    ("piston.tilt_inertia_kg_m2", 4.0e-3),
    ("piston.cg_above_pin_mm", 12.0),
    ("piston.pin_offset_mm", 0.0),
    ("piston.compression_height_mm", 72.0),
    ("piston.skirt_length_mm", 65.0),
    ("piston.pin_below_skirt_top_mm", 20.0),
    ("piston.clearance_um", 80.0),
    ("piston.barrel_um", 12.0),
    ("piston.ovality_um", 30.0),
    ("piston.contact_stiffness_n_per_m", 3.0e8),
    ("piston.contact_damping_n_s_per_m", 3000.0),
    ("piston.thermal.skirt_top_temp_c", 150.0),
    ("operating.load", 1.0),
    ("operating.combustion.intake_bar", 2.8),
    ("operating.combustion.start_deg", 353.0),
    ("operating.combustion.heat_release_j", 5800.0),
    ("operating.combustion.polytropic", 1.35),
    ("transient.step_deg", 0.25),
    ("transient.damping_ratio", 0.02),
    ("transient.max_penetration_um", 50.0),
    ("cavitation.gap_mm", 4.0),
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// Fuzz through the whole `simulate` command (24 cases, a few seconds each): a key scaled
    /// by a hostile factor exits 0 with its JSON, or 2 / 1 with one message, never a panic
    /// and within a minute (the small engine's run takes about a second).
    #[test]
    fn fuzz_simulate_with_hostile_values_exits_cleanly(
        key in 0..RUN_KEYS.len(),
        factor in prop_oneof![Just(0.0), Just(-1.0), Just(1e-3), Just(0.5), Just(2.0), Just(10.0), Just(1e3), Just(1e300)],
    ) {
        static CACHE: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
        let cache = CACHE.get_or_init(|| tempfile::tempdir().unwrap());
        let (name, base) = RUN_KEYS[key];
        let set = format!("{name}={}", if base == 0.0 { factor } else { base * factor });
        let t = Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_linercav"))
            .args(["simulate", SMALL, "--json", "--cache-dir", cache.path().to_str().unwrap(), "--set", &set])
            .env("OPENBLAS_NUM_THREADS", "1")
            .output()
            .unwrap();
        let code = out.status.code();
        let err = String::from_utf8_lossy(&out.stderr);
        prop_assert!(matches!(code, Some(0..=2)), "{set}: {code:?} {err}");
        prop_assert!(!err.contains("panicked"), "{set}: {err}");
        if code == Some(0) {
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
            prop_assert!(v["cylinders"].as_array().is_some_and(|c| !c.is_empty()), "{set}");
        } else {
            prop_assert!(err.contains("error: ") && out.stdout.is_empty(), "{set}: {err}");
        }
        prop_assert!(t.elapsed() < Duration::from_secs(60), "{set}: {:?}", t.elapsed());
    }
}

/// Regression (found by the fuzz above): at twice the rated speed the output filter spans
/// more crank angle than the step-error window held, and the window's peak panicked on an
/// empty slice; the window now widens and the run completes with its estimate.
#[test]
fn regression_step_error_window_at_high_speed() {
    let cache = tempfile::tempdir().unwrap();
    let (code, out, err) = linercav(&[
        "simulate",
        SMALL,
        "--json",
        "--cache-dir",
        cache.path().to_str().unwrap(),
        "--set",
        "engine.speed_rpm=3800",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let e = v["stats"]["step_error_estimate"].as_f64().unwrap();
    assert!(e.is_finite() && e > 0.0, "estimate {e}");
}

/// Doubtful values are warned about, not refused, and the default scene has none: a clearance
/// worn past 0.5 % of the bore; a pin offset beyond 5 % of it; an average that takes in the first cycle, which starts from
/// rest (a one-cycle run has no other and is not warned about); a cut enrichment on a
/// crankcase in one piece; fewer than 20 shapes per cut between components; a piston whose
/// mass, tilt inertia or contact damping lies outside what pistons of its bore have.
#[test]
fn contract_doubtful_values_are_warned_about() {
    use linercav::scene::Scene;
    let warnings = |sets: &[&str]| -> Vec<String> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        Scene::load(Path::new("models/engine.toml"), &sets)
            .unwrap()
            .warnings
    };
    assert!(warnings(&[]).is_empty(), "{:?}", warnings(&[]));
    let wide = warnings(&["piston.clearance_um=700"]);
    assert!(
        wide.iter().any(|w| w.contains("piston.clearance_um")),
        "{wide:?}"
    );
    assert!(warnings(&["piston.clearance_um=500"]).is_empty());
    let offset = warnings(&["piston.pin_offset_mm=10"]);
    assert!(
        offset.iter().any(|w| w.contains("piston.pin_offset_mm")),
        "{offset:?}"
    );
    assert!(warnings(&["piston.pin_offset_mm=-1"]).is_empty());
    let all = warnings(&["transient.cycles=21", "transient.averaged_cycles=21"]);
    assert!(
        all.iter().any(|w| w.contains("transient.averaged_cycles")),
        "{all:?}"
    );
    assert!(warnings(&["transient.cycles=1", "transient.averaged_cycles=1"]).is_empty());
    // an enrichment of cuts that a one-piece crankcase does not have is said to do nothing
    let ignored = warnings(&["rom.cut_enrichment=100"]);
    assert!(
        ignored.iter().any(|w| w.contains("rom.cut_enrichment")),
        "{ignored:?}"
    );
    assert!(warnings(&["rom.cut_enrichment=100", "rom.crankcase_components=3"]).is_empty());
    // few shapes per cut: percent-level coupling error (session 78: 6 was accepted silently)
    let few = warnings(&["rom.crankcase_components=2", "rom.cut_shapes=6"]);
    assert!(few.iter().any(|w| w.contains("rom.cut_shapes")), "{few:?}");
    assert!(warnings(&["rom.crankcase_components=2", "rom.cut_shapes=20"]).is_empty());
    assert!(warnings(&["rom.cut_shapes=6"]).is_empty());
    // a piston light, wobbly or glued for its bore (session 78)
    for (set, key) in [
        ("piston.mass_kg=0.2", "piston.mass_kg"),
        ("piston.tilt_inertia_kg_m2=0.5", "piston.tilt_inertia_kg_m2"),
        (
            "piston.contact_damping_n_s_per_m=3e6",
            "piston.contact_damping_n_s_per_m",
        ),
    ] {
        let w = warnings(&[set]);
        assert!(w.iter().any(|w| w.contains(key)), "{set}: {w:?}");
    }
}

/// Regression (issue 40, found in session 38): under an address-space limit as a batch
/// scheduler sets one (RLIMIT_AS 2 GB), the default engine's ROM build (estimated 3.8 GB) aborted
/// in an allocation; it is refused up front, exit 2, naming the estimate.
#[test]
fn regression_an_address_space_limit_is_respected() {
    let o = under_address_space_cap(2_000_000_000, &["rom", "models/engine.toml", "--no-cache"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("needs about") && err.contains("GB"), "{err}");
}

/// Regression (session 59): a run the memory check lets through under an address-space cap
/// completes. The default liner's `modes` (estimate 0.74 GB) fits a 2.1 GB cap by the rule
/// (768 MiB of headroom + 1.25 times the estimate: `machine::address_space_left`). Under that
/// cap the old rule refused it, and without the allocator fitted to the cap it mapped
/// 1.98 GB; now 1.55 GB.
#[test]
fn regression_a_run_let_through_under_an_address_space_cap_completes() {
    let args = [
        "modes",
        "models/engine.toml",
        "--part",
        "liner",
        "--count",
        "20",
    ];
    let o = under_address_space_cap(2_100_000_000, &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("no mode missed"));
}

/// Regression (session 70's hostile sweep): a mesh file was read whole before any memory
/// check, so a 2 GB deck under a 1 GB address-space cap aborted in its allocation (exit 134);
/// it is refused before it is read, exit 2, with what reading it takes.
#[test]
fn regression_a_mesh_file_larger_than_memory_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["big.bdf", "big.inp", "big.msh"] {
        let p = dir.path().join(name);
        // a sparse file: no disk used
        std::fs::File::create(&p).unwrap().set_len(2 << 30).unwrap();
        let mut args = vec!["modes", "--count", "3", "--mesh", p.to_str().unwrap()];
        args.extend(STEEL);
        let o = under_limit((libc::RLIMIT_AS, 1_000_000_000), &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains("reading it takes about"), "{name}: {err}");
    }
}

/// Regression (session 70's hostile sweep): a write beyond the file-size limit (`ulimit -f`)
/// killed the process by SIGXFSZ and left the temporary file; the write now fails as an
/// error naming the output, exit 2, and nothing is left.
#[test]
fn regression_a_file_size_limit_leaves_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("liner.inp");
    let args = [
        "export-mesh",
        SMALL,
        "--part",
        "liner",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = under_limit((libc::RLIMIT_FSIZE, 100_000), &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("liner.inp") && err.contains("cannot write"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Runs the command line `args` with RLIMIT_AS set to `cap` bytes.
fn under_address_space_cap(cap: u64, args: &[&str]) -> std::process::Output {
    under_limit((libc::RLIMIT_AS, cap), args)
}

/// Runs the command line `args` with the resource limit `resource` set to `cap`.
fn under_limit(
    (resource, cap): (libc::__rlimit_resource_t, u64),
    args: &[&str],
) -> std::process::Output {
    use std::os::unix::process::CommandExt;
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_linercav"));
    c.args(args);
    // SAFETY: setrlimit is async-signal-safe; the struct lives for the call
    unsafe {
        c.pre_exec(move || {
            let r = libc::rlimit {
                rlim_cur: cap,
                rlim_max: cap,
            };
            if libc::setrlimit(resource, &r) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    c.output().unwrap()
}

/// Regression (session 74's hostile sweep): `calibrate --png /dev/null` replaced the device
/// with a PNG file (and a FIFO given to `export-mesh --out` became a regular file); an output
/// path naming the run's own input (`--vtu mesh.inp`, `--png data.csv`) overwrote the input;
/// a full standard output (`> /dev/full`) panicked with 101. Now each exits 2 naming the
/// path, and the device, pipe or input is left as it was.
#[test]
fn regression_outputs_never_replace_a_device_a_pipe_or_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = |n: &str| d.join(n).to_str().unwrap().to_string();
    let fifo = path("pipe.msh");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let mesh = path("copy.msh");
    std::fs::copy(MESH, &mesh).unwrap();
    let data = path("rig.csv");
    std::fs::write(&data, "time_s,acceleration_m_s2,pressure_kpa\n").unwrap();
    let calibrate = |png: &str| {
        let mut a = vec!["calibrate", "--data", &data, "--gap-mm", "4.7"];
        a.extend(["--static-kpa", "240", "--temp-c", "90", "--png", png]);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let on_mesh = |command: &str, input: &str, rest: &[&str]| {
        let mut a = vec![command, "--mesh", input];
        a.extend(STEEL);
        a.extend(rest);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let export = |input: &str, out: &str| on_mesh("export-mesh", input, &["--out", out]);
    let vtu = on_mesh("modes", &mesh, &["--count", "6", "--vtu", &mesh]);
    let cases: [(Vec<String>, &str, &str); 5] = [
        (export(MESH, &fifo), &fifo, "exists and is not a file"),
        (export(&mesh, &mesh), &mesh, "is the input"),
        (vtu, &mesh, "is the input"),
        (calibrate(&data), &data, "is the input"),
        (
            calibrate("/dev/null"),
            "/dev/null",
            "exists and is not a file",
        ),
    ];
    let before = std::fs::read(&mesh).unwrap();
    for (args, target, says) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = linercav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains(target) && err.contains(says),
            "{args:?}: {err}"
        );
    }
    use std::os::unix::fs::FileTypeExt;
    let kind = |p: &str| std::fs::metadata(p).unwrap().file_type();
    assert!(kind(&fifo).is_fifo() && kind("/dev/null").is_char_device());
    assert_eq!(std::fs::read(&mesh).unwrap(), before);
    assert!(std::fs::read_to_string(&data)
        .unwrap()
        .starts_with("time_s"));
    // a full standard output is an error naming it (exit 2), not a panic
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_linercav"))
        .args(["coolant", "--temp-c", "90", "--static-kpa", "240"])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("standard output: cannot write"), "{err}");
}
