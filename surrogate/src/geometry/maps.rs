//! Geometry images of one template: encoding per-vertex vectors into an R x R x 3 image
//! (barycentric interpolation per texel), reading an image back to one value per vertex
//! (bilinear at every UV corner, chart-aware, seam duplicates averaged) and the exact
//! transpose of the readback (an image gradient from per-vertex gradients), which the
//! intersection guidance needs.
//!
//! Images are channels-last `[f64; 3]` per texel, texel `j * R + i` (see `atlas.rs`).

use sim::recording::TemplateArrays;

use super::atlas::Atlas;
use crate::error::{Error, Result};

/// One template's encoder and readback at one resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryImage {
    atlas: Atlas,
    /// The mesh triangles (3D vertex indices), one per UV triangle.
    triangles: Vec<[u32; 3]>,
    vertices: usize,
    /// Readback as a sparse matrix, CSR over vertices: `entries[start[v]..start[v + 1]]` are
    /// (texel, weight) pairs whose weights sum to 1.
    start: Vec<usize>,
    entries: Vec<(u32, f64)>,
    /// Texels the readback touches (with a non-zero weight).
    read: Vec<bool>,
}

/// Bilinear weights at a UV point: four (texel, weight) pairs, texels clamped to the image.
fn bilinear(uv: [f64; 2], r: usize) -> [(usize, f64); 4] {
    let x = uv[0] * r as f64 - 0.5;
    let y = uv[1] * r as f64 - 0.5;
    let (i0, j0) = (x.floor(), y.floor());
    let (fx, fy) = (x - i0, y - j0);
    let clamp = |v: f64| v.clamp(0.0, r as f64 - 1.0) as usize;
    let (ia, ib) = (clamp(i0), clamp(i0 + 1.0));
    let (ja, jb) = (clamp(j0), clamp(j0 + 1.0));
    [
        (ja * r + ia, (1.0 - fx) * (1.0 - fy)),
        (ja * r + ib, fx * (1.0 - fy)),
        (jb * r + ia, (1.0 - fx) * fy),
        (jb * r + ib, fx * fy),
    ]
}

impl GeometryImage {
    /// The geometry image of a template: `triangles` over its `vertices` 3D vertices, and its
    /// UV layout (`uvs`, one UV triangle per triangle) at `resolution`.
    pub fn new(
        vertices: usize,
        triangles: &[[u32; 3]],
        uvs: &[[f64; 2]],
        uv_triangles: &[[u32; 3]],
        resolution: usize,
    ) -> Result<Self> {
        if triangles.len() != uv_triangles.len() {
            return Err(Error::UvTriangleCount {
                triangles: triangles.len(),
                uv_triangles: uv_triangles.len(),
            });
        }
        if let Some(t) = triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= vertices))
        {
            return Err(Error::BadTriangle {
                triangle: t,
                vertices,
            });
        }
        let atlas = Atlas::new(uvs, uv_triangles, resolution)?;
        // The UV corners of every vertex, each once (seam duplicates are several corners).
        let mut corners: Vec<Vec<u32>> = vec![Vec::new(); vertices];
        for (t, uv_t) in triangles.iter().zip(uv_triangles) {
            for (&v, &c) in t.iter().zip(uv_t) {
                let list = &mut corners[v as usize];
                if !list.contains(&c) {
                    list.push(c);
                }
            }
        }
        if let Some(v) = corners.iter().position(Vec::is_empty) {
            return Err(Error::VertexWithoutUv { vertex: v });
        }
        let r = resolution;
        let mut start = Vec::with_capacity(vertices + 1);
        let mut entries = Vec::new();
        start.push(0);
        for list in &corners {
            let share = 1.0 / list.len() as f64;
            for &c in list {
                let chart = atlas.corner_chart()[c as usize];
                let taps = bilinear(uvs[c as usize], r);
                // Chart-aware: texels of other charts are ignored and the rest renormalized
                // (plain bilinear where no tap is on this chart).
                let own: f64 = taps
                    .iter()
                    .filter(|(k, _)| atlas.texel_chart()[*k] == chart)
                    .map(|(_, w)| w)
                    .sum();
                for (k, w) in taps {
                    let weight = if own > 1e-12 {
                        if atlas.texel_chart()[k] == chart {
                            w / own
                        } else {
                            0.0
                        }
                    } else {
                        w
                    };
                    if weight != 0.0 {
                        entries.push((k as u32, weight * share));
                    }
                }
            }
            start.push(entries.len());
        }
        let mut read = vec![false; r * r];
        for &(k, _) in &entries {
            read[k as usize] = true;
        }
        Ok(Self {
            atlas,
            triangles: triangles.to_vec(),
            vertices,
            start,
            entries,
            read,
        })
    }

    /// The geometry image of a recorded template.
    pub fn of_template(template: &TemplateArrays, resolution: usize) -> Result<Self> {
        Self::new(
            template.positions.len(),
            &template.triangles,
            &template.uvs,
            &template.uv_triangles,
            resolution,
        )
    }

    /// The physical size of a texel of `template` at `resolution`, cm: the square root of
    /// its 3D area over its UV area, over the resolution.
    pub fn texel_cm(template: &TemplateArrays, resolution: usize) -> f64 {
        let t = template;
        let area3 = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|i| nalgebra::Vector3::from(t.positions[i as usize]));
            0.5 * (b - a).cross(&(c - a)).norm()
        };
        let area2 = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|i| t.uvs[i as usize]);
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs()
        };
        let surface: f64 = t.triangles.iter().map(area3).sum();
        let uv: f64 = t.uv_triangles.iter().map(area2).sum();
        100.0 * (surface / uv.max(1e-12)).sqrt() / resolution as f64
    }

    /// The atlas.
    pub fn atlas(&self) -> &Atlas {
        &self.atlas
    }

    /// Texels per side.
    pub fn resolution(&self) -> usize {
        self.atlas.resolution()
    }

    /// Vertices of the template.
    pub fn vertices(&self) -> usize {
        self.vertices
    }

    /// Texels that matter for training: inside a chart, or read by the readback.
    pub fn loss_mask(&self) -> Vec<bool> {
        self.atlas
            .inside()
            .iter()
            .zip(&self.read)
            .map(|(a, b)| *a || *b)
            .collect()
    }

    /// Per-vertex vectors to an image: each texel interpolates its triangle's corners with its
    /// (possibly extrapolated) barycentrics.
    pub fn encode(&self, values: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
        self.check_vertices(values.len())?;
        Ok(self
            .atlas
            .texels()
            .iter()
            .map(|s| {
                let t = self.triangles[s.triangle as usize];
                let mut out = [0.0; 3];
                for (&v, w) in t.iter().zip(s.weights) {
                    for (o, x) in out.iter_mut().zip(values[v as usize]) {
                        *o += w * x;
                    }
                }
                out
            })
            .collect())
    }

    /// An image back to one value per vertex (`R` in the docs: a sparse linear map).
    pub fn read(&self, image: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
        self.check_texels(image.len())?;
        Ok((0..self.vertices)
            .map(|v| {
                let mut out = [0.0; 3];
                for &(k, w) in &self.entries[self.start[v]..self.start[v + 1]] {
                    for (o, x) in out.iter_mut().zip(image[k as usize]) {
                        *o += w * x;
                    }
                }
                out
            })
            .collect())
    }

    /// The transpose of [`Self::read`]: per-vertex vectors (a gradient with respect to the
    /// read values) to an image (the gradient with respect to the image).
    pub fn read_transpose(&self, per_vertex: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
        self.check_vertices(per_vertex.len())?;
        let r = self.resolution();
        let mut image = vec![[0.0; 3]; r * r];
        for (v, g) in per_vertex.iter().enumerate() {
            for &(k, w) in &self.entries[self.start[v]..self.start[v + 1]] {
                for (o, x) in image[k as usize].iter_mut().zip(g) {
                    *o += w * x;
                }
            }
        }
        Ok(image)
    }

    fn check_vertices(&self, n: usize) -> Result<()> {
        if n != self.vertices {
            return Err(Error::VertexCount {
                expected: self.vertices,
                got: n,
            });
        }
        Ok(())
    }

    fn check_texels(&self, n: usize) -> Result<()> {
        let r = self.resolution();
        if n != r * r {
            return Err(Error::TexelCount {
                expected: r * r,
                got: n,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles and UVs of an n x n grid over the UV square [0.2, 0.8]^2: one chart.
    fn grid(n: usize) -> (Vec<[u32; 3]>, Vec<[f64; 2]>) {
        let mut uvs = Vec::new();
        for j in 0..n {
            for i in 0..n {
                uvs.push([
                    0.2 + 0.6 * i as f64 / (n - 1) as f64,
                    0.2 + 0.6 * j as f64 / (n - 1) as f64,
                ]);
            }
        }
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
                tris.push([a, b, d]);
                tris.push([a, d, c]);
            }
        }
        (tris, uvs)
    }

    fn relative_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
        let scale = b.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    }

    #[test]
    fn a_field_affine_in_uv_and_a_constant_round_trip_exactly() {
        let (tris, uvs) = grid(9);
        let image = GeometryImage::new(uvs.len(), &tris, &uvs, &tris, 64).unwrap();
        let affine: Vec<[f64; 3]> = uvs
            .iter()
            .map(|p| [1.0 + 2.0 * p[0] - p[1], 0.5 * p[1], -3.0 + p[0]])
            .collect();
        let back = image.read(&image.encode(&affine).unwrap()).unwrap();
        let error = relative_error(&back, &affine);
        assert!(error < 1e-9, "affine field: relative error {error}");
        let constant = vec![[0.3, -1.2, 7.0]; uvs.len()];
        let back = image.read(&image.encode(&constant).unwrap()).unwrap();
        let error = relative_error(&back, &constant);
        assert!(error < 1e-12, "constant field: relative error {error}");
    }

    #[test]
    fn the_transpose_is_the_adjoint_of_the_readback() {
        let (tris, uvs) = grid(7);
        let image = GeometryImage::new(uvs.len(), &tris, &uvs, &tris, 32).unwrap();
        let r = 32;
        let x: Vec<[f64; 3]> = (0..r * r)
            .map(|k| {
                let f = k as f64;
                [(f * 0.37).sin(), (f * 0.11).cos(), (f * 0.07).sin() * 2.0]
            })
            .collect();
        let y: Vec<[f64; 3]> = (0..uvs.len())
            .map(|v| {
                let f = v as f64;
                [(f * 1.3).cos(), (f * 0.5).sin(), 1.0 - f * 0.01]
            })
            .collect();
        let dot = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .map(|(p, q)| p * q)
                .sum()
        };
        let left = dot(&image.read(&x).unwrap(), &y);
        let right = dot(&x, &image.read_transpose(&y).unwrap());
        assert!(
            (left - right).abs() <= 1e-9 * left.abs().max(right.abs()),
            "<R x, y> = {left}, <x, R^T y> = {right}"
        );
    }

    #[test]
    fn a_seam_vertex_reads_one_value_from_both_of_its_charts() {
        // Two triangles sharing the 3D edge (1, 2), cut apart in UV into two charts.
        let triangles = [[0, 1, 2], [1, 3, 2]];
        let uvs = [
            [0.1, 0.1],
            [0.4, 0.1],
            [0.1, 0.4],
            [0.6, 0.6],
            [0.9, 0.6],
            [0.6, 0.9],
        ];
        let uv_triangles = [[0, 1, 2], [4, 5, 3]];
        let image = GeometryImage::new(4, &triangles, &uvs, &uv_triangles, 64).unwrap();
        assert_eq!(image.atlas().charts(), 2);
        let values = [
            [0.0, 0.0, 0.0],
            [1.0, 2.0, 3.0],
            [-1.0, 0.5, 2.0],
            [4.0, 4.0, 4.0],
        ];
        let back = image.read(&image.encode(&values).unwrap()).unwrap();
        assert_eq!(back.len(), 4);
        let error = relative_error(&back, &values);
        assert!(error < 1e-9, "seam vertices read back {back:?}");
    }

    #[test]
    fn chart_aware_readback_ignores_a_neighbouring_chart() {
        // Two charts 0.2 texels apart carrying very different values: a plain bilinear sample
        // at the border would mix them.
        let gap = 0.2 / 64.0;
        let uvs = [
            [0.2, 0.2],
            [0.5, 0.2],
            [0.2, 0.5],
            [0.5 + gap, 0.2],
            [0.8, 0.2],
            [0.5 + gap, 0.5],
        ];
        let triangles = [[0, 1, 2], [3, 4, 5]];
        let image = GeometryImage::new(6, &triangles, &uvs, &triangles, 64).unwrap();
        let values = [
            [0.0; 3], [0.0; 3], [0.0; 3], [100.0; 3], [100.0; 3], [100.0; 3],
        ];
        let back = image.read(&image.encode(&values).unwrap()).unwrap();
        let error = relative_error(&back, &values);
        assert!(error < 1e-9, "read back {back:?}");
    }
}
