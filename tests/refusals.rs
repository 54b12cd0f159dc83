//! Regression tests of the hostile-input findings of issue 40 (tried as a new user would):
//! silent successes now refused, leftovers now removed, late refusals now made before any
//! work, unclear messages now naming the file, key or flag and what was expected. Each exits
//! 2 (bad input) or 1 (numerical failure) with one message and nothing on stdout.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

mod common;
use common::{linercav, refused};

const SMALL: &str = "tests/fixtures/engine_small.toml";

/// A cache directory holding the small engine's ROM.
fn small_rom_cache() -> (tempfile::TempDir, String) {
    let cache = tempfile::tempdir().unwrap();
    let dir = cache.path().to_str().unwrap().to_string();
    let (c, _, err) = linercav(&["rom", SMALL, "--cache-dir", &dir]);
    assert_eq!(c, 0, "{err}");
    (cache, dir)
}

/// Regression: `--set K` was dropped without a word when `--vary K` named the same key.
#[test]
fn regression_a_fixed_key_that_the_design_varies_is_refused() {
    refused(
        &[
            "sweep",
            SMALL,
            "--vary",
            "piston.clearance_um=60,100",
            "--set",
            "piston.clearance_um=80",
        ],
        2,
        "--set 'piston.clearance_um=80'",
    );
}

/// Regression: a pressure table covering 0-99 deg, or one revolution (0-360 deg) of the
/// four-stroke cycle, was read as a periodic 720 deg curve (motored peaks, exit 0).
#[test]
fn regression_a_pressure_table_that_does_not_cover_the_cycle_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (name, last) in [("partial.csv", 99), ("one_revolution.csv", 360)] {
        let rows: String = (0..=last)
            .step_by(3)
            .map(|a| {
                format!(
                    "{a},{}\n",
                    1.0 + 150.0 * (-(f64::from(a) - 360.0).powi(2) / 800.0).exp()
                )
            })
            .collect();
        let p = dir.path().join(name);
        std::fs::write(&p, format!("crank_angle_deg,pressure_bar\n{rows}")).unwrap();
        let set = format!("operating.pressure_file={}", toml_string(&p));
        let err = refused(&["simulate", SMALL, "--set", &set], 2, name);
        assert!(err.contains("whole 0-720 deg"), "{err}");
    }
}

/// Regression: a pressure row's crank angle beyond the cycle was printed in full (1e300 as
/// 301 digits); it is printed as read, short, and not rounded onto the bound (720.0004, which
/// four significant digits would print as the bound itself).
#[test]
fn regression_a_pressure_rows_angle_is_printed_as_read() {
    let dir = tempfile::tempdir().unwrap();
    for (angle, shown) in [("720.0004", "720.0004 deg"), ("1e300", "1e300 deg")] {
        let p = dir.path().join("angle.csv");
        std::fs::write(
            &p,
            format!("crank_angle_deg,pressure_bar\n0,1\n360,150\n{angle},1\n"),
        )
        .unwrap();
        let set = format!("operating.pressure_file={}", toml_string(&p));
        let err = refused(&["simulate", SMALL, "--set", &set], 2, shown);
        assert!(err.contains("line 4") && err.len() < 600, "{err}");
    }
}

/// Regression: `sweep --refine` over an interval narrower than it tells runs apart
/// (40:40.00000000000003) ran 3 of 9 runs without a word; it is refused before any run.
#[test]
fn regression_a_refinement_too_narrow_for_its_runs_is_refused() {
    let err = refused(
        &[
            "sweep",
            SMALL,
            "--refine",
            "piston.clearance_um=40:40.00000000000003",
            "--runs",
            "9",
        ],
        2,
        "--refine",
    );
    assert!(err.contains("too narrow"), "{err}");
}

/// Regression: `sweep --refine piston.slices=10:12 --runs 5` (a key of whole numbers) ran
/// the first batch and then failed at its first midpoint, 11.5; it is refused before any run,
/// naming the key, the value it cannot take and `--vary`, and no output directory is made.
#[test]
fn regression_a_refinement_of_a_whole_number_key_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("refined");
    let err = refused(
        &[
            "sweep",
            SMALL,
            "--refine",
            "piston.slices=10:12",
            "--runs",
            "5",
            "--out",
            out.to_str().unwrap(),
        ],
        2,
        "--refine",
    );
    assert!(
        err.contains("piston.slices") && err.contains("whole number") && err.contains("--vary"),
        "{err}"
    );
    assert!(!out.exists());
}

/// A path as a TOML string literal.
fn toml_string(p: &Path) -> String {
    format!("\"{}\"", p.display())
}

/// Regression: `transient.mode_cutoff_hz = 1` integrated no mode and said nothing.
#[test]
fn regression_a_mode_cutoff_below_every_mode_is_refused() {
    let (_cache, dir) = small_rom_cache();
    for cmd in [
        vec!["simulate", SMALL],
        vec!["sweep", SMALL, "--vary", "piston.clearance_um=60,100"],
    ] {
        let mut args = cmd.clone();
        args.extend_from_slice(&["--cache-dir", &dir, "--set", "transient.mode_cutoff_hz=1"]);
        refused(&args, 2, "transient.mode_cutoff_hz");
    }
}

/// Regression: `--range operating.load=1e308:1.7e308` gave "invalid type: string" (the sampled
/// value was printed as a 309-digit integer); the key's own check now speaks.
#[test]
fn regression_a_huge_sampled_value_reaches_the_key_check() {
    let err = refused(
        &[
            "sweep",
            SMALL,
            "--sample",
            "mc:2",
            "--range",
            "operating.load=1e308:1.7e308",
        ],
        2,
        "operating.load",
    );
    assert!(!err.contains("invalid type"), "{err}");
}

/// Regression: `max_penetration_um = 1e-9` failed with "0.0 um > 0.0 um", then (with its
/// digits) as a numerical failure (exit 1) with a hint on the contact stiffness. A limit far
/// below the contact's penetrations is now refused up front, naming the key (exit 2); a
/// small legal one still stops the run with its digits.
#[test]
fn regression_a_tiny_penetration_limit_is_printed_with_its_digits() {
    let (_cache, dir) = small_rom_cache();
    let args = |v: &str| {
        [
            "simulate".to_string(),
            SMALL.into(),
            "--cache-dir".into(),
            dir.clone(),
            "--set".into(),
            format!("transient.max_penetration_um={v}"),
        ]
    };
    let a = args("1e-9");
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let err = refused(&a, 2, "transient.max_penetration_um");
    assert!(err.contains("at least 0.1 um"), "{err}");
    let a = args("0.1");
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let err = refused(&a, 1, "deep penetration");
    assert!(err.contains("> 0.1 um"), "{err}");
}

/// Regression: an empty `operating.pressure_file` or `cavitation.calibration_file` failed as
/// "small/: cannot read the pressure file: not a regular file", and an empty `rom.cache_dir`
/// put the ROM cache into the scene's own directory without a word. Each is refused naming
/// its key.
#[test]
fn regression_empty_path_keys_are_refused_naming_the_key() {
    for key in [
        "operating.pressure_file",
        "cavitation.calibration_file",
        "rom.cache_dir",
    ] {
        let set = format!("{key}=\"\"");
        let err = refused(&["simulate", SMALL, "--set", &set], 2, key);
        assert!(err.contains("is empty"), "{key}: {err}");
    }
}

/// Regression: `modes --assembly --full` with `crankcase.mesh.per_sector = 2000` built the
/// engine's FE model with no estimate (exit 134 in an allocation after 22 s under a 6 GB
/// cap), and `export-mesh` of a liner with `radial = 100000` ran on at many GB; both are
/// now sized first and refused (exit 2) naming the estimate and the keys.
#[test]
fn regression_the_full_engine_and_exported_meshes_are_sized_before_they_are_made() {
    let out = tempfile::tempdir().unwrap();
    let msh = out.path().join("liner.msh");
    for args in [
        vec![
            "modes",
            SMALL,
            "--assembly",
            "--full",
            "--count",
            "5",
            "--set",
            "crankcase.mesh.per_sector=2000",
        ],
        vec![
            "export-mesh",
            SMALL,
            "--part",
            "liner",
            "--out",
            msh.to_str().unwrap(),
            "--set",
            "liner.mesh.radial=100000",
        ],
    ] {
        let err = refused(&args, 2, "needs about");
        assert!(err.contains(".mesh"), "{args:?}: {err}");
    }
    assert!(!msh.exists());
}

/// Regression: the full-order window steps at the slap sub-step, so its time grows with
/// `transient.slap_substeps`; it was sized by its model alone. The default engine's window at
/// 64 sub-steps (23,040 steps of one factor solve, about 2.4 h on the 2-core machine) under
/// `limits.max_hours = 1` is refused before any work (exit 2), naming the step's keys.
#[test]
fn regression_the_full_order_windows_stepping_is_held_to_the_time_limit() {
    let args = [
        "simulate",
        "models/engine.toml",
        "--full-order",
        "--set",
        "transient.slap_substeps=64",
        "--set",
        "limits.max_hours=1",
    ];
    let err = refused(&args, 2, "limits.max_hours");
    assert!(err.contains("transient.slap_substeps"), "{err}");
}

/// `modes` of the small engine's liner read from the hex20 fixture under
/// `limits.max_memory_gb` = `gb`: (exit code, stdout, stderr).
fn modes_of_the_liner_fixture(gb: &str) -> (i32, String, String) {
    linercav(&[
        "modes",
        SMALL,
        "--part",
        "liner",
        "--count",
        "5",
        "--set",
        "liner.mesh_file=liner_hex20.msh",
        "--set",
        &format!("limits.max_memory_gb={gb}"),
    ])
}

/// Regression: `modes SCENE --part liner` with the liner from a mesh file ignored the scene's
/// `limits.max_memory_gb` (the machine's limit was checked); the scene's own limit now holds.
#[test]
fn regression_a_scene_mesh_file_is_held_to_the_scene_limits() {
    let (code, out, err) = modes_of_the_liner_fixture("1e-9");
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("limits.max_memory_gb allows"), "{err}");
    assert!(err.contains("liner_hex20.msh"), "{err}");
}

/// Regression: `modes` on a mesh file was held to the ROM build's memory scaled by DOFs (13 GB
/// for the 754k-DOF tet4 casting, which peaks at 4.8 GB), so a machine with 8-12 GB free
/// refused it. Now the assembly is checked before it starts and the solve once the factor's
/// size is known: a limit the assembly fits but the solve does not is refused naming the
/// factor's entries, before the factorisation; a limit above the solve's need runs.
#[test]
fn regression_the_modal_solve_is_held_to_its_factor_size() {
    let run = modes_of_the_liner_fixture;
    // the fixture's assembly is estimated at 0.019 GB and its solve at 0.088 GB
    let (code, out, err) = run("0.06");
    assert_eq!(code, 2, "{out}{err}");
    for part in [
        "liner_hex20.msh",
        "the modal solve",
        "factor entries",
        "allows 0.06 GB",
    ] {
        assert!(err.contains(part), "{part}: {err}");
    }
    let (code, _, err) = run("0.2");
    assert_eq!(code, 0, "{err}");
}

/// Regression: `--set` beside `--mesh` was dropped without a word, so a refusal's advice to
/// raise `limits.max_memory_gb` could not be followed for a bare mesh. The limits keys now
/// apply; any other key, or a value that is not a positive number, is refused naming it.
#[test]
fn regression_set_beside_a_bare_mesh_is_applied_or_refused() {
    let run = |set: &str| {
        linercav(&[
            "modes",
            "--mesh",
            "tests/fixtures/liner_hex20.msh",
            "--youngs",
            "1.4e11",
            "--poisson",
            "0.26",
            "--density",
            "7200",
            "--count",
            "5",
            "--set",
            set,
        ])
    };
    // (the override, what the message says, what it names)
    for (set, expected, named) in [
        (
            "limits.max_memory_gb=0.01",
            "limits.max_memory_gb allows 0.01 GB",
            "liner_hex20.msh",
        ),
        (
            "limits.max_hours=-1",
            "expected a positive number",
            "--set limits.max_hours=-1",
        ),
        (
            "liner.mesh.radial=3",
            "with --mesh only limits.max_memory_gb",
            "--set liner.mesh.radial=3",
        ),
    ] {
        let (code, out, err) = run(set);
        assert_eq!(code, 2, "{set}: {out}{err}");
        assert!(
            err.contains(expected) && err.contains(named),
            "{set}: {err}"
        );
    }
    let (code, _, err) = run("limits.max_memory_gb=1");
    assert_eq!(code, 0, "{err}");
}

/// Regression: a report into a directory holding `summary.md/` (a directory) ran to the end
/// (minutes) and only then exited 2. Now refused before any work: the empty cache stays empty.
#[test]
fn regression_an_output_name_taken_by_a_directory_is_found_before_any_work() {
    let cache = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    std::fs::create_dir(out.path().join("summary.md")).unwrap();
    for cmd in ["report", "simulate", "sweep"] {
        let mut args = vec![cmd, SMALL];
        if cmd == "sweep" {
            std::fs::create_dir_all(out.path().join("sweep_piston_clearance_um.png")).unwrap();
            args.extend_from_slice(&["--vary", "piston.clearance_um=60,100"]);
        }
        if cmd == "simulate" {
            std::fs::create_dir_all(out.path().join("time_series.csv")).unwrap();
        }
        args.extend_from_slice(&[
            "--cache-dir",
            cache.path().to_str().unwrap(),
            "--out",
            out.path().to_str().unwrap(),
        ]);
        refused(&args, 2, "is not a file");
        assert_eq!(
            std::fs::read_dir(cache.path()).unwrap().count(),
            0,
            "{cmd}: work started before the refusal"
        );
    }
    // a shard's part name taken by a directory: refused before its runs (it was found only
    // after them, as "Is a directory (os error 21)")
    std::fs::create_dir(out.path().join("part-00001-of-00002.json")).unwrap();
    refused(
        &[
            "sweep",
            SMALL,
            "--vary",
            "piston.clearance_um=60,100",
            "--shard",
            "1/2",
            "--cache-dir",
            cache.path().to_str().unwrap(),
            "--out",
            out.path().to_str().unwrap(),
        ],
        2,
        "part-00001-of-00002.json",
    );
    assert_eq!(std::fs::read_dir(cache.path()).unwrap().count(), 0);
}

/// Regression (session 75's sweep): a sharded sweep checked only its own runs' values, so the
/// shard without the bad run exited 0 and the bad value surfaced in the other shard only (the
/// merge then lacked a part). Every shard now refuses it before its own runs, as the whole
/// sweep does, naming the key, with no ROM built.
#[test]
fn regression_every_shard_refuses_a_bad_value_in_any_shards_runs() {
    for shard in ["1/2", "2/2"] {
        let cache = tempfile::tempdir().unwrap();
        let out = tempfile::tempdir().unwrap();
        refused(
            &[
                "sweep",
                SMALL,
                "--vary",
                "piston.clearance_um=60,-5",
                "--shard",
                shard,
                "--cache-dir",
                cache.path().to_str().unwrap(),
                "--out",
                out.path().to_str().unwrap(),
            ],
            2,
            "piston.clearance_um",
        );
        assert_eq!(std::fs::read_dir(cache.path()).unwrap().count(), 0);
    }
}

/// Regression: a shard run that failed, or was stopped by SIGTERM, left its (new) part
/// directory behind, empty.
#[test]
fn regression_a_failed_or_stopped_shard_leaves_no_empty_part_directory() {
    let (_cache, dir) = small_rom_cache();
    let root = tempfile::tempdir().unwrap();
    let parts = root.path().join("new").join("parts");
    let args = |extra: &[&str]| {
        let mut a: Vec<String> = [
            "sweep",
            SMALL,
            "--vary",
            "piston.clearance_um=60,65,70,75,80,85,90,95,100,105,110,115",
            "--shard",
            "1/2",
            "--cache-dir",
            &dir,
            "--out",
            parts.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    // a numerical failure in the run (exit 1)
    let a = args(&["--set", "transient.max_penetration_um=0.1"]);
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    refused(&a, 1, "deep penetration");
    assert!(!root.path().join("new").exists(), "a directory left");
    // stopped by SIGTERM while it runs (six runs of the small engine, a second or more)
    let mut child = Command::new(env!("CARGO_BIN_EXE_linercav"))
        .args(args(&[]))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    // SAFETY: kill(2) on our own child's pid
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let status = child.wait().unwrap();
    // 128 + 15, as a shell reports a process SIGTERM ended (a scheduler's cancel)
    assert_eq!(
        status.code(),
        Some(143),
        "the shard finished before the signal"
    );
    assert!(!root.path().join("new").exists(), "a directory left");
}

/// Regression: SIGINT during a ROM build left `rom-<key>.lock` in the cache directory, though
/// the message said the temporary files were removed.
#[test]
fn regression_a_stopped_rom_build_leaves_no_lock_file() {
    let cache = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_linercav"))
        .args(["rom", SMALL, "--cache-dir"])
        .arg(cache.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // the small engine's build takes several seconds; its lock is taken at once
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: kill(2) on our own child's pid
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let status = child.wait().unwrap();
    assert_eq!(
        status.code(),
        Some(130),
        "the build finished before the signal"
    );
    let left: Vec<String> = std::fs::read_dir(cache.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    // complete entries (a part reduced before the signal, stored atomically) may stay
    assert!(
        left.iter()
            .all(|n| n.ends_with(".bin") && !n.starts_with('.') && !n.contains(".tmp")),
        "left in the cache: {left:?}"
    );
}

/// Regression: an inverted tet4 passed the mesh check (its constant Jacobian has the sign of
/// its mean) and failed in the assembly with exit 1, without the file and with a 0-based
/// element index.
#[test]
fn regression_an_inverted_tet4_is_refused_naming_the_file_and_element() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("inverted.bdf");
    // element 2 has its nodes 2 and 3 swapped
    std::fs::write(
        &p,
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nGRID,5,,1.,1.,1.\n\
         CTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,5,4\nPSOLID,1,1\nMAT1,1,2.1e11,,0.3,7850.\nENDDATA\n",
    )
    .unwrap();
    let err = refused(
        &["modes", "--mesh", p.to_str().unwrap(), "--count", "2"],
        2,
        "inverted.bdf",
    );
    // CTETRA 2 is the deck's eighth line
    assert!(
        err.contains("inverted.bdf:8") && err.contains("inverted"),
        "{err}"
    );
}

/// Regression: a flat element was reported as a mid-edge node lying 0.33 edge lengths off, and
/// a hex20 with a corner node given twice as one lying "inf" edge lengths off; both are named
/// degenerate, with what makes them so.
#[test]
fn regression_a_flat_or_collapsed_element_is_named_degenerate() {
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.bdf");
    // element 1's fourth node lies in the plane of the other three
    std::fs::write(
        &flat,
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,1.,1.,0.\nGRID,5,,0.,0.,1.\n\
         CTETRA,1,1,1,2,3,4\nCTETRA,2,1,1,2,3,5\nPSOLID,1,1\nMAT1,1,2.1e11,,0.3,7850.\nENDDATA\n",
    )
    .unwrap();
    let err = refused(
        &["modes", "--mesh", flat.to_str().unwrap(), "--count", "2"],
        2,
        "flat.bdf",
    );
    // CTETRA 1 is the deck's seventh line
    assert!(
        err.contains("flat.bdf:7") && err.contains("no volume"),
        "{err}"
    );
    // the fixture's hex20 #1 with its second corner node replaced by its first
    let text = std::fs::read_to_string("tests/fixtures/block_hex20.inp").unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let at = 1 + lines
        .iter()
        .position(|l| l.starts_with("*ELEMENT"))
        .unwrap();
    let mut ids: Vec<String> = lines[at].split(',').map(str::to_string).collect();
    ids[2] = ids[1].clone();
    lines[at] = ids.join(",");
    let collapsed = dir.path().join("collapsed.inp");
    std::fs::write(&collapsed, lines.join("\n")).unwrap();
    let args = ["--youngs", "210e9", "--poisson", "0.3", "--density", "7850"];
    let mut cmd = vec![
        "modes",
        "--mesh",
        collapsed.to_str().unwrap(),
        "--count",
        "2",
    ];
    cmd.extend(args);
    let err = refused(&cmd, 2, "collapsed.inp");
    // named by its file and line (`at` is the 0-based index of its line), the node by where
    // it is
    assert!(
        err.contains("degenerate")
            && err.contains(&format!("collapsed.inp:{}", at + 1))
            && err.contains(") m is given twice"),
        "{err}"
    );
}

/// Regression: in a deck that mixes element kinds the mesh check counted elements per kind
/// (all tetrahedra, then all hexahedra) and named a bad element by that count as if it were
/// its place in the file; it names the file and line that define it, also in an included
/// file.
#[test]
fn regression_a_bad_element_of_a_mixed_deck_is_named_by_its_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let main = dir.path().join("mixed.bdf");
    // a unit cube (CHEXA 1) with a flat tetrahedron (CTETRA 2, its fourth node in the plane
    // z = 0) in an included file; hexahedra come after tetrahedra in the mesh's own order
    std::fs::write(
        &main,
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,1.,1.,0.\nGRID,4,,0.,1.,0.\n\
         GRID,5,,0.,0.,1.\nGRID,6,,1.,0.,1.\nGRID,7,,1.,1.,1.\nGRID,8,,0.,1.,1.\n\
         CHEXA,1,1,1,2,3,4,5,6,+\n+,7,8\nINCLUDE 'tets.bdf'\nPSOLID,1,1\nMAT1,1,2.1e11,,0.3,7850.\nENDDATA\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("tets.bdf"),
        "$ tetrahedra\nCTETRA,2,1,1,2,3,4\n",
    )
    .unwrap();
    let err = refused(
        &["modes", "--mesh", main.to_str().unwrap(), "--count", "2"],
        2,
        "no volume",
    );
    assert!(err.contains("tets.bdf:2"), "{err}");
    // an element no section reaches is named the same way (it was "number 2, counted in
    // kind order")
    let bare = dir.path().join("bare.inp");
    std::fs::write(
        &bare,
        "*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n5, 1., 1., 1.\n\
         *ELEMENT, TYPE=C3D4, ELSET=A\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D4\n2, 2, 3, 5, 4\n\
         *MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *SOLID SECTION, ELSET=A, MATERIAL=STEEL\n",
    )
    .unwrap();
    let err = refused(
        &["modes", "--mesh", bare.to_str().unwrap(), "--count", "2"],
        2,
        "has no material",
    );
    assert!(err.contains("bare.inp:10"), "{err}");
    // an element of an Abaqus part is defined once for all its instances: the part and
    // instance are named with the line
    let inst = dir.path().join("inst.inp");
    std::fs::write(
        &inst,
        "*PART, NAME=P\n*NODE\n1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 1., 1., 0.\n\
         *ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*END PART\n*ASSEMBLY, NAME=A\n\
         *INSTANCE, NAME=first, PART=P\n*END INSTANCE\n*INSTANCE, NAME=second, PART=P\n0., 0., 5.\n\
         *END INSTANCE\n*END ASSEMBLY\n",
    )
    .unwrap();
    let mut cmd = vec!["modes", "--mesh", inst.to_str().unwrap(), "--count", "2"];
    cmd.extend([
        "--youngs",
        "2.1e11",
        "--poisson",
        "0.3",
        "--density",
        "7850",
    ]);
    let err = refused(&cmd, 2, "no volume");
    assert!(
        err.contains("inst.inp:8 (part 'P', instance 'first')"),
        "{err}"
    );
}

/// Regression (hostile sweep): a Gmsh file with one solid element tag given twice was read as
/// two elements (the Nastran and Abaqus readers refuse such a deck), and a hex8 with two
/// distinct corner nodes at one place was said to have no volume (it has): both are named
/// for what they are.
#[test]
fn regression_a_repeated_element_tag_and_coincident_corners_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let dup = dir.path().join("dup.msh");
    std::fs::write(
        &dup,
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n\
         0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n$Elements\n1 2 1 2\n3 1 4 2\n\
         1 1 2 3 4\n1 2 3 5 4\n$EndElements\n",
    )
    .unwrap();
    let mut cmd = vec!["modes", "--mesh", dup.to_str().unwrap(), "--count", "2"];
    cmd.extend([
        "--youngs",
        "2.1e11",
        "--poisson",
        "0.3",
        "--density",
        "7850",
    ]);
    let err = refused(&cmd, 2, "element tag 1 defined twice");
    assert!(err.contains("dup.msh:22"), "{err}");
    let hex = dir.path().join("hex.bdf");
    // GRID 8 sits on GRID 7
    std::fs::write(
        &hex,
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,1.,1.,0.\nGRID,4,,0.,1.,0.\n\
         GRID,5,,0.,0.,1.\nGRID,6,,1.,0.,1.\nGRID,7,,1.,1.,1.\nGRID,8,,1.,1.,1.\n\
         CHEXA,1,1,1,2,3,4,5,6,+\n+,7,8\nPSOLID,1,1\nMAT1,1,2.1e11,,0.3,7850.\nENDDATA\n",
    )
    .unwrap();
    let err = refused(
        &["modes", "--mesh", hex.to_str().unwrap(), "--count", "2"],
        2,
        "two of its corner nodes are at one place",
    );
    assert!(err.contains("hex.bdf:10"), "{err}");
    // with a flat tetrahedron after it in the file, the hexahedron is still the one named
    // (the mesh groups tetrahedra first; the first bad element in the file is reported)
    let text = std::fs::read_to_string(&hex)
        .unwrap()
        .replace("PSOLID", "GRID,9,,2.,0.,0.\nCTETRA,2,1,1,2,9,3\nPSOLID");
    std::fs::write(&hex, text).unwrap();
    let err = refused(
        &["modes", "--mesh", hex.to_str().unwrap(), "--count", "2"],
        2,
        "two of its corner nodes are at one place",
    );
    assert!(err.contains("hex.bdf:10"), "{err}");
}

/// Regression: a Nastran deck cut short inside a CTETRA card was refused with "element 1 has 6
/// nodes", which did not say why; the message now points at the missing continuation.
#[test]
fn regression_a_deck_cut_inside_a_card_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("tests/fixtures/block_tet10.bdf").unwrap();
    let first = text.find("\nCTETRA").expect("the fixture has CTETRA cards") + 1;
    let end = first + text[first..].find('\n').unwrap();
    let cut = dir.path().join("cut.bdf");
    std::fs::write(&cut, &text[..end]).unwrap();
    let err = refused(
        &["modes", "--mesh", cut.to_str().unwrap(), "--count", "2"],
        2,
        "cut.bdf",
    );
    assert!(err.contains("continuation line missing"), "{err}");
}

/// Regression: parts of two samples with different seeds were refused with a Rust debug dump
/// of the designs; now the designs are printed as their command-line options.
#[test]
fn regression_parts_of_different_seeds_name_the_seed() {
    let (_cache, dir) = small_rom_cache();
    let root = tempfile::tempdir().unwrap();
    for (seed, shard) in [("1", "1/2"), ("2", "2/2")] {
        let out = root.path().join(format!("seed{seed}"));
        let (c, _, err) = linercav(&[
            "sweep",
            SMALL,
            "--sample",
            "mc:2",
            "--range",
            "piston.clearance_um=60:100",
            "--seed",
            seed,
            "--shard",
            shard,
            "--cache-dir",
            &dir,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(c, 0, "{err}");
    }
    let err = refused(
        &[
            "sweep-merge",
            root.path().join("seed1").to_str().unwrap(),
            root.path().join("seed2").to_str().unwrap(),
            "--out",
            root.path().join("merged").to_str().unwrap(),
        ],
        2,
        "--seed 2",
    );
    assert!(!err.contains("Sample {"), "{err}");
}

/// Regression: `modes SCENE --part liner` made any mesh it was given (`liner.mesh.radial =
/// 100000` ran past 60 s at 6-12 GB, and aborted under an address-space cap); the generated
/// mesh is now sized first and refused naming its keys, before anything is allocated.
#[test]
fn regression_a_generated_liner_mesh_is_sized_before_it_is_made() {
    for set in [
        "liner.mesh.radial=100000",
        "liner.mesh.circumferential=9223372036854775804",
        // (1e-6 mm is now refused by the key's range, 0.01 mm and more; 0.02 mm still asks
        // for a lattice far beyond the machine)
        "liner.mesh.axial_size_mm=0.02",
        "liner.mesh.radial_flange=1000000",
    ] {
        let err = refused(
            &[
                "modes", SMALL, "--part", "liner", "--count", "5", "--set", set,
            ],
            2,
            "liner.mesh",
        );
        assert!(
            err.contains("needs about") || err.contains("would take"),
            "{set}: {err}"
        );
    }
}

/// Regression (issue 37's substructuring keys): components beyond the cylinders, no cut
/// shapes or fewer than a cut's six rigid motions, and engine mode shapes on the meshes (`modes --assembly --rom --vtu`) of a
/// substructured crankcase (which keeps no full basis) are refused naming the key (exit 2),
/// the last before any part is reduced and with nothing written.
#[test]
fn regression_substructuring_keys_are_checked() {
    refused(
        &[
            "rom",
            SMALL,
            "--no-cache",
            "--set",
            "rom.crankcase_components=3",
        ],
        2,
        "rom.crankcase_components",
    );
    refused(
        &["rom", SMALL, "--no-cache", "--set", "rom.cut_shapes=0"],
        2,
        "rom.cut_shapes",
    );
    // fewer than a cut's six rigid motions ran, exit 0, with the first modes 17-67 % high
    let err = refused(
        &[
            "rom",
            SMALL,
            "--no-cache",
            "--set",
            "rom.crankcase_components=2",
            "--set",
            "rom.cut_shapes=5",
        ],
        2,
        "rom.cut_shapes",
    );
    assert!(err.contains("at least 6"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let vtu = dir.path().join("shapes.vtu");
    refused(
        &[
            "modes",
            SMALL,
            "--assembly",
            "--rom",
            "--count",
            "5",
            "--vtu",
            vtu.to_str().unwrap(),
            "--set",
            "rom.crankcase_components=2",
        ],
        2,
        "rom.crankcase_components",
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Regression (hostile input): the liner maps are estimated before the run starts; beyond the
/// memory limit `simulate --maps` exits 2 naming the maps, the estimate and the limit, and
/// writes nothing; within it the same run maps.
#[test]
fn regression_maps_beyond_the_memory_limit_are_refused_before_the_run() {
    let (_cache, dir) = small_rom_cache();
    let out = tempfile::tempdir().unwrap();
    let target = out.path().join("sim");
    let args = |limit: &str| -> Vec<String> {
        [
            "simulate",
            SMALL,
            "--maps",
            "--cache-dir",
            &dir,
            "--set",
            &format!("limits.max_memory_gb={limit}"),
            "--out",
            target.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let refused: Vec<String> = args("0.005");
    let (code, _, err) = linercav(&refused.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("mapping the liners") && err.contains("limits.max_memory_gb allows 0.005 GB"),
        "{err}"
    );
    assert!(!target.exists());
    let fits: Vec<String> = args("1");
    let (code, _, err) = linercav(&fits.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{err}");
    assert!(target.join("liner_maps.vtu").exists() && target.join("liner_maps.png").exists());
}

/// Regression: `--set K=a --set K=b` kept the last value without a word.
#[test]
fn regression_a_key_set_twice_is_refused() {
    let err = refused(
        &[
            "simulate",
            SMALL,
            "--set",
            "piston.clearance_um=80",
            "--set=piston.clearance_um=120",
        ],
        2,
        "--set 'piston.clearance_um' is given twice ('80', then '120')",
    );
    assert!(err.contains("give each key once"), "{err}");
}

/// Regression: `sweep-merge` read a part with no size or file-type check (`/dev/zero` grew to
/// 23.8 GB before the kernel killed it, a FIFO hung) and staged its output directory first
/// (the kill left it behind). A part is a regular file of bounded size, read before anything
/// is written.
#[test]
fn regression_a_sweep_part_that_is_not_a_file_is_refused_before_any_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("merged");
    let err = common::refused_capped(
        &["sweep-merge", "/dev/zero", "--out", out.to_str().unwrap()],
        2,
        "/dev/zero",
    );
    assert!(err.contains("not a regular file"), "{err}");
    assert!(!out.exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Regression: a `--set` value followed by more TOML on another line, or by a comment, was
/// taken and the rest dropped without a word; a table and a key inside it, both set, were not
/// refused (the flags' order decided).
#[test]
fn regression_set_values_that_bring_more_than_a_value_are_refused() {
    refused(
        &[
            "simulate",
            SMALL,
            "--set",
            "piston.clearance_um=100\n[engine]\ncylinders=3",
        ],
        2,
        "a value is one line",
    );
    refused(
        &[
            "simulate",
            SMALL,
            "--set",
            "piston.clearance_um=100 # was 80",
        ],
        2,
        "a comment after the value",
    );
    refused(
        &[
            "simulate",
            SMALL,
            "--set",
            "piston.thermal.liner_temp_c=100",
            "--set",
            "piston.thermal={liner_temp_c=130.0}",
        ],
        2,
        "'piston.thermal.liner_temp_c' is given twice",
    );
}

/// Regression: the barrel's widest point off the skirt ran (the barrel became a uniform
/// drop); a crank offset beyond the bore ran into a deep penetration (exit 1), and a crank
/// offset too large for the rod was reported as `piston.pin_offset_mm`'s.
#[test]
fn regression_offsets_and_the_barrels_widest_point_are_bounded() {
    for v in ["1e9", "-1e9", "-20.5", "45.5"] {
        let set = format!("piston.barrel_max_below_pin_mm={v}");
        refused(
            &["simulate", SMALL, "--set", &set],
            2,
            "must lie on the skirt",
        );
    }
    // the skirt's top and bottom themselves are accepted (pin 20 mm below the top of 65)
    for v in ["-20", "45", "0"] {
        let set = vec![format!("piston.barrel_max_below_pin_mm={v}")];
        let scene = linercav::api::load_scene(Path::new(SMALL), &set);
        assert!(scene.is_ok(), "{v}: {:?}", scene.err());
    }
    refused(
        &["simulate", SMALL, "--set", "piston.crank_offset_mm=140"],
        2,
        "piston.crank_offset_mm",
    );
    // too large for the rod: both offsets named when both are given, the one given otherwise
    let rod = |sets: &[&str]| {
        let mut args = vec!["simulate", SMALL, "--set", "engine.rod_length_mm=110"];
        for s in sets {
            args.extend(["--set", s]);
        }
        refused(&args, 2, "too large for the rod")
    };
    let err = rod(&["piston.crank_offset_mm=50"]);
    assert!(err.contains("key 'piston.crank_offset_mm'"), "{err}");
    let err = rod(&["piston.crank_offset_mm=50", "piston.pin_offset_mm=0.5"]);
    assert!(
        err.contains("piston.pin_offset_mm and piston.crank_offset_mm"),
        "{err}"
    );
}

/// Regression: a sweep checked its base scene's transient only (a run of 1e8 cycles that
/// `simulate` refuses at once was started; `limits.max_hours` was passed by a design varying
/// `transient.cycles`), and each variant's ROM only when it came to build it (a second
/// variant's ROM beyond `limits.max_memory_gb` was refused after the first one's build). Every
/// run and every ROM to build is now checked before the first is built.
#[test]
fn regression_a_sweeps_runs_and_roms_are_checked_before_any_is_built() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let (c, o) = (cache.to_str().unwrap(), dir.path().join("o"));
    let o = o.to_str().unwrap();
    let sweep = |extra: &[&str]| {
        let mut args = vec!["sweep", SMALL, "--cache-dir", c, "--out", o];
        args.extend(["--set", "transient.averaged_cycles=1"]);
        args.extend(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |extra: &[&str], expect: &str| {
        let args = sweep(extra);
        common::refused_capped(
            &args.iter().map(String::as_str).collect::<Vec<_>>(),
            2,
            expect,
        );
    };
    // the run that fails is named by its values
    run(
        &["--vary", "transient.cycles=2,100000000"],
        "run transient.cycles=100000000: ",
    );
    run(
        &[
            "--set",
            "limits.max_hours=0.001",
            "--vary",
            "transient.cycles=1,300",
        ],
        "limits.max_hours allows 0.001 h",
    );
    run(
        &[
            "--set",
            "transient.cycles=2",
            "--set",
            "liner.mesh.circumferential=40",
            "--set",
            "limits.max_memory_gb=1.5",
            "--vary",
            "liner.mesh.axial_size_mm=25,2",
        ],
        "the ROM build needs about",
    );
    // a variant's piston (its pressure curve, its hot skirt) is set up before any build too
    run(
        &[
            "--set",
            "transient.cycles=2",
            "--vary",
            "operating.combustion.compression_ratio=17,1e9",
        ],
        "the built-in pressure curve",
    );
    assert!(!cache.exists(), "a ROM was built before the refusal");
    assert!(!Path::new(o).exists());
}

/// Regression: the built-in pressure curve had no upper bound (a compression ratio of 1e9, a
/// heat release of 1e12 J or an intake of 1e6 bar ran into a deep penetration, exit 1), nor
/// had the crankcase pressure; the curve's peak is bounded as a pressure table's values are.
#[test]
fn regression_the_built_in_pressure_curve_and_the_crankcase_pressure_are_bounded() {
    for set in [
        "operating.combustion.compression_ratio=1e9",
        "operating.combustion.heat_release_j=1e12",
        "operating.combustion.intake_bar=1e6",
    ] {
        refused(
            &["simulate", SMALL, "--set", set],
            2,
            "the built-in pressure curve",
        );
    }
    refused(
        &[
            "simulate",
            SMALL,
            "--set",
            "operating.crankcase_pressure_bar=1e9",
        ],
        2,
        "operating.crankcase_pressure_bar",
    );
}

/// Regression: `[cavitation]` took a coolant gap of 1e9 mm, a static pressure of 1e12 kPa and
/// a k_p of 1e30 Pa per m/s^2 without a word, and thresholds out of order from a calibration
/// file were reported against the key 'cavitation' (not the file's key).
#[test]
fn regression_cavitation_values_are_bounded_and_a_calibration_file_is_named() {
    for (set, key) in [
        ("cavitation.gap_mm=1e9", "cavitation.gap_mm"),
        (
            "cavitation.static_pressure_kpa=1e12",
            "cavitation.static_pressure_kpa",
        ),
        (
            "cavitation.k_p_pa_per_m_s2=1e30",
            "cavitation.k_p_pa_per_m_s2",
        ),
    ] {
        let err = refused(&["simulate", SMALL, "--set", set], 2, key);
        assert!(err.contains("must be at most"), "{err}");
    }
    let dir = tempfile::tempdir().unwrap();
    let cal = dir.path().join("cal.json");
    std::fs::write(
        &cal,
        r#"{"onset_m_s2": 1300, "high_risk_m_s2": 1200, "k_p_pa_per_m_s2": 138}"#,
    )
    .unwrap();
    let set = format!("cavitation.calibration_file={}", cal.display());
    refused(
        &["simulate", SMALL, "--set", &set],
        2,
        "cavitation.calibration_file",
    );
    // k_p from a calibration file is bounded as the scene's key is
    std::fs::write(
        &cal,
        r#"{"onset_m_s2": 1000, "high_risk_m_s2": 1300, "k_p_pa_per_m_s2": 1e30}"#,
    )
    .unwrap();
    let err = refused(
        &["simulate", SMALL, "--set", &set],
        2,
        "k_p_pa_per_m_s2 must be at most",
    );
    assert!(err.contains("cal.json"), "{err}");
}

/// Regression: the type a key needs was said in the code's words: "expected a map" (a table
/// of named entries) and "expected a sequence" (an array); each is now said as the scene
/// writes it. A calibration file given as a JSON array was taken as its three values in the
/// code's field order (a wrong-length one said "expected struct CalibrationThresholds"): it
/// is refused, asking for an object; one that gives a threshold twice is refused, naming it.
#[test]
fn regression_wrong_types_are_named_as_the_scene_writes_them() {
    for (set, key, said) in [
        ("crankcase.sets=3", "crankcase.sets", "expected a table"),
        (
            "engine.firing_order=3",
            "engine.firing_order",
            "expected an array",
        ),
    ] {
        let err = refused(&["rom", SMALL, "--set", set], 2, key);
        assert!(err.contains(said), "{set}: {err}");
        assert!(!err.contains("map") && !err.contains("sequence"), "{err}");
    }
    let dir = tempfile::tempdir().unwrap();
    let cal = dir.path().join("cal.json");
    std::fs::write(&cal, "[1000, 1300, 138]").unwrap();
    let set = format!("cavitation.calibration_file={}", cal.display());
    let err = refused(
        &["simulate", SMALL, "--set", &set],
        2,
        "cavitation.calibration_file",
    );
    assert!(err.contains("expected an object"), "{err}");
    assert!(!err.contains("struct"), "{err}");
    // a threshold given twice: the last won silently (session 75's sweep)
    std::fs::write(
        &cal,
        r#"{"onset_m_s2": 1000, "high_risk_m_s2": 1300, "k_p_pa_per_m_s2": 138, "onset_m_s2": 5}"#,
    )
    .unwrap();
    let err = refused(
        &["simulate", SMALL, "--set", &set],
        2,
        "cavitation.calibration_file",
    );
    assert!(err.contains("duplicate field `onset_m_s2`"), "{err}");
}

/// Regression: the documented `crankcase.mesh.element = "tet10"` failed on every engine tried
/// with "solid element #7 ... is inverted" (the generated lattice's tetrahedra invert at the
/// blends between bores), naming no key. It is refused naming the key and the way out.
#[test]
fn regression_the_generated_crankcase_in_tet10_is_refused_naming_the_key() {
    let err = refused(
        &[
            "rom",
            SMALL,
            "--no-cache",
            "--set",
            "crankcase.mesh.element=tet10",
        ],
        2,
        "crankcase.mesh.element",
    );
    assert!(
        err.contains("not available") && err.contains("hex20"),
        "{err}"
    );
}

/// Regression: a box set that selects no node (the fixed set's box 320 mm below the
/// crankcase) built the parts and then failed the engine assembly as singular, exit 1, "check
/// the crankcase 'fix' sets". It is bad input: refused before any reduction, exit 2, naming the
/// key and the mesh's extent.
#[test]
fn regression_a_box_set_of_no_nodes_is_refused_naming_its_key() {
    let err = refused(
        &[
            "rom",
            SMALL,
            "--no-cache",
            "--set",
            "crankcase.sets.pan_rail.box_mm=[-2000.0,-2000.0,-500.5,2000.0,2000.0,-499.5]",
        ],
        2,
        "crankcase.sets.pan_rail.box_mm selects no node",
    );
    assert!(err.contains("spans"), "{err}");
    // `modes --part liner` ran free-free under "fixed: clamp" with a clamp box of no nodes
    refused(
        &[
            "modes",
            SMALL,
            "--part",
            "liner",
            "--count",
            "3",
            "--set",
            "liner.sets.clamp.box_mm=[0.0,0.0,-900.0,1.0,1.0,-899.0]",
            "--set",
            "liner.fix=[\"clamp\"]",
        ],
        2,
        "liner.sets.clamp.box_mm",
    );
}

/// Regression: duplicates and conflicts taken without a word: `rom.cylinders = [1, 1]`
/// (de-duplicated), `rom-tradeoff --factors 2,2` (the same ROM built twice), `--shards` beside
/// `--shard` and `--shards 0` (ignored), `transient.hht_alpha = nan` under the Newmark scheme
/// (unchecked while unused); a missing top-level table was reported against the key '.'.
#[test]
fn regression_duplicates_and_conflicting_flags_are_refused() {
    refused(
        &["rom", SMALL, "--set", "rom.cylinders=[1,1]"],
        2,
        "cylinder 1 is given twice",
    );
    refused(
        &["rom-tradeoff", SMALL, "--factors", "2,2"],
        2,
        "the factor 2 is given twice",
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p");
    let out = out.to_str().unwrap();
    let sweep = [
        "sweep",
        SMALL,
        "--vary",
        "piston.clearance_um=60,80",
        "--out",
        out,
    ];
    let mut both = sweep.to_vec();
    both.extend(["--shards", "3", "--shard", "1/2"]);
    refused(&both, 2, "not both");
    let mut zero = sweep.to_vec();
    zero.extend(["--shards", "0"]);
    refused(&zero, 2, "--shards 0");
    // --shards outside an Indexed Job ran the whole sweep
    let mut alone = sweep.to_vec();
    alone.extend(["--shards", "2"]);
    refused(&alone, 2, "--shards 2: ");
    refused(
        &["simulate", SMALL, "--set", "transient.hht_alpha=nan"],
        2,
        "transient.hht_alpha",
    );
    let scene = dir.path().join("top.toml");
    std::fs::write(&scene, "title = \"x\"\n").unwrap();
    let err = refused(
        &["rom", scene.to_str().unwrap()],
        2,
        "missing field `engine`",
    );
    assert!(!err.contains("key '.'"), "{err}");
}

/// Regression: a cache directory that exists as a file or device said "File exists (os error
/// 17)"; it is named as not a directory.
#[test]
fn regression_a_cache_dir_that_is_not_a_directory_is_said_so() {
    refused(
        &["rom", SMALL, "--cache-dir", "/dev/null"],
        2,
        "/dev/null: cannot write: exists and is not a directory",
    );
}

/// Regression (session 75's hostile sweep): a scheduler's task variable that is not UTF-8
/// (`SLURM_ARRAY_TASK_ID=$'\xff'`, `JOB_COMPLETION_INDEX=$'\xff'` with `--shards 2`) was
/// taken as unset: the task ran the whole unsharded sweep and exited 0. It is refused, exit
/// 2, naming the variable, before any run (nothing on stdout, no output directory).
#[test]
fn regression_a_task_variable_that_is_not_utf8_is_refused() {
    use std::os::unix::ffi::OsStrExt;
    let bad = std::ffi::OsStr::from_bytes(b"\xff");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("w");
    let cases: [(&str, &[&str]); 2] = [
        ("SLURM_ARRAY_TASK_ID", &[]),
        ("JOB_COMPLETION_INDEX", &["--shards", "2"]),
    ];
    for (var, extra) in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_linercav"))
            .args(["sweep", SMALL, "--vary", "piston.clearance_um=40,80,120"])
            .args(["--out", out.to_str().unwrap()])
            .args(extra)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("JOB_COMPLETION_INDEX")
            .env(var, bad)
            .env("SLURM_ARRAY_TASK_MIN", "1")
            .env("SLURM_ARRAY_TASK_MAX", "2")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{var}: {err}");
        assert!(err.contains(var) && err.contains("whole number"), "{err}");
        assert!(o.stdout.is_empty() && !out.exists(), "{var}");
    }
}
