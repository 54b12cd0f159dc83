//! The realisation spread of the default engine's explanation: the default and three runs with
//! the damping ratio at 0.0198, 0.0199 and 0.0201 (the slap is chaotic enough that such a
//! change redraws the cycle-to-cycle pattern). Prints each run's dominant response, the
//! nearest system modes with their correlation to the per-cylinder peaks, and the ranking;
//! the numbers behind docs/validation.md's "four realisations".
//! `cargo run --release --example realisations`
use linercav::api::{
    evaluate, get_rom, piston_of, run_cycle, settings_of, simulation, CacheOptions, Scene,
};
use std::path::Path;

fn main() {
    let path = Path::new("models/engine.toml");
    let base = Scene::load(path, &[]).unwrap();
    let rom = get_rom(&base, &CacheOptions::default(), &|_| {})
        .unwrap()
        .rom;
    for zeta in ["0.0198", "0.0199", "0.02", "0.0201"] {
        let scene = Scene::load(path, &[format!("transient.damping_ratio={zeta}")]).unwrap();
        let piston = piston_of(&scene).unwrap();
        let settings = settings_of(simulation(&scene).unwrap(), scene.rom.band_hz);
        let res = run_cycle(&scene, &rom, &piston, settings, |_, _| {}).unwrap();
        let ev = evaluate(
            &res,
            &rom,
            &linercav::cavitation::Setup::new(&scene.cavitation).unwrap(),
            &scene.engine.firing_order,
            scene.rom.band_hz,
        );
        let modes: Vec<String> = ev
            .nearest_modes
            .iter()
            .map(|m| {
                format!(
                    "{:.1} Hz r {:.2}",
                    m.frequency_hz,
                    m.pearson.unwrap_or(f64::NAN)
                )
            })
            .collect();
        println!(
            "zeta {zeta}: dominant {:.1} Hz; nearest {}; ranking {:?}",
            ev.dominant_hz,
            modes.join(", "),
            ev.ranking
        );
    }
}
