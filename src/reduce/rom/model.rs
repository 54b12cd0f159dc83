//! The engine ROM as stored: per-cylinder rows, the residual flexibility, the build's record,
//! and the checks a loaded entry must pass.

use crate::reduce::cache::Invalid;
use crate::reduce::craig_bampton::CbStats;
use crate::reduce::engine::Dense;
use crate::reduce::part_cache::Source;

/// Reduced data of one modelled cylinder. Mode rows hold the displacement of mass-normalised
/// system modes along the stated direction.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CylinderRom {
    /// 1-based cylinder number.
    pub cylinder: usize,
    pub axis_x: f64,
    /// Heights of the bore-line nodes (ascending) on the thrust (+y) and anti-thrust (-y) side.
    pub thrust_z: Vec<f64>,
    pub antithrust_z: Vec<f64>,
    /// Outward radial displacement of the bore-line nodes (nodes x modes).
    pub thrust_modes: Dense,
    pub antithrust_modes: Dense,
    /// Liner analysis points, radial toward the coolant (+y), top to bottom (points x modes).
    pub point_modes: Dense,
    /// Crankcase jacket-wall points facing them (+y).
    pub crankcase_point_modes: Dense,
    /// Head-bolt preload displacement at the bore-line nodes and points \[m\].
    pub preload_thrust: Vec<f64>,
    pub preload_antithrust: Vec<f64>,
    pub preload_points: Vec<f64>,
    /// Residual flexibility of the dropped system modes between the analysis points and this
    /// cylinder's contact DOFs (points x (thrust, anti-thrust nodes)) [m/N]: the quasi-static
    /// part of a point's response to a contact force near it, u_p = phi_p . eta + R_pc F.
    pub point_residual: Dense,
    /// Offset of this cylinder's contact DOFs (thrust, then anti-thrust) in the residual
    /// flexibility matrix.
    pub contact_offset: usize,
    /// The liner's wet outer surface, for the liner maps (no nodes when the liner mesh has no
    /// `coolant_wetted` set).
    pub surface: SurfaceRows,
}

/// Rows of a liner's wet outer surface (node set `coolant_wetted`), each like an analysis
/// point's: u_n = phi_n . eta + R_nc F along the outward radial direction (x, y, 0) / r.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SurfaceRows {
    /// Liner mesh node of each row, ascending.
    pub nodes: Vec<usize>,
    /// Outward radial displacement of the modes (nodes x modes).
    pub modes: Dense,
    /// Residual flexibility to this cylinder's contact DOFs (nodes x contact DOFs) [m/N].
    pub residual: Dense,
}

/// Per-part summary.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PartInfo {
    pub name: String,
    pub stats: CbStats,
    /// How many copies of this reduction the engine uses.
    pub copies: usize,
    /// Reduced in the build, or read from the component cache.
    pub source: Source,
}

/// What the ROM holds and how it was made.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RomInfo {
    pub full_dofs: usize,
    pub reduced_dofs: usize,
    pub system_modes: usize,
    /// Residual vectors (pseudo-modes above the cut-off) of the contact load patterns,
    /// appended to the system modes ([`crate::reduce::engine::residual_vectors`]).
    pub residual_vectors: usize,
    pub band_hz: f64,
    pub cutoff_hz: f64,
    pub interface_harmonics: usize,
    pub parts: Vec<PartInfo>,
    pub build_seconds: f64,
    /// Largest relative change of a system frequency below the band when the part-mode
    /// cut-off is lowered to 2/3 of its value: an upper estimate of the truncation error.
    pub estimated_error: f64,
    pub left_out: Vec<String>,
    /// Interfaces, points and materials found on imported meshes (none for generated ones).
    pub interfaces: Option<crate::mesh::find::FoundInterfaces>,
    /// The warnings said while the meshes were read and the ROM built (decks against the
    /// scene, materials, constraints not applied), kept with a cached ROM.
    pub warnings: Vec<String>,
}

/// The cached engine reduced-order model.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EngineRom {
    /// System modes kept (below the cut-off), ascending, then the residual vectors' pseudo-modes
    /// (above the cut-off, ascending) \[Hz\].
    pub frequencies_hz: Vec<f64>,
    pub cylinders: Vec<CylinderRom>,
    /// Residual flexibility of the dropped modes at all contact DOFs [m/N].
    pub residual_flexibility: Dense,
    pub info: RomInfo,
}

impl EngineRom {
    /// Checks what a checksum cannot (a forged or mis-written file with a valid hash): at least
    /// one system mode, frequencies finite, non-negative and ascending within the system and
    /// the residual-vector groups, every matrix's dimensions consistent with the mode count and
    /// the contact DOFs, and every entry finite. Returns what is wrong.
    pub fn validate(&self) -> Result<(), Invalid> {
        let i = &self.info;
        let nm = self.frequencies_hz.len();
        if i.system_modes == 0 || nm != i.system_modes + i.residual_vectors {
            return Err(Invalid::ModeCount {
                frequencies: nm,
                system_modes: i.system_modes,
                residual_vectors: i.residual_vectors,
            });
        }
        let f = &self.frequencies_hz;
        if f.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(Invalid::Frequency);
        }
        let ascending = |s: &[f64]| s.windows(2).all(|w| w[0] <= w[1]);
        if !ascending(&f[..i.system_modes]) || !ascending(&f[i.system_modes..]) {
            return Err(Invalid::Order);
        }
        if self.cylinders.is_empty() {
            return Err(Invalid::NoCylinder);
        }
        let contact: usize = self
            .cylinders
            .iter()
            .map(|c| c.thrust_z.len() + c.antithrust_z.len())
            .sum();
        let square = &self.residual_flexibility;
        check_dense("residual flexibility", square, contact, contact)?;
        for c in &self.cylinders {
            let (nt, na) = (c.thrust_z.len(), c.antithrust_z.len());
            let np = c.point_modes.nrows();
            let at = |what: &str| format!("cylinder {}: {what}", c.cylinder);
            check_dense(&at("thrust modes"), &c.thrust_modes, nt, nm)?;
            check_dense(&at("anti-thrust modes"), &c.antithrust_modes, na, nm)?;
            check_dense(&at("point modes"), &c.point_modes, np, nm)?;
            let ncp = c.crankcase_point_modes.nrows();
            check_dense(
                &at("crankcase point modes"),
                &c.crankcase_point_modes,
                ncp,
                nm,
            )?;
            check_dense(&at("point residual"), &c.point_residual, np, nt + na)?;
            let ns = c.surface.nodes.len();
            check_dense(&at("surface modes"), &c.surface.modes, ns, nm)?;
            check_dense(&at("surface residual"), &c.surface.residual, ns, nt + na)?;
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            if c.preload_thrust.len() != nt
                || c.preload_antithrust.len() != na
                || c.preload_points.len() != np
                || !finite(&c.preload_thrust)
                || !finite(&c.preload_antithrust)
                || !finite(&c.preload_points)
                || !finite(&c.thrust_z)
                || !finite(&c.antithrust_z)
                || np == 0
                || nt == 0
                || na == 0
                || c.contact_offset + nt + na > contact
            {
                return Err(Invalid::CylinderRows(c.cylinder));
            }
        }
        Ok(())
    }
}

impl CylinderRom {
    /// Mode `j`'s displacement at contact DOF `a` (thrust nodes, then anti-thrust).
    pub fn contact_mode(&self, a: usize, j: usize) -> f64 {
        let nt = self.thrust_z.len();
        if a < nt {
            self.thrust_modes[[a, j]]
        } else {
            self.antithrust_modes[[a - nt, j]]
        }
    }

    /// The quasi-static response at `rows` (rows x modes: the point or surface mode rows) to
    /// this cylinder's contact forces of the ROM modes from `first` on [m/N] (rows x contact
    /// DOFs, thrust then anti-thrust):
    ///
    ///   S = sum_{j >= first} r_j c_j^T / omega_j^2,   omega_j = 2 pi `frequencies_hz`\[j\],
    ///
    /// r_j and c_j the j-th columns of `rows` and of the contact DOFs' mode rows. A window that
    /// integrates only the first `first` modes (`simulate --full-order` with
    /// `transient.mode_cutoff_hz`) adds S to the residual rows: the modes it drops respond
    /// statically, as in the contact's residual flexibility (the engine cycle sums the same
    /// through the dropped modes' quasi-static coordinates, with every cylinder's forces).
    pub fn static_part(&self, rows: &Dense, frequencies_hz: &[f64], first: usize) -> Dense {
        let nc = self.thrust_z.len() + self.antithrust_z.len();
        let mut s = Dense::zeros((rows.nrows(), nc));
        for (j, f) in frequencies_hz.iter().enumerate().skip(first) {
            let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
            for a in 0..nc {
                let ca = self.contact_mode(a, j) / w2;
                if ca == 0.0 {
                    continue;
                }
                for p in 0..rows.nrows() {
                    s[[p, a]] += rows[[p, j]] * ca;
                }
            }
        }
        s
    }
}

/// A stored matrix has the expected dimensions and finite entries.
pub(super) fn check_dense(what: &str, d: &Dense, rows: usize, cols: usize) -> Result<(), Invalid> {
    if d.nrows() != rows || d.ncols() != cols || !d.is_standard_layout() {
        return Err(Invalid::Shape {
            what: what.into(),
            rows: d.nrows(),
            cols: d.ncols(),
            want_rows: rows,
            want_cols: cols,
        });
    }
    if d.iter().any(|x| !x.is_finite()) {
        return Err(Invalid::NotFinite { what: what.into() });
    }
    Ok(())
}

/// One system mode, the normalised thrust-side radial amplitude at each
/// cylinder's analysis points (cylinder-major, points top to bottom).
#[derive(serde::Serialize)]
pub struct ShapeMode {
    pub frequency_hz: f64,
    pub coefficients: Vec<Vec<f64>>,
}

impl EngineRom {
    /// Mode-shape coefficients: c_{cyl,p} = phi(point) / max |phi(points)| over all cylinders and
    /// points of that mode (so the largest is +-1; the sign shows the phase between cylinders).
    pub fn shapes(&self) -> Vec<ShapeMode> {
        let rom = self;
        (0..rom.frequencies_hz.len())
            .map(|j| {
                let raw: Vec<Vec<f64>> = rom
                    .cylinders
                    .iter()
                    .map(|c| {
                        (0..c.point_modes.nrows())
                            .map(|p| c.point_modes[[p, j]])
                            .collect()
                    })
                    .collect();
                let max = raw.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
                ShapeMode {
                    frequency_hz: rom.frequencies_hz[j],
                    coefficients: raw
                        .into_iter()
                        .map(|r| r.into_iter().map(|v| v * scale).collect())
                        .collect(),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cylinder of `nt` + `na` contact DOFs, `np` points and `nm` modes with pseudo-random
    /// rows.
    fn cylinder(nt: usize, na: usize, np: usize, nm: usize) -> CylinderRom {
        let mut seed = 7u64;
        let mut rows = |r: usize| {
            Dense::from_shape_fn((r, nm), |_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
        };
        CylinderRom {
            cylinder: 1,
            axis_x: 0.0,
            thrust_z: vec![0.0; nt],
            antithrust_z: vec![0.0; na],
            thrust_modes: rows(nt),
            antithrust_modes: rows(na),
            point_modes: rows(np),
            crankcase_point_modes: rows(1),
            preload_thrust: vec![0.0; nt],
            preload_antithrust: vec![0.0; na],
            preload_points: vec![0.0; np],
            point_residual: Dense::zeros((np, nt + na)),
            contact_offset: 0,
            surface: SurfaceRows::default(),
        }
    }

    /// Verification: the static part of the modes from `first` on equals the matrix form
    /// Phi_p,d Omega_d^-2 Phi_c,d^T (the contact rows stacked thrust, then anti-thrust), and
    /// the kept modes' static flexibility plus it is the same for every cut (the points' static
    /// response does not depend on how many modes are integrated). Roundoff tolerance: sums of
    /// at most 9 products of O(1e-8) terms, 1e-12 relative.
    #[test]
    fn verification_static_part_of_dropped_modes_is_the_modal_sum() {
        let (nt, na, np, nm) = (5, 4, 3, 9);
        let c = cylinder(nt, na, np, nm);
        let f: Vec<f64> = (0..nm).map(|j| 1000.0 * (j + 1) as f64).collect();
        let w2: Vec<f64> = f
            .iter()
            .map(|f| (2.0 * std::f64::consts::PI * f).powi(2))
            .collect();
        let contact = ndarray::concatenate(
            ndarray::Axis(0),
            &[c.thrust_modes.view(), c.antithrust_modes.view()],
        )
        .unwrap();
        let whole = c.static_part(&c.point_modes, &f, 0);
        let scale = whole.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for first in 0..=nm {
            let scaled = Dense::from_shape_fn((np, nm), |(p, j)| {
                if j >= first {
                    c.point_modes[[p, j]] / w2[j]
                } else {
                    0.0
                }
            });
            let matrix_form = scaled.dot(&contact.t());
            let part = c.static_part(&c.point_modes, &f, first);
            let kept = &whole - &part;
            let kept_direct = Dense::from_shape_fn((np, nt + na), |(p, a)| {
                (0..first)
                    .map(|j| c.point_modes[[p, j]] * contact[[a, j]] / w2[j])
                    .sum::<f64>()
            });
            for ((x, y), (k, kd)) in part
                .iter()
                .zip(&matrix_form)
                .zip(kept.iter().zip(&kept_direct))
            {
                assert!((x - y).abs() <= 1e-12 * scale, "first {first}: {x} vs {y}");
                assert!(
                    (k - kd).abs() <= 1e-12 * scale,
                    "first {first}: {k} vs {kd}"
                );
            }
        }
        assert!(c
            .static_part(&c.point_modes, &f, nm)
            .iter()
            .all(|v| *v == 0.0));
    }
}
