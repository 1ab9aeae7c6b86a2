//! Line charts of training curves (loss against step, log scale): plotters maps the data and
//! draws the lines and grid; labels use the crate's bitmap font, so no system font is needed.

use plotters::coord::combinators::IntoLogRange;
use plotters::prelude::*;

use crate::{Error, RgbImage, draw_text};

/// One curve: a name for the legend, its points and its colour.
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend entry.
    pub name: &'a str,
    /// `(x, y)` points in drawing order; points with `y <= 0` or not finite are skipped.
    pub points: &'a [(f64, f64)],
    /// RGB colour.
    pub colour: [u8; 3],
}

/// The chart's axes: x from the data, y in whole decades 10^d0 ..= 10^d1 so the grid lines
/// fall on 10^k.
struct Range {
    x0: f64,
    x1: f64,
    d0: i32,
    d1: i32,
}

impl Range {
    /// The range of the drawable points of `series` (positive, finite), or a default.
    fn of(series: &[Series]) -> Self {
        let all: Vec<(f64, f64)> = series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|&&(x, y)| x.is_finite() && y.is_finite() && y > 0.0)
            .copied()
            .collect();
        let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, 1.0f64, 1e-3f64, 1.0f64);
        if !all.is_empty() {
            x0 = all.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            x1 = all.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
            y0 = all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            y1 = all.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        }
        if x1 <= x0 {
            x1 = x0 + 1.0;
        }
        let (d0, mut d1) = (y0.log10().floor() as i32, y1.log10().ceil() as i32);
        if d1 <= d0 {
            d1 = d0 + 1;
        }
        Self { x0, x1, d0, d1 }
    }
}

/// A white `width` x `height` chart of `series` with a log-scale y axis, a title, tick labels
/// and a legend. Fails only on a size plotters cannot draw.
pub fn log_line_chart(
    title: &str,
    x_label: &str,
    series: &[Series],
    width: u32,
    height: u32,
) -> Result<RgbImage, Error> {
    let finite = |&&(x, y): &&(f64, f64)| x.is_finite() && y.is_finite() && y > 0.0;
    let range = Range::of(series);
    let (x0, x1, d0, d1) = (range.x0, range.x1, range.d0, range.d1);
    let (y0, y1) = (10f64.powi(d0), 10f64.powi(d1));
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    let mut ticks = Vec::new();
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        let plot_error = |e: &dyn std::fmt::Display| Error::Input(format!("chart: {e}"));
        let mut chart = ChartBuilder::on(&root)
            .margin_top(28)
            .margin_left(64)
            .margin_right(16)
            .margin_bottom(32)
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(|e| plot_error(&e))?;
        let grey = RGBColor(220, 220, 220);
        for d in d0..=d1 {
            let y = 10f64.powi(d);
            chart
                .draw_series(LineSeries::new([(x0, y), (x1, y)], grey))
                .map_err(|e| plot_error(&e))?;
            ticks.push((chart.backend_coord(&(x0, y)), format!("1e{d}")));
        }
        for k in 0..=4 {
            let x = x0 + (x1 - x0) * k as f64 / 4.0;
            chart
                .draw_series(LineSeries::new([(x, y0), (x, y1)], grey))
                .map_err(|e| plot_error(&e))?;
            ticks.push((chart.backend_coord(&(x, y0)), format!("{x:.0}")));
        }
        for s in series {
            let [r, g, b] = s.colour;
            let points: Vec<(f64, f64)> = s.points.iter().filter(finite).copied().collect();
            chart
                .draw_series(LineSeries::new(points, RGBColor(r, g, b).stroke_width(2)))
                .map_err(|e| plot_error(&e))?;
        }
        root.present().map_err(|e| plot_error(&e))?;
    }
    let mut image = RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| Error::Input("chart buffer of the wrong size".into()))?;
    let ink = [40, 40, 40];
    for ((px, py), text) in ticks {
        let (px, py) = (px.max(0) as u32, py.max(0) as u32);
        if text.starts_with("1e") {
            draw_text(&mut image, 4, py.saturating_sub(4), &text, ink, 1);
        } else {
            let half = text.len() as u32 * 4;
            draw_text(&mut image, px.saturating_sub(half), py + 6, &text, ink, 1);
        }
    }
    draw_text(&mut image, 64, 8, title, ink, 1);
    let label_x = width.saturating_sub(x_label.len() as u32 * 8 + 16);
    draw_text(
        &mut image,
        label_x,
        height.saturating_sub(12),
        x_label,
        ink,
        1,
    );
    let mut legend_x = 64 + title.len() as u32 * 8 + 24;
    for s in series {
        draw_text(
            &mut image,
            legend_x,
            8,
            &format!("- {}", s.name),
            s.colour,
            1,
        );
        legend_x += (s.name.len() as u32 + 3) * 8;
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_falling_curve_is_drawn_in_its_colour() {
        let points: Vec<(f64, f64)> = (0..50)
            .map(|k| (k as f64, (-0.1 * k as f64).exp()))
            .collect();
        let image = log_line_chart(
            "loss",
            "step",
            &[Series {
                name: "train",
                points: &points,
                colour: [200, 30, 30],
            }],
            320,
            200,
        )
        .unwrap();
        assert_eq!(image.dimensions(), (320, 200));
        let red = image.pixels().filter(|p| p.0 == [200, 30, 30]).count();
        assert!(red > 100, "{red} pixels of the curve's colour");
        // The curve falls: its colour sits higher on the left than on the right.
        let top = |x0: u32, x1: u32| {
            (0..200)
                .find(|&y| (x0..x1).any(|x| image.get_pixel(x, y).0 == [200, 30, 30] && y > 20))
                .unwrap_or(200)
        };
        assert!(top(70, 120) < top(250, 300));
    }
}
