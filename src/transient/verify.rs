//! The ROM's transient verified against the full-order model (`simulate --full-order`): the ROM against the full-order FE model on a window around firing
//! TDC of one cylinder, with the same piston, contact, scheme and step (the cycle's slap
//! sub-step, [`window_step_deg`]).
//!
//! Both runs start from the preload state at rest with the piston centred at the window start,
//! only that cylinder's piston acts, and both use the same Rayleigh damping C = a M + b K (the
//! scene's damping ratio at the first system mode and at the band's upper edge; the ROM's modes
//! get zeta_j = a / (2 w_j) + b w_j / 2, which is the same damping in modal form). The point
//! accelerations of both are low-passed to the scene's band by the same zero-phase FIR
//! ([`super::signal::low_pass`]): the ROM is meant to be accurate in its band, and
//! the full model's content above the band (up to the mesh's limit) is not what either run
//! reports. The error is the largest relative difference of the peak negative acceleration
//! over the analysis points; the speed-up is the full-order wall time (assembly, factorisation
//! and stepping) over the ROM's window stepping on the cached ROM.

use super::cycle::{integrated_modes, CycleSettings, EngineRun, EngineSetup};
use super::error::TransientError;
use super::full_order::{FullLiner, Row};
use super::modal::ModalStructure;
use super::scheme::{ModalIntegrator, Scheme};
use super::signal::{low_pass, sampled_peak};
use super::window::{self, ModalLiner, Window, WindowResult};
use crate::linalg::dense::{from_rows, row, Dense};
use crate::piston::Piston;
use crate::reduce::full::FullSystem;
use crate::reduce::rom::RomError;
use crate::reduce::rom::{preload_loads, EngineRom, RomInputs};
use crate::reduce::scene_rom::SceneRomError;
use crate::reduce::scene_rom::{load_meshes, rom_inputs};
use crate::scene::Scene;
use crate::scene::SceneError;
use std::time::Instant;

/// Why the comparison could not be made.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    SceneRom(#[from] SceneRomError),
    #[error(transparent)]
    Rom(#[from] RomError),
    /// The ROM does not fit the liner mesh it is compared with (a stale cache?).
    #[error("{0}")]
    RomDoesNotFit(String),
    /// A factorisation of the full-order window failed (`what`: which matrix).
    #[error("{what}: {source}")]
    Factor {
        what: &'static str,
        source: crate::linalg::factor::FactorError,
    },
    /// An engine transient of the comparison failed (`what`: which one).
    #[error("{what}: {source}")]
    Transient {
        what: &'static str,
        source: TransientError,
    },
    /// A window run of the comparison failed: which window of which scene and cylinder.
    #[error("{}: {what} window, cylinder {cylinder}: {source}", scene.display())]
    Window {
        scene: std::path::PathBuf,
        what: String,
        cylinder: usize,
        source: Box<TransientError>,
    },
}

impl VerifyError {
    /// 2 for what the user can correct, 1 for a failed computation.
    pub fn exit_code(&self) -> i32 {
        match self {
            VerifyError::Scene(_) => 2,
            VerifyError::SceneRom(e) => e.exit_code(),
            VerifyError::Rom(e) => e.exit_code(),
            VerifyError::RomDoesNotFit(_)
            | VerifyError::Factor { .. }
            | VerifyError::Transient { .. }
            | VerifyError::Window { .. } => 1,
        }
    }
}

type Result<T> = std::result::Result<T, VerifyError>;

/// Window around firing TDC (360 deg) in the cylinder's own crank angle \[deg\]: from before the
/// piston crosses over at TDC to past the side-force peak.
pub const WINDOW_DEG: (f64, f64) = (330.0, 420.0);

/// One analysis point compared.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PointComparison {
    pub point: usize,
    pub peak_negative_full_m_s2: f64,
    pub peak_negative_rom_m_s2: f64,
    pub crank_angle_full_deg: f64,
    pub crank_angle_rom_deg: f64,
    pub relative_error: f64,
}

/// What the comparison found.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FullOrderReport {
    pub cylinder: usize,
    pub window_start_deg: f64,
    pub window_end_deg: f64,
    pub step_deg: f64,
    pub steps: usize,
    /// The scheme both models ran on the window (the scene's).
    pub scheme: Scheme,
    /// Upper edge of the band both series are low-passed to \[Hz\].
    pub filter_band_hz: f64,
    pub full_dofs: usize,
    pub rom_modes: usize,
    /// Rayleigh coefficients a [1/s] and b \[s\].
    pub rayleigh_a: f64,
    pub rayleigh_b: f64,
    pub points: Vec<PointComparison>,
    /// Largest relative error of the ROM's peak negative acceleration over the points.
    pub rom_error_peak_negative: f64,
    /// How far the window's step is from converged: the largest relative change of the ROM's
    /// peak negative acceleration over the points when its window is run again at half the
    /// step (the full model's, not run twice, is of the same order). Where it is not small
    /// against `rom_error_peak_negative`, the error mixes the two models' step errors into the
    /// structural difference.
    pub rom_step_change: f64,
    /// Largest contact-force difference relative to the full model's peak contact force.
    pub contact_force_error: f64,
    /// Largest difference of the preload displacement at the bore lines, relative to its
    /// largest magnitude.
    pub preload_error: f64,
    pub full_seconds: f64,
    pub full_stepping_seconds: f64,
    pub rom_seconds: f64,
    /// full_seconds / rom_seconds, and the stepping alone.
    pub speedup: f64,
    pub speedup_stepping: f64,
    /// The two runs' series (written by `simulate --full-order --out DIR`).
    #[serde(skip)]
    pub full_series: WindowResult,
    #[serde(skip)]
    pub rom_series: WindowResult,
    /// The window's step \[s\].
    #[serde(skip)]
    pub dt: f64,
}

/// The full model's rows of liner instance `inst`: its `nc` bore-line contact DOFs (thrust
/// +y, then anti-thrust -y; the ROM's count, else the cache is stale) and its `np` analysis
/// points (+y).
fn liner_rows(
    sys: &FullSystem,
    lm: &crate::mesh::Mesh,
    inst: usize,
    nc: usize,
    np: usize,
) -> Result<(Vec<Row>, Vec<Row>)> {
    let set = |name: &str| -> Result<Vec<usize>> {
        lm.node_set(name).map(|s| s.to_vec()).ok_or_else(|| {
            // the ROM was built from this mesh with these sets: a stale cache or a bug
            VerifyError::RomDoesNotFit(format!(
                "liner mesh: node set '{name}' is missing, though the ROM was built with it"
            ))
        })
    };
    let mut contact: Vec<Row> = Vec::with_capacity(nc);
    for (name, dir) in [
        ("bore_thrust", [0.0, 1.0, 0.0]),
        ("bore_antithrust", [0.0, -1.0, 0.0]),
    ] {
        for n in set(name)? {
            contact.push(sys.node_row(inst, n, dir));
        }
    }
    if contact.len() != nc {
        return Err(VerifyError::RomDoesNotFit(format!(
            "full-order window: {} bore-line DOFs in the mesh, {nc} in the ROM (stale cache?)",
            contact.len()
        )));
    }
    let mut points: Vec<Row> = Vec::new();
    for k in 1..=np {
        let n = set(&format!("point_{k}"))?[0];
        points.push(sys.node_row(inst, n, [0.0, 1.0, 0.0]));
    }
    Ok((contact, points))
}

/// The preload displacement at the contact rows: K u = f (liner clamps and bolt reactions)
/// solved on the full model.
fn full_preload(sys: &FullSystem, inp: &RomInputs<'_>, contact: &[Row]) -> Result<Vec<f64>> {
    let nl = inp.cylinders.len();
    let pre = preload_loads(inp).map_err(VerifyError::from)?;
    let mut f = vec![0.0; sys.dofs()];
    for i in 0..nl {
        sys.add_load(i, &pre.liner, &mut f);
    }
    for l in &pre.crankcase {
        sys.add_load(nl, l, &mut f);
    }
    let llt = sys
        .analysis
        .llt(&sys.km.pattern, &sys.km.k)
        .map_err(|source| VerifyError::Factor {
            what: "full-order preload",
            source,
        })?;
    llt.solve_vec(&mut f);
    Ok(contact
        .iter()
        .map(|r| r.iter().map(|&(k, v)| v * f[k]).sum())
        .collect())
}

/// The full-order and ROM windows side by side: per point the peak negative acceleration
/// (filtered at `band`) with its crank angle and relative error |P_rom - P_full| / |P_full|,
/// and the contact force's largest difference relative to the full model's largest force.
fn compare_windows(
    full_res: &WindowResult,
    rom_res: &WindowResult,
    dt: f64,
    band: f64,
) -> (Vec<PointComparison>, f64) {
    let peak = |res: &WindowResult, p: usize| peak_negative(res, p, dt, band);
    let cmp = (0..full_res.acceleration.nrows())
        .map(|p| {
            let (pf, af) = peak(full_res, p);
            let (pr, ar) = peak(rom_res, p);
            PointComparison {
                point: p + 1,
                peak_negative_full_m_s2: pf,
                peak_negative_rom_m_s2: pr,
                crank_angle_full_deg: af,
                crank_angle_rom_deg: ar,
                relative_error: (pr - pf).abs() / pf.abs().max(1e-30),
            }
        })
        .collect();
    let contact_force_error =
        scaled_difference(&full_res.contact_force_n, &rom_res.contact_force_n);
    (cmp, contact_force_error)
}

/// The largest difference of two series relative to the reference's largest magnitude,
/// max_i |a_i - b_i| / max_i |a_i| (`reference` a, `other` b).
fn scaled_difference(reference: &[f64], other: &[f64]) -> f64 {
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    reference
        .iter()
        .zip(other)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale.max(1e-30)
}

/// Runs the comparison on the scene's meshes.
pub fn compare(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    settings: &CycleSettings,
    progress: &dyn Fn(&str),
) -> Result<FullOrderReport> {
    progress("full-order window: ROM run");
    // the full-order model takes no onset impulses: both models run without the correction
    let settings = &CycleSettings {
        onset_correction: false,
        ..settings.clone()
    };
    let step_deg = window_step_deg(settings.step_deg, settings.slap_substeps);
    let rw = rom_window(scene, rom, piston, settings, None, Some(step_deg))?;
    let half = rom_window(scene, rom, piston, settings, None, Some(0.5 * step_deg))?;
    let rom_step_change = step_change(&rw, &half);
    let RomWindow {
        cylinder,
        index: idx,
        res: rom_res,
        win,
        dt,
        band,
        rayleigh: (ra, rb),
        preload: rom_preload,
        modes: nm,
    } = rw;
    let crom = &rom.cylinders[idx];
    let (nt, na) = (crom.thrust_z.len(), crom.antithrust_z.len());
    let nc = nt + na;
    let scheme = win.scheme;
    let fail = |source: TransientError, what: &str| VerifyError::Window {
        scene: scene.path.clone(),
        what: what.to_string(),
        cylinder,
        source: Box::new(source),
    };
    // --- full-order window
    let t_full = Instant::now();
    progress("full-order window: assembling the full model");
    crate::reduce::scene_rom::check_held(scene)?;
    let em = load_meshes(scene)?;
    let inp = rom_inputs(scene, &em, false);
    let sys = FullSystem::build(&inp)?;
    let inst = inp
        .cylinders
        .iter()
        .position(|&c| c == cylinder)
        .expect("ROM and scene model the same cylinders");
    let (contact, points) = liner_rows(&sys, &em.liner, inst, nc, crom.point_modes.nrows())?;
    progress("full-order window: preload (static solve)");
    let preload = full_preload(&sys, &inp, &contact)?;
    let preload_error = scaled_difference(&preload, &rom_preload);
    progress("full-order window: factorising the Newmark matrix");
    let mut full =
        FullLiner::new(&sys, contact, points, preload, scheme, dt, (ra, rb)).map_err(|source| {
            VerifyError::Factor {
                what: "full-order Newmark matrix",
                source,
            }
        })?;
    progress("full-order window: stepping");
    let full_res = window::run(&win, piston, &mut full).map_err(|e| fail(e, "full-order"))?;
    let full_seconds = t_full.elapsed().as_secs_f64();
    // --- compare
    let (cmp, contact_force_error) = compare_windows(&full_res, &rom_res, dt, band);
    Ok(FullOrderReport {
        cylinder,
        window_start_deg: win.start_deg,
        window_end_deg: win.end_deg,
        step_deg: win.step_deg,
        steps: full_res.crank_angle_deg.len(),
        scheme,
        filter_band_hz: band,
        full_dofs: sys.dofs(),
        rom_modes: nm,
        rayleigh_a: ra,
        rayleigh_b: rb,
        rom_error_peak_negative: cmp
            .iter()
            .map(|c: &PointComparison| c.relative_error)
            .fold(0.0, f64::max),
        rom_step_change,
        points: cmp,
        contact_force_error,
        preload_error,
        full_seconds,
        full_stepping_seconds: full_res.seconds,
        rom_seconds: rom_res.seconds,
        speedup: full_seconds / rom_res.seconds.max(1e-9),
        speedup_stepping: full_res.seconds / rom_res.seconds.max(1e-9),
        full_series: full_res,
        rom_series: rom_res,
        dt,
    })
}

/// The window's step \[deg\]: the cycle's slap sub-step, `step_deg / slap_substeps` (1/12 deg on
/// the default engine), uniform over the window in both models. The comparison is meant to
/// measure the structural models, and at the base step their step errors differ: the full
/// model's wall carries every mode, the ROM's its system modes and the static part of the rest,
/// and the slap excites the modes above the cut-off at omega h > 1, where the average
/// acceleration rule's period error is large (the default engine at its 1/4 deg: 1.58 %, at
/// 1/12 deg 0.58 %, at 1/16 deg 0.95 %, the full model's peaks within 0.3 % between the last
/// two; docs/physics.md). `transient.slap_substeps = 1` runs the window at the base step.
pub fn window_step_deg(step_deg: f64, slap_substeps: usize) -> f64 {
    step_deg / slap_substeps.max(1) as f64
}

/// The full-order window's stepping on `dofs` DOFs at `step_deg` \[s\]: one solve with
/// K_eff's factor per step, (`WINDOW_DEG` span / step) steps at 0.38 s per step on the
/// default engine's 351,522 DOFs (2-core machine: 412 s for the 1080 steps at 1/12 deg),
/// scaled as the factor's entries, (dofs / 351,522)^(4/3).
pub fn window_stepping_seconds(dofs: f64, step_deg: f64) -> f64 {
    let steps = (WINDOW_DEG.1 - WINDOW_DEG.0) / step_deg;
    steps * 0.38 * (dofs / 351_522.0).powf(4.0 / 3.0)
}

/// The largest relative change of the points' peak negative acceleration from the ROM's
/// window `at` to the same window at half its step `half`, max_p |P_p - P_p,half| / |P_p,half|.
fn step_change(at: &RomWindow, half: &RomWindow) -> f64 {
    let peaks = |w: &RomWindow| -> Vec<f64> {
        (0..w.res.acceleration.nrows())
            .map(|p| peak_negative(&w.res, p, w.dt, w.band).0)
            .collect()
    };
    largest_relative(peaks(at).iter().zip(&peaks(half)))
}

/// Peak negative acceleration (magnitude) of point `p` of a window run after the band's
/// low-pass, located between the samples ([`sampled_peak`]), and its crank angle; the
/// filter's edge samples are skipped.
pub fn peak_negative(res: &WindowResult, p: usize, dt: f64, band: f64) -> (f64, f64) {
    let (y, edge) = low_pass(row(&res.acceleration, p), dt, band, false);
    let n = y.len();
    match sampled_peak(&y, edge.min(n)..n.saturating_sub(edge), -1.0) {
        Some((value, at)) => {
            let k = at.floor() as usize;
            let next = res.crank_angle_deg.get(k + 1).copied();
            let angle = res.crank_angle_deg[k]
                + (at - k as f64) * next.map_or(0.0, |a| a - res.crank_angle_deg[k]);
            (value, angle)
        }
        None => (f64::NEG_INFINITY, 0.0),
    }
}

/// The ROM's run on the window of the first modelled cylinder in the firing order.
pub struct RomWindow {
    pub cylinder: usize,
    /// Index of the cylinder in the ROM.
    pub index: usize,
    pub res: WindowResult,
    pub win: Window,
    pub dt: f64,
    pub band: f64,
    pub rayleigh: (f64, f64),
    /// Preload displacement at the contact DOFs.
    pub preload: Vec<f64>,
    /// Modes integrated.
    pub modes: usize,
}

/// Cylinder index `idx`'s liner from the ROM with its first `nm` system modes (Rayleigh
/// damping `rayleigh`): the dropped modes join the static correction,
/// R += phi phi^T / omega^2 (contact x contact and points x contact), as the cycle does for
/// `mode_cutoff_hz`. Also returns the preload displacement at the contact DOFs.
fn truncated_liner(
    rom: &EngineRom,
    idx: usize,
    nm: usize,
    (ra, rb): (f64, f64),
    scheme: Scheme,
) -> (ModalLiner, Vec<f64>) {
    let crom = &rom.cylinders[idx];
    let two_pi = 2.0 * std::f64::consts::PI;
    let all = rom.frequencies_hz.len();
    let w: Vec<f64> = rom.frequencies_hz[..nm]
        .iter()
        .map(|f| two_pi * f)
        .collect();
    let zeta: Vec<f64> = w.iter().map(|w| ra / (2.0 * w) + rb * w / 2.0).collect();
    let (nt, na) = (crom.thrust_z.len(), crom.antithrust_z.len());
    let nc = nt + na;
    let mut data = Vec::with_capacity(nc * nm);
    for i in 0..nt {
        data.extend_from_slice(&row(&crom.thrust_modes, i)[..nm]);
    }
    for i in 0..na {
        data.extend_from_slice(&row(&crom.antithrust_modes, i)[..nm]);
    }
    let rows = from_rows(nc, nm, data);
    let r = &rom.residual_flexibility;
    let off = crom.contact_offset;
    let np = crom.point_modes.nrows();
    let points = Dense::from_shape_fn((np, nm), |(i, j)| crom.point_modes[[i, j]]);
    // dropped modes join the static correction: R += phi phi^T / w^2 (contact x contact and
    // points x contact), as the cycle does for `mode_cutoff_hz`
    let every_contact_mode = Dense::from_shape_fn((nc, all), |(a, j)| crom.contact_mode(a, j));
    let dropped = crom.static_part(&every_contact_mode, &rom.frequencies_hz, nm);
    let rflex = Dense::from_shape_fn((nc, nc), |(a, b)| r[[off + a, off + b]] + dropped[[a, b]]);
    let point_residual =
        &crom.point_residual + &crom.static_part(&crom.point_modes, &rom.frequencies_hz, nm);
    let rom_preload: Vec<f64> = crom
        .preload_thrust
        .iter()
        .chain(&crom.preload_antithrust)
        .copied()
        .collect();
    let mut integrator = ModalIntegrator::new(&w, &zeta, scheme);
    integrator.dynamic_modes = rom.info.system_modes.min(w.len());
    let modal = ModalLiner {
        structure: ModalStructure::new(integrator, rows, rflex, rom_preload.clone()),
        points,
        point_residual: Some(point_residual),
    };
    (modal, rom_preload)
}

/// Runs the ROM alone on the window with the scene's scheme (HHT-alpha included): system modes
/// up to `keep_below_hz` (when None: those the cycle integrates, `transient.mode_cutoff_hz`
/// and `transient.residual_vectors`; the dropped ones join the static correction) at
/// `step_deg` (the scene's when None).
pub fn rom_window(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    settings: &CycleSettings,
    keep_below_hz: Option<f64>,
    step_deg: Option<f64>,
) -> Result<RomWindow> {
    let cylinder = scene
        .engine
        .firing_order
        .iter()
        .copied()
        .find(|c| rom.cylinders.iter().any(|r| r.cylinder == *c))
        .ok_or_else(|| crate::scene::SceneError::Field {
            path: scene.path.clone(),
            key: "rom.cylinders".into(),
            msg: "none of the modelled cylinders is in engine.firing_order: the full-order window needs one".into(),
        })?;
    let idx = rom
        .cylinders
        .iter()
        .position(|r| r.cylinder == cylinder)
        .expect("found above");
    let crom = &rom.cylinders[idx];
    let scheme = settings.scheme;
    let omega = piston.kinematics.omega;
    let step_deg = step_deg.unwrap_or(settings.step_deg);
    let dt = step_deg.to_radians() / omega;
    let band = rom.info.band_hz;
    let two_pi = 2.0 * std::f64::consts::PI;
    let (ra, rb) = window::rayleigh(
        settings.damping_ratio,
        two_pi * rom.frequencies_hz[0],
        two_pi * band,
    );
    let win = Window {
        start_deg: WINDOW_DEG.0,
        end_deg: WINDOW_DEG.1,
        step_deg,
        omega,
        scheme,
        liner_top: scene.liner_geometry.length,
        thrust_z: crom.thrust_z.clone(),
        antithrust_z: crom.antithrust_z.clone(),
        max_newton: settings.max_newton,
        max_penetration: settings.max_penetration,
        onset_correction: settings.onset_correction,
    };
    let fail = |source: TransientError, what: &str| VerifyError::Window {
        scene: scene.path.clone(),
        what: what.to_string(),
        cylinder,
        source: Box::new(source),
    };
    // --- ROM window
    let nm = match keep_below_hz {
        Some(f) => rom
            .frequencies_hz
            .iter()
            .take_while(|&&x| x <= f)
            .count()
            .max(1),
        None => integrated_modes(rom, settings),
    };
    let (mut modal, rom_preload) = truncated_liner(rom, idx, nm, (ra, rb), scheme);
    let res = window::run(&win, piston, &mut modal).map_err(|e| fail(e, "ROM"))?;
    Ok(RomWindow {
        cylinder,
        index: idx,
        res,
        win,
        dt,
        band,
        rayleigh: (ra, rb),
        preload: rom_preload,
        modes: nm,
    })
}

/// What a point of the speed-against-error curve varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TradeoffKind {
    /// The ROM's mode cut-off, on the single-cylinder window from rest.
    ModeCutoff,
    /// The step with the scene's slap sub-steps, on the engine's firing slaps.
    Step,
    /// A uniform step (no slap sub-steps), on the engine's firing slaps.
    UniformStep,
}

/// One point of the speed-against-error curve.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TradeoffPoint {
    pub setting: String,
    pub kind: TradeoffKind,
    pub modes: usize,
    pub step_deg: f64,
    /// Largest relative error against the converged reference (a step 64 times finer than
    /// the scene's, all modes): over the window's points for a mode cut-off, over the
    /// cylinders' worst points (the reference's) for a step.
    pub error: f64,
    /// Wall time of the stepping: the window, or all cylinders' windows \[s\].
    pub seconds: f64,
}

/// Multiples of the scene's step on the speed-against-error curve.
pub const TRADEOFF_STEPS: [f64; 4] = [4.0, 2.0, 1.0, 0.5];
/// The converged reference's step: the scene's divided by this, uniform.
pub const REFERENCE_DIVISOR: f64 = 64.0;
/// The cycle (0-based, from rest) whose firing slaps the step points are measured on: past
/// the start-up cycle.
pub const TRADEOFF_CYCLE: usize = 2;

/// Speed against error: the ROM's mode cut-off on the single-cylinder window from rest
/// ([`rom_window`]), and the step, with the scene's slap sub-steps and uniform, on every
/// cylinder's firing slap of the engine ([`engine_steps`]); each against a reference at a step
/// [`REFERENCE_DIVISOR`] times finer with all modes.
pub fn tradeoff(
    scene: &Scene,
    rom: &EngineRom,
    piston: &Piston,
    settings: &CycleSettings,
) -> Result<Vec<TradeoffPoint>> {
    let base = settings.step_deg;
    let run = |keep: Option<f64>, step: f64| -> Result<(Vec<f64>, usize, f64)> {
        let rw = rom_window(scene, rom, piston, settings, keep, Some(step))?;
        let peaks = (0..rw.res.acceleration.nrows())
            .map(|p| peak_negative(&rw.res, p, rw.dt, rw.band).0)
            .collect();
        Ok((peaks, rw.modes, rw.res.seconds))
    };
    // the window is one piston from rest, deterministic; the truncated-mode rows at 1/8 of
    // the step, where the step's own error is small against the truncation's
    let (reference, _, _) = run(None, base / REFERENCE_DIVISOR)?;
    let fine = base / 8.0;
    let mut out = Vec::new();
    let band = scene.rom.band_hz;
    for f in [band, 1.5 * band, 2.0 * band] {
        let (p, m, s) = run(Some(f), fine)?;
        out.push(TradeoffPoint {
            setting: format!("modes <= {f:.0} Hz, step {fine} deg"),
            kind: TradeoffKind::ModeCutoff,
            modes: m,
            step_deg: fine,
            error: largest_relative(p.iter().zip(&reference)),
            seconds: s,
        });
    }
    let setup = super::engine::setup_of(scene, rom, piston);
    out.extend(engine_steps(&setup, settings)?);
    Ok(out)
}

/// max_i |a_i - b_i| / |b_i| over pairs (value, reference).
fn largest_relative<'x>(pairs: impl Iterator<Item = (&'x f64, &'x f64)>) -> f64 {
    pairs
        .map(|(a, b)| (a - b).abs() / b.abs().max(1e-30))
        .fold(0.0, f64::max)
}

/// The step's error and cost on the engine's firing slaps: from the states of a run at the
/// scene's settings where each cylinder's firing-slap window begins in cycle
/// [`TRADEOFF_CYCLE`] ([`EngineRun::slap_window_states`]), the windows are run at the steps
/// [`TRADEOFF_STEPS`] x h with the scene's slap sub-steps and uniformly, and at h /
/// [`REFERENCE_DIVISOR`] uniformly (the converged reference). The error of a setting is the
/// largest over the cylinders of |P - P_ref| / P_ref at each cylinder's worst point (the
/// reference's), the cost the wall time of all windows. The windows start from identical
/// states, so the comparison carries no cycle-to-cycle scatter.
pub fn engine_steps(setup: &EngineSetup, settings: &CycleSettings) -> Result<Vec<TradeoffPoint>> {
    let fail = |source: TransientError| VerifyError::Transient {
        what: "speed against error, the engine's firing slaps",
        source,
    };
    let run = EngineRun::new(
        setup,
        CycleSettings {
            tolerance: None,
            step_error: false,
            ..settings.clone()
        },
    );
    let h = run.base_dt();
    let (states, steps) = run.slap_window_states(TRADEOFF_CYCLE).map_err(fail)?;
    let peaks = |substeps: usize, factor: f64| -> Result<(Vec<Vec<f64>>, f64)> {
        let t0 = Instant::now();
        let n = ((steps as f64 / factor).round() as usize).max(1);
        let p = states
            .iter()
            .map(|(c, s)| {
                s.clone()
                    .with_slap_substeps(substeps)
                    .window_peaks(*c, n, h * factor)
            })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(fail)?;
        Ok((p, t0.elapsed().as_secs_f64()))
    };
    let (reference, _) = peaks(1, 1.0 / REFERENCE_DIVISOR)?;
    let worst: Vec<usize> = reference
        .iter()
        .map(|r| {
            (0..r.len())
                .max_by(|&a, &b| r[a].total_cmp(&r[b]))
                .unwrap_or(0)
        })
        .collect();
    let m = settings.slap_substeps.max(1);
    let modes = states.first().map_or(0, |(_, s)| s.stats.modes);
    let mut out = Vec::new();
    for (kind, substeps) in [(TradeoffKind::Step, m), (TradeoffKind::UniformStep, 1)] {
        if kind == TradeoffKind::Step && m == 1 {
            continue;
        }
        for k in TRADEOFF_STEPS {
            let (p, seconds) = peaks(substeps, k)?;
            let step = settings.step_deg * k;
            let error = largest_relative(
                worst
                    .iter()
                    .enumerate()
                    .map(|(c, &w)| (&p[c][w], &reference[c][w])),
            );
            out.push(TradeoffPoint {
                setting: match kind {
                    TradeoffKind::Step => format!("step {step} deg, {m} slap sub-steps"),
                    _ => format!("step {step} deg, uniform"),
                },
                kind,
                modes,
                step_deg: step,
                error,
                seconds,
            });
        }
    }
    Ok(out)
}
