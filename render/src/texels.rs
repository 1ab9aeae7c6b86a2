//! Pictures of texel grids (geometry images, masks): one colour per texel, drawn as a square
//! block of pixels, v = 0 at the bottom so the picture reads like a UV plot.

use image::{Rgb, RgbImage};

use crate::{ColourScale, draw_colour_bar};

/// An R x R texel grid (texel `j * R + i`, row `j` = v) as a picture, each texel `pixels`
/// pixels wide, coloured by `colour(texel)`.
pub fn texel_picture(
    resolution: usize,
    pixels: u32,
    colour: impl Fn(usize) -> [u8; 3],
) -> RgbImage {
    let r = resolution as u32;
    let pixels = pixels.max(1);
    RgbImage::from_fn(r * pixels, r * pixels, |x, y| {
        let i = (x / pixels) as usize;
        let j = (r - 1 - y / pixels) as usize;
        Rgb(colour(j * resolution + i))
    })
}

/// A map of 3-vectors (a position map) as a picture: each component over its range among the
/// texels of `mask` as one colour channel; the other texels dimmed.
pub fn vector_picture(
    image: &[[f64; 3]],
    mask: &[bool],
    resolution: usize,
    pixels: u32,
) -> RgbImage {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (v, _) in image.iter().zip(mask).filter(|(_, m)| **m) {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    texel_picture(resolution, pixels, |t| {
        let dim = if mask[t] { 1.0 } else { 0.35 };
        std::array::from_fn(|k| {
            let span = (hi[k] - lo[k]).max(1e-12);
            (255.0 * dim * ((image[t][k] - lo[k]) / span).clamp(0.0, 1.0)) as u8
        })
    })
}

/// A map of 3-vectors in metres as their lengths in cm on `scale`, with a colour bar; the
/// texels outside `mask` grey.
pub fn magnitude_picture(
    image: &[[f64; 3]],
    mask: &[bool],
    resolution: usize,
    pixels: u32,
    scale: ColourScale,
) -> RgbImage {
    let mut picture = texel_picture(resolution, pixels, |t| {
        if !mask[t] {
            return [200, 200, 200];
        }
        let v = image[t];
        let cm = 100.0 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        scale.colour(cm as f32)
    });
    draw_colour_bar(&mut picture, &scale, "cm");
    picture
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_zero_is_drawn_bottom_left() {
        let picture = texel_picture(4, 3, |k| if k == 0 { [255, 0, 0] } else { [0, 0, 0] });
        assert_eq!(picture.dimensions(), (12, 12));
        assert_eq!(picture.get_pixel(1, 11).0, [255, 0, 0]);
        assert_eq!(picture.get_pixel(1, 1).0, [0, 0, 0]);
    }

    #[test]
    fn vectors_span_their_range_inside_the_mask_and_lengths_their_scale() {
        let image = [
            [0.0, 1.0, 2.0],
            [1.0, 3.0, 2.0],
            [9.0, 9.0, 9.0],
            [0.5, 2.0, 2.0],
        ];
        let mask = [true, true, false, true];
        let p = vector_picture(&image, &mask, 2, 1);
        // Texel 0 (bottom left) is each channel's minimum, texel 1 its maximum (channel 2 is
        // constant); texel 2, outside the mask, is dimmed and clamped.
        assert_eq!(p.get_pixel(0, 1).0, [0, 0, 0]);
        assert_eq!(p.get_pixel(1, 1).0, [255, 255, 0]);
        assert_eq!(p.get_pixel(0, 0).0, [89, 89, 89]);
        let scale = ColourScale {
            min: 0.0,
            max: 100.0,
        };
        let m = magnitude_picture(&[[1.0, 0.0, 0.0], [0.0; 3]], &[true, false], 1, 64, scale);
        assert_eq!(m.get_pixel(0, 0).0, scale.colour(100.0));
        let grey = magnitude_picture(&[[0.0; 3]], &[false], 1, 64, scale);
        assert_eq!(grey.get_pixel(0, 0).0, [200, 200, 200]);
    }
}
