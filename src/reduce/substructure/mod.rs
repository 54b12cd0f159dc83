//! Substructured reduction of a large part: memory bounded by one component's factor.
//!
//! A part too large to factorise at once (a production crankcase of millions of DOFs) is cut
//! into components by planes x = x_j across its long axis: every element goes to the slab its
//! centroid lies in, and the nodes a slab shares with the next form the cut j. Each cut's
//! displacement is expanded in cut shapes: the traces on the cut of the lowest free modes of a
//! slab a few element layers either side of it (the cut's rigid motions exactly, then smooth
//! fields by stiffness as the part near the cut has it, each piece of the section on its own;
//! `cut_shapes`). Both neighbours evaluate the same shapes on the same nodes, so they share
//! the cut coordinates: the coupling is exact in the span of the shapes and converges as
//! their number grows (measured in tests/rom.rs and benches/RESULTS.md). Shapes tried and
//! dropped there: the eigenvectors of the cut's own block (K_ss, M_ss), which localise on
//! weakly held nodes, a thin slab's Schur complement on the cut, and the slab's transfer
//! operator sampled by random displacements of its outer faces (randomised local spaces:
//! over one or two element layers its singular values fall slowly, so the samples fill the
//! basis with rough boundary data; CHANGELOG, session 67).
//!
//! Each component is reduced by [`super::craig_bampton::reduce`] on its own (its share of
//! the part's interfaces, loads, outputs and fixed sets, plus its cuts as interfaces), one
//! after the other: the peak memory is that of the largest component. Assembled over the shared cut
//! coordinates the components give a model (K_A, M_A) in coordinates [b | i]: b the part's
//! interface coordinates, i the cut coordinates and every component's modes and attachments.
//! A second Craig-Bampton step on this dense model gives the part the same structure as a
//! one-shot reduction, so everything downstream is unchanged:
//!
//!   T = [[I, 0, 0], [X, Phi_k, Phi_a]],  X = -K_ii^-1 K_ib,
//!
//! Phi_k the modes of K_ii phi = lambda M_ii phi below the cut-off, Phi_a the residual
//! attachments u = K_ii^-1 f - Phi_k Lambda_k^-1 Phi_k^T f of the part's loads and of the
//! interface inertia f = (M_A [I; X])_i, M_ii-orthonormalised as in the one-shot reduction;
//! K_r = T^T K_A T, M_r = T^T M_A T.

use super::craig_bampton::{
    gram_cut, symmetrise, CbSettings, CbStats, InterfaceBlock, Load, Output, Part, PartReduction,
    ReduceError,
};
use super::part_cache::{reduce_cached_with, ModeStore, PartCacheError, Source};
use crate::fem::dofs::{DofMap, FIXED};
use crate::fem::model::FeModel;
use crate::mesh::{ElementBlock, Mesh};
use faer::{Mat, MatRef, Side};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

mod enrich;

/// How a part is cut into components.
#[derive(Clone, Debug, PartialEq)]
pub struct Split {
    /// Cut planes x = x_j \[m\], ascending: components = cuts + 1.
    pub cuts_x: Vec<f64>,
    /// Shapes per cut (fewer when the cut has fewer DOFs).
    pub cut_shapes: usize,
    /// Each component's modes up to this multiple of the part's cut-off (>= 1): the second
    /// step cuts the assembled model at the part's cut-off, so components that carry modes
    /// above it leave the assembled spectrum below it converged.
    pub component_cutoff_factor: f64,
    /// Shapes added to each cut from a first assembly's force imbalance at the cut (0: none;
    /// `substructure/enrich.rs`).
    pub enrichment: usize,
}

/// One component: its mesh (own node numbering) and each of its nodes' index in the part.
struct Component {
    mesh: Mesh,
    nodes: Vec<usize>,
}

/// Name of the node set of cut `j` (0-based) in the components' meshes.
fn cut_set(j: usize) -> String {
    format!("substructure_cut_{}", j + 1)
}

fn other(part: &str, msg: String) -> ReduceError {
    ReduceError::Other {
        part: part.into(),
        msg,
    }
}

/// A substructuring the mesh does not allow (exit 2: the scene can change it).
fn refused(part: &str, msg: String) -> ReduceError {
    ReduceError::Substructure {
        part: part.into(),
        msg,
    }
}

/// The slab of each element: the number of cut planes below its centroid's x.
fn element_slabs(mesh: &Mesh, cuts_x: &[f64]) -> Vec<usize> {
    mesh.elements()
        .map(|(_, nodes)| {
            let x = nodes.iter().map(|&n| mesh.nodes[n][0]).sum::<f64>() / nodes.len() as f64;
            cuts_x.iter().filter(|&&c| c < x).count()
        })
        .collect()
}

/// The sub-mesh of the elements `keep` (global element indices, ascending): nodes renumbered
/// in the part's order, node sets restricted (order kept, empty ones dropped), element sets,
/// materials and element lines carried. Returns the mesh and its nodes' part indices.
fn sub_mesh(mesh: &Mesh, keep: &[bool]) -> (Mesh, Vec<usize>) {
    let mut used = vec![false; mesh.nodes.len()];
    let mut blocks = Vec::new();
    let mut element_map = vec![usize::MAX; keep.len()];
    let mut element_material = Vec::new();
    let (mut lines, mut scope) = (Vec::new(), Vec::new());
    let (mut e, mut next_e) = (0, 0);
    for b in &mesh.blocks {
        let nn = b.kind.num_nodes();
        let mut conn = Vec::new();
        for el in b.conn.chunks(nn) {
            if keep[e] {
                conn.extend_from_slice(el);
                el.iter().for_each(|&n| used[n] = true);
                element_map[e] = next_e;
                next_e += 1;
                if let Some(&m) = mesh.element_material.get(e) {
                    element_material.push(m);
                }
                if let Some(l) = &mesh.element_lines {
                    lines.extend(l.at.get(e));
                    scope.extend(l.scope.get(e));
                }
            }
            e += 1;
        }
        if !conn.is_empty() {
            blocks.push(ElementBlock { kind: b.kind, conn });
        }
    }
    let nodes: Vec<usize> = (0..mesh.nodes.len()).filter(|&n| used[n]).collect();
    let mut local = vec![usize::MAX; mesh.nodes.len()];
    for (i, &n) in nodes.iter().enumerate() {
        local[n] = i;
    }
    for b in &mut blocks {
        b.conn.iter_mut().for_each(|n| *n = local[*n]);
    }
    let restrict = |sets: &BTreeMap<String, Vec<usize>>, map: &[usize]| {
        sets.iter()
            .filter_map(|(name, v)| {
                let r: Vec<usize> = v
                    .iter()
                    .filter_map(|&x| (map[x] != usize::MAX).then_some(map[x]))
                    .collect();
                (!r.is_empty()).then(|| (name.clone(), r))
            })
            .collect()
    };
    let sub = Mesh {
        nodes: nodes.iter().map(|&n| mesh.nodes[n]).collect(),
        blocks,
        node_sets: restrict(&mesh.node_sets, &local),
        element_sets: restrict(&mesh.element_sets, &element_map),
        materials: mesh.materials.clone(),
        element_material,
        element_lines: mesh
            .element_lines
            .as_ref()
            .map(|l| crate::mesh::ElementLines {
                files: l.files.clone(),
                at: lines,
                unit: l.unit,
                scopes: l.scopes.clone(),
                scope,
            }),
    };
    (sub, nodes)
}

/// Cuts `mesh` at the planes `cuts_x`: the components (each with the sets `cut_set(j)` of the
/// cuts on its sides) and each cut's nodes (part numbering, ascending). Refused when a slab is
/// empty, two cuts share a node (slabs thinner than an element) or a cut is empty (the part
/// falls apart).
fn split_mesh(
    part: &str,
    mesh: &Mesh,
    cuts_x: &[f64],
) -> Result<(Vec<Component>, Vec<Vec<usize>>), ReduceError> {
    let slabs = element_slabs(mesh, cuts_x);
    let nc = cuts_x.len() + 1;
    let mut comps = Vec::with_capacity(nc);
    let mut owner = vec![Vec::<usize>::new(); mesh.nodes.len()];
    for c in 0..nc {
        let keep: Vec<bool> = slabs.iter().map(|&s| s == c).collect();
        if !keep.contains(&true) {
            return Err(refused(
                part,
                format!(
                    "no element lies in component {} of {nc} (cut planes x = {cuts_x:?} m)",
                    c + 1
                ),
            ));
        }
        let (m, nodes) = sub_mesh(mesh, &keep);
        nodes.iter().for_each(|&n| owner[n].push(c));
        comps.push(Component { mesh: m, nodes });
    }
    let mut cuts = vec![Vec::new(); nc - 1];
    for (n, o) in owner.iter().enumerate() {
        match o.as_slice() {
            [_] | [] => {}
            [a, b] if b - a == 1 => cuts[*a].push(n),
            _ => {
                return Err(refused(
                    part,
                    format!("node {} at {:?} lies in components {:?}: the cut planes x = {cuts_x:?} m are closer than an element", n + 1, mesh.nodes[n], o.iter().map(|c| c + 1).collect::<Vec<_>>()),
                ))
            }
        }
    }
    for (j, cut) in cuts.iter().enumerate() {
        if cut.is_empty() {
            return Err(refused(
                part,
                format!("the cut at x = {} m crosses no node shared by its two sides (the part would fall apart there)", cuts_x[j]),
            ));
        }
        for c in [j, j + 1] {
            let comp = &mut comps[c];
            let local: Vec<usize> = cut
                .iter()
                .map(|&n| {
                    comp.nodes
                        .binary_search(&n)
                        .expect("cut node in both sides")
                })
                .collect();
            comp.mesh.node_sets.insert(cut_set(j), local);
        }
    }
    Ok((comps, cuts))
}

/// The slab a cut's shapes come from: its mesh (own numbering, the part's sets restricted),
/// its nodes' part indices, the cut's nodes (part numbering) and the part's fixed sets in it.
struct Slab {
    mesh: Mesh,
    nodes: Vec<usize>,
    cut: Vec<usize>,
    fix: Vec<String>,
}

impl Slab {
    /// The [`SLAB_LAYERS`] element layers either side of `cut` in part `p`.
    fn of(p: &Part<'_>, cut: &[usize]) -> Self {
        let mut on_cut = vec![false; p.mesh.nodes.len()];
        cut.iter().for_each(|&n| on_cut[n] = true);
        let keep = slab_elements(p.mesh, &on_cut, SLAB_LAYERS);
        let (mesh, nodes) = sub_mesh(p.mesh, &keep);
        let fix = p
            .fix
            .iter()
            .filter(|s| mesh.node_set(s).is_some())
            .cloned()
            .collect();
        Self {
            mesh,
            nodes,
            cut: cut.to_vec(),
            fix,
        }
    }

    /// Cache key of the slab's shapes: the slab (mesh, sets, material, fixed sets), its cut's
    /// nodes, the shape count and the method's constants.
    fn key(&self, p: &Part<'_>, count: usize) -> String {
        let cut: Vec<f64> = self
            .cut
            .iter()
            .map(|&n| self.nodes.binary_search(&n).expect("cut node in its slab") as f64)
            .collect();
        let mut extra = vec![count as f64, SLAB_LAYERS as f64, SUBSPACE_PASSES as f64];
        extra.extend(cut);
        super::part_cache::mesh_key("cut", &self.mesh, p.material, &self.fix, &extra)
    }
}

/// Element layers on each side of a cut in the slab its shapes come from. Measured on the
/// default engine cut into 3 components with 200 shapes per cut (lowest system eigenvalue
/// against the one-piece reduction): 1 layer 2.0e-3, 3 layers 2.0e-4, 5 layers 2.0e-4 at
/// twice the cost, 8 layers 1.6e-4 (benches/RESULTS.md).
const SLAB_LAYERS: usize = 3;

/// The elements within `layers` element layers of the nodes flagged `on_cut`.
fn slab_elements(mesh: &Mesh, on_cut: &[bool], layers: usize) -> Vec<bool> {
    let mut near = on_cut.to_vec();
    let mut keep = vec![false; mesh.num_elements()];
    for _ in 0..layers {
        for (e, (_, nodes)) in mesh.elements().enumerate() {
            keep[e] |= nodes.iter().any(|&n| near[n]);
        }
        for (e, (_, nodes)) in mesh.elements().enumerate() {
            if keep[e] {
                nodes.iter().for_each(|&n| near[n] = true);
            }
        }
    }
    keep
}

/// The shapes of one cut (3 rows per cut node, in the slab's cut order): the traces on the
/// cut of a basis of about the lowest `count` free modes of the slab (the part's fixed sets
/// held; [`crate::eigen::subspace::inverse_subspace`]), orthonormalised (an SVD, directions
/// below 1e-8 of the largest dropped), each scaled to a largest entry of 1. The slab's rigid motions give the cut's
/// rigid motions exactly; its membrane and bending modes give smooth fields that respect the
/// cut's connectivity (separate pieces move on their own). A cut with at most 2 `count` + 16
/// free DOFs keeps all of them (unit shapes): no reduction, exact coupling.
fn cut_shapes(p: &Part<'_>, slab: &Slab, count: usize) -> Result<Mat<f64>, ReduceError> {
    let (nodes, cut, fix) = (&slab.nodes, &slab.cut, &slab.fix);
    let slab = slab.mesh.clone();
    let err_model = |source| ReduceError::Model {
        part: p.name.to_string(),
        source,
    };
    let model = FeModel::build_with(slab, p.material, fix, &[]).map_err(err_model)?;
    let local: Vec<usize> = cut
        .iter()
        .map(|&c| nodes.binary_search(&c).expect("cut node in its slab"))
        .collect();
    let pairs: Vec<(usize, usize)> = (0..cut.len())
        .flat_map(|j| {
            let (d, node) = (&model.dofs.dof, local[j]);
            (0..3).filter_map(move |i| {
                let dof = d[3 * node + i];
                (dof != FIXED).then_some((3 * j + i, dof))
            })
        })
        .collect();
    if pairs.len() <= count.saturating_mul(2).saturating_add(16) {
        let mut psi = Mat::<f64>::zeros(3 * cut.len(), pairs.len());
        for (c, &(r, _)) in pairs.iter().enumerate() {
            psi[(r, c)] = 1.0;
        }
        return Ok(psi);
    }
    // a shift below the slab's lowest elastic mode: 1e-6 of its mean eigenvalue trace(K)/trace(M)
    let km = &model.km;
    let sigma = -1e-6 * km.eigenvalue_scale();
    let t = Instant::now();
    let n = model.n_free();
    let llt = model
        .analysis
        .llt(&km.pattern, &km.shifted(sigma))
        .map_err(|e| err_model(e.into()))?;
    let x = crate::eigen::subspace::inverse_subspace(
        &km.pattern.compress(&km.m),
        &llt,
        n,
        count,
        SUBSPACE_PASSES,
        0x9e37_79b9_7f4a_7c15,
    );
    log::info!(
        "[{}] cut shapes: slab of {n} DOFs, {count} vectors in {:.2} s",
        p.name,
        t.elapsed().as_secs_f64()
    );
    let traces = Mat::from_fn(3 * cut.len(), count, |r, j| {
        pairs
            .binary_search_by_key(&r, |&(row, _)| row)
            .map_or(0.0, |k| x[(pairs[k].1, j)])
    });
    directions(p.name, "cut shapes", &traces, (1e-8, usize::MAX))
}

/// The leading left singular vectors of `m` (`what` names them in an error): those above
/// `rel` times the largest singular value, at most `count`, each scaled to a largest entry
/// of 1.
fn directions(
    part: &str,
    what: &str,
    m: &Mat<f64>,
    (rel, count): (f64, usize),
) -> Result<Mat<f64>, ReduceError> {
    let svd = m.thin_svd().map_err(|e| {
        other(
            part,
            format!("substructuring: the {what}' SVD failed: {e:?}"),
        )
    })?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0f64, f64::max);
    let kept: Vec<usize> = (0..s.nrows())
        .filter(|&i| s[i] > rel * smax)
        .take(count)
        .collect();
    let u = svd.U();
    let mut out = Mat::from_fn(m.nrows(), kept.len(), |r, c| u[(r, kept[c])]);
    for j in 0..out.ncols() {
        let top = (0..out.nrows()).fold(0.0f64, |t, i| t.max(out[(i, j)].abs()));
        for i in 0..out.nrows() {
            out[(i, j)] /= top.max(f64::MIN_POSITIVE);
        }
    }
    Ok(out)
}

/// Passes of the cut slab's subspace iteration
/// ([`crate::eigen::subspace::inverse_subspace`]): each damps a mode's share by its
/// eigenvalue's ratio to the block's, so the span settles on the lowest modes within a few.
/// Only the span is wanted (the traces keep all its directions), not converged eigenvectors:
/// a block method needs a tenth of the solve cost per vector of Lanczos and none of its
/// O(n ncv^2) work.
const SUBSPACE_PASSES: usize = 5;

/// What a component's reduction reads, owned (names, remapped sets, loads and outputs) with
/// where its pieces go in the part: `blocks[k]` the part interface (or, from
/// `part_blocks` on, the cut) behind its k-th interface, `loads[k]` / `outputs[k]` the part's.
struct ComponentPart {
    name: String,
    fix: Vec<String>,
    interfaces: Vec<InterfaceBlock>,
    blocks: Vec<usize>,
    loads: Vec<Load>,
    load_index: Vec<usize>,
    outputs: Vec<Output>,
    output_index: Vec<usize>,
}

/// The first component holding all of `nodes` (part numbering).
fn home(comps: &[Component], nodes: impl Iterator<Item = usize> + Clone) -> Option<usize> {
    comps
        .iter()
        .position(|c| nodes.clone().all(|n| c.nodes.binary_search(&n).is_ok()))
}

/// Distributes the part's interfaces, loads and outputs over the components (each to the
/// first component holding all its nodes; refused when one straddles a cut) and adds the cuts
/// as interfaces with their shapes `cut_psi`.
fn component_parts(
    p: &Part<'_>,
    comps: &[Component],
    cut_psi: &[Mat<f64>],
) -> Result<Vec<ComponentPart>, ReduceError> {
    let nc = comps.len();
    let mut out: Vec<ComponentPart> = (0..nc)
        .map(|c| ComponentPart {
            name: format!("{}.{}", p.name, c + 1),
            fix: p
                .fix
                .iter()
                .filter(|s| comps[c].mesh.node_set(s).is_some())
                .cloned()
                .collect(),
            interfaces: Vec::new(),
            blocks: Vec::new(),
            loads: Vec::new(),
            load_index: Vec::new(),
            outputs: Vec::new(),
            output_index: Vec::new(),
        })
        .collect();
    let local = |c: usize, n: usize| comps[c].nodes.binary_search(&n).expect("node in its home");
    for (k, b) in p.interfaces.iter().enumerate() {
        let nodes = p.mesh.node_set(&b.set).unwrap_or(&[]);
        let c = home(comps, nodes.iter().copied()).ok_or_else(|| {
            refused(
                p.name,
                format!(
                    "interface set '{}' straddles a cut plane; place the cuts elsewhere",
                    b.set
                ),
            )
        })?;
        out[c].interfaces.push(InterfaceBlock {
            set: b.set.clone(),
            psi: b.psi.clone(),
        });
        out[c].blocks.push(k);
    }
    for (k, l) in p.loads.iter().enumerate() {
        let c = home(comps, l.entries.iter().map(|e| e.0))
            .ok_or_else(|| refused(p.name, format!("load '{}' straddles a cut plane", l.name)))?;
        out[c].loads.push(Load {
            name: l.name.clone(),
            entries: l.entries.iter().map(|&(n, f)| (local(c, n), f)).collect(),
        });
        out[c].load_index.push(k);
    }
    for (k, o) in p.outputs.iter().enumerate() {
        let c = home(comps, std::iter::once(o.node)).expect("every node lies in a component");
        out[c].outputs.push(Output {
            node: local(c, o.node),
            dir: o.dir,
        });
        out[c].output_index.push(k);
    }
    for (j, psi) in cut_psi.iter().enumerate() {
        for c in [j, j + 1] {
            out[c].interfaces.push(InterfaceBlock {
                set: cut_set(j),
                psi: psi.clone(),
            });
            out[c].blocks.push(p.interfaces.len() + j);
        }
    }
    Ok(out)
}

/// The components of a split part with their reduction inputs: the cuts' shapes come from
/// the component cache `dir` or are computed (and stored); only the cuts `wanted` (by index)
/// are computed, the others left without shapes (a task that reduces one component).
struct Prepared {
    comps: Vec<Component>,
    cuts: Vec<Vec<usize>>,
    cut_psi: Vec<Mat<f64>>,
    cparts: Vec<ComponentPart>,
}

fn prepare(
    p: &Part<'_>,
    split: &Split,
    dir: Option<&Path>,
    wanted: &dyn Fn(usize) -> bool,
) -> Result<Prepared, PartCacheError> {
    let t0 = Instant::now();
    let part = p.name;
    let (comps, cuts) = split_mesh(part, p.mesh, &split.cuts_x)?;
    let mut cut_psi = Vec::with_capacity(cuts.len());
    for (j, cut) in cuts.iter().enumerate() {
        if !wanted(j) {
            cut_psi.push(Mat::zeros(3 * cut.len(), 0));
            continue;
        }
        let slab = Slab::of(p, cut);
        let key = slab.key(p, split.cut_shapes);
        let file = format!("cut-{part}-{}", j + 1);
        let (psi, _) = super::part_cache::cached_matrix(dir, &file, &key, || {
            cut_shapes(p, &slab, split.cut_shapes)
        })?;
        cut_psi.push(psi);
    }
    log::info!(
        "[{part}] {} components, cut DOFs {}, cut shapes {} ({:.2} s)",
        comps.len(),
        crate::text::joined(&cuts.iter().map(|c| 3 * c.len()).collect::<Vec<_>>(), ", "),
        crate::text::joined(&cut_psi.iter().map(|m| m.ncols()).collect::<Vec<_>>(), ", "),
        t0.elapsed().as_secs_f64()
    );
    let cparts = component_parts(p, &comps, &cut_psi)?;
    Ok(Prepared {
        comps,
        cuts,
        cut_psi,
        cparts,
    })
}

/// Component `c`'s reduction through the component cache `dir`, its modes up to
/// `factor` times the part's cut-off (those of a first pass when `modes` holds them).
fn reduce_component(
    p: &Part<'_>,
    prep: &Prepared,
    (c, factor): (usize, f64),
    (settings, dir): (&CbSettings, Option<&Path>),
    modes: Option<&ModeStore>,
) -> Result<(PartReduction, Source), PartCacheError> {
    let cb = CbSettings {
        cutoff_hz: settings.cutoff_hz * factor,
        keep_basis: false,
    };
    reduce_cached_with(&component(p, prep, c), &cb, dir, modes)
}

/// The cut shapes of a split part prepared for the components `wanted` (by index) and,
/// when the split asks for it, enriched; returns them with the store that holds the first
/// pass's modes (a store only when the cuts are enriched).
fn prepare_enriched(
    p: &Part<'_>,
    split: &Split,
    (settings, dir): (&CbSettings, Option<&Path>),
    wanted: &dyn Fn(usize) -> bool,
) -> Result<(Prepared, Option<ModeStore>), PartCacheError> {
    let mut prep = prepare(p, split, dir, wanted)?;
    if split.enrichment == 0 {
        return Ok((prep, None));
    }
    let store = ModeStore::new(dir)?;
    enrich::enrich(p, &mut prep, split, (settings, dir), &store)?;
    Ok((prep, Some(store)))
}

/// Component `c` of a prepared split of part `p` as a part of its own.
fn component<'a>(p: &Part<'a>, prep: &'a Prepared, c: usize) -> Part<'a> {
    let (comp, cp) = (&prep.comps[c], &prep.cparts[c]);
    Part {
        name: &cp.name,
        mesh: &comp.mesh,
        material: p.material,
        surface: p.surface,
        fix: &cp.fix,
        interfaces: &cp.interfaces,
        loads: &cp.loads,
        outputs: &cp.outputs,
    }
}

/// One component (`c`, 0-based) of a split part reduced into the component cache `dir` with
/// the shapes of its own cuts: one task of a component job array; a later
/// [`reduce_split`] finds it there.
pub fn reduce_one(
    p: &Part<'_>,
    settings: &CbSettings,
    split: &Split,
    dir: Option<&Path>,
    c: usize,
) -> Result<(PartReduction, Source), PartCacheError> {
    let (prep, modes) = prepare_enriched(p, split, (settings, dir), &|j| j + 1 == c || j == c)?;
    let factor = split.component_cutoff_factor;
    reduce_component(p, &prep, (c, factor), (settings, dir), modes.as_ref())
}

/// Reduces a part by substructuring (module doc): cut shapes, each component's Craig-Bampton
/// reduction through the component cache `dir` (keyed by the component's own inputs, its cut
/// shapes among them), then their assembly and the second Craig-Bampton step. Returns the
/// part's reduction and whether every component came from the cache.
pub fn reduce_split(
    p: &Part<'_>,
    settings: &CbSettings,
    split: &Split,
    dir: Option<&Path>,
) -> Result<(PartReduction, Source), PartCacheError> {
    let t0 = Instant::now();
    let part = p.name;
    let (prep, modes) = prepare_enriched(p, split, (settings, dir), &|_| true)?;
    let mut reductions = Vec::with_capacity(prep.comps.len());
    let mut all_cached = true;
    for c in 0..prep.comps.len() {
        let factor = split.component_cutoff_factor;
        let (r, source) = reduce_component(p, &prep, (c, factor), (settings, dir), modes.as_ref())?;
        all_cached &= source == Source::Cached;
        reductions.push(r);
    }
    let assembled = assemble(p, &prep.cparts, &reductions, &prep.cut_psi);
    let dofs = DofMap::with_fixed_sets(p.mesh, p.fix)
        .map_err(|e| other(part, format!("substructuring: {e}")))?;
    let mut r = second_level(part, assembled, settings.cutoff_hz, dofs)?;
    r.stats.seconds = t0.elapsed().as_secs_f64();
    // the components' interiors and the cuts' free DOFs (a fixed node on a cut is no DOF)
    let free = |n: &usize| (0..3).filter(|i| r.dofs.dof[3 * n + i] != FIXED).count();
    r.stats.interior_dofs = reductions
        .iter()
        .map(|c| c.stats.interior_dofs)
        .sum::<usize>()
        + prep.cuts.iter().flatten().map(free).sum::<usize>();
    log::info!(
        "[{part}] substructured: {} coordinates ({} constraint, {} modes, {} attachments) in {:.2} s",
        r.size(),
        r.stats.constraint_modes,
        r.stats.normal_modes,
        r.stats.attachment_modes,
        r.stats.seconds
    );
    let source = if all_cached {
        Source::Cached
    } else {
        Source::Reduced
    };
    Ok((r, source))
}

/// The components assembled over their shared coordinates: (K_A, M_A) in coordinates
/// [b | i] (the part's interface columns in its block order, then per cut its shapes' columns,
/// then each component's private coordinates), the loads Phi^T f and output rows there, and
/// the part's interface column ranges.
struct Assembled {
    k: Mat<f64>,
    m: Mat<f64>,
    nb: usize,
    loads: Mat<f64>,
    outputs: Mat<f64>,
    interface_cols: Vec<std::ops::Range<usize>>,
    /// Columns of each cut's shapes.
    cut_cols: Vec<std::ops::Range<usize>>,
    /// Each component's coordinates' columns.
    maps: Vec<Vec<usize>>,
}

fn assemble(
    p: &Part<'_>,
    cparts: &[ComponentPart],
    reductions: &[PartReduction],
    cut_psi: &[Mat<f64>],
) -> Assembled {
    // global columns of every interface block (part's, then cuts')
    let mut block_cols = Vec::new();
    let mut next = 0;
    for w in p
        .interfaces
        .iter()
        .map(|b| b.psi.ncols())
        .chain(cut_psi.iter().map(|m| m.ncols()))
    {
        block_cols.push(next..next + w);
        next += w;
    }
    let nb: usize = p.interfaces.iter().map(|b| b.psi.ncols()).sum();
    let maps: Vec<Vec<usize>> = cparts
        .iter()
        .zip(reductions)
        .map(|(cp, r)| {
            let mut map = vec![usize::MAX; r.size()];
            for (k, &blk) in cp.blocks.iter().enumerate() {
                for (lj, gj) in r.interface_cols[k].clone().zip(block_cols[blk].clone()) {
                    map[lj] = gj;
                }
            }
            for slot in map.iter_mut().filter(|s| **s == usize::MAX) {
                *slot = next;
                next += 1;
            }
            map
        })
        .collect();
    let n = next;
    let mut k = Mat::<f64>::zeros(n, n);
    let mut m = Mat::<f64>::zeros(n, n);
    let mut loads = Mat::<f64>::zeros(n, p.loads.len());
    let mut outputs = Mat::<f64>::zeros(p.outputs.len(), n);
    for ((cp, r), map) in cparts.iter().zip(reductions).zip(&maps) {
        for j in 0..r.size() {
            for i in 0..r.size() {
                k[(map[i], map[j])] += r.k[(i, j)];
                m[(map[i], map[j])] += r.m[(i, j)];
            }
        }
        for (l, &gl) in cp.load_index.iter().enumerate() {
            for i in 0..r.size() {
                loads[(map[i], gl)] += r.loads[(i, l)];
            }
        }
        for (o, &go) in cp.output_index.iter().enumerate() {
            for j in 0..r.size() {
                outputs[(go, map[j])] += r.outputs[(o, j)];
            }
        }
    }
    symmetrise(&mut k);
    symmetrise(&mut m);
    Assembled {
        k,
        m,
        nb,
        loads,
        outputs,
        interface_cols: block_cols[..p.interfaces.len()].to_vec(),
        cut_cols: block_cols[p.interfaces.len()..].to_vec(),
        maps,
    }
}

/// C = A^T B on both cores with a split that does not depend on the thread count.
fn atb(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(a.ncols(), b.ncols());
    faer::linalg::matmul::matmul(
        c.as_mut(),
        faer::Accum::Replace,
        a.transpose(),
        b,
        1.0,
        faer::Par::rayon(0),
    );
    c
}

fn ab(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    atb(a.transpose(), b)
}

/// K_ii^-1 of the assembled components' interior, factorised on its unit-mass scaling
/// (D = diag(M_ii)^-1/2: coordinates of unrelated scales, cut shapes next to modes).
struct InteriorSolve {
    d: Vec<f64>,
    chol: faer::linalg::solvers::Llt<f64>,
}

impl InteriorSolve {
    /// None when D K_ii D is not positive definite.
    fn new(k_ii: &Mat<f64>, m_ii: &Mat<f64>) -> Option<Self> {
        let ni = k_ii.nrows();
        let d: Vec<f64> = (0..ni)
            .map(|i| 1.0 / m_ii[(i, i)].max(f64::MIN_POSITIVE).sqrt())
            .collect();
        let ks = Mat::from_fn(ni, ni, |i, j| d[i] * k_ii[(i, j)] * d[j]);
        let chol = ks.llt(Side::Lower).ok()?;
        Some(Self { d, chol })
    }

    /// K_ii^-1 rhs = D (D K_ii D)^-1 D rhs.
    fn solve(&self, rhs: &Mat<f64>) -> Mat<f64> {
        use faer::linalg::solvers::SolveCore;
        let d = &self.d;
        let mut x = Mat::from_fn(d.len(), rhs.ncols(), |i, j| d[i] * rhs[(i, j)]);
        self.chol
            .solve_in_place_with_conj(faer::Conj::No, x.as_mut());
        for j in 0..x.ncols() {
            for (i, di) in d.iter().enumerate() {
                x[(i, j)] *= di;
            }
        }
        x
    }
}

/// Residual static responses u = K_ii^-1 f - Phi_k Lambda_k^-1 Phi_k^T f: what the kept modes
/// (eigenvalues `lambdas`, M-normalised `phi_k`) miss of the static response to each column f.
fn residual_static(
    solver: &InteriorSolve,
    lambdas: &[f64],
    phi_k: &Mat<f64>,
    f: &Mat<f64>,
) -> Mat<f64> {
    let mut u = solver.solve(f);
    if !lambdas.is_empty() {
        let mut pf = atb(phi_k.as_ref(), f.as_ref());
        for (r, lam) in lambdas.iter().enumerate() {
            for j in 0..pf.ncols() {
                pf[(r, j)] /= lam;
            }
        }
        u -= ab(phi_k.as_ref(), pf.as_ref());
    }
    u
}

/// The assembled components' interior (coordinates i of [b | i]): K_ii's solver, the static
/// constraint shapes X = -K_ii^-1 K_ib and the modes of K_ii phi = lambda M_ii phi up to the
/// cut-off (M-normalised).
struct Interior {
    solver: InteriorSolve,
    x: Mat<f64>,
    lambdas: Vec<f64>,
    phi_k: Mat<f64>,
}

impl Interior {
    fn of(part: &str, a: &Assembled, cutoff_hz: f64) -> Result<Self, ReduceError> {
        let (n, nb) = (a.k.nrows(), a.nb);
        let ni = n - nb;
        let sub =
            |x: &Mat<f64>, c0: usize, nc: usize| x.as_ref().submatrix(nb, c0, ni, nc).to_owned();
        let (k_ii, k_ib, m_ii) = (sub(&a.k, nb, ni), sub(&a.k, 0, nb), sub(&a.m, nb, ni));
        let fail = |what: &str| {
            other(
                part,
                format!("substructuring: the assembled components' {what}"),
            )
        };
        let solver = InteriorSolve::new(&k_ii, &m_ii).ok_or_else(|| {
            fail("interior stiffness is not positive definite (the interfaces do not hold it)")
        })?;
        let mut x = solver.solve(&k_ib);
        for v in x.col_iter_mut().flat_map(|c| c.iter_mut()) {
            *v = -*v;
        }
        let omega_c2 = (2.0 * std::f64::consts::PI * cutoff_hz).powi(2);
        let sys = super::engine::system_modes(k_ii, &m_ii, omega_c2)
            .map_err(|e| fail(&format!("interior modes: {e}")))?;
        let nk = sys.lambdas.iter().take_while(|&&l| l <= omega_c2).count();
        Ok(Self {
            solver,
            x,
            lambdas: sys.lambdas[..nk].to_vec(),
            phi_k: sys.vectors.as_ref().subcols(0, nk).to_owned(),
        })
    }
}

/// The second Craig-Bampton step on the assembled components (module doc): T = [[I, 0, 0],
/// [X, Phi_k, Phi_a]] and K_r = T^T K_A T, M_r = T^T M_A T with the loads and output rows
/// carried through T.
fn second_level(
    part: &str,
    a: Assembled,
    cutoff_hz: f64,
    dofs: DofMap,
) -> Result<PartReduction, ReduceError> {
    let (n, nb) = (a.k.nrows(), a.nb);
    let ni = n - nb;
    let Interior {
        solver,
        x,
        lambdas,
        phi_k,
    } = Interior::of(part, &a, cutoff_hz)?;
    let nk = lambdas.len();
    let m_ii = a.m.as_ref().submatrix(nb, nb, ni, ni).to_owned();
    let m_ib = a.m.as_ref().submatrix(nb, 0, ni, nb).to_owned();
    // attachment candidates: the loads' interior rows, then the interface inertia M_ib + M_ii X
    let nl = a.loads.ncols();
    let mut f = Mat::<f64>::zeros(ni, nl + nb);
    f.as_mut()
        .subcols_mut(0, nl)
        .copy_from(a.loads.as_ref().subrows(nb, ni));
    let inertia = &m_ib + ab(m_ii.as_ref(), x.as_ref());
    f.as_mut().subcols_mut(nl, nb).copy_from(&inertia);
    let u = residual_static(&solver, &lambdas, &phi_k, &f);
    let phi_a = orthonormalise(part, &m_ii, &u)?;
    let na = phi_a.ncols();
    let nr = nb + nk + na;
    let mut t = Mat::<f64>::zeros(n, nr);
    for i in 0..nb {
        t[(i, i)] = 1.0;
    }
    t.as_mut().submatrix_mut(nb, 0, ni, nb).copy_from(&x);
    t.as_mut().submatrix_mut(nb, nb, ni, nk).copy_from(&phi_k);
    t.as_mut()
        .submatrix_mut(nb, nb + nk, ni, na)
        .copy_from(&phi_a);
    let mut k = atb(t.as_ref(), ab(a.k.as_ref(), t.as_ref()).as_ref());
    let mut m = atb(t.as_ref(), ab(a.m.as_ref(), t.as_ref()).as_ref());
    symmetrise(&mut k);
    symmetrise(&mut m);
    let freqs: Vec<f64> = lambdas.iter().map(|&l| super::engine::hz(l)).collect();
    let stats = CbStats {
        full_dofs: dofs.n_free,
        interior_dofs: 0,
        constraint_modes: nb,
        normal_modes: nk,
        attachment_modes: na,
        highest_mode_hz: freqs.last().copied().unwrap_or(0.0),
        seconds: 0.0,
    };
    Ok(PartReduction {
        k,
        m,
        interface_cols: a.interface_cols,
        modes: nb..nb + nk,
        mode_frequencies_hz: freqs,
        attachments: nb + nk..nr,
        outputs: ab(a.outputs.as_ref(), t.as_ref()),
        loads: atb(t.as_ref(), a.loads.as_ref()),
        basis: None,
        fixed_modes: None,
        dofs,
        stats,
    })
}

/// The candidates `u` M-orthonormalised as in the one-shot reduction: each scaled to unit
/// M-norm, the scaled Gram D U^T M U D = V S V^T cut at [`gram_cut`], Phi_a = U D V_k S_k^-1/2.
fn orthonormalise(part: &str, m: &Mat<f64>, u: &Mat<f64>) -> Result<Mat<f64>, ReduceError> {
    let nu = u.ncols();
    if nu == 0 {
        return Ok(u.clone());
    }
    let mut gram = atb(u.as_ref(), ab(m.as_ref(), u.as_ref()).as_ref());
    symmetrise(&mut gram);
    let d: Vec<f64> = (0..nu)
        .map(|j| 1.0 / gram[(j, j)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let gram = Mat::from_fn(nu, nu, |i, j| d[i] * gram[(i, j)] * d[j]);
    let (s, v) = super::engine::symmetric_evd(gram.as_ref())
        .map_err(|e| other(part, format!("substructuring: attachment modes: {e}")))?;
    // ascending: the kept directions are the last ones
    let sorted: Vec<f64> = s.iter().rev().copied().collect();
    let nk = gram_cut(&sorted);
    let tr = Mat::from_fn(nu, nk, |r, c| {
        let col = nu - 1 - c;
        d[r] * v[(r, col)] / s[col].sqrt()
    });
    Ok(ab(u.as_ref(), tr.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cut of a lattice bar: elements split by centroid, the shared node plane found and
    /// given to both sides; a slab with no element refused.
    #[test]
    fn split_finds_the_shared_plane() {
        let coord = |k: [usize; 3]| [k[0] as f64 * 0.1, k[1] as f64 * 0.1, k[2] as f64 * 0.1];
        let active = |_: usize, _: usize, _: usize| true;
        let lat = crate::mesh::lattice::Lattice {
            cells: [4, 1, 1],
            periodic_j: false,
            active: &active,
            coord: &coord,
        };
        let mesh = lat.generate(crate::scene::spec::ElementKind::Hex8).mesh;
        let (comps, cuts) = split_mesh("bar", &mesh, &[0.2]).unwrap();
        assert_eq!(comps.len(), 2);
        assert_eq!(cuts[0].len(), 4);
        assert!(cuts[0]
            .iter()
            .all(|&n| (mesh.nodes[n][0] - 0.2).abs() < 1e-12));
        // lattice indices step 2 per cell (room for mid-side nodes): cells 0.2 m long, the
        // first component the one cell left of the plane
        assert_eq!(comps[0].nodes.len(), 8);
        assert_eq!(comps[1].nodes.len(), 16);
        assert_eq!(comps[1].mesh.node_set(&cut_set(0)).unwrap().len(), 4);
        // planes closer than an element are refused
        assert!(split_mesh("bar", &mesh, &[0.2, 0.21]).is_err());
    }
}
