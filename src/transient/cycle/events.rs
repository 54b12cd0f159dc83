//! Slap events: each skirt side's contact episodes grouped into impacts, taken from every
//! committed step (the slap sub-steps included), so that a slap's force is its peak between
//! the sub-steps, not the nearest base-step sample.
//!
//! An event on side s (thrust, anti-thrust) of a cylinder begins at a contact onset of that
//! side (its summed slice force turns positive) after the side has been apart for more than
//! [`EVENT_SEPARATION_DEG`] of crank angle; contacts within that span after the last one are
//! its rebounds. Per event:
//! - `crank_angle_deg`: the cylinder's own crank angle at the onset (the impact);
//! - `force_n`: the largest dynamic slap force of the side over the event,
//!   s (F_thrust - F_anti - F_side), s = +1 thrust, -1 anti-thrust (the contact force beyond
//!   the quasi-static side force F_side, as the per-cycle slap-force peak has always been),
//!   its peak interpolated between the samples ([`parabola_peak`]; the samples are unevenly
//!   spaced where sub-steps begin and end). A sampled maximum alone misses a smooth peak by
//!   up to h^2 |F''| / 8, about 2 % on the default engine's 1/12 deg slap sub-steps, by an
//!   amount that depends on where the step grid falls;
//! - `impact_velocity_m_s`: the velocity of the side's deepest slice toward the wall at its
//!   contact onset, row . v (the piston's; the wall's own motion, a few percent of it, is not
//!   subtracted);
//! - `impact_energy_j`: the kinetic energy of the piston's secondary motion (lateral and tilt)
//!   at that onset, E = 1/2 v^T M_b v with M_b the body's 2 x 2 mass;
//!
//! the onset located within its step from the penetrations at the step's ends and the piston's
//! motion before contact (`EngineRun::observe_events`), so they do not depend on where the
//! step happened to begin.
//!
//! Over the averaged cycles the events of a cylinder are grouped by side and onset angle
//! (onsets within [`EVENT_CLUSTER_DEG`] of each other are the same event of different cycles;
//! a cycle's largest in a group counts), and each group reports the means over the cycles it
//! occurs in, with standard errors s / sqrt(n).

use crate::transient::signal::parabola_peak;
use serde::Serialize;

/// A side apart for more than this crank angle begins a new event at its next contact \[deg\]
/// (the impact and its first rebounds last about 1.5 deg on the default engine:
/// `transient.slap_span_deg`).
pub const EVENT_SEPARATION_DEG: f64 = 3.0;

/// Onsets of the same side within this crank angle of each other, in different cycles, are
/// one event \[deg\] (the firing slap's onset moves by a few degrees from cycle to cycle).
pub const EVENT_CLUSTER_DEG: f64 = 10.0;

/// One cycle's slap event (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SlapEvent {
    /// 0-based cycle of the onset (global crank angle / 720).
    #[serde(skip)]
    pub cycle: usize,
    pub thrust: bool,
    pub crank_angle_deg: f64,
    pub force_n: f64,
    /// The cylinder's own crank angle of the largest force \[deg\].
    pub force_crank_angle_deg: f64,
    pub impact_velocity_m_s: f64,
    pub impact_energy_j: f64,
    /// The side's contact impulse over the whole event, from the onset to the step that
    /// separates after its last rebound: the slap's momentum and, when the side stays in
    /// contact, the steady support against the side force until it lifts off \[N s\].
    pub impulse_n_s: f64,
}

/// A mean over cycles and its standard error s / sqrt(n).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Mean {
    pub value: f64,
    pub se: f64,
}

impl Mean {
    fn of(v: &[f64]) -> Self {
        let n = v.len() as f64;
        if v.is_empty() {
            return Mean::default();
        }
        let m = v.iter().sum::<f64>() / n;
        let se = if v.len() > 1 {
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt()
        } else {
            0.0
        };
        Mean { value: m, se }
    }
}

/// One event of a cylinder over the averaged cycles: means over the cycles it occurred in.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EventSummary {
    /// "thrust" or "antithrust".
    pub side: &'static str,
    /// Mean onset crank angle (the cylinder's own) \[deg\].
    pub crank_angle_deg: f64,
    pub force_n: Mean,
    pub impact_velocity_m_s: Mean,
    pub impact_energy_j: Mean,
    pub impulse_n_s: Mean,
    /// Averaged cycles in which the event occurred.
    pub cycles: usize,
}

/// What one committed step shows of one cylinder.
pub(super) struct SideSample {
    /// Global crank angle at the end of the step, and the cylinder's own \[deg\].
    pub global_deg: f64,
    pub own_deg: f64,
    /// Summed contact force of the thrust and anti-thrust side, quasi-static side force [N].
    pub forces: (f64, f64),
    pub side_force: f64,
    /// Per side, the approach rate of its deepest slice and the piston's secondary kinetic
    /// energy at that slice's contact onset within the step ([m/s], \[J\]; what an event starting
    /// in this step takes as its impact).
    pub rates: (f64, f64),
    pub kinetic_energy: (f64, f64),
    /// Per side, the step's contact impulse \[N s\].
    pub impulses: (f64, f64),
}

/// The open event of one side and when it last touched.
#[derive(Clone, Default)]
struct SideState {
    open: Option<SlapEvent>,
    last_contact_deg: f64,
    /// The side's last two contact samples of the open event, oldest first, as (global
    /// crank angle \[deg\], own crank angle \[deg\], dynamic force \[N\]); cleared by a step
    /// without contact, so that three consecutive samples never straddle a separation.
    recent: Vec<(f64, f64, f64)>,
}

/// The events of a run, per cylinder.
#[derive(Clone, Default)]
pub(super) struct EventRecorder {
    sides: Vec<[SideState; 2]>,
    /// Closed events per cylinder, in onset order.
    pub(super) done: Vec<Vec<SlapEvent>>,
}

impl EventRecorder {
    pub(super) fn new(cylinders: usize) -> Self {
        EventRecorder {
            sides: vec![Default::default(); cylinders],
            done: vec![Vec::new(); cylinders],
        }
    }

    /// Takes one committed step of cylinder `c`.
    pub(super) fn observe(&mut self, c: usize, s: &SideSample) {
        let dynamic = s.forces.0 - s.forces.1 - s.side_force;
        for (k, thrust) in [(0, true), (1, false)] {
            let (force, rate, energy, impulse) = if thrust {
                (s.forces.0, s.rates.0, s.kinetic_energy.0, s.impulses.0)
            } else {
                (s.forces.1, s.rates.1, s.kinetic_energy.1, s.impulses.1)
            };
            let side = &mut self.sides[c][k];
            if force <= 0.0 {
                side.recent.clear();
                // the step that separates still carries the contact's last impulse
                if let Some(e) = side.open.as_mut() {
                    if s.global_deg - side.last_contact_deg <= EVENT_SEPARATION_DEG {
                        e.impulse_n_s += impulse;
                    }
                }
                continue;
            }
            let rebound = side
                .open
                .is_some_and(|_| s.global_deg - side.last_contact_deg <= EVENT_SEPARATION_DEG);
            if !rebound {
                if let Some(e) = side.open.take() {
                    self.done[c].push(e);
                }
                side.recent.clear();
                side.open = Some(SlapEvent {
                    cycle: (s.global_deg / 720.0).floor().max(0.0) as usize,
                    thrust,
                    crank_angle_deg: s.own_deg,
                    force_n: f64::NEG_INFINITY,
                    force_crank_angle_deg: s.own_deg,
                    impact_velocity_m_s: rate,
                    impact_energy_j: energy,
                    impulse_n_s: 0.0,
                });
            }
            side.last_contact_deg = s.global_deg;
            let e = side.open.as_mut().expect("opened above");
            e.impulse_n_s += impulse;
            let f = if thrust { dynamic } else { -dynamic };
            if f > e.force_n {
                e.force_n = f;
                e.force_crank_angle_deg = s.own_deg;
            }
            // the previous sample a local maximum: the peak between its neighbours
            if let [(g0, _, f0), (g1, o1, f1)] = side.recent[..] {
                if f1 >= f0 && f1 >= f {
                    let (x, peak) = parabola_peak((g0, f0), (g1, f1), (s.global_deg, f));
                    if peak > e.force_n {
                        e.force_n = peak;
                        e.force_crank_angle_deg = o1 + (x - g1);
                    }
                }
                side.recent.remove(0);
            }
            side.recent.push((s.global_deg, s.own_deg, f));
        }
    }

    /// Closes the open events (the end of the run).
    pub(super) fn close(&mut self) {
        for (c, sides) in self.sides.iter_mut().enumerate() {
            for side in sides.iter_mut() {
                if let Some(e) = side.open.take() {
                    self.done[c].push(e);
                }
            }
            self.done[c].sort_by(|a, b| {
                (a.cycle, a.crank_angle_deg)
                    .partial_cmp(&(b.cycle, b.crank_angle_deg))
                    .unwrap()
            });
        }
    }

    /// Cylinder `c`'s events with their onset in `cycle` (open ones included).
    pub(super) fn in_cycle(&self, c: usize, cycle: usize) -> Vec<SlapEvent> {
        self.done[c]
            .iter()
            .chain(self.sides[c].iter().filter_map(|s| s.open.as_ref()))
            .filter(|e| e.cycle == cycle)
            .copied()
            .collect()
    }
}

/// The event groups of one cylinder over `cycles` (their events), each cycle's largest per
/// group counted, groups in onset order; and for each input event its group.
pub(super) fn summarise(events: &[SlapEvent]) -> (Vec<EventSummary>, Vec<usize>) {
    let mut order: Vec<usize> = (0..events.len()).collect();
    order.sort_by(|&a, &b| {
        let key = |e: &SlapEvent| (!e.thrust, e.crank_angle_deg);
        key(&events[a]).partial_cmp(&key(&events[b])).unwrap()
    });
    // groups: consecutive onsets of one side within EVENT_CLUSTER_DEG
    let mut group = vec![0; events.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (pos, &i) in order.iter().enumerate() {
        let new = pos == 0 || {
            let p = &events[order[pos - 1]];
            p.thrust != events[i].thrust
                || events[i].crank_angle_deg - p.crank_angle_deg > EVENT_CLUSTER_DEG
        };
        if new {
            groups.push(Vec::new());
        }
        groups.last_mut().expect("pushed").push(i);
        group[i] = groups.len() - 1;
    }
    let mut summaries: Vec<(usize, EventSummary)> = groups
        .iter()
        .enumerate()
        .map(|(g, members)| {
            // each cycle's largest event of the group
            let mut per_cycle: Vec<&SlapEvent> = Vec::new();
            for &i in members {
                let e = &events[i];
                match per_cycle.iter_mut().find(|x| x.cycle == e.cycle) {
                    Some(x) if e.force_n > x.force_n => *x = e,
                    Some(_) => {}
                    None => per_cycle.push(e),
                }
            }
            let pick = |f: &dyn Fn(&SlapEvent) -> f64| {
                Mean::of(&per_cycle.iter().map(|e| f(e)).collect::<Vec<_>>())
            };
            (
                g,
                EventSummary {
                    side: if events[members[0]].thrust {
                        "thrust"
                    } else {
                        "antithrust"
                    },
                    crank_angle_deg: pick(&|e| e.crank_angle_deg).value,
                    force_n: pick(&|e| e.force_n),
                    impact_velocity_m_s: pick(&|e| e.impact_velocity_m_s),
                    impact_energy_j: pick(&|e| e.impact_energy_j),
                    impulse_n_s: pick(&|e| e.impulse_n_s),
                    cycles: per_cycle.len(),
                },
            )
        })
        .collect();
    summaries.sort_by(|a, b| a.1.crank_angle_deg.total_cmp(&b.1.crank_angle_deg));
    let mut rank = vec![0; summaries.len()];
    for (new, (old, _)) in summaries.iter().enumerate() {
        rank[*old] = new;
    }
    (
        summaries.into_iter().map(|(_, s)| s).collect(),
        group.iter().map(|&g| rank[g]).collect(),
    )
}

/// The event a peak at `angle` (the cylinder's own crank angle) belongs to among one cycle's
/// `events`: the latest onset at or before it (within one cycle; None when the peak precedes
/// every onset).
pub(super) fn event_before(events: &[SlapEvent], angle: f64) -> Option<usize> {
    events
        .iter()
        .enumerate()
        .filter(|(_, e)| e.crank_angle_deg <= angle + 1e-9)
        .max_by(|a, b| a.1.crank_angle_deg.total_cmp(&b.1.crank_angle_deg))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(global: f64, ft: f64, fa: f64, side: f64) -> SideSample {
        SideSample {
            global_deg: global,
            own_deg: global % 720.0,
            forces: (ft, fa),
            side_force: side,
            rates: (0.3, 0.2),
            kinetic_energy: (0.5, 0.4),
            impulses: (0.01, 0.02),
        }
    }

    /// A thrust slap with a rebound inside the separation span is one event whose force is the
    /// largest dynamic force; contact again after the span is a new event; the anti-thrust
    /// side keeps its own events.
    #[test]
    fn regression_events_group_rebounds() {
        let mut r = EventRecorder::new(1);
        r.observe(0, &sample(365.0, 0.0, 0.0, 1000.0));
        r.observe(0, &sample(366.0, 5000.0, 0.0, 1000.0));
        r.observe(0, &sample(366.5, 9000.0, 0.0, 1000.0));
        r.observe(0, &sample(367.0, 0.0, 0.0, 1000.0));
        r.observe(0, &sample(368.0, 3000.0, 0.0, 1000.0)); // rebound
        r.observe(0, &sample(380.0, 2000.0, 0.0, 1000.0)); // a new event
        r.observe(0, &sample(381.0, 0.0, 4000.0, -1000.0)); // anti-thrust
        r.close();
        let e = &r.done[0];
        assert_eq!(e.len(), 3, "{e:?}");
        assert_eq!((e[0].crank_angle_deg, e[0].force_n), (366.0, 8000.0));
        assert_eq!(e[0].force_crank_angle_deg, 366.5);
        assert_eq!((e[1].crank_angle_deg, e[1].force_n), (380.0, 1000.0));
        assert!(!e[2].thrust);
        assert_eq!(e[2].force_n, 3000.0);
        let (groups, of) = summarise(e);
        assert_eq!(groups.len(), 3, "onsets 14 deg apart are two events");
        assert_eq!(groups[0].force_n.value, 8000.0);
        assert_eq!(of, vec![0, 1, 2]);
        assert_eq!(event_before(e, 370.0), Some(0));
        assert_eq!(event_before(e, 390.0), Some(2));
        assert_eq!(event_before(e, 300.0), None);
    }
}
