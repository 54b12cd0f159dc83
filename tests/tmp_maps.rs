use linercav::api::*;
use std::path::Path;
#[test]
#[ignore]
fn tmp_default_maps() {
    let scene = Scene::load(
        Path::new("models/engine.toml"),
        &[
            "transient.cycles=5".to_string(),
            "transient.averaged_cycles=4".to_string(),
        ],
    )
    .unwrap();
    let rom = get_rom(
        &scene,
        &CacheOptions {
            no_cache: false,
            dir: None,
        },
        &|_| {},
    )
    .unwrap()
    .rom;
    let piston = piston_of(&scene).unwrap();
    for maps in [false, true] {
        let mut settings = settings_of(scene.simulation.as_ref().unwrap(), scene.rom.band_hz);
        settings.surface_maps = maps;
        let t = std::time::Instant::now();
        let r = run_cycle(&scene, &rom, &piston, settings, |_, _| {}).unwrap();
        println!(
            "maps {maps}: {:.2} s, {} surfaces",
            t.elapsed().as_secs_f64(),
            r.surface.len()
        );
    }
}
