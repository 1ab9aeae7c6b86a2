//! Solves with the global matrix's Cholesky factor on two cores, the same bits on any number.
//!
//! faer factorizes P = L L^T (after its fill-reducing permutation); its own solve treats each
//! coordinate as a separate column, one thread per column group, and a triangular solve has no
//! parallelism inside faer's simplicial kernel. Here the three coordinates are solved together
//! (one `Vec3` per row: each factor entry is loaded once for all three) and the elimination
//! tree is split into two independent groups of subtrees, solved on two threads, and the rest
//! (the separators above them), solved after. The split depends only on the factor's structure
//! and every sum runs in a fixed order, so the result does not depend on the thread count.
//!
//! Written by hand because no crate solves a sparse triangular system over its elimination
//! tree's subtrees with interleaved right-hand sides; faer does the factorization.

use std::ops::{AddAssign, Mul, Sub};

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// A value solved for: a scalar or a `Vec3` of the three coordinates.
pub(crate) trait Solvable:
    Copy + Send + Sync + AddAssign + Sub<Output = Self> + Mul<f64, Output = Self>
{
    fn zero() -> Self;
}

impl Solvable for f64 {
    fn zero() -> Self {
        0.0
    }
}

impl Solvable for crate::cloth::Vec3 {
    fn zero() -> Self {
        Self::zeros()
    }
}

/// L with rows and columns renumbered so that positions [0, a) and [a, b) are two groups of
/// independent subtrees of the elimination tree and [b, n) the rest, stored by columns,
/// diagonal apart.
pub(crate) struct SplitFactor {
    /// The row of P at each position.
    order: Vec<u32>,
    groups: [usize; 2],
    diagonal_inverse: Vec<f64>,
    col_ptr: Vec<u32>,
    /// Per column, the first of its entries in the rest (rows >= b).
    col_rest: Vec<u32>,
    col_rows: Vec<u32>,
    col_values: Vec<f64>,
}

impl SplitFactor {
    /// The factor of a simplicial `symbolic` with numeric values `factor` (faer's layout:
    /// compressed columns, diagonal first); `None` for a supernodal one.
    pub fn new(symbolic: &SymbolicCholesky<usize>, factor: &[f64]) -> Option<Self> {
        let SymbolicCholeskyRaw::Simplicial(simplicial) = symbolic.raw() else {
            return None;
        };
        let n = symbolic.nrows();
        let (ptr, idx) = (simplicial.col_ptr(), simplicial.row_idx());
        if (0..n).any(|j| ptr[j] == ptr[j + 1] || idx[ptr[j]] != j) {
            return None;
        }
        let (group, groups) = split(n, |j| &idx[ptr[j] + 1..ptr[j + 1]]);
        // New positions: each group in its old order (children before parents), then the rest.
        let mut old_of: Vec<usize> = Vec::with_capacity(n);
        for g in 0..3 {
            old_of.extend((0..n).filter(|&j| group[j] == g));
        }
        let mut new_of = vec![0u32; n];
        for (k, &j) in old_of.iter().enumerate() {
            new_of[j] = k as u32;
        }
        let faer_rows: Vec<u32> = match symbolic.perm() {
            Some(perm) => perm.arrays().0.iter().map(|&i| i as u32).collect(),
            None => (0..n as u32).collect(),
        };
        let mut out = Self {
            order: old_of.iter().map(|&j| faer_rows[j]).collect(),
            groups,
            diagonal_inverse: old_of.iter().map(|&j| factor[ptr[j]].recip()).collect(),
            col_ptr: vec![0],
            col_rest: Vec::with_capacity(n),
            col_rows: Vec::with_capacity(factor.len() - n),
            col_values: Vec::with_capacity(factor.len() - n),
        };
        let mut entries: Vec<(u32, f64)> = Vec::new();
        for &j in &old_of {
            entries.clear();
            entries.extend((ptr[j] + 1..ptr[j + 1]).map(|k| (new_of[idx[k]], factor[k])));
            entries.sort_unstable_by_key(|e| e.0);
            let rest = entries.partition_point(|e| (e.0 as usize) < groups[1]);
            out.col_rest.push((out.col_rows.len() + rest) as u32);
            out.col_rows.extend(entries.iter().map(|e| e.0));
            out.col_values.extend(entries.iter().map(|e| e.1));
            out.col_ptr.push(out.col_rows.len() as u32);
        }
        Some(out)
    }

    /// Rows of P in solve order: position k holds row `order()[k]`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Solves L L^T x = b in place; `x` holds b in solve order (see [`Self::order`]);
    /// `scratch` is any vector (reused between solves).
    pub fn solve<T: Solvable>(&self, x: &mut [T], scratch: &mut Vec<T>) {
        let [a, b] = self.groups;
        let rest = x.len() - b;
        scratch.clear();
        scratch.resize(2 * rest, T::zero());
        {
            let (first, second) = x[..b].split_at_mut(a);
            let (border_first, border_second) = scratch.split_at_mut(rest);
            crate::spin_join::join(
                || self.forward(first, 0, border_first, 0..a),
                || self.forward(second, a, border_second, a..b),
            );
        }
        let (groups, rest) = x.split_at_mut(b);
        self.forward_rest(rest, scratch);
        self.backward_rest(rest);
        let rest = &*rest;
        let (first, second) = groups.split_at_mut(a);
        crate::spin_join::join(
            || self.backward(first, 0, rest, 0..a),
            || self.backward(second, a, rest, a..b),
        );
    }

    /// L y = b over one group's columns (`x` holds the group from position `offset`), column
    /// by column, each solved value pushed to the rows below it: rows of the group into `x`,
    /// rows of the rest into `border` (the group's own sums, added to the rest's later).
    fn forward<T: Solvable>(
        &self,
        x: &mut [T],
        offset: usize,
        border: &mut [T],
        cols: std::ops::Range<usize>,
    ) {
        let b = self.groups[1];
        for j in cols {
            let local = j - offset;
            let xj = x[local] * self.diagonal_inverse[j];
            x[local] = xj;
            let (start, mid, end) = self.column(j);
            for k in start..mid {
                let i = self.col_rows[k] as usize - offset;
                x[i] = x[i] - xj * self.col_values[k];
            }
            for k in mid..end {
                let i = self.col_rows[k] as usize - b;
                border[i] += xj * self.col_values[k];
            }
        }
    }

    /// L y = b over the rest's columns (`rest` holds positions from b on), after both groups,
    /// with their `border` sums.
    fn forward_rest<T: Solvable>(&self, rest: &mut [T], border: &[T]) {
        let (b, n) = (self.groups[1], rest.len());
        for r in 0..n {
            let mut pushed = border[r];
            pushed += border[n + r];
            let xj = (rest[r] - pushed) * self.diagonal_inverse[b + r];
            rest[r] = xj;
            let (start, _, end) = self.column(b + r);
            for k in start..end {
                let i = self.col_rows[k] as usize - b;
                rest[i] = rest[i] - xj * self.col_values[k];
            }
        }
    }

    /// Column j's entries: its first, its first in the rest, and its end.
    fn column(&self, j: usize) -> (usize, usize, usize) {
        (
            self.col_ptr[j] as usize,
            self.col_rest[j] as usize,
            self.col_ptr[j + 1] as usize,
        )
    }

    /// L^T x = y over one group's columns, last first: `x` holds the group from position
    /// `offset`, `rest` the solved positions from b on.
    fn backward<T: Solvable>(
        &self,
        x: &mut [T],
        offset: usize,
        rest: &[T],
        cols: std::ops::Range<usize>,
    ) {
        let b = self.groups[1];
        for j in cols.rev() {
            let (start, mid, end) = self.column(j);
            let mut acc = T::zero();
            for k in start..mid {
                acc += x[self.col_rows[k] as usize - offset] * self.col_values[k];
            }
            for k in mid..end {
                acc += rest[self.col_rows[k] as usize - b] * self.col_values[k];
            }
            let local = j - offset;
            x[local] = (x[local] - acc) * self.diagonal_inverse[j];
        }
    }

    /// L^T x = y over the rest's columns, last first (`rest` holds positions from b on).
    fn backward_rest<T: Solvable>(&self, rest: &mut [T]) {
        let b = self.groups[1];
        for r in (0..rest.len()).rev() {
            let j = b + r;
            let span = self.col_ptr[j] as usize..self.col_ptr[j + 1] as usize;
            let mut acc = T::zero();
            for (&i, &l) in self.col_rows[span.clone()]
                .iter()
                .zip(&self.col_values[span])
            {
                acc += rest[i as usize - b] * l;
            }
            rest[r] = (rest[r] - acc) * self.diagonal_inverse[j];
        }
    }
}

/// Splits the elimination tree of a factor with `n` columns (`below(j)`: the rows of column
/// j's entries under the diagonal) into groups 0 and 1, unions of whole subtrees of about
/// equal work, and group 2, the rest: the ancestors of the subtrees. Returns each column's
/// group and the group boundaries [a, b] in the renumbered order.
fn split<'a>(n: usize, below: impl Fn(usize) -> &'a [usize]) -> (Vec<u8>, [usize; 2]) {
    let mut parent = vec![usize::MAX; n];
    let mut work = vec![0usize; n];
    for (j, p) in parent.iter_mut().enumerate() {
        let rows = below(j);
        *p = rows.iter().copied().min().unwrap_or(usize::MAX);
        work[j] = rows.len() + 1;
    }
    let mut subtree = work.clone();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for j in 0..n {
        if parent[j] != usize::MAX {
            subtree[parent[j]] += subtree[j];
            children[parent[j]].push(j);
        }
    }
    let total: usize = work.iter().sum();
    let mut group = vec![2u8; n];
    let mut roots: Vec<usize> = (0..n).filter(|&j| parent[j] == usize::MAX).collect();
    let mut rest_work = 0;
    let assignment = loop {
        // Largest first, each to the lighter group.
        roots.sort_unstable_by_key(|&r| (std::cmp::Reverse(subtree[r]), r));
        let mut load = [0usize; 2];
        let mut of_root = Vec::with_capacity(roots.len());
        for &r in &roots {
            let g = usize::from(load[1] < load[0]);
            load[g] += subtree[r];
            of_root.push(g as u8);
        }
        let balanced = load[0].abs_diff(load[1]) * 20 <= total;
        // Moving the largest subtree's root to the rest would leave too much work serial.
        if balanced || roots.is_empty() || (rest_work + work[roots[0]]) * 5 > total {
            break of_root;
        }
        let top = roots.remove(0);
        rest_work += work[top];
        roots.extend(children[top].iter().copied());
    };
    let mut stack: Vec<(usize, u8)> = roots.iter().copied().zip(assignment).collect();
    while let Some((j, g)) = stack.pop() {
        group[j] = g;
        stack.extend(children[j].iter().map(|&c| (c, g)));
    }
    let a = group.iter().filter(|&&g| g == 0).count();
    let b = a + group.iter().filter(|&&g| g == 1).count();
    (group, [a, b])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::Vec3;
    use faer::sparse::linalg::cholesky::{LltRef, factorize_symbolic_cholesky};
    use faer::sparse::{SparseColMat, Triplet};
    use faer::{Conj, Mat, Par, Side};

    /// The Laplacian of an m x m grid plus a diagonal (a mass matrix): SPD and sparse like P.
    fn grid_matrix(m: usize) -> SparseColMat<usize, f64> {
        let id = |r: usize, c: usize| r * m + c;
        let mut t = Vec::new();
        for r in 0..m {
            for c in 0..m {
                let mut degree = 0.0;
                for (dr, dc) in [(0, 1), (1, 0), (1, 1)] {
                    if r + dr < m && c + dc < m {
                        // Lower triangle only: (larger, smaller).
                        t.push(Triplet::new(id(r + dr, c + dc), id(r, c), -1.0));
                    }
                }
                for (dr, dc) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1), (1, 1), (-1, -1)] {
                    let (rr, cc) = (r as i64 + dr, c as i64 + dc);
                    if (0..m as i64).contains(&rr) && (0..m as i64).contains(&cc) {
                        degree += 1.0;
                    }
                }
                t.push(Triplet::new(
                    id(r, c),
                    id(r, c),
                    degree + 0.01 * (1 + r % 3) as f64,
                ));
            }
        }
        SparseColMat::try_new_from_triplets(m * m, m * m, &t).unwrap()
    }

    #[test]
    fn matches_faers_solve_and_splits_the_work() {
        let m = 40;
        let n = m * m;
        let matrix = grid_matrix(m);
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .unwrap();
        let mut values = vec![0.0; symbolic.len_val()];
        let mut stack = faer::dyn_stack::MemBuffer::new(
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        symbolic
            .factorize_numeric_llt(
                &mut values,
                matrix.as_ref(),
                Side::Lower,
                Default::default(),
                Par::Seq,
                faer::dyn_stack::MemStack::new(&mut stack),
                Default::default(),
            )
            .unwrap();
        let factor = SplitFactor::new(&symbolic, &values).expect("simplicial");
        let [a, b] = factor.groups;
        assert!(a > n / 4 && b - a > n / 4, "groups {a}, {}", b - a);
        assert!(n - b < n / 5, "rest {}", n - b);

        let rhs: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i as f64).sin(), (i % 7) as f64, 1.0 - (i as f64).cos()))
            .collect();
        let mut expected = Mat::<f64>::zeros(n, 3);
        for (i, r) in rhs.iter().enumerate() {
            for c in 0..3 {
                expected[(i, c)] = r[c];
            }
        }
        let llt = LltRef::<usize, f64>::new(&symbolic, &values);
        let mut scratch =
            faer::dyn_stack::MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(3, Par::Seq));
        llt.solve_in_place_with_conj(
            Conj::No,
            expected.as_mut(),
            Par::Seq,
            faer::dyn_stack::MemStack::new(&mut scratch),
        );
        let solve = |threads: usize| {
            let mut x: Vec<Vec3> = factor.order().iter().map(|&i| rhs[i as usize]).collect();
            if threads == 0 {
                // Outside any pool: the spinning helper (see spin_join.rs).
                factor.solve(&mut x, &mut Vec::new());
            } else {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| factor.solve(&mut x, &mut Vec::new()));
            }
            let mut out = vec![Vec3::zeros(); n];
            for (k, &i) in factor.order().iter().enumerate() {
                out[i as usize] = x[k];
            }
            out
        };
        let one = solve(1);
        for (i, v) in one.iter().enumerate() {
            for c in 0..3 {
                let e = expected[(i, c)];
                assert!(
                    (v[c] - e).abs() <= 1e-12 * (1.0 + e.abs()),
                    "{i} {c}: {v:?} vs {e}"
                );
            }
        }
        assert_eq!(one, solve(2), "the same bits on one and two threads");
        assert_eq!(one, solve(3));
        assert_eq!(one, solve(0), "the same bits with the spinning helper");
        // The scalar solve is the x column's.
        let mut x: Vec<f64> = factor.order().iter().map(|&i| rhs[i as usize].x).collect();
        factor.solve(&mut x, &mut Vec::new());
        for (k, &i) in factor.order().iter().enumerate() {
            assert_eq!(x[k], one[i as usize].x);
        }
    }
}
