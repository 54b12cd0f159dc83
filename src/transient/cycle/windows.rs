//! The firing-slap windows: where each cylinder's window starts, the states there, and the
//! windows run on from them at any step (the step-error estimate and the speed-against-error
//! comparisons).

use super::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

impl<'a> EngineRun<'a> {
    /// Where each cylinder's step-error window starts in the last cycle (global step) and its
    /// length in steps. The peaks are compared away from the output filter's ends; where the
    /// filter spans more than the window's first and last 35 deg (high speed: at 3800 rpm a
    /// 110 deg window was shorter than the filter), the window is widened at both ends so the
    /// compared part still covers the slap at 355-395 deg.
    pub(super) fn step_error_plan(
        &self,
        cycles: usize,
        spc: usize,
        filter_steps: usize,
    ) -> (Vec<usize>, usize) {
        let step_deg = self.settings.step_deg;
        let lead_steps = ((filter_steps as f64 * step_deg - SLAP_MARGIN_DEG).max(0.0) / step_deg)
            .ceil() as usize;
        let window_steps = ((STEP_ERROR_WINDOW_DEG.1 - STEP_ERROR_WINDOW_DEG.0) / step_deg).round()
            as usize
            + 2 * lead_steps;
        let lead_deg = lead_steps as f64 * step_deg;
        let starts = self
            .cyls
            .iter()
            .map(|c| {
                let own = (STEP_ERROR_WINDOW_DEG.0 - lead_deg + c.phase).rem_euclid(720.0);
                (cycles - 1) * spc + (own / step_deg).round() as usize % spc
            })
            .collect();
        (starts, window_steps)
    }

    /// Samples of the record an output at step size `dt` reaches on either side: the output
    /// filter's half length and the second difference's reach.
    pub(super) fn output_margin(&self, dt: f64) -> usize {
        self.settings
            .output_band_hz
            .map_or(0, |band| fir_half_length(dt, band))
            + OUTPUT_DIFFERENCE_REACH
    }

    /// The run's states where each cylinder's firing-slap window starts in cycle `cycle`
    /// (0-based, from rest): the windows of the step-error estimate
    /// ([`STEP_ERROR_WINDOW_DEG`], widened by the output filter's reach), as (cylinder index,
    /// state) in time order, and the windows' length in base steps. Every state can be run on
    /// by [`EngineRun::window_peaks`] at any step, so that settings are compared on identical
    /// slaps.
    pub fn slap_window_states(
        mut self,
        cycle: usize,
    ) -> Result<(Vec<(usize, Self)>, usize), TransientError> {
        let spc = (720.0 / self.settings.step_deg).round() as usize;
        let dt = self.base_dt();
        let (starts, steps) = self.step_error_plan(cycle + 1, spc, self.output_margin(dt));
        let mut order: Vec<usize> = (0..starts.len()).collect();
        order.sort_by_key(|&c| starts[c]);
        let mut states = Vec::with_capacity(order.len());
        let mut g = 0;
        for c in order {
            while g < starts[c] {
                g += 1;
                self.checked_step(g as f64 * dt)?;
            }
            states.push((c, self.clone()));
        }
        Ok((states, steps))
    }

    /// This state with `slap_substeps` sub-steps per base step in slaps (1: a uniform step).
    pub fn with_slap_substeps(mut self, substeps: usize) -> Self {
        self.settings.slap_substeps = substeps.max(1);
        self
    }

    /// Runs `steps` steps of `h` from the current state and returns the peak negative
    /// acceleration of cylinder index `c`'s points over the window, filtered like the cycle's
    /// outputs and taken where the filter's ends do not reach.
    pub fn window_peaks(
        mut self,
        c: usize,
        steps: usize,
        h: f64,
    ) -> Result<Vec<f64>, TransientError> {
        let n = self.cyls[c].rom.point_modes.nrows();
        let mut disp = vec![Vec::with_capacity(steps); n];
        let t0 = self.time;
        for k in 1..=steps {
            let target = t0 + k as f64 * h;
            let dt = target - self.time;
            self.advance(dt)?;
            for (p, u) in self.point_displacements(c, false).into_iter().enumerate() {
                disp[p].push(u);
            }
        }
        let half = self.output_margin(h);
        Ok((0..n)
            .map(|p| {
                let acc = second_difference4(&disp[p], h);
                let y = match self.settings.output_band_hz {
                    Some(band) => low_pass(&acc, h, band, false).0,
                    None => acc,
                };
                let lo = half.min(y.len());
                sampled_peak(&y, lo..y.len().saturating_sub(half).max(lo), -1.0)
                    .map_or(0.0, |(p, _)| p.max(0.0))
            })
            .collect())
    }

    /// Runs `steps` steps of `h` from the current state and returns each cylinder's slap
    /// events with their onset in the window ([`SlapEvent`]; an event in contact at the start
    /// counts from there), so that settings can be compared on identical slaps.
    pub fn window_events(
        mut self,
        steps: usize,
        h: f64,
    ) -> Result<Vec<Vec<SlapEvent>>, TransientError> {
        self.events = EventRecorder::new(self.cyls.len());
        let t0 = self.time;
        for k in 1..=steps {
            let target = t0 + k as f64 * h;
            self.advance(target - self.time)?;
        }
        self.events.close();
        Ok(self.events.done)
    }

    /// The half-step estimate's window of cylinder index `c` from this state: its peaks at
    /// `dt` and at `dt` / 2 ([`EngineRun::window_peaks`]), the two runs side by side.
    fn step_error(
        self,
        c: usize,
        window_steps: usize,
        dt: f64,
    ) -> Result<StepError, TransientError> {
        let cylinder = self.cyls[c].rom.cylinder;
        let half = self.clone();
        let (peak_h, peak_half_h) = rayon::join(
            move || self.window_peaks(c, window_steps, dt),
            move || half.window_peaks(c, 2 * window_steps, 0.5 * dt),
        );
        Ok(StepError {
            cylinder,
            peak_h: peak_h?,
            peak_half_h: peak_half_h?,
        })
    }
}

/// The half-step estimate's windows of a run ([`EngineRun::step_error`]), each started as a
/// task as soon as the run reaches its state, so that they run on the other core while the
/// cycles go on. The windows are independent runs from their own states: the results are
/// the same bits as one after the other, and the first failing window in time order is the
/// one reported, as a serial run would.
pub(super) struct StepErrorRuns {
    window_steps: usize,
    dt: f64,
    /// Each window's result in the order started (None until it has run).
    slots: Mutex<Vec<Option<Result<StepError, TransientError>>>>,
    /// Set when the run failed: windows not yet begun are skipped.
    cancelled: AtomicBool,
}

impl StepErrorRuns {
    pub(super) fn new(window_steps: usize, dt: f64) -> Self {
        Self {
            window_steps,
            dt,
            slots: Mutex::new(Vec::new()),
            cancelled: AtomicBool::new(false),
        }
    }

    /// Starts cylinder index `c`'s window from `state` as a task of `scope`.
    pub(super) fn start<'s, 'a: 's>(
        &'s self,
        scope: &rayon::Scope<'s>,
        c: usize,
        state: EngineRun<'a>,
    ) {
        let slot = {
            let mut slots = self.slots.lock().expect("no window panicked");
            slots.push(None);
            slots.len() - 1
        };
        scope.spawn(move |_| {
            if self.cancelled.load(Ordering::Relaxed) {
                return;
            }
            let result = state.step_error(c, self.window_steps, self.dt);
            self.slots.lock().expect("no window panicked")[slot] = Some(result);
        });
    }

    /// Skips the windows that have not begun (the run failed).
    pub(super) fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    /// Every window's step error in the order started; the first failure in that order.
    pub(super) fn results(self) -> Result<Vec<StepError>, TransientError> {
        self.slots
            .into_inner()
            .expect("no window panicked")
            .into_iter()
            .map(|r| r.expect("every window ran (the run did not fail)"))
            .collect()
    }
}
