use linercav::fem::material::Elastic;
use linercav::fem::model::FeModel;
use linercav::fem::shape::ElementKind;
use linercav::mesh::liner::*;
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let nt: usize = args[1].parse().unwrap();
    let nr: usize = args[2].parse().unwrap();
    let h: f64 = args[3].parse().unwrap();
    let kind = match args[4].as_str() {
        "hex20" => ElementKind::Hex20,
        "tet10" => ElementKind::Tet10,
        "hex8" => ElementKind::Hex8,
        _ => ElementKind::Tet4,
    };
    let flange: f64 = args.get(5).map(|s| s.parse().unwrap()).unwrap_or(0.150);
    let geo = LinerGeometry {
        outer_diameter: 0.135,
        inner_diameter: 0.115,
        length: 0.26,
        flange_outer_diameter: flange,
        flange_height: 0.012,
        guide_height: 0.03,
        analysis_depths: vec![0.035, 0.06, 0.085, 0.11],
    };
    let m = LinerMeshing {
        kind,
        circumferential: nt,
        radial: nr,
        radial_flange: 1,
        axial_size: h,
    };
    let t = Instant::now();
    let mesh = generate(&geo, &m);
    let mat = Elastic {
        young: 140e9,
        poisson: 0.26,
        density: 7200.0,
    };
    let mut model = FeModel::build(mesh, &mat, &[]).unwrap();
    println!(
        "dofs {} nnz {} Lnnz {} build {:.2}s {:?}",
        model.n_free(),
        model.km.pattern.nnz(),
        model.analysis.factor_nnz(),
        t.elapsed().as_secs_f64(),
        model.timings
    );
    let sigma = -(2.0 * std::f64::consts::PI * 100.0f64).powi(2);
    {
        let sh = model.km.shifted(sigma);
        let t = Instant::now();
        let llt = model.analysis.llt(&model.km.pattern, &sh).unwrap();
        println!("llt {:.3}", t.elapsed().as_secs_f64());
        let mut x = vec![1.0; model.n_free()];
        let t = Instant::now();
        for _ in 0..10 {
            llt.solve_vec(&mut x);
        }
        println!("10 solves {:.3}", t.elapsed().as_secs_f64());
        let t = Instant::now();
        let c = model
            .analysis
            .negative_pivots(
                &model.km.pattern,
                &model.km.shifted(4767.0f64.powi(2) * 39.47),
            )
            .unwrap();
        println!("ldlt {c} {:.3}", t.elapsed().as_secs_f64());
    }
    let sol = model.modes(16, sigma, 4).unwrap();
    let f: Vec<String> = (0..16)
        .map(|j| format!("{:.2}", sol.modes.frequency_hz(j)))
        .collect();
    println!("{}", f.join(" "));
    println!(
        "solve {:.2} mass {:.2} arpack {:.2}",
        sol.modes.seconds_solve, sol.modes.seconds_mass, sol.modes.seconds_arpack
    );
    println!(
        "res max {:.2e} orth {:.2e} sturm {:?} solves {} total {:.2}s {:?}",
        sol.residuals.iter().cloned().fold(0.0, f64::max),
        sol.m_orthogonality,
        sol.sturm,
        sol.modes.solves,
        t.elapsed().as_secs_f64(),
        model.timings
    );
}
#[allow(dead_code)]
fn unused() {}
