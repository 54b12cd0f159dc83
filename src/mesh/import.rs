//! Meshes from files as the later stages need them: read in their unit and converted to SI,
//! refused when their size is implausible for that unit, their materials resolved (the deck's
//! per element, or one given material that overrides them), and, for an engine, moved into the
//! liner's and the engine's frames with the interface and point sets found from the geometry
//! ([`super::find`]) where the decks do not name them.

use super::find::{self, FoundInterfaces, LinerShape};
use super::{Mesh, MeshUnit};
use crate::scene::spec::Elastic;
use std::path::{Path, PathBuf};

/// Why an imported mesh cannot be used: the file, the key or flag at fault, and why.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error(transparent)]
    Msh(#[from] super::collect::DeckError),
    #[error("{}: {msg} (length unit: {key}, metres when not given)", path.display())]
    Implausible {
        path: PathBuf,
        key: String,
        msg: String,
    },
    /// A deck that contradicts the scene it is used in.
    #[error("{}: {msg} (scene key {key})", path.display())]
    Mismatch {
        path: PathBuf,
        key: String,
        msg: String,
    },
    #[error("{}: {msg} ({key})", path.display())]
    Material {
        path: PathBuf,
        key: String,
        msg: String,
    },
    #[error("{}: {source}", path.display())]
    Find {
        path: PathBuf,
        #[source]
        source: find::FindError,
    },
}

/// Largest extent of any part linercav models, \[m\] (a marine engine's block is ~20 m long).
pub const MAX_EXTENT_M: f64 = 30.0;
/// Smallest extent: below this a part is no engine component (a metre deck read as mm).
pub const MIN_EXTENT_M: f64 = 5e-3;

/// Reads `path` in `unit`, converts it to SI and refuses a size implausible for the unit;
/// `unit_key` names the scene key or flag that set the unit (for the message).
pub fn read_si(path: &Path, unit: MeshUnit, unit_key: &str) -> Result<Mesh, ImportError> {
    let mut mesh = super::read(path)?;
    mesh.to_si(unit);
    check_extent(&mesh, path, unit, unit_key)?;
    Ok(mesh)
}

/// Refuses a mesh whose largest extent lies outside [MIN_EXTENT_M, MAX_EXTENT_M].
pub fn check_extent(
    mesh: &Mesh,
    path: &Path,
    unit: MeshUnit,
    unit_key: &str,
) -> Result<(), ImportError> {
    let (lo, hi) = mesh.bounding_box();
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    if (MIN_EXTENT_M..=MAX_EXTENT_M).contains(&extent) {
        return Ok(());
    }
    let other = match unit {
        MeshUnit::M => "mm",
        MeshUnit::Mm => "m",
    };
    Err(ImportError::Implausible {
        path: path.to_path_buf(),
        key: unit_key.into(),
        msg: format!(
            "the mesh is {} m across read in {}: no engine part is smaller than {} m or larger than {} m; is the deck in {other}? set {unit_key} accordingly",
            crate::text::num(extent),
            unit.name(),
            MIN_EXTENT_M,
            MAX_EXTENT_M
        ),
    })
}

/// Where the material of a part came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MaterialSource {
    /// The scene's `material` key or the command's flags (overriding a deck's).
    Given,
    /// The deck's own materials, per element.
    Deck,
}

/// Resolves a part's material: `given` wins (the deck's materials are dropped), else every
/// element must have the deck's. Returns the nominal material (the given one, or the deck's
/// first: only a fallback, each element carries its own) and where it came from.
pub fn resolve_material(
    mesh: &mut Mesh,
    given: Option<Elastic>,
    path: &Path,
    key: &str,
) -> Result<(Elastic, MaterialSource, Option<String>), ImportError> {
    if let Some(m) = given {
        let warning = overridden(mesh, &m, path, key);
        mesh.clear_materials();
        return Ok((m, MaterialSource::Given, warning));
    }
    let bad = |msg: String| ImportError::Material {
        path: path.to_path_buf(),
        key: key.into(),
        msg,
    };
    if mesh.materials.is_empty() {
        return Err(bad("the mesh defines no material: give one".into()));
    }
    if let Some(e) = mesh.element_without_material() {
        return Err(bad(format!(
            "solid element {} has no material: assign it a section/property, or give a material",
            mesh.element_name(e)
        )));
    }
    // only the materials solid elements use: a deck's dummy materials of beams and
    // connectors ("massless", "rigid") carry no solid
    let used: std::collections::BTreeSet<u32> = mesh.element_material.iter().copied().collect();
    let solids: Vec<&super::DeckMaterial> = used
        .iter()
        .filter_map(|&k| mesh.materials.get(k as usize))
        .collect();
    for m in &solids {
        m.elastic.validate().map_err(|e| {
            bad(format!(
                "the deck's material '{}': {e} (constants in the deck's unit system: a deck in m takes Pa and kg/m^3, a deck in mm MPa and t/mm^3; or give {key} to override it)",
                m.name
            ))
        })?;
    }
    let unusual: Vec<String> = solids
        .iter()
        .filter_map(|m| {
            m.elastic
                .structural_warning(&format!("the deck's material '{}'", m.name))
        })
        .collect();
    let warning =
        (!unusual.is_empty()).then(|| format!("{}: {}", path.display(), unusual.join("; ")));
    let nominal = solids
        .first()
        .map_or(mesh.materials[0].elastic, |m| m.elastic);
    Ok((nominal, MaterialSource::Deck, warning))
}

/// The warning for a given material `m` that replaces deck materials of `mesh` with other
/// constants (relative difference above 1e-6 in E, nu or rho; a deck that states the same
/// material as the scene is not warned of).
fn overridden(mesh: &Mesh, m: &Elastic, path: &Path, key: &str) -> Option<String> {
    let differs = |a: f64, b: f64| (a - b).abs() > 1e-6 * a.abs().max(b.abs());
    let other: Vec<String> = mesh
        .materials
        .iter()
        .filter(|d| {
            let e = &d.elastic;
            differs(e.young, m.young)
                || differs(e.poisson, m.poisson)
                || differs(e.density, m.density)
        })
        .map(|d| {
            let e = &d.elastic;
            format!(
                "'{}' (E {:.4} GPa, nu {}, rho {:.1} kg/m^3)",
                d.name,
                e.young * 1e-9,
                e.poisson,
                e.density
            )
        })
        .collect();
    (!other.is_empty()).then(|| {
        format!(
            "{}: {key} (E {:.4} GPa, nu {}, rho {:.1} kg/m^3) replaces the deck's material {}: every element takes {key}; leave {key} out to use the deck's",
            path.display(),
            m.young * 1e-9,
            m.poisson,
            m.density,
            other.join(", ")
        )
    })
}

/// The liner's place and the crankcase's targets, from the scene.
pub struct EngineFrame<'a> {
    pub axis_x: &'a [f64],
    /// Depths of the analysis points below the liner top \[m\].
    pub depths: &'a [f64],
    /// The scene's bore \[m\] (the found bore must match it).
    pub bore: f64,
    /// Key naming the liner mesh's unit (for messages).
    pub liner_unit_key: &'a str,
}

/// Puts an engine's meshes into their frames and completes their sets (module docs of
/// [`find`]): a liner from a file is moved into its own frame and measured; a crankcase from a
/// file is seated on it; each set the later stages need and the deck does not name is found.
/// `liner_file` / `crankcase_file` are the files (None for a generated mesh, which has all).
pub fn complete_engine(
    liner: &mut Mesh,
    crankcase: &mut Mesh,
    generated_shape: LinerShape,
    liner_file: Option<&Path>,
    crankcase_file: Option<&Path>,
    frame: &EngineFrame<'_>,
) -> Result<FoundInterfaces, ImportError> {
    let mut found = FoundInterfaces::default();
    let shape = match liner_file {
        Some(p) => {
            let (s, axis, centre) =
                find::place_liner(liner).map_err(|source| ImportError::Find {
                    path: p.to_path_buf(),
                    source,
                })?;
            check_bore(p, &s, frame)?;
            check_length(p, &s, &generated_shape)?;
            if crankcase_file.is_none() {
                check_generated_fit(p, &s, &generated_shape)?;
            } else {
                warn_unused_size(p, &s, &generated_shape);
            }
            found.liner_axis = Some(axis);
            found.liner_centre = Some(centre);
            found.liner_turn = find::turn_liner_to_thrust_line(liner, &s);
            s
        }
        None => generated_shape,
    };
    found.liner = Some(shape);
    if let Some(p) = crankcase_file {
        let need_seat =
            (1..=frame.axis_x.len()).any(|c| crankcase.node_set(&format!("seat_{c}")).is_none());
        if need_seat {
            found.crankcase_shift_z = find::seat_crankcase(crankcase, frame.axis_x, &shape)
                .map_err(|source| ImportError::Find {
                    path: p.to_path_buf(),
                    source,
                })?;
            found.crankcase_shift_xy = find::centre_crankcase(crankcase, frame.axis_x, &shape);
        }
        let analysis_z: Vec<f64> = frame.depths.iter().map(|d| shape.length - d).collect();
        let targets = find::CrankcaseTargets {
            axis_x: frame.axis_x,
            analysis_z: &analysis_z,
        };
        found.sets.extend(
            find::crankcase_sets(crankcase, &shape, &targets).map_err(|source| {
                ImportError::Find {
                    path: p.to_path_buf(),
                    source,
                }
            })?,
        );
        for x in find::extra_bores(crankcase, frame.axis_x, &shape) {
            crate::text::warn(format!(
                "{}: the crankcase has a bore at x = {} mm beyond the scene's {} cylinders (bores at x = {} mm): it stays empty, which changes the crankcase's stiffness; check engine.cylinders and the deck",
                p.display(),
                crate::text::num(x * 1e3),
                frame.axis_x.len(),
                frame
                    .axis_x
                    .iter()
                    .map(|x| crate::text::num(x * 1e3))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    if let Some(p) = liner_file {
        let guide = find::named_guide_band(crankcase).ok_or_else(|| ImportError::Find {
            path: p.to_path_buf(),
            source: find::FindError {
                part: "crankcase".into(),
                msg: "no guide_1 set: the liner's guide band cannot be placed".into(),
            },
        })?;
        found.guide_band = Some(guide);
        let t = find::LinerTargets {
            guide,
            depths: frame.depths,
        };
        let mut sets = find::liner_sets(liner, &shape, &t);
        find::check_liner_deck_sets(liner, &shape, &t, &sets).map_err(|source| {
            ImportError::Find {
                path: p.to_path_buf(),
                source,
            }
        })?;
        sets.append(&mut found.sets);
        found.sets = sets;
        narrow_guide(p, liner, crankcase, frame.axis_x.len(), &mut found);
    }
    dry_deck_bore(liner, crankcase, frame.axis_x, &mut found);
    Ok(found)
}

/// Takes the deck plate's bore out of the liner's wet surface: no coolant where the deck holds
/// the liner, from the lowest of the bores' deck undersides ([`find::deck_underside`]) up.
fn dry_deck_bore(liner: &mut Mesh, crankcase: &Mesh, axis_x: &[f64], found: &mut FoundInterfaces) {
    let Some(shape) = found.liner else {
        return;
    };
    let tol = 0.02 * find::mesh_size(crankcase);
    let deck = (axis_x.iter().enumerate())
        .filter_map(|(c, &xc)| find::deck_underside(crankcase, (c + 1, xc), &shape, tol))
        .fold(f64::INFINITY, f64::min);
    if deck.is_finite() {
        find::trim_wet_zone(liner, &shape, deck, &mut found.sets);
    }
}

/// Narrows the guide band (`found.guide_band`) of a liner deck at `p` to where the liner's
/// pilot meets the bore ([`find::trim_lower_guide`]), on both parts, with a warning when the
/// crankcase's guide bore is longer than that.
fn narrow_guide(
    p: &Path,
    liner: &mut Mesh,
    crankcase: &mut Mesh,
    cylinders: usize,
    found: &mut FoundInterfaces,
) {
    let Some(liner_tol) = found.liner.map(|s| s.tol) else {
        return;
    };
    let (Some(guide), Some(band)) = (
        found.guide_band,
        find::trim_lower_guide(liner, &mut found.sets, liner_tol),
    ) else {
        return;
    };
    let tol = 0.02 * find::mesh_size(crankcase);
    // the pilot beyond the crankcase's guide bore is not in it
    let band = [band[0].max(guide[0]), band[1].min(guide[1])];
    if band[0] > guide[0] + tol || band[1] < guide[1] - tol {
        crate::text::warn(format!(
            "{}: the crankcase's guide bore (z {}..{} mm) is longer than the liner's pilot in it (z {}..{} mm): coupled over the pilot only; check the guide heights of the decks (or liner.guide_height_mm)",
            p.display(),
            crate::text::num(guide[0] * 1e3),
            crate::text::num(guide[1] * 1e3),
            crate::text::num(band[0] * 1e3),
            crate::text::num(band[1] * 1e3)
        ));
        find::narrow_guides(crankcase, cylinders, band, &mut found.sets);
        found.guide_band = Some(band);
    }
}

/// A liner deck under a generated crankcase: the crankcase is built to the scene's liner
/// (`scene`: its pilot radius, flange and flange underside; the length is
/// [`check_length`]'s), so the deck's (`deck`)
/// must be the same ([`size_mismatches`]). A wall 5.5 mm thicker in the
/// scene than in the deck built the crankcase's bore around a liner that was not there and
/// moved the first system mode by 3 % without a word.
fn check_generated_fit(
    path: &Path,
    deck: &LinerShape,
    scene: &LinerShape,
) -> Result<(), ImportError> {
    match size_mismatches(deck, scene).into_iter().next() {
        None => Ok(()),
        Some((key, what, d, s)) => Err(ImportError::Mismatch {
            path: path.to_path_buf(),
            key: key.into(),
            msg: format!(
                "the liner mesh's {what} is {} mm, the scene's {} mm: the generated crankcase is built to the scene's liner; give the deck's value",
                crate::text::num(d * 1e3),
                crate::text::num(s * 1e3)
            ),
        }),
    }
}

/// A liner deck under a crankcase deck: the scene's outer (wet wall) diameter, pilot diameter,
/// flange diameter and flange height are not used (the decks hold the parts); each that
/// differs from the deck's ([`FIT_TOLERANCE`], the pilot as in [`size_mismatches`]) is
/// warned of, naming the key (a
/// scene edited in the belief that it changes the liner changed nothing but the cache key).
/// The pilot only where the scene gives one: a scene without (its pilot the outer diameter)
/// says nothing of a stepped deck's pilots.
fn warn_unused_size(path: &Path, deck: &LinerShape, scene: &LinerShape) {
    let plain = scene.pilot_radius == scene.outer_radius;
    let wall = (
        "liner.outer_diameter_mm",
        "wet wall's outer diameter",
        2.0 * deck.outer_radius,
        2.0 * scene.outer_radius,
    );
    let sizes = size_mismatches(deck, scene)
        .into_iter()
        .filter(|m| !(plain && m.1 == "pilot diameter"));
    for (key, what, d, s) in [wall]
        .into_iter()
        .filter(|&(_, _, d, s)| (d - s).abs() > FIT_TOLERANCE * s)
        .chain(sizes)
    {
        crate::text::warn(format!(
            "{}: the liner mesh's {what} is {} mm, the scene's {key} {} mm: the scene's value is not used (both parts come from decks)",
            path.display(),
            crate::text::num(d * 1e3),
            crate::text::num(s * 1e3)
        ));
    }
}

/// The liner sizes in which a deck (`deck`) and the scene (`scene`) differ: the pilot
/// diameter by more than twice the liner's surface tolerance (the pilot is a fit: a deck
/// crankcase's bore is coupled only within that tolerance of it, [`LinerShape::holds`], and a
/// generated one is built to the scene's, so a 141 mm scene pilot round a 140 mm deck tied
/// the liner across a 0.5 mm gap), the flange by more than [`FIT_TOLERANCE`]: (scene key,
/// what, deck's value, scene's value) \[m\].
fn size_mismatches(
    deck: &LinerShape,
    scene: &LinerShape,
) -> Vec<(&'static str, &'static str, f64, f64)> {
    let pilot = (2.0 * scene.pilot_radius, 2.0 * deck.tol);
    let flange = 2.0 * scene.flange_radius;
    let height = scene.length - scene.seat_z;
    let sizes = [
        (
            "liner.pilot_diameter_mm (default liner.outer_diameter_mm)",
            "pilot diameter",
            2.0 * deck.pilot_radius,
            pilot,
        ),
        (
            "liner.flange_outer_diameter_mm",
            "flange diameter",
            2.0 * deck.flange_radius,
            (flange, FIT_TOLERANCE * flange),
        ),
        (
            "liner.flange_height_mm",
            "flange height",
            deck.length - deck.seat_z,
            (height, FIT_TOLERANCE * height),
        ),
    ];
    sizes
        .into_iter()
        .filter(|&(_, _, d, (s, allowed))| (d - s).abs() > allowed)
        .map(|(key, what, d, (s, _))| (key, what, d, s))
        .collect()
}

/// Relative difference between a liner deck's dimension and the scene's beyond which they are
/// different parts, not the same drawing rounded: 1 % (0.7 mm on a 135 mm pilot diameter,
/// several times any fit's clearance).
const FIT_TOLERANCE: f64 = 0.01;

/// A liner deck's length against the scene's `liner.length_mm` (`scene`), within
/// [`FIT_TOLERANCE`], whatever the crankcase: the transient places the pistons from the
/// scene's liner top. A 240 mm deck under a 260 mm scene ran the pistons 20 mm high on the
/// bore lines and halved the small engine's peaks, exit 0.
fn check_length(path: &Path, deck: &LinerShape, scene: &LinerShape) -> Result<(), ImportError> {
    if (deck.length - scene.length).abs() <= FIT_TOLERANCE * scene.length {
        return Ok(());
    }
    Err(ImportError::Mismatch {
        path: path.to_path_buf(),
        key: "liner.length_mm".into(),
        msg: format!(
            "the liner mesh is {} mm long, the scene's {} mm: the pistons run from the scene's liner top (and a generated crankcase is built to it); give the deck's length",
            crate::text::num(deck.length * 1e3),
            crate::text::num(scene.length * 1e3)
        ),
    })
}

/// The found bore must be the scene's: a ratio near 1000 or 1/1000 is a unit mistake.
fn check_bore(path: &Path, s: &LinerShape, frame: &EngineFrame<'_>) -> Result<(), ImportError> {
    let d = 2.0 * s.inner_radius;
    let ratio = d / frame.bore;
    if (ratio - 1.0).abs() <= 0.01 {
        return Ok(());
    }
    let hint = if !(0.01..=100.0).contains(&ratio) {
        format!("; set {} to the deck's unit", frame.liner_unit_key)
    } else {
        String::new()
    };
    Err(ImportError::Implausible {
        path: path.to_path_buf(),
        key: frame.liner_unit_key.into(),
        msg: format!(
            "the liner mesh's bore is {} mm, the scene's engine.bore_mm is {} mm{hint}",
            crate::text::num(d * 1e3),
            crate::text::num(frame.bore * 1e3)
        ),
    })
}
