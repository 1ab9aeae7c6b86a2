//! Pictures of garment sequences, with no GPU and no display: a small CPU rasterizer (two-sided
//! Lambert shading, outlines, optional per-vertex colouring with a colour bar), contact sheets,
//! PNG and animated GIF encoding, and a self-contained WebGL viewer page.
//!
//! The drawing core takes plain data (vertex positions and triangles as `f32` triples) and
//! gives pictures. [`recording`] draws the engine's recordings with their bodies on top of it
//! (frames, sheets, GIFs, the viewer page and the reports' comparisons), for the command line
//! and the surrogate's reports.
#![warn(missing_docs)]

mod camera;
mod chart;
mod colour;
mod raster;
pub mod recording;
mod sheet;
mod texels;
pub mod viewer;

pub use camera::{Bounds, Camera, View};
pub use chart::{Series, log_line_chart};
pub use colour::{ColourScale, draw_colour_bar, draw_text};
pub use image::RgbImage;
pub use raster::{Layer, Renderer, Style};
pub use sheet::{GifWriter, contact_sheet, write_png};
pub use texels::{magnitude_picture, texel_picture, vector_picture};

/// A point or vector, world units (metres in this project).
pub type P3 = [f32; 3];

/// What can go wrong while encoding pictures or pages.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Writing failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// PNG encoding failed.
    #[error("PNG encoding: {0}")]
    Png(#[from] image::ImageError),
    /// GIF encoding failed.
    #[error("GIF encoding: {0}")]
    Gif(#[from] gif::EncodingError),
    /// A picture size GIF cannot hold, or a frame of the wrong size.
    #[error("picture size {0} does not fit the GIF (at most 65535, all frames the same size)")]
    Size(u32),
    /// Inconsistent input data.
    #[error("{0}")]
    Input(String),
    /// A recording could not be read, or a body measured.
    #[error(transparent)]
    Engine(#[from] sim::Error),
    /// An output could not be written whole.
    #[error(transparent)]
    Files(#[from] files::Error),
}
