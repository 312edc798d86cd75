//! What the rock costs a factorisation, and what reusing one ordering
//! costs, on the mechanical matrix of a scene (METIS; 3 dofs per node,
//! joint pairs coupled, no supports: the fill, not the values):
//!
//! 1. rock elements by elevation;
//! 2. the complete dam and rock, the concrete alone, the concrete with the
//!    rock's Schur complement on the rock–concrete interface (a dense
//!    block), and the one-off factorisation of the rock with the
//!    interface last;
//! 3. the rock and the concrete below a quarter, half, three quarters and
//!    all of the height: a METIS call of its own against the complete
//!    mesh's order restricted to its dofs (relative order kept, as
//!    `mechanics::live::ConstructionOrdering` does), and (4.) the share
//!    of each below;
//! 4. on the complete matrix's METIS order, the supernodes whose whole
//!    subtree holds only rock unknowns: their columns of L never change
//!    while the rock stays linear, so their share of the flops and entries
//!    is what a factorisation and a solve could keep from one day to the
//!    next if that rock were condensed once.
//!
//!     cargo run --release --example rock_condensation [SCENE]
use groutready::fem::{metis_nested_dissection, CholeskySolver, Ordering, Pattern};
use groutready::mesh::{Mesh, Part};
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    let inputs = groutready::app::load_inputs(std::path::Path::new(&path), None)?;
    let mesh = &inputs.mesh;
    rock_layers(mesh);
    condensation(mesh)?;
    ordering_reuse(mesh)?;
    frozen_subtrees(mesh)
}

fn node_dofs(v: u32) -> [u32; 3] {
    [3 * v, 3 * v + 1, 3 * v + 2]
}

/// The pattern of the elements `live` and the joint pairs between live
/// nodes, with node `v` numbered `map[v]` (u32::MAX: not in it), plus
/// `extra` element dof lists.
fn pattern(
    mesh: &Mesh,
    live: &dyn Fn(usize) -> bool,
    map: &[u32],
    n: u32,
    extra: &[Vec<u32>],
) -> Arc<Pattern> {
    let m = |v: u32| node_dofs(map[v as usize]);
    let mut elems: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| live(e))
        .map(|(_, c)| c.iter().flat_map(|&v| m(v)).collect())
        .collect();
    for p in &mesh.face_pairs {
        for k in 0..4 {
            let (a, b) = (p.nodes_a[k], p.nodes_b[k]);
            if a != b && map[a as usize] != u32::MAX && map[b as usize] != u32::MAX {
                elems.push([m(a), m(b)].concat());
            }
        }
    }
    elems.extend(extra.iter().cloned());
    Arc::new(Pattern::new(3 * n as usize, &elems))
}

/// Numbers the nodes `keep` in increasing order; returns the map and count.
fn number(keep: impl Fn(usize) -> bool, nn: usize) -> (Vec<u32>, u32) {
    let mut map = vec![u32::MAX; nn];
    let mut n = 0u32;
    for (v, slot) in map.iter_mut().enumerate() {
        if keep(v) {
            *slot = n;
            n += 1;
        }
    }
    (map, n)
}

fn report(name: &str, pattern: Arc<Pattern>, ord: Ordering) -> anyhow::Result<CholeskySolver> {
    let t = Instant::now();
    let s = CholeskySolver::with_options(pattern.clone(), &ord, faer::Par::Seq)?;
    println!(
        "{name:24} n={:8} nnz(A)={:10} nnz(L)={:11} flops={:8.2} Gflop (analysis {:.2} s)",
        pattern.n_dofs(),
        pattern.nnz(),
        s.factor_nnz(),
        s.factor_flops() / 1e9,
        t.elapsed().as_secs_f64()
    );
    Ok(s)
}

/// Rock elements by the elevation of their centres.
fn rock_layers(mesh: &Mesh) {
    let mut zs: Vec<i64> = Vec::new();
    for (e, conn) in mesh.elements.iter().enumerate() {
        if mesh.parts[e] == Part::Rock {
            let z: f64 = conn.iter().map(|&v| mesh.nodes[v as usize][2]).sum::<f64>() / 8.0;
            zs.push((z / 50.0).floor() as i64 * 50);
        }
    }
    zs.sort();
    for chunk in zs.chunk_by(|a, b| a == b) {
        let z = chunk[0];
        println!(
            "rock elements with centre in [{z}, {}) m: {}",
            z + 50,
            chunk.len()
        );
    }
}

/// Part 2 of the module doc.
fn condensation(mesh: &Mesh) -> anyhow::Result<()> {
    let nn = mesh.nodes.len();
    let (mut in_rock, mut in_conc) = (vec![false; nn], vec![false; nn]);
    for (e, conn) in mesh.elements.iter().enumerate() {
        let flag = match mesh.parts[e] {
            Part::Rock => &mut in_rock,
            Part::Concrete { .. } => &mut in_conc,
        };
        conn.iter().for_each(|&v| flag[v as usize] = true);
    }
    let all = |_: usize| true;
    let concrete = |e: usize| mesh.parts[e] != Part::Rock;
    let identity: Vec<u32> = (0..nn as u32).collect();
    report(
        "complete",
        pattern(mesh, &all, &identity, nn as u32, &[]),
        Ordering::Metis,
    )?;

    let (map, n_ci) = number(|v| in_conc[v], nn);
    let interface: Vec<u32> = (0..nn as u32)
        .filter(|&v| in_conc[v as usize] && in_rock[v as usize])
        .collect();
    report(
        "concrete",
        pattern(mesh, &concrete, &map, n_ci, &[]),
        Ordering::Metis,
    )?;
    println!(
        "interface: {} nodes, {} dofs",
        interface.len(),
        3 * interface.len()
    );
    let clique: Vec<u32> = interface
        .iter()
        .flat_map(|&v| node_dofs(map[v as usize]))
        .collect();
    report(
        "concrete + condensed",
        pattern(mesh, &concrete, &map, n_ci, &[clique]),
        Ordering::Metis,
    )?;

    // the rock, interior first (METIS) and the interface last
    let (mut map, n_r) = number(|v| in_rock[v] && !in_conc[v], nn);
    for (k, &v) in interface.iter().enumerate() {
        map[v as usize] = n_r + k as u32;
    }
    let n_ri = n_r + interface.len() as u32;
    let rock = |e: usize| mesh.parts[e] == Part::Rock;
    let mut perm = metis_nested_dissection(&interior_pattern(mesh, &map, n_r))?;
    perm.extend(3 * n_r..3 * n_ri);
    report(
        "rock, interface last",
        pattern(mesh, &rock, &map, n_ri, &[]),
        Ordering::Custom(perm),
    )?;
    Ok(())
}

/// The rock elements' couplings among the rock's interior dofs (numbered
/// below `3 n_r` by `map`).
fn interior_pattern(mesh: &Mesh, map: &[u32], n_r: u32) -> Pattern {
    let elems: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| mesh.parts[e] == Part::Rock)
        .map(|(_, c)| {
            c.iter()
                .flat_map(|&v| node_dofs(map[v as usize]))
                .filter(|&d| d < 3 * n_r)
                .collect()
        })
        .collect();
    Pattern::new(3 * n_r as usize, &elems)
}

/// Part 3 of the module doc.
fn ordering_reuse(mesh: &Mesh) -> anyhow::Result<()> {
    let nn = mesh.nodes.len();
    let identity: Vec<u32> = (0..nn as u32).collect();
    let t = Instant::now();
    let complete = metis_nested_dissection(&pattern(mesh, &|_| true, &identity, nn as u32, &[]))?;
    println!("complete: METIS {:.2} s", t.elapsed().as_secs_f64());
    let (zmin, zmax) = (mesh.layer_z[0], mesh.crest_z);
    for frac in [0.25, 0.5, 0.75, 1.0] {
        let zcut = zmin + frac * (zmax - zmin);
        let live = |e: usize| match mesh.parts[e] {
            Part::Rock => true,
            Part::Concrete { .. } => {
                let c = &mesh.elements[e];
                c.iter().map(|&v| mesh.nodes[v as usize][2]).sum::<f64>() / 8.0 < zcut
            }
        };
        let mut node_live = vec![false; nn];
        for e in (0..mesh.elements.len()).filter(|&e| live(e)) {
            mesh.elements[e]
                .iter()
                .for_each(|&v| node_live[v as usize] = true);
        }
        let (map, n) = number(|v| node_live[v], nn);
        let p = pattern(mesh, &live, &map, n, &[]);
        println!("concrete below {zcut:.1} m:");
        report("  its own METIS", p.clone(), Ordering::Metis)?;
        let restricted: Vec<u32> = complete
            .iter()
            .filter_map(|&d| {
                let m = map[d as usize / 3];
                (m != u32::MAX).then(|| 3 * m + d % 3)
            })
            .collect();
        report(
            "  the complete order",
            p.clone(),
            Ordering::Custom(restricted.clone()),
        )?;
        let conc = in_concrete(mesh, &live);
        let mut node_of = vec![0u32; n as usize];
        for (v, &m) in map.iter().enumerate() {
            if m != u32::MAX {
                node_of[m as usize] = v as u32;
            }
        }
        frozen_share("  the complete order", &p, &restricted, &|d| {
            conc[node_of[d / 3] as usize]
        })?;
    }
    Ok(())
}

/// Part 4 of the module doc, on the complete matrix.
fn frozen_subtrees(mesh: &Mesh) -> anyhow::Result<()> {
    let nn = mesh.nodes.len();
    let identity: Vec<u32> = (0..nn as u32).collect();
    let p = pattern(mesh, &|_| true, &identity, nn as u32, &[]);
    let fwd = metis_nested_dissection(&p)?;
    let conc = in_concrete(mesh, &|_| true);
    frozen_share("complete", &p, &fwd, &|d| conc[d / 3])
}

/// Nodes of the live concrete elements.
fn in_concrete(mesh: &Mesh, live: &dyn Fn(usize) -> bool) -> Vec<bool> {
    let mut in_conc = vec![false; mesh.nodes.len()];
    for (e, conn) in mesh.elements.iter().enumerate() {
        if mesh.parts[e] != Part::Rock && live(e) {
            conn.iter().for_each(|&v| in_conc[v as usize] = true);
        }
    }
    in_conc
}

/// The share of one factorisation's flops and entries in the supernodes
/// whose subtree holds only rock unknowns (`concrete(dof)` false), on the
/// order `fwd` of `p`.
fn frozen_share(
    name: &str,
    p: &Pattern,
    fwd: &[u32],
    concrete: &dyn Fn(usize) -> bool,
) -> anyhow::Result<()> {
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    };
    let n = p.n_dofs();
    let mut inv = vec![0u32; n];
    for (k, &d) in fwd.iter().enumerate() {
        inv[d as usize] = k as u32;
    }
    let sym = factorize_symbolic_cholesky(
        p.symbolic(),
        faer::Side::Upper,
        SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, &inv, n)),
        Default::default(),
    )
    .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let SymbolicCholeskyRaw::Supernodal(s) = sym.raw() else {
        anyhow::bail!("not supernodal");
    };
    let u = |x: &[u32]| x.iter().map(|&v| v as usize).collect::<Vec<usize>>();
    let (begin, end) = (u(s.supernode_begin()), u(s.supernode_end()));
    let (rptr, ridx) = (u(s.col_ptr_for_row_idx()), u(s.row_idx()));
    let ns = s.n_supernodes();
    let mut sn_of = vec![0usize; n];
    for k in 0..ns {
        sn_of[begin[k]..end[k]].iter_mut().for_each(|x| *x = k);
    }
    // children before parents: a supernode is frozen when its columns are
    // rock-only and no child is live
    let mut frozen: Vec<bool> = (0..ns)
        .map(|k| (begin[k]..end[k]).all(|c| !concrete(fwd[c] as usize)))
        .collect();
    for k in 0..ns {
        if !frozen[k] {
            if let Some(&r) = ridx[rptr[k]..rptr[k + 1]].first() {
                frozen[sn_of[r]] = false;
            }
        }
    }
    let (mut fl, mut fl_frozen, mut nnz, mut nnz_frozen, mut cols_frozen, mut c_entries) =
        (0.0, 0.0, 0.0, 0.0, 0usize, 0.0);
    for k in 0..ns {
        let w = (end[k] - begin[k]) as f64;
        let below = (rptr[k + 1] - rptr[k]) as f64;
        let f: f64 = (0..w as usize)
            .map(|i| (w - i as f64 + below).powi(2))
            .sum();
        let e = w * (w + 1.0) / 2.0 + w * below;
        fl += f;
        nnz += e;
        if frozen[k] {
            fl_frozen += f;
            nnz_frozen += e;
            cols_frozen += end[k] - begin[k];
            let root = ridx[rptr[k]..rptr[k + 1]]
                .first()
                .is_none_or(|&r| !frozen[sn_of[r]]);
            if root {
                c_entries += below * (below + 1.0) / 2.0;
            }
        }
    }
    println!(
        "{name:24} frozen rock subtrees: {cols_frozen} of {n} columns, {:.1}M of {:.1}M entries \
         of L ({:.1} %), {:.2} of {:.2} Gflop ({:.1} %); their update blocks {:.1}M entries",
        nnz_frozen / 1e6,
        nnz / 1e6,
        100.0 * nnz_frozen / nnz,
        fl_frozen / 1e9,
        fl / 1e9,
        100.0 * fl_frozen / fl,
        c_entries / 1e6
    );
    Ok(())
}
