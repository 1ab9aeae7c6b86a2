//! Contact sheets (labelled grids of pictures), PNG encoding and animated GIFs.

use std::io::Write;

use image::{Rgb, RgbImage};

use crate::Error;
use crate::colour::{GLYPH, draw_text};

/// Lays pictures out in a grid of `columns`, each with its label in the top-left corner.
/// Pictures smaller than the first are centred in their cell.
pub fn contact_sheet(tiles: &[(RgbImage, String)], columns: usize) -> RgbImage {
    let Some((first, _)) = tiles.first() else {
        return RgbImage::new(1, 1);
    };
    let (tw, th) = first.dimensions();
    let columns = columns.clamp(1, tiles.len()) as u32;
    let rows = tiles.len().div_ceil(columns as usize) as u32;
    let gap = 4;
    let mut sheet = RgbImage::from_pixel(
        columns * tw + (columns + 1) * gap,
        rows * th + (rows + 1) * gap,
        Rgb([255, 255, 255]),
    );
    let text_scale = if th >= 400 { 2 } else { 1 };
    for (k, (tile, label)) in tiles.iter().enumerate() {
        let (c, r) = (k as u32 % columns, k as u32 / columns);
        let x0 = gap + c * (tw + gap) + tw.saturating_sub(tile.width()) / 2;
        let y0 = gap + r * (th + gap) + th.saturating_sub(tile.height()) / 2;
        for (x, y, p) in tile.enumerate_pixels() {
            if x < tw && y < th {
                sheet.put_pixel(x0 + x, y0 + y, *p);
            }
        }
        let pad = GLYPH * text_scale / 2;
        draw_text(
            &mut sheet,
            x0 + pad,
            y0 + pad,
            label,
            [20, 20, 24],
            text_scale,
        );
    }
    sheet
}

/// Encodes a picture as PNG.
pub fn write_png(out: &mut impl Write, image: &RgbImage) -> Result<(), Error> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png)?;
    out.write_all(bytes.get_ref())?;
    Ok(())
}

/// An animated GIF written frame by frame (each frame quantized to its own 256 colours).
pub struct GifWriter<W: Write> {
    encoder: gif::Encoder<W>,
    size: (u16, u16),
    delay_cs: u16,
}

impl<W: Write> GifWriter<W> {
    /// Starts a looping GIF of `width` x `height` frames shown at `fps`.
    pub fn new(out: W, width: u32, height: u32, fps: f32) -> Result<Self, Error> {
        let size = (
            u16::try_from(width).map_err(|_| Error::Size(width))?,
            u16::try_from(height).map_err(|_| Error::Size(height))?,
        );
        let mut encoder = gif::Encoder::new(out, size.0, size.1, &[])?;
        encoder.set_repeat(gif::Repeat::Infinite)?;
        // GIF delays are in hundredths of a second; browsers slow delays below 2 down.
        let delay_cs = (100.0 / fps.max(1.0)).round().clamp(2.0, 65535.0) as u16;
        Ok(Self {
            encoder,
            size,
            delay_cs,
        })
    }

    /// Appends a frame (same size as the GIF).
    pub fn push(&mut self, image: &RgbImage) -> Result<(), Error> {
        if image.dimensions() != (self.size.0 as u32, self.size.1 as u32) {
            return Err(Error::Size(image.width()));
        }
        let mut frame = gif::Frame::from_rgb_speed(self.size.0, self.size.1, image.as_raw(), 10);
        frame.delay = self.delay_cs;
        self.encoder.write_frame(&frame)?;
        Ok(())
    }

    /// Finishes the file and returns the writer.
    pub fn finish(self) -> Result<W, Error> {
        Ok(self.encoder.into_inner()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_places_tiles_in_a_grid() {
        let red = RgbImage::from_pixel(20, 10, Rgb([255, 0, 0]));
        let blue = RgbImage::from_pixel(20, 10, Rgb([0, 0, 255]));
        let tiles = vec![
            (red.clone(), String::new()),
            (blue, String::new()),
            (red, String::new()),
        ];
        let sheet = contact_sheet(&tiles, 2);
        assert_eq!(sheet.dimensions(), (2 * 20 + 3 * 4, 2 * 10 + 3 * 4));
        assert_eq!(sheet.get_pixel(4 + 20 + 4 + 5, 9).0, [0, 0, 255]);
        assert_eq!(sheet.get_pixel(9, 4 + 10 + 4 + 5).0, [255, 0, 0]);
    }

    #[test]
    fn gif_round_trips_its_frames() {
        let mut g = GifWriter::new(Vec::new(), 16, 8, 15.0).unwrap();
        for v in [0u8, 128, 255] {
            g.push(&RgbImage::from_pixel(16, 8, Rgb([v, 40, 200])))
                .unwrap();
        }
        assert!(g.push(&RgbImage::new(4, 4)).is_err());
        let bytes = g.finish().unwrap();
        let mut decoder = gif::DecodeOptions::new()
            .read_info(std::io::Cursor::new(bytes))
            .unwrap();
        let mut frames = 0;
        while let Some(f) = decoder.read_next_frame().unwrap() {
            assert_eq!((f.width, f.height, f.delay), (16, 8, 7));
            frames += 1;
        }
        assert_eq!(frames, 3);
    }
}
