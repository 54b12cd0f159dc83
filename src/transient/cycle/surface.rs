//! Liner maps: per averaged cycle, the peak negative acceleration of every node of each liner's
//! wet outer surface, formed as the analysis points' are.
//!
//! A surface node's displacement is u_n(t) = r_n . x(t), r_n = [phi_n | R_nc] its ROM row
//! ([`crate::reduce::rom::SurfaceRows`]) and x = [eta; q; F_c] the modal coordinates (the
//! integrated modes' eta, then the quasi-static q of those not integrated, as the points have
//! them: [`EngineRun::point_displacements`]) and the cylinder's contact loads. Its output
//! acceleration is the point outputs' chain applied to u_n: the fourth-order second difference d, then the zero-phase FIR h (taps h_k, k = -L..L).
//! Both are linear and time-invariant, so y_n(t) = r_n . xbar(t), xbar = h * d(x).
//!
//! The minimum over a cycle's S samples for N nodes would take N S m products (m = modes +
//! contact loads: 6 x 1,968 x 2,880 x 605 per cycle on the default engine, about 40 times the
//! transient's own work). It is found exactly with far fewer. With each coordinate weighted by
//! its RMS D_j (w_n = D r_n, x' = D^-1 xbar), let P hold the q leading eigenvectors of W^T W and
//! Q the rest of an orthonormal basis. Then
//!   y_n(t) = a_n . z(t) + (Q^T w_n) . (Q^T x'(t)),   a_n = P^T w_n,  z = P^T x',
//! and by Cauchy-Schwarz the second term is at most b_n c(t), b_n = |Q^T w_n| =
//! sqrt(|w_n|^2 - |a_n|^2), c(t) = |Q^T x'(t)| = sqrt(|x'(t)|^2 - |z(t)|^2). So the q
//! projections bracket every y_n(t) within +-(b_n c(t) + rounding allowance) at a cost of
//! q (m + N) per sample (the centres and the comparisons in single precision). Only the
//! samples whose lower bracket reaches below the node's smallest upper bracket can hold its
//! minimum; y_n is evaluated exactly there (and at the minimum's neighbours, for the vertex of
//! [`sampled_peak`]). A bracket that is not finite admits its sample. The result is the exact
//! minimum of the sampled series whatever q and D are; they only decide how many samples are
//! evaluated exactly.

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

/// Relative allowance for the single-precision bracket: its centres (products of length q
/// of values rounded to f32) and its sums and comparisons carry errors of about (q + 4) 6e-8
/// of |a_n| |z(t)| <= |w_n| |x'(t)|: 1e-5 of |w_n| |x'(t)| (3 ulps of f32 would do for the
/// comparisons alone).
const ROUNDOFF_SINGLE: f64 = 1e-5;

/// Cycles the transient may run ahead of the maps (each queued cycle holds its record
/// segment: about 15 MB on the default engine); counted in `scene::budget::maps`.
pub const QUEUED_CYCLES: usize = 8;

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
/// from sample `start` on. Each mapped cycle's segment goes to a worker thread ([`Mapper`]),
/// which maps it while the transient runs on: the transient keeps one core busy, the maps
/// the other.
pub(super) struct SurfaceRecord {
    start: usize,
    nb: usize,
    eta: Vec<f64>,
    loads: Vec<Vec<f64>>,
    ncon: Vec<usize>,
    jobs: Option<std::sync::mpsc::SyncSender<Job>>,
    worker: Option<std::thread::JoinHandle<MapperResult>>,
    /// Set when the run stops early: the worker drops the cycles still queued.
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Drop for SurfaceRecord {
    /// A run that stops early (an error) stops the worker too and waits for it, so that no
    /// mapping goes on after the run has returned.
    fn drop(&mut self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
        self.jobs = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

/// What the mapper returns: per cylinder and node the peak of each mapped cycle, or the
/// first failure.
type MapperResult = Result<Vec<Vec<Vec<f64>>>, TransientError>;

/// One cycle's segment of the record, sample-major (zero before the record's start).
struct Job {
    cycle: usize,
    eta: Vec<f64>,
    loads: Vec<Vec<f64>>,
}

impl SurfaceRecord {
    /// A record from global sample `from` on (nothing earlier is kept), for cycles of `spc`
    /// samples at step `dt` with the output filter's `margin`.
    pub(super) fn new(
        run: &EngineRun<'_>,
        from: usize,
        (spc, margin, dt): (usize, usize, f64),
    ) -> Result<Self, TransientError> {
        let ncon: Vec<usize> = run
            .cyls
            .iter()
            .map(|c| c.rom.thrust_z.len() + c.rom.antithrust_z.len())
            .collect();
        // every mode's coordinate: the integrated ones and the quasi-static rest
        let nb = run.structure.integrator.eta.len() + run.dropped_static.len();
        let len = spc + 2 * margin;
        let mut mapper = Mapper {
            surfaces: run.cyls.iter().map(|c| c.rom.surface.clone()).collect(),
            nb,
            ncon: ncon.clone(),
            projectors: run.cyls.iter().map(|_| None).collect(),
            peaks: run
                .cyls
                .iter()
                .map(|c| vec![Vec::new(); c.rom.surface.nodes.len()])
                .collect(),
            window: Window {
                len,
                margin,
                spc,
                dt,
                batch: run
                    .settings
                    .output_band_hz
                    .map(|band| BatchLowPass::new(len, dt, band)),
            },
        };
        // at most QUEUED_CYCLES queued: the transient (faster than the maps on the default
        // engine) runs ahead by that much, then waits rather than the queue growing
        let (jobs, inbox) = std::sync::mpsc::sync_channel::<Job>(QUEUED_CYCLES);
        let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop = cancel.clone();
        let worker = std::thread::Builder::new()
            .name("liner-maps".into())
            .spawn(move || {
                for job in inbox {
                    if stop.load(std::sync::atomic::Ordering::Relaxed) {
                        break;
                    }
                    mapper.map(job)?;
                }
                Ok(mapper.peaks)
            })
            .map_err(|e| TransientError::MapsStopped(format!("no thread for the maps: {e}")))?;
        Ok(SurfaceRecord {
            start: from,
            nb,
            eta: Vec::new(),
            loads: run.cyls.iter().map(|_| Vec::new()).collect(),
            ncon,
            jobs: Some(jobs),
            worker: Some(worker),
            cancel,
        })
    }

    /// Appends global sample `g` (ignored before the record's start).
    pub(super) fn push(&mut self, run: &EngineRun<'_>, g: usize) {
        if g < self.start {
            return;
        }
        self.eta.extend_from_slice(&run.structure.integrator.eta);
        self.eta.extend_from_slice(&run.dropped_static);
        for (c, loads) in self.loads.iter_mut().enumerate() {
            let off = loads.len();
            loads.resize(off + self.ncon[c], 0.0);
            let first = run.cyls[c].rom.contact_offset;
            for (_, at, force) in run.prev_loaded.iter().filter(|(b, _, _)| *b == c) {
                for i in 0..2 {
                    loads[off + at.dofs[i] - first] += at.weights[i] * force;
                }
            }
        }
    }

    /// Hands cycle `k` (its record [k N - margin, (k + 1) N + margin) complete) to the
    /// mapper, then drops what no later cycle needs.
    pub(super) fn map_cycle(&mut self, k: usize, (spc, margin): (usize, usize)) {
        let lo = (k * spc) as isize - margin as isize;
        let len = spc + 2 * margin;
        let segment = |record: &[f64], m: usize| -> Vec<f64> {
            let mut v = vec![0.0; len * m];
            for s in 0..len {
                let g = lo + s as isize;
                if g >= self.start as isize {
                    let i = (g as usize - self.start) * m;
                    if let Some(src) = record.get(i..i + m) {
                        v[s * m..(s + 1) * m].copy_from_slice(src);
                    }
                }
            }
            v
        };
        let job = Job {
            cycle: k,
            eta: segment(&self.eta, self.nb),
            loads: self
                .loads
                .iter()
                .zip(&self.ncon)
                .map(|(l, &m)| segment(l, m))
                .collect(),
        };
        if let Some(jobs) = &self.jobs {
            // a closed inbox means the worker stopped: finish() reports it
            let _ = jobs.send(job);
        }
        let keep_from = ((k + 1) * spc).saturating_sub(margin).max(self.start);
        let drop = keep_from - self.start;
        self.eta.drain(..(drop * self.nb).min(self.eta.len()));
        for (loads, &m) in self.loads.iter_mut().zip(&self.ncon) {
            loads.drain(..(drop * m).min(loads.len()));
        }
        self.start = keep_from;
    }

    /// Waits for the mapper and returns the mapped cycles' peaks per cylinder, or where it
    /// failed.
    pub(super) fn finish(
        mut self,
        run: &EngineRun<'_>,
    ) -> Result<Vec<SurfacePeaks>, TransientError> {
        self.jobs = None;
        let peaks = match self.worker.take().map(|w| w.join()) {
            Some(Ok(p)) => p?,
            Some(Err(panic)) => {
                let msg = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "the mapping thread stopped".into());
                return Err(TransientError::MapsStopped(msg));
            }
            None => Vec::new(),
        };
        Ok(peaks
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
            .collect())
    }
}

/// The maps' worker: each cylinder's surface rows and brackets, and the peaks so far.
struct Mapper {
    surfaces: Vec<SurfaceRows>,
    nb: usize,
    ncon: Vec<usize>,
    projectors: Vec<Option<Projector>>,
    peaks: Vec<Vec<Vec<f64>>>,
    window: Window,
}

impl Mapper {
    /// Maps one cycle's segment: appends each surface node's peak negative acceleration; a
    /// non-finite coordinate or bracket is reported with the cylinder and the cycle.
    fn map(&mut self, job: Job) -> Result<(), TransientError> {
        let eta_bar = self.window.outputs(&job.eta, self.nb);
        for (c, loads) in job.loads.iter().enumerate() {
            let surface = &self.surfaces[c];
            if surface.nodes.is_empty() {
                continue;
            }
            let fail = |msg: &str| TransientError::Maps {
                cylinder: c + 1,
                cycle: job.cycle,
                msg: msg.into(),
            };
            let ncon = self.ncon[c];
            let f_bar = self.window.outputs(loads, ncon);
            let mut x = Mat::<f64>::zeros(eta_bar.nrows() + ncon, self.window.spc);
            x.as_mut()
                .subrows_mut(0, eta_bar.nrows())
                .copy_from(&eta_bar);
            x.as_mut()
                .subrows_mut(eta_bar.nrows(), ncon)
                .copy_from(&f_bar);
            if !x.is_all_finite() {
                return Err(fail("the filtered coordinates are not finite"));
            }
            let mut p = match self.projectors[c].take() {
                Some(p) => p,
                None => {
                    Projector::new(surface, x.as_ref(), None).map_err(|e| fail(&evd_failed(e)))?
                }
            };
            let (peaks, exact) = p.peaks(x.as_ref());
            if exact > REWEIGHT_ABOVE {
                p = Projector::new(surface, x.as_ref(), Some(&p.weight))
                    .map_err(|e| fail(&evd_failed(e)))?;
            }
            self.projectors[c] = Some(p);
            for (series, v) in self.peaks[c].iter_mut().zip(peaks) {
                series.push(v);
            }
        }
        Ok(())
    }
}

/// One cycle's output window: `len` samples, the cycle's `spc` of them `margin` in, at step
/// `dt`, and the low-pass (None: the outputs are not filtered).
struct Window {
    len: usize,
    margin: usize,
    spc: usize,
    dt: f64,
    batch: Option<BatchLowPass>,
}

impl Window {
    /// Each of the `m` series of a sample-major segment (`len` samples) as the point outputs
    /// form theirs ([`Record::outputs`]): the fourth-order second difference, the low-pass (two
    /// series per transform), the cycle's samples; as a series x samples matrix.
    fn outputs(&self, segment: &[f64], m: usize) -> Mat<f64> {
        let mut series: Vec<Vec<f64>> = (0..m)
            .map(|j| {
                let raw: Vec<f64> = (0..self.len).map(|s| segment[s * m + j]).collect();
                second_difference4(&raw, self.dt)
            })
            .collect();
        if let Some(f) = &self.batch {
            for pair in series.chunks_mut(2) {
                match pair {
                    [a, b] => f.apply_pair(a, b),
                    [a] => f.apply_pair(a, &mut vec![0.0; self.len]),
                    _ => {}
                }
            }
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
    /// a_n = P^T w_n in single precision: nodes x q.
    a32: Mat<f32>,
    /// b_n = |Q^T w_n| (with its roundoff allowance) and |w_n|.
    tail: Vec<f64>,
    norm: Vec<f64>,
}

/// The message of a failed eigen-decomposition of the weighted surface rows.
fn evd_failed(e: faer::linalg::evd::EvdError) -> String {
    format!("the eigen-decomposition of the weighted rows failed: {e:?}")
}

impl Projector {
    /// The brackets for the surface rows, each coordinate weighted by its RMS over `x`
    /// (coordinates x samples) or `previous`, whichever is larger, but at least 1e-3 of the
    /// largest of its group (modes, contact loads): a contact DOF idle in one cycle may carry
    /// the next one's slap.
    fn new(
        surface: &SurfaceRows,
        x: MatRef<'_, f64>,
        previous: Option<&[f64]>,
    ) -> Result<Self, faer::linalg::evd::EvdError> {
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
                // a group idle in this cycle (no contact yet) keeps unit weights: any positive
                // weight is valid, and a vanishing one would overflow x / D later
                *w = if top > 0.0 { w.max(1e-3 * top) } else { 1.0 };
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
        let evd = gram.self_adjoint_eigen(faer::Side::Lower)?;
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
        let a32 = Mat::from_fn(ns, q, |n, i| a[(n, i)] as f32);
        Ok(Projector {
            rows_t,
            weight,
            p_scaled,
            a32,
            tail,
            norm,
        })
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
        // the bracket in single precision: centres, half widths and the comparisons, with
        // the allowance ROUNDOFF_SINGLE |w_n| |x'(t)| for their rounding
        let z32 = Mat::<f32>::from_fn(spc, q, |t, i| z[(t, i)] as f32);
        let (c32, xn32): (Vec<f32>, Vec<f32>) = c
            .iter()
            .zip(&xn)
            .map(|(&a, &b)| (a as f32, b as f32))
            .unzip();
        let mut evaluated = 0usize;
        let mut out = Vec::with_capacity(self.a32.nrows());
        let ns = self.a32.nrows();
        let mut yhat = Mat::<f32>::zeros(spc, NODE_BLOCK);
        for n0 in (0..ns).step_by(NODE_BLOCK) {
            let nb = NODE_BLOCK.min(ns - n0);
            // the bracket centres of a block of nodes, scanned while in cache
            matmul(
                yhat.as_mut().subcols_mut(0, nb),
                Accum::Replace,
                z32.as_ref(),
                self.a32.as_ref().subrows(n0, nb).transpose(),
                1.0f32,
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
                let (b, w) = (
                    self.tail[n] as f32,
                    ((ROUNDOFF_SINGLE + ROUNDOFF) * self.norm[n]) as f32,
                );
                let upper = smallest_upper(y, &c32, &xn32, (b, w));
                let mut best: Option<(usize, f64)> = None;
                for (t, ((&yt, &ct), &xt)) in y.iter().zip(&c32).zip(&xn32).enumerate() {
                    // a bracket that is not finite (incomparable) admits its sample
                    let lower = yt - (b * ct + w * xt);
                    if lower.partial_cmp(&upper) != Some(std::cmp::Ordering::Greater) {
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
        let per_node = evaluated as f64 / self.a32.nrows().max(1) as f64;
        log::debug!("surface map: {q} directions, {per_node:.2} exact samples per node of {spc}");
        (out, per_node)
    }
}

/// min_t (y_t + b c_t + w x_t): the smallest upper bracket of a node (sixteen independent
/// running minima, so that the loop vectorises).
fn smallest_upper(y: &[f32], c: &[f32], x: &[f32], (b, w): (f32, f32)) -> f32 {
    let mut lanes = [f32::INFINITY; 16];
    let (yc, cc, xc) = (y.chunks_exact(16), c.chunks_exact(16), x.chunks_exact(16));
    let tail = yc
        .remainder()
        .iter()
        .zip(cc.remainder())
        .zip(xc.remainder());
    for ((ys, cs), xs) in yc.zip(cc).zip(xc) {
        for i in 0..16 {
            let v = ys[i] + (b * cs[i] + w * xs[i]);
            if v < lanes[i] {
                lanes[i] = v;
            }
        }
    }
    let mut upper = lanes.iter().copied().fold(f32::INFINITY, f32::min);
    for ((&yt, &ct), &xt) in tail {
        upper = upper.min(yt + (b * ct + w * xt));
    }
    upper
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transient::signal::tests::noise;

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
            let p = Projector::new(&surface, made_on.as_ref(), None).unwrap();
            assert!(p.p_scaled.ncols() <= MAX_DIRECTIONS);
            let (peaks, exact) = p.peaks(x.as_ref());
            assert!(exact < spc as f64, "every sample evaluated: {exact}");
            for (n, &got) in peaks.iter().enumerate() {
                let r = p.rows_t.col(n).try_as_col_major().unwrap().as_slice();
                let y: Vec<f64> = (0..spc)
                    .map(|t| dot(r, x.col(t).try_as_col_major().unwrap().as_slice()))
                    .collect();
                let (want, _) = sampled_peak(&y, 0..spc, -1.0).unwrap();
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "node {n}: {got} against {want}"
                );
            }
        }
    }
}
