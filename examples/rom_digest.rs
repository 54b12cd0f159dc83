//! Digests (BLAKE3 of the bits) of the small engine's ROM: both parts' reduced matrices, the
//! system modes and the cylinders' rows. Two runs, or runs with RAYON_NUM_THREADS=1 and 2,
//! must print the same lines (the ROM does not depend on the thread count or the run).
//! `RAYON_NUM_THREADS=1 cargo run --release --example rom_digest`
use std::path::Path;
fn h(m: &faer::Mat<f64>) -> String {
    let mut v = Vec::new();
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            v.extend_from_slice(&m[(i, j)].to_bits().to_le_bytes());
        }
    }
    blake3::hash(&v).to_hex()[..12].to_string()
}
fn main() {
    let sc =
        linercav::scene::Scene::load(Path::new("tests/fixtures/engine_small.toml"), &[]).unwrap();
    let (b, _, _) = linercav::reduce::scene_rom::build_rom(&sc, false, None, &|_| {}).unwrap();
    println!(
        "liner k {} m {} out {} loads {}",
        h(&b.liner.k),
        h(&b.liner.m),
        h(&b.liner.outputs),
        h(&b.liner.loads)
    );
    println!(
        "cc k {} m {} out {} loads {}",
        h(&b.crankcase.k),
        h(&b.crankcase.m),
        h(&b.crankcase.outputs),
        h(&b.crankcase.loads)
    );
    println!(
        "sys vectors {} lambdas {:?}",
        h(&b.system.vectors),
        &b.system.lambdas[..3]
    );
    let bytes = bincode::serialize(&b.rom.cylinders).unwrap();
    println!("cylinders {}", &blake3::hash(&bytes).to_hex()[..12]);
}
