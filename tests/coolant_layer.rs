//! The coolant layer's normal mass on the liner's wet surface (`fem::surface`), against
//! closed-form answers: the mass a rigid motion sees, and the ovalling frequency of a ring
//! carrying a radial mass (ring theory).

use linercav::fem::model::FeModel;
use linercav::fem::surface::SurfaceMass;
use linercav::mesh::liner::{generate, LinerGeometry, LinerMeshing};
use linercav::scene::spec::Elastic;
use linercav::scene::spec::ElementKind;
use linercav::scene::{MeshSource, Scene};
use std::f64::consts::PI;
use std::path::Path;

const IRON: Elastic = Elastic {
    young: 140e9,
    poisson: 0.26,
    density: 7200.0,
};
const SIGMA: f64 = -1.0e4;

fn wet(mu: f64) -> Vec<SurfaceMass> {
    vec![SurfaceMass {
        set: "coolant_wetted".into(),
        mass_per_area: mu,
    }]
}

/// u^T (M_wet - M_dry) u for a rigid unit translation along `dir`.
fn added_mass_along(dry: &FeModel, wet: &FeModel, dir: usize) -> f64 {
    let n = dry.n_free();
    let mut u = vec![0.0; n];
    for node in 0..dry.mesh.nodes.len() {
        let d = dry.dofs.dof[3 * node + dir];
        if d != linercav::fem::dofs::FIXED {
            u[d] = 1.0;
        }
    }
    let dm: Vec<f64> = wet.km.m.iter().zip(&dry.km.m).map(|(w, d)| w - d).collect();
    let mut y = vec![0.0; n];
    dry.km.pattern.matvec(&dm, &u, &mut y);
    u.iter().zip(&y).map(|(a, b)| a * b).sum()
}

/// The default liner's wet zone (outer surface from the guide band's top to the deck plate's
/// underside, down to the mesh's last element level below it: the layer acts on whole faces)
/// is a cylinder of radius R_o and height L_w: a rigid translation across the axis
/// carries mu int(n_x^2) dA = mu pi R_o L_w, one along the axis nothing (the layer slides).
/// The 20-node faces put every node on the circle; the quadratic arc between them deviates
/// from the circle by O((pi/48)^4) ~ 2e-5 relative at 48 elements around, so 1e-4.
#[test]
fn verification_rigid_motion_of_the_default_liner_sees_mu_pi_r_l() {
    let scene = Scene::load(Path::new("models/engine.toml"), &[]).unwrap();
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        panic!("default liner is parametric")
    };
    let mesh = generate(geometry, meshing);
    let g = geometry;
    let deck = g
        .deck_underside
        .expect("the default crankcase has a deck plate");
    // the highest element level (corner height) at or below the deck's underside
    let top = (mesh.elements())
        .flat_map(|(kind, nodes)| nodes[..kind.num_corners()].to_vec())
        .map(|n| mesh.nodes[n][2])
        .filter(|&z| z < deck + 1e-9)
        .fold(f64::NEG_INFINITY, f64::max);
    let mu = 4.5;
    let dry = FeModel::build(mesh.clone(), &IRON, &[]).unwrap();
    let wet_model = FeModel::build_with(mesh, &IRON, &[], &wet(mu)).unwrap();
    let wet_length = top - (g.guide_bottom + g.guide_height);
    let expected = mu * PI * g.outer_diameter / 2.0 * wet_length;
    for dir in [0, 1] {
        let got = added_mass_along(&dry, &wet_model, dir);
        println!("translation {dir}: {got:.6} kg, mu pi R L = {expected:.6} kg");
        assert!(
            (got - expected).abs() / expected < 1e-4,
            "{got} vs {expected}"
        );
    }
    let axial = added_mass_along(&dry, &wet_model, 2);
    assert!(axial.abs() < 1e-12 * expected, "axial {axial}");
}

/// A thin ring with its whole outer surface wet. Inextensional ovalling of order n has radial
/// amplitude w and tangential w / n, so the structure's kinetic energy per mid-surface area is
/// rho t (1 + 1/n^2) w^2 / 2 and the layer's mu (R_o / R_m) w^2 / 2 (outer area per mid-surface
/// area R_o / R_m); the strain energy is unchanged, hence
///   (f_wet / f_dry)^2 = rho t (1 + 1/n^2) / (rho t (1 + 1/n^2) + mu R_o / R_m).
/// Ring theory neglects the through-wall variation of the tangential motion and rotary
/// inertia, terms of relative size (t/R)^2 / 12 ~ 5e-4 at t/R = 0.08 in each energy; the
/// mesh's own error largely cancels in the ratio. Tolerance 0.3 % on a ratio of about 0.75.
#[test]
fn verification_ovalling_of_a_wet_ring_follows_ring_theory() {
    let (ro, ri, length) = (0.065, 0.060, 0.02);
    let geo = LinerGeometry {
        outer_diameter: 2.0 * ro,
        inner_diameter: 2.0 * ri,
        length,
        flange_outer_diameter: 2.0 * ro,
        flange_height: length / 4.0,
        guide_height: length / 4.0,
        guide_bottom: 0.0,
        analysis_depths: vec![length / 2.0],
        pilot_diameter: 2.0 * ro,
        deck_underside: None,
    };
    let meshing = LinerMeshing {
        kind: ElementKind::Hex20,
        circumferential: 48,
        radial: 1,
        radial_flange: 1,
        axial_size: 0.01,
    };
    let mut mesh = generate(&geo, &meshing);
    // the whole outer surface wet
    let outer: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&i| {
            let p = mesh.nodes[i];
            ((p[0] * p[0] + p[1] * p[1]).sqrt() - ro).abs() < 1e-9
        })
        .collect();
    mesh.node_sets.insert("coolant_wetted".into(), outer);
    let (t, rm) = (ro - ri, (ro + ri) / 2.0);
    let m_wall = IRON.density * t;
    let n = 2.0f64;
    let mu = m_wall; // as heavy as the wall: a 25 % frequency drop, well above the tolerance
    let frequency = |surface: &[SurfaceMass]| {
        let mut model = FeModel::build_with(mesh.clone(), &IRON, &[], surface).unwrap();
        let sol = model.modes(8, SIGMA, 4).unwrap();
        assert!(sol.sturm.as_ref().unwrap().ok);
        // modes 6 and 7: the ovalling pair
        (sol.modes.frequency_hz(6), sol.modes.frequency_hz(7))
    };
    let (d6, d7) = frequency(&[]);
    let (w6, w7) = frequency(&wet(mu));
    let expected =
        (m_wall * (1.0 + 1.0 / (n * n)) / (m_wall * (1.0 + 1.0 / (n * n)) + mu * ro / rm)).sqrt();
    println!("n=2 dry {d6:.2}/{d7:.2} Hz, wet {w6:.2}/{w7:.2} Hz: ratio {:.5}, ring theory {expected:.5}", w6 / d6);
    for ratio in [w6 / d6, w7 / d7] {
        assert!(
            (ratio - expected).abs() / expected < 3e-3,
            "{ratio} vs {expected}"
        );
    }
}
