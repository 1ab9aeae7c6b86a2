//! Pictures of texel grids (geometry images, masks): one colour per texel, drawn as a square
//! block of pixels, v = 0 at the bottom so the picture reads like a UV plot.

use image::{Rgb, RgbImage};

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
}
