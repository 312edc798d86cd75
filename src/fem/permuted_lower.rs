//! The matrix as faer's numeric factorisations read it: the lower
//! triangle of P A Pᵀ (supernodal) or its upper triangle (simplicial),
//! with P the elimination order.
//!
//! faer's `SymbolicCholesky::factorize_numeric_llt` builds that matrix at
//! every call (`permute_self_adjoint_to_unsorted`: count the columns, sum
//! them up, place every entry). The structure depends on the pattern and
//! the order only, so [`PermutedLower`] makes it once per symbolic
//! analysis and keeps where each stored entry of A lands; a factorisation
//! then moves the values in one pass. On the demo's `plan` the permutation
//! was 8.8 % of all samples (`perf`, 28 Nov 2026), most of it on the core
//! that factorises the next step ahead.
//!
//! Rows *held* in every matrix factorised (Dirichlet rows: an identity row
//! and column, the supports) are left out of the structure but for their
//! diagonal: the analysis then eliminates them without fill, and
//! [`PermutedLower::place`] checks that the entries it leaves out are zero.
//!
//! The factor is the same to the bit: faer's factorisations add (or
//! scatter) each entry of A once, so neither the order of the rows within
//! a column nor who permuted them changes a value
//! (`solver::tests::the_factor_from_the_map_is_faers_to_the_bit`; the
//! demo's run folder is the same to the byte).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

use super::sparse::Pattern;

/// Marks an entry of A left out of the permuted structure (a held row's).
const LEFT_OUT: u32 = u32::MAX;

/// Whether entry (i, j) of A leaves the analysis: an off-diagonal entry of
/// a held row or column.
pub(super) fn left_out(i: usize, j: usize, held: Option<&[bool]>) -> bool {
    i != j && held.is_some_and(|h| h[i] || h[j])
}

/// The lower (or upper) triangle of P A Pᵀ's structure, and where each
/// stored entry of A (its upper triangle, column by column) goes in it.
#[derive(Debug)]
pub struct PermutedLower {
    structure: SymbolicSparseColMat<u32>,
    /// `target[k]`: the value index of entry k of the pattern, or
    /// [`LEFT_OUT`]
    target: Vec<u32>,
    /// entries in the structure
    nnz: usize,
}

impl PermutedLower {
    /// `inv[d]`: the position of dof d in the elimination order; `upper`:
    /// the upper triangle (faer's simplicial factorisation) instead of the
    /// lower; `held`: rows whose off-diagonal entries are left out.
    pub fn new(pattern: &Pattern, inv: &[u32], upper: bool, held: Option<&[bool]>) -> Self {
        let n = pattern.n_dofs();
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let kept = |k: usize, j: usize| !left_out(ri[k] as usize, j, held);
        // (row, column) in the permuted structure
        let place = |k: usize, j: usize| {
            let (a, b) = (inv[ri[k] as usize], inv[j]);
            if upper {
                (a.min(b), a.max(b))
            } else {
                (a.max(b), a.min(b))
            }
        };
        let mut col_ptr = vec![0u32; n + 1];
        for j in 0..n {
            for k in cp[j] as usize..cp[j + 1] as usize {
                if kept(k, j) {
                    col_ptr[place(k, j).1 as usize + 1] += 1;
                }
            }
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let nnz = col_ptr[n] as usize;
        let mut next = col_ptr.clone();
        let mut row_idx = vec![0u32; nnz];
        let mut target = vec![LEFT_OUT; ri.len()];
        for j in 0..n {
            let (s0, s1) = (cp[j] as usize, cp[j + 1] as usize);
            for (k, t) in (s0..s1).zip(&mut target[s0..s1]) {
                if !kept(k, j) {
                    continue;
                }
                let (row, col) = place(k, j);
                let at = next[col as usize];
                next[col as usize] += 1;
                row_idx[at as usize] = row;
                *t = at;
            }
        }
        let structure = SymbolicSparseColMat::new_unsorted_checked(n, n, col_ptr, None, row_idx);
        PermutedLower {
            structure,
            target,
            nnz,
        }
    }

    /// The values of A (its pattern's order) placed in `out`. `Err(k)`:
    /// entry k of A, left out as a held row's, is not zero (`out` then
    /// holds no usable matrix).
    pub fn place(&self, values: &[f64], out: &mut Vec<f64>) -> Result<(), usize> {
        out.resize(self.nnz, 0.0);
        for (k, (&t, &v)) in self.target.iter().zip(values).enumerate() {
            match t {
                LEFT_OUT if v != 0.0 => return Err(k),
                LEFT_OUT => {}
                t => out[t as usize] = v,
            }
        }
        Ok(())
    }

    /// The permuted matrix with the values [`PermutedLower::place`] wrote.
    pub fn matrix<'a>(&'a self, placed: &'a [f64]) -> SparseColMatRef<'a, u32, f64> {
        SparseColMatRef::new(self.structure.as_ref(), placed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every entry of a small matrix lands at (max, min) of its permuted
    /// indices, with its value.
    #[test]
    fn entries_land_at_their_permuted_lower_position() {
        // one element on three dofs: the full upper triangle, a_ij = 10 i + j
        let pattern = Pattern::new(3, &[[0u32, 1, 2]]);
        let mut values = vec![0.0; pattern.nnz()];
        for j in 0..3 {
            let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
            for k in cp[j] as usize..cp[j + 1] as usize {
                values[k] = (10 * ri[k] as usize + j) as f64;
            }
        }
        // elimination order 2, 0, 1: inv[0] = 1, inv[1] = 2, inv[2] = 0
        let inv = [1u32, 2, 0];
        let p = PermutedLower::new(&pattern, &inv, false, None);
        let mut placed = Vec::new();
        p.place(&values, &mut placed).unwrap();
        let m = p.matrix(&placed);
        let mut entries = Vec::new();
        for c in 0..3 {
            for (r, v) in m.row_idx_of_col(c).zip(m.val_of_col(c)) {
                assert!(r >= c, "an entry above the diagonal");
                entries.push((r, c, *v));
            }
        }
        assert_eq!(entries.len(), 6, "the lower triangle, each entry once");
        let old = [2usize, 0, 1];
        for (r, c, v) in entries {
            let (i, j) = (old[r].min(old[c]), old[r].max(old[c]));
            assert_eq!(v, (10 * i + j) as f64, "entry ({r}, {c})");
        }
    }
}
