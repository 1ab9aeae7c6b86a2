//! Projective-dynamics constraint terms W_t = (w_t / 2) |A_t x - p_t|^2 in one flat store.
//!
//! Every term is a stencil (vertex, coefficient) pairs, so A_t x = sum_k c_k x_{v_k} is a
//! 3-vector and the global matrix is sum_t w_t a_t a_t^T, one scalar matrix shared by x, y
//! and z. The kinds differ only in their projection p_t, each in its own file.

mod attachments;
pub mod bending;
mod seams;
mod springs;
mod stretch;

pub use attachments::Attachment;
pub use bending::BendingRest;
pub use seams::Seam;
pub use springs::Spring;

use crate::cloth::{ClothMesh, Vec3};
use crate::params::Material;

/// What a term's projection does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    /// Edge spring: the edge vector rescaled to its rest length.
    Stretch { rest_length: f64 },
    /// Laplacian bending: the current Laplacian rescaled to the rest Laplacian's norm.
    Bend { rest: Vec3 },
    /// Seam: the gap capped at the seam length cap (0 = closed).
    Seam,
    /// Attachment to a moving target point (index into the attachment targets).
    Attach { target: usize },
}

/// All terms of one cloth, with the weights of one material.
#[derive(Debug, Clone, Default)]
pub struct Constraints {
    /// The edge springs come first, terms [0, edges): stencil (i, 1), (j, -1) at entries
    /// 2t and 2t + 1, rest lengths in `edge_rest` (read without `kind`: see `project_all`).
    edges: usize,
    edge_rest: Vec<f64>,
    ptr: Vec<usize>,
    vertex: Vec<u32>,
    coeff: Vec<f64>,
    weight: Vec<f64>,
    kind: Vec<Kind>,
}

/// What the projections need besides the positions.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ProjectionInputs<'a> {
    /// Longest gap a seam keeps, m (infinite = no pull, 0 = closed).
    pub seam_length_cap: f64,
    /// Current target of each attachment.
    pub attachment_targets: &'a [Vec3],
}

impl Constraints {
    /// Stretch springs on every edge and bending on every interior vertex, then seams, extra
    /// springs and attachments, weighted by `material` (k_s per edge, k_b per bending term) and their own
    /// stiffness.
    pub fn build(
        mesh: &ClothMesh,
        material: &Material,
        bending_rest: BendingRest,
        seams: &[Seam],
        springs: &[Spring],
        attachments: &[Attachment],
    ) -> Self {
        let mut c = Self::default();
        c.ptr.push(0);
        stretch::add(&mut c, mesh, material.stretch);
        bending::add(&mut c, mesh, material.bending, bending_rest);
        seams::add(&mut c, seams);
        springs::add(&mut c, springs);
        attachments::add(&mut c, attachments);
        c
    }

    pub(crate) fn push(&mut self, stencil: &[(u32, f64)], weight: f64, kind: Kind) {
        for &(v, c) in stencil {
            self.vertex.push(v);
            self.coeff.push(c);
        }
        self.ptr.push(self.vertex.len());
        self.weight.push(weight);
        self.kind.push(kind);
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.weight.len()
    }

    /// Whether there are no terms.
    pub fn is_empty(&self) -> bool {
        self.weight.is_empty()
    }

    /// The stencil of term `t`.
    pub(crate) fn stencil(&self, t: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.ptr[t]..self.ptr[t + 1];
        self.vertex[range.clone()]
            .iter()
            .zip(&self.coeff[range])
            .map(|(&v, &c)| (v as usize, c))
    }

    /// Whether term `t` is a bending term.
    pub(crate) fn is_bending(&self, t: usize) -> bool {
        matches!(self.kind[t], Kind::Bend { .. })
    }

    /// Largest diagonal entry a bending term adds to A^T W A, and the smallest diagonal entry
    /// of the other terms plus `masses` / h^2 (to decide whether bending can be lagged).
    pub(crate) fn bending_share(&self, masses: &[f64], h: f64) -> f64 {
        let mut others: Vec<f64> = masses.iter().map(|m| m / (h * h)).collect();
        let mut bending: f64 = 0.0;
        for t in 0..self.len() {
            for (v, c) in self.stencil(t) {
                let d = self.weight[t] * c * c;
                if self.is_bending(t) {
                    bending = bending.max(d);
                } else {
                    others[v] += d;
                }
            }
        }
        bending / others.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Weight of term `t`.
    pub(crate) fn weight(&self, t: usize) -> f64 {
        self.weight[t]
    }

    /// A_t x.
    #[inline]
    pub(crate) fn apply(&self, t: usize, x: &[Vec3]) -> Vec3 {
        let mut sum = Vec3::zeros();
        for k in self.ptr[t]..self.ptr[t + 1] {
            sum += self.coeff[k] * x[self.vertex[k] as usize];
        }
        sum
    }

    /// p_t: the projection of the current A_t x onto the term's constraint set.
    #[inline]
    pub(crate) fn project(&self, t: usize, ax: Vec3, inputs: &ProjectionInputs) -> Vec3 {
        match self.kind[t] {
            Kind::Stretch { rest_length } => stretch::project(ax, rest_length),
            Kind::Bend { rest } => bending::project(ax, rest),
            Kind::Seam => seams::project(ax, inputs.seam_length_cap),
            Kind::Attach { target } => attachments::project(inputs.attachment_targets[target]),
        }
    }

    /// A_t x of every term into `out` (the same bits as [`Self::apply`] term by term).
    pub(crate) fn apply_all(&self, x: &[Vec3], out: &mut [Vec3]) {
        self.map_terms(x, out, |_, ax| ax, |_, ax| ax);
    }

    /// q_t = p_t(A_t x) - b_t for every term, b_t = A_t x_n (`start`), or A_t x for bending
    /// terms when `lag_bending` (they enter at the current iterate: see system.rs).
    pub(crate) fn project_all(
        &self,
        x: &[Vec3],
        start: &[Vec3],
        lag_bending: bool,
        inputs: &ProjectionInputs,
        q: &mut [Vec3],
    ) {
        self.map_terms(
            x,
            q,
            |t, edge| stretch::project(edge, self.edge_rest[t]) - start[t],
            |t, ax| {
                let base = if lag_bending && self.is_bending(t) {
                    ax
                } else {
                    start[t]
                };
                self.project(t, ax, inputs) - base
            },
        );
    }

    /// out_t = `edge(t, A_t x)` for the edge springs and `other(t, A_t x)` for the rest, on
    /// two halves of about equal stencil entries (a bending term has six or more, an edge
    /// two). The edge springs, most of the terms, take a loop of their own over plain arrays
    /// (same bits as the general stencil: 0 + 1 x_i - 1 x_j = x_i - x_j exactly).
    fn map_terms(
        &self,
        x: &[Vec3],
        out: &mut [Vec3],
        edge: impl Fn(usize, Vec3) -> Vec3 + Sync,
        other: impl Fn(usize, Vec3) -> Vec3 + Sync,
    ) {
        crate::spin_join::halves(out, &self.ptr, |first, out| {
            let edges = self.edges.clamp(first, first + out.len()) - first;
            let (edge_out, rest_out) = out.split_at_mut(edges);
            for (k, o) in edge_out.iter_mut().enumerate() {
                let t = first + k;
                let (i, j) = (self.vertex[2 * t], self.vertex[2 * t + 1]);
                *o = edge(t, x[i as usize] - x[j as usize]);
            }
            for (k, o) in rest_out.iter_mut().enumerate() {
                let t = first + edges + k;
                *o = other(t, self.apply(t, x));
            }
        });
    }

    /// Per vertex, the terms it appears in with coefficient times weight (for the gather that
    /// builds the right-hand side without write conflicts).
    pub(crate) fn incidence(&self, num_vertices: usize) -> (Vec<usize>, Vec<(u32, f64)>) {
        let mut count = vec![0usize; num_vertices + 1];
        for &v in &self.vertex {
            count[v as usize + 1] += 1;
        }
        for i in 0..num_vertices {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut entries = vec![(0u32, 0.0); self.vertex.len()];
        for t in 0..self.len() {
            for k in self.ptr[t]..self.ptr[t + 1] {
                let v = self.vertex[k] as usize;
                entries[fill[v]] = (t as u32, self.coeff[k] * self.weight[t]);
                fill[v] += 1;
            }
        }
        (count, entries)
    }

    /// Potential energy sum_t (w_t / 2) |A_t x - p_t(x)|^2, joules.
    pub(crate) fn energy(&self, x: &[Vec3], inputs: &ProjectionInputs) -> f64 {
        (0..self.len())
            .map(|t| {
                let ax = self.apply(t, x);
                0.5 * self.weight[t] * (ax - self.project(t, ax, inputs)).norm_squared()
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_all_and_apply_all_match_each_term() {
        let mesh = ClothMesh::grid(6, 0.5, 0.0).unwrap();
        let seams = [Seam {
            a: 0,
            b: 35,
            stiffness: 1e3,
        }];
        let c = Constraints::build(
            &mesh,
            &Material::default(),
            BendingRest::Curved,
            &seams,
            &[],
            &[],
        );
        // A crumpled state and a start with its own A x_n.
        let x: Vec<Vec3> = mesh
            .rest()
            .iter()
            .enumerate()
            .map(|(i, p)| p + Vec3::new(0.0, 0.01 * (i as f64 * 0.7).sin(), 0.003 * i as f64))
            .collect();
        let start: Vec<Vec3> = (0..c.len()).map(|t| c.apply(t, mesh.rest())).collect();
        let inputs = ProjectionInputs {
            seam_length_cap: 0.0,
            attachment_targets: &[],
        };
        for lag in [false, true] {
            let mut q = vec![Vec3::zeros(); c.len()];
            c.project_all(&x, &start, lag, &inputs, &mut q);
            for (t, q) in q.iter().enumerate() {
                let ax = c.apply(t, &x);
                let base = if lag && c.is_bending(t) { ax } else { start[t] };
                assert_eq!(*q, c.project(t, ax, &inputs) - base, "term {t}");
            }
        }
        let mut ax = vec![Vec3::zeros(); c.len()];
        c.apply_all(&x, &mut ax);
        for (t, ax) in ax.iter().enumerate() {
            assert_eq!(*ax, c.apply(t, &x), "A x of term {t}");
        }
    }
}
