//! VTK XML unstructured grid (.vtu, ASCII) with mode shapes as point vectors, for ParaView.
//! Quadratic cells are written as VTK_QUADRATIC_TETRA (24) and VTK_QUADRATIC_HEXAHEDRON (25),
//! with the mid-edge nodes reordered from Gmsh's to VTK's convention.

use crate::fem::shape::ElementKind;
use crate::mesh::Mesh;
use std::io::Write;

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
