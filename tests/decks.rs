//! Engines as decks: interfaces and points found from the geometry against the generator's
//! exact sets, units, materials from decks.

use linercav::api::load_scene;
use linercav::mesh::find::LinerShape;
use linercav::mesh::import::{complete_engine, EngineFrame};
use linercav::mesh::{crankcase, liner, Mesh};
use linercav::scene::{CrankcaseSource, MeshSource};
use std::path::Path;

/// The default engine's generated liner and crankcase (with the generator's sets) and the
/// scene's frame data.
fn default_meshes() -> (Mesh, Mesh, LinerShape, Vec<f64>, Vec<f64>, f64) {
    let scene = load_scene(Path::new("models/engine.toml"), &[]).unwrap();
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        panic!("the default liner is parametric")
    };
    let lm = liner::generate(geometry, meshing);
    let cc = scene.crankcase.as_ref().unwrap();
    let CrankcaseSource::Parametric { geometry: cg, meshing: cmesh } = &cc.source else {
        panic!("the default crankcase is parametric")
    };
    let cm = crankcase::generate(cg, cmesh);
    let g = &scene.liner_geometry;
    let shape = LinerShape {
        inner_radius: g.inner_diameter / 2.0,
        outer_radius: g.outer_diameter / 2.0,
        flange_radius: g.flange_outer_diameter / 2.0,
        length: g.length,
        seat_z: g.length - g.flange_height,
        tol: 1e-6,
    };
    let e = &scene.engine;
    let axis_x = (0..e.cylinders)
        .map(|c| (c as f64 - (e.cylinders as f64 - 1.0) / 2.0) * e.cylinder_pitch)
        .collect();
    (lm, cm, shape, axis_x, g.analysis_depths.clone(), e.bore)
}

/// Verification: on the default engine moved out of its frames (the liner turned to lie along
/// -x and translated, the crankcase lifted by 0.3 m) and stripped of every set, the sets found
/// from the geometry are exactly the generator's (the generator places lattice planes at every
/// interface edge and point, so exact equality is the right check: a found set that differed
/// by a ring of nodes would be a wrong tolerance or band).
#[test]
fn verification_found_sets_equal_the_generators() {
    let (lm0, cm0, shape0, axis_x, depths, bore) = default_meshes();
    let mut lm = lm0.clone();
    lm.node_sets.clear();
    // liner axis z -> -x: (x, y, z) -> (-z, y, x) about the origin, then translated
    for p in &mut lm.nodes {
        *p = [0.7 - p[2], p[1] - 0.05, p[0] + 1.2];
    }
    let mut cm = cm0.clone();
    cm.node_sets.retain(|k, _| k == "pan_rail");
    for p in &mut cm.nodes {
        p[2] += 0.3;
    }
    let frame = EngineFrame {
        axis_x: &axis_x,
        depths: &depths,
        bore,
        liner_unit_key: "liner.mesh_unit",
        crankcase_unit_key: "crankcase.mesh_unit",
    };
    let found = complete_engine(
        &mut lm,
        &mut cm,
        shape0,
        Some(Path::new("liner.inp")),
        Some(Path::new("crankcase.bdf")),
        &frame,
    )
    .unwrap();
    let s = found.liner.unwrap();
    // radii and heights to roundoff of the moved coordinates
    for (a, b) in [
        (s.inner_radius, shape0.inner_radius),
        (s.outer_radius, shape0.outer_radius),
        (s.flange_radius, shape0.flange_radius),
        (s.length, shape0.length),
        (s.seat_z, shape0.seat_z),
    ] {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    assert!((found.crankcase_shift_z + 0.3).abs() < 1e-9);
    for (name, want) in &lm0.node_sets {
        same_set(&lm, name, want, "liner");
    }
    for (name, want) in &cm0.node_sets {
        same_set(&cm, name, want, "crankcase");
    }
}

/// Asserts that `mesh`'s set `name` holds exactly `want`, naming a few nodes that differ.
fn same_set(mesh: &Mesh, name: &str, want: &[usize], part: &str) {
    use std::collections::BTreeSet;
    let got: BTreeSet<usize> = mesh.node_sets[name].iter().copied().collect();
    let want: BTreeSet<usize> = want.iter().copied().collect();
    let extra: Vec<_> = got.difference(&want).take(3).map(|&n| mesh.nodes[n]).collect();
    let missing: Vec<_> = want.difference(&got).take(3).map(|&n| mesh.nodes[n]).collect();
    assert!(
        extra.is_empty() && missing.is_empty(),
        "{part} set {name}: {} found, {} expected; extra at {extra:?}, missing at {missing:?}",
        got.len(),
        want.len()
    );
}
