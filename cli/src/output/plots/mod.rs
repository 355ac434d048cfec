//! PNG figures for reports, by kind: [`line`](mod@line) plots (histories, forces, energy, sweeps),
//! [`shape`] plots (deformed shapes and forging stages, coloured through [`colour_bar`]) and
//! [`solid`] plots (deformed 3D bodies, shaded, coloured the same way).
//!
//! This module owns what they share: the Ubuntu Light font embedded in
//! `epaint_default_fonts` (registered once with plotters as `sans-serif`, so rendering never
//! depends on system fonts), text sizes and margins, data spans, the axes style and tick labels.
//! Tick positions are plotters' own (multiples of 1, 2 or 5 times a power of ten). Non-finite data
//! are skipped, degenerate ranges are widened, and every problem is reported as an
//! `Err(String)`: nothing in here panics on user data.

mod clip;
mod colour_bar;
mod line;
mod shape;
mod solid;

pub use line::{line_plot, Colour, Marker, Series};
pub use shape::{shape_plot, stages_plot, Lap, Stage};
pub use solid::{solid_plot, SolidPanel, View};

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::ranged1d::Ranged;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

/// Font family under which the embedded font is registered.
const FONT: &str = "sans-serif";
/// Font sizes in pixels.
const TITLE_FONT: f64 = 30.0;
const PANEL_TITLE_FONT: f64 = 24.0;
const DESC_FONT: f64 = 22.0;
const TICK_FONT: f64 = 18.0;
/// Height of the strip holding the figure title.
const TITLE_H: u32 = 54;
/// Height of the area below a plot holding tick labels and the axis description.
const X_AREA: u32 = 68;
/// Margins around a chart's plotting area and label areas.
const MARGIN_TOP: u32 = 8;
const MARGIN_BOTTOM: u32 = 8;
const MARGIN_LEFT: u32 = 12;
const MARGIN_RIGHT: u32 = 32;
/// Colour of the grid lines at the ticks.
const GRID: RGBColor = RGBColor(222, 222, 222);

/// Registers the embedded font once; later calls report the outcome of the first.
fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_ok()
    });
    ok.then_some(())
        .ok_or_else(|| "the embedded plot font could not be loaded".into())
}

/// Text style of the given pixel size in the embedded font.
fn font(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&BLACK)
}

/// Width in pixels of `text` at the given font size (estimated if the font cannot lay it out).
fn text_width(size: f64, text: &str) -> u32 {
    (FONT, size).into_font().box_size(text).map_or_else(
        |_| ((0.6 * size) as u32).saturating_mul(text.chars().count() as u32),
        |(w, _)| w,
    )
}

/// Creates the PNG canvas of the given size at `path`, white, after checking that the path
/// ends in `.png` (any other extension would make the image encoder pick another format).
fn png_canvas(
    path: &Path,
    size: (u32, u32),
) -> Result<DrawingArea<BitMapBackend<'_>, Shift>, String> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(format!("plot file {} must end in .png", path.display()));
    }
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    Ok(root)
}

/// Writes a canvas made by [`png_canvas`] to its file.
fn save(root: &DrawingArea<BitMapBackend, Shift>, path: &Path) -> Result<(), String> {
    root.present()
        .map_err(|e| format!("could not write {}: {e}", path.display()))
}

/// Formats a drawing error.
fn draw_err(e: impl std::fmt::Display) -> String {
    format!("could not draw the plot: {e}")
}

/// Draws `text` centred on the pixel `centre` of `area`.
fn centred_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    size: f64,
    centre: (i32, i32),
) -> Result<(), String> {
    let style = font(size).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(text, centre, style)).map_err(draw_err)
}

/// Draws a figure title centred in a strip [`TITLE_H`] high at the top of `root`; returns the
/// area below it.
fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, String> {
    let (strip, body) = root.split_vertically(TITLE_H);
    let centre = ((strip.dim_in_pixel().0 / 2) as i32, (TITLE_H / 2) as i32);
    centred_text(&strip, title, TITLE_FONT, centre)?;
    Ok(body)
}

/// At most `max` items, evenly spaced and including the first and the last.
fn evenly_spaced<T>(items: &[T], max: usize) -> Vec<&T> {
    if items.len() <= max || max < 2 {
        return items.iter().take(max.max(1)).collect();
    }
    let (last, steps) = (items.len() - 1, max - 1);
    (0..max)
        .map(|i| &items[(i * last + steps / 2) / steps])
        .collect()
}

/// A closed interval of finite numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Span {
    lo: f64,
    hi: f64,
}

impl Span {
    /// The interval [0, 1].
    const UNIT: Span = Span { lo: 0.0, hi: 1.0 };

    /// Smallest span holding every finite value, `None` if there is none.
    fn of(values: impl IntoIterator<Item = f64>) -> Option<Span> {
        let mut finite = values.into_iter().filter(|v| v.is_finite());
        let first = finite.next()?;
        Some(finite.fold(
            Span {
                lo: first,
                hi: first,
            },
            |s, v| Span {
                lo: s.lo.min(v),
                hi: s.hi.max(v),
            },
        ))
    }

    fn union(self, other: Span) -> Span {
        Span {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    fn width(self) -> f64 {
        self.hi - self.lo
    }

    /// Span of the given width around the same centre.
    fn with_width(self, width: f64) -> Span {
        let c = 0.5 * self.lo + 0.5 * self.hi;
        Span {
            lo: c - 0.5 * width,
            hi: c + 0.5 * width,
        }
    }

    /// Gives a zero (or numerically negligible) width a sensible size around the same value.
    fn widened(self) -> Span {
        let magnitude = self.lo.abs().max(self.hi.abs());
        if self.width() > 1e-9 * magnitude && self.width() > 1e-200 {
            self
        } else if magnitude > 1e-200 {
            self.with_width(0.1 * magnitude)
        } else {
            self.with_width(1.0)
        }
    }

    /// Span grown by `fraction` of its width on both sides.
    fn padded(self, fraction: f64) -> Span {
        self.with_width(self.width() * (1.0 + 2.0 * fraction))
    }

    /// Fails if the span cannot be drawn (infinite ends or width, or no width).
    fn checked(self) -> Result<Span, String> {
        let width = self.width();
        if self.lo.is_finite() && self.hi.is_finite() && width.is_finite() && width > 0.0 {
            return Ok(self);
        }
        Err(format!(
            "data range [{:e}, {:e}] is too large to plot",
            self.lo, self.hi
        ))
    }

    /// Position of `v` in the span, 0 at `lo` and 1 at `hi`.
    fn fraction(self, v: f64) -> f64 {
        (v - self.lo) / self.width()
    }

    /// The span as a plotters coordinate.
    fn coord(self) -> RangedCoordf64 {
        (self.lo..self.hi).into()
    }
}

/// One axis: its span, at most how many ticks plotters may put on it, and how they are
/// labelled (decimal places, and a power of ten shared by all labels for very large or small
/// numbers).
#[derive(Debug, Clone, PartialEq)]
struct Axis {
    span: Span,
    max_ticks: usize,
    decimals: usize,
    exponent: Option<i32>,
}

impl Axis {
    fn new(span: Span, max_ticks: usize) -> Axis {
        let ticks = span.coord().key_points(max_ticks);
        let step = match ticks.as_slice() {
            [a, b, ..] => b - a,
            _ => span.width(),
        };
        let magnitude = ticks.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let exponent = (magnitude >= 1e5 || (magnitude > 0.0 && step < 1e-4))
            .then(|| magnitude.log10().floor() as i32);
        let scaled = step / 10f64.powi(exponent.unwrap_or(0));
        Axis {
            span,
            max_ticks,
            decimals: (-scaled.log10() - 1e-6).ceil().clamp(0.0, 15.0) as usize,
            exponent,
        }
    }

    /// The tick positions (plotters' key points for the span).
    fn ticks(&self) -> Vec<f64> {
        self.span.coord().key_points(self.max_ticks)
    }

    /// Text of the tick at `v`.
    fn label(&self, v: f64) -> String {
        let v = if v.abs() < 1e-9 * self.span.width() {
            0.0
        } else {
            v
        };
        match self.exponent {
            Some(_) if v == 0.0 => "0".to_string(),
            Some(e) => format!("{:.*}e{e}", self.decimals, v / 10f64.powi(e)),
            None => format!("{:.*}", self.decimals, v),
        }
    }

    /// Width of a label area beside the plot: widest tick label, tick marks and the rotated
    /// axis description.
    fn label_area(&self) -> u32 {
        let widest = self
            .ticks()
            .into_iter()
            .map(|v| text_width(TICK_FONT, &self.label(v)));
        widest.max().unwrap_or(0) + 14 + (1.3 * DESC_FONT) as u32 + 10
    }
}

/// Builds a chart of the two axes on `area` (margins, label areas: `y_area` wide at the left,
/// [`X_AREA`] below) and draws its axes with [`draw_axes`].
fn axes_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    axes: (&Axis, &Axis),
    descs: (&str, &str),
    y_area: u32,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, String> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(MARGIN_TOP)
        .margin_bottom(MARGIN_BOTTOM)
        .margin_left(MARGIN_LEFT)
        .margin_right(MARGIN_RIGHT)
        .x_label_area_size(X_AREA)
        .y_label_area_size(y_area)
        .build_cartesian_2d(axes.0.span.coord(), axes.1.span.coord())
        .map_err(draw_err)?;
    draw_axes(&mut chart, axes, descs, true)?;
    Ok(chart)
}

/// Draws the axes of `chart` in the shared style: ticks, tick labels and descriptions in the
/// label areas the chart has, grid lines at the ticks if `grid`, and a thin frame around the
/// plotting area.
fn draw_axes<DB: DrawingBackend>(
    chart: &mut ChartContext<DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    (x, y): (&Axis, &Axis),
    (x_desc, y_desc): (&str, &str),
    grid: bool,
) -> Result<(), String> {
    let x_fmt = |v: &f64| x.label(*v);
    let y_fmt = |v: &f64| y.label(*v);
    let mut mesh = chart.configure_mesh();
    if !grid {
        mesh.disable_mesh();
    }
    mesh.x_labels(x.max_ticks)
        .y_labels(y.max_ticks)
        .max_light_lines(0)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(font(TICK_FONT))
        .axis_desc_style(font(DESC_FONT))
        .bold_line_style(GRID)
        .axis_style(BLACK)
        .set_all_tick_mark_size(6)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .draw()
        .map_err(draw_err)?;
    let corners = [(x.span.lo, y.span.lo), (x.span.hi, y.span.hi)];
    chart
        .plotting_area()
        .draw(&Rectangle::new(corners, BLACK.stroke_width(1)))
        .map_err(draw_err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::Range;

    /// A fresh directory for one test's images, removed when it drops.
    pub(super) fn temp_dir(test: &str) -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix(&format!("rkforge_plots_{test}_"))
            .tempdir()
            .expect("create temp dir")
    }

    /// Checks the PNG signature and returns width and height from the IHDR chunk.
    pub(super) fn png_size(path: &Path) -> (u32, u32) {
        let bytes = std::fs::read(path).expect("PNG file written");
        assert!(
            bytes.len() > 33,
            "{} is too short for a PNG",
            path.display()
        );
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR", "first chunk is IHDR");
        let be =
            |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
        (be(16), be(20))
    }

    /// Renders into memory and returns the RGB pixels with the image size.
    pub(super) fn render(
        size: (u32, u32),
        draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>),
    ) -> Vec<u8> {
        let mut pixels = vec![0u8; 3 * size.0 as usize * size.1 as usize];
        {
            let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
            root.fill(&WHITE).expect("fill");
            draw(&root);
            root.present().expect("present to buffer");
        }
        pixels
    }

    /// Number of dark pixels in the rows `rows` of an RGB image `width` pixels wide.
    pub(super) fn dark_pixels(pixels: &[u8], width: u32, rows: Range<u32>) -> usize {
        let row_bytes = 3 * width as usize;
        pixels[rows.start as usize * row_bytes..rows.end as usize * row_bytes]
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c < 100))
            .count()
    }

    /// Deterministic pseudo-random garbage (xorshift): counts and numbers with a share of
    /// zeros, extremes, NaN and infinities.
    pub(super) struct Garbage(pub(super) u64);

    impl Garbage {
        pub(super) fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }

        pub(super) fn value(&mut self) -> f64 {
            const SPECIALS: [f64; 10] = [
                0.0,
                -0.0,
                1.0,
                -1.0,
                1e-300,
                1e300,
                f64::MAX,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            let r = self.next();
            match r % 4 {
                0 => SPECIALS[(r >> 8) as usize % SPECIALS.len()],
                _ => (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0,
            }
        }
    }

    #[test]
    fn ticks_are_nice_and_labelled_consistently() {
        let labels = |lo: f64, hi: f64, n: usize| {
            let axis = Axis::new(Span { lo, hi }, n);
            let ticks = axis.ticks();
            ticks.iter().map(|&v| axis.label(v)).collect::<Vec<_>>()
        };
        assert_eq!(
            labels(-0.03, 1.03, 7),
            ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]
        );
        assert_eq!(labels(-1.0, 55.0, 7), ["0", "10", "20", "30", "40", "50"]);
        assert_eq!(labels(-0.3, 0.75, 12)[..4], ["-0.2", "-0.1", "0.0", "0.1"]);
        let big = Axis::new(
            Span {
                lo: 2.0e6,
                hi: 2.05e6,
            },
            6,
        );
        assert_eq!(big.label(2.01e6), "2.01e6");
        let small = Axis::new(Span { lo: 0.0, hi: 5e-5 }, 6);
        assert_eq!(small.label(0.0), "0");
        assert_eq!(small.label(2e-5), "2e-5");
    }

    #[test]
    fn spans_are_made_drawable() {
        let flat = Span { lo: 3.0, hi: 3.0 }.widened();
        assert!(flat.width() > 0.0 && flat.lo + flat.hi == 6.0);
        let zero = Span { lo: 0.0, hi: 0.0 }.widened();
        assert_eq!(zero, Span { lo: -0.5, hi: 0.5 });
        assert_eq!(
            Span::of([f64::NAN, 2.0, f64::INFINITY, -1.0]),
            Some(Span { lo: -1.0, hi: 2.0 })
        );
        assert_eq!(Span::of([f64::NAN]), None);
        let huge = Span {
            lo: -f64::MAX,
            hi: f64::MAX,
        };
        assert!(huge.checked().is_err());
    }
}
