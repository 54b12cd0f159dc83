//! The default engine's crankcase model with scene overrides: its DOFs, stored entries of K and
//! the entries of its Cholesky factor (symbolic analysis only), the machine-independent
//! figures of benches/RESULTS.md ("ROM build against crankcase size").
//! `cargo run --release --example factor_size -- crankcase.mesh.per_sector=8`
use linercav::fem::model::FeModel;
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene =
        linercav::scene::Scene::load(std::path::Path::new("models/engine.toml"), &args).unwrap();
    let em = linercav::reduce::scene_rom::load_meshes(&scene).unwrap();
    let cc = scene.crankcase.as_ref().unwrap();
    let t = Instant::now();
    let m = FeModel::build(em.crankcase.clone(), &em.crankcase_material, &cc.fix).unwrap();
    println!(
        "{:?} build {:.2}s n={} nnz={} factor_nnz={} ({:.1} GB)",
        args,
        t.elapsed().as_secs_f64(),
        m.n_free(),
        m.km.pattern.nnz(),
        m.analysis.factor_nnz(),
        m.analysis.factor_nnz() as f64 * 8e-9
    );
}
