//! The full-order coupled engine model: the reference the ROM is judged against.
//!
//! Unknowns: the interior DOFs of every part instance (crankcase, one liner per modelled
//! cylinder; interior = not on an interface set) and the global interface coordinates q (the
//! same interface fields as the ROM, see [`super::interface`]). A part's displacement is
//! u = P_i u_i + G q_p (G: the interface shapes on its boundary DOFs), so its contribution is
//!
//!   [ K_ii        K_ib G     ]      (and likewise for M)
//!   [ G^T K_bi    G^T K_bb G ]
//!
//! No modal truncation: the only difference from the ROM is the Craig-Bampton truncation, which
//! is what the comparison measures. The matrix is sparse (interface coordinates couple only to
//! DOFs next to their interface); it is ordered part by part (METIS on each part's interior
//! node graph) with q last, factorised once and solved by the certified ARPACK driver.

use super::craig_bampton::Load;
use super::craig_bampton::ReduceError;
use super::rom::RomError;
use super::rom::{RomBuild, RomInputs};
use crate::fem::assembly::NodeGraph;
use crate::fem::dofs::{DofMap, FIXED};
use crate::fem::model::{FeModel, ModelError};
use crate::linalg::factor::Analysis;
use crate::linalg::ordering;
use crate::linalg::sparse::{Pattern, StiffnessMass};
use crate::mesh::Mesh;
use std::collections::{BTreeMap, HashMap};

/// Result of the full coupled modal solve.
pub struct FullModes {
    pub frequencies_hz: Vec<f64>,
    pub residuals: Vec<f64>,
    pub sturm_ok: bool,
    pub dofs: usize,
    /// Mode shapes per part instance in the part's free-DOF numbering (instance-major:
    /// liners of the modelled cylinders, then the crankcase), one Vec per mode.
    pub shapes: Vec<Vec<Vec<f64>>>,
}

/// One part type prepared for coupling.
struct PartData {
    model: FeModel,
    /// Interior numbering (B) of each A DOF, FIXED on the boundary.
    a_to_b: Vec<usize>,
    n_int: usize,
    /// Interior DOF order (B indices) from nested dissection.
    order: Vec<usize>,
    /// Boundary coupling rows: A row -> K G and M G rows (length n_q of the part).
    kg: HashMap<usize, (Vec<f64>, Vec<f64>)>,
    qq_k: Vec<f64>,
    qq_m: Vec<f64>,
    nq: usize,
    /// G rows: boundary A DOF -> (column, value).
    g: HashMap<usize, Vec<(usize, f64)>>,
}

fn prepare(
    mesh: &Mesh,
    material: &crate::scene::spec::Elastic,
    surface: &[crate::fem::surface::SurfaceMass],
    fix: &[String],
    blocks: &[super::craig_bampton::InterfaceBlock],
) -> Result<PartData, ModelError> {
    let model = FeModel::build_with(mesh.clone(), material, fix, surface)?;
    let mut sets = fix.to_vec();
    sets.extend(blocks.iter().map(|b| b.set.clone()));
    let inner = DofMap::with_fixed_sets(mesh, &sets).map_err(ModelError::from)?;
    let na = model.n_free();
    let mut a_to_b = vec![FIXED; na];
    for (slot, &a) in model.dofs.dof.iter().enumerate() {
        if a != FIXED {
            a_to_b[a] = inner.dof[slot];
        }
    }
    // G rows
    let mut g: HashMap<usize, Vec<(usize, f64)>> = HashMap::new();
    let mut col0 = 0;
    for b in blocks {
        let nodes = mesh.node_set(&b.set).unwrap_or(&[]);
        for (k, &node) in nodes.iter().enumerate() {
            for i in 0..3 {
                let a = model.dofs.dof[3 * node + i];
                if a == FIXED {
                    continue;
                }
                let row = g.entry(a).or_default();
                for j in 0..b.psi.ncols() {
                    let v = b.psi[(3 * k + i, j)];
                    if v != 0.0 {
                        row.push((col0 + j, v));
                    }
                }
            }
        }
        col0 += b.psi.ncols();
    }
    let nq = col0;
    let p = &model.km.pattern;
    let mut kg: HashMap<usize, (Vec<f64>, Vec<f64>)> = HashMap::new();
    for (&b, row) in &g {
        for q in p.col_ptr[b]..p.col_ptr[b + 1] {
            let r = p.row_idx[q];
            let (kv, mv) = (model.km.k[q], model.km.m[q]);
            let e = kg
                .entry(r)
                .or_insert_with(|| (vec![0.0; nq], vec![0.0; nq]));
            for &(j, v) in row {
                e.0[j] += kv * v;
                e.1[j] += mv * v;
            }
        }
    }
    let mut qq_k = vec![0.0; nq * nq];
    let mut qq_m = vec![0.0; nq * nq];
    for (&b, row) in &g {
        if let Some((kr, mr)) = kg.get(&b) {
            for &(i, v) in row {
                for j in 0..nq {
                    qq_k[i * nq + j] += v * kr[j];
                    qq_m[i * nq + j] += v * mr[j];
                }
            }
        }
    }
    kg.retain(|&r, _| a_to_b[r] != FIXED);
    // nested dissection of the interior node graph
    let graph = NodeGraph::new(mesh);
    let node_dofs = inner.node_dofs();
    let keep: Vec<bool> = node_dofs.iter().map(|d| !d.is_empty()).collect();
    let (xadj, adjncy, ids) = graph.without_self_loops(&keep);
    let order_nodes = ordering::nested_dissection(&xadj, &adjncy).map_err(ModelError::Ordering)?;
    let node_perm: Vec<usize> = order_nodes.iter().map(|&v| ids[v]).collect();
    let (order, _) = ordering::expand_to_dofs(&node_perm, &node_dofs, inner.n_free);
    Ok(PartData {
        model,
        a_to_b,
        n_int: inner.n_free,
        order,
        kg,
        qq_k,
        qq_m,
        nq,
        g,
    })
}

/// The assembled full-order coupled engine model (see the module docs), ordered and analysed.
pub struct FullSystem {
    pub km: StiffnessMass,
    pub analysis: Analysis,
    /// Modelled cylinders (1-based); liner instance i is cylinder `cylinders[i]`.
    pub cylinders: Vec<usize>,
    liner: PartData,
    crankcase: PartData,
    /// First unknown of each instance's interior (liners, then the crankcase).
    offsets: Vec<usize>,
    n_int_total: usize,
    /// Per instance: the part's interface column -> global interface coordinate.
    qmaps: Vec<Vec<usize>>,
}

/// Global numbering of the interface coordinates: per modelled cylinder the liner's map (its
/// interface columns shared with the crankcase's blocks 3c and 3c + 1, the rest new), then the
/// crankcase's identity map; and their count.
fn interface_maps(
    liner: &PartData,
    liner_blocks: &[super::craig_bampton::InterfaceBlock],
    cc: &PartData,
    cc_blocks: &[super::craig_bampton::InterfaceBlock],
    cylinders: &[usize],
) -> (Vec<Vec<usize>>, usize) {
    let cols = |blocks: &[super::craig_bampton::InterfaceBlock]| {
        let mut v = Vec::new();
        let mut c0 = 0;
        for b in blocks {
            v.push(c0..c0 + b.psi.ncols());
            c0 += b.psi.ncols();
        }
        v
    };
    let (cc_cols, liner_cols) = (cols(cc_blocks), cols(liner_blocks));
    let mut nq_total = cc.nq;
    let mut qmaps: Vec<Vec<usize>> = Vec::new();
    for &cyl in cylinders {
        let c = cyl - 1;
        let mut map = vec![usize::MAX; liner.nq];
        for (lb, cb) in [(0usize, 3 * c), (1, 3 * c + 1)] {
            for (lj, gj) in liner_cols[lb].clone().zip(cc_cols[cb].clone()) {
                map[lj] = gj;
            }
        }
        for slot in map.iter_mut() {
            if *slot == usize::MAX {
                *slot = nq_total;
                nq_total += 1;
            }
        }
        qmaps.push(map);
    }
    qmaps.push((0..cc.nq).collect());
    (qmaps, nq_total)
}

/// The coupled model's unknowns: each part instance's interior DOFs from `offsets[inst]`,
/// then the `nq_total` interface coordinates from `n_int_total`.
struct Layout<'a> {
    parts: &'a [&'a PartData],
    offsets: &'a [usize],
    qmaps: &'a [Vec<usize>],
    n_int_total: usize,
    nq_total: usize,
}

impl Layout<'_> {
    /// Assembles K and M (lower and upper parts, column-compressed): per part instance its
    /// interior block and its interior-interface coupling rows, then the interface columns
    /// summed over the parts.
    fn assemble(&self) -> StiffnessMass {
        let n = self.n_int_total + self.nq_total;
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx: Vec<usize> = Vec::new();
        let mut kv: Vec<f64> = Vec::new();
        let mut mv: Vec<f64> = Vec::new();
        let mut qcols: Vec<BTreeMap<usize, (f64, f64)>> = vec![BTreeMap::new(); self.nq_total];
        let mut col = 0;
        for (inst, part) in self.parts.iter().enumerate() {
            let off = self.offsets[inst];
            let qmap = &self.qmaps[inst];
            let p = &part.model.km.pattern;
            let mut b_to_a = vec![0; part.n_int];
            for (a, &b) in part.a_to_b.iter().enumerate() {
                if b != FIXED {
                    b_to_a[b] = a;
                }
            }
            for (b, &a) in b_to_a.iter().enumerate() {
                debug_assert_eq!(col, off + b);
                let mut entries: Vec<(usize, f64, f64)> = Vec::new();
                for q in p.col_ptr[a]..p.col_ptr[a + 1] {
                    let r = part.a_to_b[p.row_idx[q]];
                    if r != FIXED {
                        entries.push((off + r, part.model.km.k[q], part.model.km.m[q]));
                    }
                }
                if let Some((kr, mr)) = part.kg.get(&a) {
                    for j in 0..part.nq {
                        entries.push((self.n_int_total + qmap[j], kr[j], mr[j]));
                        let e = qcols[qmap[j]].entry(off + b).or_insert((0.0, 0.0));
                        e.0 += kr[j];
                        e.1 += mr[j];
                    }
                }
                entries.sort_by_key(|e| e.0);
                for (r, k, m) in entries {
                    row_idx.push(r);
                    kv.push(k);
                    mv.push(m);
                }
                col += 1;
                col_ptr[col] = row_idx.len();
            }
            for i in 0..part.nq {
                for j in 0..part.nq {
                    let e = qcols[qmap[j]]
                        .entry(self.n_int_total + qmap[i])
                        .or_insert((0.0, 0.0));
                    e.0 += part.qq_k[i * part.nq + j];
                    e.1 += part.qq_m[i * part.nq + j];
                }
            }
        }
        for qc in &qcols {
            for (&r, &(k, m)) in qc {
                row_idx.push(r);
                kv.push(k);
                mv.push(m);
            }
            col += 1;
            col_ptr[col] = row_idx.len();
        }
        StiffnessMass {
            pattern: Pattern {
                n,
                col_ptr,
                row_idx,
            },
            k: kv,
            m: mv,
        }
    }

    /// The fill-reducing order: each part's own order of its interior DOFs, the interface
    /// coordinates last; (forward, inverse).
    fn ordering(&self) -> (Vec<usize>, Vec<usize>) {
        let n = self.n_int_total + self.nq_total;
        let mut fwd: Vec<usize> = Vec::with_capacity(n);
        for (inst, part) in self.parts.iter().enumerate() {
            fwd.extend(part.order.iter().map(|&b| self.offsets[inst] + b));
        }
        fwd.extend(self.n_int_total..n);
        let mut inv = vec![0; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        (fwd, inv)
    }
}

impl FullSystem {
    /// Assembles the full coupled model of the scene's meshes (the same interface fields as
    /// the ROM) and analyses its pattern.
    pub fn build(inp: &RomInputs<'_>) -> Result<Self, RomError> {
        let (liner_blocks, cc_blocks) = super::rom::interface_blocks(inp)?;
        let in_part = |part: &str| {
            let part = part.to_string();
            move |source| RomError::Reduce(ReduceError::Model { part, source })
        };
        let liner = prepare(
            inp.liner,
            &inp.liner_material,
            &inp.liner_surface_mass,
            &[],
            &liner_blocks,
        )
        .map_err(in_part("liner"))?;
        let cc = prepare(
            inp.crankcase,
            &inp.crankcase_material,
            &[],
            &inp.crankcase_fix,
            &cc_blocks,
        )
        .map_err(in_part("crankcase"))?;
        let nl = inp.cylinders.len();
        let (qmaps, nq_total) =
            interface_maps(&liner, &liner_blocks, &cc, &cc_blocks, &inp.cylinders);
        let n_int_total = nl * liner.n_int + cc.n_int;
        let offsets: Vec<usize> = (0..=nl).map(|i| i * liner.n_int).collect();
        let parts: Vec<&PartData> = (0..nl)
            .map(|_| &liner)
            .chain(std::iter::once(&cc))
            .collect();
        let layout = Layout {
            parts: &parts,
            offsets: &offsets,
            qmaps: &qmaps,
            n_int_total,
            nq_total,
        };
        let km = layout.assemble();
        let (fwd, inv) = layout.ordering();
        let analysis = Analysis::new(&km.pattern, &fwd, &inv)
            .map_err(|e| in_part("engine")(ModelError::from(e)))?;
        Ok(Self {
            km,
            analysis,
            cylinders: inp.cylinders.clone(),
            liner,
            crankcase: cc,
            offsets,
            n_int_total,
            qmaps,
        })
    }

    /// Unknowns of the coupled model.
    pub fn dofs(&self) -> usize {
        self.km.pattern.n
    }

    /// Part instances: one liner per modelled cylinder, then the crankcase.
    pub fn instances(&self) -> usize {
        self.cylinders.len() + 1
    }

    fn part(&self, inst: usize) -> &PartData {
        if inst < self.cylinders.len() {
            &self.liner
        } else {
            &self.crankcase
        }
    }

    /// The displacement of `node` of instance `inst` along `dir` as a sparse row over the
    /// unknowns: u . dir = sum_k row_k x_k (interior DOFs directly, interface DOFs through
    /// their interface shapes G). Constrained DOFs contribute nothing.
    pub fn node_row(&self, inst: usize, node: usize, dir: [f64; 3]) -> Vec<(usize, f64)> {
        let part = self.part(inst);
        let mut row = Vec::new();
        for (i, &d) in dir.iter().enumerate() {
            let a = part.model.dofs.dof[3 * node + i];
            if a == FIXED || d == 0.0 {
                continue;
            }
            let b = part.a_to_b[a];
            if b != FIXED {
                row.push((self.offsets[inst] + b, d));
            } else if let Some(g) = part.g.get(&a) {
                for &(c, v) in g {
                    row.push((self.n_int_total + self.qmaps[inst][c], d * v));
                }
            }
        }
        row
    }

    /// Adds the generalised force of `load` (nodal forces on instance `inst`) to `f`:
    /// f += T^T f_part, T the map from unknowns to the part's nodal displacements.
    pub fn add_load(&self, inst: usize, load: &Load, f: &mut [f64]) {
        for &(node, force) in &load.entries {
            for (i, &fi) in force.iter().enumerate() {
                let mut e = [0.0; 3];
                e[i] = 1.0;
                for (k, v) in self.node_row(inst, node, e) {
                    f[k] += v * fi;
                }
            }
        }
    }

    /// A solution vector split into each instance's free-DOF displacement (part numbering).
    pub fn part_displacements(&self, v: &[f64]) -> Vec<Vec<f64>> {
        (0..self.instances())
            .map(|inst| {
                let part = self.part(inst);
                let mut u = vec![0.0; part.model.n_free()];
                for (a, &b) in part.a_to_b.iter().enumerate() {
                    if b != FIXED {
                        u[a] = v[self.offsets[inst] + b];
                    }
                }
                for (&a, row) in &part.g {
                    u[a] = row
                        .iter()
                        .map(|&(c, val)| val * v[self.n_int_total + self.qmaps[inst][c]])
                        .sum();
                }
                u
            })
            .collect()
    }

    /// Each instance's DOF map (for writing shapes on the meshes).
    pub fn dof_maps(&self) -> Vec<&DofMap> {
        (0..self.instances())
            .map(|i| &self.part(i).model.dofs)
            .collect()
    }
}

/// The first `count` ROM system modes on the parts' free DOFs (instance-major: liners of the
/// modelled cylinders, then the crankcase), from a build that kept its bases.
///
/// `None` when the build did not keep its bases.
pub fn recover_shapes(b: &RomBuild, count: usize) -> Option<Vec<Vec<Vec<f64>>>> {
    let lb = b.liner.basis.as_ref()?;
    let cb = b.crankcase.basis.as_ref()?;
    let mut shapes = Vec::new();
    for j in 0..count {
        let y = b.system.vectors.as_ref().col(j);
        let mut per = Vec::new();
        let recover = |basis: &faer::Mat<f64>, map: &[usize]| -> Vec<f64> {
            let mut u = vec![0.0; basis.nrows()];
            for (k, &g) in map.iter().enumerate() {
                let c = y[g];
                if c != 0.0 {
                    for i in 0..basis.nrows() {
                        u[i] += basis[(i, k)] * c;
                    }
                }
            }
            u
        };
        for map in &b.liner_maps {
            per.push(recover(lb, map));
        }
        per.push(recover(cb, &b.crankcase_map));
        shapes.push(per);
    }
    Some(shapes)
}
