//! Fill-reducing orderings for [`CholeskySolver`](super::CholeskySolver).
//!
//! faer offers AMD. On 3-D meshes a geometric nested dissection usually
//! gives less fill and a factorisation that is faster and better blocked:
//! split the dofs by a plane through the median of the longest extent, take
//! as separator the dofs of one side that are coupled to the other side,
//! order both halves recursively and the separator last.

use super::sparse::Pattern;

/// Which fill-reducing ordering the Cholesky solver uses.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Ordering {
    /// faer's approximate minimum degree.
    #[default]
    Amd,
    /// METIS's multilevel nested dissection (`METIS_NodeND`) of the
    /// matrix graph, computed when the solver analyses its pattern.
    Metis,
    /// Elimination order: `perm[k]` is the dof eliminated k-th (a permutation
    /// of 0..n), e.g. from [`nested_dissection`].
    Custom(Vec<u32>),
}

/// Why METIS refused a graph.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("METIS_NodeND returned status {status} on a graph of {n} vertices")]
pub struct MetisError {
    pub status: i32,
    pub n: usize,
}

/// Knobs of `METIS_NodeND`; None keeps METIS's default.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MetisKnobs {
    /// separators computed at each bisection, the smallest kept
    /// (`METIS_OPTION_NSEPS`; METIS: 1)
    pub separators: Option<i32>,
    /// imbalance allowed between the two parts of a bisection, in
    /// thousandths (`METIS_OPTION_UFACTOR`; METIS: 200 for NodeND)
    pub imbalance: Option<i32>,
}

/// METIS's nested-dissection elimination order of the graph of `pattern`
/// (see [`Ordering::Custom`]) with METIS's default knobs.
pub fn metis_nested_dissection(pattern: &Pattern) -> Result<Vec<u32>, MetisError> {
    metis_nested_dissection_with(pattern, MetisKnobs::default())
}

/// METIS's nested-dissection elimination order of the graph of `pattern`
/// with `knobs`. Deterministic: METIS seeds its generator
/// with a fixed value at each call, and the calls are serialised because
/// that generator is process-global (two plans in two threads otherwise
/// got different orderings, and results that differed in the last bits).
pub fn metis_nested_dissection_with(
    pattern: &Pattern,
    knobs: MetisKnobs,
) -> Result<Vec<u32>, MetisError> {
    use metis_sys::{
        idx_t, moptions_et_METIS_OPTION_NSEPS as NSEPS,
        moptions_et_METIS_OPTION_UFACTOR as UFACTOR, METIS_NodeND, METIS_SetDefaultOptions,
        METIS_NOPTIONS,
    };
    let n = pattern.n_dofs();
    if n <= 1 {
        return Ok((0..n as u32).collect());
    }
    let graph = Graph::of(pattern);
    let err = |status: i32| MetisError { status, n };
    let to_idx = |v: usize| idx_t::try_from(v).map_err(|_| err(-1));
    let mut xadj = graph
        .ptr
        .iter()
        .map(|&p| to_idx(p))
        .collect::<Result<Vec<_>, _>>()?;
    let mut adjncy: Vec<idx_t> = graph.adj.iter().map(|&v| v as idx_t).collect();
    let mut nvtxs = to_idx(n)?;
    let mut options = [0 as idx_t; METIS_NOPTIONS as usize];
    let mut perm = vec![0 as idx_t; n];
    let mut iperm = vec![0 as idx_t; n];
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the arrays have the lengths METIS reads (xadj n+1, adjncy
    // xadj[n], options METIS_NOPTIONS, perm and iperm n) and outlive the
    // calls; a null vwgt means unit weights.
    let status = unsafe {
        METIS_SetDefaultOptions(options.as_mut_ptr());
        for (key, value) in [(NSEPS, knobs.separators), (UFACTOR, knobs.imbalance)] {
            if let Some(v) = value {
                options[key as usize] = v as idx_t;
            }
        }
        METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(err(status));
    }
    // METIS: row k of the permuted matrix is row perm[k] of the original,
    // i.e. perm[k] is the dof eliminated k-th.
    Ok(perm.into_iter().map(|v| v as u32).collect())
}

/// Geometric nested dissection of the graph of `pattern`, using one point
/// per dof (`dof_coords[i]`). Returns the elimination order (see
/// [`Ordering::Custom`]). Subsets of at most `leaf_size` dofs are kept in
/// their input order.
///
/// # Panics
/// If `dof_coords.len() != pattern.n_dofs()`.
pub fn nested_dissection(pattern: &Pattern, dof_coords: &[[f64; 3]], leaf_size: usize) -> Vec<u32> {
    let n = pattern.n_dofs();
    assert_eq!(dof_coords.len(), n, "one coordinate per dof");
    let graph = Graph::of(pattern);
    let mut order = Vec::with_capacity(n);
    // side[v]: 0 = not in the current subset, 1 = side A, 2 = side B
    let mut side = vec![0u8; n];
    let leaf = leaf_size.max(1);
    // explicit stack: (subset, separator to append after the subset's halves)
    enum Task {
        Split(Vec<u32>),
        Emit(Vec<u32>),
    }
    let mut stack = vec![Task::Split((0..n as u32).collect())];
    while let Some(task) = stack.pop() {
        let set = match task {
            Task::Emit(sep) => {
                order.extend_from_slice(&sep);
                continue;
            }
            Task::Split(set) => set,
        };
        if set.len() <= leaf {
            order.extend_from_slice(&set);
            continue;
        }
        match bisect(&set, dof_coords, &graph, &mut side) {
            // all coordinates equal along the longest axis: no geometric split
            None => order.extend_from_slice(&set),
            Some((a, b, sep)) => {
                // popped in reverse: A, then B, then the separator
                stack.push(Task::Emit(sep));
                stack.push(Task::Split(b));
                stack.push(Task::Split(a));
            }
        }
    }
    debug_assert_eq!(order.len(), n);
    order
}

/// The full adjacency (without the diagonal) of a pattern's upper triangle:
/// the neighbours of v are `adj[ptr[v]..ptr[v + 1]]`.
struct Graph {
    ptr: Vec<usize>,
    adj: Vec<u32>,
}

impl Graph {
    fn of(pattern: &Pattern) -> Graph {
        let n = pattern.n_dofs();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut deg = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize] {
                if i as usize != j {
                    deg[i as usize + 1] += 1;
                    deg[j + 1] += 1;
                }
            }
        }
        for i in 0..n {
            deg[i + 1] += deg[i];
        }
        let ptr = deg;
        let mut fill = ptr.clone();
        let mut adj = vec![0u32; ptr[n]];
        for j in 0..n {
            for &i in &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize] {
                let i = i as usize;
                if i != j {
                    adj[fill[i]] = j as u32;
                    fill[i] += 1;
                    adj[fill[j]] = i as u32;
                    fill[j] += 1;
                }
            }
        }
        Graph { ptr, adj }
    }

    fn neighbours(&self, v: u32) -> &[u32] {
        &self.adj[self.ptr[v as usize]..self.ptr[v as usize + 1]]
    }
}

/// Split `set` by the plane through the median of its longest extent into
/// (A, B, separator): the separator is the smaller of the two one-sided
/// boundaries, taken out of its side. `None` when every point has the same
/// coordinate along that axis. `side` is all 0 on entry and on return.
fn bisect(
    set: &[u32],
    coords: &[[f64; 3]],
    graph: &Graph,
    side: &mut [u8],
) -> Option<(Vec<u32>, Vec<u32>, Vec<u32>)> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in set {
        for k in 0..3 {
            lo[k] = lo[k].min(coords[v as usize][k]);
            hi[k] = hi[k].max(coords[v as usize][k]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mut keys: Vec<f64> = set.iter().map(|&v| coords[v as usize][axis]).collect();
    let mid = keys.len() / 2;
    let (_, &mut median, _) = keys.select_nth_unstable_by(mid, f64::total_cmp);
    let (mut a, mut b): (Vec<u32>, Vec<u32>) = set
        .iter()
        .partition(|&&v| coords[v as usize][axis] < median);
    if a.is_empty() || b.is_empty() {
        return None;
    }
    for &v in &a {
        side[v as usize] = 1;
    }
    for &v in &b {
        side[v as usize] = 2;
    }
    // separator: the smaller of the two one-sided boundaries
    let boundary = |part: &[u32], other: u8, side: &[u8]| -> Vec<bool> {
        part.iter()
            .map(|&v| {
                graph
                    .neighbours(v)
                    .iter()
                    .any(|&w| side[w as usize] == other)
            })
            .collect()
    };
    let in_sep_b = boundary(&b, 1, side);
    let in_sep_a = boundary(&a, 2, side);
    let nb = in_sep_b.iter().filter(|&&x| x).count();
    let na = in_sep_a.iter().filter(|&&x| x).count();
    let mut sep = Vec::new();
    let (part, mask) = if nb <= na {
        (&mut b, in_sep_b)
    } else {
        (&mut a, in_sep_a)
    };
    let mut k = 0;
    part.retain(|&v| {
        let s = mask[k];
        k += 1;
        if s {
            sep.push(v);
        }
        !s
    });
    for &v in set {
        side[v as usize] = 0;
    }
    Some((a, b, sep))
}
