//! The crankcase reduced in components against the one-piece reduction of the same scene
//! (issue 37): every system frequency below half the cut-off, and the modal assurance
//! criterion of the paired mode shapes over the six liners.
//!
//! MAC(a, b) = (x_a^T M_L x_b)^2 / ((x_a^T M_L x_a)(x_b^T M_L x_b)), x the system mode's
//! liner coordinates (every cylinder's) and M_L the block diagonal of the liner's reduced mass.
//! The liner is reduced identically in both builds (the same component), so this is the
//! mass-weighted MAC over every physical DOF of the six liners (Phi_L^T M Phi_L = M_L): the
//! walls whose accelerations the tool predicts. The crankcase's own DOFs are not compared (the
//! substructured build keeps no physical basis of it). Modes are paired by their largest MAC
//! (two close modes may swap order between the builds); near-degenerate modes may mix within
//! their cluster, so the MAC of each mode with its cluster (the components' modes within 1e-3
//! of the paired mode's frequency, summed) is printed too. `MAC_DETAIL=1` prints every pair.
//!
//! `cargo run --release --example components_mac -- SCENE COMPONENTS [KEY=VALUE ...]`, the
//! settings applied to the components' build only (e.g. `rom.cut_shapes=500`); on the default
//! engine in 3 components about 2 min and 3 GB (run by benches/production.sh).
use faer::Mat;
use linercav::reduce::rom::RomBuild;
use linercav::scene::Scene;
use std::path::Path;

/// Frequencies [Hz] and the liner coordinates of the system modes below `f_max`.
fn liner_modes(b: &RomBuild, f_max: f64) -> (Vec<f64>, Vec<Mat<f64>>) {
    let freqs: Vec<f64> = b
        .system
        .lambdas
        .iter()
        .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .take_while(|&f| f < f_max)
        .collect();
    let v = &b.system.vectors;
    let per = b
        .liner_maps
        .iter()
        .map(|map| Mat::from_fn(map.len(), freqs.len(), |r, j| v[(map[r], j)]))
        .collect();
    (freqs, per)
}

/// x_a^T M_L x_b summed over the liners, for every pair of columns.
fn liner_products(m_l: &Mat<f64>, a: &[Mat<f64>], b: &[Mat<f64>]) -> Mat<f64> {
    let mut g = Mat::<f64>::zeros(a[0].ncols(), b[0].ncols());
    for (xa, xb) in a.iter().zip(b) {
        g += xa.transpose() * (m_l * xb);
    }
    g
}

fn build(path: &Path, sets: &[String]) -> RomBuild {
    let scene = Scene::load(path, sets).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (b, _, _) = linercav::reduce::scene_rom::build_rom(&scene, false, None, &|_| {})
        .unwrap_or_else(|e| panic!("ROM of {}: {e}", path.display()));
    b
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = Path::new(
        args.get(1)
            .map(String::as_str)
            .unwrap_or("models/engine.toml"),
    );
    let n_comp: usize = args
        .get(2)
        .map_or(3, |s| s.parse().expect("components: an integer"));
    let t = std::time::Instant::now();
    let one = build(path, &[]);
    let t_one = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let mut sets = vec![format!("rom.crankcase_components={n_comp}")];
    sets.extend(args.iter().skip(3).cloned());
    let comp = build(path, &sets);
    let t_comp = t.elapsed().as_secs_f64();
    let f_max = 0.5 * one.rom.info.cutoff_hz;
    let (fa, xa) = liner_modes(&one, f_max);
    let (fb, xb) = liner_modes(&comp, f_max);
    println!(
        "  one piece: {} system modes below {f_max:.0} Hz; {n_comp} components: {} (builds {t_one:.1} s, {t_comp:.1} s)",
        fa.len(),
        fb.len()
    );
    let m_l = &one.liner.m;
    let cross = liner_products(m_l, &xa, &xb);
    let na = liner_products(m_l, &xa, &xa);
    let nb = liner_products(m_l, &xb, &xb);
    let mac = |i: usize, j: usize| cross[(i, j)].powi(2) / (na[(i, i)] * nb[(j, j)]);
    compare(&fa, &fb, &mac);
}

/// Prints the frequency differences and MAC of the two builds' modes (`fa` one piece, `fb`
/// components, `mac(i, j)` of one-piece mode i and components' mode j).
fn compare(fa: &[f64], fb: &[f64], mac: &dyn Fn(usize, usize) -> f64) {
    let n = fa.len().min(fb.len());
    // each one-piece mode paired with the components' mode of largest MAC (a swap of two close
    // modes between the builds pairs them by shape, not by order)
    let pair: Vec<usize> = (0..n)
        .map(|i| {
            (0..n)
                .max_by(|&p, &q| mac(i, p).total_cmp(&mac(i, q)))
                .unwrap_or(i)
        })
        .collect();
    let mut taken = pair.clone();
    taken.sort_unstable();
    taken.dedup();
    let swapped = (0..n).filter(|&i| pair[i] != i).count();
    let rel: Vec<f64> = (0..n)
        .map(|i| (fb[pair[i]] - fa[i]).abs() / fa[i])
        .collect();
    let worst = (0..n)
        .max_by(|&i, &j| rel[i].total_cmp(&rel[j]))
        .unwrap_or(0);
    let mut sorted = rel.clone();
    sorted.sort_by(f64::total_cmp);
    println!(
        "  frequencies (paired by MAC; {swapped} pairs out of order, {} of {n} components' modes matched): largest relative difference {:.2e} (mode {}, {:.1} Hz), median {:.2e}, components higher in {} of {n}",
        taken.len(),
        rel[worst],
        worst + 1,
        fa[worst],
        sorted[n / 2],
        (0..n).filter(|&i| fb[pair[i]] > fa[i]).count()
    );
    let paired: Vec<f64> = (0..n).map(|i| mac(i, pair[i])).collect();
    // the MAC with the cluster of near-degenerate modes (within 1e-3 of the paired mode's
    // frequency in the components' build): a pair that only mixes within it sums to ~1
    let cluster: Vec<f64> = (0..n)
        .map(|i| {
            let f = fb[pair[i]];
            (0..n)
                .filter(|&j| (fb[j] - f).abs() <= 1e-3 * f)
                .map(|j| mac(i, j))
                .fold(0.0, |s, m| s + m)
        })
        .collect();
    if std::env::var_os("MAC_DETAIL").is_some() {
        for i in 0..n {
            println!(
                "  {:3} {:9.2} Hz  {:9.2} Hz  MAC {:.6}  cluster {:.6}",
                i + 1,
                fa[i],
                fb[pair[i]],
                paired[i],
                cluster[i]
            );
        }
    }
    let low = |v: &[f64]| (0..n).min_by(|&i, &j| v[i].total_cmp(&v[j])).unwrap_or(0);
    let (lp, lc) = (low(&paired), low(&cluster));
    println!(
        "  MAC over the six liners (mass-weighted): smallest {:.6} (1 - MAC {:.1e}; mode {}, {:.1} Hz), {} of {n} >= 0.999; with near-degenerate clusters (1e-3) smallest {:.6} (mode {}), {} of {n} >= 0.999",
        paired[lp],
        1.0 - paired[lp],
        lp + 1,
        fa[lp],
        paired.iter().filter(|&&m| m >= 0.999).count(),
        cluster[lc],
        lc + 1,
        cluster.iter().filter(|&&m| m >= 0.999).count()
    );
}
