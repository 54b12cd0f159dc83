//! Liner maps: per averaged cycle, the peak negative acceleration of every node of each liner's
//! wet outer surface, formed as the analysis points' are.
//!
//! A surface node's displacement is u_n(t) = r_n . x(t), r_n = [phi_n | R_nc] its ROM row
//! ([`crate::reduce::rom::SurfaceRows`]) and x = [eta; F_c] the modal coordinates and the
//! cylinder's contact loads. Its output acceleration is the point outputs' filter chain (the
//! fourth-order second difference, then the zero-phase low-pass) applied to u_n; both are
//! linear and time-invariant, so y_n(t) = r_n . xbar(t) with xbar the filtered second
//! difference of x, which is formed once per coordinate instead of once per node.
//!
//! The minimum over the cycle's S samples of y_n for N nodes would take N S m products
//! (m = modes + contact loads: 6 x 1,800 x 2,880 x 605 per cycle on the default engine, about
//! 40 times the transient's own cost). It is found exactly with far fewer. In coordinates
//! weighted by each coordinate's RMS over a cycle (w_n = D r_n, x' = D^-1 xbar), let P hold
//! the q leading eigenvectors of W^T W and Q the rest of an orthonormal basis; then
//!   y_n(t) = (P^T w_n) . (P^T x'(t)) + (Q^T w_n) . (Q^T x'(t)),
//! and by Cauchy-Schwarz the second term is at most b_n c(t), b_n = |Q^T w_n| =
//! sqrt(|w_n|^2 - |P^T w_n|^2), c(t) = sqrt(|x'|^2 - |P^T x'|^2). The first term for every
//! node and sample costs S q (m + N); it brackets y_n(t) within +-(b_n c(t) + roundoff). Only
//! the samples whose lower bracket reaches below the smallest upper bracket can hold the
//! minimum; y_n is evaluated exactly there (and at the minimum's neighbours, for the vertex
//! of [`sampled_peak`]). The result is the exact minimum of the sampled series whatever q
//! is; q only decides how many samples are evaluated exactly.

#[allow(unused_imports)]
use super::*;
use crate::transient::signal::BatchLowPass;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// Leading directions kept in the bracket, at most: enough that few samples besides the
/// peak's neighbours need an exact product (measured on the default engine: CHANGELOG).
const MAX_DIRECTIONS: usize = 48;

/// Directions whose weighted row energy is below this fraction of the largest are left to
/// the bound.
const DIRECTION_CUT: f64 = 1e-8;

/// Relative allowance for roundoff in the bracket (products of length m and q in f64 carry
/// relative errors of about m 1e-16 of |w_n| |x'|): 1e-9 of |w_n| |x'(t)|.
const ROUNDOFF: f64 = 1e-9;

/// One cylinder's wet surface peaks over the averaged cycles.
#[derive(Clone, Debug, Default)]
pub struct SurfacePeaks {
    /// 1-based cylinder number.
    pub cylinder: usize,
    /// Liner mesh node of each row (as [`crate::reduce::rom::SurfaceRows::nodes`]).
    pub nodes: Vec<usize>,
    /// Peak negative acceleration as a positive magnitude [m/s^2], nodes x averaged cycles.
    pub per_cycle: Array2<f64>,
}

/// The rolling record of the modal coordinates and each cylinder's contact loads from sample
/// `from` on, and the brackets of each cylinder ([`Projector`], made from the first cycle
/// mapped).
pub(super) struct SurfaceRecord {
    start: usize,
    eta: Vec<Vec<f64>>,
    loads: Vec<Vec<Vec<f64>>>,
    projectors: Vec<Option<Projector>>,
    filter: Option<BatchLowPass>,
    peaks: Vec<Vec<Vec<f64>>>,
}

impl SurfaceRecord {
    /// A record from global sample `from` on (nothing earlier is kept).
    pub(super) fn new(run: &EngineRun<'_>, from: usize) -> Self {
        let nb = run.structure.integrator.eta.len();
        let loads = run
            .cyls
            .iter()
            .map(|c| vec![Vec::new(); c.rom.thrust_z.len() + c.rom.antithrust_z.len()])
            .collect();
        SurfaceRecord {
            start: from,
            eta: vec![Vec::new(); nb],
            loads,
            projectors: run.cyls.iter().map(|_| None).collect(),
            filter: None,
            peaks: run
                .cyls
                .iter()
                .map(|c| vec![Vec::new(); c.rom.surface.nodes.len()])
                .collect(),
        }
    }

    /// Appends global sample `g` (ignored before the record's start).
    pub(super) fn push(&mut self, run: &EngineRun<'_>, g: usize) {
        if g < self.start {
            return;
        }
        for (v, &e) in self.eta.iter_mut().zip(&run.structure.integrator.eta) {
            v.push(e);
        }
        for (c, loads) in self.loads.iter_mut().enumerate() {
            let off = run.cyls[c].rom.contact_offset;
            let mut f = vec![0.0; loads.len()];
            for (_, at, force) in run.prev_loaded.iter().filter(|(b, _, _)| *b == c) {
                for i in 0..2 {
                    f[at.dofs[i] - off] += at.weights[i] * force;
                }
            }
            for (series, v) in loads.iter_mut().zip(f) {
                series.push(v);
            }
        }
    }

    /// Maps cycle `k` (its record [k N - margin, (k + 1) N + margin) complete): appends each
    /// surface node's peak negative acceleration, then drops what no later cycle needs.
    pub(super) fn map_cycle(
        &mut self,
        run: &EngineRun<'_>,
        k: usize,
        (spc, margin, dt): (usize, usize, f64),
    ) {
        let lo = (k * spc) as isize - margin as isize;
        let len = spc + 2 * margin;
        if self.filter.is_none() {
            if let Some(band) = run.settings.output_band_hz {
                self.filter = Some(BatchLowPass::new(len, dt, band));
            }
        }
        let filtered = |series: &[Vec<f64>]| -> Mat<f64> {
            let cols = filtered_columns(series, self.start, lo, (len, margin, spc), dt, &self.filter);
            Mat::from_fn(cols.len(), spc, |j, t| cols[j][t])
        };
        // x^T: coordinates x samples, the modes first, then the contact loads
        let eta_bar = filtered(&self.eta);
        let xs: Vec<Mat<f64>> = self
            .loads
            .iter()
            .map(|loads| {
                let f_bar = filtered(loads);
                let mut x = Mat::<f64>::zeros(eta_bar.nrows() + f_bar.nrows(), spc);
                x.as_mut().subrows_mut(0, eta_bar.nrows()).copy_from(&eta_bar);
                x.as_mut()
                    .subrows_mut(eta_bar.nrows(), f_bar.nrows())
                    .copy_from(&f_bar);
                x
            })
            .collect();
        let cyls = &run.cyls;
        let results: Vec<(Option<Projector>, Vec<f64>)> = xs
            .par_iter()
            .zip(self.projectors.par_iter_mut())
            .enumerate()
            .map(|(c, (x, proj))| {
                let surface = &cyls[c].rom.surface;
                if surface.nodes.is_empty() {
                    return (None, Vec::new());
                }
                let proj = proj
                    .take()
                    .unwrap_or_else(|| Projector::new(surface, x.as_ref()));
                let peaks = proj.peaks(x.as_ref());
                (Some(proj), peaks)
            })
            .collect();
        for (c, (proj, peaks)) in results.into_iter().enumerate() {
            self.projectors[c] = proj;
            for (series, p) in self.peaks[c].iter_mut().zip(peaks) {
                series.push(p);
            }
        }
        let keep_from = ((k + 1) * spc).saturating_sub(margin).max(self.start);
        for v in self.eta.iter_mut().chain(self.loads.iter_mut().flatten()) {
            v.drain(..(keep_from - self.start).min(v.len()));
        }
        self.start = keep_from;
    }

    /// The mapped cycles' peaks per cylinder.
    pub(super) fn finish(self, run: &EngineRun<'_>) -> Vec<SurfacePeaks> {
        self.peaks
            .into_iter()
            .zip(&run.cyls)
            .map(|(nodes, c)| {
                let cycles = nodes.first().map_or(0, Vec::len);
                SurfacePeaks {
                    cylinder: c.rom.cylinder,
                    nodes: c.rom.surface.nodes.clone(),
                    per_cycle: Array2::from_shape_fn((nodes.len(), cycles), |(n, k)| nodes[n][k]),
                }
            })
            .collect()
    }
}

/// Each series' output over the cycle: the fourth-order second difference of its segment
/// [lo, lo + len) ([`record_segment`], [`second_difference4`]), low-passed by `filter` (two
/// series per transform), samples margin .. margin + spc.
fn filtered_columns(
    series: &[Vec<f64>],
    start: usize,
    lo: isize,
    (len, margin, spc): (usize, usize, usize),
    dt: f64,
    filter: &Option<BatchLowPass>,
) -> Vec<Vec<f64>> {
    let mut d2: Vec<Vec<f64>> = series
        .iter()
        .map(|v| second_difference4(&record_segment(v, start, lo, len), dt))
        .collect();
    if let Some(f) = filter {
        d2.par_chunks_mut(2).for_each(|pair| match pair {
            [a, b] => f.apply_pair(a, b),
            [a] => f.apply_pair(a, &mut vec![0.0; len]),
            _ => {}
        });
    }
    d2.into_iter()
        .map(|v| v[margin..margin + spc].to_vec())
        .collect()
}

/// The brackets of one cylinder's surface (see the module doc).
struct Projector {
    /// The rows r_n, transposed: coordinates x nodes (each node's row contiguous).
    rows_t: Mat<f64>,
    /// Weight D_j of each coordinate (its RMS over the first mapped cycle).
    weight: Vec<f64>,
    /// P: coordinates x q, orthonormal.
    p: Mat<f64>,
    /// P^T w_n: nodes x q.
    a: Mat<f64>,
    /// b_n = |Q^T w_n| (with its roundoff allowance) and |w_n|.
    tail: Vec<f64>,
    norm: Vec<f64>,
}

impl Projector {
    /// The brackets for the surface rows, weighted by the RMS of the coordinates in `x`
    /// (coordinates x samples).
    fn new(surface: &crate::reduce::rom::SurfaceRows, x: MatRef<'_, f64>) -> Self {
        let (nm, nc) = (x.nrows() - surface.residual.ncols(), surface.residual.ncols());
        let ns = surface.nodes.len();
        let rows_t = Mat::from_fn(nm + nc, ns, |j, n| {
            if j < nm {
                surface.modes[[n, j]]
            } else {
                surface.residual[[n, j - nm]]
            }
        });
        let rms: Vec<f64> = (0..x.nrows())
            .map(|j| (x.row(j).iter().map(|v| v * v).sum::<f64>() / x.ncols() as f64).sqrt())
            .collect();
        let largest = rms.iter().copied().fold(0.0, f64::max);
        let weight: Vec<f64> = rms.iter().map(|&r| r.max(1e-6 * largest).max(1e-300)).collect();
        let w_t = Mat::from_fn(nm + nc, ns, |j, n| weight[j] * rows_t[(j, n)]);
        let mut gram = Mat::<f64>::zeros(nm + nc, nm + nc);
        matmul(gram.as_mut(), Accum::Replace, w_t.as_ref(), w_t.transpose(), 1.0, Par::Seq);
        let evd = gram
            .self_adjoint_eigen(faer::Side::Lower)
            .expect("the eigen-decomposition of a symmetric matrix");
        let s = evd.S().column_vector();
        let top = s[s.nrows() - 1].max(0.0);
        let q = (0..s.nrows())
            .rev()
            .take_while(|&i| s[i] > DIRECTION_CUT * top)
            .count()
            .clamp(1, MAX_DIRECTIONS);
        let u = evd.U();
        let p = Mat::from_fn(nm + nc, q, |j, i| u[(j, s.nrows() - 1 - i)]);
        let mut a = Mat::<f64>::zeros(ns, q);
        matmul(a.as_mut(), Accum::Replace, w_t.transpose(), p.as_ref(), 1.0, Par::Seq);
        let norm: Vec<f64> = (0..ns).map(|n| w_t.col(n).norm_l2()).collect();
        let tail = (0..ns)
            .map(|n| {
                let head = a.row(n).norm_l2();
                ((norm[n] * norm[n] - head * head).max(0.0) + 1e-12 * norm[n] * norm[n]).sqrt()
            })
            .collect();
        Projector {
            rows_t,
            weight,
            p,
            a,
            tail,
            norm,
        }
    }

    /// Each node's peak negative acceleration (a positive magnitude, as [`sampled_peak`]
    /// gives it) over the samples of `x` (coordinates x samples).
    fn peaks(&self, x: MatRef<'_, f64>) -> Vec<f64> {
        let (m, ns_) = (x.nrows(), x.ncols());
        let xw = Mat::from_fn(m, ns_, |j, t| x[(j, t)] / self.weight[j]);
        let mut z = Mat::<f64>::zeros(ns_, self.p.ncols());
        matmul(z.as_mut(), Accum::Replace, xw.transpose(), self.p.as_ref(), 1.0, Par::Seq);
        let mut yhat = Mat::<f64>::zeros(ns_, self.a.nrows());
        matmul(yhat.as_mut(), Accum::Replace, z.as_ref(), self.a.transpose(), 1.0, Par::Seq);
        let (c, xn): (Vec<f64>, Vec<f64>) = (0..ns_)
            .map(|t| {
                let all = xw.col(t).norm_l2();
                let head = z.row(t).norm_l2();
                (
                    ((all * all - head * head).max(0.0) + 1e-12 * all * all).sqrt(),
                    all,
                )
            })
            .unzip();
        let exact = |n: usize, t: usize| -> f64 {
            let r = self.rows_t.col(n);
            (0..m).map(|j| r[j] * x[(j, t)]).sum()
        };
        (0..self.a.nrows())
            .map(|n| {
                let y = yhat.col(n);
                let half = |t: usize| self.tail[n] * c[t] + ROUNDOFF * self.norm[n] * xn[t];
                let upper = (0..ns_)
                    .map(|t| y[t] + half(t))
                    .fold(f64::INFINITY, f64::min);
                let mut best: Option<(usize, f64)> = None;
                for t in 0..ns_ {
                    if y[t] - half(t) <= upper {
                        let v = exact(n, t);
                        if best.is_none_or(|(_, b)| v < b) {
                            best = Some((t, v));
                        }
                    }
                }
                let (k, v) = best.expect("the smallest upper bracket's sample is a candidate");
                let mut around = Vec::with_capacity(3);
                if k > 0 {
                    around.push(exact(n, k - 1));
                }
                around.push(v);
                if k + 1 < ns_ {
                    around.push(exact(n, k + 1));
                }
                sampled_peak(&around, 0..around.len(), -1.0).map_or(0.0, |(g, _)| g)
            })
            .collect()
    }
}
