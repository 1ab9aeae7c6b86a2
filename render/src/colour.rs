//! Scalar colouring (viridis), colour bars and bitmap-font labels drawn into pictures.

use image::{Rgb, RgbImage};

/// Maps values in `[min, max]` to viridis colours (clamped outside; NaN is grey).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColourScale {
    /// Value drawn dark purple.
    pub min: f32,
    /// Value drawn yellow.
    pub max: f32,
}

/// Viridis at nine evenly spaced stops (matplotlib's table, rounded to 8 bits).
const VIRIDIS: [[u8; 3]; 9] = [
    [68, 1, 84],
    [71, 44, 122],
    [59, 81, 139],
    [44, 113, 142],
    [33, 144, 141],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

impl ColourScale {
    /// The colour of `value`.
    pub fn colour(&self, value: f32) -> [u8; 3] {
        if !value.is_finite() {
            return [128, 128, 128];
        }
        let span = self.max - self.min;
        let t = if span > 0.0 {
            ((value - self.min) / span).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let x = t * (VIRIDIS.len() - 1) as f32;
        let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
        let f = x - i as f32;
        std::array::from_fn(|c| {
            (VIRIDIS[i][c] as f32 * (1.0 - f) + VIRIDIS[i + 1][c] as f32 * f).round() as u8
        })
    }
}

/// Pixel size of one glyph at `scale` 1.
pub const GLYPH: u32 = 8;

/// Draws ASCII text with its top-left corner at (x, y), each glyph `scale` x 8 pixels.
pub fn draw_text(image: &mut RgbImage, x: u32, y: u32, text: &str, colour: [u8; 3], scale: u32) {
    let scale = scale.max(1);
    for (k, ch) in text.chars().enumerate() {
        let glyph = font8x8::legacy::BASIC_LEGACY
            .get(ch as usize)
            .copied()
            .unwrap_or([0; 8]);
        let gx = x + k as u32 * GLYPH * scale;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8u32 {
                if bits >> col & 1 == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (gx + col * scale + dx, y + row as u32 * scale + dy);
                        if px < image.width() && py < image.height() {
                            image.put_pixel(px, py, Rgb(colour));
                        }
                    }
                }
            }
        }
    }
}

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * GLYPH * scale.max(1)
}

/// Draws a vertical colour bar at the right edge with its label and the range's ends.
pub fn draw_colour_bar(image: &mut RgbImage, scale: &ColourScale, label: &str) {
    let (w, h) = (image.width(), image.height());
    let text_scale = if h >= 400 { 2 } else { 1 };
    let bar_w = (w / 32).max(6);
    let top = h / 8 + 2 * GLYPH * text_scale;
    let bottom = h - h / 8;
    if bottom <= top + 2 || w < bar_w + 4 {
        return;
    }
    let x0 = w - bar_w - w / 40 - 1;
    let ink = [20, 20, 24];
    for y in top..bottom {
        let t = 1.0 - (y - top) as f32 / (bottom - top - 1) as f32;
        let c = scale.colour(scale.min + t * (scale.max - scale.min));
        for x in x0..x0 + bar_w {
            let frame = y == top || y + 1 == bottom || x == x0 || x + 1 == x0 + bar_w;
            image.put_pixel(x, y, Rgb(if frame { ink } else { c }));
        }
    }
    let right_aligned = |t: &str| x0.saturating_sub(text_width(t, text_scale) + 4);
    let max = format_value(scale.max);
    let min = format_value(scale.min);
    draw_text(image, right_aligned(&max), top, &max, ink, text_scale);
    let y_min = bottom.saturating_sub(GLYPH * text_scale);
    draw_text(image, right_aligned(&min), y_min, &min, ink, text_scale);
    let lx = (x0 + bar_w).saturating_sub(text_width(label, text_scale));
    draw_text(
        image,
        lx,
        top - 2 * GLYPH * text_scale,
        label,
        ink,
        text_scale,
    );
}

/// Short tick labels: 3 significant digits.
fn format_value(v: f32) -> String {
    if v == 0.0 || (v.abs() >= 0.01 && v.abs() < 1000.0) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_ends_are_viridis_ends_and_nan_is_grey() {
        let s = ColourScale { min: 1.0, max: 3.0 };
        assert_eq!(s.colour(1.0), VIRIDIS[0]);
        assert_eq!(s.colour(-5.0), VIRIDIS[0]);
        assert_eq!(s.colour(3.0), VIRIDIS[8]);
        assert_eq!(s.colour(2.0), VIRIDIS[4]);
        assert_eq!(s.colour(f32::NAN), [128, 128, 128]);
    }

    #[test]
    fn text_marks_pixels_and_bar_fits() {
        let mut img = RgbImage::from_pixel(200, 200, Rgb([255; 3]));
        draw_text(&mut img, 2, 2, "E 1.5", [0; 3], 1);
        let dark = img.pixels().filter(|p| p.0 == [0; 3]).count();
        assert!(dark > 20, "{dark}");
        draw_colour_bar(&mut img, &ColourScale { min: 0.0, max: 5.0 }, "cm");
        assert!(
            img.pixels()
                .any(|p| p.0[0] > 200 && p.0[1] > 200 && p.0[2] < 100)
        );
        assert_eq!(format_value(1.25), "1.25");
        assert_eq!(format_value(0.0), "0");
    }
}
