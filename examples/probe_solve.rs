use linercav::fem::model::FeModel;
use std::time::Instant;
fn main() {
    let scene =
        linercav::scene::Scene::load(std::path::Path::new("models/engine.toml"), &[]).unwrap();
    let em = linercav::reduce::scene_rom::load_meshes(&scene).unwrap();
    let cc = scene.crankcase.as_ref().unwrap();
    let t = Instant::now();
    let m = FeModel::build(em.crankcase.clone(), &em.crankcase_material, &cc.fix).unwrap();
    println!(
        "build {:.2}s n={} nnz={} factor_nnz={}",
        t.elapsed().as_secs_f64(),
        m.n_free(),
        m.km.pattern.nnz(),
        m.analysis.factor_nnz()
    );
    let t = Instant::now();
    let llt = m.analysis.llt(&m.km.pattern, &m.km.shifted(-1e4)).unwrap();
    println!("llt {:.2}s", t.elapsed().as_secs_f64());
    let n = m.n_free();
    let mut x = vec![1.0; n];
    let t = Instant::now();
    for _ in 0..20 {
        llt.solve_vec(&mut x);
    }
    println!("solve_vec x20 {:.3}s", t.elapsed().as_secs_f64());
    let mut y = vec![0.0; n];
    let t = Instant::now();
    for _ in 0..20 {
        m.km.pattern.matvec(&m.km.m, &x, &mut y);
    }
    println!("matvec x20 {:.3}s", t.elapsed().as_secs_f64());
    let mut b = faer::Mat::<f64>::from_fn(n, 64, |i, j| ((i + j) % 7) as f64);
    let t = Instant::now();
    llt.solve_in_place(b.as_mut());
    println!("solve 64 cols {:.3}s", t.elapsed().as_secs_f64());
    let mut b = faer::Mat::<f64>::from_fn(n, 256, |i, j| ((i + j) % 7) as f64);
    let t = Instant::now();
    llt.solve_in_place(b.as_mut());
    println!("solve 256 cols {:.3}s", t.elapsed().as_secs_f64());
    let x = faer::Mat::<f64>::from_fn(n, 64, |i, j| ((i + j) % 7) as f64);
    let mut y = faer::Mat::<f64>::zeros(n, 64);
    let t = Instant::now();
    for _ in 0..5 {
        m.km.pattern.mul_dense(&m.km.k, x.as_ref(), y.as_mut());
    }
    println!("mul_dense 64 cols x5 {:.3}s", t.elapsed().as_secs_f64());
}
