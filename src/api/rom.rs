//! `rom`, `modes --assembly`, `shapes`: the engine reduced-order model of a scene
//! ([`crate::reduce::scene_rom`]) with a progress display, and the commands' reports.

use super::progress::Progress;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::reduce::rom::RomBuild;
pub use crate::reduce::scene_rom::{CacheOptions, LoadedRom};
use crate::scene::Scene;
use std::cell::OnceCell;

/// The phases of a ROM build on a terminal (the bar appears with the first phase).
#[derive(Default)]
pub struct RomProgress(OnceCell<Progress>);

impl RomProgress {
    pub fn phase(&self, msg: &str) {
        self.0.get_or_init(Progress::new).phase(msg)
    }
}

/// Gets the ROM of a scene ([`crate::reduce::scene_rom::get_rom`]), showing the build's
/// phases on a terminal.
pub fn get_rom_with_progress(scene: &Scene, opts: &CacheOptions) -> Result<LoadedRom> {
    let bar = RomProgress::default();
    Ok(crate::reduce::scene_rom::get_rom(scene, opts, &|m| {
        bar.phase(m)
    })?)
}

/// Builds the ROM of a scene without the cache ([`crate::reduce::scene_rom::build_rom`]),
/// showing its phases on a terminal.
pub fn build_rom_with_progress(scene: &Scene, keep_bases: bool) -> Result<(RomBuild, Mesh, Mesh)> {
    // sized first, as a build through the cache is (`modes --assembly --rom --vtu` aborted
    // in an allocation under a 0.95 GB address-space cap)
    crate::reduce::scene_rom::check_build_limits(scene)?;
    let bar = RomProgress::default();
    Ok(crate::reduce::scene_rom::build_rom(
        scene,
        keep_bases,
        None,
        &|m| bar.phase(m),
    )?)
}

/// JSON report of the `rom` command.
#[derive(serde::Serialize)]
pub struct RomReport {
    pub full_dofs: usize,
    pub reduced_dofs: usize,
    pub cutoff_hz: f64,
    pub band_hz: f64,
    pub cache: &'static str,
    pub seconds: f64,
    pub build_seconds: f64,
    pub system_modes: usize,
    pub estimated_error: f64,
    pub modes_per_part: serde_json::Value,
    pub parts: Vec<crate::reduce::rom::PartInfo>,
    pub left_out: Vec<String>,
    pub cache_file: Option<String>,
    pub first_frequencies_hz: Vec<f64>,
    /// Every system mode's frequency below half the cut-off \[Hz\] (where the reduction is
    /// accurate: what two reductions of one engine are compared on).
    pub frequencies_below_half_cutoff_hz: Vec<f64>,
    /// Interfaces, points and materials found on imported meshes (absent for generated ones).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interfaces: Option<crate::mesh::find::FoundInterfaces>,
    /// How the crankcase was cut for its reduction (absent when reduced in one piece):
    /// [`crate::scene::budget::Split::substructured`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub substructured: Option<crate::scene::budget::Split>,
    /// The warnings said while the ROM was built (kept with a cached ROM).
    pub warnings: Vec<String>,
}

impl RomReport {
    pub fn new(l: &LoadedRom) -> Self {
        let i = &l.rom.info;
        let mut per = serde_json::Map::new();
        for p in &i.parts {
            per.insert(p.name.clone(), serde_json::json!(p.stats.normal_modes));
        }
        Self {
            full_dofs: i.full_dofs,
            reduced_dofs: i.reduced_dofs,
            cutoff_hz: i.cutoff_hz,
            band_hz: i.band_hz,
            cache: l.cache,
            seconds: l.seconds,
            build_seconds: i.build_seconds,
            system_modes: i.system_modes,
            estimated_error: i.estimated_error,
            modes_per_part: serde_json::Value::Object(per),
            parts: i.parts.clone(),
            left_out: i.left_out.clone(),
            cache_file: l.cache_file.as_ref().map(|p| p.display().to_string()),
            first_frequencies_hz: l.rom.frequencies_hz.iter().take(20).copied().collect(),
            frequencies_below_half_cutoff_hz: l
                .rom
                .frequencies_hz
                .iter()
                .copied()
                .filter(|&f| f < 0.5 * i.cutoff_hz)
                .collect(),
            interfaces: i.interfaces.clone(),
            substructured: None,
            warnings: i.warnings.clone(),
        }
    }

    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "engine ROM ({} cache, {:.2} s; built in {:.1} s)",
            self.cache, self.seconds, self.build_seconds
        );
        let _ = writeln!(s, "  full DOFs        {}", self.full_dofs);
        let _ = writeln!(s, "  reduced DOFs     {}", self.reduced_dofs);
        let _ = writeln!(
            s,
            "  band / cut-off   {:.0} Hz / {:.0} Hz",
            self.band_hz, self.cutoff_hz
        );
        let _ = writeln!(
            s,
            "  system modes     {} below the cut-off",
            self.system_modes
        );
        for p in &self.parts {
            let st = &p.stats;
            let _ = writeln!(
                s,
                "  {:<10} x{}  {} DOFs -> {} interface + {} modes (<= {:.0} Hz) + {} attachment, {}",
                p.name, p.copies, st.full_dofs, st.constraint_modes, st.normal_modes, st.highest_mode_hz, st.attachment_modes,
                match p.source {
                    crate::reduce::part_cache::Source::Reduced => format!("{:.1} s", st.seconds),
                    crate::reduce::part_cache::Source::Cached => "from the component cache".to_string(),
                }
            );
        }
        let _ = writeln!(
            s,
            "  estimated error  {:.2e} (relative frequency change in the band at 2/3 cut-off)",
            self.estimated_error
        );
        for l in &self.left_out {
            let _ = writeln!(s, "  left out: {l}");
        }
        let f: Vec<String> = self
            .first_frequencies_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        let _ = writeln!(s, "  first modes [Hz]: {}", f.join(", "));
        if let Some(c) = &self.substructured {
            let _ = writeln!(
                s,
                "  crankcase in {} components: {} shapes per cut (every DOF of a cut with at most {}), components' modes to {} x the cut-off",
                c.components,
                c.cut_shapes,
                c.cut_shapes.saturating_mul(2).saturating_add(16),
                c.cutoff_factor
            );
            if c.enrichment > 0 {
                let _ = writeln!(
                    s,
                    "  cut shapes enriched: up to {} added per cut from a first assembly's imbalance (rom.cut_enrichment)",
                    c.enrichment
                );
            }
            // the estimated error above is the modal truncation's alone
            let _ = writeln!(
                s,
                "  the estimated error does not count the cuts' (measured on the default engine in 3 components: 3.3e-4 median, 5.1e-3 worst with 200 shapes per cut; 2.1e-5 worst with 100 added by rom.cut_enrichment; docs/physics.md)"
            );
        }
        if let Some(found) = &self.interfaces {
            s.push_str(&interfaces_text(found));
        }
        // a build's warnings went to standard error then; a cached ROM's are told here
        if self.cache == "hit" {
            for w in &self.warnings {
                let _ = writeln!(s, "  warning of its build: {w}");
            }
        }
        s
    }
}

/// What was found on imported meshes, one line per set.
pub fn interfaces_text(f: &crate::mesh::find::FoundInterfaces) -> String {
    use std::fmt::Write;
    let mut s = String::from("  imported meshes:\n");
    for m in &f.materials {
        let _ = writeln!(s, "    material  {m}");
    }
    if let Some(l) = &f.liner {
        let _ = writeln!(
            s,
            "    liner     bore r {:.3} mm, outer r {:.3} mm, pilot r {:.3} mm, flange r {:.3} mm, length {:.3} mm, seat at {:.3} mm",
            l.inner_radius * 1e3,
            l.outer_radius * 1e3,
            l.pilot_radius * 1e3,
            l.flange_radius * 1e3,
            l.length * 1e3,
            l.seat_z * 1e3
        );
    }
    if let Some([g0, g1]) = f.guide_band {
        let _ = writeln!(
            s,
            "    guide     z {:.3}..{:.3} mm (liner frame)",
            g0 * 1e3,
            g1 * 1e3
        );
    }
    if f.liner_turn != 0.0 {
        let _ = writeln!(
            s,
            "    liner turned by {:.4} deg about its axis: a column of its bore's nodes on the thrust line",
            f.liner_turn.to_degrees()
        );
    }
    if f.crankcase_shift_z != 0.0 {
        let _ = writeln!(
            s,
            "    crankcase moved by {:.3} mm along z to seat the liners",
            f.crankcase_shift_z * 1e3
        );
    }
    if f.crankcase_shift_xy != [0.0; 2] {
        let _ = writeln!(
            s,
            "    crankcase moved by ({:.4}, {:.4}) mm across to centre its bores on the liners' axes",
            f.crankcase_shift_xy[0] * 1e3,
            f.crankcase_shift_xy[1] * 1e3
        );
    }
    for set in &f.sets {
        let _ = writeln!(
            s,
            "    {:<9} {:<16} {:>6} nodes  {:<8} {}",
            set.part, set.name, set.nodes, set.source, set.detail
        );
    }
    s
}

pub use crate::reduce::rom::ShapeMode;

/// `shapes` JSON: per system mode, the normalised thrust-side radial amplitude at each
/// cylinder's analysis points (cylinder-major, points top to bottom).
#[derive(serde::Serialize)]
pub struct ShapesReport {
    pub modes: Vec<ShapeMode>,
    pub cylinders: Vec<usize>,
    pub cache: &'static str,
}

impl ShapesReport {
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "mode-shape coefficients (radial, thrust side; rows: cylinders {}; columns: points top to bottom)",
            crate::text::joined(&self.cylinders, ", ")
        );
        for m in &self.modes {
            let _ = writeln!(s, "{:9.1} Hz", m.frequency_hz);
            for (c, row) in self.cylinders.iter().zip(&m.coefficients) {
                let v: Vec<String> = row.iter().map(|x| format!("{x:+.3}")).collect();
                let _ = writeln!(s, "   cyl {c}: {}", v.join("  "));
            }
        }
        s
    }
}

/// `rom --component I/N|auto`: one component's reduction into the component cache
/// ([`crate::reduce::scene_rom::reduce_component`]); `I/N` parsed as a sweep's shard, `auto`
/// from the scheduler's environment.
pub fn reduce_component(
    scene: &Scene,
    opts: &crate::reduce::scene_rom::CacheOptions,
    arg: &str,
) -> Result<crate::reduce::scene_rom::ComponentDone> {
    use crate::scene::design::Shard;
    let names = crate::reduce::rom::component_names(scene.rom.crankcase_components);
    let count = names.len();
    let task = if arg == "auto" {
        Shard::from_env_as(
            &crate::scene::design::scheduler_var,
            (Some(count), "the engine's components"),
            "--component",
        )?.ok_or_else(|| {
            Error::Argument {
                flag: "--component auto".into(),
                msg: format!("no scheduler task in the environment (SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX): give --component I/{count}"),
            }
        })?
    } else {
        Shard::parse("--component", arg)?
    };
    if task.count != count {
        return Err(Error::Argument {
            flag: format!("{}: --component", scene.path.display()),
            msg: format!(
                "the engine has {count} components ({}), the task names {} (an array of {count} tasks is needed)",
                names.join(", "),
                task.count
            ),
        });
    }
    Ok(crate::reduce::scene_rom::reduce_component(
        scene, opts, task.index,
    )?)
}

/// Text of a component task's outcome.
pub fn component_text(d: &crate::reduce::scene_rom::ComponentDone) -> String {
    format!(
        "component {}/{} ({}): {} DOFs -> {} reduced, {} in {:.1} s\n",
        d.index,
        d.count,
        d.component,
        d.full_dofs,
        d.reduced_dofs,
        match d.source {
            crate::reduce::part_cache::Source::Reduced => "reduced into the component cache",
            crate::reduce::part_cache::Source::Cached => "already in the component cache",
        },
        d.seconds
    )
}
