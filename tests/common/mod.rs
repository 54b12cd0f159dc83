//! Helpers shared by the integration tests: the binary as a process, small structured meshes
//! and dense oracles.
#![allow(dead_code)]

/// Runs the `linercav` binary with `args` and returns its whole output.
pub fn linercav_output(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_linercav"))
        .args(args)
        .output()
        .expect("the linercav binary runs")
}

/// Runs the `linercav` binary: (exit code, stdout, stderr).
pub fn linercav(args: &[&str]) -> (i32, String, String) {
    let out = linercav_output(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The JSON a successful run printed (fails the test with its stderr otherwise).
pub fn json(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// `frequencies_hz` of a `modes --json` answer.
pub fn freqs(v: &serde_json::Value) -> Vec<f64> {
    v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

use linercav::mesh::lattice::Lattice;
use linercav::mesh::Mesh;
use linercav::scene::spec::ElementKind;

/// A box [0, lx] x [0, ly] x [0, lz] of n cells per axis, optionally distorted by a smooth map
/// that keeps the outer faces planar (interior nodes move).
pub fn box_mesh(kind: ElementKind, n: [usize; 3], l: [f64; 3], distort: f64) -> Mesh {
    let coord = move |k: [usize; 3]| {
        let s: Vec<f64> = (0..3).map(|a| k[a] as f64 / (2 * n[a]) as f64).collect();
        let bump = |t: f64| (std::f64::consts::PI * t).sin();
        let w = bump(s[0]) * bump(s[1]) * bump(s[2]);
        [
            l[0] * (s[0] + distort * w * (2.0 * s[1] - 1.0) * 0.5),
            l[1] * (s[1] + distort * w * (2.0 * s[2] - 1.0) * 0.5),
            l[2] * (s[2] + distort * w * (2.0 * s[0] - 1.0) * 0.5),
        ]
    };
    let active = |_: usize, _: usize, _: usize| true;
    let lat = Lattice {
        cells: n,
        periodic_j: false,
        active: &active,
        coord: &coord,
    };
    let lm = lat.generate(kind);
    let mut mesh = lm.mesh;
    let ends: Vec<usize> = (0..lm.keys.len()).filter(|&i| lm.keys[i][0] == 0).collect();
    mesh.node_sets.insert("x0".into(), ends);
    let boundary: Vec<usize> = (0..lm.keys.len())
        .filter(|&i| (0..3).any(|a| lm.keys[i][a] == 0 || lm.keys[i][a] == 2 * n[a]))
        .collect();
    mesh.node_sets.insert("boundary".into(), boundary);
    mesh
}

/// Dense generalised symmetric eigenvalues of (K, M) by Cholesky of M, ascending.
pub fn dense_eigenvalues(k: &[Vec<f64>], m: &[Vec<f64>]) -> Vec<f64> {
    let n = k.len();
    let km = nalgebra::DMatrix::from_fn(n, n, |i, j| k[i][j]);
    let mm = nalgebra::DMatrix::from_fn(n, n, |i, j| m[i][j]);
    let l = mm.cholesky().expect("M is positive definite").l();
    let linv = l.clone().try_inverse().expect("invertible");
    let a = &linv * km * linv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut ev: Vec<f64> = a.symmetric_eigen().eigenvalues.iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    ev
}

pub const KINDS: [ElementKind; 4] = [
    ElementKind::Tet4,
    ElementKind::Tet10,
    ElementKind::Hex8,
    ElementKind::Hex20,
];

/// Asserts a refusal of the binary run with `args`: the exit code, one `error:` message naming
/// `needle`, no panic, nothing on stdout. Returns the message.
pub fn refused(args: &[&str], code: i32, needle: &str) -> String {
    refused_as(args, linercav(args), code, needle)
}

/// As [`refused`], the binary run under `timeout 60` and a 4 GB address-space cap
/// (`prlimit`): a regression that would run on, or read without end, fails its test instead
/// of taking the machine.
pub fn refused_capped(args: &[&str], code: i32, needle: &str) -> String {
    let out = std::process::Command::new("timeout")
        .args(["60", "prlimit", "--as=4000000000", "--"])
        .arg(env!("CARGO_BIN_EXE_linercav"))
        .args(args)
        .output()
        .expect("timeout and prlimit run");
    let run = (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    refused_as(args, run, code, needle)
}

/// The checks of [`refused`] on a run's (exit code, stdout, stderr).
fn refused_as(
    args: &[&str],
    (c, out, err): (i32, String, String),
    code: i32,
    needle: &str,
) -> String {
    assert_eq!(c, code, "{args:?}: exit {c}, stderr: {err}");
    assert!(err.contains("error: "), "{args:?}: no error message: {err}");
    assert!(!err.contains("panicked"), "{args:?}: panic: {err}");
    assert!(out.is_empty(), "{args:?}: stdout not empty: {out}");
    assert!(
        err.contains(needle),
        "{args:?}: should name '{needle}': {err}"
    );
    err
}
