//! Merging meshes: coincident nodes (within a tolerance) become one node.

use super::{ElementBlock, Mesh};
use std::collections::HashMap;

/// Merges `parts` into one mesh; nodes closer than `tol` are joined. Node and element sets are
/// carried over (sets of the same name are united).
///
/// Nodes are bucketed on a grid of cell size `tol`; a node is compared with the nodes of the 27
/// surrounding cells, so joining does not depend on where the grid falls.
pub fn merge(parts: Vec<Mesh>, tol: f64) -> Mesh {
    let mut out = Mesh::default();
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let cell = |p: &[f64; 3]| -> [i64; 3] {
        [
            (p[0] / tol).floor() as i64,
            (p[1] / tol).floor() as i64,
            (p[2] / tol).floor() as i64,
        ]
    };
    let mut elem_offset = 0;
    for part in parts {
        let mut map = Vec::with_capacity(part.nodes.len());
        for p in &part.nodes {
            let c = cell(p);
            let mut found = None;
            'search: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                            for &n in list {
                                let q = out.nodes[n];
                                let d2 = (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>();
                                if d2 <= tol * tol {
                                    found = Some(n);
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            let id = found.unwrap_or_else(|| {
                out.nodes.push(*p);
                grid.entry(c).or_default().push(out.nodes.len() - 1);
                out.nodes.len() - 1
            });
            map.push(id);
        }
        for block in &part.blocks {
            let conn = block.conn.iter().map(|&n| map[n]);
            match out.blocks.iter_mut().find(|b| b.kind == block.kind) {
                Some(b) => b.conn.extend(conn),
                None => out.blocks.push(ElementBlock {
                    kind: block.kind,
                    conn: conn.collect(),
                }),
            }
        }
        for (name, nodes) in &part.node_sets {
            let set = out.node_sets.entry(name.clone()).or_default();
            set.extend(nodes.iter().map(|&n| map[n]));
            set.sort_unstable();
            set.dedup();
        }
        for (name, elems) in &part.element_sets {
            out.element_sets
                .entry(name.clone())
                .or_default()
                .extend(elems.iter().map(|&e| e + elem_offset));
        }
        elem_offset += part.num_elements();
    }
    out
}
