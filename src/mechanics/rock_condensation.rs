//! The rock that no step changes, condensed once per run.
//!
//! The rock is linear and never ages, so its stiffness is the same on every
//! day. Order the complete dam's unknowns by the construction ordering
//! ([`super::live::ConstructionOrdering`], METIS's nested dissection) and
//! call a column of the elimination tree *frozen* when its unknown belongs
//! to rock elements only and every column below it is frozen. The frozen
//! columns R form whole subtrees; their columns of L depend on the rock's
//! stiffness alone, in every live set (the rock is born whole on day 0 and
//! the live sets are eliminated in the restriction of the same order).
//! With D the other unknowns,
//!
//! ```text
//! [A_RR  A_RD] [x_R]   [b_R]        S x_D = b_D − A_DR A_RR⁻¹ b_R,
//! [A_DR  A_DD] [x_D] = [b_D]   ⇔    x_R  = A_RR⁻¹ (b_R − A_RD x_D),
//!                                   S    = A_DD − C,  C = A_DR A_RR⁻¹ A_RD,
//! ```
//!
//! and A_RR, A_RD and C are constant: A_RR is factorised once, C is
//! computed once, and each step factorises S, the live set without R. S
//! has the fill of L's other columns (C couples the boundary of each frozen
//! subtree, which the subtree's root already couples in L), so a
//! factorisation saves the frozen columns' flops and every solve of the
//! contact passes their entries: on the demo's complete dam 11.4 % of the
//! flops and 18.5 % of L; poured to a quarter of its height 54.3 % and
//! 63.5 % (`cargo run --release --example rock_condensation`). A step pays
//! two solves with A_RR's factor (its loads condensed, x_R recovered).
//!
//! The frozen subtrees are independent (A_RR is block diagonal by them),
//! so C is a sum of dense blocks C_T over each subtree's boundary,
//! computed subtree by subtree; the live system assembles −C_T as an
//! element of its own ([`CondensedRock::blocks`]).
//!
//! Supported rock unknowns stay in R, held (A_RR's row the identity): their
//! increment, zero unless prescribed, enters b_R and b_D through their
//! couplings. Off with tied rock (`solver.rock_coarsening` above 1) and
//! with orderings other than the construction ordering, whose live sets
//! are not eliminated in one order. `solver.condense_rock = false` keeps
//! the whole rock in every step, the exact path `groutready study perf`
//! compares with.
//!
//! Verified by the unit tests below (the condensed solve against the whole
//! one on a block of rock with a live part) and `tests/it/fast_path.rs`
//! (a staged dam with joints against the run without condensation).

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::simplicial;
use faer::sparse::SymbolicSparseColMatRef;
use faer::{Mat, Par};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::fem::{CholeskySolver, Ordering, Pattern, SolveError, SparseSym, NO_DOF};

use super::live::NONE;

/// Columns of a subtree's boundary solved at once while C is computed.
const CHUNK: usize = 64;

/// One frozen subtree's share of C, as an element of the live systems.
#[derive(Debug, Clone)]
pub struct SchurBlock {
    /// the global node dofs of the subtree's boundary
    pub dofs: Vec<u32>,
    /// −C_T over `dofs`
    pub minus_c: DMatrix<f64>,
}

/// The frozen rock: its factor, its coupling to the rest, and C.
pub struct CondensedRock {
    /// condensed index of each global node dof (NONE: not condensed)
    pub index: Vec<u32>,
    /// global node dof of each condensed unknown, in elimination order
    pub dofs: Vec<u32>,
    /// A_RR, held at the supported unknowns
    solver: CholeskySolver,
    /// A_RD as (condensed index, global dof, value), sorted by condensed
    /// index
    coupling: Vec<(u32, u32, f64)>,
    /// supported condensed unknowns
    held: Vec<bool>,
    /// A's couplings of the held unknowns: (held index, condensed index of
    /// a free one, value) and (held index, global dof not condensed, value)
    held_to_r: Vec<(u32, u32, f64)>,
    held_to_d: Vec<(u32, u32, f64)>,
    /// C by frozen subtree
    pub blocks: Vec<SchurBlock>,
}

impl std::fmt::Debug for CondensedRock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CondensedRock")
            .field("n", &self.dofs.len())
            .field("blocks", &self.blocks.len())
            .finish_non_exhaustive()
    }
}

/// The rock as the condensation reads it.
pub struct RockElements<'a> {
    /// connectivity of every element of the mesh
    pub conn: &'a [[u32; 8]],
    /// rock or not, per element
    pub rock: &'a [bool],
    /// the unit-modulus stiffness of each element
    pub k_unit: &'a [crate::fem::elasticity::PackedSym24],
    /// the rock's modulus \[Pa\]
    pub modulus: f64,
    /// supported global node dofs
    pub supported: &'a [bool],
}

impl CondensedRock {
    /// Condenses the global node dofs `frozen` (in elimination order
    /// `order`, each dof of it once): factorises A_RR and computes C.
    /// None when nothing is frozen.
    pub fn new(rock: &RockElements, order: &[u32]) -> Result<Option<CondensedRock>, SolveError> {
        let n_global = rock.supported.len();
        let mut index = vec![NONE; n_global];
        for (r, &g) in order.iter().enumerate() {
            index[g as usize] = r as u32;
        }
        let n = order.len();
        if n == 0 {
            return Ok(None);
        }
        let held: Vec<bool> = order.iter().map(|&g| rock.supported[g as usize]).collect();
        let Assembled {
            a_rr,
            coupling,
            held_to_r,
            held_to_d,
        } = assemble(rock, &index, &held, n);
        let ordering = Ordering::Custom((0..n as u32).collect());
        let mut solver =
            CholeskySolver::with_held(a_rr.pattern().clone(), &ordering, par(n), &held)?;
        solver.factorize(&a_rr)?;
        let mut condensed = CondensedRock {
            index,
            dofs: order.to_vec(),
            solver,
            coupling,
            held,
            held_to_r,
            held_to_d,
            blocks: Vec::new(),
        };
        condensed.blocks = condensed.schur_blocks(&a_rr)?;
        Ok(Some(condensed))
    }

    /// Number of condensed unknowns.
    pub fn n(&self) -> usize {
        self.dofs.len()
    }

    /// b_D −= A_DR A_RR⁻¹ b_R, `b_r` over the condensed unknowns and
    /// `b_d` over a live system's (`index_of`: its unknown of each global
    /// node dof), with the increments `held` (condensed index, value) of
    /// supported condensed unknowns (zero for the others); returns y =
    /// A_RR⁻¹ b_R (y = the increment on a held unknown), which
    /// [`CondensedRock::recover`] takes.
    pub fn condense(
        &self,
        b_r: &[f64],
        held: &[(u32, f64)],
        index_of: &[u32],
        b_d: &mut [f64],
    ) -> Result<Vec<f64>, SolveError> {
        let mut y = b_r.to_vec();
        self.hold(&mut y);
        if !held.is_empty() {
            let mut p = vec![0.0; self.n()];
            for &(h, v) in held {
                // only supported unknowns take increments (`prescribe` checks)
                debug_assert!(self.held[h as usize], "condensed unknown {h} is not held");
                p[h as usize] = v;
                y[h as usize] = v;
            }
            for &(h, r, v) in &self.held_to_r {
                y[r as usize] -= v * p[h as usize];
            }
            for &(h, g, v) in &self.held_to_d {
                b_d[index_of[g as usize] as usize] -= v * p[h as usize];
            }
        }
        self.solver.solve_in_place(&mut y)?;
        for &(r, g, v) in &self.coupling {
            b_d[index_of[g as usize] as usize] -= v * y[r as usize];
        }
        Ok(y)
    }

    /// x_R = A_RR⁻¹ (b_R − A_RD x_D) = y − A_RR⁻¹ A_RD x_D, y from
    /// [`CondensedRock::condense`].
    pub fn recover(
        &self,
        y: &[f64],
        index_of: &[u32],
        x_d: &[f64],
    ) -> Result<Vec<f64>, SolveError> {
        let mut t = vec![0.0; self.n()];
        for &(r, g, v) in &self.coupling {
            t[r as usize] += v * x_d[index_of[g as usize] as usize];
        }
        self.hold(&mut t);
        self.solver.solve_in_place(&mut t)?;
        Ok(y.iter().zip(&t).map(|(a, b)| a - b).collect())
    }

    /// Zeroes the supported unknowns' entries (their increment is zero).
    fn hold(&self, v: &mut [f64]) {
        for (x, &h) in v.iter_mut().zip(&self.held) {
            if h {
                *x = 0.0;
            }
        }
    }

    /// C subtree by subtree: the frozen unknowns connected through A_RR
    /// (a subtree is connected, two are not), each with the boundary its
    /// couplings reach, C_T = A_TD A_RR⁻¹ A_DT. The subtrees do not couple,
    /// so one right-hand side carries the j-th boundary column of every
    /// subtree at once, and the solves number the largest boundary, not
    /// their sum (`CHUNK` columns a solve).
    fn schur_blocks(&self, a_rr: &SparseSym) -> Result<Vec<SchurBlock>, SolveError> {
        let n = self.n();
        let component = components(a_rr.pattern(), &self.held);
        let n_comp = component.iter().map(|&c| c + 1).max().unwrap_or(0) as usize;
        let mut by_comp: Vec<Vec<(u32, u32, f64)>> = vec![Vec::new(); n_comp];
        for &(r, g, v) in &self.coupling {
            by_comp[component[r as usize] as usize].push((r, g, v));
        }
        by_comp.retain(|e| !e.is_empty());
        let boundaries: Vec<Vec<u32>> = by_comp
            .iter()
            .map(|entries| {
                let mut dofs: Vec<u32> = entries.iter().map(|&(_, g, _)| g).collect();
                dofs.sort_unstable();
                dofs.dedup();
                dofs
            })
            .collect();
        // (component, row r, its boundary column, value)
        let entries: Vec<(usize, u32, usize, f64)> = by_comp
            .iter()
            .enumerate()
            .flat_map(|(t, es)| {
                let dofs = &boundaries[t];
                es.iter()
                    .map(move |&(r, g, v)| (t, r, dofs.binary_search(&g).unwrap_or(usize::MAX), v))
            })
            .collect();
        let widest = boundaries.iter().map(Vec::len).max().unwrap_or(0);
        let mut c: Vec<DMatrix<f64>> = boundaries
            .iter()
            .map(|d| DMatrix::zeros(d.len(), d.len()))
            .collect();
        // two chunks at a time, one per core, each a solve of its own
        // right-hand sides, copied into C before the next two
        let starts: Vec<usize> = (0..widest).step_by(CHUNK).collect();
        for pair in starts.chunks(2) {
            let slabs: Vec<Vec<DMatrix<f64>>> = pair
                .par_iter()
                .map(|&start| {
                    self.chunk(n, start, CHUNK.min(widest - start), &entries, &boundaries)
                })
                .collect::<Result<_, _>>()?;
            for (&start, slab) in pair.iter().zip(slabs) {
                for (ct, st) in c.iter_mut().zip(slab) {
                    for j in 0..st.ncols() {
                        ct.column_mut(start + j).copy_from(&st.column(j));
                    }
                }
            }
        }
        // symmetric to round-off; its upper triangle is what is assembled
        Ok(boundaries
            .into_iter()
            .zip(c)
            .map(|(dofs, minus_c)| SchurBlock { dofs, minus_c })
            .collect())
    }
}

impl CondensedRock {
    /// Columns `start..start + w` of every subtree's −C_T (a subtree with
    /// fewer boundary columns gets those it has): one solve with `w`
    /// right-hand sides, the j-th carrying every subtree's j-th column.
    fn chunk(
        &self,
        n: usize,
        start: usize,
        w: usize,
        entries: &[(usize, u32, usize, f64)],
        boundaries: &[Vec<u32>],
    ) -> Result<Vec<DMatrix<f64>>, SolveError> {
        let mut z = Mat::<f64>::zeros(n, w);
        for &(_, r, j, v) in entries {
            if (start..start + w).contains(&j) {
                z[(r as usize, j - start)] += v;
            }
        }
        self.solver.solve_columns(&mut z)?;
        let mut slab: Vec<DMatrix<f64>> = boundaries
            .iter()
            .map(|d| DMatrix::zeros(d.len(), w.min(d.len().saturating_sub(start))))
            .collect();
        for &(t, r, i, v) in entries {
            let st = &mut slab[t];
            for j in 0..st.ncols() {
                st[(i, j)] -= v * z[(r as usize, j)];
            }
        }
        Ok(slab)
    }
}

/// Factorise on both cores from this many condensed unknowns.
fn par(n: usize) -> Par {
    if n < super::live::PARALLEL_FROM_DOFS {
        Par::Seq
    } else {
        Par::rayon(0)
    }
}

/// What [`assemble`] makes.
struct Assembled {
    /// A_RR, rows of the held unknowns the identity
    a_rr: SparseSym,
    /// A_RD of the free condensed unknowns
    coupling: Vec<(u32, u32, f64)>,
    /// the held unknowns' couplings to the free ones and to D
    held_to_r: Vec<(u32, u32, f64)>,
    held_to_d: Vec<(u32, u32, f64)>,
}

/// A_RR, A_RD and the held unknowns' couplings, from the rock elements
/// touching a condensed unknown.
fn assemble(rock: &RockElements, index: &[u32], held: &[bool], n: usize) -> Assembled {
    let touching: Vec<usize> = (0..rock.conn.len())
        .filter(|&e| {
            rock.rock[e]
                && rock.conn[e]
                    .iter()
                    .any(|&v| (0..3).any(|c| index[3 * v as usize + c] != NONE))
        })
        .collect();
    let global = |e: usize| -> [u32; 24] {
        std::array::from_fn(|k| 3 * rock.conn[e][k / 3] + (k % 3) as u32)
    };
    let lists: Vec<Vec<u32>> = touching
        .iter()
        .map(|&e| {
            global(e)
                .iter()
                .map(|&g| match index[g as usize] {
                    NONE => NO_DOF,
                    r => r,
                })
                .collect()
        })
        .collect();
    let mut a = SparseSym::new(Arc::new(Pattern::new(n, &lists)));
    let (mut coupling, mut held_to_r, mut held_to_d) = (Vec::new(), Vec::new(), Vec::new());
    for (slot, &e) in touching.iter().enumerate() {
        a.add_packed_scaled(slot, rock.modulus, &rock.k_unit[e].0);
        let gd = global(e);
        for (ka, &ga) in gd.iter().enumerate() {
            let r = index[ga as usize];
            if r == NONE {
                continue;
            }
            for (kb, &gb) in gd.iter().enumerate() {
                let v = rock.modulus * rock.k_unit[e].get(ka, kb);
                match (held[r as usize], index[gb as usize]) {
                    (false, NONE) => coupling.push((r, gb, v)),
                    (true, NONE) => held_to_d.push((r, gb, v)),
                    (true, s) if !held[s as usize] => held_to_r.push((r, s, v)),
                    _ => {}
                }
            }
        }
    }
    a.apply_dirichlet(held);
    Assembled {
        a_rr: a,
        coupling: summed(coupling),
        held_to_r: summed(held_to_r),
        held_to_d: summed(held_to_d),
    }
}

/// The triplets sorted by their first two and the duplicates summed.
fn summed(mut t: Vec<(u32, u32, f64)>) -> Vec<(u32, u32, f64)> {
    t.sort_unstable_by_key(|&(a, b, _)| (a, b));
    t.dedup_by(|b, a| {
        let same = a.0 == b.0 && a.1 == b.1;
        if same {
            a.2 += b.2;
        }
        same
    });
    t
}

/// The connected components of the graph of `pattern` without the held
/// unknowns (each held unknown its own component).
fn components(pattern: &Pattern, held: &[bool]) -> Vec<u32> {
    let n = pattern.n_dofs();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let p = parent[i as usize];
            parent[i as usize] = parent[p as usize];
            i = p;
        }
        i
    }
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..n {
        if held[j] {
            continue;
        }
        for &i in &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize] {
            if held[i as usize] {
                continue;
            }
            let (a, b) = (root(&mut parent, i), root(&mut parent, j as u32));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut next = 0;
    (0..n)
        .map(|i| {
            let r = root(&mut parent, i as u32) as usize;
            if label[r] == u32::MAX {
                label[r] = next;
                next += 1;
            }
            label[r]
        })
        .collect()
}

/// The frozen unknowns of a complete pattern eliminated in `fwd` (`fwd[k]`
/// the unknown eliminated k-th): those whose column of the elimination tree
/// (faer's, of the permuted pattern) and every column below it satisfy
/// `rock_only`. In elimination order.
pub fn frozen_columns(
    pattern: &Pattern,
    fwd: &[u32],
    rock_only: &dyn Fn(usize) -> bool,
) -> Vec<u32> {
    let n = pattern.n_dofs();
    let mut inv = vec![0u32; n];
    for (k, &d) in fwd.iter().enumerate() {
        inv[d as usize] = k as u32;
    }
    // the upper triangle of the permuted pattern, column by column
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    let mut upper: Vec<Vec<u32>> = vec![Vec::new(); n];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize] {
            let (pi, pj) = (inv[i as usize], inv[j]);
            upper[pi.max(pj) as usize].push(pi.min(pj));
        }
    }
    let mut ptr = Vec::with_capacity(n + 1);
    ptr.push(0u32);
    let mut rows = Vec::new();
    for col in &mut upper {
        col.sort_unstable();
        rows.extend_from_slice(col);
        ptr.push(rows.len() as u32);
    }
    drop(upper);
    // faer's elimination tree of it (−1 at a root)
    let permuted = SymbolicSparseColMatRef::new_checked(n, n, &ptr, None, &rows);
    let (mut etree, mut counts) = (vec![0i32; n], vec![0u32; n]);
    let mut mem = MemBuffer::new(simplicial::prefactorize_symbolic_cholesky_scratch::<u32>(
        n,
        rows.len(),
    ));
    simplicial::prefactorize_symbolic_cholesky(
        &mut etree,
        &mut counts,
        permuted,
        MemStack::new(&mut mem),
    );
    let parent: Vec<u32> = etree
        .iter()
        .map(|&p| if p < 0 { NONE } else { p as u32 })
        .collect();
    let mut frozen: Vec<bool> = fwd.iter().map(|&d| rock_only(d as usize)).collect();
    for k in 0..n {
        if !frozen[k] && parent[k] != NONE {
            frozen[parent[k] as usize] = false;
        }
    }
    (0..n).filter(|&k| frozen[k]).map(|k| fwd[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block of 8 × 8 × 8 hex8 elements: the lower three quarters rock,
    /// the rest "concrete" (any other part).
    fn block() -> (
        Vec<[u32; 8]>,
        Vec<bool>,
        Vec<crate::fem::elasticity::PackedSym24>,
        usize,
    ) {
        let m = 8usize;
        // the corners in VTK order, as offsets on the grid
        let corners = crate::fem::hex8::NODES.map(|p| p.map(|v| (v > 0.0) as usize));
        let (mut conn, mut rock, mut k_unit) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let at = |c: [usize; 3]| [i + c[0], j + c[1], k + c[2]];
                    conn.push(corners.map(|c| {
                        let [x, y, z] = at(c);
                        (x + (m + 1) * (y + (m + 1) * z)) as u32
                    }));
                    rock.push(k < 3 * m / 4);
                    let coords = corners.map(|c| {
                        let [x, y, z] = at(c);
                        [x as f64, y as f64 * 1.3, z as f64 * 0.8]
                    });
                    let g = crate::fem::elasticity::gauss_points(&coords).unwrap();
                    let q = crate::fem::elasticity::poisson_matrix(0.22);
                    k_unit.push(crate::fem::elasticity::PackedSym24::from_upper(
                        &crate::fem::elasticity::stiffness(&g, &q),
                    ));
                }
            }
        }
        (conn, rock, k_unit, (m + 1).pow(3))
    }

    /// The condensed solve (S x_D = b_D − A_DR A_RR⁻¹ b_R, then x_R)
    /// equals the solve of the whole system, with the concrete at another
    /// modulus and a settlement prescribed on the supported base (held
    /// unknowns, condensed or not); the frozen set is the rock-only
    /// columns' subtrees of a METIS order.
    #[test]
    fn the_condensed_solve_is_the_whole_one() {
        let (conn, rock_el, k_unit, nn) = block();
        let n = 3 * nn;
        let supported: Vec<bool> = (0..n).map(|g| g / 3 < 81).collect();
        let lists: Vec<Vec<u32>> = conn
            .iter()
            .map(|c| (0..24).map(|k| 3 * c[k / 3] + (k % 3) as u32).collect())
            .collect();
        let pattern = Arc::new(Pattern::new(n, &lists));
        let fwd = crate::fem::metis_nested_dissection(&pattern).unwrap();
        let mut in_conc = vec![false; n];
        for (e, c) in conn.iter().enumerate() {
            if !rock_el[e] {
                c.iter()
                    .for_each(|&v| (0..3).for_each(|k| in_conc[3 * v as usize + k] = true));
            }
        }
        let frozen = frozen_columns(&pattern, &fwd, &|d| !in_conc[d]);
        assert!(!frozen.is_empty() && frozen.len() < n - in_conc.iter().filter(|&&c| c).count());
        let (e_rock, e_conc) = (3.0e10, 1.7e10);
        let rock = RockElements {
            conn: &conn,
            rock: &rock_el,
            k_unit: &k_unit,
            modulus: e_rock,
            supported: &supported,
        };
        let cr = CondensedRock::new(&rock, &frozen).unwrap().unwrap();
        let free = frozen.iter().filter(|&&g| !supported[g as usize]).count();
        assert!(
            free > 100,
            "{free} free frozen unknowns of {}",
            frozen.len()
        );
        // the whole system
        let mut whole = SparseSym::new(pattern.clone());
        for (e, k) in k_unit.iter().enumerate() {
            whole.add_packed_scaled(e, if rock_el[e] { e_rock } else { e_conc }, &k.0);
        }
        let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 23) as f64 - 11.0).collect();
        let mut b_w = b.clone();
        // a settlement of the supported base, varying along it
        let presc: Vec<f64> = (0..n)
            .map(|g| {
                if supported[g] {
                    1e-4 * ((g % 7) as f64 - 3.0)
                } else {
                    0.0
                }
            })
            .collect();
        whole.apply_dirichlet_with_rhs(&supported, &presc, &mut b_w);
        let mut s_whole =
            CholeskySolver::with_options(pattern.clone(), &Ordering::Custom(fwd.clone()), Par::Seq)
                .unwrap();
        s_whole.factorize(&whole).unwrap();
        let mut x_w = b_w.clone();
        s_whole.solve_in_place(&mut x_w).unwrap();
        // the rest: numbered in order, the condensed dofs left out
        let mut index_of = vec![NONE; n];
        let rest: Vec<u32> = (0..n as u32)
            .filter(|&g| cr.index[g as usize] == NONE)
            .collect();
        for (i, &g) in rest.iter().enumerate() {
            index_of[g as usize] = i as u32;
        }
        let nd = rest.len();
        let mut d_lists: Vec<Vec<u32>> = lists
            .iter()
            .map(|l| {
                l.iter()
                    .map(|&g| {
                        if index_of[g as usize] == NONE {
                            NO_DOF
                        } else {
                            index_of[g as usize]
                        }
                    })
                    .collect()
            })
            .collect();
        d_lists.extend(
            cr.blocks
                .iter()
                .map(|bl| bl.dofs.iter().map(|&g| index_of[g as usize]).collect()),
        );
        let mut s = SparseSym::new(Arc::new(Pattern::new(nd, &d_lists)));
        for (e, k) in k_unit.iter().enumerate() {
            s.add_packed_scaled(e, if rock_el[e] { e_rock } else { e_conc }, &k.0);
        }
        for (t, bl) in cr.blocks.iter().enumerate() {
            s.add_element(conn.len() + t, &bl.minus_c);
        }
        let b_r: Vec<f64> = cr.dofs.iter().map(|&g| b[g as usize]).collect();
        let held: Vec<(u32, f64)> = cr
            .dofs
            .iter()
            .enumerate()
            .filter(|&(_, &g)| supported[g as usize])
            .map(|(r, &g)| (r as u32, presc[g as usize]))
            .collect();
        assert!(!held.is_empty());
        let mut b_d: Vec<f64> = rest.iter().map(|&g| b[g as usize]).collect();
        let y = cr.condense(&b_r, &held, &index_of, &mut b_d).unwrap();
        let sup_d: Vec<bool> = rest.iter().map(|&g| supported[g as usize]).collect();
        let presc_d: Vec<f64> = rest.iter().map(|&g| presc[g as usize]).collect();
        s.apply_dirichlet_with_rhs(&sup_d, &presc_d, &mut b_d);
        let fwd_d: Vec<u32> = fwd
            .iter()
            .filter_map(|&g| (index_of[g as usize] != NONE).then_some(index_of[g as usize]))
            .collect();
        let mut s_solver =
            CholeskySolver::with_options(s.pattern().clone(), &Ordering::Custom(fwd_d), Par::Seq)
                .unwrap();
        s_solver.factorize(&s).unwrap();
        let mut x_d = b_d.clone();
        s_solver.solve_in_place(&mut x_d).unwrap();
        let x_r = cr.recover(&y, &index_of, &x_d).unwrap();
        let scale = x_w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for (i, &g) in rest.iter().enumerate() {
            worst = worst.max((x_d[i] - x_w[g as usize]).abs());
        }
        for (r, &g) in cr.dofs.iter().enumerate() {
            worst = worst.max((x_r[r] - x_w[g as usize]).abs());
        }
        assert!(worst <= 1e-12 * scale, "differs by {worst:e} of {scale:e}");
        // and S is smaller to factorise than the whole
        assert!(s_solver.factor_flops() < s_whole.factor_flops());
    }
}
