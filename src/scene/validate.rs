//! The validators: each `[section]` of the raw scene checked and turned into its SI model,
//! every refusal naming its key and what was expected.

#[allow(unused_imports)]
use super::*;

pub(super) fn validate(path: &Path, raw: RawScene) -> Result<Scene, SceneError> {
    let c = Checker { path };
    let engine = validate_engine(&c, &raw.engine)?;
    for (name, m) in &raw.materials {
        let el = Elastic {
            young: m.youngs_pa,
            poisson: m.poisson,
            density: m.density_kg_m3,
        };
        el.validate()
            .map_err(|e| c.err(&format!("materials.{name}"), e.to_string()))?;
    }
    let material = |key: &str, name: &str| -> Result<Elastic, SceneError> {
        let m = raw.materials.get(name).ok_or_else(|| {
            c.err(
                key,
                format!(
                    "unknown material '{name}'; [materials] defines: {}",
                    raw.materials.keys().cloned().collect::<Vec<_>>().join(", ")
                ),
            )
        })?;
        Ok(Elastic {
            young: m.youngs_pa,
            poisson: m.poisson,
            density: m.density_kg_m3,
        })
    };
    let l = &raw.liner;
    let geometry = validate_liner_geometry(&c, l, &engine)?;
    let meshing = validate_liner_meshing(&c, l)?;
    let base = scene_base(path);
    let base = base.as_path();
    let liner_geometry = geometry.clone();
    let source = match &l.mesh_file {
        Some(f) => MeshSource::File(mesh_file(&c, "liner.mesh_file", base, f)?),
        None => MeshSource::Liner { geometry, meshing },
    };
    let liner = Part {
        name: "liner".into(),
        material: part_material(&c, "liner", &l.material, &source, &material)?,
        mesh_unit: mesh_unit(&c, "liner.mesh_unit", &l.mesh_unit, l.mesh_file.is_some())?,
        box_sets: box_sets(&c, "liner.sets", &l.sets)?,
        source,
        fix: l.fix.clone(),
    };
    let solver = Solver {
        shift_hz: c.positive("solver.shift_hz", raw.solver.shift_hz)?,
        guard_modes: check_guard_modes(&c, raw.solver.guard_modes)?,
    };
    let crankcase = match &raw.crankcase {
        None => None,
        Some(cc) => Some(validate_crankcase(
            &c,
            base,
            cc,
            &engine,
            &liner_geometry,
            &material,
        )?),
    };
    let (mut liner, mut liner_geometry) = (liner, liner_geometry);
    if let Some(Crankcase {
        source: CrankcaseSource::Parametric { geometry: deck, .. },
        ..
    }) = &crankcase
    {
        // the liner's upper pilot: inside the deck bore, from the deck's underside up
        let underside = Some(deck.seat_z - deck.deck_thickness);
        liner_geometry.deck_underside = underside;
        if let MeshSource::Liner { geometry, .. } = &mut liner.source {
            geometry.deck_underside = underside;
        }
    }
    let rom = validate_rom(&c, &raw.rom, base, &engine, &liner)?;
    let simulation = validate_simulation(&c, base, &raw, &engine, &liner_geometry)?;
    let cavitation = validate_cavitation(&c, base, &raw.cavitation)?;
    let report = validate_report(&c, &raw, simulation.is_some())?;
    Ok(Scene {
        path: path.to_path_buf(),
        title: raw.title,
        engine,
        liner,
        liner_geometry,
        crankcase,
        solver,
        rom,
        simulation,
        cavitation,
        limits: validate_limits(&c, &raw.limits)?,
        report,
        warnings: Vec::new(),
    })
}

/// `[engine]`: cylinders, firing order (a permutation), crank train.
pub(super) fn validate_engine(c: &Checker<'_>, e: &raw::RawEngine) -> Result<Engine, SceneError> {
    if e.cylinders == 0 {
        return Err(c.err("engine.cylinders", "must be at least 1"));
    }
    // the count is compared first: 1..=cylinders is never listed for a huge count
    let mut fo = e.firing_order.clone();
    fo.sort_unstable();
    if fo.len() != e.cylinders || fo.iter().enumerate().any(|(i, &k)| k != i + 1) {
        return Err(c.err(
            "engine.firing_order",
            format!(
                "must be a permutation of 1..={}, got {:?}",
                e.cylinders, e.firing_order
            ),
        ));
    }
    let engine = Engine {
        cylinders: e.cylinders,
        firing_order: e.firing_order.clone(),
        bore: c.mm("engine.bore_mm", e.bore_mm)?,
        stroke: c.mm("engine.stroke_mm", e.stroke_mm)?,
        rod_length: c.mm("engine.rod_length_mm", e.rod_length_mm)?,
        cylinder_pitch: c.mm("engine.cylinder_pitch_mm", e.cylinder_pitch_mm)?,
        speed_rpm: c.positive("engine.speed_rpm", e.speed_rpm)?,
    };
    // a bore in mm: 0.115 (a bore typed in metres) was blamed on liner.inner_diameter_mm
    c.within("engine.bore_mm", e.bore_mm, BORE_MM)?;
    // no engine runs below its cranking speed (1 rpm was blamed on transient.step_deg, whose
    // fixed angle step is then 42 ms long)
    if engine.speed_rpm < MIN_SPEED_RPM {
        return Err(c.err(
            "engine.speed_rpm",
            format!(
                "{} rpm is below any engine's running speed (at least {} rpm; slow marine engines idle near 60)",
                num(engine.speed_rpm),
                num(MIN_SPEED_RPM)
            ),
        ));
    }
    // reciprocating engines run below ~10,000 rpm; far above, the step check would blame the
    // step for what is a mistyped speed
    if engine.speed_rpm > 1e5 {
        return Err(c.err(
            "engine.speed_rpm",
            format!(
                "{} rpm is no engine speed (at most 1e5)",
                num(engine.speed_rpm)
            ),
        ));
    }
    // the mean piston speed 2 s n / 60: heavy-duty diesels run at 8-12 m/s and racing engines
    // peak near 25 m/s; at 50,000 rpm the test engine ran into "deep penetration" (exit 1)
    let mean_piston_speed = 2.0 * engine.stroke * engine.speed_rpm / 60.0;
    if mean_piston_speed > MAX_MEAN_PISTON_SPEED {
        return Err(c.err(
            "engine.speed_rpm",
            format!(
                "{} rpm gives a mean piston speed of {} m/s with a {} mm stroke, beyond any piston engine (at most {} m/s)",
                num(engine.speed_rpm),
                num(mean_piston_speed),
                num(engine.stroke * 1e3),
                num(MAX_MEAN_PISTON_SPEED)
            ),
        ));
    }
    if engine.rod_length <= engine.stroke / 2.0 {
        return Err(c.err(
            "engine.rod_length_mm",
            "must exceed half the stroke (crank radius), or the crank cannot turn",
        ));
    }
    // engines' rods are 1.3-2 strokes long; at 1e9 mm the rod stood still and every peak was 0
    if engine.rod_length > 10.0 * engine.stroke {
        return Err(c.err(
            "engine.rod_length_mm",
            "must be at most 10 strokes (engines' rods are 1.3-2 strokes long)",
        ));
    }
    Ok(engine)
}

/// `[liner]` geometry: diameters, flange, guide band, analysis points in the coolant zone.
pub(super) fn validate_liner_geometry(
    c: &Checker<'_>,
    l: &raw::RawLiner,
    engine: &Engine,
) -> Result<LinerGeometry, SceneError> {
    check_analysis_points(c, l)?;
    let mut geometry = LinerGeometry {
        outer_diameter: c.mm("liner.outer_diameter_mm", l.outer_diameter_mm)?,
        inner_diameter: c.mm("liner.inner_diameter_mm", l.inner_diameter_mm)?,
        length: c.mm("liner.length_mm", l.length_mm)?,
        flange_outer_diameter: c
            .mm("liner.flange_outer_diameter_mm", l.flange_outer_diameter_mm)?,
        flange_height: c.mm("liner.flange_height_mm", l.flange_height_mm)?,
        guide_height: c.mm("liner.guide_height_mm", l.guide_height_mm)?,
        guide_bottom: 0.0,
        analysis_depths: (0..l.analysis_points)
            .map(|i| (l.analysis_first_depth_mm + i as f64 * l.analysis_spacing_mm) * 1e-3)
            .collect(),
        pilot_diameter: 0.0,
        deck_underside: None,
    };
    geometry.pilot_diameter = match l.pilot_diameter_mm {
        Some(d) => c.mm("liner.pilot_diameter_mm", d)?,
        None => geometry.outer_diameter,
    };
    if geometry.inner_diameter >= geometry.outer_diameter {
        return Err(c.err(
            "liner.inner_diameter_mm",
            "must be smaller than outer_diameter_mm",
        ));
    }
    if (geometry.inner_diameter - engine.bore).abs() > 1e-9 {
        return Err(c.err(
            "liner.inner_diameter_mm",
            format!("must equal engine.bore_mm ({} mm)", num(engine.bore * 1e3)),
        ));
    }
    let plain = geometry.pilot_diameter == geometry.outer_diameter;
    if geometry.pilot_diameter <= geometry.inner_diameter
        || (!plain && geometry.pilot_diameter >= geometry.flange_outer_diameter)
    {
        return Err(c.err(
            "liner.pilot_diameter_mm",
            "must lie between inner_diameter_mm and flange_outer_diameter_mm",
        ));
    }
    if geometry.flange_outer_diameter < geometry.outer_diameter {
        return Err(c.err(
            "liner.flange_outer_diameter_mm",
            "must be at least outer_diameter_mm",
        ));
    }
    if engine.cylinder_pitch <= geometry.flange_outer_diameter {
        return Err(c.err(
            "engine.cylinder_pitch_mm",
            "must exceed the liner flange diameter (liners would overlap)",
        ));
    }
    if geometry.flange_height + geometry.guide_height >= geometry.length {
        return Err(c.err(
            "liner.guide_height_mm",
            "flange and guide band together must be shorter than the liner",
        ));
    }
    if let Some(depth_mm) = l.guide_depth_mm {
        let depth = c.mm("liner.guide_depth_mm", depth_mm)?;
        let bottom = geometry.length - depth - geometry.guide_height;
        if depth <= geometry.flange_height || bottom < -1e-9 {
            return Err(c.err(
                "liner.guide_depth_mm",
                format!(
                    "the guide band must lie below the flange and within the liner: depth in ({}, {}] mm",
                    l.flange_height_mm,
                    l.length_mm - l.guide_height_mm
                ),
            ));
        }
        geometry.guide_bottom = bottom.max(0.0);
    }
    c.positive("liner.analysis_spacing_mm", l.analysis_spacing_mm)?;
    c.positive("liner.analysis_first_depth_mm", l.analysis_first_depth_mm)?;
    if l.analysis_points == 0 {
        return Err(c.err("liner.analysis_points", "must be at least 1"));
    }
    let deepest = geometry.analysis_depths.last().copied().unwrap_or(0.0);
    if geometry.analysis_depths[0] <= geometry.flange_height
        || deepest >= geometry.length - geometry.guide_bottom - geometry.guide_height
    {
        return Err(c.err(
            "liner.analysis_first_depth_mm",
            "analysis points must lie in the coolant zone, between the flange and the lower guide band",
        ));
    }
    Ok(geometry)
}

/// `[liner.mesh]`: element kind and divisions of the generated liner.
pub(super) fn validate_liner_meshing(
    c: &Checker<'_>,
    l: &raw::RawLiner,
) -> Result<LinerMeshing, SceneError> {
    let mesh = &l.mesh;
    let kind = match mesh.element.as_str() {
        "hex20" => ElementKind::Hex20,
        "tet10" => ElementKind::Tet10,
        "hex8" => ElementKind::Hex8,
        "tet4" => ElementKind::Tet4,
        other => {
            return Err(c.err(
                "liner.mesh.element",
                format!("expected \"hex20\", \"tet10\", \"hex8\" or \"tet4\", got \"{other}\""),
            ))
        }
    };
    if mesh.circumferential < 8 || mesh.circumferential % 4 != 0 {
        return Err(c.err(
            "liner.mesh.circumferential",
            "must be a multiple of 4 and at least 8 (thrust and anti-thrust lines fall on nodes)",
        ));
    }
    if mesh.radial == 0 || mesh.radial_flange == 0 {
        return Err(c.err("liner.mesh.radial", "must be at least 1"));
    }
    let meshing = LinerMeshing {
        kind,
        circumferential: mesh.circumferential,
        radial: mesh.radial,
        radial_flange: mesh.radial_flange,
        axial_size: c.mm("liner.mesh.axial_size_mm", mesh.axial_size_mm)?,
    };
    Ok(meshing)
}

/// The largest `rom.cutoff_factor` (and `rom-tradeoff --factors`): modes far above the band
/// only cost.
pub const CUTOFF_FACTOR_MAX: f64 = 10.0;

/// `[rom]`: band, cut-off, interface harmonics (resolved by the liner ring), cylinders, cache.
/// The crankcase's substructuring keys (`rom.crankcase_components`, `rom.cut_shapes`,
/// `rom.component_cutoff_factor`, `rom.cut_enrichment`); returns the components' cut-off factor.
fn validate_split(c: &Checker<'_>, r: &raw::RawRom, engine: &Engine) -> Result<f64, SceneError> {
    if r.crankcase_components == 0 || r.crankcase_components > engine.cylinders {
        return Err(c.err(
            "rom.crankcase_components",
            format!(
                "must be 1..={} (the crankcase is cut midway between bores), got {}",
                engine.cylinders, r.crankcase_components
            ),
        ));
    }
    if r.cut_shapes < 6 {
        return Err(c.err(
            "rom.cut_shapes",
            format!(
                "must be at least 6 (a cut's six rigid motions), got {}; 20 or more for results within about 1 % (docs/physics.md)",
                r.cut_shapes
            ),
        ));
    }
    let f = r.component_cutoff_factor;
    if !(1.0..=4.0).contains(&f) {
        return Err(c.err(
            "rom.component_cutoff_factor",
            format!("must be in [1, 4], got {}", crate::text::exact(f)),
        ));
    }
    if r.cut_enrichment > MAX_CUT_ENRICHMENT {
        return Err(c.err(
            "rom.cut_enrichment",
            format!(
                "must be 0..={MAX_CUT_ENRICHMENT} (shapes added per cut; 0: none), got {}",
                r.cut_enrichment
            ),
        ));
    }
    Ok(f)
}

pub(super) fn validate_rom(
    c: &Checker<'_>,
    r: &raw::RawRom,
    base: &Path,
    engine: &Engine,
    liner: &Part,
) -> Result<Rom, SceneError> {
    let band_hz = c.positive("rom.band_hz", r.band_hz)?;
    bounded(
        c,
        "rom.band_hz",
        band_hz,
        MAX_BAND_HZ,
        "cavitation is judged on responses up to some 10 kHz",
    )?;
    if !(r.cutoff_factor.is_finite() && (1.0..=CUTOFF_FACTOR_MAX).contains(&r.cutoff_factor)) {
        return Err(c.err(
            "rom.cutoff_factor",
            format!(
                "must lie in [1, {CUTOFF_FACTOR_MAX}] (modes far above the band only cost), got {}",
                crate::text::exact(r.cutoff_factor)
            ),
        ));
    }
    if r.interface_harmonics == 0 {
        return Err(c.err(
            "rom.interface_harmonics",
            "must be at least 1 (rigid liner motion needs n = 1)",
        ));
    }
    // a ring of n_c elements carries harmonics up to about n_c before they alias; the
    // ovalling shapes that couple liner and crankcase are n <= 6
    let ring = match &liner.source {
        MeshSource::Liner { meshing, .. } => meshing.circumferential,
        MeshSource::File(_) => MAX_HARMONICS,
    };
    if r.interface_harmonics > ring.min(MAX_HARMONICS) {
        return Err(c.err(
            "rom.interface_harmonics",
            format!(
                "must be at most {} (the liner ring has {ring} elements; harmonics beyond it alias), got {}",
                ring.min(MAX_HARMONICS),
                r.interface_harmonics
            ),
        ));
    }
    let mut cylinders = if r.cylinders.is_empty() {
        (1..=engine.cylinders).collect()
    } else {
        r.cylinders.clone()
    };
    cylinders.sort_unstable();
    if let Some(w) = cylinders.windows(2).find(|w| w[0] == w[1]) {
        return Err(c.err(
            "rom.cylinders",
            format!("cylinder {} is given twice: give each once", w[0]),
        ));
    }
    if let Some(&bad) = cylinders.iter().find(|&&k| k == 0 || k > engine.cylinders) {
        return Err(c.err(
            "rom.cylinders",
            format!("cylinder {bad} does not exist (1..={})", engine.cylinders),
        ));
    }
    let f = validate_split(c, r, engine)?;
    let rom = Rom {
        band_hz,
        cutoff_hz: band_hz * r.cutoff_factor,
        harmonics: r.interface_harmonics,
        residual_vector_spacing: r.residual_vector_spacing,
        crankcase_components: r.crankcase_components,
        cut_shapes: r.cut_shapes,
        component_cutoff_factor: f,
        cut_enrichment: r.cut_enrichment,
        cylinders,
        cache_dir: base.join(path_value(
            c,
            "rom.cache_dir",
            &r.cache_dir,
            "the default .linercav-cache",
        )?),
    };
    Ok(rom)
}

pub(super) fn validate_limits(c: &Checker<'_>, l: &raw::RawLimits) -> Result<Limits, SceneError> {
    if let Some(gb) = l.max_memory_gb {
        c.positive("limits.max_memory_gb", gb)?;
    }
    if let Some(h) = l.max_hours {
        c.positive("limits.max_hours", h)?;
    }
    Ok(Limits {
        max_memory_gb: l.max_memory_gb,
        max_hours: l.max_hours,
    })
}

/// `[report]`: a skirt model to compare against needs the transient's sections (that it
/// differs from the scene's own is checked by `report`, since the comparison's own runs are
/// the scene with `piston.lubrication` set to it).
fn validate_report(
    c: &Checker<'_>,
    raw: &raw::RawScene,
    simulated: bool,
) -> Result<ReportSpec, SceneError> {
    let Some(other) = raw.report.compare_lubrication else {
        return Ok(ReportSpec::default());
    };
    let Some(piston) = raw.piston.as_ref().filter(|_| simulated) else {
        return Err(c.err(
            "report.compare_lubrication",
            "compares two transients: the scene needs [piston], [operating] and [transient]",
        ));
    };
    // the other model's film data (`[piston.oil]`) are checked now, not after the scene's runs
    let mut other_piston = piston.clone();
    other_piston.lubrication = other;
    validate_oil(c, &other_piston)?;
    Ok(ReportSpec {
        compare_lubrication: Some(lubrication_of(other)),
    })
}

/// The validated skirt model of a raw one.
fn lubrication_of(l: raw::RawLubrication) -> spec::Lubrication {
    match l {
        raw::RawLubrication::Dry => spec::Lubrication::Dry,
        raw::RawLubrication::Squeeze => spec::Lubrication::Squeeze,
        raw::RawLubrication::Mixed => spec::Lubrication::Mixed,
    }
}

/// Thresholds written by `linercav calibrate --json`, with the coolant state they were
/// measured at (absent from a hand-written file).
#[derive(serde::Deserialize)]
pub(super) struct CalibrationThresholds {
    onset_m_s2: f64,
    high_risk_m_s2: f64,
    k_p_pa_per_m_s2: f64,
    #[serde(default)]
    gap_mm: Option<f64>,
    #[serde(default)]
    coolant: Option<CalibratedCoolant>,
}

/// The coolant state of a calibration (`calibrate --json`'s `coolant`).
#[derive(serde::Deserialize)]
struct CalibratedCoolant {
    temp_c: f64,
    glycol: f64,
    static_pa: f64,
}

/// How the coolant state of calibration `t` differs from the scene's (`coolant`, `gap` in m):
/// gap and static pressure by more than 2 %, temperature by more than 2 K, glycol by more
/// than 0.01; each as "what: calibrated, scene".
fn calibration_state_differences(
    t: &CalibrationThresholds,
    coolant: &crate::coolant::Coolant,
    gap: f64,
) -> Vec<String> {
    let mut out = Vec::new();
    let rel = |a: f64, b: f64| (a - b).abs() > 0.02 * a.abs().max(b.abs());
    if let Some(g) = t.gap_mm.filter(|&g| rel(g, gap * 1e3)) {
        out.push(format!("gap {} mm, scene {} mm", num(g), num(gap * 1e3)));
    }
    if let Some(k) = &t.coolant {
        if (k.temp_c - coolant.temp_c).abs() > 2.0 {
            out.push(format!(
                "temperature {} C, scene {} C",
                num(k.temp_c),
                num(coolant.temp_c)
            ));
        }
        if rel(k.static_pa, coolant.static_pa) {
            out.push(format!(
                "static pressure {} kPa, scene {} kPa",
                num(k.static_pa * 1e-3),
                num(coolant.static_pa * 1e-3)
            ));
        }
        if (k.glycol - coolant.glycol).abs() > 0.01 {
            out.push(format!(
                "glycol {}, scene {}",
                num(k.glycol),
                num(coolant.glycol)
            ));
        }
    }
    out
}

/// Largest coolant gap accepted \[mm\] (`cavitation.gap_mm`).
const MAX_GAP_MM: f64 = 100.0;
/// Largest static coolant pressure accepted \[kPa\] (`cavitation.static_pressure_kpa`, and
/// `calibrate --static-kpa`).
pub const MAX_STATIC_KPA: f64 = 10_000.0;

/// Largest `rom.cut_enrichment` (shapes added per cut).
const MAX_CUT_ENRICHMENT: usize = 10_000;

/// Bores accepted \[mm\]: from a model engine's 20 mm to a slow marine engine's ~1 m.
const BORE_MM: (f64, f64) = (20.0, 1500.0);

/// The lowest engine speed accepted \[rpm\].
const MIN_SPEED_RPM: f64 = 50.0;

/// The highest output band accepted \[Hz\]: liner cavitation is judged on responses up to some
/// 10 kHz, and a shell mesh of an engine resolves no mode near 50 kHz (1e308 Hz was blamed on
/// transient.step_deg).
const MAX_BAND_HZ: f64 = 5e4;

/// The highest risk threshold accepted \[m/s^2\]: the peaks of liners at risk are 1e2-1e4
/// m/s^2 (1e308 left the derived onset infinite: "onset (inf)").
const MAX_THRESHOLD_M_S2: f64 = 1e6;

/// The highest contact stiffness per slice accepted \[N/m\]: skirt penalties are 1e7-1e10;
/// 1e308 reached the solver ("did not converge").
const MAX_CONTACT_STIFFNESS: f64 = 1e12;

/// Wiebe's a and m accepted: a = 6.9 burns 99.9 % (a = 50 burns all but e^-50), m is 0.5-3
/// for engines; 1e308 reached the solver as a non-finite pressure, m = 1e6 as a burn all at
/// its end ("deep penetration").
const WIEBE_A: (f64, f64) = (1e-3, 50.0);
const WIEBE_M: (f64, f64) = (0.0, 20.0);

/// Largest wall-pressure transfer accepted \[Pa per m/s^2\] (`cavitation.k_p_pa_per_m_s2`): at 1000
/// m/s^2 it would be 1 GPa.
const MAX_K_P: f64 = 1e6;

/// Refuses `v` of `key` above `max` (1e9 mm gaps and 1e12 kPa pressures gave a verdict without
/// a word); `why` says what such values are.
fn bounded(c: &Checker<'_>, key: &str, v: f64, max: f64, why: &str) -> Result<(), SceneError> {
    if v > max {
        return Err(c.err(
            key,
            format!(
                "must be at most {} ({why}), got {}",
                num(max),
                crate::text::exact(v)
            ),
        ));
    }
    Ok(())
}

/// The thresholds of the scene's calibration file `f` (not beside the scene's own threshold
/// keys), with a warning when the file's coolant state differs from the scene's (`coolant`,
/// `gap` in m).
fn calibration_spec(
    c: &Checker<'_>,
    base: &Path,
    (r, f): (&raw::RawCavitation, &str),
    (coolant, gap): (&crate::coolant::Coolant, f64),
) -> Result<ThresholdSpec, SceneError> {
    if r.k_p_pa_per_m_s2.is_some() || r.onset_m_s2.is_some() || r.high_risk_m_s2.is_some() {
        return Err(c.err(
            "cavitation.calibration_file",
            "give either a calibration file or k_p_pa_per_m_s2/onset_m_s2/high_risk_m_s2, not both",
        ));
    }
    let f = path_value(
        c,
        "cavitation.calibration_file",
        f,
        "thresholds from k_p_pa_per_m_s2, onset_m_s2 and high_risk_m_s2",
    )?;
    let (spec, t) = calibration_thresholds(c, &base.join(f))?;
    let differs = calibration_state_differences(&t, coolant, gap);
    if !differs.is_empty() {
        // (a calibration made with another coolant was applied without a word)
        log::warn!(
            "{}: cavitation.calibration_file {f} was measured at another coolant state ({}): its onset and high-risk thresholds are the rig's at that state",
            c.path.display(),
            differs.join("; ")
        );
    }
    Ok(spec)
}

pub(super) fn validate_cavitation(
    c: &Checker<'_>,
    base: &Path,
    r: &raw::RawCavitation,
) -> Result<CavitationSpec, SceneError> {
    use crate::coolant::Coolant;
    let coolant =
        Coolant::new(r.coolant_temp_c, r.glycol, r.static_pressure_kpa * 1e3).map_err(|e| {
            use crate::coolant::CoolantError as E;
            let key = match e {
                E::Temperature(_) => "cavitation.coolant_temp_c",
                E::Glycol(_) => "cavitation.glycol",
                E::Pressure(_) | E::Boiling { .. } => "cavitation.static_pressure_kpa",
            };
            c.err(key, e.to_string())
        })?;
    c.positive("cavitation.gap_mm", r.gap_mm)?;
    bounded(
        c,
        "cavitation.gap_mm",
        r.gap_mm,
        MAX_GAP_MM,
        "a coolant jacket is a few mm wide",
    )?;
    // (its lower bound, 0.05 mm, is the sanity review's, with the reason)
    let gap = r.gap_mm * 1e-3;
    bounded(
        c,
        "cavitation.static_pressure_kpa",
        r.static_pressure_kpa,
        MAX_STATIC_KPA,
        "a cooling system holds 1-3 bar",
    )?;
    let thresholds = if let Some(f) = &r.calibration_file {
        calibration_spec(c, base, (r, f), (&coolant, gap))?
    } else {
        if let Some(k) = r.k_p_pa_per_m_s2 {
            if !(k.is_finite() && k >= 0.0) {
                return Err(c.err(
                    "cavitation.k_p_pa_per_m_s2",
                    format!(
                        "must be a finite number >= 0, got {}",
                        crate::text::exact(k)
                    ),
                ));
            }
            bounded(
                c,
                "cavitation.k_p_pa_per_m_s2",
                k,
                MAX_K_P,
                "the gap's coolant gives a few Pa per m/s^2, rig calibrations some hundred",
            )?;
        }
        let threshold = |key: &str, v: Option<f64>| -> Result<Option<f64>, SceneError> {
            let Some(v) = v else { return Ok(None) };
            let v = c.positive(key, v)?;
            bounded(
                c,
                key,
                v,
                MAX_THRESHOLD_M_S2,
                "the peaks of liners at risk are 1e2-1e4 m/s^2",
            )?;
            Ok(Some(v))
        };
        let high = threshold("cavitation.high_risk_m_s2", r.high_risk_m_s2)?;
        let onset = threshold("cavitation.onset_m_s2", r.onset_m_s2)?;
        ThresholdSpec::Scene {
            onset_m_s2: onset,
            high_risk_m_s2: high,
            k_p_pa_per_m_s2: r.k_p_pa_per_m_s2,
        }
    };
    let layer_mass_per_area = match r.coolant_mass.as_str() {
        "none" => None,
        "layer" => Some(coolant.density_kg_m3 * gap),
        other => {
            return Err(c.err(
                "cavitation.coolant_mass",
                format!("expected \"none\" or \"layer\", got \"{other}\""),
            ))
        }
    };
    // their order is checked where the cavitation stage resolves them (`cavitation::Setup`,
    // called by `api::load_scene` right after loading)
    Ok(CavitationSpec {
        coolant,
        gap,
        thresholds,
        layer_mass_per_area,
    })
}

/// The thresholds of a calibration file written by `linercav calibrate --json`.
pub(super) fn calibration_thresholds(
    c: &Checker<'_>,
    path: &Path,
) -> Result<(ThresholdSpec, CalibrationThresholds), SceneError> {
    let key = "cavitation.calibration_file";
    let text = crate::files::read_text(path, crate::files::LIMIT_TEXT)
        .map_err(|e| c.err(key, format!("cannot read {}: {e}", path.display())))?;
    let not_calibration = |e: String| {
        c.err(
            key,
            format!(
                "{}: not a calibration JSON (need an object with onset_m_s2, high_risk_m_s2, k_p_pa_per_m_s2): {e}",
                path.display(),
            ),
        )
    };
    // an object only: serde would also take the three values as an array, in an order the
    // file does not show. Read straight into the thresholds, whose fields serde checks for
    // duplicates (through a JSON value the last of two `onset_m_s2` won silently).
    if !text.trim_start().starts_with('{') {
        return Err(not_calibration("expected an object".into()));
    }
    let t: CalibrationThresholds =
        serde_json::from_str(&text).map_err(|e| not_calibration(e.to_string()))?;
    for (name, v) in [
        ("onset_m_s2", t.onset_m_s2),
        ("high_risk_m_s2", t.high_risk_m_s2),
        ("k_p_pa_per_m_s2", t.k_p_pa_per_m_s2),
    ] {
        if !v.is_finite() || v < 0.0 {
            return Err(c.err(
                key,
                format!(
                    "{}: {name} must be a finite number >= 0, got {}",
                    path.display(),
                    crate::text::exact(v)
                ),
            ));
        }
    }
    if t.k_p_pa_per_m_s2 > MAX_K_P {
        return Err(c.err(
            key,
            format!(
                "{}: k_p_pa_per_m_s2 must be at most {}, got {}",
                path.display(),
                num(MAX_K_P),
                crate::text::exact(t.k_p_pa_per_m_s2)
            ),
        ));
    }
    let spec = ThresholdSpec::Calibrated {
        onset_m_s2: t.onset_m_s2,
        high_risk_m_s2: t.high_risk_m_s2,
        k_p_pa_per_m_s2: t.k_p_pa_per_m_s2,
    };
    Ok((spec, t))
}

pub(super) fn validate_simulation(
    c: &Checker<'_>,
    base: &Path,
    raw: &RawScene,
    engine: &Engine,
    liner: &LinerGeometry,
) -> Result<Option<Simulation>, SceneError> {
    let (p, o, t) = match (&raw.piston, &raw.operating, &raw.transient) {
        (None, None, None) => return Ok(None),
        (Some(p), Some(o), Some(t)) => (p, o, t),
        _ => {
            return Err(c.err(
                "piston",
                "[piston], [operating] and [transient] go together: give all three or none",
            ))
        }
    };
    let piston = validate_piston(c, p, engine, liner)?;
    let lubricated = piston.oil.is_some();
    Ok(Some(Simulation {
        piston,
        operating: validate_operating(c, base, o)?,
        transient: validate_transient(c, t, lubricated)?,
    }))
}

/// The skirt of `[piston]`: its shape (slices, clearance, barrel, ovality), the thermal
/// expansion of piston and liner at their temperatures, and the contact stiffness.
fn validate_skirt(
    c: &Checker<'_>,
    p: &raw::RawPiston,
    engine: &Engine,
    skirt_length: f64,
    top_above_pin: f64,
) -> Result<spec::SkirtSpec, SceneError> {
    let th = &p.thermal;
    let temp = |key: &str, v: f64| -> Result<f64, SceneError> {
        if v.is_finite() && (-50.0..=400.0).contains(&v) {
            Ok(v)
        } else {
            Err(c.err(
                key,
                format!(
                    "must be a temperature in [-50, 400] deg C, got {}",
                    crate::text::exact(v)
                ),
            ))
        }
    };
    let expansion = |key: &str, v: f64| -> Result<f64, SceneError> {
        if v.is_finite() && (0.0..=1e-4).contains(&v) {
            Ok(v)
        } else {
            Err(c.err(
                key,
                format!("must be in [0, 1e-4] 1/K, got {}", crate::text::exact(v)),
            ))
        }
    };
    Ok(spec::SkirtSpec {
        bore: engine.bore,
        length: skirt_length,
        top_above_pin,
        slices: p.slices,
        clearance: c.nonneg("piston.clearance_um", p.clearance_um)? * 1e-6,
        barrel: c.within("piston.barrel_um", p.barrel_um, SKIRT_PROFILE_UM)? * 1e-6,
        barrel_max_below_pin: barrel_max_below_pin(c, p, skirt_length, top_above_pin)?,
        ovality: c.within("piston.ovality_um", p.ovality_um, SKIRT_PROFILE_UM)? * 1e-6,
        piston_expansion: expansion(
            "piston.thermal.piston_expansion_per_k",
            th.piston_expansion_per_k,
        )?,
        skirt_top_temp_c: temp("piston.thermal.skirt_top_temp_c", th.skirt_top_temp_c)?,
        skirt_bottom_temp_c: temp("piston.thermal.skirt_bottom_temp_c", th.skirt_bottom_temp_c)?,
        liner_expansion: expansion(
            "piston.thermal.liner_expansion_per_k",
            th.liner_expansion_per_k,
        )?,
        liner_temp_c: temp("piston.thermal.liner_temp_c", th.liner_temp_c)?,
        reference_temp_c: temp("piston.thermal.reference_temp_c", th.reference_temp_c)?,
        stiffness: contact_stiffness(c, p.contact_stiffness_n_per_m)?,
    })
}

/// `piston.contact_stiffness_n_per_m`: positive, at most [`MAX_CONTACT_STIFFNESS`].
fn contact_stiffness(c: &Checker<'_>, v: f64) -> Result<f64, SceneError> {
    let key = "piston.contact_stiffness_n_per_m";
    let k = c.positive(key, v)?;
    bounded(
        c,
        key,
        k,
        MAX_CONTACT_STIFFNESS,
        "skirt contact penalties are 1e7-1e10 N/m per slice",
    )?;
    Ok(k)
}

/// `[piston]`: masses, geometry (the pin inside the liner at TDC, the offset within the rod's
/// reach), skirt profile, slices and thermal state.
/// Skirt profile depths accepted \[um\] (`piston.barrel_um`, `piston.ovality_um`): profiles
/// are 10-500 um; 1e308 um gave a 306-digit hot clearance and no slap at all.
const SKIRT_PROFILE_UM: (f64, f64) = (0.0, 5000.0);

pub(super) fn validate_piston(
    c: &Checker<'_>,
    p: &raw::RawPiston,
    engine: &Engine,
    liner: &LinerGeometry,
) -> Result<PistonSpec, SceneError> {
    let mass = c.positive("piston.mass_kg", p.mass_kg)?;
    let cg_above_pin = c.finite("piston.cg_above_pin_mm", p.cg_above_pin_mm)? * 1e-3;
    let tilt_inertia = c.positive("piston.tilt_inertia_kg_m2", p.tilt_inertia_kg_m2)?;
    if tilt_inertia <= mass * cg_above_pin * cg_above_pin {
        return Err(c.err(
            "piston.tilt_inertia_kg_m2",
            format!(
                "must exceed mass x cg_above_pin^2 = {:.3e} kg m^2 (it is the inertia about the pin, including the parallel-axis part)",
                mass * cg_above_pin * cg_above_pin
            ),
        ));
    }
    let compression_height = c.mm("piston.compression_height_mm", p.compression_height_mm)?;
    let skirt_length = c.mm("piston.skirt_length_mm", p.skirt_length_mm)?;
    let top_above_pin = c.finite("piston.pin_below_skirt_top_mm", p.pin_below_skirt_top_mm)? * 1e-3;
    if top_above_pin >= compression_height || top_above_pin <= 0.0 || top_above_pin >= skirt_length
    {
        return Err(c.err(
            "piston.pin_below_skirt_top_mm",
            "the pin must lie within the skirt, and the skirt top below the crown",
        ));
    }
    let crown_depth = c.nonneg("piston.crown_depth_at_tdc_mm", p.crown_depth_at_tdc_mm)? * 1e-3;
    if crown_depth + compression_height >= liner.length {
        return Err(c.err(
            "piston.compression_height_mm",
            "the pin at top dead centre would lie below the liner",
        ));
    }
    // 10 slices resolve the skirt's barrel and contact patch; beyond a few hundred the
    // contact cost grows with no change in the answer
    if !(10..=MAX_SLICES).contains(&p.slices) {
        return Err(c.err(
            "piston.slices",
            format!("must lie in [10, {MAX_SLICES}], got {}", p.slices),
        ));
    }
    let skirt = validate_skirt(c, p, engine, skirt_length, top_above_pin)?;
    let piston = PistonSpec {
        mass,
        pin_mass: c.nonneg("piston.pin_mass_kg", p.pin_mass_kg)?,
        tilt_inertia,
        cg_above_pin,
        cg_lateral: c.finite("piston.cg_offset_mm", p.cg_offset_mm)? * 1e-3,
        pin_offset: c.finite("piston.pin_offset_mm", p.pin_offset_mm)? * 1e-3,
        crank_offset: offset(c, "piston.crank_offset_mm", p.crank_offset_mm, engine)?,
        compression_height,
        crown_depth_at_tdc: crown_depth,
        skirt,
        contact_damping: c.nonneg(
            "piston.contact_damping_n_s_per_m",
            p.contact_damping_n_s_per_m,
        )?,
        friction: c.within("piston.friction", p.friction, FRICTION_RANGE)?,
        pin_friction: c.within("piston.pin_friction", p.pin_friction, FRICTION_RANGE)?,
        pin_radius: pin_radius(c, p, engine)?,
        pin_slip_rate: c.within("piston.pin_slip_rad_s", p.pin_slip_rad_s, PIN_SLIP_RANGE)?,
        oil: validate_oil(c, p)?,
    };
    let offset = (piston.pin_offset - piston.crank_offset).abs();
    if offset + engine.stroke / 2.0 >= engine.rod_length {
        // the keys the user moved: both when both are given
        let key = match (piston.pin_offset != 0.0, piston.crank_offset != 0.0) {
            (true, true) => "piston.pin_offset_mm and piston.crank_offset_mm",
            (false, true) => "piston.crank_offset_mm",
            _ => "piston.pin_offset_mm",
        };
        return Err(c.err(
            key,
            "the offset (pin offset less crank offset) is too large for the rod",
        ));
    }
    Ok(piston)
}

/// The crank's offset \[m\] from `mm`: finite and within the bore's radius (a desaxe of a few
/// mm; one beyond the bore ran into a deep penetration, exit 1). The pin's offset is checked
/// with the piston's other lateral offsets (`scene::sanity`).
fn offset(c: &Checker<'_>, key: &str, mm: f64, engine: &Engine) -> Result<f64, SceneError> {
    let v = c.finite(key, mm)? * 1e-3;
    if v.abs() < engine.bore / 2.0 {
        Ok(v)
    } else {
        Err(c.err(
            key,
            format!(
                "must lie within the bore's radius ({} mm either way), got {}",
                num(engine.bore / 2.0 * 1e3),
                crate::text::exact(mm)
            ),
        ))
    }
}

/// The barrel's widest point below the pin \[m\] from `piston.barrel_max_below_pin_mm`: on the
/// skirt, from its top (`top_above_pin` above the pin) to its bottom (a point off the skirt
/// turned the barrel into a uniform drop without a word).
fn barrel_max_below_pin(
    c: &Checker<'_>,
    p: &raw::RawPiston,
    skirt_length: f64,
    top_above_pin: f64,
) -> Result<f64, SceneError> {
    let key = "piston.barrel_max_below_pin_mm";
    let v = c.finite(key, p.barrel_max_below_pin_mm)? * 1e-3;
    let (lo, hi) = (-top_above_pin, skirt_length - top_above_pin);
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(c.err(
            key,
            format!(
                "must lie on the skirt, from {} (its top) to {} mm (its bottom) below the pin, got {}",
                num(lo * 1e3),
                num(hi * 1e3),
                crate::text::exact(p.barrel_max_below_pin_mm)
            ),
        ))
    }
}

/// Mean piston speed above which a speed is refused [m/s]: racing engines peak near 25 m/s.
const MAX_MEAN_PISTON_SPEED: f64 = 30.0;

/// Coulomb coefficients of the skirt and the pin (`piston.friction`, `piston.pin_friction`):
/// lubricated steel on cast iron or bronze lies near 0.01-0.15 and even clean dry metal pairs
/// stay below 1; a larger value is a typing error (50 stopped a run with "deep penetration").
const FRICTION_RANGE: (f64, f64) = (0.0, 1.0);

/// `piston.pin_slip_rad_s` [rad/s]: below 1e-4 the torque's reversal is a step on the
/// transient's time scale (the rod turns at tens of rad/s), above 1e4 the torque never builds.
const PIN_SLIP_RANGE: (f64, f64) = (1e-4, 1e4);

/// Film viscosities the Vogel data may give at the film's temperatures [Pa s]: engine oils lie
/// between about 2 mPa s (hot, thin grades) and hundreds of Pa s (the Vogel fit of a 15W-40
/// extrapolated to -30 deg C: 430 Pa s); a value outside [1e-4, 1e4] is a unit slip or an
/// overflow (b / (T + c) large).
const VISCOSITY_RANGE_PA_S: (f64, f64) = (1e-4, 1e4);

/// `piston.pin_diameter_mm`: the pin's radius \[m\], 0.2 x bore when not given.
fn pin_radius(c: &Checker<'_>, p: &raw::RawPiston, engine: &Engine) -> Result<f64, SceneError> {
    let Some(given) = p.pin_diameter_mm else {
        return Ok(0.2 * engine.bore);
    };
    let d = c.positive("piston.pin_diameter_mm", given)? * 1e-3;
    // a pin thinner than a tenth of the bore could not carry the gas force
    if d < 0.1 * engine.bore {
        return Err(c.err(
            "piston.pin_diameter_mm",
            format!(
                "must be at least a tenth of the bore ({:.1} mm; heavy-duty pins are 0.38-0.42 of it), got {}",
                engine.bore * 1e2,
                crate::text::exact(given)
            ),
        ));
    }
    if d >= engine.bore {
        return Err(c.err(
            "piston.pin_diameter_mm",
            format!(
                "must be less than the bore ({:.1} mm), got {}",
                engine.bore * 1e3,
                crate::text::exact(given)
            ),
        ));
    }
    Ok(d / 2.0)
}

/// `piston.lubrication` and `[piston.oil]`: the film's data, SI; `None` for a dry skirt.
fn validate_oil(c: &Checker<'_>, p: &raw::RawPiston) -> Result<Option<spec::OilSpec>, SceneError> {
    use spec::Lubrication;
    let model = lubrication_of(p.lubrication);
    // checked for a dry skirt too: a report may compare it with a lubricated one, and a value
    // given is a value meant
    let oil = film_data(c, p, model)?;
    Ok((model != Lubrication::Dry).then_some(oil))
}

/// `[piston.oil]`, SI, for the film model `model` (the asperity data checked whatever the
/// model, kept for `mixed`; the viscosity over the film's temperatures for a film only).
fn film_data(
    c: &Checker<'_>,
    p: &raw::RawPiston,
    model: spec::Lubrication,
) -> Result<spec::OilSpec, SceneError> {
    let o = &p.oil;
    let supply = c.positive("piston.oil.supply_um", o.supply_um)?;
    if supply > 1000.0 {
        return Err(c.err(
            "piston.oil.supply_um",
            format!(
                "must lie in (0, 1000] um, got {}",
                crate::text::exact(supply)
            ),
        ));
    }
    let vogel = [
        c.positive("piston.oil.vogel_a_mpa_s", o.vogel_a_mpa_s)? * 1e-3,
        c.positive("piston.oil.vogel_b_c", o.vogel_b_c)?,
        c.finite("piston.oil.vogel_c_c", o.vogel_c_c)?,
    ];
    // the film's temperature is the mean of the skirt's (linear from its top to its bottom)
    // and the liner's ([`crate::piston::lubrication`])
    let th = &p.thermal;
    let film = |skirt: f64| 0.5 * (skirt + th.liner_temp_c);
    let coldest = film(th.skirt_bottom_temp_c.min(th.skirt_top_temp_c));
    let hottest = film(th.skirt_bottom_temp_c.max(th.skirt_top_temp_c));
    if coldest + vogel[2] <= 0.0 {
        return Err(c.err(
            "piston.oil.vogel_c_c",
            format!(
                "T + c must be positive at the film's temperatures (down to {} deg C)",
                num(coldest)
            ),
        ));
    }
    // a dry skirt's oil data need only be numbers: a cold-start scene may lie outside what a
    // film is checked for
    if model != spec::Lubrication::Dry {
        check_viscosity(c, vogel, (coldest, hottest))?;
    }
    // Greenwood-Tripp's data: roughness of honed liners and ground skirts 0.1-5 um, eta beta
    // sigma 0.03-0.07, sigma / beta 1e-4 - 0.1, E' of metal pairs 50-250 GPa
    let asperity = spec::AsperitySpec {
        sigma: c.within("piston.oil.roughness_um", o.roughness_um, (1e-3, 100.0))? * 1e-6,
        eta_beta_sigma: c.within("piston.oil.eta_beta_sigma", o.eta_beta_sigma, (1e-4, 1.0))?,
        sigma_over_beta: c.within("piston.oil.sigma_over_beta", o.sigma_over_beta, (1e-6, 1.0))?,
        modulus: c.within(
            "piston.oil.asperity_modulus_gpa",
            o.asperity_modulus_gpa,
            (1.0, 1000.0),
        )? * 1e9,
    };
    Ok(spec::OilSpec {
        model,
        supply: supply * 1e-6,
        vogel,
        asperity: (model == spec::Lubrication::Mixed).then_some(asperity),
    })
}

/// The Vogel viscosity mu = a exp(b / (T + c)) (`vogel` SI: a \[Pa s\], b, c \[deg C\]) at the
/// film's coldest and hottest temperatures (`range`, deg C) lies in [`VISCOSITY_RANGE_PA_S`]
/// (it falls with T, so the two ends bound it). Checked for a lubricated skirt only.
fn check_viscosity(c: &Checker<'_>, vogel: [f64; 3], range: (f64, f64)) -> Result<(), SceneError> {
    let mu = |t: f64| vogel[0] * (vogel[1] / (t + vogel[2])).exp();
    let (cold, hot) = (mu(range.0), mu(range.1));
    let (lo, hi) = VISCOSITY_RANGE_PA_S;
    if cold.is_finite() && cold <= hi && hot >= lo {
        return Ok(());
    }
    Err(c.err(
        "piston.oil.vogel_a_mpa_s / vogel_b_c / vogel_c_c",
        format!(
            "give a viscosity of {} to {} mPa s at the film's temperatures ({} to {} deg C), outside the {} to {} mPa s of engine oils",
            num(hot * 1e3),
            num(cold * 1e3),
            num(range.0),
            num(range.1),
            num(lo * 1e3),
            num(hi * 1e3)
        ),
    ))
}

/// Shortest burn `operating.combustion.duration_deg` may give \[deg\]: fifty of the built-in
/// pressure curve's 0.1-deg Runge-Kutta steps (`piston::pressure`), which resolve the Wiebe
/// heat release; burns last 40-120 deg.
const MIN_BURN_DEG: f64 = 5.0;

/// `[operating]`: load, combustion model (Wiebe) or measured pressure curve.
pub(super) fn validate_operating(
    c: &Checker<'_>,
    base: &Path,
    o: &raw::RawOperating,
) -> Result<Operating, SceneError> {
    if !(o.load.is_finite() && (0.0..=1.0).contains(&o.load)) {
        return Err(c.err(
            "operating.load",
            format!("must be in [0, 1], got {}", crate::text::exact(o.load)),
        ));
    }
    let cb = &o.combustion;
    if !(cb.compression_ratio.is_finite() && cb.compression_ratio > 1.0) {
        return Err(c.err("operating.combustion.compression_ratio", "must exceed 1"));
    }
    if !(cb.intake_bar.is_finite() && cb.intake_bar >= 1.0) {
        return Err(c.err(
            "operating.combustion.intake_bar",
            "must be at least 1 bar (absolute)",
        ));
    }
    if !(cb.polytropic > 1.0 && cb.polytropic < 1.67) {
        return Err(c.err("operating.combustion.polytropic", "must lie in (1, 1.67)"));
    }
    if !(cb.evo_deg > 450.0 && cb.evo_deg < 700.0) {
        return Err(c.err("operating.combustion.evo_deg", "must lie in (450, 700) deg"));
    }
    if !(cb.start_deg > 180.0 && cb.start_deg < cb.evo_deg) {
        return Err(c.err(
            "operating.combustion.start_deg",
            "must lie between 180 deg and evo_deg",
        ));
    }
    let wiebe = spec::Wiebe {
        compression_ratio: cb.compression_ratio,
        intake_pa: cb.intake_bar * 1e5,
        exhaust_over_intake_pa: c.nonneg(
            "operating.combustion.exhaust_over_intake_bar",
            cb.exhaust_over_intake_bar,
        )? * 1e5,
        start_deg: cb.start_deg,
        // a burn lasts 40-120 deg; one longer than the cycle is no burn, one shorter than
        // MIN_BURN_DEG falls between the built-in curve's 0.1-deg integration steps (0.01 deg
        // gave the motored curve's 128 bar peak, exit 0)
        duration_deg: c.within(
            "operating.combustion.duration_deg",
            c.positive("operating.combustion.duration_deg", cb.duration_deg)?,
            (MIN_BURN_DEG, 720.0),
        )?,
        a: c.within("operating.combustion.wiebe_a", cb.wiebe_a, WIEBE_A)?,
        m: c.within("operating.combustion.wiebe_m", cb.wiebe_m, WIEBE_M)?,
        heat_j: c.nonneg("operating.combustion.heat_release_j", cb.heat_release_j)?,
        polytropic: cb.polytropic,
        evo_deg: cb.evo_deg,
        load: o.load,
    };
    let operating = Operating {
        load: o.load,
        pressure: match &o.pressure_file {
            Some(f) => PressureSource::File(base.join(path_value(
                c,
                "operating.pressure_file",
                f,
                "the built-in Wiebe curve",
            )?)),
            None => PressureSource::Wiebe(wiebe),
        },
        crankcase_pa: crankcase_pressure(c, o.crankcase_pressure_bar)?,
    };
    Ok(operating)
}

/// Largest crankcase pressure accepted \[bar\]: a crankcase holds about 1 bar (blow-by lifts
/// it by millibars); 1e9 bar ran into a deep penetration (exit 1).
const MAX_CRANKCASE_BAR: f64 = 10.0;

/// `operating.crankcase_pressure_bar` \[Pa\]: positive, at most [`MAX_CRANKCASE_BAR`].
fn crankcase_pressure(c: &Checker<'_>, bar: f64) -> Result<f64, SceneError> {
    let key = "operating.crankcase_pressure_bar";
    let v = c.positive(key, bar)?;
    if v > MAX_CRANKCASE_BAR {
        return Err(c.err(
            key,
            format!(
                "must be at most {} bar (a crankcase holds about 1 bar), got {}",
                num(MAX_CRANKCASE_BAR),
                crate::text::exact(bar)
            ),
        ));
    }
    Ok(v * 1e5)
}

/// `[transient]`: scheme (unset: "hht" for a `lubricated` skirt, else "newmark"), step (a
/// whole number of steps per cycle), cycles, damping, tolerance.
pub(super) fn validate_transient(
    c: &Checker<'_>,
    t: &raw::RawTransient,
    lubricated: bool,
) -> Result<TransientSpec, SceneError> {
    // checked whichever scheme runs: a NaN left in an unused key is still a bad value
    if !(t.hht_alpha.is_finite() && (-1.0 / 3.0..=0.0).contains(&t.hht_alpha)) {
        return Err(c.err(
            "transient.hht_alpha",
            format!(
                "must lie in [-1/3, 0], got {}",
                crate::text::exact(t.hht_alpha)
            ),
        ));
    }
    let implied = if lubricated { "hht" } else { "newmark" };
    let scheme = match t.scheme.as_deref().unwrap_or(implied) {
        "newmark" => spec::SchemeChoice::AverageAcceleration,
        "hht" => spec::SchemeChoice::Hht { alpha: t.hht_alpha },
        other => {
            return Err(c.err(
                "transient.scheme",
                format!("expected \"newmark\" or \"hht\", got \"{other}\""),
            ))
        }
    };
    let step = c.positive("transient.step_deg", t.step_deg)?;
    let n = 720.0 / step;
    if !n.is_finite() || (n - n.round()).abs() > 1e-9 * n || n.round() < 36.0 {
        return Err(c.err(
            "transient.step_deg",
            format!(
                "720 must be a whole multiple of the step, with at least 36 steps, got {}",
                crate::text::exact(step)
            ),
        ));
    }
    if t.cycles == 0 {
        return Err(c.err("transient.cycles", "must be at least 1"));
    }
    if t.averaged_cycles == 0 {
        return Err(c.err("transient.averaged_cycles", "must be at least 1"));
    }
    if !(1..=64).contains(&t.slap_substeps) {
        return Err(c.err(
            "transient.slap_substeps",
            format!("must lie in 1..=64, got {}", t.slap_substeps),
        ));
    }
    if !(t.slap_span_deg.is_finite() && (0.0..=720.0).contains(&t.slap_span_deg)) {
        return Err(c.err(
            "transient.slap_span_deg",
            format!(
                "must lie in [0, 720], got {}",
                crate::text::exact(t.slap_span_deg)
            ),
        ));
    }
    if !(t.damping_ratio.is_finite() && (0.0..1.0).contains(&t.damping_ratio)) {
        return Err(c.err(
            "transient.damping_ratio",
            format!(
                "must lie in [0, 1), got {}",
                crate::text::exact(t.damping_ratio)
            ),
        ));
    }
    let transient = TransientSpec {
        scheme,
        step_deg: step,
        cycles: t.cycles,
        // more than were run: all of them (`--set transient.cycles=1` keeps working)
        averaged_cycles: t.averaged_cycles.min(t.cycles),
        adaptive: t.adaptive,
        damping_ratio: t.damping_ratio,
        max_penetration: max_penetration(c, t.max_penetration_um)?,
        mode_cutoff_hz: match t.mode_cutoff_hz {
            Some(f) => Some(c.positive("transient.mode_cutoff_hz", f)?),
            None => None,
        },
        slap_substeps: t.slap_substeps,
        slap_span_deg: t.slap_span_deg,
        max_seconds: c.positive("transient.max_seconds", t.max_seconds)?,
        tolerance: if t.tolerance.is_finite() && t.tolerance > 0.0 && t.tolerance < 1.0 {
            t.tolerance
        } else {
            return Err(c.err(
                "transient.tolerance",
                format!(
                    "must lie in (0, 1) (a relative error), got {}",
                    crate::text::exact(t.tolerance)
                ),
            ));
        },
    };
    Ok(transient)
}

/// `[crankcase.mesh]`: element kind, elements per sector (even), wall layers, axial size.
fn validate_crankcase_meshing(
    c: &Checker<'_>,
    m: &raw::RawCrankcaseMesh,
) -> Result<CrankcaseMeshing, SceneError> {
    let kind = match m.element.as_str() {
        "hex20" => ElementKind::Hex20,
        // the lattice split into Kuhn tetrahedra inverts some of them where the crankcase's
        // blends between bores bend the map (every engine tried): refused, not failed later
        "tet10" => {
            return Err(c.err(
                "crankcase.mesh.element",
                "\"tet10\" is not available for the generated crankcase (its tetrahedra invert where the walls blend between bores): use \"hex20\", or a tet10 deck of your own as crankcase.mesh_file",
            ))
        }
        other => {
            return Err(c.err(
                "crankcase.mesh.element",
                format!("expected \"hex20\", got \"{other}\""),
            ))
        }
    };
    if m.per_sector < 2 || m.per_sector % 2 != 0 {
        return Err(c.err(
            "crankcase.mesh.per_sector",
            "must be even and at least 2 (the thrust line falls on nodes)",
        ));
    }
    if m.wall_layers == 0 {
        return Err(c.err("crankcase.mesh.wall_layers", "must be at least 1"));
    }
    Ok(CrankcaseMeshing {
        kind,
        per_sector: m.per_sector,
        wall_layers: m.wall_layers,
        axial_size: c.mm("crankcase.mesh.axial_size_mm", m.axial_size_mm)?,
    })
}

pub(super) fn validate_crankcase(
    c: &Checker<'_>,
    base: &Path,
    cc: &raw::RawCrankcase,
    engine: &Engine,
    liner: &LinerGeometry,
    material: &dyn Fn(&str, &str) -> Result<Elastic, SceneError>,
) -> Result<Crankcase, SceneError> {
    let geometry = CrankcaseGeometry {
        cylinders: engine.cylinders,
        pitch: engine.cylinder_pitch,
        bore_radius: liner.pilot_diameter / 2.0,
        flange_radius: liner.flange_outer_diameter / 2.0,
        seat_z: liner.length - liner.flange_height,
        guide_height: liner.guide_height,
        guide_bottom: liner.guide_bottom,
        deck_thickness: c.mm("crankcase.deck_thickness_mm", cc.deck_thickness_mm)?,
        jacket_wall: c.mm("crankcase.jacket_wall_mm", cc.jacket_wall_mm)?,
        skirt_depth: c.mm("crankcase.skirt_depth_mm", cc.skirt_depth_mm)?,
        front_wall: c.mm("crankcase.front_wall_mm", cc.front_wall_mm)?,
        rear_wall: c.mm("crankcase.rear_wall_mm", cc.rear_wall_mm)?,
        rail_width: c.mm("crankcase.rail_width_mm", cc.rail_width_mm)?,
        rail_height: c.mm("crankcase.rail_height_mm", cc.rail_height_mm)?,
        analysis_z: liner
            .analysis_depths
            .iter()
            .map(|d| liner.length - d)
            .collect(),
    };
    if liner.flange_outer_diameter <= liner.outer_diameter.max(liner.pilot_diameter) {
        return Err(c.err(
            "liner.flange_outer_diameter_mm",
            "the crankcase needs a liner flange to seat on (flange diameter > outer diameter)",
        ));
    }
    crankcase_proportions(c, cc, engine.bore * 1e3)?;
    if geometry.seat_z - geometry.deck_thickness
        <= geometry.guide_bottom + geometry.guide_height + 1e-9
    {
        return Err(c.err(
            "crankcase.deck_thickness_mm",
            "the deck reaches down into the lower guide band: no water jacket left",
        ));
    }
    if let Some(&z) = geometry.analysis_z.first() {
        if z >= geometry.seat_z - geometry.deck_thickness {
            return Err(c.err(
                "crankcase.deck_thickness_mm",
                "the first analysis point lies inside the deck, not in the coolant zone",
            ));
        }
    }
    if geometry.rail_height >= geometry.skirt_depth {
        return Err(c.err(
            "crankcase.rail_height_mm",
            "must be smaller than skirt_depth_mm",
        ));
    }
    let meshing = validate_crankcase_meshing(c, &cc.mesh)?;
    let source = match &cc.mesh_file {
        Some(f) => CrankcaseSource::File(mesh_file(c, "crankcase.mesh_file", base, f)?),
        None => CrankcaseSource::Parametric { geometry, meshing },
    };
    c.positive("crankcase.flange_clamp_kn", cc.flange_clamp_kn)?;
    // a clamp over the bore area of more than MAX_CLAMP_PA: 1e5 kN on a 115 mm bore pushed the
    // flange through its seat (deep penetration blamed on the contact)
    let most_kn = MAX_CLAMP_PA * std::f64::consts::FRAC_PI_4 * engine.bore.powi(2) * 1e-3;
    let clamp_force = c.within(
        "crankcase.flange_clamp_kn",
        cc.flange_clamp_kn,
        (0.0, most_kn.round()),
    )? * 1e3;
    let file = matches!(source, CrankcaseSource::File(_));
    Ok(Crankcase {
        material: match &cc.material {
            Some(name) => Some(material("crankcase.material", name)?),
            None if file => None,
            None => return Err(c.err(
                "crankcase.material",
                "missing: the parametric crankcase needs a material (name an entry of [materials])",
            )),
        },
        mesh_unit: mesh_unit(c, "crankcase.mesh_unit", &cc.mesh_unit, file)?,
        box_sets: box_sets(c, "crankcase.sets", &cc.sets)?,
        source,
        fix: cc.fix.clone(),
        clamp_force,
    })
}

/// A part's material: the named entry of `[materials]`, required unless the mesh is a file
/// (whose own materials are then used).
pub(super) fn part_material(
    c: &Checker<'_>,
    part: &str,
    name: &Option<String>,
    source: &MeshSource,
    material: &dyn Fn(&str, &str) -> Result<Elastic, SceneError>,
) -> Result<Option<Elastic>, SceneError> {
    let key = format!("{part}.material");
    match (name, source) {
        (Some(n), _) => Ok(Some(material(&key, n)?)),
        (None, MeshSource::File(_)) => Ok(None),
        (None, _) => Err(c.err(
            &key,
            "missing: the parametric mesh needs a material (name an entry of [materials])",
        )),
    }
}

/// A mesh file's unit: "m" (default) or "mm"; only meaningful with a mesh file.
pub(super) fn mesh_unit(
    c: &Checker<'_>,
    key: &str,
    raw: &Option<String>,
    file: bool,
) -> Result<spec::MeshUnit, SceneError> {
    let Some(u) = raw else {
        return Ok(spec::MeshUnit::M);
    };
    let unit = spec::MeshUnit::parse(u)
        .ok_or_else(|| c.err(key, format!("expected \"m\" or \"mm\", got \"{u}\"")))?;
    if !file {
        return Err(c.err(
            key,
            "applies to a mesh_file only (the parametric mesh is built in SI)",
        ));
    }
    Ok(unit)
}

/// Box sets of a part, converted from mm to m; each box must have finite, ordered corners.
pub(super) fn box_sets(
    c: &Checker<'_>,
    key: &str,
    raw: &std::collections::BTreeMap<String, raw::RawBoxSet>,
) -> Result<Vec<(String, [f64; 6])>, SceneError> {
    let mut out = Vec::new();
    for (name, b) in raw {
        let v = b.box_mm;
        let ordered = (0..3).all(|a| v[a] <= v[a + 3]);
        if !v.iter().all(|x| x.is_finite() && x.abs() < 1e6) || !ordered {
            return Err(c.err(
                &format!("{key}.{name}.box_mm"),
                format!("expected [x0, y0, z0, x1, y1, z1] in mm with finite values below 1e6 and x0 <= x1, y0 <= y1, z0 <= z1, got {v:?}"),
            ));
        }
        out.push((name.clone(), v.map(|x| x * 1e-3)));
    }
    Ok(out)
}

/// The smallest `transient.max_penetration_um` accepted \[um\]: the penalty contact carries
/// its load through penetrations of a few um, so a limit far below stops every run at its
/// first contact (1e-9 um gave exit 1 with "the contact stiffness is too low").
const MIN_PENETRATION_LIMIT_UM: f64 = 0.1;

/// `transient.max_penetration_um` in metres, at least [`MIN_PENETRATION_LIMIT_UM`].
fn max_penetration(c: &Checker<'_>, um: f64) -> Result<f64, SceneError> {
    let key = "transient.max_penetration_um";
    if um.is_finite() && um < MIN_PENETRATION_LIMIT_UM {
        return Err(c.err(
            key,
            format!(
                "must be at least {MIN_PENETRATION_LIMIT_UM} um (the contact carries its load through penetrations of a few um), got {}",
                crate::text::exact(um)
            ),
        ));
    }
    Ok(c.positive(key, um)? * 1e-6)
}

/// Refuses crankcase walls, deck, rails and bay depth that no engine has: thinner than
/// [`MIN_WALL_MM`] (a 1e-9 mm deck made degenerate elements, named by no key) or larger than
/// [`MAX_WALL_BORES`] bores (a 14 m front wall on a 115 mm bore ran without a word).
fn crankcase_proportions(
    c: &Checker<'_>,
    cc: &raw::RawCrankcase,
    bore_mm: f64,
) -> Result<(), SceneError> {
    let lengths = [
        ("crankcase.deck_thickness_mm", cc.deck_thickness_mm),
        ("crankcase.jacket_wall_mm", cc.jacket_wall_mm),
        ("crankcase.skirt_depth_mm", cc.skirt_depth_mm),
        ("crankcase.front_wall_mm", cc.front_wall_mm),
        ("crankcase.rear_wall_mm", cc.rear_wall_mm),
        ("crankcase.rail_width_mm", cc.rail_width_mm),
        ("crankcase.rail_height_mm", cc.rail_height_mm),
    ];
    let hi = MAX_WALL_BORES * bore_mm;
    for (key, v) in lengths {
        if !(MIN_WALL_MM..=hi).contains(&v) {
            return Err(c.err(
                key,
                format!(
                    "must lie in [{}, {}] mm ({} mm to {} bores), got {}",
                    num(MIN_WALL_MM),
                    num(hi),
                    num(MIN_WALL_MM),
                    num(MAX_WALL_BORES),
                    crate::text::exact(v)
                ),
            ));
        }
    }
    Ok(())
}

/// The largest liner clamp accepted, as a pressure over the bore area \[Pa\]: engines clamp
/// with 10-40 MPa over it (150 kN on a 115 mm truck bore, 8-12 MN on a 500 mm marine bore, 2-3
/// times the peak gas load); 500 MPa allows 5.2 MN at 115 mm.
const MAX_CLAMP_PA: f64 = 500e6;

/// The thinnest crankcase wall accepted \[mm\] (cast walls are 3 mm and more).
const MIN_WALL_MM: f64 = 1.0;
/// The largest crankcase wall, deck, rail or bay depth accepted, in bores (an engine's crank
/// bay is about 1.5 bores deep, its end walls a fifth of a bore thick).
const MAX_WALL_BORES: f64 = 5.0;

/// The directory a scene's relative paths (meshes, pressure and calibration files, the ROM
/// cache) are taken from: the scene file's. A scene named by `/dev/stdin` or `/dev/fd/N` (a
/// file redirected to the process) takes the directory of the file behind it (its cache
/// went to `/dev/.linercav-cache`), the current directory when there is none.
fn scene_base(path: &Path) -> std::path::PathBuf {
    if path.starts_with("/dev") || path.starts_with("/proc") {
        return match std::fs::canonicalize(path) {
            Ok(real) if !real.starts_with("/dev") && !real.starts_with("/proc") => {
                real.parent().map_or_else(|| ".".into(), Path::to_path_buf)
            }
            _ => ".".into(),
        };
    }
    path.parent().unwrap_or(Path::new(".")).to_path_buf()
}

/// A mesh file's path: the name `f` (not blank: an empty one joined the scene's directory,
/// "cannot read mesh file small/") in the scene's directory `base`, a file that is there (a
/// missing one was reported by its name alone, without the scene's key).
pub(super) fn mesh_file(
    c: &Checker<'_>,
    key: &str,
    base: &Path,
    f: &str,
) -> Result<std::path::PathBuf, SceneError> {
    let p = base.join(path_value(c, key, f, "the parametric mesh")?);
    if !p.is_file() {
        let why = if p.exists() {
            "is not a regular file"
        } else {
            "does not exist"
        };
        return Err(c.err(
            key,
            format!(
                "'{f}' ({}) {why}: give a mesh file's path, relative to the scene file",
                p.display()
            ),
        ));
    }
    Ok(p)
}

/// A path key's value: not blank (an empty one names the scene's own directory, and reading
/// it failed as "small/: not a regular file", or the ROM cache went into the scene's
/// directory); `default` says what leaving the key out gives.
pub(super) fn path_value<'f>(
    c: &Checker<'_>,
    key: &str,
    f: &'f str,
    default: &str,
) -> Result<&'f str, SceneError> {
    if f.trim().is_empty() {
        return Err(c.err(
            key,
            format!("is empty: give a path (relative to the scene file), or leave the key out for {default}"),
        ));
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression (session 70's hostile sweep): a calibration measured at a 4.7 mm gap, 90 C
    /// and 240 kPa was applied to a scene at 20 mm without a word; each difference is named,
    /// and the same state (within 2 %, 2 K) gives none.
    #[test]
    fn regression_a_calibration_at_another_coolant_state_is_named() {
        let t: CalibrationThresholds = serde_json::from_str(
            r#"{"onset_m_s2": 900, "high_risk_m_s2": 1200, "k_p_pa_per_m_s2": 138,
                "gap_mm": 4.7, "coolant": {"temp_c": 90, "glycol": 0, "static_pa": 240000,
                "density_kg_m3": 965}, "events": 25}"#,
        )
        .unwrap();
        let at = |temp, static_pa| crate::coolant::Coolant::new(temp, 0.0, static_pa).unwrap();
        assert!(calibration_state_differences(&t, &at(90.5, 241e3), 4.75e-3).is_empty());
        let d = calibration_state_differences(&t, &at(20.0, 500e3), 20e-3);
        assert_eq!(d.len(), 3, "{d:?}");
        assert!(d[0].contains("gap 4.7 mm, scene 20 mm"), "{d:?}");
        // a hand-written file (the thresholds only) states no coolant
        let bare: CalibrationThresholds = serde_json::from_str(
            r#"{"onset_m_s2": 900, "high_risk_m_s2": 1200, "k_p_pa_per_m_s2": 138}"#,
        )
        .unwrap();
        assert!(calibration_state_differences(&bare, &at(20.0, 500e3), 20e-3).is_empty());
    }
}
