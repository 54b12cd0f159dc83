//! One 720 deg cycle of the six-cylinder default engine on the cached ROM (the fast path users
//! run in sweeps). Run: cargo bench --bench transient  (builds the default ROM on first use).

use criterion::{criterion_group, criterion_main, Criterion};
use linercav::api::{get_rom, piston_of, run_cycle, settings_of, CacheOptions, Scene};
use std::path::Path;

fn cycle(c: &mut Criterion) {
    let scene = Scene::load(
        Path::new("models/engine.toml"),
        &["transient.cycles=1".into()],
    )
    .expect("default scene");
    let rom = get_rom(&scene, &CacheOptions::default(), &|_| {})
        .expect("ROM")
        .rom;
    let piston = piston_of(&scene).expect("piston");
    let settings = settings_of(
        scene.simulation.as_ref().expect("sections"),
        scene.rom.band_hz,
    );
    let mut g = c.benchmark_group("transient");
    g.sample_size(10);
    g.bench_function("one_cycle_six_cylinders", |b| {
        b.iter(|| run_cycle(&scene, &rom, &piston, settings.clone(), |_, _| {}).expect("runs"))
    });
    g.finish();
}

criterion_group!(benches, cycle);
criterion_main!(benches);
