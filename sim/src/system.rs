//! The global matrix P = M + h^2 sum_t w_t a_t a_t^T and its sparse Cholesky factorization
//! (faer): analysed once per mesh (the symbolic part is shared between materials), factorized
//! once per material and step size, never when contacts change.
//!
//! Pinned vertices are eliminated: their rows and columns are replaced by the identity in the
//! factorized matrix and their known velocities move to the right-hand side, so pins are exact.
//! The full symmetric matrix is kept in CSR form for the contact step, which needs single rows.
//!
//! Weak bending can be left out of the factorized matrix ("lagged"): its terms then enter the
//! right-hand side at the current iterate, h w A^T (p - A x^k), which has the same fixed point.
//! Bending stencils reach two rings of neighbours and triple the Cholesky factor's size, so
//! when bending adds under 10% to the matrix diagonal (typical garment materials) this makes
//! every solve about twice as fast at no cost in accuracy.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Par, Side};

use crate::cloth::Vec3;
use crate::constraints::Constraints;
use crate::error::{Error, Result};
use crate::factor::SplitFactor;

/// Symbolic analysis of one sparsity pattern (mesh + constraints + pins), shareable.
pub type Symbolic = Arc<SymbolicCholesky<usize>>;

/// The factorized global matrix and the workspace of its solves.
pub(crate) struct GlobalSystem {
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
    pinned: Vec<bool>,
    symbolic: Symbolic,
    lag_bending: bool,
    factor: SplitFactor,
    /// (solve position of a free row, entry of P coupling it to a pinned vertex), in row
    /// order: the known velocities moved to the right-hand side.
    pin_couplings: Vec<(u32, u32)>,
    /// Right-hand sides in the factor's solve order.
    ordered: Vec<Vec3>,
    ordered_scalar: Vec<f64>,
    scratch: Vec<Vec3>,
    scratch_scalar: Vec<f64>,
}

impl GlobalSystem {
    /// Assembles and factorizes P for step `h`. `symbolic` is reused when given (it must come
    /// from the same mesh, constraints and pins). Stages: the full matrix in CSR, its reduced
    /// lower triangle, the symbolic analysis (or the one given), the numeric factor, the pin
    /// couplings.
    pub fn new(
        masses: &[f64],
        constraints: &Constraints,
        h: f64,
        pinned: &[bool],
        lag_bending: bool,
        symbolic: Option<Symbolic>,
    ) -> Result<Self> {
        let n = masses.len();
        let (row_ptr, col, val) = assemble_csr(masses, constraints, h, lag_bending);
        let matrix = reduced_lower(&row_ptr, &col, &val, pinned)?;
        let symbolic = match symbolic {
            Some(s) if s.nrows() == n => s,
            _ => analyse(&matrix)?,
        };
        let factor = factorize(&symbolic, &matrix)?;
        let mut pin_couplings = Vec::new();
        for (position, &i) in factor.order().iter().enumerate() {
            let i = i as usize;
            if pinned[i] {
                continue;
            }
            for k in row_ptr[i]..row_ptr[i + 1] {
                if pinned[col[k] as usize] {
                    pin_couplings.push((position as u32, k as u32));
                }
            }
        }
        Ok(Self {
            pin_couplings,
            row_ptr,
            col,
            val,
            pinned: pinned.to_vec(),
            symbolic,
            lag_bending,
            factor,
            ordered: vec![Vec3::zeros(); n],
            ordered_scalar: vec![0.0; n],
            scratch: Vec::new(),
            scratch_scalar: Vec::new(),
        })
    }

    /// The shareable symbolic analysis.
    pub fn symbolic(&self) -> Symbolic {
        self.symbolic.clone()
    }

    /// Whether bending terms are left out of the matrix (and lagged in the right-hand side).
    pub fn lags_bending(&self) -> bool {
        self.lag_bending
    }

    /// Row `j` of P times `v`.
    #[inline]
    pub fn row_times(&self, j: usize, v: &[Vec3]) -> Vec3 {
        let mut sum = Vec3::zeros();
        for k in self.row_ptr[j]..self.row_ptr[j + 1] {
            sum += self.val[k] * v[self.col[k] as usize];
        }
        sum
    }

    /// Solves P u = b for one scalar right-hand side `b` (zero on pinned vertices, which stay
    /// at rest), written to `out`: a third of [`GlobalSystem::solve`]'s work.
    pub fn solve_scalar(&mut self, b: &[f64], out: &mut [f64]) {
        for (x, &i) in self.ordered_scalar.iter_mut().zip(self.factor.order()) {
            let i = i as usize;
            *x = if self.pinned[i] { 0.0 } else { b[i] };
        }
        self.factor
            .solve(&mut self.ordered_scalar, &mut self.scratch_scalar);
        for (x, &i) in self.ordered_scalar.iter().zip(self.factor.order()) {
            out[i as usize] = *x;
        }
    }

    /// Solves P v = rhs with pinned velocities prescribed: `rhs` holds the right-hand side on
    /// free vertices and the prescribed velocity on pinned ones; the solution is written to
    /// `out` (on two threads; the same bits on any number, see `factor.rs`).
    pub fn solve(&mut self, rhs: &[Vec3], out: &mut [Vec3]) {
        for (x, &i) in self.ordered.iter_mut().zip(self.factor.order()) {
            *x = rhs[i as usize];
        }
        for &(position, k) in &self.pin_couplings {
            let c = self.col[k as usize] as usize;
            self.ordered[position as usize] -= self.val[k as usize] * rhs[c];
        }
        self.factor.solve(&mut self.ordered, &mut self.scratch);
        for (x, &i) in self.ordered.iter().zip(self.factor.order()) {
            out[i as usize] = *x;
        }
    }
}

/// P's full symmetric entries (masses, and h^2 w_t a_t a_t^T of every term but lagged
/// bending) merged into CSR: (row pointers, columns, values).
fn assemble_csr(
    masses: &[f64],
    constraints: &Constraints,
    h: f64,
    lag_bending: bool,
) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
    let n = masses.len();
    let mut entries: Vec<(u32, u32, f64)> = Vec::with_capacity(n + 9 * constraints.len());
    for (i, &m) in masses.iter().enumerate() {
        entries.push((i as u32, i as u32, m));
    }
    let h2 = h * h;
    let mut stencil = Vec::new();
    for t in 0..constraints.len() {
        if lag_bending && constraints.is_bending(t) {
            continue;
        }
        let w = h2 * constraints.weight(t);
        stencil.clear();
        stencil.extend(constraints.stencil(t));
        for &(a, ca) in &stencil {
            for &(b, cb) in &stencil {
                entries.push((a as u32, b as u32, w * ca * cb));
            }
        }
    }
    entries.sort_unstable_by_key(|&(r, c, _)| (r, c));
    let mut row_ptr = vec![0usize; n + 1];
    let mut col: Vec<u32> = Vec::with_capacity(entries.len());
    let mut val: Vec<f64> = Vec::with_capacity(entries.len());
    let mut last = None;
    for &(r, c, v) in &entries {
        if last == Some((r, c)) {
            *val.last_mut().expect("merged entry") += v;
        } else {
            col.push(c);
            val.push(v);
            row_ptr[r as usize + 1] += 1;
            last = Some((r, c));
        }
    }
    for i in 0..n {
        row_ptr[i + 1] += row_ptr[i];
    }
    (row_ptr, col, val)
}

/// The lower triangle of the reduced matrix: pinned rows and columns replaced by the identity.
fn reduced_lower(
    row_ptr: &[usize],
    col: &[u32],
    val: &[f64],
    pinned: &[bool],
) -> Result<SparseColMat<usize, f64>> {
    let n = pinned.len();
    let mut lower = Vec::with_capacity(val.len() / 2 + n);
    for r in 0..n {
        for k in row_ptr[r]..row_ptr[r + 1] {
            let c = col[k] as usize;
            if c > r {
                continue;
            }
            if pinned[r] || pinned[c] {
                if r == c {
                    lower.push(Triplet::new(r, c, 1.0));
                }
                continue;
            }
            lower.push(Triplet::new(r, c, val[k]));
        }
    }
    SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &lower)
        .map_err(|e| factorization("assembly", e))
}

/// The symbolic analysis of `matrix`'s pattern. Simplicial: the solves are ours
/// (`factor.rs`); measured, faer's supernodal solve of this matrix was 1.7x slower.
fn analyse(matrix: &SparseColMat<usize, f64>) -> Result<Symbolic> {
    let symbolic = factorize_symbolic_cholesky(
        matrix.symbolic(),
        Side::Lower,
        Default::default(),
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        },
    )
    .map_err(|e| factorization("symbolic", e))?;
    Ok(Arc::new(symbolic))
}

/// The numeric LL^T factor of `matrix` on `symbolic`'s pattern, split for our solves.
fn factorize(symbolic: &Symbolic, matrix: &SparseColMat<usize, f64>) -> Result<SplitFactor> {
    let mut factor = vec![0.0; symbolic.len_val()];
    let mut stack =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
    symbolic
        .factorize_numeric_llt(
            &mut factor,
            matrix.as_ref(),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut stack),
            Default::default(),
        )
        .map_err(|e| factorization("numeric", e))?;
    SplitFactor::new(symbolic, &factor)
        .ok_or_else(|| factorization("symbolic", "the factor is not simplicial"))
}

fn factorization(stage: &'static str, e: impl std::fmt::Debug) -> Error {
    let message = if stage == "numeric" {
        // The matrix is mass plus weighted Laplacians: it fails to be positive definite only
        // through extreme weights, which slivers (near-zero angles) and out-of-range
        // materials make.
        format!(
            "the cloth's system is not positive definite ({e:?}): the mesh has sliver or \
             near-degenerate triangles, or the material is far out of range"
        )
    } else {
        format!("{e:?}")
    };
    Error::Factorization { stage, message }
}
