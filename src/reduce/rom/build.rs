//! The ROM build: both parts reduced (or taken from the component cache), assembled over the
//! modelled cylinders, the system modes below the cut-off, the residual vectors of the contact
//! load patterns, the preload and the per-cylinder rows; the truncation error estimate.

use super::*;
use crate::reduce::craig_bampton::PartReduction;
use crate::reduce::engine::{
    self, assemble, hz, residual_flexibility, Dense, Placement, SystemModes,
};
use crate::reduce::part_cache::{reduce_cached, Source};
use faer::{Mat, MatRef};
use std::time::Instant;

/// A built ROM plus (on request) what is needed to recover full mode shapes.
pub struct RomBuild {
    pub rom: EngineRom,
    pub liner: PartReduction,
    pub crankcase: PartReduction,
    /// Global index of each liner coordinate, per modelled cylinder (same order as
    /// `rom.cylinders`), and of each crankcase coordinate.
    pub liner_maps: Vec<Vec<usize>>,
    pub crankcase_map: Vec<usize>,
    pub system: SystemModes,
}

/// Contact load patterns for the residual vectors: on each bore line (sides of `sides` nodes,
/// repeated for `cylinders`), hat functions w_i = max(0, 1 - |i - c| / e) centred every e =
/// `spacing` nodes and at the last node; e = 1 gives one unit load per node, e = 0 none.
pub fn hat_patterns(sides: &[usize], cylinders: usize, spacing: usize) -> Mat<f64> {
    let per: usize = sides.iter().sum();
    let rows = per * cylinders;
    let mut cols: Vec<Vec<(usize, f64)>> = Vec::new();
    if spacing > 0 {
        for c in 0..cylinders {
            let mut r0 = c * per;
            for &nn in sides {
                let mut centres: Vec<usize> = (0..nn).step_by(spacing).collect();
                if nn > 0 && centres.last() != Some(&(nn - 1)) {
                    centres.push(nn - 1);
                }
                for &cn in &centres {
                    let col = (0..nn)
                        .filter_map(|i| {
                            let w = 1.0 - (i as f64 - cn as f64).abs() / spacing as f64;
                            (w > 0.0).then_some((r0 + i, w))
                        })
                        .collect();
                    cols.push(col);
                }
                r0 += nn;
            }
        }
    }
    let mut p = Mat::<f64>::zeros(rows, cols.len());
    for (j, col) in cols.iter().enumerate() {
        for &(i, w) in col {
            p[(i, j)] = w;
        }
    }
    p
}

/// Global layout of the engine's reduced coordinates: the crankcase first, then per modelled
/// cylinder the liner's coordinates, its interface columns shared with the crankcase's.
pub(super) fn layout(
    liner: &PartReduction,
    crankcase: &PartReduction,
    cylinders: &[usize],
) -> (Vec<usize>, Vec<Vec<usize>>, usize) {
    let n_c = crankcase.size();
    let mut next = n_c;
    let mut liner_maps = Vec::new();
    for &cyl in cylinders {
        let c = cyl - 1;
        let mut map = vec![usize::MAX; liner.size()];
        for (b, cc_b) in [(0usize, 3 * c), (1, 3 * c + 1)] {
            for (lj, gj) in liner.interface_cols[b]
                .clone()
                .zip(crankcase.interface_cols[cc_b].clone())
            {
                map[lj] = gj;
            }
        }
        for slot in map.iter_mut() {
            if *slot == usize::MAX {
                *slot = next;
                next += 1;
            }
        }
        liner_maps.push(map);
    }
    ((0..n_c).collect(), liner_maps, next)
}

/// Rows `r0..r0 + nr` of a part's output matrix in global coordinates (columns scattered
/// through `map`).
pub(super) fn scatter_rows(
    rows: &Mat<f64>,
    map: &[usize],
    r0: usize,
    nr: usize,
    n_g: usize,
) -> Mat<f64> {
    let mut g = Mat::<f64>::zeros(nr, n_g);
    for i in 0..nr {
        for j in 0..rows.ncols() {
            g[(i, map[j])] += rows[(r0 + i, j)];
        }
    }
    g
}

/// The engine's modal basis: the `kept` system modes below the cut-off, then the residual
/// vectors of the contact load patterns (pseudo-modes above it) with their eigenvalues `mu`.
pub(super) struct Basis {
    kept: usize,
    mu: Vec<f64>,
    /// Global coordinates x (kept + residual) modes.
    modes: Mat<f64>,
    /// The residual vectors scaled by mu^-1/2: their static flexibility is (G Ys)(G Ys)^T.
    ys: Mat<f64>,
}

/// The basis from the system modes and W = F_d G_c^T, the dropped modes' flexibility at the
/// contact rows ([`SystemModes::dropped_flexibility`]).
pub(super) fn basis(
    sys: &SystemModes,
    kept: usize,
    w: MatRef<'_, f64>,
    patterns: &Mat<f64>,
) -> Result<Basis, RomError> {
    let n_g = sys.vectors.nrows();
    let (ya, mu) = engine::residual_vectors(sys, kept, w, patterns)?;
    let mut modes = Mat::<f64>::zeros(n_g, kept + mu.len());
    modes
        .as_mut()
        .subcols_mut(0, kept)
        .copy_from(sys.vectors.as_ref().subcols(0, kept));
    modes.as_mut().subcols_mut(kept, mu.len()).copy_from(&ya);
    let ys = Mat::from_fn(n_g, mu.len(), |i, j| ya[(i, j)] / mu[j].sqrt());
    Ok(Basis {
        kept,
        mu,
        modes,
        ys,
    })
}

/// The preload in global coordinates: the liners' clamp loads and the bolts' reactions.
pub(super) fn preload_vector(
    liner: &PartReduction,
    clamp_load: usize,
    liner_maps: &[Vec<usize>],
    crankcase: &PartReduction,
    n_g: usize,
) -> Mat<f64> {
    let mut f = Mat::<f64>::zeros(n_g, 1);
    for map in liner_maps {
        for j in 0..liner.size() {
            f[(map[j], 0)] += liner.loads[(j, clamp_load)];
        }
    }
    for l in 0..crankcase.loads.ncols() {
        for j in 0..crankcase.size() {
            f[(j, 0)] += crankcase.loads[(j, l)];
        }
    }
    f
}

/// Residual cross flexibility points x contact not carried by the modes:
/// G_p F_d G_c^T - (G_p Ys)(G_c Ys)^T, F_d the flexibility of the dropped system modes, with
/// `w` = F_d G_c^T (global x contact rows) and G_p / G_c the point / contact rows of `g_all`
/// (contact rows first).
pub(super) fn point_residual(
    g_all: &Mat<f64>,
    w: MatRef<'_, f64>,
    b: &Basis,
    ncon: usize,
) -> Dense {
    let np = g_all.nrows() - ncon;
    let gys = g_all * &b.ys;
    let r = g_all.as_ref().subrows(ncon, np) * w
        - gys.as_ref().subrows(ncon, np) * gys.as_ref().subrows(0, ncon).transpose();
    crate::linalg::dense::from_faer(&r)
}

/// What [`cylinder_rom`] needs of the assembled engine.
pub(super) struct Assembled<'a> {
    inp: &'a RomInputs<'a>,
    rows: &'a LinerRows,
    liner: &'a PartReduction,
    liner_maps: &'a [Vec<usize>],
    crankcase: &'a PartReduction,
    crankcase_map: &'a [usize],
    /// Global coordinates.
    n_g: usize,
    /// W = F_d G_c^T for every modelled cylinder's contact rows (cylinder-major columns).
    w: &'a Mat<f64>,
    basis: &'a Basis,
    /// The static preload displacement (global coordinates x 1).
    u0: &'a Mat<f64>,
}

/// One modelled cylinder's rows of the ROM: its liner's contact and point rows `g_all` (global
/// coordinates) projected on the modes, the crankcase's point rows, the preload.
pub(super) fn cylinder_rom(
    a: &Assembled<'_>,
    cyl: usize,
    g_all: &Mat<f64>,
    idx: usize,
) -> CylinderRom {
    let (inp, r) = (a.inp, a.rows);
    let (nt, na, np) = (r.thrust.len(), r.anti.len(), r.points.len());
    let offset = idx * (nt + na);
    let modes_rows = g_all * &a.basis.modes;
    let pre = g_all * a.u0;
    let c = cyl - 1;
    let n_g = a.n_g;
    let w = a.w.as_ref().subcols(idx * (nt + na), nt + na);
    let g_cc = scatter_rows(
        &a.crankcase.outputs,
        a.crankcase_map,
        c * inp.analysis_points,
        inp.analysis_points,
        n_g,
    );
    let cc_modes = &g_cc * &a.basis.modes;
    let sub = |r0: usize, nr: usize| {
        crate::linalg::dense::from_faer(&modes_rows.as_ref().subrows(r0, nr).to_owned())
    };
    let zs = |nodes: &[usize]| {
        nodes
            .iter()
            .map(|&n| inp.liner.nodes[n][2])
            .collect::<Vec<_>>()
    };
    let column = |r0: usize, nr: usize| (0..nr).map(|i| pre[(r0 + i, 0)]).collect();
    CylinderRom {
        cylinder: cyl,
        axis_x: inp.axis_x[c],
        thrust_z: zs(&r.thrust),
        antithrust_z: zs(&r.anti),
        thrust_modes: sub(0, nt),
        antithrust_modes: sub(nt, na),
        point_modes: sub(nt + na, np),
        crankcase_point_modes: crate::linalg::dense::from_faer(&cc_modes),
        preload_thrust: column(0, nt),
        preload_antithrust: column(nt, na),
        preload_points: column(nt + na, np),
        point_residual: point_residual(g_all, w, a.basis, nt + na),
        contact_offset: offset,
        surface: surface_rows(a, idx, g_all.as_ref().subrows(0, nt + na), w),
    }
}

/// A cylinder's wet-surface rows ([`SurfaceRows`]) from the liner's outputs after the points
/// (`G_s`, liner coordinates), gathered through the cylinder's map into global coordinates:
/// modes G_s Y, and the residual flexibility to the contact rows `g_c` as in
/// [`point_residual`], G_s [F_d g_c^T] - (G_s Ys)(g_c Ys)^T with `w` = F_d g_c^T (global x
/// contact rows).
pub(super) fn surface_rows(
    a: &Assembled<'_>,
    idx: usize,
    g_c: MatRef<'_, f64>,
    w: MatRef<'_, f64>,
) -> SurfaceRows {
    let r = a.rows;
    let ns = r.surface.len();
    if ns == 0 {
        return SurfaceRows {
            nodes: Vec::new(),
            modes: Dense::zeros((0, a.basis.modes.ncols())),
            residual: Dense::zeros((0, g_c.nrows())),
        };
    }
    let (map, outputs) = (&a.liner_maps[idx], &a.liner.outputs);
    let s0 = outputs.nrows() - ns;
    let gather = |m: MatRef<'_, f64>| Mat::from_fn(map.len(), m.ncols(), |i, j| m[(map[i], j)]);
    let g_s = outputs.as_ref().subrows(s0, ns);
    let modes = g_s * gather(a.basis.modes.as_ref());
    let gys_c = g_c * &a.basis.ys;
    let residual = g_s * gather(w) - (g_s * gather(a.basis.ys.as_ref())) * gys_c.transpose();
    SurfaceRows {
        nodes: r.surface.clone(),
        modes: crate::linalg::dense::from_faer(&modes),
        residual: crate::linalg::dense::from_faer(&residual),
    }
}

/// Relative error bound of the smaller system's band eigenvalues in [`truncation_error`]: the
/// estimate is a frequency change of order 1e-2 printed to three digits.
pub(super) const ESTIMATE_TOL: f64 = 1e-6;

/// Error estimate of the Craig-Bampton truncation: the largest relative change of the system
/// frequencies in the band when the parts' mode cut-off is lowered to 2/3 (NaN when that
/// smaller system cannot be solved). The smaller system's band eigenvalues come from block
/// Lanczos when it is large ([`engine::lowest_eigenvalues`]), else (or when that gives no
/// answer) they are refined from the full system's modes restricted to its coordinates (a
/// block of up to max(400, 3/2 x kept) of them: as many as the system's solve returned, kept
/// + 64 after block Lanczos) rather than solved densely from scratch.
pub(super) fn truncation_error(
    inp: &RomInputs<'_>,
    parts: &[(&PartReduction, &[usize])],
    kg: &Mat<f64>,
    mg: &Mat<f64>,
    sys: &SystemModes,
) -> f64 {
    let limit = inp.cutoff_hz * 2.0 / 3.0;
    let mut keep = vec![true; kg.nrows()];
    for (p, map) in parts {
        for (j, f) in p.modes.clone().zip(&p.mode_frequencies_hz) {
            if *f > limit {
                keep[map[j]] = false;
            }
        }
    }
    let idx: Vec<usize> = (0..kg.nrows()).filter(|&i| keep[i]).collect();
    let kk = Mat::from_fn(idx.len(), idx.len(), |i, j| kg[(idx[i], idx[j])]);
    let mm = Mat::from_fn(idx.len(), idx.len(), |i, j| mg[(idx[i], idx[j])]);
    let band = (2.0 * std::f64::consts::PI * inp.band_hz).powi(2);
    let in_band = sys.lambdas.iter().take_while(|&&l| l <= band).count();
    let cut = (2.0 * std::f64::consts::PI * inp.cutoff_hz).powi(2);
    let kept = sys.lambdas.iter().take_while(|&&l| l <= cut).count();
    let p = idx
        .len()
        .min(400.max(3 * kept / 2))
        .max(in_band)
        .min(sys.vectors.ncols());
    let lanczos = (idx.len() > engine::LANCZOS_ABOVE)
        .then(|| engine::lowest_eigenvalues(&kk, &mm, in_band, 1.1 * band, ESTIMATE_TOL))
        .flatten();
    let smaller = match lanczos {
        Some(l2) => Ok(l2),
        None => {
            let start = Mat::from_fn(idx.len(), p, |i, j| sys.vectors[(idx[i], j)]);
            engine::refined_eigenvalues(&kk, &mm, start.as_ref())
        }
    };
    match smaller {
        Ok(l2) => sys.lambdas[..in_band]
            .iter()
            .zip(&l2)
            .map(|(a, b)| (hz(*b) - hz(*a)).abs() / hz(*a))
            .fold(0.0, f64::max),
        Err(_) => f64::NAN,
    }
}

/// What the ROM leaves out, in words for the report.
pub(super) fn left_out(inp: &RomInputs<'_>, n_g: usize, b: &Basis) -> Vec<String> {
    let mut out = Vec::new();
    let missing: Vec<String> = (1..=inp.axis_x.len())
        .filter(|c| !inp.cylinders.contains(c))
        .map(|c| c.to_string())
        .collect();
    if !missing.is_empty() {
        out.push(format!(
            "liners of cylinders {} (their bores are free; rom.cylinders)",
            missing.join(", ")
        ));
    }
    out.push(format!(
        "system modes above the cut-off {:.0} Hz ({} of {}), represented {} at the contact DOFs",
        inp.cutoff_hz,
        n_g - b.kept,
        n_g,
        if b.mu.is_empty() {
            "statically".to_string()
        } else {
            format!("by {} residual vectors (static part exact)", b.mu.len())
        }
    ));
    if inp.crankcase.node_set("deck_top").is_none() {
        out.push(
            "head-bolt reaction on the deck (the crankcase mesh has no 'deck_top' set)".into(),
        );
    }
    out
}

/// The record of the two parts: their reductions' statistics, copies and sources.
fn part_infos(
    inp: &RomInputs<'_>,
    liner: &PartReduction,
    crankcase: &PartReduction,
    sources: [Source; 2],
) -> Vec<PartInfo> {
    vec![
        PartInfo {
            name: "liner".into(),
            stats: liner.stats.clone(),
            copies: inp.cylinders.len(),
            source: sources[0],
        },
        PartInfo {
            name: "crankcase".into(),
            stats: crankcase.stats.clone(),
            copies: 1,
            source: sources[1],
        },
    ]
}

/// Builds the engine ROM: Craig-Bampton reductions of the liner and the crankcase, their
/// assembly over the modelled cylinders, the system modes below the cut-off with residual
/// vectors of the contact load patterns, the preload, and per cylinder the rows the transient
/// needs.
pub fn build(inp: &RomInputs<'_>, progress: &dyn Fn(&str)) -> Result<RomBuild, RomError> {
    let t0 = Instant::now();
    let progress = |what: &str| {
        log::info!("{:7.2} s  {what}", t0.elapsed().as_secs_f64());
        progress(what)
    };
    crate::linalg::thread_count_invariant();
    let data = PartData::new(inp)?;
    let rows = &data.rows;
    let (liner, crankcase, sources) = reduce_parts(inp, &data, &progress)?;
    progress("assembling the engine");
    let (crankcase_map, liner_maps, n_g) = layout(&liner, &crankcase, &inp.cylinders);
    let mut placements = vec![Placement {
        part: &crankcase,
        map: crankcase_map.clone(),
    }];
    placements.extend(liner_maps.iter().map(|map| Placement {
        part: &liner,
        map: map.clone(),
    }));
    let (kg, mg) = assemble(n_g, &placements);
    progress("system modes");
    let omega_c2 = (2.0 * std::f64::consts::PI * inp.cutoff_hz).powi(2);
    let sys = engine::system_modes(kg.clone(), &mg, omega_c2)?;
    let kept = sys.lambdas.iter().take_while(|&&l| l <= omega_c2).count();
    let ncon = rows.thrust.len() + rows.anti.len();
    let n_rows = ncon + rows.points.len();
    let (g_rows, gc) = output_rows(&liner, &liner_maps, ncon, n_rows, n_g);
    progress("residual vectors");
    let patterns = hat_patterns(
        &[rows.thrust.len(), rows.anti.len()],
        g_rows.len(),
        inp.residual_vector_spacing,
    );
    let w = sys.dropped_flexibility(kept, gc.as_ref());
    let basis = basis(&sys, kept, w.as_ref(), &patterns)?;
    let f = preload_vector(&liner, rows.clamp_load, &liner_maps, &crankcase, n_g);
    let u0 = sys.static_solve(f.as_ref());
    let assembled = Assembled {
        inp,
        rows,
        liner: &liner,
        liner_maps: &liner_maps,
        crankcase: &crankcase,
        crankcase_map: &crankcase_map,
        n_g,
        w: &w,
        basis: &basis,
        u0: &u0,
    };
    let cylinders = inp
        .cylinders
        .iter()
        .zip(&g_rows)
        .enumerate()
        .map(|(idx, (&cyl, g_all))| cylinder_rom(&assembled, cyl, g_all, idx))
        .collect();
    let gcs = &gc * &basis.ys;
    let rflex = residual_flexibility(gc.as_ref(), w.as_ref()) - &gcs * gcs.transpose();
    progress("error estimate");
    let mut parts: Vec<(&PartReduction, &[usize])> = vec![(&crankcase, &crankcase_map)];
    parts.extend(liner_maps.iter().map(|m| (&liner, m.as_slice())));
    let estimated_error = truncation_error(inp, &parts, &kg, &mg, &sys);
    log::info!("{:7.2} s  built", t0.elapsed().as_secs_f64());
    let info = RomInfo {
        full_dofs: crankcase.stats.full_dofs + inp.cylinders.len() * liner.stats.full_dofs,
        reduced_dofs: n_g,
        system_modes: kept,
        residual_vectors: basis.mu.len(),
        band_hz: inp.band_hz,
        cutoff_hz: inp.cutoff_hz,
        interface_harmonics: inp.harmonics,
        parts: part_infos(inp, &liner, &crankcase, sources),
        build_seconds: t0.elapsed().as_secs_f64(),
        estimated_error,
        left_out: left_out(inp, n_g, &basis),
        interfaces: None,
        warnings: Vec::new(),
    };
    let rom = EngineRom {
        frequencies_hz: sys.lambdas[..kept]
            .iter()
            .chain(&basis.mu)
            .map(|&l| hz(l))
            .collect(),
        cylinders,
        residual_flexibility: crate::linalg::dense::from_faer(&rflex),
        info,
    };
    Ok(RomBuild {
        rom,
        liner,
        crankcase,
        liner_maps,
        crankcase_map,
        system: sys,
    })
}

/// The Craig-Bampton reductions of the liner and the crankcase ([`reduce_cached`]), through the
/// component cache when the inputs name one, one after the other: each uses both cores in its
/// block solves and products, and run at once the two gave results that differed from run to
/// run in the last bits (their allocations interleave, and the dense kernels' rounding depends
/// on the data's alignment), for about 5 s gained on the default engine.
pub(super) fn reduce_parts(
    inp: &RomInputs<'_>,
    data: &PartData,
    progress: &dyn Fn(&str),
) -> Result<(PartReduction, PartReduction, [Source; 2]), RomError> {
    // refused before any work: the liner's reduction would be lost
    if inp.keep_bases && inp.crankcase_components > 1 {
        return Err(crate::reduce::craig_bampton::ReduceError::Substructure {
            part: COMPONENTS[1].into(),
            msg: "mode shapes on the meshes need the crankcase's full basis, which a substructured reduction does not keep: set rom.crankcase_components = 1 for this command".into(),
        }
        .into());
    }
    let settings = cb_settings(inp);
    let [liner, crankcase] = data.parts(inp);
    let dir = inp.part_cache.as_deref();
    progress("reducing the liner");
    let (l, ls) = reduce_cached(&liner, &settings, dir)?;
    progress("reducing the crankcase");
    let (c, cs) = match crankcase_split(inp) {
        Some(split) => {
            crate::reduce::substructure::reduce_split(&crankcase, &settings, &split, dir)?
        }
        None => reduce_cached(&crankcase, &settings, dir)?,
    };
    Ok((l, c, [ls, cs]))
}

/// One component's reduction into the component cache (`inp.part_cache`), for a scheduler's
/// task: `index` 0 the liner, then the crankcase or its components ([`component_names`]). A
/// later build finds it there.
pub fn reduce_component(
    inp: &RomInputs<'_>,
    index: usize,
) -> Result<(PartReduction, Source), RomError> {
    crate::linalg::thread_count_invariant();
    let data = PartData::new(inp)?;
    let [liner, crankcase] = data.parts(inp);
    let (settings, dir) = (cb_settings(inp), inp.part_cache.as_deref());
    Ok(match (index, crankcase_split(inp)) {
        (0, _) => reduce_cached(&liner, &settings, dir)?,
        (_, None) => reduce_cached(&crankcase, &settings, dir)?,
        (c, Some(split)) => {
            crate::reduce::substructure::reduce_one(&crankcase, &settings, &split, dir, c - 1)?
        }
    })
}

/// The liner's output rows (contact DOFs, then points) scattered onto each modelled
/// cylinder's reduced DOFs, and the contact rows of all cylinders stacked (`gc`, the first
/// `ncon` rows of each).
pub(super) fn output_rows(
    liner: &PartReduction,
    liner_maps: &[Vec<usize>],
    ncon: usize,
    n_rows: usize,
    n_g: usize,
) -> (Vec<Mat<f64>>, Mat<f64>) {
    let g_rows: Vec<Mat<f64>> = liner_maps
        .iter()
        .map(|map| scatter_rows(&liner.outputs, map, 0, n_rows, n_g))
        .collect();
    let mut gc = Mat::<f64>::zeros(ncon * g_rows.len(), n_g);
    for (i, g) in g_rows.iter().enumerate() {
        gc.as_mut()
            .subrows_mut(i * ncon, ncon)
            .copy_from(g.as_ref().subrows(0, ncon));
    }
    (g_rows, gc)
}
