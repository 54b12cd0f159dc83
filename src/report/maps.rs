//! The liner maps as figures and data: `liner_maps.png` (each liner's wet outer surface
//! unrolled, circumferential angle against depth below the liner top, coloured by the mean
//! peak negative acceleration, one panel per cylinder, the analysis points marked) and
//! `liner_maps.vtu` (the surfaces in engine coordinates with the map's point fields, for
//! ParaView).

use crate::cavitation::maps::LinerMap;
use crate::fem::surface::boundary_faces;
use crate::files::{write_atomic, WriteError};
use crate::mesh::liner::COOLANT_WETTED;
use crate::mesh::Mesh;
use crate::report::png::write_png;
use plotters::prelude::*;
use std::collections::HashMap;
use std::path::Path;

/// Where a liner's surface nodes lie: per node of the map (in [`LinerMap::nodes`]' order)
/// its liner-frame position, circumferential angle theta = atan2(y, x) \[deg, 0..360\]
/// (thrust side +y at 90) and depth below the liner top \[mm\]; the faces of `coolant_wetted`
/// by their corners (indices into the nodes); the analysis points' angle and depth.
pub struct SurfaceGeometry {
    pub xyz: Vec<[f64; 3]>,
    pub theta_deg: Vec<f64>,
    pub depth_mm: Vec<f64>,
    pub faces: Vec<Vec<usize>>,
    pub points: Vec<(f64, f64)>,
}

impl SurfaceGeometry {
    /// The geometry of `nodes` (a map's) on the liner `mesh`; the analysis points from its
    /// sets `point_1` .. `point_{analysis_points}` (those it has).
    pub fn new(mesh: &Mesh, nodes: &[usize], analysis_points: usize) -> Self {
        let top = mesh
            .nodes
            .iter()
            .map(|p| p[2])
            .fold(f64::NEG_INFINITY, f64::max);
        let place = |p: [f64; 3]| {
            (
                p[1].atan2(p[0]).to_degrees().rem_euclid(360.0),
                (top - p[2]) * 1e3,
            )
        };
        let index: HashMap<usize, usize> = nodes.iter().enumerate().map(|(i, &n)| (n, i)).collect();
        let faces = boundary_faces(mesh, COOLANT_WETTED)
            .unwrap_or_default()
            .into_iter()
            .filter_map(|f| {
                f.corners
                    .iter()
                    .map(|&a| index.get(&f.nodes[a]).copied())
                    .collect::<Option<Vec<usize>>>()
            })
            .collect();
        let points = (1..=analysis_points)
            .filter_map(|k| mesh.node_set(&format!("point_{k}"))?.first().copied())
            .map(|n| place(mesh.nodes[n]))
            .collect();
        let (theta_deg, depth_mm) = nodes.iter().map(|&n| place(mesh.nodes[n])).unzip();
        SurfaceGeometry {
            xyz: nodes.iter().map(|&n| mesh.nodes[n]).collect(),
            theta_deg,
            depth_mm,
            faces,
            points,
        }
    }
}

/// A perceptually ordered colour scale (viridis, linear between eight anchors) at u in [0, 1].
fn viridis(u: f64) -> RGBColor {
    const ANCHORS: [(u8, u8, u8); 8] = [
        (68, 1, 84),
        (70, 50, 127),
        (54, 92, 141),
        (39, 127, 142),
        (31, 161, 135),
        (74, 194, 109),
        (159, 218, 58),
        (253, 231, 37),
    ];
    let x = u.clamp(0.0, 1.0) * (ANCHORS.len() - 1) as f64;
    let i = (x.floor() as usize).min(ANCHORS.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (ANCHORS[i], ANCHORS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// `liner_maps.png`: per cylinder (panels in `maps`' order) the unrolled wet surface, each face
/// filled with the mean of its corners' mean peak negative acceleration on one colour scale
/// for all panels (0 to the largest node value), the analysis points as white rings, and a
/// colour bar with the Ca = 1 threshold `threshold` \[m/s^2\].
pub fn write_maps_png(
    path: &Path,
    maps: &[LinerMap],
    geometry: &[SurfaceGeometry],
    threshold: f64,
) -> Result<(), WriteError> {
    let top = maps
        .iter()
        .flat_map(|m| m.peak_negative_m_s2.iter().copied())
        .fold(0.0, f64::max)
        .max(1e-9);
    let cols = maps.len().clamp(1, 3);
    let rows = maps.len().div_ceil(cols).max(1);
    let size = (520 * cols as u32 + 150, 360 * rows as u32 + 60);
    write_png(path, size, |root| {
        let (title, body) = root.split_vertically(50);
        title.titled(
            "Liner maps: mean peak negative acceleration over the wet outer surface (unrolled; white rings: analysis points)",
            ("sans-serif", 20),
        )?;
        let (panels, bar) = body.split_horizontally(520 * cols as u32);
        for ((m, g), area) in maps
            .iter()
            .zip(geometry)
            .zip(panels.split_evenly((rows, cols)))
        {
            draw_panel(&area, m, g, top)?;
        }
        draw_colour_bar(&bar, top, threshold)?;
        Ok(())
    })
}

/// One cylinder's unrolled surface.
fn draw_panel(
    area: &crate::report::png::Area<'_>,
    m: &LinerMap,
    g: &SurfaceGeometry,
    top: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let deepest = g.depth_mm.iter().copied().fold(0.0, f64::max).max(1.0);
    let shallowest = g.depth_mm.iter().copied().fold(deepest, f64::min);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("cylinder {} ({} cycles)", m.cylinder, m.cycles),
            ("sans-serif", 16),
        )
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..360.0, -deepest..-shallowest)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("angle from +x [deg] (thrust side 90)")
        .y_desc("depth below liner top [mm]")
        .y_label_formatter(&|v| format!("{:.0}", -v))
        .x_labels(9)
        .draw()?;
    let colour = |v: f64| viridis(v / top);
    for f in &g.faces {
        let value = f.iter().map(|&i| m.peak_negative_m_s2[i]).sum::<f64>() / f.len() as f64;
        let thetas: Vec<f64> = f.iter().map(|&i| g.theta_deg[i]).collect();
        let seam = thetas.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - thetas.iter().copied().fold(f64::INFINITY, f64::min)
            > 180.0;
        // a face across the 0/360 seam is drawn at both ends, clamped to the range
        let shifts: &[f64] = if seam { &[0.0, -360.0] } else { &[0.0] };
        for &shift in shifts {
            let pts: Vec<(f64, f64)> = f
                .iter()
                .map(|&i| {
                    let t = g.theta_deg[i]
                        + if seam && g.theta_deg[i] < 180.0 {
                            360.0
                        } else {
                            0.0
                        };
                    ((t + shift).clamp(0.0, 360.0), -g.depth_mm[i])
                })
                .collect();
            chart.draw_series(std::iter::once(Polygon::new(pts, colour(value).filled())))?;
        }
    }
    chart.draw_series(
        g.points
            .iter()
            .map(|&(t, d)| Circle::new((t, -d), 5, ShapeStyle::from(&WHITE).stroke_width(2))),
    )?;
    Ok(())
}

/// The colour bar: 0 .. `top` \[m/s^2\] with the Ca = 1 threshold drawn across it.
fn draw_colour_bar(
    area: &crate::report::png::Area<'_>,
    top: f64,
    threshold: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut chart = ChartBuilder::on(area)
        .caption("m/s^2", ("sans-serif", 14))
        .margin_top(30)
        .margin_bottom(50)
        .margin_left(10)
        .margin_right(60)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, 0.0..top)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(8)
        .y_label_style(("sans-serif", 13))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .draw()?;
    let steps = 100;
    chart.draw_series((0..steps).map(|k| {
        let (a, b) = (
            k as f64 / steps as f64 * top,
            (k + 1) as f64 / steps as f64 * top,
        );
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            viridis((a + b) / (2.0 * top)).filled(),
        )
    }))?;
    if threshold > 0.0 && threshold < top {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.0, threshold), (1.0, threshold)],
            ShapeStyle::from(&RED).stroke_width(3),
        )))?;
        chart.draw_series(std::iter::once(Text::new(
            "Ca = 1",
            (0.05, threshold),
            ("sans-serif", 14).into_font().color(&RED),
        )))?;
    }
    Ok(())
}

/// `liner_maps.vtu`: every cylinder's wet surface (faces by their corners: VTK quads or
/// triangles, polygons otherwise) in engine coordinates (the liner frame moved to the
/// cylinder's axis `axis_x[k]` \[m\]), with the point fields `peak_negative_m_s2`,
/// `peak_negative_se_m_s2`, `ca`, `ca_se`, `cavitating_fraction`, `cavitating_fraction_se`
/// and `cylinder`.
pub fn write_maps_vtu(
    path: &Path,
    maps: &[LinerMap],
    geometry: &[SurfaceGeometry],
    axis_x: &[f64],
) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        let points: usize = geometry.iter().map(|g| g.xyz.len()).sum();
        let cells: usize = geometry.iter().map(|g| g.faces.len()).sum();
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
        )?;
        writeln!(
            w,
            "<UnstructuredGrid>\n<Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">"
        )?;
        writeln!(w, "<PointData Scalars=\"peak_negative_m_s2\">")?;
        type Field = fn(&LinerMap) -> &Vec<f64>;
        let fields: [(&str, Field); 6] = [
            ("peak_negative_m_s2", |m| &m.peak_negative_m_s2),
            ("peak_negative_se_m_s2", |m| &m.peak_negative_se_m_s2),
            ("ca", |m| &m.ca),
            ("ca_se", |m| &m.ca_se),
            ("cavitating_fraction", |m| &m.cavitating_fraction),
            ("cavitating_fraction_se", |m| &m.cavitating_fraction_se),
        ];
        for (name, field) in fields {
            writeln!(
                w,
                "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
            )?;
            for m in maps {
                for v in field(m) {
                    writeln!(w, "{v:e}")?;
                }
            }
            writeln!(w, "</DataArray>")?;
        }
        writeln!(
            w,
            "<DataArray type=\"Int32\" Name=\"cylinder\" format=\"ascii\">"
        )?;
        for (m, g) in maps.iter().zip(geometry) {
            for _ in &g.xyz {
                writeln!(w, "{}", m.cylinder)?;
            }
        }
        writeln!(w, "</DataArray>\n</PointData>")?;
        writeln!(
            w,
            "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
        )?;
        for (g, &x0) in geometry.iter().zip(axis_x) {
            for p in &g.xyz {
                writeln!(w, "{:e} {:e} {:e}", x0 + p[0], p[1], p[2])?;
            }
        }
        writeln!(w, "</DataArray>\n</Points>\n<Cells>")?;
        writeln!(
            w,
            "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
        )?;
        let mut base = 0;
        for g in geometry {
            for f in &g.faces {
                let ids: Vec<String> = f.iter().map(|&i| (base + i).to_string()).collect();
                writeln!(w, "{}", ids.join(" "))?;
            }
            base += g.xyz.len();
        }
        writeln!(
            w,
            "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
        )?;
        let mut off = 0;
        for f in geometry.iter().flat_map(|g| &g.faces) {
            off += f.len();
            writeln!(w, "{off}")?;
        }
        writeln!(
            w,
            "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
        )?;
        for f in geometry.iter().flat_map(|g| &g.faces) {
            let t = match f.len() {
                3 => 5,
                4 => 9,
                _ => 7,
            };
            writeln!(w, "{t}")?;
        }
        writeln!(
            w,
            "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>"
        )?;
        Ok(())
    })
}

/// One liner map in a line: where its largest mean peak lies and how much of the wet surface
/// is past the Ca = 1 threshold.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MapSummary {
    pub cylinder: usize,
    /// Wet-surface nodes mapped.
    pub nodes: usize,
    /// The node with the largest mean peak negative acceleration: its angle from +x \[deg\]
    /// (thrust side 90), depth below the liner top \[mm\], and its map values.
    pub hottest_theta_deg: f64,
    pub hottest_depth_mm: f64,
    pub peak_negative_m_s2: f64,
    pub peak_negative_se_m_s2: f64,
    pub ca: f64,
    pub ca_se: f64,
    pub cavitating_fraction: f64,
    pub cavitating_fraction_se: f64,
    /// Share of the nodes whose mean peak gives Ca < 1.
    pub share_ca_below_1: f64,
}

impl MapSummary {
    /// The summary of map `m` on its geometry `g`.
    pub fn of(m: &LinerMap, g: &SurfaceGeometry) -> Option<Self> {
        let i = (0..m.nodes.len())
            .max_by(|&a, &b| m.peak_negative_m_s2[a].total_cmp(&m.peak_negative_m_s2[b]))?;
        Some(MapSummary {
            cylinder: m.cylinder,
            nodes: m.nodes.len(),
            hottest_theta_deg: g.theta_deg[i],
            hottest_depth_mm: g.depth_mm[i],
            peak_negative_m_s2: m.peak_negative_m_s2[i],
            peak_negative_se_m_s2: m.peak_negative_se_m_s2[i],
            ca: m.ca[i],
            ca_se: m.ca_se[i],
            cavitating_fraction: m.cavitating_fraction[i],
            cavitating_fraction_se: m.cavitating_fraction_se[i],
            share_ca_below_1: m.ca.iter().filter(|&&c| c < 1.0).count() as f64
                / m.nodes.len() as f64,
        })
    }
}
