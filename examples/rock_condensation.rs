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
//! 5. layer merging (`mechanics::layer_merging`): the concrete's vertical
//!    grid lines off the joint faces keeping only the node levels of the
//!    grouting zones' boundaries, the nodes between tied to them, below
//!    the top three zones of the dam poured to a half, three quarters and
//!    all of its height; ordered by METIS on the tied set, by the untied
//!    complete dam's order, and by the merged complete dam's order with
//!    each node that may be tied just before its master below (the
//!    mechanics' `ConstructionOrdering` with merging on). A copy of a scene
//!    with `[lifts] height_m` at the zone height bounds what thicker layers
//!    (rock and all) would give: the example builds the mesh alone.
//!
//!     cargo run --release --example rock_condensation [SCENE]
use groutready::fem::{metis_nested_dissection, CholeskySolver, Ordering, Pattern};
use groutready::mechanics::layer_merging::LayerMerge;
use groutready::mechanics::Supports;
use groutready::mesh::{Mesh, Part};
use std::sync::Arc;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or("models/demo_arch.toml".into());
    // the mesh alone: a copy of a scene with other lifts (layer merging's
    // bound, `[lifts] height_m`) need not match its schedules
    let scene = groutready::scene::Scene::load(std::path::Path::new(&path))?;
    let mesh = &groutready::app::build_mesh(&scene, &path)?;
    rock_layers(mesh);
    condensation(mesh)?;
    ordering_reuse(mesh)?;
    frozen_subtrees(mesh)?;
    merged_concrete(mesh)
}

fn node_dofs(v: u32) -> [u32; 3] {
    [3 * v, 3 * v + 1, 3 * v + 2]
}

/// The pattern of the elements `live` and the joint pairs between live
/// nodes, with node `v` numbered `map[v]` (u32::MAX: not in it), plus
/// `extra` element dof lists: [`tied_pattern`] with every node its own
/// master.
fn pattern(
    mesh: &Mesh,
    live: &dyn Fn(usize) -> bool,
    map: &[u32],
    n: u32,
    extra: &[Vec<u32>],
) -> Arc<Pattern> {
    let own: Vec<Vec<u32>> = (0..mesh.nodes.len() as u32).map(|v| vec![v]).collect();
    tied_pattern(mesh, &own, map, n, live, extra)
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
        frozen_share("  the complete order", "rock", &p, &restricted, &|d| {
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
    let rock = frozen_share("complete", "rock", &p, &fwd, &|d| conc[d / 3])?;
    // Within one step only the joints' rows change (contact states, grout
    // layers cracking): the subtrees without a joint face's unknown keep
    // their columns of L from one refactorisation of the step to the next.
    let mut on_joint = vec![false; nn];
    for fp in &mesh.face_pairs {
        for v in fp.nodes_a.iter().chain(&fp.nodes_b) {
            on_joint[*v as usize] = true;
        }
    }
    let step = frozen_share("complete", "joint-free", &p, &fwd, &|d| on_joint[d / 3])?;
    println!(
        "{:24} beyond the condensed rock, a refactorisation within a step could keep \
         {:.1} % of the flops and {:.1} % of the entries of L (the joint-free concrete subtrees)",
        "",
        100.0 * (step.flops_frozen - rock.flops_frozen) / (step.flops - rock.flops_frozen),
        100.0 * (step.entries_frozen - rock.entries_frozen) / (step.entries - rock.entries_frozen),
    );
    Ok(())
}

/// What [`frozen_share`] measured.
struct Share {
    flops: f64,
    flops_frozen: f64,
    entries: f64,
    entries_frozen: f64,
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
/// whose subtree holds no changing unknown (`changes(dof)` false: the rock
/// with `changes` the concrete), on the order `fwd` of `p`.
fn frozen_share(
    name: &str,
    what: &str,
    p: &Pattern,
    fwd: &[u32],
    changes: &dyn Fn(usize) -> bool,
) -> anyhow::Result<Share> {
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
        .map(|k| (begin[k]..end[k]).all(|c| !changes(fwd[c] as usize)))
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
        "{name:24} frozen {what} subtrees: {cols_frozen} of {n} columns, {:.1}M of {:.1}M entries \
         of L ({:.1} %), {:.2} of {:.2} Gflop ({:.1} %); their update blocks {:.1}M entries",
        nnz_frozen / 1e6,
        nnz / 1e6,
        100.0 * nnz_frozen / nnz,
        fl_frozen / 1e9,
        fl / 1e9,
        100.0 * fl_frozen / fl,
        c_entries / 1e6
    );
    Ok(Share {
        flops: fl,
        flops_frozen: fl_frozen,
        entries: nnz,
        entries_frozen: nnz_frozen,
    })
}

/// Per node: itself, or the two masters `merge` ties it to when it is
/// in `tied`.
fn masters_of(merge: &LayerMerge, tied: &[u32], nn: usize) -> Vec<Vec<u32>> {
    let mut masters: Vec<Vec<u32>> = (0..nn as u32).map(|v| vec![v]).collect();
    for &v in tied {
        if let Some(t) = merge.tie_of(v) {
            masters[v as usize] = vec![t.lo, t.hi];
        }
    }
    masters
}

/// The pattern of the elements `live` and the joint pairs, each node's dofs
/// those of its masters (numbered by `map`; a pair with an unnumbered node
/// that is its own master is left out), plus `extra` element dof lists.
fn tied_pattern(
    mesh: &Mesh,
    masters: &[Vec<u32>],
    map: &[u32],
    n: u32,
    live: &dyn Fn(usize) -> bool,
    extra: &[Vec<u32>],
) -> Arc<Pattern> {
    let dofs = |nodes: &mut dyn Iterator<Item = u32>| {
        let mut d: Vec<u32> = nodes
            .flat_map(|v| masters[v as usize].clone())
            .flat_map(|m| node_dofs(map[m as usize]))
            .collect();
        d.sort_unstable();
        d.dedup();
        d
    };
    let mut elems: Vec<Vec<u32>> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| live(e))
        .map(|(_, c)| dofs(&mut c.iter().copied()))
        .collect();
    for p in &mesh.face_pairs {
        for k in 0..4 {
            if map[p.nodes_a[k] as usize] == u32::MAX && masters[p.nodes_a[k] as usize].len() == 1
                || map[p.nodes_b[k] as usize] == u32::MAX
                    && masters[p.nodes_b[k] as usize].len() == 1
            {
                continue;
            }
            elems.push(dofs(&mut [p.nodes_a[k], p.nodes_b[k]].into_iter()));
        }
    }
    elems.extend(extra.iter().cloned());
    Arc::new(Pattern::new(3 * n as usize, &elems))
}

/// Node sequence of a dof order over `map`'s numbering.
fn node_sequence(order: &[u32], map: &[u32]) -> Vec<u32> {
    let mut node_of = vec![u32::MAX; map.len()];
    for (v, &m) in map.iter().enumerate() {
        if m != u32::MAX {
            node_of[m as usize] = v as u32;
        }
    }
    let mut seen = vec![false; map.len()];
    let mut out = Vec::new();
    for &d in order {
        let v = node_of[d as usize / 3];
        if !seen[v as usize] {
            seen[v as usize] = true;
            out.push(v);
        }
    }
    out
}

/// Part 5 of the module doc: live sets of the dam poured to a half, three
/// quarters and all of its height, the concrete tied (`LayerMerge`) below
/// three zones under the top; before them, how far the tied nodes lie off
/// their chords.
fn merged_concrete(mesh: &Mesh) -> anyhow::Result<()> {
    let nn = mesh.nodes.len();
    let supported = Supports::far_boundary(mesh).flags(nn);
    let merge = LayerMerge::build(mesh, &supported, 1);
    let every: Vec<u32> = merge.all().iter().map(|&(v, _)| v).collect();
    let all = masters_of(&merge, &every, nn);
    let offs: Vec<f64> = merge
        .all()
        .iter()
        .map(|&(v, t)| {
            let (lo, hi, x) = (
                mesh.nodes[t.lo as usize],
                mesh.nodes[t.hi as usize],
                mesh.nodes[v as usize],
            );
            (0..3)
                .map(|k| (x[k] - (1.0 - t.w) * lo[k] - t.w * hi[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    for lim in [0.01, 0.02, 0.05, 0.1, 0.2, 0.5] {
        println!(
            "nodes merging may tie within {lim} m of their chords: {} of {}",
            offs.iter().filter(|&&o| o <= lim).count(),
            offs.len()
        );
    }
    let identity: Vec<u32> = (0..nn as u32).collect();
    let fine = metis_nested_dissection(&pattern(mesh, &|_| true, &identity, nn as u32, &[]))?;
    let fine_nodes = node_sequence(&fine, &identity);
    let (map_all, n_all) = number(|v| all[v].len() == 1, nn);
    let merged_order =
        metis_nested_dissection(&tied_pattern(mesh, &all, &map_all, n_all, &|_| true, &[]))?;
    let merged_nodes = node_sequence(&merged_order, &map_all);
    // each node that may be tied just before the master eliminated first
    let mut at = vec![usize::MAX; nn];
    for (k, &m) in merged_nodes.iter().enumerate() {
        at[m as usize] = k;
    }
    let mut before: Vec<Vec<u32>> = vec![Vec::new(); nn];
    for (v, t) in merge.all() {
        let first = if at[t.lo as usize] <= at[t.hi as usize] {
            t.lo
        } else {
            t.hi
        };
        before[first as usize].push(v);
    }
    let merged_seq: Vec<u32> = merged_nodes
        .iter()
        .flat_map(|&m| before[m as usize].iter().copied().chain([m]))
        .collect();
    let (zmin, zmax) = (mesh.layer_z[0], mesh.crest_z);
    let zone = mesh.lift_height * mesh.zone_lifts as f64;
    let centre = |e: usize| {
        mesh.elements[e]
            .iter()
            .map(|&v| mesh.nodes[v as usize][2])
            .sum::<f64>()
            / 8.0
    };
    for frac in [0.5, 0.75, 1.0] {
        let zcut = zmin + frac * (zmax - zmin);
        let live = |e: usize| mesh.parts[e] == Part::Rock || centre(e) < zcut;
        let mut node_live = vec![false; nn];
        for e in (0..mesh.elements.len()).filter(|&e| live(e)) {
            mesh.elements[e]
                .iter()
                .for_each(|&v| node_live[v as usize] = true);
        }
        // the top three zones too young to merge
        let all_live = vec![true; mesh.elements.len()];
        let birth: Vec<f64> = (0..mesh.elements.len())
            .map(|e| {
                if centre(e) < zcut - 3.0 * zone {
                    0.0
                } else {
                    1e9
                }
            })
            .collect();
        let tied = masters_of(&merge, &merge.tied_at(&all_live, &birth, 1.0), nn);
        let untied = masters_of(&merge, &[], nn);
        for (name, m) in [("untied", &untied), ("tied", &tied)] {
            let (map, n) = number(|v| node_live[v] && m[v].len() == 1, nn);
            let p = tied_pattern(mesh, m, &map, n, &live, &[]);
            println!(
                "live below {zcut:.1} m, {name}, {} tied:",
                (0..nn).filter(|&v| node_live[v] && m[v].len() == 2).count()
            );
            report("  its own METIS", p.clone(), Ordering::Metis)?;
            let dofs_of = |seq: &mut dyn Iterator<Item = u32>| -> Vec<u32> {
                seq.filter(|&v| map[v as usize] != u32::MAX)
                    .flat_map(|v| node_dofs(map[v as usize]))
                    .collect()
            };
            report(
                "  the fine order",
                p.clone(),
                Ordering::Custom(dofs_of(&mut fine_nodes.iter().copied())),
            )?;
            report(
                "  the merged order",
                p,
                Ordering::Custom(dofs_of(&mut merged_seq.iter().copied())),
            )?;
        }
    }
    Ok(())
}
