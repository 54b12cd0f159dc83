//! Liner verification: convergence of the ovalling frequencies of a liner-like ring with the
//! observed rate, and the default liner mesh against a converged reference.

use linercav::fem::model::FeModel;
use linercav::mesh::liner::{generate, LinerGeometry, LinerMeshing};
use linercav::scene::spec::Elastic;
use linercav::scene::spec::ElementKind;
use linercav::scene::{MeshSource, Scene};
use std::path::Path;

const REFERENCE: &str = "tests/reference/liner_free_free.json";

/// The default scene's liner meshing (models/engine.toml), and a refined one: 1.5x finer
/// around, through the wall and along the axis.
fn default_liner() -> (LinerGeometry, LinerMeshing) {
    let scene = Scene::load(Path::new("models/engine.toml"), &[]).unwrap();
    match scene.liner.source {
        MeshSource::Liner { geometry, meshing } => (geometry, meshing),
        MeshSource::File(_) => panic!("default liner is parametric"),
    }
}

/// Regenerates the converged reference of the default liner (about 1 minute, 2 GB):
/// `cargo test --release --test liner -- --ignored reference`.
/// The reference mesh is 1.5x finer in every direction; with the O(h^4) convergence shown by
/// `verification_ovalling_frequency_converges_at_fourth_order` its own error is about 1.5^-4 = 20 % of the
/// default mesh's, which the 0.4 % floor of `verification_default_liner_is_within_half_a_percent` covers.
#[test]
#[ignore]
fn verification_reference_liner_frequencies() {
    let (geo, m) = default_liner();
    let fine = LinerMeshing {
        circumferential: 72,
        radial: 3,
        radial_flange: 2,
        axial_size: m.axial_size / 1.5,
        ..m
    };
    let f = elastic_frequencies(&geo, &fine, 10);
    let json = serde_json::json!({
        "what": "free-free elastic frequencies [Hz] of the default liner, mesh 72 x 3 (flange 2), axial 6.67 mm, Hex20",
        "regenerate": "cargo test --release --test liner -- --ignored reference",
        "frequencies_hz": f,
    });
    std::fs::write(REFERENCE, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    println!("{f:?}");
}

/// The default liner mesh reproduces the first 10 elastic frequencies of the refined reference
/// within 0.4 % (so within 0.5 % of the converged values, see the reference's note).
#[test]
fn verification_default_liner_is_within_half_a_percent() {
    let text = std::fs::read_to_string(REFERENCE).expect("reference JSON committed");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let reference: Vec<f64> = v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let (geo, m) = default_liner();
    let f = elastic_frequencies(&geo, &m, 10);
    for (j, (a, b)) in f.iter().zip(&reference).enumerate() {
        let rel = (a - b) / b;
        println!(
            "elastic mode {:>2}: {a:9.2} Hz, reference {b:9.2} Hz, {:+.3} %",
            j + 1,
            100.0 * rel
        );
        assert!(rel.abs() < 0.004, "mode {} off by {rel}", j + 1);
    }
    // The first elastic pair is the n = 2 ovalling: thin-ring theory,
    // omega = n (n^2 - 1) / sqrt(n^2 + 1) * sqrt(E I / (rho A R^4)) with I / A = t^2 / 12 at the
    // mean radius R, gives 1392 Hz for a 10 mm wall, 1725 Hz for 13 mm and 1829 Hz for the
    // default 14 mm (FE: 1857 Hz); the finite tube with its flange sits 1.5-4 % above the ring,
    // so 8 % catches a wrong mode or material.
    let (ro, ri) = (geo.outer_diameter / 2.0, geo.inner_diameter / 2.0);
    let (r, t) = ((ro + ri) / 2.0, ro - ri);
    let n: f64 = 2.0;
    let ring = n * (n * n - 1.0) / (n * n + 1.0).sqrt()
        * (IRON.young * t * t / 12.0 / (IRON.density * r.powi(4))).sqrt()
        / (2.0 * std::f64::consts::PI);
    assert!(
        (f[0] / ring - 1.0).abs() < 0.08,
        "first ovalling {} Hz, ring theory {ring} Hz",
        f[0]
    );
}

const IRON: Elastic = Elastic {
    young: 140e9,
    poisson: 0.26,
    density: 7200.0,
};
const SIGMA: f64 = -(2.0 * std::f64::consts::PI * 100.0) * (2.0 * std::f64::consts::PI * 100.0);

fn ring(length: f64) -> LinerGeometry {
    LinerGeometry {
        outer_diameter: 0.135,
        inner_diameter: 0.115,
        length,
        flange_outer_diameter: 0.135,
        flange_height: length / 4.0,
        guide_height: length / 4.0,
        guide_bottom: 0.0,
        analysis_depths: vec![length / 2.0],
        pilot_diameter: 0.135,
        deck_underside: None,
    }
}

/// Elastic frequencies [Hz] (rigid modes dropped) of a free-free mesh.
fn elastic_frequencies(geo: &LinerGeometry, m: &LinerMeshing, count: usize) -> Vec<f64> {
    let mut model = FeModel::build(generate(geo, m), &IRON, &[]).unwrap();
    let sol = model.modes(count + 6, SIGMA, 4).unwrap();
    assert!(sol.sturm.as_ref().unwrap().ok);
    (6..count + 6).map(|j| sol.modes.frequency_hz(j)).collect()
}

/// Ovalling (n = 2) frequency of a short ring under uniform refinement h, h/2, h/4.
/// Quadratic elements converge eigenvalues as O(h^4) (twice the energy-norm order 2p, p = 2);
/// the observed rate log2((f_h - f_h/2) / (f_h/2 - f_h/4)) must lie within 3.3..4.7 (the
/// pre-asymptotic drift of a rate at this resolution). The extrapolated value must agree with
/// the thin-ring formula f = 1/(2 pi) sqrt(E t^2 / (12 rho R^4) n^2 (n^2-1)^2/(n^2+1)) within
/// 2 %: at t/R = 0.16 the shear deformation and rotary inertia it neglects lower the n = 2
/// frequency by about 1 % (observed: -1.1 %), so 2 % is twice the expected model difference.
#[test]
fn verification_ovalling_frequency_converges_at_fourth_order() {
    let geo = ring(0.02);
    let levels = [(12usize, 1usize), (24, 2), (48, 4)];
    let f: Vec<f64> = levels
        .iter()
        .map(|&(nt, nr)| {
            let m = LinerMeshing {
                kind: ElementKind::Hex20,
                circumferential: nt,
                radial: nr,
                radial_flange: 1,
                axial_size: 0.02 / nr as f64,
            };
            elastic_frequencies(&geo, &m, 2)[0]
        })
        .collect();
    let rate = ((f[0] - f[1]) / (f[1] - f[2])).log2();
    let extrapolated = f[2] + (f[2] - f[1]) / (2f64.powf(rate) - 1.0);
    let (t, r, n) = (0.01f64, 0.0625f64, 2.0f64);
    let thin =
        (IRON.young * t * t / (12.0 * IRON.density * r.powi(4)) * n * n * (n * n - 1.0).powi(2)
            / (n * n + 1.0))
            .sqrt()
            / (2.0 * std::f64::consts::PI);
    println!("ovalling n=2: {:.3} {:.3} {:.3} Hz; observed rate {rate:.2}; extrapolated {extrapolated:.3} Hz; thin ring {thin:.3} Hz", f[0], f[1], f[2]);
    assert!((3.3..4.7).contains(&rate), "observed rate {rate}");
    assert!((extrapolated - thin).abs() / thin < 0.02);
}

/// Verification of the pilot surfaces (`liner.pilot_diameter_mm`): a liner whose guide band
/// and deck part sit at r_p = 70 mm while its wet wall has r_o = 69 mm. Every outer-surface
/// node lies on the radius its height asks for (to roundoff), no element is inverted, and the
/// volume equals the stepped tube's closed form, a sum of annular frusta (the tapers straight
/// between the levels). Tolerance 1e-4: the quadratic arcs of 48 elements around deviate from
/// the circle by about R (2 pi / 48)^4 / 400 ~ 1e-6 R, while a pilot zone misplaced by one
/// element layer or a missing taper moves the volume by more than 1e-3.
#[test]
fn verification_pilot_surfaces_make_a_stepped_tube() {
    let (ri, ro, rp, rf, length) = (0.0575, 0.069, 0.070, 0.074, 0.2);
    let geo = LinerGeometry {
        outer_diameter: 2.0 * ro,
        inner_diameter: 2.0 * ri,
        length,
        flange_outer_diameter: 2.0 * rf,
        flange_height: 0.012,
        guide_height: 0.03,
        guide_bottom: 0.04,
        analysis_depths: vec![0.04, 0.065],
        pilot_diameter: 2.0 * rp,
        deck_underside: Some(0.17),
    };
    let meshing = LinerMeshing {
        kind: ElementKind::Hex20,
        circumferential: 48,
        radial: 2,
        radial_flange: 1,
        axial_size: 0.01,
    };
    let mut mesh = generate(&geo, &meshing);
    let (g0, g1, deck, seat) = (0.04, 0.07, 0.17, length - 0.012);
    // outer surface: the guide band and the deck part at r_p, the coolant zone at r_o
    let r = |p: &[f64; 3]| p[0].hypot(p[1]);
    for &n in &mesh.node_sets["lower_guide"] {
        assert!((r(&mesh.nodes[n]) - rp).abs() < 1e-12, "guide node {n}");
    }
    for k in 1..=2 {
        let n = mesh.node_sets[&format!("point_{k}")][0];
        assert!((r(&mesh.nodes[n]) - ro).abs() < 1e-12, "point {k}");
    }
    let upper: Vec<usize> = mesh.node_sets["outer_thrust"]
        .iter()
        .copied()
        .filter(|&n| mesh.nodes[n][2] >= deck - 1e-12)
        .collect();
    assert!(!upper.is_empty());
    for n in upper {
        assert!((r(&mesh.nodes[n]) - rp).abs() < 1e-12, "deck-bore node {n}");
    }
    linercav::fem::element::check_mesh(&mut mesh).expect("no inverted element");
    // closed form: annular frusta between the levels where the outer radius changes
    let frustum = |h: f64, a: f64, b: f64| std::f64::consts::PI * h * (a * a + a * b + b * b) / 3.0;
    let mut corners: Vec<f64> = Vec::new();
    for (_, nodes) in mesh.elements() {
        for &n in &nodes[..8] {
            let z = mesh.nodes[n][2];
            if !corners.iter().any(|&w| (w - z).abs() < 1e-9) {
                corners.push(z);
            }
        }
    }
    corners.sort_by(f64::total_cmp);
    // the taper layers: the element layer below the band, above it, and below the deck
    let below = |z: f64| corners.iter().copied().rfind(|&w| w < z - 1e-9).unwrap();
    let above = |z: f64| corners.iter().copied().find(|&w| w > z + 1e-9).unwrap();
    let (t0, t1, t2) = (below(g0), above(g1), below(deck));
    let outer_volume = frustum(t0, ro, ro)
        + frustum(g0 - t0, ro, rp)
        + frustum(g1 - g0, rp, rp)
        + frustum(t1 - g1, rp, ro)
        + frustum(t2 - t1, ro, ro)
        + frustum(deck - t2, ro, rp)
        + frustum(seat - deck, rp, rp)
        + frustum(length - seat, rf, rf);
    let exact = outer_volume - std::f64::consts::PI * ri * ri * length;
    let v: f64 = mesh
        .elements()
        .map(|(kind, nodes)| {
            let c: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.nodes[n]).collect();
            linercav::fem::element::volume(kind, &c)
        })
        .sum();
    assert!((v / exact - 1.0).abs() < 1e-4, "volume {v} against {exact}");
}

/// Verification: the up-front estimate of a generated liner's DOFs and of its reduction's
/// loads (`budget::liner_dofs`, `budget::liner_loads`, which refuse a ROM build before any
/// mesh exists) equals the generated mesh's own count: 3 per node, and the two bore lines'
/// nodes plus the clamp, on the default liner, coarser and finer ones, other layer counts and
/// the small engine's liner (the count per lattice cell before was 7 % low on the default and
/// 20 % low on the small engine's at 3 mm, 21 % high at its default 25 mm).
#[test]
fn verification_the_liner_estimate_counts_the_generated_mesh() {
    use linercav::scene::budget::{liner_dofs, liner_loads};
    let (geo, m) = default_liner();
    let small = Scene::load(Path::new("tests/fixtures/engine_small.toml"), &[]).unwrap();
    let MeshSource::Liner {
        geometry: small_geo,
        meshing: small_m,
    } = small.liner.source
    else {
        panic!("the small engine's liner is parametric")
    };
    let cases = [
        (geo.clone(), m.clone()),
        (
            geo.clone(),
            LinerMeshing {
                axial_size: m.axial_size * 2.7,
                ..m.clone()
            },
        ),
        (
            geo.clone(),
            LinerMeshing {
                axial_size: m.axial_size / 2.0,
                radial: 3,
                ..m.clone()
            },
        ),
        (
            geo.clone(),
            LinerMeshing {
                circumferential: 64,
                radial_flange: 3,
                ..m.clone()
            },
        ),
        (small_geo.clone(), small_m.clone()),
        (
            small_geo,
            LinerMeshing {
                axial_size: 0.003,
                ..small_m
            },
        ),
    ];
    for (g, mm) in cases {
        let mesh = generate(&g, &mm);
        let dofs = 3 * mesh.nodes.len();
        assert_eq!(liner_dofs(&g, &mm), dofs as f64, "{mm:?}");
        let lines = mesh.node_sets["bore_thrust"].len() + mesh.node_sets["bore_antithrust"].len();
        let loads = (lines + 1) as f64;
        assert_eq!(liner_loads(&g, &mm), loads, "{mm:?}");
    }
}
