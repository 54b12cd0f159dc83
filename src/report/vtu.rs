//! VTK XML unstructured grid (.vtu, ASCII) with mode shapes as point vectors, for ParaView.
//! Quadratic cells are written as VTK_QUADRATIC_TETRA (24) and VTK_QUADRATIC_HEXAHEDRON (25),
//! with the mid-edge nodes reordered from Gmsh's to VTK's convention.

use crate::fem::dofs::DofMap;
use crate::files::{write_atomic, WriteError};
use crate::mesh::{ElementBlock, Mesh};
use crate::scene::spec::ElementKind;
use std::io::Write;
use std::path::Path;

fn vtk_type(kind: ElementKind) -> u8 {
    match kind {
        ElementKind::Tet4 => 10,
        ElementKind::Tet10 => 24,
        ElementKind::Hex8 => 12,
        ElementKind::Hex20 => 25,
    }
}

/// For each VTK node slot, our (Gmsh) node index.
fn vtk_order(kind: ElementKind) -> &'static [usize] {
    match kind {
        ElementKind::Tet4 => &[0, 1, 2, 3],
        ElementKind::Tet10 => &[0, 1, 2, 3, 4, 5, 6, 7, 9, 8],
        ElementKind::Hex8 => &[0, 1, 2, 3, 4, 5, 6, 7],
        ElementKind::Hex20 => &[
            0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
        ],
    }
}

/// A named nodal vector field (3 components per node).
pub struct Field<'a> {
    pub name: String,
    pub values: &'a [f64],
}

/// Writes the mesh with nodal vector fields.
pub fn write(mesh: &Mesh, fields: &[Field], w: &mut dyn Write) -> std::io::Result<()> {
    let ne = mesh.num_elements();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(
        w,
        "<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{ne}\">",
        mesh.nodes.len()
    )?;
    writeln!(w, "<PointData>")?;
    for f in fields {
        writeln!(
            w,
            "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">",
            f.name
        )?;
        for v in f.values.chunks(3) {
            writeln!(w, "{:e} {:e} {:e}", v[0], v[1], v[2])?;
        }
        writeln!(w, "</DataArray>")?;
    }
    writeln!(w, "</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">")?;
    for x in &mesh.nodes {
        writeln!(w, "{:e} {:e} {:e}", x[0], x[1], x[2])?;
    }
    writeln!(w, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">")?;
    let mut offsets = Vec::with_capacity(ne);
    let mut types = Vec::with_capacity(ne);
    let mut off = 0;
    for (kind, nodes) in mesh.elements() {
        let line: Vec<String> = vtk_order(kind)
            .iter()
            .map(|&a| nodes[a].to_string())
            .collect();
        writeln!(w, "{}", line.join(" "))?;
        off += nodes.len();
        offsets.push(off);
        types.push(vtk_type(kind));
    }
    writeln!(
        w,
        "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    for o in offsets {
        writeln!(w, "{o}")?;
    }
    writeln!(
        w,
        "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    )?;
    for t in types {
        writeln!(w, "{t}")?;
    }
    writeln!(
        w,
        "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>"
    )
}

/// Writes one part's mode shapes on its mesh as one VTU file: field j is mode j's free-DOF
/// vector `shapes[j]` expanded to every node (fixed DOFs zero), named with its frequency.
pub fn write_part_modes(
    path: &Path,
    mesh: &Mesh,
    dofs: &DofMap,
    shapes: &[&[f64]],
    freqs: &[f64],
) -> Result<(), WriteError> {
    let full: Vec<Vec<f64>> = shapes.iter().map(|u| dofs.expand(u)).collect();
    write_mode_fields(path, mesh, &full, freqs)
}

/// Writes nodal mode shapes `fields` (3 values per node) on `mesh` as one VTU file, field j
/// named with its number and frequency `freqs[j]`.
fn write_mode_fields(
    path: &Path,
    mesh: &Mesh,
    fields: &[Vec<f64>],
    freqs: &[f64],
) -> Result<(), WriteError> {
    let named: Vec<Field<'_>> = fields
        .iter()
        .zip(freqs)
        .enumerate()
        .map(|(j, (v, f))| Field {
            name: format!("mode_{:02}_{:.1}Hz", j + 1, f),
            values: v,
        })
        .collect();
    write_atomic(path, |w| write(mesh, &named, w))?;
    Ok(())
}

/// Mode shapes of the engine's part instances on their meshes: liners of the modelled
/// `cylinders` (placed at `axis_x`), then the crankcase; `shapes[mode][instance]` in each
/// instance's free-DOF order.
#[derive(Clone, Copy)]
pub struct EngineShapes<'a> {
    pub cylinders: &'a [usize],
    pub axis_x: &'a [f64],
    pub liner: &'a Mesh,
    pub crankcase: &'a Mesh,
    pub dofs: &'a [&'a DofMap],
    pub shapes: &'a [Vec<Vec<f64>>],
    pub freqs: &'a [f64],
}

/// Writes coupled mode shapes on the placed meshes (liners of the modelled cylinders, then the
/// crankcase) as one VTU file. `shapes[mode][instance]` are in each instance's free-DOF order.
pub fn write_engine_modes(path: &Path, e: &EngineShapes<'_>) -> Result<(), WriteError> {
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
                None => all.blocks.push(ElementBlock {
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
    write_mode_fields(path, &all, &fields, freqs)
}
