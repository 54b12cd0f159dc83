//! Engines as decks: interfaces and points found from the geometry against the generator's
//! exact sets, units, materials from decks, the small engine taken out as mm decks (an Abaqus
//! part/instance liner, a Nastran crankcase over nested INCLUDEs with MAT1/PSOLID) and back in.

mod common;
use common::{json, linercav, linercav_output, refused};

use linercav::api::load_scene;
use linercav::mesh::find::LinerShape;
use linercav::mesh::import::{complete_engine, EngineFrame};
use linercav::mesh::{crankcase, liner, Mesh};
use linercav::scene::{CrankcaseSource, MeshSource};
use std::path::Path;

/// The default engine's generated liner and crankcase (with the generator's sets) and the
/// scene's frame data, the scene's keys set by `sets` (KEY=VALUE).
fn default_meshes(sets: &[&str]) -> (Mesh, Mesh, LinerShape, Vec<f64>, Vec<f64>, f64) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scene = load_scene(Path::new("models/engine.toml"), &sets).unwrap();
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        panic!("the default liner is parametric")
    };
    let lm = liner::generate(geometry, meshing);
    let cm = generated_crankcase(&scene);
    let g = &scene.liner_geometry;
    let shape = LinerShape {
        inner_radius: g.inner_diameter / 2.0,
        outer_radius: g.outer_diameter / 2.0,
        flange_radius: g.flange_outer_diameter / 2.0,
        pilot_radius: g.pilot_diameter / 2.0,
        length: g.length,
        seat_z: g.length - g.flange_height,
        tol: 1e-6,
    };
    let e = &scene.engine;
    let axis_x = (0..e.cylinders)
        .map(|c| linercav::scene::bore_axis_x(e.cylinders, e.cylinder_pitch, c))
        .collect();
    (lm, cm, shape, axis_x, g.analysis_depths.clone(), e.bore)
}

/// The generated crankcase of a scene whose crankcase is parametric, with the generator's sets.
fn generated_crankcase(scene: &linercav::scene::Scene) -> Mesh {
    let cc = scene.crankcase.as_ref().unwrap();
    let CrankcaseSource::Parametric { geometry, meshing } = &cc.source else {
        panic!("the crankcase is parametric")
    };
    crankcase::generate(geometry, meshing)
}

/// Verification: on the default engine moved out of its frames (the liner turned to lie along
/// -x and translated, the crankcase lifted by 0.3 m) and stripped of every set, the sets found
/// from the geometry are exactly the generator's (the generator places lattice planes at every
/// interface edge and point, so exact equality is the right check: a found set that differed
/// by a ring of nodes would be a wrong tolerance or band).
#[test]
fn verification_found_sets_equal_the_generators() {
    found_sets_equal_the_generators(&[]);
}

/// Verification: as above for a stepped liner, its guide band and deck bore on a pilot
/// diameter 3 mm above the wet wall's (`liner.pilot_diameter_mm = 146`, wet wall 143 mm,
/// flange 148 mm), as real wet liners are made. Such a deck was refused with a nonsense
/// measure ("flange height is 260 mm": the pilots were taken for the flange) and no guide.
#[test]
fn verification_found_sets_of_a_stepped_liner_equal_the_generators() {
    found_sets_equal_the_generators(&["liner.pilot_diameter_mm=146"]);
}

/// The default engine with `sets`, moved out of its frames and stripped of its sets: the
/// found sets must be the generator's, node for node (see above).
fn found_sets_equal_the_generators(sets: &[&str]) {
    let (lm0, cm0, shape0, axis_x, depths, bore) = default_meshes(sets);
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
        (s.pilot_radius, shape0.pilot_radius),
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

/// Verification (session 84): the liner's wet surface is the coolant jacket's, from the guide
/// band's top to the deck plate's underside (228 mm on the default engine: seat 248 mm, deck
/// 20 mm); it reached the flange, so the coolant layer's mass and the maps covered the 20 mm
/// the deck bore holds. Node heights are exact lattice values, so the bounds are to roundoff.
#[test]
fn verification_the_wet_surface_ends_at_the_deck_underside() {
    let (lm, _, shape, ..) = default_meshes(&[]);
    let scene = load_scene(Path::new("models/engine.toml"), &[]).unwrap();
    let g = &scene.liner_geometry;
    let cc = scene.crankcase.as_ref().unwrap();
    let CrankcaseSource::Parametric { geometry: c, .. } = &cc.source else {
        panic!("the crankcase is parametric")
    };
    let (guide_top, deck) = (g.guide_bottom + g.guide_height, c.seat_z - c.deck_thickness);
    assert!((deck - (shape.seat_z - 0.020)).abs() < 1e-9, "{deck}");
    let z: Vec<f64> = lm.node_sets["coolant_wetted"]
        .iter()
        .map(|&n| lm.nodes[n][2])
        .collect();
    let lo = z.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!((lo - guide_top).abs() < 1e-9, "{lo} {guide_top}");
    // the highest node level at or below the deck: the next one above lies above it
    let above = lm.nodes.iter().map(|p| p[2]).filter(|&z| z > hi + 1e-9);
    let next = above.fold(f64::INFINITY, f64::min);
    assert!(
        hi <= deck + 1e-9 && next > deck + 1e-9,
        "{hi} {next} {deck}"
    );
}

/// Asserts that `mesh`'s set `name` holds exactly `want`, naming a few nodes that differ.
fn same_set(mesh: &Mesh, name: &str, want: &[usize], part: &str) {
    use std::collections::BTreeSet;
    let got: BTreeSet<usize> = mesh.node_sets[name].iter().copied().collect();
    let want: BTreeSet<usize> = want.iter().copied().collect();
    let extra: Vec<_> = got
        .difference(&want)
        .take(3)
        .map(|&n| mesh.nodes[n])
        .collect();
    let missing: Vec<_> = want
        .difference(&got)
        .take(3)
        .map(|&n| mesh.nodes[n])
        .collect();
    assert!(
        extra.is_empty() && missing.is_empty(),
        "{part} set {name}: {} found, {} expected; extra at {extra:?}, missing at {missing:?}",
        got.len(),
        want.len()
    );
}

const SMALL: &str = "tests/fixtures/engine_small.toml";

/// Writes the small engine's liner as an Abaqus part/instance deck in mm (the instance moved
/// by (100, 50, 300) mm) and its crankcase as a Nastran deck in mm whose grids and elements sit
/// in nested INCLUDE files (one name quoted over two lines), both with their materials and no
/// set; returns the scene text that uses them (no `material` keys, the fixed set as a box).
fn small_engine_as_decks(dir: &Path) -> String {
    let d = |f: &str| dir.join(f).display().to_string();
    for (part, file) in [("liner", "liner.inp"), ("crankcase", "flat.bdf")] {
        let (code, _, err) = linercav(&[
            "export-mesh",
            SMALL,
            "--part",
            part,
            "--unit",
            "mm",
            "--no-sets",
            "--out",
            &d(file),
        ]);
        assert_eq!(code, 0, "{err}");
    }
    let inp = std::fs::read_to_string(dir.join("liner.inp")).unwrap();
    assert!(!inp.contains("*NSET"));
    let inp = inp.replace("*END INSTANCE", "100.0, 50.0, 300.0\n*END INSTANCE");
    std::fs::write(dir.join("liner.inp"), inp).unwrap();
    let flat = std::fs::read_to_string(dir.join("flat.bdf")).unwrap();
    assert!(!flat.lines().any(|l| l.starts_with("SET1")));
    let lines: Vec<&str> = flat.lines().collect();
    let first_elem = lines
        .iter()
        .position(|l| l.starts_with("CHEXA") || l.starts_with("CTETRA"))
        .unwrap();
    let first_mat = lines
        .iter()
        .position(|l| l.starts_with("$ material") || l.starts_with("MAT1"))
        .unwrap();
    let grids = &lines[1..first_elem];
    let elems = &lines[first_elem..first_mat];
    let half = elems.len() / 2 - elems.len() / 2 % 2;
    let split = (half..elems.len())
        .find(|&k| elems[k].starts_with('C'))
        .unwrap();
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(dir.join("grids.bdf"), grids.join("\n") + "\n").unwrap();
    std::fs::write(
        dir.join("sub/elems.bdf"),
        elems[..split].join("\n") + "\nINCLUDE 'more.bdf'\n",
    )
    .unwrap();
    std::fs::write(dir.join("sub/more.bdf"), elems[split..].join("\n") + "\n").unwrap();
    let main = format!(
        "BEGIN BULK\nINCLUDE 'grids.bdf'\nINCLUDE 'sub/\n  elems.bdf'\n{}\n",
        lines[first_mat..].join("\n")
    );
    std::fs::write(dir.join("crankcase.bdf"), main).unwrap();
    let scene = std::fs::read_to_string(SMALL).unwrap();
    let mut out = String::new();
    let mut section = String::new();
    for l in scene.lines() {
        if l.starts_with('[') {
            section = l.split('#').next().unwrap().trim().to_string();
        }
        let key = l.split('=').next().unwrap().trim();
        if key == "material" && (section == "[liner]" || section == "[crankcase]") {
            continue;
        }
        if key == "cache_dir" {
            out += &format!("cache_dir = \"{}\"\n", d("cache"));
            continue;
        }
        out += l;
        out += "\n";
        if section == "[liner]" && l.starts_with("[liner]") {
            out += "mesh_file = \"liner.inp\"\nmesh_unit = \"mm\"\n";
        }
        if l.starts_with("[crankcase]") {
            out += "mesh_file = \"crankcase.bdf\"\nmesh_unit = \"mm\"\n";
        }
    }
    out += "\n[crankcase.sets.pan_rail]\nbox_mm = [-2000.0, -2000.0, -180.5, 2000.0, 2000.0, -179.5]\n";
    out
}

/// [`small_engine_as_decks`] written into `dir` with its scene, `dir/engine.toml`: its path.
fn decks_scene(dir: &Path) -> std::path::PathBuf {
    let sp = dir.join("engine.toml");
    std::fs::write(&sp, small_engine_as_decks(dir)).unwrap();
    sp
}

/// Writes `dir/engine.toml`: the small engine with its liner from the mm deck `deck` and its
/// cache in `dir`; returns its path.
fn liner_deck_scene(dir: &Path, deck: &Path) -> std::path::PathBuf {
    let scene = std::fs::read_to_string(SMALL)
        .unwrap()
        .replace(
            "[liner]\n",
            &format!(
                "[liner]\nmesh_file = {:?}\nmesh_unit = \"mm\"\n",
                deck.display()
            ),
        )
        .replace(
            "cache_dir = \".linercav-cache\"",
            &format!("cache_dir = {:?}", dir.join("cache").display()),
        );
    let path = dir.join("engine.toml");
    std::fs::write(&path, scene).unwrap();
    path
}

/// Asserts that two `rom --json` outputs (the parametric engine's and its decks') give at
/// least 10 system frequencies, the same within 1e-6 each (the bound's reason: the
/// verification of the small engine as mm decks).
fn same_system_frequencies(param: &serde_json::Value, decks: &serde_json::Value) {
    let (a, b) = (frequencies(param), frequencies(decks));
    assert!(a.len() >= 10 && a.len() == b.len(), "{a:?} {b:?}");
    for (k, (fa, fb)) in a.iter().zip(&b).enumerate() {
        assert!(
            (fa - fb).abs() <= 1e-6 * fa,
            "mode {k}: {fa} Hz parametric, {fb} Hz decks"
        );
    }
}

fn frequencies(v: &serde_json::Value) -> Vec<f64> {
    v["first_frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Verification: the small engine taken out as mm decks without set names or material keys
/// and read back gives the parametric engine's system frequencies. The decks hold the same
/// meshes (12-17 significant digits), the found sets are the generator's (see above), the
/// materials come from the decks: only roundoff separates the two models. The tolerance was
/// first set at 1e-7; measured, the ROM's system frequencies move by up to 4.6e-8 (1.6e-7 with
/// the moved instance) when the same mesh only passes through a 16-column Nastran deck in
/// metres (coordinates rounded at 1e-13): the Craig-Bampton chain amplifies roundoff near the
/// close pairs (1860.4 / 1861.9 Hz). 1e-6 is the bound here, 1,000 times below the issue's
/// 0.1 %; the amplification is noted in the CHANGELOG as something to look into.
#[test]
fn verification_small_engine_as_mm_decks_gives_the_parametric_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let sp = decks_scene(dir.path());
    let sp = sp.display().to_string();
    let param = json(&linercav_output(&["rom", SMALL, "--json", "--no-cache"]));
    let decks = json(&linercav_output(&["rom", &sp, "--json", "--no-cache"]));
    same_system_frequencies(&param, &decks);
    let found = &decks["interfaces"];
    let sets = found["sets"].as_array().unwrap();
    let source = |part: &str, name: &str| {
        sets.iter()
            .find(|s| s["part"] == part && s["name"] == name)
            .map(|s| s["source"].as_str().unwrap().to_string())
    };
    assert_eq!(source("liner", "flange_seat").as_deref(), Some("geometry"));
    assert_eq!(source("crankcase", "guide_2").as_deref(), Some("geometry"));
    assert_eq!(source("crankcase", "pan_rail").as_deref(), Some("box"));
    let mats = found["materials"].as_array().unwrap();
    assert!(
        mats.iter().all(|m| m.as_str().unwrap().contains("deck")),
        "{mats:?}"
    );
    // the liner instance was moved by (100, 50, 300) mm: placing it back is what the equal
    // frequencies above show; the generated engine reports nothing found
    assert!(param["interfaces"].is_null());
}

/// Verification (session 84): with the coolant layer on, the small engine as mm decks (the
/// wet surface found on the liner deck, ended at the crankcase deck's deck bore) and its
/// generated liner in its crankcase as a deck (the generator's set ended there) give the
/// parametric engine's system frequencies, whose generator ends the set at the scene's deck
/// (the height itself: `verification_the_wet_surface_ends_at_the_deck_underside`). The
/// bound is the roundoff bound of the test above (1e-6), kept; the decks' wet surface left
/// to the flange moves the first mode by 8.8e-4 (seen failing so).
#[test]
fn verification_the_coolant_layer_on_mm_decks_gives_the_parametric_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let layer = |scene: &Path| {
        let scene = scene.to_str().unwrap();
        json(&linercav_output(&[
            "rom",
            scene,
            "--json",
            "--no-cache",
            "--set",
            "cavitation.coolant_mass=layer",
        ]))
    };
    let param = layer(Path::new(SMALL));
    same_system_frequencies(&param, &layer(&decks_scene(dir.path())));
    export_crankcase_mm_with_sets(&dir.path().join("cc.inp"));
    let scene = std::fs::read_to_string(SMALL)
        .unwrap()
        .replace(
            "[crankcase]\n",
            "[crankcase]\nmesh_file = \"cc.inp\"\nmesh_unit = \"mm\"\n",
        )
        .replace(
            "cache_dir = \".linercav-cache\"",
            &format!("cache_dir = {:?}", dir.path().join("cache").display()),
        );
    let path = dir.path().join("cc.toml");
    std::fs::write(&path, scene).unwrap();
    same_system_frequencies(&param, &layer(&path));
}

/// Verification: the small engine with a stepped liner (`liner.pilot_diameter_mm = 140`: guide
/// band and deck bore 2.5 mm proud of the 135 mm wet wall), both parts taken out as mm decks
/// and read back, gives the parametric engine's system frequencies within 1e-6 (the bound and
/// its reason as in the plain decks' verification above). Before, the deck was refused with a
/// flange "260 mm" high (the pilots taken for the flange) and no guide bore found.
#[test]
fn verification_a_stepped_liner_as_mm_decks_gives_the_parametric_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let sp = decks_scene(dir.path());
    let pilot = "liner.pilot_diameter_mm=140";
    export_mm("liner", &[pilot], &dir.path().join("liner.inp"));
    export_mm("crankcase", &[pilot], &dir.path().join("crankcase.inp"));
    let sp = sp.display().to_string();
    let param = json(&linercav_output(&[
        "rom",
        SMALL,
        "--json",
        "--no-cache",
        "--set",
        pilot,
    ]));
    let decks = json(&linercav_output(&[
        "rom",
        &sp,
        "--json",
        "--no-cache",
        "--set",
        "crankcase.mesh_file=\"crankcase.inp\"",
        "--set",
        pilot,
    ]));
    same_system_frequencies(&param, &decks);
    let liner = &decks["interfaces"]["liner"];
    assert!((liner["pilot_radius"].as_f64().unwrap() - 0.070).abs() < 1e-9);
    assert!((liner["outer_radius"].as_f64().unwrap() - 0.0675).abs() < 1e-9);
}

/// Regression: the small engine with its bores 149 mm apart (the 148 mm flanges' counterbores
/// 1 mm apart) built from its parameters, but its own exported crankcase deck was refused:
/// the seat found from the geometry took, within the finder's mesh tolerance, a bridge node
/// 0.125 mm beyond the flange's rim, which the engine's fit check then rejected ("node 1508 ...
/// is not under the liner flange"). The deck now gives the parametric frequencies (1e-6, as the
/// verification above).
#[test]
fn regression_close_counterbores_of_a_deck_are_seated() {
    let dir = tempfile::tempdir().unwrap();
    let pitch = "engine.cylinder_pitch_mm=149";
    let text = small_engine_as_decks(dir.path());
    let cc = dir.path().join("crankcase.bdf");
    export_mm("crankcase", &[pitch], &cc);
    let sp = dir.path().join("engine.toml");
    std::fs::write(&sp, text).unwrap();
    let sp = sp.display().to_string();
    let param = json(&linercav_output(&[
        "rom",
        SMALL,
        "--json",
        "--no-cache",
        "--set",
        pitch,
    ]));
    let decks = json(&linercav_output(&[
        "rom",
        &sp,
        "--json",
        "--no-cache",
        "--set",
        pitch,
    ]));
    same_system_frequencies(&param, &decks);
}

/// Regression: a crankcase deck with a stray element (a second piece, joined to nothing)
/// failed in the factorisation ("not positive definite", exit 1, no file named), and a liner
/// with one was placed with a wrong bore; a part in pieces is refused naming the file.
#[test]
fn regression_a_part_in_two_pieces_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let sp = decks_scene(dir.path());
    let more = dir.path().join("sub/more.bdf");
    let text = std::fs::read_to_string(&more).unwrap();
    let first = text.lines().find(|l| l.starts_with('C')).unwrap();
    let pid = first[16..24].trim().to_string();
    let mut stray = String::new();
    for (k, (x, y, z)) in [(0, 0, 0), (10, 0, 0), (0, 10, 0), (0, 0, 10)]
        .iter()
        .enumerate()
    {
        stray += &format!("GRID,{},,{x}.,{y}.,{}.\n", 9_000_001 + k, 1000 + z);
    }
    stray += &format!("CTETRA,9000001,{pid},9000001,9000002,9000003,9000004\n");
    std::fs::write(&more, text + &stray).unwrap();
    let err = refused(
        &["rom", sp.to_str().unwrap(), "--no-cache"],
        2,
        "crankcase.bdf",
    );
    assert!(
        err.contains("2 disconnected pieces") && err.contains(", 1 elements"),
        "{err}"
    );
}

/// Regression: a missing INCLUDE file of a scene's deck was reported as "cannot read mesh
/// file" by the cache key, naming the missing file but not the file and line that include it.
#[test]
fn regression_a_missing_include_names_the_including_line() {
    let dir = tempfile::tempdir().unwrap();
    let sp = decks_scene(dir.path());
    std::fs::remove_file(dir.path().join("sub/more.bdf")).unwrap();
    let err = refused(
        &["rom", sp.to_str().unwrap(), "--no-cache"],
        2,
        "elems.bdf:",
    );
    assert!(err.contains("INCLUDE") && err.contains("more.bdf"), "{err}");
}

/// Verification: `modes --mesh liner.inp --unit mm` without material flags takes the deck's
/// material and gives the modes of the scene's liner (same mesh, same material: 1e-6 relative
/// is the bound, roundoff is far below it); the same deck read in metres is refused
/// (exit 2) naming --unit, before any solve.
#[test]
fn verification_modes_of_an_mm_deck_with_its_own_material() {
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("liner.inp").display().to_string();
    let (code, _, err) = linercav(&[
        "export-mesh",
        SMALL,
        "--part",
        "liner",
        "--unit",
        "mm",
        "--no-sets",
        "--out",
        &deck,
    ]);
    assert_eq!(code, 0, "{err}");
    let scene = json(&linercav_output(&[
        "modes", SMALL, "--part", "liner", "--count", "12", "--json",
    ]));
    let mesh = json(&linercav_output(&[
        "modes", "--mesh", &deck, "--unit", "mm", "--count", "12", "--json",
    ]));
    let (a, b) = (common::freqs(&scene), common::freqs(&mesh));
    for (k, (fa, fb)) in a.iter().zip(&b).enumerate().skip(6) {
        assert!((fa - fb).abs() <= 1e-6 * fa, "mode {k}: {fa} vs {fb}");
    }
    assert!(mesh["material"].as_str().unwrap().starts_with("deck"));
    let (code, _, err) = linercav(&["modes", "--mesh", &deck, "--unit", "m", "--count", "12"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--unit") && err.contains("liner.inp"), "{err}");
    // refused on reading: the message is the size check's, not a failed certification
    assert!(err.contains("across read in m"), "{err}");
}

/// The first `n` frequencies [Hz] of a cantilevered box mesh.
fn cantilever_frequencies(
    mesh: Mesh,
    fallback: &linercav::scene::spec::Elastic,
    n: usize,
) -> Vec<f64> {
    let mut model =
        linercav::fem::model::FeModel::build(mesh, fallback, &["x0".to_string()]).unwrap();
    let sol = model
        .modes(n, -(2.0 * std::f64::consts::PI * 10.0).powi(2), 4)
        .unwrap();
    (0..n).map(|j| sol.modes.frequency_hz(j)).collect()
}

/// Verification: deck materials are assembled per element. A cantilevered box whose two halves
/// carry materials A and A gives the modes of the box with A (to roundoff: the same matrices);
/// B = A with E four times larger gives every frequency exactly twice as high (f ~ sqrt(E/rho)
/// for a body of one material); halves A and B lie strictly between the two.
#[test]
fn verification_deck_materials_are_assembled_per_element() {
    use linercav::mesh::{DeckMaterial, NO_MATERIAL};
    use linercav::scene::spec::Elastic;
    let a = Elastic {
        young: 110e9,
        poisson: 0.28,
        density: 7200.0,
    };
    let b = Elastic {
        young: 4.0 * 110e9,
        ..a
    };
    let base = common::box_mesh(
        linercav::scene::spec::ElementKind::Hex8,
        [8, 2, 2],
        [0.4, 0.05, 0.05],
        0.0,
    );
    let with = |first: Elastic, second: Elastic| {
        let mut m = base.clone();
        m.materials = vec![
            DeckMaterial {
                name: "first".into(),
                elastic: first,
            },
            DeckMaterial {
                name: "second".into(),
                elastic: second,
            },
        ];
        let ne = m.num_elements();
        m.element_material = vec![NO_MATERIAL; ne];
        for (e, (_, nodes)) in base.elements().enumerate() {
            let x: f64 = nodes.iter().map(|&k| base.nodes[k][0]).sum::<f64>() / nodes.len() as f64;
            m.element_material[e] = if x < 0.2 { 0 } else { 1 };
        }
        m
    };
    let plain = cantilever_frequencies(base.clone(), &a, 6);
    let aa = cantilever_frequencies(with(a, a), &b, 6);
    let bb = cantilever_frequencies(with(b, b), &a, 6);
    let ab = cantilever_frequencies(with(a, b), &a, 6);
    for k in 0..6 {
        assert!(
            (aa[k] - plain[k]).abs() <= 1e-10 * plain[k],
            "mode {k}: {} vs {}",
            aa[k],
            plain[k]
        );
        assert!(
            (bb[k] - 2.0 * plain[k]).abs() <= 1e-10 * plain[k],
            "mode {k}: {} vs 2 x {}",
            bb[k],
            plain[k]
        );
        assert!(
            ab[k] > plain[k] * (1.0 + 1e-6) && ab[k] < bb[k] * (1.0 - 1e-6),
            "mode {k}: {}",
            ab[k]
        );
    }
}

/// Regression (issue 40): an empty `mesh_file` was read as the scene's directory ("cannot read
/// mesh file small/"); it is refused naming the key. So is (session 70's hostile sweep) a
/// missing file or a directory, which were reported by the file's name alone.
#[test]
fn regression_empty_or_missing_mesh_file_is_refused_by_key() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("adir.inp")).unwrap();
    for (value, says) in [
        ("", "is empty"),
        ("nothere.inp", "'nothere.inp'"),
        ("adir.inp", "is not a regular file"),
    ] {
        let text = std::fs::read_to_string(SMALL)
            .unwrap()
            .replace("[liner]\n", &format!("[liner]\nmesh_file = \"{value}\"\n"));
        let p = dir.path().join("engine.toml");
        std::fs::write(&p, text).unwrap();
        let (code, _, err) = linercav(&["rom", &p.display().to_string(), "--no-cache"]);
        assert_eq!(code, 2, "{value}: {err}");
        assert!(
            err.contains("key 'liner.mesh_file'") && err.contains(says),
            "{value}: {err}"
        );
    }
}

/// Regression (session 70's review): the material bounds (E, density, wave speed) held a
/// deck's dummy materials too, which carry no solid (a "massless" MAT1 of 1e-3 kg/m^3 for
/// connectors refused the whole deck); only the materials solid elements use are checked,
/// and those are refused with their name.
#[test]
fn regression_only_the_materials_of_solids_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("dummy.bdf");
    let write = |pid_mat: &str| {
        std::fs::write(
            &deck,
            format!(
                "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n\
                 GRID,5,,1.,1.,1.\nCTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,4,5\nPSOLID,1,{pid_mat}\n\
                 MAT1,1,2.1e11,,0.3,7850.\nMAT1,2,2.1e13,,0.3,1e-3\nENDDATA\n"
            ),
        )
        .unwrap();
    };
    let args = ["modes", "--mesh", deck.to_str().unwrap(), "--count", "2"];
    write("1");
    let (code, _, err) = common::linercav(&args);
    assert_eq!(code, 0, "{err}");
    write("2");
    let (code, _, err) = common::linercav(&args);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("'MAT1 2'") && err.contains("density"), "{err}");
}

/// Regression: a material given on the command line (or in the scene) over a deck that
/// defines other constants replaced them silently (noted in the log only); it is warned of,
/// naming the deck's material, and the same constants as the deck's are not.
#[test]
fn regression_a_given_material_over_a_different_deck_material_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("steel.bdf");
    std::fs::write(
        &deck,
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nGRID,5,,1.,1.,1.\n\
         CTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,4,5\nPSOLID,1,1\nMAT1,1,2.1e11,,0.3,7850.\nENDDATA\n",
    )
    .unwrap();
    let run = |e: &str, nu: &str, rho: &str| {
        let args = ["modes", "--mesh", deck.to_str().unwrap(), "--count", "2"];
        let mut args = args.to_vec();
        args.extend(["--youngs", e, "--poisson", nu, "--density", rho]);
        let (code, _, err) = common::linercav(&args);
        assert_eq!(code, 0, "{err}");
        err
    };
    let err = run("1.2e11", "0.26", "7200");
    assert!(
        err.contains("replaces the deck's material 'MAT1 1'") && err.contains("210.0000 GPa"),
        "{err}"
    );
    // and among the run's warnings in its JSON
    let out = linercav_output(&[
        "modes",
        "--mesh",
        deck.to_str().unwrap(),
        "--count",
        "2",
        "--youngs",
        "1.2e11",
        "--poisson",
        "0.26",
        "--density",
        "7200",
        "--json",
    ]);
    let warnings = json(&out)["warnings"].to_string();
    assert!(
        warnings.contains("replaces the deck's material"),
        "{warnings}"
    );
    let err = run("2.1e11", "0.3", "7850");
    assert!(!err.contains("replaces the deck's material"), "{err}");
}

/// Regression: a crankcase deck that names its own guide sets, and a fixed set of the deck
/// (`crankcase.fix`), had them left out of what `rom` lists of the imported meshes (found sets
/// were listed, named guide sets and fixed sets were not): each is listed as the deck's, with
/// its node count, the fixed set marked as fixed.
#[test]
fn regression_a_decks_own_guide_and_fixed_sets_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("crankcase.bdf");
    export_crankcase_mm_with_sets(&deck);
    let mut scene = String::new();
    let mut section = String::new();
    for l in std::fs::read_to_string(SMALL).unwrap().lines() {
        if l.starts_with('[') {
            section = l.split('#').next().unwrap().trim().to_string();
        }
        let key = l.split('=').next().unwrap().trim();
        if section == "[crankcase]" && key == "material" {
            continue;
        }
        scene += l;
        scene += "\n";
        if l.starts_with("[crankcase]") {
            scene += "mesh_file = \"crankcase.bdf\"\nmesh_unit = \"mm\"\n";
        }
    }
    let sp = dir.path().join("engine.toml");
    std::fs::write(&sp, scene).unwrap();
    let out = json(&linercav_output(&[
        "rom",
        &sp.display().to_string(),
        "--json",
        "--no-cache",
    ]));
    let sets = out["interfaces"]["sets"].as_array().unwrap();
    let listed = |name: &str| {
        sets.iter()
            .find(|s| s["part"] == "crankcase" && s["name"] == name)
            .unwrap_or_else(|| panic!("{name} not listed: {sets:?}"))
    };
    let cm = generated_crankcase(&load_scene(Path::new(SMALL), &[]).unwrap());
    for name in ["guide_1", "guide_2", "pan_rail"] {
        let s = listed(name);
        assert_eq!(s["source"], "deck", "{s}");
        assert_eq!(s["nodes"], cm.node_sets[name].len(), "{s}");
    }
    assert!(listed("pan_rail")["detail"]
        .as_str()
        .unwrap()
        .contains("fixed"));
}

/// Regression (session 78, a hostile-input sweep): a liner deck's own sets were taken as given,
/// and a liner deck under a generated crankcase was not compared with the scene's liner. All
/// of these ran with exit 0 and moved results without a word: the bore lines swapped (every
/// peak changed), an analysis point of two nodes (point 1 reported point 2's response), an
/// analysis point on the bore, and a scene wall 5.5 mm thicker than the deck's (the crankcase
/// built around a liner that was not there: first system mode 524.0 -> 509.6 Hz), and a scene
/// pilot 1 mm wider than the deck's (within the 1 % once allowed, the generated crankcase's
/// bore tied to the liner across a 0.5 mm gap; session 80's review). Each is now
/// refused, exit 2, naming the set or the scene key; points swapped in depth are warned of,
/// naming both depths (a deck may place its sensors where the engine has them).
#[test]
fn regression_a_liner_decks_sets_and_size_are_checked_against_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let deck = std::fs::read_to_string("tests/fixtures/liner_hex20.inp").unwrap();
    let point_1 = "*NSET, NSET=point_1\n891\n";
    assert!(deck.contains(point_1), "the fixture's point_1");
    let swap =
        |text: &str, a: &str, b: &str| text.replace(a, "\u{0}").replace(b, a).replace('\u{0}', b);
    let scene = |file: &str, sets: &[&str]| -> Vec<String> {
        let mut args = vec![
            "rom".to_string(),
            SMALL.to_string(),
            "--no-cache".to_string(),
            "--set".to_string(),
            format!("liner.mesh_file=\"{}\"", dir.path().join(file).display()),
            // stops after the meshes are read and checked
            "--set".to_string(),
            "limits.max_memory_gb=0.01".to_string(),
        ];
        for s in sets {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        args
    };
    let cases: [(&str, String, &[&str], &str); 5] = [
        (
            "bore_swap.inp",
            swap(&deck, "NSET=bore_thrust\n", "NSET=bore_antithrust\n"),
            &[],
            "'bore_thrust' must lie on the bore, thrust side",
        ),
        (
            "two.inp",
            deck.replace(point_1, "*NSET, NSET=point_1\n891,779\n"),
            &[],
            "'point_1' holds 2 nodes",
        ),
        (
            "inner.inp",
            deck.replace(point_1, "*NSET, NSET=point_1\n892\n"),
            &[],
            "'point_1' must be a node of the outer (coolant) wall",
        ),
        (
            "thick.inp",
            deck.clone(),
            &["liner.outer_diameter_mm=146"],
            "scene key liner.pilot_diameter_mm",
        ),
        (
            "pilot.inp",
            deck.clone(),
            &["liner.pilot_diameter_mm=136"],
            "pilot diameter is 135 mm, the scene's 136 mm",
        ),
    ];
    for (file, text, sets, says) in &cases {
        std::fs::write(dir.path().join(file), text).unwrap();
        let args = scene(file, sets);
        let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        let (code, _, err) = linercav(&args);
        assert_eq!(code, 2, "{file}: {err}");
        assert!(err.contains(says) && err.contains(*file), "{file}: {err}");
    }
    // the fixture as it is passes these checks (and stops at the memory limit)
    let args = scene("thick.inp", &[]);
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
    let (_, _, err) = linercav(&args);
    assert!(
        err.contains("limits.max_memory_gb") && !err.contains("warning"),
        "{err}"
    );
    // points 1 and 4 swapped: warned of, both depths named
    let p4 = "*NSET, NSET=point_4\n";
    let swapped = deck.replace(point_1, "*NSET, NSET=point_1\nP4\n");
    let at4 = deck[deck.find(p4).unwrap() + p4.len()..]
        .lines()
        .next()
        .unwrap()
        .to_string();
    let swapped = swapped
        .replace(&format!("{p4}{at4}\n"), &format!("{p4}891\n"))
        .replace("point_1\nP4\n", &format!("point_1\n{at4}\n"));
    std::fs::write(dir.path().join("swap.inp"), swapped).unwrap();
    let args = scene("swap.inp", &[]);
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
    let (_, _, err) = linercav(&args);
    assert!(
        err.contains("'point_1' lies 115 mm below") && err.contains("put point 1 at 40 mm"),
        "{err}"
    );
}

/// Regression (session 78, a hostile-input sweep): a deck's constraints (Abaqus `*BOUNDARY`,
/// Nastran `SPC1`) are read past, by design (linercav holds the sets named by `--fix` or a
/// part's `fix` key), but silently: a user who clamped the deck got free-free modes with only
/// "free-free" in the output to say so. Each is now warned of, naming the file and the line.
#[test]
fn regression_a_decks_constraints_not_applied_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = "1, 0., 0., 0.\n2, 1., 0., 0.\n3, 0., 1., 0.\n4, 0., 0., 1.\n5, 1., 1., 1.\n";
    let inp = format!(
        "*Node\n{nodes}*Element, type=C3D4, elset=solid\n1, 1, 2, 3, 4\n2, 2, 3, 4, 5\n\
         *Nset, nset=base\n1, 2, 3\n*Material, name=steel\n*Elastic\n2.1e11, 0.3\n*Density\n7850.\n\
         *Solid Section, elset=solid, material=steel\n*Step\n*Frequency\n5\n*Boundary\nbase, 1, 3\n*End Step\n"
    );
    let bdf =
        "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n\
               GRID,5,,1.,1.,1.\nCTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,4,5\nPSOLID,1,1\n\
               MAT1,1,2.1e11,,0.3,7850.\nSPC1,1,123,1,2,3\nENDDATA\n";
    for (name, text, says) in [
        ("bc.inp", inp.as_str(), "bc.inp:21: *BOUNDARY"),
        ("bc.bdf", bdf, "bc.bdf:11: SPC1"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let (code, _, err) = linercav(&["modes", "--mesh", path.to_str().unwrap(), "--count", "2"]);
        assert_eq!(code, 0, "{name}: {err}");
        assert!(
            err.contains(says) && err.contains("not applied"),
            "{name}: {err}"
        );
    }
}

/// Regression (session 78, a hostile-input sweep): a MAT1's G beside E and NU was ignored even
/// when negative or a third off; it is refused when not positive and warned of beyond 1 % of
/// E / (2 (1 + NU)) (E and NU are used), and a consistent one passes without a word.
#[test]
fn regression_a_mat1_shear_modulus_against_e_and_nu_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let deck = |g: &str| {
        format!(
            "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n\
             GRID,5,,1.,1.,1.\nCTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,4,5\nPSOLID,1,1\n\
             MAT1,1,2.1e11,{g},0.3,7850.\nENDDATA\n"
        )
    };
    let path = dir.path().join("g.bdf");
    let run = |g: &str| {
        std::fs::write(&path, deck(g)).unwrap();
        linercav(&["modes", "--mesh", path.to_str().unwrap(), "--count", "2"])
    };
    let (code, _, err) = run("8.08e10");
    assert!(code == 0 && !err.contains("warning"), "{err}");
    let (code, _, err) = run("5e10");
    assert!(
        code == 0 && err.contains("g.bdf:10: MAT1: G = 5e10 differs"),
        "{err}"
    );
    let (code, _, err) = run("-5e10");
    assert!(
        code == 2 && err.contains("g.bdf:10") && err.contains("G (field 4)"),
        "{err}"
    );
}

/// Regression: a liner deck's length was compared with the scene's `liner.length_mm` only under
/// a generated crankcase. Under a deck crankcase (which is seated on the liner whatever its
/// length) a 240 mm liner deck in a 260 mm scene ran with exit 0: the transient places the
/// pistons from the scene's liner top, so they ran 20 mm high on the bore lines and the small
/// engine's peaks halved. Now refused, exit 2, naming the key and both lengths.
#[test]
fn regression_a_liner_decks_length_is_checked_under_a_deck_crankcase() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let run = |sets: &[&str]| read_and_checked(&scene, sets);
    let (code, _, err) = run(&["liner.length_mm=240"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("liner.inp")
            && err.contains("liner.length_mm")
            && err.contains("the liner mesh is 260 mm long, the scene's 240 mm"),
        "{err}"
    );
    // the scene's own length passes this check (and stops at the memory limit)
    let (_, _, err) = run(&[]);
    assert!(err.contains("limits.max_memory_gb"), "{err}");
}

/// Regression (session 79, a sweep of decks against their scene): a liner deck whose flange is
/// 3 mm higher than the crankcase deck's counterbore is deep seats the crankcase 3 mm lower,
/// and its guide bore then reaches below the liner's bottom. Those faces were dropped, the
/// deck plate's bore under the seat was taken for the guide, and the liner hung from the deck
/// with its lower end free: slap +30-39 %, point 1 -38 %, exit 0. The guide now counts from the
/// liner's bottom up, with a warning naming the depth; on the small engine's one-element guide
/// that leaves too little to couple, and the build stops (exit 2) instead of answering.
#[test]
fn regression_a_guide_bore_below_the_liners_bottom_is_not_replaced_by_the_deck_bore() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    export_mm(
        "liner",
        &["liner.flange_height_mm=15"],
        &dir.path().join("liner.inp"),
    );
    let (code, _, err) = linercav(&["rom", scene.to_str().unwrap(), "--no-cache"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("guide bore reaches 3 mm below the liner's bottom")
            && err.contains("coupled over z 0..27 mm only"),
        "{err}"
    );
}

/// Regression (session 79, a sweep of decks against their scene): with both parts from decks,
/// the scene's liner pilot diameter, flange diameter and flange height are not used, yet a
/// scene edited in them ran without a word (the results to the bit the same, only the ROM
/// rebuilt for the new cache key). Each differing key is now warned of, naming both values.
#[test]
fn regression_scene_liner_sizes_unused_under_decks_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let run = |sets: &[&str]| read_and_checked(&scene, sets).2;
    let err = run(&["liner.outer_diameter_mm=140", "liner.flange_height_mm=15"]);
    assert!(
        err.contains(
            "wet wall's outer diameter is 135 mm, the scene's liner.outer_diameter_mm 140 mm"
        ) && err.contains("flange height is 12 mm, the scene's liner.flange_height_mm 15 mm")
            && err.contains("the scene's value is not used"),
        "{err}"
    );
    assert!(!run(&[]).contains("is not used"));
}

/// `rom SCENE --no-cache` with `sets`, stopped by a tiny memory limit after the meshes are read
/// and checked: (exit code, stdout, stderr).
fn read_and_checked(scene: &Path, sets: &[&str]) -> (i32, String, String) {
    let mut args = vec!["rom", scene.to_str().unwrap(), "--no-cache"];
    args.extend(["--set", "limits.max_memory_gb=0.01"]);
    for s in sets {
        args.extend(["--set", s]);
    }
    linercav(&args)
}

/// Regression (session 79, a sweep of decks against their scene): a crankcase deck of a
/// 3-cylinder engine moved so that two of its bores sit on a 2-cylinder scene's axes ran with
/// its third bore empty, exit 0 (points 3-10 % off). An empty bore of the liner's size beyond
/// the scene's cylinders is now warned of, naming its axis; the deck as written (no extra bore)
/// gives no such warning.
#[test]
fn regression_an_empty_bore_beyond_the_scenes_cylinders_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let deck = dir.path().join("three.inp");
    export_mm(
        "crankcase",
        &["engine.cylinders=3", "engine.firing_order=[1,3,2]"],
        &deck,
    );
    // bores at x = -152, 0, 152 mm moved to -76, 76, 228 (the scene's at -76 and 76)
    let text = std::fs::read_to_string(&deck).unwrap();
    let text = text.replace("*END INSTANCE", "76.0, 0.0, 0.0\n*END INSTANCE");
    std::fs::write(&deck, text).unwrap();
    let err = read_and_checked(&scene, &["crankcase.mesh_file=\"three.inp\""]).2;
    assert!(
        err.contains("three.inp: the crankcase has a bore at x = 228 mm beyond the scene's 2 cylinders (bores at x = -76, 76 mm)"),
        "{err}"
    );
    assert!(!read_and_checked(&scene, &[])
        .2
        .contains("beyond the scene's"));
}

/// Regression (session 79's deck sweep): a crankcase deck whose deck plate is 60 mm thick
/// (the scene's `crankcase.deck_thickness_mm` 20 mm) put analysis point 1, 40 mm below the
/// liner top, inside the plate, exit 0: its response was reported as a coolant-side one. The
/// coolant zone is now taken from the deck (the plate's bore against the guide band) and
/// such a point refused, naming the point, the depth keys and the zone.
#[test]
fn regression_an_analysis_point_inside_a_crankcase_decks_plate_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let deck = dir.path().join("thick.inp");
    export_mm(
        "crankcase",
        &[
            "crankcase.deck_thickness_mm=60",
            "liner.analysis_first_depth_mm=80",
        ],
        &deck,
    );
    let (code, _, err) = read_and_checked(&scene, &["crankcase.mesh_file=\"thick.inp\""]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("thick.inp")
            && err.contains(
                "analysis point 1 (40 mm below the liner top: liner.analysis_first_depth_mm"
            )
            && err.contains("inside the crankcase's deck plate")
            && err.contains("72..230 mm below the liner top"),
        "{err}"
    );
    // the same deck with the points in its coolant zone passes this check (and stops at the
    // memory limit)
    let err = read_and_checked(
        &scene,
        &[
            "crankcase.mesh_file=\"thick.inp\"",
            "liner.analysis_first_depth_mm=80",
        ],
    )
    .2;
    assert!(err.contains("limits.max_memory_gb"), "{err}");
}

/// Regression (session 79's note): a deck's warnings were said on standard error while the
/// ROM was built, and nowhere after: a later run on the cached ROM (`rom`, `simulate --json`,
/// whose `warnings` array was empty) did not tell them. The ROM now keeps its build's
/// warnings: `rom --json` lists them, and `rom` from the cache tells them again.
#[test]
fn regression_a_cached_roms_build_warnings_are_told_again() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let sp = scene.to_str().unwrap();
    let unused = "flange height is 12 mm, the scene's liner.flange_height_mm 15 mm";
    let args = ["rom", sp, "--set", "liner.flange_height_mm=15"];
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains(unused), "{err}");
    let (code, out, _) = linercav(&args);
    assert_eq!(code, 0);
    assert!(
        out.contains("hit cache") && out.contains("warning of its build: "),
        "{out}"
    );
    assert!(out.contains(unused), "{out}");
    let mut json_args = args.to_vec();
    json_args.push("--json");
    let v = json(&linercav_output(&json_args));
    let warnings = v["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains(unused)),
        "{warnings:?}"
    );
}

/// Regression (a sweep of stepped decks, session 80): a liner whose lower guide (139 mm) is
/// narrower than its deck pilot (140 mm), as real wet liners are made, in a crankcase deck
/// bored to match. Its upper pilot, wider than everything below it, was taken for the flange:
/// "flange height 32 mm", the crankcase moved 20 mm down, then "'flange_seat': cannot carry
/// the interface field" (exit 2). The flange now starts at the highest face facing down.
#[test]
fn regression_a_lower_guide_narrower_than_the_deck_pilot_is_measured() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let pilot = "liner.pilot_diameter_mm=140";
    let (liner, crank) = (dir.path().join("liner.inp"), dir.path().join("c.inp"));
    export_mm("liner", &[pilot], &liner);
    export_mm("crankcase", &[pilot], &crank);
    // the guide band (z <= 30 mm) to a 139 mm pilot on both parts
    let narrow = |p: [f64; 3], xc: f64| {
        let r = (p[0] - xc).hypot(p[1]);
        if p[2] < 30.01 && p[2] > -0.01 && (r - 70.0).abs() < 0.01 {
            let k = 69.5 / 70.0;
            [xc + (p[0] - xc) * k, p[1] * k, p[2]]
        } else {
            p
        }
    };
    edit_inp_nodes(&liner, &|p| narrow(p, 0.0));
    edit_inp_nodes(&crank, &|p| {
        narrow(p, if p[0] < 0.0 { -76.0 } else { 76.0 })
    });
    let (code, out, err) = linercav(&[
        "rom",
        scene.to_str().unwrap(),
        "--no-cache",
        "--json",
        "--set",
        "crankcase.mesh_file=\"c.inp\"",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("guide bore reaches"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let f = &v["interfaces"];
    let l = &f["liner"];
    let mm = |k: &str| l[k].as_f64().unwrap() * 1e3;
    assert!((mm("seat_z") - 248.0).abs() < 1e-6, "{l}");
    assert!((mm("pilot_radius") - 70.0).abs() < 1e-6, "{l}");
    assert!((mm("outer_radius") - 67.5).abs() < 1e-6, "{l}");
    assert!(f["crankcase_shift_z"].as_f64().unwrap().abs() < 1e-9, "{f}");
    assert_eq!(
        f["guide_band"][1].as_f64().map(|z| (z * 1e3).round()),
        Some(30.0)
    );
}

/// Regression (a sweep of stepped decks, session 80): a crankcase deck whose guide bore is
/// 50 mm long around a liner piloted over 30 mm coupled the liner's wet wall and taper to it
/// across a gap of up to 2.5 mm (+1.9 % on a frequency, exit 0); so did a generated crankcase
/// with `liner.guide_height_mm = 50`. The guide is now coupled over the liner's pilot only,
/// with a warning naming both bands; a matching pair gives no such warning.
#[test]
fn regression_a_guide_bore_longer_than_the_liners_pilot_is_coupled_over_the_pilot() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let pilot = "liner.pilot_diameter_mm=140";
    export_mm("liner", &[pilot], &dir.path().join("liner.inp"));
    let long = dir.path().join("long.inp");
    export_mm("crankcase", &[pilot, "liner.guide_height_mm=50"], &long);
    let err = read_and_checked(&scene, &["crankcase.mesh_file=\"long.inp\""]).2;
    assert!(
        err.contains("the crankcase's guide bore (z 0..50 mm) is longer than the liner's pilot in it (z 0..30 mm): coupled over the pilot only"),
        "{err}"
    );
    let matched = dir.path().join("matched.inp");
    export_mm("crankcase", &[pilot], &matched);
    let err = read_and_checked(&scene, &["crankcase.mesh_file=\"matched.inp\""]).2;
    assert!(!err.contains("is longer than"), "{err}");
}

/// Moves each node of the Abaqus deck `path` (its `*NODE` lines: id, x, y, z) by `f`.
fn edit_inp_nodes(path: &Path, f: &dyn Fn([f64; 3]) -> [f64; 3]) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = String::new();
    let mut nodes = false;
    for line in text.lines() {
        if line.starts_with('*') {
            nodes = line.to_uppercase().starts_with("*NODE");
        } else if nodes && !line.trim().is_empty() {
            let v: Vec<&str> = line.split(',').map(str::trim).collect();
            let p = [1, 2, 3].map(|i| v[i].parse::<f64>().unwrap());
            let q = f(p);
            out += &format!("{}, {:.15e}, {:.15e}, {:.15e}\n", v[0], q[0], q[1], q[2]);
            continue;
        }
        out += line;
        out += "\n";
    }
    std::fs::write(path, out).unwrap();
}

/// `export-mesh SMALL --part PART --unit mm --no-sets` with `sets` to `out`, which must succeed.
fn export_mm(part: &str, sets: &[&str], out: &Path) {
    let mut args = vec![
        "export-mesh",
        SMALL,
        "--part",
        part,
        "--unit",
        "mm",
        "--no-sets",
    ];
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(["--out", out.to_str().unwrap()]);
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");
}

/// A node of a liner in its own frame (z the axis) slid along the axis by up to `amp` on the
/// +y side, over z0 <= z <= z1 (amp sin^2 over the band, times y / r): the tube's surfaces stay
/// where they were (nodes slide along the wall), the node cloud becomes lopsided as an
/// unstructured deck's with a local refinement is.
fn lopsided(p: [f64; 3], z0: f64, z1: f64, amp: f64) -> [f64; 3] {
    if p[1] <= 0.0 || p[2] <= z0 || p[2] >= z1 {
        return p;
    }
    let s = (std::f64::consts::PI * (p[2] - z0) / (z1 - z0)).sin();
    let dz = amp * s * s * p[1] / p[0].hypot(p[1]);
    [p[0], p[1], p[2] + dz]
}

/// The principal axis of the nodes' second moments of largest moment (a liner's axis):
/// what placed a liner before the bore's own axis was fitted.
fn principal_axis_largest(nodes: &[[f64; 3]]) -> nalgebra::Vector3<f64> {
    let n = nodes.len() as f64;
    let c = [0, 1, 2].map(|a| nodes.iter().map(|p| p[a]).sum::<f64>() / n);
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in nodes {
        let d = nalgebra::Vector3::new(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        cov += d * d.transpose();
    }
    let e = nalgebra::SymmetricEigen::new(cov);
    e.eigenvectors.column(e.eigenvalues.imax()).into_owned()
}

/// Verification: the default liner made lopsided (nodes on its +y side slid up to 1 mm along
/// the wall), then turned by 0.2 rad and moved, is placed on its bore's axis. The bore's
/// nodes lie on an exact cylinder, so the fitted axis is exact up to roundoff: 1e-9 rad is
/// far above the fit's roundoff (coordinates to 1e-16 relative) and far below what the parts'
/// fit check resolves (15 um over a 0.3 m liner, 5e-5 rad). The lopsided cloud's principal
/// axis, which placed liners before, is checked to be off by more than 1e-4 rad, so the test
/// would catch its return (session 80: a jittered deck 1e-4 rad off was refused as "parts
/// overlap" against its crankcase).
#[test]
fn verification_a_lopsided_turned_liner_is_placed_on_its_bores_axis() {
    let (mut lm, _, shape, ..) = default_meshes(&[]);
    let l = shape.length;
    for p in &mut lm.nodes {
        *p = lopsided(*p, 0.25 * l, 0.55 * l, 1e-3);
    }
    let turn = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(nalgebra::Vector3::new(1.0, 2.0, 0.0)),
        0.2,
    );
    let shift = nalgebra::Vector3::new(0.1, -0.2, 0.3);
    move_rigidly(&mut lm, &turn, shift);
    let want = turn * nalgebra::Vector3::z();
    let off = principal_axis_largest(&lm.nodes).angle(&want);
    let off = off.min(std::f64::consts::PI - off);
    assert!(
        off > 1e-4,
        "the lopsided cloud's principal axis is only {off} rad off"
    );
    assert_placed_back(&mut lm, &turn, shift, &shape);
}

/// p -> turn p + shift for every node of `lm`.
fn move_rigidly(lm: &mut Mesh, turn: &nalgebra::Rotation3<f64>, shift: nalgebra::Vector3<f64>) {
    for p in &mut lm.nodes {
        let q = turn * nalgebra::Vector3::from(*p) + shift;
        *p = [q[0], q[1], q[2]];
    }
}

/// Asserts that `place_liner` finds the axis `turn e_z` within 1e-9 rad, the bottom centre
/// `shift` and the generated `shape`'s bore, wet wall and length within 1e-9 m (exact
/// geometry: roundoff).
fn assert_placed_back(
    lm: &mut Mesh,
    turn: &nalgebra::Rotation3<f64>,
    shift: nalgebra::Vector3<f64>,
    shape: &LinerShape,
) {
    let (found, axis, centre) = linercav::mesh::find::place_liner(lm).unwrap();
    let want = turn * nalgebra::Vector3::z();
    let got = nalgebra::Vector3::from(axis);
    assert!(got.angle(&want) < 1e-9, "axis {got:?}, want {want:?}");
    let c = nalgebra::Vector3::from(centre) - shift;
    assert!(c.norm() < 1e-9, "bottom centre off by {c:?}");
    for (a, b, what) in [
        (found.inner_radius, shape.inner_radius, "bore"),
        (found.outer_radius, shape.outer_radius, "wet wall"),
        (found.length, shape.length, "length"),
    ] {
        assert!((a - b).abs() < 1e-9, "{what}: found {a} m, generated {b} m");
    }
}

/// Verification: a liner with a recess in its bore on one side (0.5 mm deep over a quarter of
/// the bore at one node level: a few times the surface tolerance, inside the band h / 4 in
/// which bore nodes are taken), turned and moved by a known rigid motion, is placed on its
/// bore's axis within 1e-9 rad and its radii measured within 1e-9 m, as the lopsided liner
/// above: the recess's nodes are left out of the fits. Before, such a recess tilted the axis
/// (0.2 mm on 9 of the small engine's 2528 nodes: 4e-5 rad, the bore measured 10 um small,
/// exit 0).
#[test]
fn verification_a_liner_with_a_one_sided_bore_recess_is_placed_on_its_bores_axis() {
    let (mut lm, _, shape, ..) = default_meshes(&[]);
    let ri = shape.inner_radius;
    let level = lm
        .nodes
        .iter()
        .map(|p| p[2])
        .min_by(|a, b| {
            (a - 0.6 * shape.length)
                .abs()
                .total_cmp(&(b - 0.6 * shape.length).abs())
        })
        .unwrap();
    let mut moved = 0;
    for p in &mut lm.nodes {
        let r = p[0].hypot(p[1]);
        let in_quarter = p[1] > r * std::f64::consts::FRAC_1_SQRT_2;
        if (r - ri).abs() < 1e-9 && (p[2] - level).abs() < 1e-9 && in_quarter {
            let k = (r + 0.5e-3) / r;
            *p = [p[0] * k, p[1] * k, p[2]];
            moved += 1;
        }
    }
    assert!(moved >= 5, "{moved} nodes recessed");
    let turn = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(nalgebra::Vector3::new(-2.0, 1.0, 0.5)),
        0.3,
    );
    let shift = nalgebra::Vector3::new(-0.4, 0.2, 0.1);
    move_rigidly(&mut lm, &turn, shift);
    assert_placed_back(&mut lm, &turn, shift, &shape);
}

/// Verification: the small engine's liner deck turned 5 deg about its own axis (a structured
/// deck whose bore nodes then miss the thrust line by 5 mm) is turned back by the column of
/// bore nodes nearest the line and gives the parametric engine's frequencies to the 1e-6 of
/// the decks' verification above. Before, its thrust line was empty, exit 2 naming no cause.
#[test]
fn verification_a_liner_deck_turned_about_its_axis_is_turned_onto_the_thrust_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let (sn, cs) = 5f64.to_radians().sin_cos();
    edit_inp_nodes(&dir.path().join("liner.inp"), &|p| {
        [p[0] * cs - p[1] * sn, p[0] * sn + p[1] * cs, p[2]]
    });
    let param = json(&linercav_output(&["rom", SMALL, "--json", "--no-cache"]));
    let turned = json(&linercav_output(&[
        "rom",
        scene.to_str().unwrap(),
        "--json",
        "--no-cache",
    ]));
    same_system_frequencies(&param, &turned);
    let turn = turned["interfaces"]["liner_turn"].as_f64().unwrap();
    // the column's angle from nodes written with 16 digits: roundoff
    assert!(
        (turn + 5f64.to_radians()).abs() < 1e-12,
        "turned by {turn} rad"
    );
}

/// Verification: a crankcase deck 10 um off the engine frame in x (within its mesh tolerance,
/// 0.28 mm; beyond the seat's rim allowance of 7 um) is centred on the liners and gives the
/// parametric engine's frequencies to the 1e-6 of the decks' verification above (the same
/// meshes moved rigidly). Before the centring, each seat lost the rim nodes on one side and
/// the frequencies moved by 1.8e-3, exit 0.
#[test]
fn verification_a_crankcase_deck_slightly_off_the_frame_is_centred_on_the_liners() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let deck = dir.path().join("off.inp");
    export_mm("crankcase", &[], &deck);
    edit_inp_nodes(&deck, &|p| [p[0] + 0.01, p[1], p[2]]);
    let param = json(&linercav_output(&["rom", SMALL, "--json", "--no-cache"]));
    let off = json(&linercav_output(&[
        "rom",
        scene.to_str().unwrap(),
        "--json",
        "--no-cache",
        "--set",
        "crankcase.mesh_file=\"off.inp\"",
    ]));
    same_system_frequencies(&param, &off);
    let shift = &off["interfaces"]["crankcase_shift_xy"];
    let (dx, dy) = (shift[0].as_f64().unwrap(), shift[1].as_f64().unwrap());
    // the bores' circles are fitted to nodes written with 16 digits: roundoff of 1e-12 m
    assert!((dx + 1e-5).abs() < 1e-12 && dy.abs() < 1e-12, "{shift}");
}

/// Regression: the small engine's liner as an mm deck made lopsided as above (1 mm over its
/// middle) is placed on its bore's axis and seated in the crankcase deck: the run builds,
/// the axis found is the deck's z axis exactly (an axis within 1e-12 of a coordinate axis is
/// taken as it) and the bottom centre the instance's offset.
#[test]
fn regression_a_lopsided_liner_deck_is_seated_in_its_crankcase_deck() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let l_mm = 1e3
        * load_scene(Path::new(SMALL), &[])
            .unwrap()
            .liner_geometry
            .length;
    edit_inp_nodes(&dir.path().join("liner.inp"), &|p| {
        lopsided(p, 0.25 * l_mm, 0.55 * l_mm, 1.0)
    });
    let out = json(&linercav_output(&[
        "rom",
        scene.to_str().unwrap(),
        "--json",
        "--no-cache",
    ]));
    let found = &out["interfaces"];
    let numbers = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    assert_eq!(numbers(&found["liner_axis"]), [0.0, 0.0, 1.0]);
    let centre = numbers(&found["liner_centre"]);
    for (c, want) in centre.iter().zip([0.1, 0.05, 0.3]) {
        assert!((c - want).abs() < 1e-9, "bottom centre {centre:?}");
    }
}

/// Regression (session 80's review): a crankcase deck with its own sets, 2 mm off the engine
/// frame sideways, was refused as "part 'crankcase': node set 'bore 1'" (a set no deck has),
/// the node's place in metres. It is now refused naming the cylinder, the node in mm and its
/// distance from the bore axis.
#[test]
fn regression_a_crankcase_deck_off_the_engine_frame_is_refused_naming_the_cylinder() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    let deck = dir.path().join("off.inp");
    export_crankcase_mm_with_sets(&deck);
    edit_inp_nodes(&deck, &|p| [p[0], p[1] + 2.0, p[2]]);
    let (code, _, err) = linercav(&[
        "rom",
        scene.to_str().unwrap(),
        "--no-cache",
        "--set",
        "crankcase.mesh_file=\"off.inp\"",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("the crankcase around cylinder 1's liner: crankcase node")
            && err.contains("mm from the bore axis (x = -76 mm, y = 0)")
            && err.contains("the parts overlap"),
        "{err}"
    );
}

/// `export-mesh SMALL --part crankcase --unit mm` (with the generator's sets) to `out`, which
/// must succeed.
fn export_crankcase_mm_with_sets(out: &Path) {
    let out = out.to_str().unwrap();
    let args = [
        "export-mesh",
        SMALL,
        "--part",
        "crankcase",
        "--unit",
        "mm",
        "--out",
        out,
    ];
    let (code, _, err) = linercav(&args);
    assert_eq!(code, 0, "{err}");
}

/// The small engine's crankcase deck (mm, no sets; its deck plate, z 228..248 mm, in two
/// 10 mm element layers) with a counterbore as wide as the liner's flange (74 mm) and 10 mm
/// deep at each of `cylinders` (1-based): the upper layer's elements within the flange's
/// radius taken out (a node moved instead would bend the single ring of elements between
/// bore and flange, which the element checks refuse). Written to `out`.
fn counterbored_crankcase(out: &Path, cylinders: &[usize]) {
    export_mm("crankcase", &["crankcase.mesh.axial_size_mm=10"], out);
    let text = std::fs::read_to_string(out).unwrap();
    let mut nodes = std::collections::HashMap::new();
    let mut section = String::new();
    for line in text.lines() {
        if line.starts_with('*') {
            section = line.to_uppercase();
        } else if section.starts_with("*NODE") {
            let v: Vec<f64> = line.split(',').map(|t| t.trim().parse().unwrap()).collect();
            nodes.insert(v[0] as i64, [v[1], v[2], v[3]]);
        }
    }
    let in_counterbore = |n: &i64| {
        let p = nodes[n];
        let (c, xc) = if p[0] < 0.0 { (1, -76.0) } else { (2, 76.0) };
        cylinders.contains(&c) && (p[0] - xc).hypot(p[1]) < 74.0 + 0.01 && p[2] > 238.0 - 0.01
    };
    let (mut kept, mut dropped) = (String::new(), std::collections::HashSet::new());
    let mut record: (Vec<i64>, String) = (Vec::new(), String::new());
    for line in text.lines() {
        if line.starts_with('*') {
            section = line.to_uppercase();
        } else if section.starts_with("*ELEMENT") {
            record
                .0
                .extend(line.split(',').filter_map(|t| t.trim().parse::<i64>().ok()));
            record.1 += line;
            record.1 += "\n";
            if record.0.len() == 21 {
                let (ids, lines) = std::mem::take(&mut record);
                if ids[1..].iter().all(in_counterbore) {
                    dropped.insert(ids[0]);
                } else {
                    kept += &lines;
                }
            }
            continue;
        } else if section.starts_with("*ELSET") {
            let ids: Vec<String> = line
                .split(',')
                .filter_map(|t| t.trim().parse::<i64>().ok())
                .filter(|id| !dropped.contains(id))
                .map(|id| id.to_string())
                .collect();
            if !ids.is_empty() {
                kept += &(ids.join(", ") + "\n");
            }
            continue;
        }
        kept += line;
        kept += "\n";
    }
    // per_sector = 2: 8 elements around a bore between its radius and the flange's
    assert_eq!(
        dropped.len(),
        8 * cylinders.len(),
        "one ring of 8 elements a bore"
    );
    std::fs::write(out, kept).unwrap();
}

/// Regression (session 82's note): a crankcase deck whose counterbores (74 mm radius, 10 mm
/// deep) are narrower than the liner deck's flange (widened to 75.5 mm) seated the liner on
/// the deck top around them, a counterbore depth too high, exit 0. It is refused naming the
/// cylinder, the radii and the floor's depth. The same crankcase under the unchanged liner
/// (counterbores exactly as wide as the flange) seats it on their floors: the crankcase is
/// lifted by the depth against the deck without counterbores (10 mm to roundoff: the decks'
/// coordinates carry 16 digits).
#[test]
fn regression_a_counterbore_narrower_than_the_flange_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    counterbored_crankcase(&dir.path().join("cb.inp"), &[1, 2]);
    export_mm(
        "crankcase",
        &["crankcase.mesh.axial_size_mm=10"],
        &dir.path().join("plain.inp"),
    );
    let run = |deck: &str| {
        let file = format!("crankcase.mesh_file=\"{deck}\"");
        let args = [
            "rom",
            scene.to_str().unwrap(),
            "--no-cache",
            "--json",
            "--set",
            &file,
        ];
        linercav(&args)
    };
    let shift_z = |deck: &str| {
        let (code, out, err) = run(deck);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        v["interfaces"]["crankcase_shift_z"].as_f64().unwrap()
    };
    let (lifted, plain) = (shift_z("cb.inp"), shift_z("plain.inp"));
    assert!((lifted - plain - 10e-3).abs() < 1e-9, "{lifted} {plain}");
    // the liner's flange widened from 74 to 75.5 mm (its ring scaled from the bore, 67.5 mm)
    edit_inp_nodes(&dir.path().join("liner.inp"), &|p| {
        let r = p[0].hypot(p[1]);
        if p[2] < 248.0 - 0.01 || r < 67.5 + 0.01 {
            return p;
        }
        let k = (67.5 + (r - 67.5) * 8.0 / 6.5) / r;
        [p[0] * k, p[1] * k, p[2]]
    });
    let (code, _, err) = run("cb.inp");
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("cylinder 1: the liner's flange (radius 75.5 mm) would rest only on its rim, at r 74..75.5 mm")
            && err.contains("the crankcase's counterbore is narrower than the flange; the counterbore's floor is 10 mm lower"),
        "{err}"
    );
}

/// Regression (session 82's note): a crankcase deck with cylinder 1's counterbore and none at
/// cylinder 2 (its deck plate where the flange goes; the crankcase is seated on cylinder 1's
/// floor) put crankcase nodes inside cylinder 2's flange, which no check looked at (only the
/// liner's wall below the flange), exit 0. It is refused naming the node and the cause.
#[test]
fn regression_a_crankcase_node_inside_the_flange_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    counterbored_crankcase(&dir.path().join("cb.inp"), &[1]);
    let (code, _, err) = linercav(&[
        "rom",
        scene.to_str().unwrap(),
        "--no-cache",
        "--set",
        "crankcase.mesh_file=\"cb.inp\"",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("the crankcase around cylinder 2's liner: crankcase node")
            && err.contains("mm from the bore axis (x = 76 mm, y = 0), inside the liner's flange (radius 74 mm): the parts overlap (a counterbore narrower than the liner's flange, or a crankcase deck off the engine frame"),
        "{err}"
    );
}

/// Regression (session 82's note): a liner deck whose nodes slid along its axis by up to 8 mm
/// over its middle (8 sin over z 130..235 mm: the surfaces stay, the node planes move) has no
/// node plane within 6.6 mm of point 3's height (z 170 mm, 90 mm below the top: the planes
/// at 157.5 and 170 mm went to 163.36 and 177.45 mm); the point was found at the nearer one
/// with no word (the other points' planes stay within 4.5 mm, under the deck's 5 mm median
/// element edge). It is warned of, naming the point, both depths and the element size; the
/// run goes on.
#[test]
fn regression_an_analysis_point_found_off_its_depth_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let scene = decks_scene(dir.path());
    edit_inp_nodes(&dir.path().join("liner.inp"), &|p| {
        if p[2] <= 130.0 || p[2] >= 235.0 {
            return p;
        }
        let s = (std::f64::consts::PI * (p[2] - 130.0) / 105.0).sin();
        [p[0], p[1], p[2] + 8.0 * s]
    });
    let (code, _, err) = linercav(&["rom", scene.to_str().unwrap(), "--no-cache"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("liner: analysis point 3 found 96.64 mm below the liner top, its nearest node on the wet wall's thrust side, against the 90 mm the scene's")
            && err.contains("(more than the deck's median element edge, 5 mm)")
            && !err.contains("analysis point 2"),
        "{err}"
    );
}

/// Regression (a review with Gmsh's decks, session 83): the small engine's liner drawn and
/// meshed in Gmsh (`tests/fixtures/liner_gmsh_tet10.msh`, tet10 of 15 mm) has a few nodes
/// within the surface tolerance of the thrust line's plane by chance, at the liner's ends:
/// its anti-thrust and outer lines were 4 nodes each, and a finer Gmsh deck's bore line 3
/// nodes at z = 0, 255 and 260 mm. The pistons' slices were spread between the ends and the
/// peaks came out 50-60 % low against the parametric engine's, exit 0. Each line now covers
/// its surface: no gap along it wider than 4 median element edges h (`find::LINE_GAP`), from
/// the liner's bottom to its top (the outer line to the flange).
#[test]
fn regression_a_gmsh_liner_decks_thrust_lines_cover_the_liner() {
    let dir = tempfile::tempdir().unwrap();
    let deck = std::fs::canonicalize("tests/fixtures/liner_gmsh_tet10.msh").unwrap();
    let path = liner_deck_scene(dir.path(), &deck);
    let out = json(&linercav_output(&[
        "rom",
        path.to_str().unwrap(),
        "--json",
        "--no-cache",
    ]));
    let found = &out["interfaces"];
    let h = found["liner"]["tol"].as_f64().unwrap() / 0.02;
    let (length, seat) = (0.26, 0.248);
    for name in ["bore_thrust", "bore_antithrust", "outer_thrust"] {
        let set = found["sets"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["name"] == name)
            .unwrap();
        let detail = set["detail"].as_str().unwrap();
        let gap: f64 = detail
            .split("gaps up to ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .unwrap_or_else(|| panic!("{name}: {detail}"))
            .parse()
            .unwrap();
        assert!(gap <= 4.0 * h, "{name}: {detail}, h = {h}");
        // and it spans the surface: at least one node per 4 h over the length
        let span = if name == "outer_thrust" { seat } else { length };
        let nodes = set["nodes"].as_u64().unwrap() as f64;
        assert!(nodes >= span / (4.0 * h), "{name}: {nodes} nodes, h = {h}");
    }
}

/// Regression (a review with Gmsh's decks, session 83): a liner deck with no node row at the
/// guide band's top (a hex20 deck made in Gmsh: its row below 30 mm at 29.76 mm) was taken
/// for a pilot ending at that row: the crankcase's guide was narrowed to its rows below it (0
/// and 15 mm) and refused for conditioning, with a warning that the guide bore is longer than
/// the pilot, exit 2. Here the small engine's liner deck with its rows up to 53 mm moved down
/// (30 -> 29.76 mm, linearly between 0 and 53 mm: the elements keep straight edges). The
/// pilot is now measured by the faces on its radius, which run on past the row: the guide is
/// coupled over its whole band, 0..30 mm, without a warning.
#[test]
fn regression_a_liner_deck_without_a_row_at_the_guides_top_is_coupled_over_the_guide() {
    let dir = tempfile::tempdir().unwrap();
    let deck = dir.path().join("liner.inp");
    export_mm("liner", &[], &deck);
    edit_inp_nodes(&deck, &|p| {
        let z = match p[2] {
            z if z <= 30.0 => z * 29.76 / 30.0,
            z if z <= 53.0 => 29.76 + (z - 30.0) * (53.0 - 29.76) / 23.0,
            z => z,
        };
        [p[0], p[1], z]
    });
    let path = liner_deck_scene(dir.path(), &deck);
    let (code, out, err) = linercav(&["rom", path.to_str().unwrap(), "--json", "--no-cache"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("is longer than the liner's pilot"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let band = &v["interfaces"]["guide_band"];
    let (z0, z1) = (band[0].as_f64().unwrap(), band[1].as_f64().unwrap());
    assert!(z0.abs() < 1e-9 && (z1 - 0.030).abs() < 1e-9, "{band}");
}
