//! Where and when a transient failed.

/// Where and when the transient failed.
#[derive(Debug, thiserror::Error)]
pub enum TransientError {
    #[error("contact iteration did not converge at crank angle {crank_angle_deg:.2} deg (t = {time_s:.6} s) after {iterations} iterations even with the step halved {halvings} times{}", film_hint(.film.as_ref()))]
    NoConvergence {
        crank_angle_deg: f64,
        time_s: f64,
        iterations: usize,
        halvings: usize,
        /// A lubricated skirt's film (None: a dry skirt).
        film: Option<crate::piston::FilmSummary>,
    },
    #[error("deep penetration: cylinder {cylinder}, {side} side, slice {slice} (height {height_mm:.1} mm on the liner): {} um > {} um at crank angle {crank_angle_deg:.2} deg (t = {time_s:.6} s); the contact stiffness is too low for the load, or the step too large", crate::text::num(*.penetration_um), crate::text::num(*.limit_um))]
    DeepPenetration {
        cylinder: usize,
        side: &'static str,
        slice: usize,
        height_mm: f64,
        penetration_um: f64,
        limit_um: f64,
        crank_angle_deg: f64,
        time_s: f64,
    },
    #[error("the solution is not finite at crank angle {crank_angle_deg:.2} deg (t = {time_s:.6} s) in {place}: check the ROM and the scene's numbers (materials, masses, contact stiffness, pressure curve)")]
    NonFinite {
        crank_angle_deg: f64,
        time_s: f64,
        /// "the piston of cylinder 3", "the structure's modal coordinates", ...
        place: String,
    },
    #[error("energy growth: the structure gained {excess_j:.3e} J more than the contact forces put in (scale {scale_j:.3e} J) by crank angle {crank_angle_deg:.2} deg (t = {time_s:.6} s): the integration is unstable (scheme or step)")]
    EnergyGrowth {
        excess_j: f64,
        scale_j: f64,
        crank_angle_deg: f64,
        time_s: f64,
    },
    #[error("singular contact system at crank angle {crank_angle_deg:.2} deg (t = {time_s:.6} s)")]
    Singular { crank_angle_deg: f64, time_s: f64 },
    #[error(
        "the liner map of cylinder {cylinder} failed in cycle {cycle} (from rest, 0-based): {msg}"
    )]
    Maps {
        cylinder: usize,
        cycle: usize,
        msg: String,
    },
    #[error("the liner maps stopped: {0}")]
    MapsStopped(String),
}

/// What a lubricated run that stopped in its contact iteration tells the user: the oil film's
/// Newton iteration did not settle, with the film's inputs that such stops were measured to
/// follow (docs/validation.md, "Films that stop"): a starved supply
/// ([`crate::scene::spec::starved`]: 1-2 um on the test engine), a very viscous film (about
/// 1e5 mPa s and more: a cold start), and with `mixed` a fine roughness (0.1 um and less on
/// the test engine: the asperities far stiffer than the skirt's contact); and the way out.
fn film_hint(film: Option<&crate::piston::FilmSummary>) -> String {
    let Some(f) = film else {
        return String::new();
    };
    let num = crate::text::num;
    let roughness = f
        .roughness_um
        .map(|r| format!(", piston.oil.roughness_um = {}", num(r)))
        .unwrap_or_default();
    let (lo, hi) = f.viscosity_mpa_s;
    let inputs = format!(
        "piston.lubrication = \"{}\", piston.oil.supply_um = {}{roughness}, viscosity {}-{} mPa s over the skirt",
        f.model,
        num(f.supply_um),
        num(lo),
        num(hi)
    );
    if crate::scene::spec::starved(f.supply_um * 1e-6) {
        format!(
            "; the skirt's oil film did not settle ({inputs}): a starved film (a supply of a few um) is known to stop so (docs/validation.md, \"A starved film does not always run\"): a larger supply (3 um or more ran on the test and the default engine) or the dry skirt"
        )
    } else {
        format!(
            "; the skirt's oil film did not settle ({inputs}): films measured to stop so are starved (a supply below 3 um), very viscous (about 1e5 mPa s and more: a cold start) or, with \"mixed\", finely rough (0.1 um and less: asperities far stiffer than the skirt's contact) (docs/validation.md, \"Films that stop\"); or the dry skirt, the reference study's model"
        )
    }
}
