//! Phase benchmarks of the one-time modal solve on a liner (default geometry, 32 x 2 Hex20
//! mesh, ~25k DOF): assembly, ordering + symbolic analysis, numeric factorisation, and the
//! ARPACK shift-invert eigen-solve of 16 modes. Inputs are deterministic; setup is not timed.

use criterion::{criterion_group, criterion_main, Criterion};
use linercav::eigen::{solve_modes, EigenSettings};
use linercav::fem::assembly::Assembler;
use linercav::fem::dofs::DofMap;
use linercav::fem::model::FeModel;
use linercav::mesh::liner::generate;
use linercav::scene::{MeshSource, Scene};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let scene = Scene::load(
        Path::new("models/engine.toml"),
        &[
            "liner.mesh.circumferential=32".into(),
            "liner.mesh.axial_size_mm=13".into(),
        ],
    )
    .unwrap();
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        unreachable!()
    };
    let mesh = generate(geometry, meshing);
    let mat = scene
        .liner
        .material
        .expect("the default liner names its material");
    let dofs = DofMap::free(mesh.nodes.len());
    let mut g = c.benchmark_group("liner_32x2_hex20");
    g.sample_size(10);
    g.bench_function("assembly (pattern + K, M)", |b| {
        b.iter(|| Assembler::new(&mesh, &dofs).assemble(&mesh, &mat).unwrap())
    });
    g.bench_function("assembly + METIS ordering + symbolic", |b| {
        b.iter(|| FeModel::build(mesh.clone(), &mat, &[]).unwrap())
    });
    let model = FeModel::build(mesh.clone(), &mat, &[]).unwrap();
    let sigma = scene.solver.sigma();
    let shifted = model.km.shifted(sigma);
    g.bench_function("numeric LLT of K - sigma M", |b| {
        b.iter(|| model.analysis.llt(&model.km.pattern, &shifted).unwrap())
    });
    let llt = model.analysis.llt(&model.km.pattern, &shifted).unwrap();
    g.bench_function("ARPACK shift-invert, 16 modes", |b| {
        b.iter(|| {
            solve_modes(
                model.n_free(),
                &EigenSettings::new(16, sigma),
                |x, y| model.km.pattern.matvec(&model.km.m, x, y),
                |x| llt.solve_vec(x),
            )
            .unwrap()
        })
    });
    g.finish();
    solves(c);
}

/// A single-vector solve with the default liner's factor (48,672 DOF, 26M entries): the Lanczos
/// iteration's unit of work, bound by reading the factor (2 x 211 MB per solve); the tree solve
/// on both cores against faer's serial supernodal solve.
fn solves(c: &mut Criterion) {
    let scene = Scene::load(Path::new("models/engine.toml"), &[]).unwrap();
    let MeshSource::Liner { geometry, meshing } = &scene.liner.source else {
        unreachable!()
    };
    let mesh = generate(geometry, meshing);
    let mat = scene.liner.material.expect("a material");
    let model = FeModel::build(mesh, &mat, &[]).unwrap();
    let shifted = model.km.shifted(scene.solver.sigma());
    let llt = model.analysis.llt(&model.km.pattern, &shifted).unwrap();
    let n = model.n_free();
    let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
    let mut g = c.benchmark_group("default_liner_factor");
    g.sample_size(20);
    g.bench_function(
        "single-vector solve, elimination tree on both cores",
        |bench| {
            bench.iter(|| {
                let mut x = b.clone();
                llt.solve_vec(&mut x);
                x
            })
        },
    );
    g.bench_function("single-vector solve, faer serial", |bench| {
        bench.iter(|| {
            let mut x = b.clone();
            llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 1));
            x
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
