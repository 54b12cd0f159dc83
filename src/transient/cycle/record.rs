//! The rolling record of a run, from which each cycle's filtered point accelerations are
//! formed once the run has gone past it.

#[allow(unused_imports)]
use super::*;

/// Samples each side of an output sample that its difference formula reads
/// ([`second_difference4`]) plus one.
pub const OUTPUT_DIFFERENCE_REACH: usize = 3;

/// The rolling record of the run from sample `start` on: per cylinder and point the liner's
/// displacement ([`EngineRun::point_displacements`]), and (from `wall_from` on, the last
/// cycle) the crankcase's. Only what a cycle not yet output needs is kept.
pub(super) struct Record {
    start: usize,
    disp: Vec<Vec<Vec<f64>>>,
    wall: Vec<Vec<Vec<f64>>>,
    wall_from: usize,
}

impl Record {
    pub(super) fn new(run: &EngineRun<'_>, wall_from: usize) -> Self {
        let disp = run
            .cyls
            .iter()
            .map(|c| vec![Vec::new(); c.rom.point_modes.nrows()])
            .collect();
        let wall = run
            .cyls
            .iter()
            .map(|c| vec![Vec::new(); c.rom.crankcase_point_modes.nrows()])
            .collect();
        Record {
            start: 0,
            disp,
            wall,
            wall_from,
        }
    }

    /// Appends global sample `g` of the run.
    pub(super) fn push(&mut self, run: &EngineRun<'_>, g: usize) {
        for c in 0..run.cyls.len() {
            for (p, u) in run.point_displacements(c, false).into_iter().enumerate() {
                self.disp[c][p].push(u);
            }
            if g >= self.wall_from {
                for (p, u) in run.point_displacements(c, true).into_iter().enumerate() {
                    self.wall[c][p].push(u);
                }
            }
        }
    }

    /// Cycle `k`'s point accelerations into `series` (the crankcase's too when `last`): the
    /// fourth-order second difference of the recorded displacements ([`second_difference4`]),
    /// filtered over the record [k N - margin, (k + 1) N + margin) (N = `spc` steps per
    /// cycle). Then drops what no later cycle needs.
    ///
    /// Formed from displacements, not from the integrator's accelerations: the modes above
    /// the base step's Nyquist rate that a slap's sub-steps resolve ring in the accelerations
    /// (omega^2 times their displacement) and would alias into the band when sampled at the
    /// base step; in the displacements they are omega^2 smaller. The difference's error in
    /// the band is (omega h)^4 / 90 (3e-4 at 3 kHz and the default step).
    pub(super) fn outputs(
        &mut self,
        run: &EngineRun<'_>,
        series: &mut Series,
        k: usize,
        last: bool,
        (spc, margin, dt): (usize, usize, f64),
    ) {
        let lo = (k * spc) as isize - margin as isize;
        let len = spc + 2 * margin;
        for (c, cs) in series.cylinders.iter_mut().enumerate() {
            let points = (0..self.disp[c].len())
                .map(|p| {
                    let u = record_segment(&self.disp[c][p], self.start, lo, len);
                    run.output_filter(&second_difference4(&u, dt), dt, margin, spc)
                })
                .collect();
            cs.acceleration = from_row_vecs(points);
            if last {
                let walls = (0..self.wall[c].len())
                    .map(|p| {
                        let w = record_segment(&self.wall[c][p], self.wall_from, lo, len);
                        run.output_filter(&second_difference4(&w, dt), dt, margin, spc)
                    })
                    .collect();
                cs.crankcase_acceleration = from_row_vecs(walls);
            }
        }
        let keep_from = ((k + 1) * spc).saturating_sub(margin).max(self.start);
        for v in self.disp.iter_mut().flatten() {
            v.drain(..keep_from - self.start);
        }
        self.start = keep_from;
    }
}

/// Samples [lo, lo + len) of a record whose element 0 is sample `start`; samples before t = 0
/// (negative indices: the engine at rest) and beyond the record are zero.
pub(super) fn record_segment(v: &[f64], start: usize, lo: isize, len: usize) -> Vec<f64> {
    (lo..lo + len as isize)
        .map(|i| {
            if i < start as isize {
                0.0
            } else {
                v.get(i as usize - start).copied().unwrap_or(0.0)
            }
        })
        .collect()
}
