//! Liner maps: per averaged cycle, the peak negative acceleration of every node of each liner's
//! wet outer surface, formed as the analysis points' are.
//!
//! A surface node's displacement is u_n(t) = r_n . x(t), r_n = [phi_n | R_nc] its ROM row
//! ([`crate::reduce::rom::SurfaceRows`]) and x = [eta; F_c] the modal coordinates and the
//! cylinder's contact loads. Its output acceleration is the point outputs' chain applied to
//! u_n: the fourth-order second difference d, then the zero-phase FIR h (taps h_k, k = -L..L).
//! Both are linear and time-invariant, so y_n(t) = r_n . xbar(t), xbar = h * d(x).
//!
//! The minimum over a cycle's S samples for N nodes would take N S m products (m = modes +
//! contact loads: 6 x 1,800 x 2,880 x 605 per cycle on the default engine, about 40 times the
//! transient's own work). It is found exactly with far fewer. With each coordinate weighted by
//! its RMS D_j (w_n = D r_n, x' = D^-1 x), let P hold the q leading eigenvectors of W^T W and
//! Q the rest of an orthonormal basis. Then
//!   y_n(t) = a_n . z(t) + (Q^T w_n) . (Q^T xbar'(t)),   a_n = P^T w_n,  z = h * (P^T d(x')),
//! and by Cauchy-Schwarz and the triangle inequality over the taps the second term is at most
//! b_n c(t), b_n = |Q^T w_n| = sqrt(|w_n|^2 - |a_n|^2) and
//!   c(t) = sum_k |h_k| e(t + k),  e(s) = |Q^T d(x')(s)| = sqrt(|d(x')(s)|^2 - |P^T d(x')(s)|^2).
//! So the q filtered projections bracket every y_n(t) within +-(b_n c(t) + roundoff) at a cost
//! of q (m + N) per sample. Only the samples whose lower bracket reaches below the node's
//! smallest upper bracket can hold its minimum; y_n is evaluated exactly there (and at the
//! minimum's neighbours, for the vertex of [`sampled_peak`]), with xbar(t) formed by the FIR
//! sum at those samples only. The result is the exact minimum of the sampled series whatever
//! q and D are; they only decide how many samples are evaluated exactly.

#[allow(unused_imports)]
use super::*;
use crate::linalg::kernels::dot;
use crate::reduce::rom::SurfaceRows;
use crate::transient::signal::BatchLowPass;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// Leading directions kept in the bracket, at most. Measured on the default engine (6 x
/// 1,802 nodes, 2,880 samples a cycle): exact samples per node 1.0 with 128 directions, 1.9-2.4
/// with 40, 3.4-9.4 with 32, 55-80 with 24, about 660 with 12; 40 costs the least in all.
const MAX_DIRECTIONS: usize = 40;

/// Directions whose weighted row energy is below this fraction of the largest are left to
/// the bound.
const DIRECTION_CUT: f64 = 1e-10;

/// Relative allowance for roundoff in the bracket (products of length m and q in f64 carry
/// relative errors of about m 1e-16 of |w_n| |x'|): 1e-9 of |w_n| times the bound of |xbar'|.
const ROUNDOFF: f64 = 1e-9;

/// Nodes whose bracket centres are formed and scanned together (a block of S x 16 values
/// stays in the core's cache between the product and the scan).
const NODE_BLOCK: usize = 16;

/// When a cycle needed more exact samples per node than this, the next cycle's brackets are
/// made anew with weights that take in that cycle's RMS as well.
const REWEIGHT_ABOVE: f64 = 16.0;

/// One cylinder's wet surface peaks over the averaged cycles.
#[derive(Clone, Debug, Default)]
pub struct SurfacePeaks {
    /// 1-based cylinder number.
    pub cylinder: usize,
    /// Liner mesh node of each row (as [`SurfaceRows::nodes`]).
    pub nodes: Vec<usize>,
    /// Peak negative acceleration as a positive magnitude [m/s^2], nodes x averaged cycles.
    pub per_cycle: Array2<f64>,
}

/// The rolling record of the modal coordinates and each cylinder's contact loads (sample-major)
/// from sample `start` on, and each cylinder's brackets ([`Projector`]).
pub(super) struct SurfaceRecord {
    start: usize,
    nb: usize,
    eta: Vec<f64>,
    loads: Vec<Vec<f64>>,
    projectors: Vec<Option<Projector>>,
    peaks: Vec<Vec<Vec<f64>>>,
}

impl SurfaceRecord {
    /// A record from global sample `from` on (nothing earlier is kept).
    pub(super) fn new(run: &EngineRun<'_>, from: usize) -> Self {
        SurfaceRecord {
            start: from,
            nb: run.structure.integrator.eta.len(),
            eta: Vec::new(),
            loads: run.cyls.iter().map(|_| Vec::new()).collect(),
            projectors: run.cyls.iter().map(|_| None).collect(),
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
        self.eta.extend_from_slice(&run.structure.integrator.eta);
        for (c, loads) in self.loads.iter_mut().enumerate() {
            let rom = run.cyls[c].rom;
            let (off, n) = (loads.len(), rom.thrust_z.len() + rom.antithrust_z.len());
            loads.resize(off + n, 0.0);
            for (_, at, force) in run.prev_loaded.iter().filter(|(b, _, _)| *b == c) {
                for i in 0..2 {
                    loads[off + at.dofs[i] - rom.contact_offset] += at.weights[i] * force;
                }
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
        let batch = run
            .settings
            .output_band_hz
            .map(|band| BatchLowPass::new(len, dt, band));
        let window = Window {
            start: self.start,
            lo,
            len,
            margin,
            spc,
            dt,
        };
        let eta_bar = window.outputs(&self.eta, self.nb, &batch);
        let results: Vec<(Option<Projector>, Vec<f64>)> = self
            .projectors
            .par_iter_mut()
            .zip(self.loads.par_iter())
            .zip(run.cyls.par_iter())
            .map(|((proj, loads), cyl)| {
                let surface = &cyl.rom.surface;
                if surface.nodes.is_empty() {
                    return (None, Vec::new());
                }
                let ncon = cyl.rom.thrust_z.len() + cyl.rom.antithrust_z.len();
                let f_bar = window.outputs(loads, ncon, &batch);
                let mut x = Mat::<f64>::zeros(eta_bar.nrows() + ncon, spc);
                x.as_mut()
                    .subrows_mut(0, eta_bar.nrows())
                    .copy_from(&eta_bar);
                x.as_mut()
                    .subrows_mut(eta_bar.nrows(), ncon)
                    .copy_from(&f_bar);
                let mut p = proj
                    .take()
                    .unwrap_or_else(|| Projector::new(surface, x.as_ref(), None));
                let (peaks, exact) = p.peaks(x.as_ref());
                if exact > REWEIGHT_ABOVE {
                    p = Projector::new(surface, x.as_ref(), Some(&p.weight));
                }
                (Some(p), peaks)
            })
            .collect();
        for (c, (proj, peaks)) in results.into_iter().enumerate() {
            self.projectors[c] = proj;
            for (series, p) in self.peaks[c].iter_mut().zip(peaks) {
                series.push(p);
            }
        }
        let keep_from = ((k + 1) * spc).saturating_sub(margin).max(self.start);
        let drop = keep_from - self.start;
        self.eta.drain(..(drop * self.nb).min(self.eta.len()));
        for (loads, cyl) in self.loads.iter_mut().zip(&run.cyls) {
            let ncon = cyl.rom.thrust_z.len() + cyl.rom.antithrust_z.len();
            loads.drain(..(drop * ncon).min(loads.len()));
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

/// The samples of one cycle's outputs: [lo, lo + len) of a record whose first sample is
/// `start` (earlier samples, before t = 0, are zero), the cycle's `spc` samples `margin` in.
struct Window {
    start: usize,
    lo: isize,
    len: usize,
    margin: usize,
    spc: usize,
    dt: f64,
}

impl Window {
    /// Each of the `m` series of a sample-major record as the point outputs form theirs
    /// ([`Record::outputs`]): the fourth-order second difference of the window's samples, the
    /// low-pass (`batch`, two series per transform), the cycle's samples; as a series x
    /// samples matrix.
    fn outputs(&self, record: &[f64], m: usize, batch: &Option<BatchLowPass>) -> Mat<f64> {
        let mut series: Vec<Vec<f64>> = (0..m)
            .into_par_iter()
            .map(|j| {
                let raw: Vec<f64> = (0..self.len)
                    .map(|s| {
                        let g = self.lo + s as isize;
                        if g < self.start as isize {
                            0.0
                        } else {
                            record
                                .get((g as usize - self.start) * m + j)
                                .copied()
                                .unwrap_or(0.0)
                        }
                    })
                    .collect();
                second_difference4(&raw, self.dt)
            })
            .collect();
        if let Some(f) = batch {
            series.par_chunks_mut(2).for_each(|pair| match pair {
                [a, b] => f.apply_pair(a, b),
                [a] => f.apply_pair(a, &mut vec![0.0; self.len]),
                _ => {}
            });
        }
        Mat::from_fn(m, self.spc, |j, t| series[j][self.margin + t])
    }
}

/// The brackets of one cylinder's surface (see the module doc).
struct Projector {
    /// The rows r_n, transposed: coordinates x nodes (each node's row contiguous).
    rows_t: Mat<f64>,
    /// Weight D_j of each coordinate.
    weight: Vec<f64>,
    /// D^-1 P: coordinates x q (P orthonormal).
    p_scaled: Mat<f64>,
    /// a_n = P^T w_n: nodes x q.
    a: Mat<f64>,
    /// b_n = |Q^T w_n| (with its roundoff allowance) and |w_n|.
    tail: Vec<f64>,
    norm: Vec<f64>,
}

impl Projector {
    /// The brackets for the surface rows, each coordinate weighted by its RMS over `x`
    /// (coordinates x samples) or `previous`, whichever is larger, but at least 1e-3 of the
    /// largest of its group (modes, contact loads): a contact DOF idle in one cycle may carry
    /// the next one's slap.
    fn new(surface: &SurfaceRows, x: MatRef<'_, f64>, previous: Option<&[f64]>) -> Self {
        let (nc, ns) = (surface.residual.ncols(), surface.nodes.len());
        let nm = x.nrows() - nc;
        let rows_t = Mat::from_fn(nm + nc, ns, |j, n| {
            if j < nm {
                surface.modes[[n, j]]
            } else {
                surface.residual[[n, j - nm]]
            }
        });
        let mut weight: Vec<f64> = (0..x.nrows())
            .map(|j| (x.row(j).iter().map(|v| v * v).sum::<f64>() / x.ncols() as f64).sqrt())
            .collect();
        if let Some(w) = previous {
            weight.iter_mut().zip(w).for_each(|(a, &b)| *a = a.max(b));
        }
        for group in [0..nm, nm..nm + nc] {
            let top = weight[group.clone()].iter().copied().fold(0.0, f64::max);
            for w in &mut weight[group] {
                *w = w.max(1e-3 * top).max(f64::MIN_POSITIVE);
            }
        }
        let w_t = Mat::from_fn(nm + nc, ns, |j, n| weight[j] * rows_t[(j, n)]);
        let mut gram = Mat::<f64>::zeros(nm + nc, nm + nc);
        matmul(
            gram.as_mut(),
            Accum::Replace,
            w_t.as_ref(),
            w_t.transpose(),
            1.0,
            Par::Seq,
        );
        let evd = gram
            .self_adjoint_eigen(faer::Side::Lower)
            .expect("the eigen-decomposition of a symmetric matrix");
        let s = evd.S().column_vector();
        let last = s.nrows() - 1;
        let q = (0..=last)
            .rev()
            .take_while(|&i| s[i] > DIRECTION_CUT * s[last].max(0.0))
            .count()
            .clamp(1, MAX_DIRECTIONS);
        let u = evd.U();
        let p = Mat::from_fn(nm + nc, q, |j, i| u[(j, last - i)]);
        let mut a = Mat::<f64>::zeros(ns, q);
        matmul(
            a.as_mut(),
            Accum::Replace,
            w_t.transpose(),
            p.as_ref(),
            1.0,
            Par::Seq,
        );
        let norm: Vec<f64> = (0..ns).map(|n| w_t.col(n).norm_l2()).collect();
        let tail = (0..ns)
            .map(|n| {
                let head = a.row(n).norm_l2();
                ((norm[n] * norm[n] - head * head).max(0.0) + 1e-12 * norm[n] * norm[n]).sqrt()
            })
            .collect();
        let p_scaled = Mat::from_fn(nm + nc, q, |j, i| p[(j, i)] / weight[j]);
        Projector {
            rows_t,
            weight,
            p_scaled,
            a,
            tail,
            norm,
        }
    }

    /// Each node's peak negative acceleration (a positive magnitude, as [`sampled_peak`]
    /// gives it) over the cycle's filtered coordinates `x` (coordinates x samples), and the
    /// exact samples per node it took.
    fn peaks(&self, x: MatRef<'_, f64>) -> (Vec<f64>, f64) {
        let (spc, q) = (x.ncols(), self.p_scaled.ncols());
        let mut z = Mat::<f64>::zeros(spc, q);
        matmul(
            z.as_mut(),
            Accum::Replace,
            x.transpose(),
            self.p_scaled.as_ref(),
            1.0,
            Par::Seq,
        );
        let column = |t: usize| x.col(t).try_as_col_major().expect("contiguous").as_slice();
        // per sample |x'| and the tail c = |Q^T x'|
        let (xn, c): (Vec<f64>, Vec<f64>) = (0..spc)
            .map(|t| {
                let all: f64 = column(t)
                    .iter()
                    .zip(&self.weight)
                    .map(|(v, w)| (v / w).powi(2))
                    .sum();
                let head: f64 = (0..q).map(|i| z[(t, i)].powi(2)).sum();
                (all.sqrt(), ((all - head).max(0.0) + 1e-12 * all).sqrt())
            })
            .unzip();
        let mut evaluated = 0usize;
        let mut out = Vec::with_capacity(self.a.nrows());
        let ns = self.a.nrows();
        let mut yhat = Mat::<f64>::zeros(spc, NODE_BLOCK);
        for n0 in (0..ns).step_by(NODE_BLOCK) {
            let nb = NODE_BLOCK.min(ns - n0);
            // the bracket centres of a block of nodes, scanned while in cache
            matmul(
                yhat.as_mut().subcols_mut(0, nb),
                Accum::Replace,
                z.as_ref(),
                self.a.as_ref().subrows(n0, nb).transpose(),
                1.0,
                Par::Seq,
            );
            for i in 0..nb {
                let n = n0 + i;
                let y = yhat
                    .col(i)
                    .try_as_col_major()
                    .expect("contiguous")
                    .as_slice();
                let r = self
                    .rows_t
                    .col(n)
                    .try_as_col_major()
                    .expect("contiguous")
                    .as_slice();
                let exact = |t: usize| dot(r, column(t));
                let (b, w) = (self.tail[n], ROUNDOFF * self.norm[n]);
                let half = |t: usize| b * c[t] + w * xn[t];
                let upper = smallest_upper(y, &c, &xn, (b, w));
                let mut best: Option<(usize, f64)> = None;
                for t in 0..spc {
                    if y[t] - half(t) <= upper {
                        evaluated += 1;
                        let v = exact(t);
                        if best.is_none_or(|(_, bv)| v < bv) {
                            best = Some((t, v));
                        }
                    }
                }
                let (k, v) = best.expect("the smallest upper bracket's sample is a candidate");
                let mut around = Vec::with_capacity(3);
                if k > 0 {
                    around.push(exact(k - 1));
                }
                around.push(v);
                if k + 1 < spc {
                    around.push(exact(k + 1));
                }
                out.push(sampled_peak(&around, 0..around.len(), -1.0).map_or(0.0, |(g, _)| g));
            }
        }
        let per_node = evaluated as f64 / self.a.nrows().max(1) as f64;
        log::debug!("surface map: {q} directions, {per_node:.2} exact samples per node of {spc}");
        (out, per_node)
    }
}

/// min_t (y_t + b c_t + w x_t): the smallest upper bracket of a node (eight independent
/// running minima, so that the loop vectorises).
fn smallest_upper(y: &[f64], c: &[f64], x: &[f64], (b, w): (f64, f64)) -> f64 {
    let mut lanes = [f64::INFINITY; 8];
    let n = y.len() / 8 * 8;
    for t0 in (0..n).step_by(8) {
        for (i, lane) in lanes.iter_mut().enumerate() {
            let v = y[t0 + i] + (b * c[t0 + i] + w * x[t0 + i]);
            if v < *lane {
                *lane = v;
            }
        }
    }
    let mut upper = lanes.iter().copied().fold(f64::INFINITY, f64::min);
    for t in n..y.len() {
        upper = upper.min(y[t] + (b * c[t] + w * x[t]));
    }
    upper
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random sequence in [-0.5, 0.5).
    fn noise(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// The surface rows of `ns` nodes on `nm` modes and `nc` contact loads: smooth in space
    /// (a few harmonics of the node index) plus a small rough part, so that the brackets'
    /// directions leave a tail.
    fn rows(ns: usize, nm: usize, nc: usize, seed: &mut u64) -> SurfaceRows {
        let mut entry = |n: usize, j: usize| {
            let x = n as f64 / ns as f64;
            let smooth = ((j % 7 + 1) as f64 * 6.3 * x + j as f64).sin() / (1.0 + j as f64);
            smooth + 1e-3 * noise(seed)
        };
        let modes = Dense::from_shape_fn((ns, nm), |(n, j)| entry(n, j));
        let residual = Dense::from_shape_fn((ns, nc), |(n, j)| 1e-3 * entry(n, nm + j));
        SurfaceRows {
            nodes: (0..ns).collect(),
            modes,
            residual,
        }
    }

    /// Signals: decaying rings of several frequencies per coordinate, the loads in newtons.
    fn signals(m: usize, nc: usize, spc: usize, seed: &mut u64) -> Mat<f64> {
        let phase: Vec<f64> = (0..m).map(|_| noise(seed) * 6.0).collect();
        Mat::from_fn(m, spc, |j, t| {
            let s = t as f64 / spc as f64;
            let ring = (40.0 * s * (1.0 + j as f64 % 5.0) + phase[j]).sin() * (-3.0 * s).exp();
            let scale = if j >= m - nc { 1e3 } else { 1.0 };
            scale * (ring + 0.05 * noise(seed))
        })
    }

    /// Verification: the brackets find each node's exact minimum. Against the brute force
    /// (every sample's y_n = r_n . x(t) with the same dot product, then [`sampled_peak`] on the
    /// whole series) the peaks are equal to the last bit, for a tail left by the direction
    /// limit (more coordinates than [`MAX_DIRECTIONS`]) and for brackets made on another
    /// cycle's signals (weights that do not fit).
    #[test]
    fn verification_bracketed_minima_equal_the_brute_force() {
        let mut seed = 11u64;
        let (ns, nm, nc, spc) = (150, 70, 12, 600);
        let surface = rows(ns, nm, nc, &mut seed);
        let own = signals(nm + nc, nc, spc, &mut seed);
        let other = signals(nm + nc, nc, spc, &mut seed);
        for (made_on, x) in [(&own, &own), (&other, &own)] {
            let p = Projector::new(&surface, made_on.as_ref(), None);
            assert!(p.p_scaled.ncols() <= MAX_DIRECTIONS);
            let (peaks, exact) = p.peaks(x.as_ref());
            assert!(exact < spc as f64, "every sample evaluated: {exact}");
            for (n, &got) in peaks.iter().enumerate() {
                let r = p.rows_t.col(n).try_as_col_major().unwrap().as_slice();
                let y: Vec<f64> = (0..spc)
                    .map(|t| dot(r, x.col(t).try_as_col_major().unwrap().as_slice()))
                    .collect();
                let (want, _) = sampled_peak(&y, 0..spc, -1.0).unwrap();
                assert_eq!(got.to_bits(), want.to_bits(), "node {n}: {got} against {want}");
            }
        }
    }
}
