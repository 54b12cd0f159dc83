//! The full coupled engine model's modes of a scene (the reference of `modes --assembly
//! --full` and `rom-tradeoff`), and engine mode shapes written as VTU for ParaView.

use crate::eigen::modal::certified_modes;
use crate::error::{Error, Result};
use crate::fem::dofs::DofMap;
use crate::files::write_atomic;
use crate::mesh::Mesh;
pub use crate::reduce::full::recover_shapes;
use crate::reduce::full::{FullModes, FullSystem};
use crate::reduce::rom::RomBuild;
use crate::reduce::scene_rom::{load_meshes, rom_inputs};
use crate::report::vtu;
use crate::scene::Scene;
use std::path::Path;

/// Mode shapes of the engine's part instances on their meshes: liners of the modelled
/// `cylinders` (placed at `axis_x`), then the crankcase; `shapes[mode][instance]` in each
/// instance's free-DOF order.
#[derive(Clone, Copy)]
struct EngineShapes<'a> {
    cylinders: &'a [usize],
    axis_x: &'a [f64],
    liner: &'a Mesh,
    crankcase: &'a Mesh,
    dofs: &'a [&'a DofMap],
    shapes: &'a [Vec<Vec<f64>>],
    freqs: &'a [f64],
}

/// Builds and solves the full coupled model of a scene for `count` modes.
pub fn run(scene: &Scene, count: usize, vtu_path: Option<&Path>) -> Result<FullModes> {
    let (lm, cm) = load_meshes(scene)?;
    let inp = rom_inputs(scene, &lm, &cm, false);
    let sys = FullSystem::build(&inp)?;
    let sigma = scene.solver.sigma();
    let (sol, _) = certified_modes(
        &sys.km,
        &sys.analysis,
        count,
        sigma,
        scene.solver.guard_modes,
    )?;
    let shapes: Vec<Vec<Vec<f64>>> = (0..sol.modes.count())
        .map(|j| sys.part_displacements(sol.modes.vector(j)))
        .collect();
    let out = FullModes {
        frequencies_hz: (0..sol.modes.count())
            .map(|j| sol.modes.frequency_hz(j))
            .collect(),
        residuals: sol.residuals.clone(),
        sturm_ok: sol.sturm.as_ref().map(|s| s.ok).unwrap_or(false),
        dofs: sys.dofs(),
        shapes,
    };
    if let Some(path) = vtu_path {
        write_engine_vtu(
            path,
            &EngineShapes {
                cylinders: &inp.cylinders,
                axis_x: &inp.axis_x,
                liner: &lm,
                crankcase: &cm,
                dofs: &sys.dof_maps(),
                shapes: &out.shapes,
                freqs: &out.frequencies_hz,
            },
        )?;
    }
    Ok(out)
}

/// Writes coupled mode shapes on the placed meshes (liners of the modelled cylinders, then the
/// crankcase) as one VTU file. `shapes[mode][instance]` are in each instance's free-DOF order.
fn write_engine_vtu(path: &Path, e: &EngineShapes<'_>) -> Result<()> {
    let EngineShapes {
        cylinders,
        axis_x,
        liner: lm,
        crankcase: cm,
        dofs,
        shapes,
        freqs,
    } = *e;
    let mut meshes = Vec::new();
    for &cyl in cylinders {
        let mut m = lm.clone();
        for p in m.nodes.iter_mut() {
            p[0] += axis_x[cyl - 1];
        }
        m.node_sets.clear();
        m.element_sets.clear();
        meshes.push(m);
    }
    let mut c = cm.clone();
    c.node_sets.clear();
    c.element_sets.clear();
    meshes.push(c);
    // concatenate without merging (parts touch but are separate bodies)
    let mut all = Mesh::default();
    let mut node_off = Vec::new();
    for m in &meshes {
        node_off.push(all.nodes.len());
        let off = all.nodes.len();
        all.nodes.extend_from_slice(&m.nodes);
        for b in &m.blocks {
            let conn = b.conn.iter().map(|&n| n + off);
            match all.blocks.iter_mut().find(|x| x.kind == b.kind) {
                Some(x) => x.conn.extend(conn),
                None => all.blocks.push(crate::mesh::ElementBlock {
                    kind: b.kind,
                    conn: conn.collect(),
                }),
            }
        }
    }
    let fields: Vec<Vec<f64>> = shapes
        .iter()
        .map(|per| {
            let mut v = vec![0.0; 3 * all.nodes.len()];
            for (inst, u) in per.iter().enumerate() {
                let full = dofs[inst].expand(u);
                let o = 3 * node_off[inst];
                v[o..o + full.len()].copy_from_slice(&full);
            }
            v
        })
        .collect();
    let named: Vec<vtu::Field<'_>> = fields
        .iter()
        .zip(freqs)
        .enumerate()
        .map(|(j, (v, f))| vtu::Field {
            name: format!("mode_{:02}_{:.1}Hz", j + 1, f),
            values: v,
        })
        .collect();
    write_atomic(path, |w| vtu::write(&all, &named, w))?;
    Ok(())
}

/// Writes the first `count` ROM system modes recovered on the meshes.
pub fn write_vtu(
    path: &Path,
    scene: &Scene,
    lm: &Mesh,
    cm: &Mesh,
    b: &RomBuild,
    count: usize,
) -> Result<()> {
    let axis_x: Vec<f64> = (0..scene.engine.cylinders)
        .map(|c| {
            (c as f64 - (scene.engine.cylinders as f64 - 1.0) / 2.0) * scene.engine.cylinder_pitch
        })
        .collect();
    let shapes = recover_shapes(b, count)
        .ok_or_else(|| Error::Failure("the ROM build did not keep its bases".into()))?;
    let dofs: Vec<&DofMap> = b
        .liner_maps
        .iter()
        .map(|_| &b.liner.dofs)
        .chain(std::iter::once(&b.crankcase.dofs))
        .collect();
    let cyls: Vec<usize> = b.rom.cylinders.iter().map(|c| c.cylinder).collect();
    write_engine_vtu(
        path,
        &EngineShapes {
            cylinders: &cyls,
            axis_x: &axis_x,
            liner: lm,
            crankcase: cm,
            dofs: &dofs,
            shapes: &shapes,
            freqs: &b.rom.frequencies_hz[..count],
        },
    )
}
