use faer::{Accum, Mat, Par};
use std::time::Instant;
fn main() {
    let n = 75810;
    let nr = 1148;
    let x = Mat::<f64>::from_fn(n, nr, |i, j| ((i * 7 + j * 13) % 17) as f64 * 0.1);
    let y = Mat::<f64>::from_fn(n, 64, |i, j| ((i * 3 + j * 5) % 11) as f64 * 0.1);
    let mut c = Mat::<f64>::zeros(nr, 64);
    for par in [Par::Seq, Par::rayon(0)] {
        let t = Instant::now();
        faer::linalg::matmul::matmul(
            c.as_mut(),
            Accum::Replace,
            x.transpose(),
            y.as_ref(),
            1.0,
            par,
        );
        let s = t.elapsed().as_secs_f64();
        println!(
            "xT*y {:?}: {:.3}s {:.1} GFLOPS",
            par,
            s,
            2.0 * n as f64 * nr as f64 * 64.0 / s / 1e9
        );
    }
    let mut c2 = Mat::<f64>::zeros(nr, nr);
    let t = Instant::now();
    faer::linalg::matmul::matmul(
        c2.as_mut(),
        Accum::Replace,
        x.transpose(),
        x.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let s = t.elapsed().as_secs_f64();
    println!(
        "full xT*x rayon: {:.3}s {:.1} GFLOPS",
        s,
        2.0 * n as f64 * nr as f64 * nr as f64 / s / 1e9
    );
}
