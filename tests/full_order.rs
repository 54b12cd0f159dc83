//! The ROM against the full-order FE model on the window around firing TDC (two-cylinder coarse
//! test engine): same piston, contact law, scheme and step; the scene's scheme on the full coupled
//! model (23.8k unknowns, no modal truncation) is the reference.

use linercav::api::{get_rom, piston_of, settings_of, CacheOptions, Scene};
use linercav::transient::verify::compare;
use std::path::Path;

const SMALL: &str = "tests/fixtures/engine_small.toml";

fn comparison(sets: &[&str]) -> linercav::transient::verify::FullOrderReport {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scene = Scene::load(Path::new(SMALL), &sets).unwrap();
    let rom = get_rom(
        &scene,
        &CacheOptions {
            no_cache: true,
            dir: None,
        },
        &|_| {},
    )
    .unwrap()
    .rom;
    let piston = piston_of(&scene).unwrap();
    let sim = scene.simulation.as_ref().unwrap();
    compare(
        &scene,
        &rom,
        &piston,
        &settings_of(sim, scene.rom.band_hz),
        &|_| {},
    )
    .unwrap()
}

fn print_points(c: &linercav::transient::verify::FullOrderReport) {
    eprintln!(
        "step {:.4} deg: the ROM's peaks move {:.2e} at half of it",
        c.step_deg, c.rom_step_change
    );
    for p in &c.points {
        eprintln!(
            "point {}: full {:.1} rom {:.1} ({:.2e})",
            p.point, p.peak_negative_full_m_s2, p.peak_negative_rom_m_s2, p.relative_error
        );
    }
}

#[test]
fn verification_rom_matches_the_full_order_model_on_the_window() {
    let c = comparison(&["rom.residual_vector_spacing=1"]);
    // The preload is one static solve in both models (the ROM's is exact for its loads through
    // the attachment modes): equal to solver roundoff.
    assert!(
        c.preload_error < 1e-9,
        "preload error {:e}",
        c.preload_error
    );
    // Peak negative acceleration in the band, every analysis point: the 2 % floor
    // (measured 0.18 % at the window's 1/12 deg, 0.14 % at the base step, with residual
    // vectors at every bore-line node; without them, static correction only, 11 % at the base
    // step: the slap's contact frequency, ~5 kHz, sits at this ROM's cut-off).
    print_points(&c);
    assert!(
        c.rom_error_peak_negative < 0.02,
        "ROM error {:.3e}",
        c.rom_error_peak_negative
    );
    assert!(c.steps > 300);
    // The window runs at the cycle's slap sub-step (the scene's 1/4 deg over its 3 sub-steps),
    // and that step must be converged well below the 2 % the comparison bounds, or the error
    // above would mix the two models' step errors into the structural one: the ROM's peaks
    // at half the step within 1 %.
    assert!(
        (c.step_deg - 0.25 / 3.0).abs() < 1e-12,
        "step {}",
        c.step_deg
    );
    assert!(
        c.rom_step_change < 0.01,
        "the ROM's peaks move {:.3e} at half the window's step",
        c.rom_step_change
    );
}

#[test]
fn verification_hht_alpha_runs_the_same_scheme_in_both_models() {
    // HHT-alpha in the full model (its own K_eff and the -alpha F0 contact term) against the
    // modal HHT update: they differ by the modal truncation only, so the same bound holds
    // (a wrong shifted term in either shows as a difference of order alpha, here 10 %).
    let c = comparison(&[
        "rom.residual_vector_spacing=1",
        "transient.scheme=hht",
        "transient.hht_alpha=-0.1",
    ]);
    assert_eq!(c.scheme.alpha, -0.1);
    print_points(&c);
    assert!(
        c.rom_error_peak_negative < 0.02,
        "ROM error {:.3e}",
        c.rom_error_peak_negative
    );
}

#[test]
fn verification_coolant_layer_enters_both_models() {
    // A heavy coolant layer (gap 30 mm: rho h = 29 kg/m^2, about a third of the test liner's
    // wall mass per area) in the liner's reduction and in the full model alike: the ROM must
    // stay within the same 2 % of the full model. The layer moves the full model's peaks by
    // 9-29 % against the dry one (measured), so a layer missing from either model fails by an
    // order of magnitude more than the bound. Measured at the window's step (1/12 deg) 1.77 %,
    // at 1/24 and 1/48 deg 1.74 and 1.58 % (the ROM's own step change 1.5, 0.6, 0.3 %); at
    // the base step 1/4 deg it read 0.50 % only because the two models' step errors (the
    // ROM's peaks move 8 % from 1/4 to 1/8 deg) cancelled there.
    let c = comparison(&[
        "rom.residual_vector_spacing=1",
        "cavitation.coolant_mass=layer",
        "cavitation.gap_mm=30",
    ]);
    print_points(&c);
    assert!(
        c.rom_error_peak_negative < 0.02,
        "ROM error {:.3e}",
        c.rom_error_peak_negative
    );
}
