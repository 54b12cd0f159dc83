//! Nastran bulk data and Abaqus input read as the same mesh as the Gmsh file they were written
//! from: meshio (an independent writer, `tests/fixtures/make_fixtures.py`) wrote the test
//! block (10-node tetrahedra and 20-node bricks, Gmsh-made) and a coarse liner (exported by
//! linercav) as `.inp`, `.bdf` (large-field GRID, small-field elements with continuations,
//! SET1 node sets) and `.nas` (free-field GRID with D exponents). The modes of each deck must
//! equal the Gmsh mesh's to 1e-9 relative, free and with a named set clamped.
//!
//! Why 1e-9: the decks hold the coordinates to 11-12 significant digits (16-column Nastran
//! fields; meshio's Abaqus writer more), so the stiffness and mass differ from the Gmsh
//! mesh's by ~1e-11 relative and the frequencies by as much; a wrong node order or a lost
//! node changes them by percents (or fails the Jacobian check).

mod common;
use common::{freqs, json, linercav, linercav_output};

const STEEL: [&str; 6] = [
    "--youngs",
    "2.1e11",
    "--poisson",
    "0.3",
    "--density",
    "7850",
];

fn frequencies(args: &[&str]) -> Vec<f64> {
    freqs(&json(&linercav_output(args)))
}

/// Largest relative difference of the elastic frequencies (those above 1e-3 of the largest;
/// rigid-body modes are zero to roundoff in both).
fn difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let top = a.iter().fold(0.0f64, |m, &x| m.max(x));
    a.iter()
        .zip(b)
        .filter(|(x, _)| **x > 1e-3 * top)
        .map(|(x, y)| (x - y).abs() / x)
        .fold(0.0, f64::max)
}

#[test]
fn verification_nastran_and_abaqus_blocks_give_the_gmsh_modes() {
    for block in ["block_tet10", "block_hex20"] {
        for fix in [None, Some("clamp")] {
            let modes = |file: &str| {
                let path = format!("tests/fixtures/{file}");
                let mut args = vec!["modes", "--mesh", &path, "--count", "10", "--json"];
                args.extend(STEEL);
                if let Some(f) = fix {
                    args.extend(["--fix", f]);
                }
                frequencies(&args)
            };
            let reference = modes(&format!("{block}.msh"));
            for deck in [
                format!("{block}.inp"),
                format!("{block}.bdf"),
                format!("{block}_free.nas"),
            ] {
                let d = difference(&reference, &modes(&deck));
                assert!(d < 1e-9, "{deck} (fix {fix:?}): {d:.2e}");
            }
        }
    }
}

#[test]
fn verification_nastran_and_abaqus_liners_give_the_gmsh_modes() {
    // the scene's liner from each file: the scene's node sets found by name in every format
    let modes = |file: &str| {
        let set = format!("liner.mesh_file={file}");
        frequencies(&[
            "modes",
            "tests/fixtures/engine_small.toml",
            "--part",
            "liner",
            "--set",
            &set,
            "--count",
            "12",
            "--json",
        ])
    };
    let reference = modes("liner_hex20.msh");
    for deck in ["liner_hex20.inp", "liner_hex20.bdf", "liner_hex20_free.nas"] {
        let d = difference(&reference, &modes(deck));
        assert!(d < 1e-9, "{deck}: {d:.2e}");
    }
}

#[test]
fn contract_unknown_mesh_formats_and_broken_decks_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("block.stl");
    std::fs::write(&bad, "solid x\n").unwrap();
    let mut args = vec!["modes", "--mesh", bad.to_str().unwrap(), "--count", "4"];
    args.extend(STEEL);
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(".bdf") && err.contains(".inp"), "{err}");
    // a deck whose element refers to a node that is not there: file, line and node named
    let text = std::fs::read_to_string("tests/fixtures/block_tet10.inp").unwrap();
    let broken = dir.path().join("broken.inp");
    let first_element = text
        .lines()
        .position(|l| l.starts_with("*ELEMENT"))
        .unwrap()
        + 1;
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == first_element {
                let mut f: Vec<String> = l.split(',').map(String::from).collect();
                f[1] = " 999999".into();
                f.join(",")
            } else {
                l.to_string()
            }
        })
        .collect();
    std::fs::write(&broken, lines.join("\n")).unwrap();
    let mut args = vec!["modes", "--mesh", broken.to_str().unwrap(), "--count", "4"];
    args.extend(STEEL);
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!("broken.inp:{}", first_element + 1)) && err.contains("999999"),
        "{err}"
    );
}
