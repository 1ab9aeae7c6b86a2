//! A small z-buffer rasterizer: triangles to depth, owner and barycentric buffers, then one
//! deferred shading pass (two-sided Lambert), outlines from depth, owner and normal
//! discontinuities, and a box-filtered downsample of the supersampled buffer.
//!
//! Written here because no maintained crate renders triangle meshes on the CPU without a GPU
//! API or a windowing stack; it is about 300 lines and allocation-free per frame (buffers are
//! kept between frames).

use image::RgbImage;

use crate::P3;
use crate::camera::{Camera, add, cross, dot, normalize, scale, sub};
use crate::colour::ColourScale;

/// One mesh to draw.
#[derive(Debug, Clone, Copy)]
pub struct Layer<'a> {
    /// Vertex positions, world units.
    pub positions: &'a [P3],
    /// Triangles (vertex indices); out-of-range indices are skipped.
    pub triangles: &'a [[u32; 3]],
    /// Base colour (sRGB).
    pub colour: [u8; 3],
    /// Optional per-vertex values, coloured through the scale instead of the base colour.
    pub values: Option<(&'a [f32], ColourScale)>,
}

/// Colours of the parts of a picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Background at the top and the bottom of the picture (a soft vertical gradient).
    pub background: ([u8; 3], [u8; 3]),
    /// Outline colour.
    pub outline: [u8; 3],
    /// Depth jump (world units) that counts as a silhouette between two samples.
    pub depth_edge: f32,
    /// Cosine of the normal angle below which neighbouring samples get a crease line.
    pub crease_cos: f32,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            background: ([236, 238, 242], [200, 204, 212]),
            outline: [34, 34, 40],
            depth_edge: 0.025,
            crease_cos: 0.55,
        }
    }
}

const NO_OWNER: u8 = u8::MAX;
const NEAR: f32 = 1e-3;

/// Renders layers into an RGB image; keeps its buffers between frames.
pub struct Renderer {
    width: usize,
    height: usize,
    ssaa: usize,
    style: Style,
    inv_depth: Vec<f32>,
    owner: Vec<u8>,
    triangle: Vec<u32>,
    bary: Vec<[f32; 2]>,
    normal: Vec<P3>,
    colour: Vec<[u8; 3]>,
    screen: Vec<[f32; 3]>,
    vertex_normals: Vec<P3>,
    vertex_depths: Vec<f32>,
    coverage: Vec<usize>,
    image: RgbImage,
}

impl Renderer {
    /// A renderer for `width` x `height` pictures, each pixel the mean of `ssaa` x `ssaa`
    /// samples (1 = no anti-aliasing).
    pub fn new(width: u32, height: u32, ssaa: u32) -> Renderer {
        let (w, h, s) = (
            width.max(1) as usize,
            height.max(1) as usize,
            ssaa.max(1) as usize,
        );
        let n = w * s * h * s;
        Renderer {
            width: w,
            height: h,
            ssaa: s,
            style: Style::default(),
            inv_depth: vec![0.0; n],
            owner: vec![NO_OWNER; n],
            triangle: vec![0; n],
            bary: vec![[0.0; 2]; n],
            normal: vec![[0.0; 3]; n],
            colour: vec![[0; 3]; n],
            screen: Vec::new(),
            vertex_normals: Vec::new(),
            vertex_depths: Vec::new(),
            coverage: Vec::new(),
            image: RgbImage::new(width.max(1), height.max(1)),
        }
    }

    /// Replaces the colours and edge thresholds.
    pub fn with_style(mut self, style: Style) -> Renderer {
        self.style = style;
        self
    }

    /// Width / height of the pictures.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Output pixels (at least half their samples) covered by layer `k` in the last picture.
    pub fn coverage(&self, k: usize) -> usize {
        self.coverage.get(k).copied().unwrap_or(0)
    }

    /// Draws the layers (at most 255) as seen by `camera`.
    pub fn render(&mut self, camera: &Camera, layers: &[Layer]) -> &RgbImage {
        let layers = &layers[..layers.len().min(NO_OWNER as usize)];
        self.inv_depth.fill(0.0);
        self.owner.fill(NO_OWNER);
        for (k, layer) in layers.iter().enumerate() {
            self.rasterize(camera, k as u8, layer);
        }
        self.shade(camera, layers);
        self.outline();
        self.downsample(layers.len());
        &self.image
    }

    /// Writes the layer's triangles into the depth, owner and barycentric buffers.
    fn rasterize(&mut self, camera: &Camera, owner: u8, layer: &Layer) {
        let (sw, sh) = (self.width * self.ssaa, self.height * self.ssaa);
        let half_h = 0.5 * sh as f32;
        let (cx, cy) = (0.5 * sw as f32, half_h);
        let f = camera.focal * half_h;
        self.screen.clear();
        self.screen.extend(layer.positions.iter().map(|&p| {
            let q = camera.to_camera(p);
            let z = if q[2].is_finite() { q[2] } else { -1.0 };
            [cx + f * q[0] / z, cy - f * q[1] / z, z]
        }));
        let n = self.screen.len() as u32;
        for (t, tri) in layer.triangles.iter().enumerate() {
            if tri.iter().any(|&i| i >= n) {
                continue;
            }
            let [a, b, c] = tri.map(|i| self.screen[i as usize]);
            if a[2] < NEAR || b[2] < NEAR || c[2] < NEAR {
                continue;
            }
            let area = edge(a, b, c);
            if area.is_nan() || area.abs() <= 1e-12 {
                continue;
            }
            let inv_area = 1.0 / area;
            let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
            let x1 = (a[0].max(b[0]).max(c[0]).ceil() as usize).min(sw);
            let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
            let y1 = (a[1].max(b[1]).max(c[1]).ceil() as usize).min(sh);
            let (iza, izb, izc) = (1.0 / a[2], 1.0 / b[2], 1.0 / c[2]);
            for y in y0..y1 {
                let p = [x0 as f32 + 0.5, y as f32 + 0.5, 0.0];
                // Edge functions at the row's first sample, stepped along x.
                let mut wa = edge(b, c, p) * inv_area;
                let mut wb = edge(c, a, p) * inv_area;
                let mut wc = edge(a, b, p) * inv_area;
                let (da, db, dc) = (
                    -(c[1] - b[1]) * inv_area,
                    -(a[1] - c[1]) * inv_area,
                    -(b[1] - a[1]) * inv_area,
                );
                let row = y * sw;
                for x in x0..x1 {
                    if wa >= 0.0 && wb >= 0.0 && wc >= 0.0 {
                        let iz = wa * iza + wb * izb + wc * izc;
                        let i = row + x;
                        if iz > self.inv_depth[i] {
                            self.inv_depth[i] = iz;
                            self.owner[i] = owner;
                            self.triangle[i] = t as u32;
                            self.bary[i] = [wb, wc];
                        }
                    }
                    wa += da;
                    wb += db;
                    wc += dc;
                }
            }
        }
    }

    /// Colours every covered sample from its interpolated normal (two-sided Lambert, a key
    /// light above-left of the camera and a weak headlight).
    fn shade(&mut self, camera: &Camera, layers: &[Layer]) {
        // A raking key light (from the upper left, half round to the side) makes folds read.
        let key = normalize(add(
            add(scale(camera.forward, -0.55), scale(camera.up, 0.5)),
            scale(camera.right, -0.65),
        ));
        let towards = scale(camera.forward, -1.0);
        let sh = self.height * self.ssaa;
        let sw = self.width * self.ssaa;
        let (top, bottom) = self.style.background;
        for (k, layer) in layers.iter().enumerate() {
            vertex_normals(layer, &mut self.vertex_normals);
            self.vertex_depths.clear();
            self.vertex_depths
                .extend(layer.positions.iter().map(|&p| camera.to_camera(p)[2]));
            for i in 0..self.owner.len() {
                if self.owner[i] as usize != k {
                    continue;
                }
                let tri = layer.triangles[self.triangle[i] as usize];
                let [b1, b2] = self.bary[i];
                let b = [1.0 - b1 - b2, b1, b2];
                let z = tri.map(|v| self.vertex_depths[v as usize]);
                let q = [b[0] / z[0], b[1] / z[1], b[2] / z[2]];
                let sum = q[0] + q[1] + q[2];
                let q = q.map(|w| w / sum);
                let mut n = [0.0f32; 3];
                for (v, w) in tri.iter().zip(q) {
                    n = add(n, scale(self.vertex_normals[*v as usize], w));
                }
                let mut n = normalize(n);
                let mut back = 1.0;
                if dot(n, towards) < 0.0 {
                    n = scale(n, -1.0);
                    back = 0.8;
                }
                self.normal[i] = n;
                let light =
                    back * (0.18 + 0.7 * dot(n, key).max(0.0) + 0.22 * dot(n, towards).max(0.0));
                let base = match layer.values {
                    Some((values, scale)) => {
                        let v: f32 = tri
                            .iter()
                            .zip(q)
                            .map(|(&j, w)| values.get(j as usize).copied().unwrap_or(f32::NAN) * w)
                            .sum();
                        scale.colour(v)
                    }
                    None => layer.colour,
                };
                self.colour[i] = base.map(|c| (c as f32 * light).round().clamp(0.0, 255.0) as u8);
            }
        }
        for y in 0..sh {
            let t = y as f32 / sh.max(2) as f32;
            let bg: [u8; 3] =
                std::array::from_fn(|c| (top[c] as f32 * (1.0 - t) + bottom[c] as f32 * t) as u8);
            for x in 0..sw {
                let i = y * sw + x;
                if self.owner[i] == NO_OWNER {
                    self.colour[i] = bg;
                }
            }
        }
    }

    /// Darkens samples on silhouettes (owner change, depth jump) and creases.
    fn outline(&mut self) {
        let sw = self.width * self.ssaa;
        let sh = self.height * self.ssaa;
        let Style {
            outline,
            depth_edge,
            crease_cos,
            ..
        } = self.style;
        for y in 0..sh {
            for x in 0..sw {
                let i = y * sw + x;
                for j in [(x + 1 < sw).then(|| i + 1), (y + 1 < sh).then(|| i + sw)]
                    .into_iter()
                    .flatten()
                {
                    let (oi, oj) = (self.owner[i], self.owner[j]);
                    if oi == NO_OWNER && oj == NO_OWNER {
                        continue;
                    }
                    // The nearer sample carries the line, so it sits on the occluding surface.
                    let (zi, zj) = (self.inv_depth[i], self.inv_depth[j]);
                    let near = if zi >= zj { i } else { j };
                    let edge = oi != oj
                        || (1.0 / zi - 1.0 / zj).abs() > depth_edge
                        || dot(self.normal[i], self.normal[j]) < crease_cos;
                    if edge {
                        self.colour[near] = outline;
                    }
                }
            }
        }
    }

    /// Box-filters the samples into the output image and counts each layer's pixels.
    fn downsample(&mut self, layers: usize) {
        let s = self.ssaa;
        let sw = self.width * s;
        self.coverage.clear();
        self.coverage.resize(layers, 0);
        let mut counts = vec![0usize; layers];
        let inv = 1.0 / (s * s) as f32;
        for y in 0..self.height {
            for x in 0..self.width {
                let mut sum = [0.0f32; 3];
                counts.fill(0);
                for dy in 0..s {
                    let row = (y * s + dy) * sw + x * s;
                    for i in row..row + s {
                        let c = self.colour[i];
                        sum = [
                            sum[0] + c[0] as f32,
                            sum[1] + c[1] as f32,
                            sum[2] + c[2] as f32,
                        ];
                        if let Some(k) = counts.get_mut(self.owner[i] as usize) {
                            *k += 1;
                        }
                    }
                }
                for (k, &c) in counts.iter().enumerate() {
                    if 2 * c >= s * s {
                        self.coverage[k] += 1;
                    }
                }
                let px = sum.map(|v| (v * inv).round() as u8);
                self.image.put_pixel(x as u32, y as u32, image::Rgb(px));
            }
        }
    }
}

/// Twice the signed area of (a, b, p) in screen space.
#[inline]
fn edge(a: [f32; 3], b: [f32; 3], p: [f32; 3]) -> f32 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Area-weighted vertex normals of a layer into `out`.
fn vertex_normals(layer: &Layer, out: &mut Vec<P3>) {
    out.clear();
    out.resize(layer.positions.len(), [0.0; 3]);
    let n = out.len() as u32;
    for tri in layer.triangles {
        if tri.iter().any(|&i| i >= n) {
            continue;
        }
        let [a, b, c] = tri.map(|i| layer.positions[i as usize]);
        let face = cross(sub(b, a), sub(c, a));
        for &i in tri {
            out[i as usize] = add(out[i as usize], face);
        }
    }
    for v in out.iter_mut() {
        *v = normalize(*v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Bounds, View};

    fn quad(z: f32, size: f32) -> (Vec<P3>, Vec<[u32; 3]>) {
        (
            vec![
                [-size, -size, z],
                [size, -size, z],
                [size, size, z],
                [-size, size, z],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn nearer_layer_wins_and_coverage_is_counted() {
        let (back, tris) = quad(0.0, 1.0);
        let (front, _) = quad(0.5, 0.3);
        let camera = Camera::look_at([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 40.0);
        let mut r = Renderer::new(64, 64, 2);
        let layers = [
            Layer {
                positions: &back,
                triangles: &tris,
                colour: [200, 50, 50],
                values: None,
            },
            Layer {
                positions: &front,
                triangles: &tris,
                colour: [50, 50, 200],
                values: None,
            },
        ];
        let img = r.render(&camera, &layers).clone();
        let centre = img.get_pixel(32, 32).0;
        assert!(
            centre[2] > centre[0],
            "centre should be the front (blue) quad: {centre:?}"
        );
        let corner_in_back = img.get_pixel(40, 32).0;
        assert!(corner_in_back[0] > corner_in_back[2], "{corner_in_back:?}");
        assert!(r.coverage(1) > 100 && r.coverage(0) > r.coverage(1));
        // Drawing the front layer first gives the same picture: depth decides, not order.
        let swapped = [layers[1], layers[0]];
        let img2 = r.render(&camera, &swapped).clone();
        assert_eq!(img2.get_pixel(32, 32), img.get_pixel(32, 32));
    }

    #[test]
    fn empty_scene_is_background_and_bad_indices_are_skipped() {
        let (p, _) = quad(0.0, 1.0);
        let bad = [[0, 1, 9]];
        let b = Bounds::of(&p).unwrap();
        let camera = Camera::framing(View::Front, &b, 1.0);
        let mut r = Renderer::new(32, 32, 1);
        r.render(
            &camera,
            &[Layer {
                positions: &p,
                triangles: &bad,
                colour: [0, 0, 0],
                values: None,
            }],
        );
        assert_eq!(r.coverage(0), 0);
    }
}
