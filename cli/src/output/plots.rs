//! PNG figures for reports: line plots, deformed shapes coloured by a field, forging stages.
//!
//! All text uses the Ubuntu Light font embedded in `epaint_default_fonts`, registered once with
//! plotters under the family name `sans-serif`, so rendering never depends on system fonts.
//! Non-finite data are skipped, degenerate ranges are widened, and every problem is reported as
//! an `Err(String)`: nothing in here panics on user data.

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

/// One curve of a line plot.
///
/// `x` and `y` must have the same length. Points with a non-finite coordinate are skipped and
/// break the line. Series with few points also get a dot at every point.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
}

/// A labelled marker (e.g. a published value) drawn as a distinct point with its label in the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Legend text; an empty label keeps the marker out of the legend.
    pub label: String,
    /// Abscissa.
    pub x: f64,
    /// Ordinate.
    pub y: f64,
}

/// One panel of [`stages_plot`]: a deformed shape with its own title and tools.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage<'a> {
    /// Panel title, e.g. "Stage 2: 40 % reduction".
    pub title: String,
    /// Node positions (m), indexed by the shared quads.
    pub positions: &'a [[f64; 2]],
    /// One value per node, shown with the shared colour scale.
    pub values: &'a [f64],
    /// Tool polylines (m), drawn as thick dark lines.
    pub tools: Vec<Vec<[f64; 2]>>,
}

/// Font family under which the embedded font is registered.
const FONT: &str = "sans-serif";
/// Font sizes in pixels.
const TITLE_FONT: f64 = 30.0;
const PANEL_TITLE_FONT: f64 = 24.0;
const DESC_FONT: f64 = 22.0;
const TICK_FONT: f64 = 18.0;
const LEGEND_FONT: f64 = 18.0;

/// Height of the strip holding the figure title.
const TITLE_H: u32 = 54;
/// Height of the strip holding a panel title in [`stages_plot`].
const PANEL_TITLE_H: u32 = 34;
/// Height of the area below a plot holding tick labels and the axis description.
const X_AREA: u32 = 68;
/// Length of tick marks.
const TICK_MARK: i32 = 6;
/// Margins around a chart's plotting area and label areas.
const MARGIN_TOP: u32 = 8;
const MARGIN_BOTTOM: u32 = 8;
const MARGIN_LEFT: u32 = 12;
const MARGIN_RIGHT: u32 = 32;

/// Size of a line plot.
const LINE_SIZE: (u32, u32) = (1000, 700);
/// Width of a shape plot with a single panel, and how much each further panel adds.
const SHAPE_WIDTH: u32 = 1000;
const STAGE_EXTRA_WIDTH: u32 = 330;
/// How far (relative to the workpiece size) tools may reach out of it and still be in view.
const TOOL_REACH: f64 = 0.15;
/// Largest number of panels in one stages figure, and per row.
const MAX_STAGES: usize = 30;
const MAX_COLUMNS: usize = 5;
/// Height the rows of a stages figure are fitted into (pixels).
const MAX_HEIGHT: u32 = 3000;
/// Smallest distance between tick marks on shape plots (pixels).
const MIN_TICK_SPACING: f64 = 80.0;
/// Bounds on the height of a shape's plotting area (pixels).
const MIN_PLOT_H: u32 = 240;
const MAX_PLOT_H: u32 = 1100;
/// Narrowest plotting area of a shape panel (pixels).
const MIN_PLOT_W: u32 = 160;
/// Colour bar geometry: gap to the plots, bar width, space right of the labels.
const CBAR_GAP: u32 = 28;
const CBAR_BAR: u32 = 26;
const CBAR_RIGHT: u32 = 14;
/// Radius of the dots drawn for nodes when there are no quads (pixels).
const NODE_DOT_RADIUS: i32 = 3;
/// Mean quad edge length (pixels) from which mesh lines are drawn.
const MIN_MESH_EDGE: f64 = 14.0;
/// Number of colour steps drawn in the colour bar.
const CBAR_STEPS: usize = 256;

/// Line colours (Tableau 10, distinguishable also in greyscale print by order).
const SERIES_COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];
const GRID: RGBColor = RGBColor(222, 222, 222);
const TOOL: RGBColor = RGBColor(25, 25, 25);
const NO_DATA: RGBColor = RGBColor(190, 190, 190);
/// Series with at most this many finite points get a dot at every point.
const MAX_DOTTED_POINTS: usize = 30;
/// Radius of those dots (pixels).
const DOT_RADIUS: i32 = 5;
/// Pixel offsets of the one-pixel lines that together draw a curve about 3 pixels wide.
const BRUSH: [(f64, f64); 5] = [(0.0, 0.0), (-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0)];
/// Shortest line segment drawn for dense curves (pixels).
const MIN_SEGMENT_PX: f64 = 2.0;

/// Viridis (matplotlib, CC0) sampled at 17 evenly spaced positions; interpolated linearly.
const VIRIDIS: [(u8, u8, u8); 17] = [
    (68, 1, 84),
    (72, 24, 106),
    (71, 45, 123),
    (66, 64, 134),
    (59, 82, 139),
    (51, 99, 141),
    (44, 114, 142),
    (38, 130, 142),
    (33, 145, 140),
    (31, 159, 136),
    (39, 173, 129),
    (61, 188, 116),
    (92, 200, 99),
    (129, 211, 77),
    (170, 220, 50),
    (213, 226, 26),
    (253, 231, 37),
];

/// Line plot of several series (legend, axis labels, title), 1000x700 PNG.
///
/// The legend goes into the corner where it covers the least data; if every placement would
/// cover data, head-room is added above the curves for it. `path` must end in `.png`.
///
/// # Errors
///
/// A series whose `x` and `y` lengths differ, a path not ending in `.png`, or a failure to
/// render or write the image.
pub fn line_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    markers: &[Marker],
) -> Result<(), String> {
    check_png_path(path)?;
    let plan = LinePlan::new(title, x_label, y_label, series, markers)?;
    let root = BitMapBackend::new(path, plan.size).into_drawing_area();
    plan.draw(&root)?;
    root.present().map_err(|e| write_err(path, e))
}

/// Deformed shape: quads filled with a colour map of the mean of their corner values, a colour
/// bar labelled `value_label`, equal aspect ratio (1 m in x = 1 m in y on screen), tool polylines
/// drawn as thick dark lines, coordinates multiplied by `scale` for the axes (e.g. 1e3 with
/// axis labels in mm). PNG about 1000 px wide, height following the aspect ratio (clamped to a sane range).
///
/// Non-finite corner values are left out of the mean; quads without any finite value are grey,
/// quads with a non-finite corner position are skipped. Without quads, nodes are drawn as
/// coloured dots. Tools are shown where they come near the workpiece. `path` must end in `.png`.
///
/// # Errors
///
/// `values` not matching `positions`, a quad index out of range, a non-finite or zero `scale`,
/// nothing finite to draw, a path not ending in `.png`, or a failure to render or write.
#[allow(clippy::too_many_arguments)]
pub fn shape_plot(
    path: &Path,
    title: &str,
    positions: &[[f64; 2]],
    quads: &[[u32; 4]],
    values: &[f64],
    value_label: &str,
    tools: &[Vec<[f64; 2]>],
    axis_labels: (&str, &str),
    scale: f64,
) -> Result<(), String> {
    let panel = Panel {
        title: "",
        positions,
        values,
        tools,
    };
    let labels = Labels {
        title,
        value: value_label,
        x: axis_labels.0,
        y: axis_labels.1,
    };
    render_shapes(path, &labels, quads, &[panel], scale)
}

/// Several deformed shapes side by side in one PNG (forging stages), sharing one colour scale.
///
/// All panels also share the same axes ranges, so sizes can be compared between stages; each
/// panel is drawn like [`shape_plot`] with the stage title above it. Up to 5 panels sit in a
/// row, more go into further rows; of more than 30 stages an evenly spaced selection of 30,
/// including the first and the last, is shown. The image is 1000 px wide for one stage and
/// grows with the number of panels per row. `path` must end in `.png`.
///
/// # Errors
///
/// No stages, any error [`shape_plot`] reports for one of the stages, or a failure to render or
/// write.
pub fn stages_plot(
    path: &Path,
    title: &str,
    quads: &[[u32; 4]],
    stages: &[Stage],
    value_label: &str,
    axis_labels: (&str, &str),
    scale: f64,
) -> Result<(), String> {
    let panels: Vec<Panel> = stages
        .iter()
        .map(|stage| Panel {
            title: &stage.title,
            positions: stage.positions,
            values: stage.values,
            tools: &stage.tools,
        })
        .collect();
    let labels = Labels {
        title,
        value: value_label,
        x: axis_labels.0,
        y: axis_labels.1,
    };
    render_shapes(path, &labels, quads, &panels, scale)
}

/// Registers the embedded font once; later calls report the outcome of the first.
fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        register_font(FONT, FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err("the embedded plot font could not be loaded".into())
    }
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

/// Rejects output paths whose extension would make the image encoder pick another format.
fn check_png_path(path: &Path) -> Result<(), String> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if is_png {
        Ok(())
    } else {
        Err(format!("plot file {} must end in .png", path.display()))
    }
}

/// Formats a drawing error.
fn draw_err(e: impl std::fmt::Display) -> String {
    format!("could not draw the plot: {e}")
}

/// Formats an error while writing the image file.
fn write_err(path: &Path, e: impl std::fmt::Display) -> String {
    format!("could not write {}: {e}", path.display())
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

/// A closed interval of finite numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Span {
    lo: f64,
    hi: f64,
}

impl Span {
    /// Smallest span holding every finite value, `None` if there is none.
    fn of(values: impl IntoIterator<Item = f64>) -> Option<Span> {
        values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold(None, |span, v| {
                Some(match span {
                    None => Span { lo: v, hi: v },
                    Some(s) => Span {
                        lo: s.lo.min(v),
                        hi: s.hi.max(v),
                    },
                })
            })
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

    fn centre(self) -> f64 {
        0.5 * self.lo + 0.5 * self.hi
    }

    /// Span of the given width around the same centre.
    fn with_width(self, width: f64) -> Span {
        let c = self.centre();
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
        let pad = fraction * self.width();
        Span {
            lo: self.lo - pad,
            hi: self.hi + pad,
        }
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
}

/// Tick positions of an axis and how to label them.
#[derive(Debug, Clone, PartialEq)]
struct Ticks {
    values: Vec<f64>,
    format: TickFormat,
}

/// Decimal places, and a power of ten shared by all labels (`None` for plain decimals).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TickFormat {
    decimals: usize,
    exponent: Option<i32>,
}

impl TickFormat {
    fn format(&self, v: f64) -> String {
        match self.exponent {
            Some(_) if v == 0.0 => "0".to_string(),
            Some(e) => format!("{:.*}e{e}", self.decimals, v / 10f64.powi(e)),
            None => format!("{:.*}", self.decimals, v),
        }
    }
}

/// Decimal places needed to show multiples of `step`.
fn decimals_for(step: f64) -> usize {
    (-step.log10() - 1e-9).ceil().clamp(0.0, 15.0) as usize
}

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw` (> 0).
fn nice_step(raw: f64) -> f64 {
    let base = 10f64.powf(raw.log10().floor());
    let mantissa = raw / base;
    let nice = [1.0, 2.0, 5.0]
        .into_iter()
        .find(|&m| mantissa <= m * (1.0 + 1e-9))
        .unwrap_or(10.0);
    nice * base
}

impl Ticks {
    /// Ticks at multiples of a nice step giving at most about `count` intervals.
    fn with_count(span: Span, count: u32) -> Ticks {
        Ticks::with_step(span, nice_step(span.width() / f64::from(count.max(1))))
    }

    /// Ticks at the multiples of `step` inside `span`.
    fn with_step(span: Span, step: f64) -> Ticks {
        let first = (span.lo / step).ceil();
        let last = (span.hi / step).floor();
        let count = last - first;
        let values: Vec<f64> = if step > 0.0 && step.is_finite() && (0.0..=200.0).contains(&count) {
            (0..=count as u32)
                .map(|k| (first + f64::from(k)) * step)
                .map(|v| if v.abs() < 1e-9 * step { 0.0 } else { v })
                .collect()
        } else {
            Vec::new()
        };
        let magnitude = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let format = if magnitude >= 1e5 || (magnitude > 0.0 && step < 1e-4) {
            let exponent = magnitude.log10().floor() as i32;
            TickFormat {
                decimals: decimals_for(step / 10f64.powi(exponent)),
                exponent: Some(exponent),
            }
        } else {
            TickFormat {
                decimals: decimals_for(step),
                exponent: None,
            }
        };
        Ticks { values, format }
    }

    fn label(&self, v: f64) -> String {
        self.format.format(v)
    }

    /// Width in pixels of the widest label.
    fn max_label_width(&self) -> u32 {
        self.values
            .iter()
            .map(|&v| text_width(TICK_FONT, &self.label(v)))
            .max()
            .unwrap_or(0)
    }
}

/// An `f64` axis whose tick marks and grid lines sit exactly at precomputed positions.
#[derive(Clone)]
struct TickedAxis {
    coord: RangedCoordf64,
    ticks: Vec<f64>,
}

impl TickedAxis {
    fn new(span: Span, ticks: &Ticks) -> TickedAxis {
        TickedAxis {
            coord: (span.lo..span.hi).into(),
            ticks: ticks.values.clone(),
        }
    }
}

impl Ranged for TickedAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.coord.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // Only bold grid lines and ticks; no light sub-grid.
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.coord.range()
    }
}

/// Width of a y label area: tick labels, tick marks and the rotated axis description.
fn y_area_width(ticks: &Ticks) -> u32 {
    ticks.max_label_width() + 14 + (1.3 * DESC_FONT) as u32 + 10
}

/// Splits a series into runs of consecutive points with finite coordinates.
fn finite_runs(x: &[f64], y: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut run = Vec::new();
    for (&x, &y) in x.iter().zip(y) {
        if x.is_finite() && y.is_finite() {
            run.push((x, y));
        } else if !run.is_empty() {
            runs.push(std::mem::take(&mut run));
        }
    }
    if !run.is_empty() {
        runs.push(run);
    }
    runs
}

/// Everything needed to draw a line plot, laid out before the image is created.
struct LinePlan<'a> {
    size: (u32, u32),
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: &'a [Series],
    runs: Vec<Vec<Vec<(f64, f64)>>>,
    markers: &'a [Marker],
    has_data: bool,
    x_span: Span,
    y_span: Span,
    x_ticks: Ticks,
    y_ticks: Ticks,
    y_area: u32,
    legend: Option<SeriesLabelPosition>,
}

/// Legend layout constants (pixels), matching plotters' legend drawing.
const LEGEND_SAMPLE: u32 = 44;
const LEGEND_MARGIN: u32 = 10;
const LEGEND_OFFSET: f64 = 5.0;
/// Resolution of the grid on which free space for the legend is looked for.
const OCCUPANCY_CELLS: usize = 100;
/// A marker counts like this many cells of curve when placing the legend.
const MARKER_WEIGHT: u32 = 20;
/// Largest fraction of the plot height given up as head-room for the legend.
const MAX_LEGEND_HEADROOM: f64 = 0.45;

impl<'a> LinePlan<'a> {
    fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: &'a [Series],
        markers: &'a [Marker],
    ) -> Result<Self, String> {
        ensure_font()?;
        if let Some(s) = series.iter().find(|s| s.x.len() != s.y.len()) {
            return Err(format!(
                "series '{}' has {} x values but {} y values",
                s.label,
                s.x.len(),
                s.y.len()
            ));
        }
        let runs: Vec<_> = series.iter().map(|s| finite_runs(&s.x, &s.y)).collect();
        let finite_markers = markers
            .iter()
            .filter(|m| m.x.is_finite() && m.y.is_finite())
            .map(|m| (m.x, m.y));
        let points: Vec<(f64, f64)> = runs
            .iter()
            .flatten()
            .flatten()
            .copied()
            .chain(finite_markers)
            .collect();
        let has_data = !points.is_empty();
        let unit = Span { lo: 0.0, hi: 1.0 };
        let x_span = Span::of(points.iter().map(|p| p.0))
            .unwrap_or(unit)
            .widened()
            .padded(0.03)
            .checked()?;
        let mut y_span = Span::of(points.iter().map(|p| p.1))
            .unwrap_or(unit)
            .widened()
            .padded(0.06)
            .checked()?;

        let size = LINE_SIZE;
        let plot_h = size.1 - TITLE_H - MARGIN_TOP - MARGIN_BOTTOM - X_AREA;
        let rough_plot_w = size.0 - MARGIN_LEFT - MARGIN_RIGHT - 100;

        let labels: Vec<&str> = series
            .iter()
            .map(|s| s.label.as_str())
            .chain(markers.iter().map(|m| m.label.as_str()))
            .filter(|l| !l.is_empty())
            .collect();
        let legend = match legend_size(&labels) {
            None => None,
            Some((w, h)) => {
                let box_frac = (
                    (f64::from(w) + LEGEND_OFFSET + 4.0) / f64::from(rough_plot_w),
                    (f64::from(h) + LEGEND_OFFSET + 4.0) / f64::from(plot_h),
                );
                let grid = occupancy(&runs, markers, x_span, y_span);
                let (position, covered) = best_legend_position(&grid, box_frac);
                // If every placement covers data, make head-room above it for the legend.
                let grown = Span {
                    lo: y_span.lo,
                    hi: y_span.lo + y_span.width() / (1.0 - box_frac.1 - 0.02),
                };
                match grown.checked() {
                    Ok(grown) if covered > 0 && box_frac.1 < MAX_LEGEND_HEADROOM => {
                        y_span = grown;
                        Some(SeriesLabelPosition::UpperRight)
                    }
                    _ => Some(position),
                }
            }
        };

        let y_ticks = Ticks::with_count(y_span, plot_h / 70);
        let y_area = y_area_width(&y_ticks);
        let plot_w = (size.0 - MARGIN_LEFT - MARGIN_RIGHT).saturating_sub(y_area);
        let x_ticks = Ticks::with_count(x_span, plot_w / 110);
        Ok(LinePlan {
            size,
            title,
            x_label,
            y_label,
            series,
            runs,
            markers,
            has_data,
            x_span,
            y_span,
            x_ticks,
            y_ticks,
            y_area,
            legend,
        })
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(draw_err)?;
        let (title_area, body) = root.split_vertically(TITLE_H);
        let centre = ((self.size.0 / 2) as i32, (TITLE_H / 2) as i32);
        centred_text(&title_area, self.title, TITLE_FONT, centre)?;

        let (x, y) = (self.x_span, self.y_span);
        let mut chart = ChartBuilder::on(&body)
            .margin_top(MARGIN_TOP)
            .margin_bottom(MARGIN_BOTTOM)
            .margin_left(MARGIN_LEFT)
            .margin_right(MARGIN_RIGHT)
            .x_label_area_size(X_AREA)
            .y_label_area_size(self.y_area)
            .build_cartesian_2d(
                TickedAxis::new(x, &self.x_ticks),
                TickedAxis::new(y, &self.y_ticks),
            )
            .map_err(draw_err)?;
        let x_fmt = |v: &f64| self.x_ticks.label(*v);
        let y_fmt = |v: &f64| self.y_ticks.label(*v);
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .label_style(font(TICK_FONT))
            .axis_desc_style(font(DESC_FONT))
            .bold_line_style(GRID)
            .axis_style(BLACK)
            .set_all_tick_mark_size(TICK_MARK)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .draw()
            .map_err(draw_err)?;

        let (plot_w, plot_h) = chart.plotting_area().dim_in_pixel();
        let pixel = (
            x.width() / f64::from(plot_w.max(1)),
            y.width() / f64::from(plot_h.max(1)),
        );
        for (i, (series, runs)) in self.series.iter().zip(&self.runs).enumerate() {
            let colour = SERIES_COLOURS[i % SERIES_COLOURS.len()];
            let style = colour.stroke_width(3);
            let dotted = runs.iter().map(Vec::len).sum::<usize>() <= MAX_DOTTED_POINTS;
            let anno = chart
                .draw_series(LineSeries::new(std::iter::empty(), style))
                .map_err(draw_err)?;
            if !series.label.is_empty() {
                let dot = if dotted { DOT_RADIUS } else { 0 };
                anno.label(series.label.as_str()).legend(move |at| {
                    EmptyElement::at(at)
                        + PathElement::new(vec![(0, 0), (34, 0)], style)
                        + Circle::new((17, 0), dot, style.filled())
                });
            }
            for run in runs {
                let line = thinned(run, pixel, MIN_SEGMENT_PX);
                // A brush of one-pixel lines gives cleaner thick curves than plotters' wide
                // strokes, which sprout spurs at the joints of short segments.
                for (bx, by) in BRUSH {
                    let shifted = line
                        .iter()
                        .map(|p| (p.0 + bx * pixel.0, p.1 + by * pixel.1));
                    chart
                        .draw_series(LineSeries::new(shifted, colour.stroke_width(1)))
                        .map_err(draw_err)?;
                }
                if dotted || run.len() == 1 {
                    let dots = run
                        .iter()
                        .map(|&p| Circle::new(p, DOT_RADIUS, style.filled()));
                    chart.draw_series(dots).map_err(draw_err)?;
                }
            }
        }

        for (kind, marker) in self.markers.iter().enumerate() {
            let finite = marker.x.is_finite() && marker.y.is_finite();
            let symbol = finite.then(|| {
                EmptyElement::at((marker.x, marker.y))
                    + Polygon::new(marker_vertices(kind), BLACK.filled())
            });
            let anno = chart.draw_series(symbol).map_err(draw_err)?;
            if !marker.label.is_empty() {
                anno.label(marker.label.as_str()).legend(move |(px, py)| {
                    EmptyElement::at((px + 17, py))
                        + Polygon::new(marker_vertices(kind), BLACK.filled())
                });
            }
        }

        draw_frame(&chart, x, y)?;
        if !self.has_data {
            let (w, h) = chart.plotting_area().dim_in_pixel();
            let area = chart.plotting_area().strip_coord_spec();
            let centre = ((w / 2) as i32, (h / 2) as i32);
            centred_text(&area, "no finite data", DESC_FONT, centre)?;
        }
        if let Some(position) = &self.legend {
            chart
                .configure_series_labels()
                .position(position.clone())
                .margin(LEGEND_MARGIN)
                .legend_area_size(LEGEND_SAMPLE)
                .label_font(font(LEGEND_FONT))
                .background_style(WHITE.mix(0.9))
                .border_style(RGBColor(150, 150, 150))
                .draw()
                .map_err(draw_err)?;
        }
        Ok(())
    }
}

/// Drops points closer than `min_step` to the previously kept one, distances measured in units
/// of `unit` (data units per x and y unit); the last point is always kept. Dense curves are
/// thinned this way to a few pixels per segment before drawing.
fn thinned(run: &[(f64, f64)], unit: (f64, f64), min_step: f64) -> Vec<(f64, f64)> {
    let mut kept: Vec<(f64, f64)> = Vec::with_capacity(run.len());
    for (i, &p) in run.iter().enumerate() {
        let far = kept.last().is_none_or(|q| {
            let d = ((p.0 - q.0) / unit.0).hypot((p.1 - q.1) / unit.1);
            d >= min_step
        });
        if far || i + 1 == run.len() {
            kept.push(p);
        }
    }
    kept
}

/// Pixel size of the legend box plotters draws for these labels, `None` without labels.
fn legend_size(labels: &[&str]) -> Option<(u32, u32)> {
    if labels.is_empty() {
        return None;
    }
    let style = font(LEGEND_FONT);
    let mut text = MultiLineText::<(i32, i32), &str>::new((0, 0), &style);
    for label in labels {
        text.push_line(*label);
    }
    let (w, h) = text.estimate_dimension().unwrap_or((
        labels
            .iter()
            .map(|l| text_width(LEGEND_FONT, l) as i32)
            .max()
            .unwrap_or(0),
        (1.25 * LEGEND_FONT) as i32 * labels.len() as i32,
    ));
    let w = w.max(0) as u32 + LEGEND_SAMPLE + 2 * LEGEND_MARGIN;
    let h = h.max(0) as u32 + 2 * LEGEND_MARGIN;
    Some((w, h))
}

/// How much data lies in each cell of an [`OCCUPANCY_CELLS`]-square grid over the plotting
/// area (row-major, row 0 at the bottom), to find free space for the legend.
fn occupancy(runs: &[Vec<Vec<(f64, f64)>>], markers: &[Marker], x: Span, y: Span) -> Vec<u32> {
    let n = OCCUPANCY_CELLS;
    let cells = n as f64;
    let mut grid = vec![0u32; n * n];
    let mut mark = |(u, v): (f64, f64), weight: u32| {
        if (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
            let i = ((u * cells) as usize).min(n - 1);
            let j = ((v * cells) as usize).min(n - 1);
            grid[j * n + i] = grid[j * n + i].saturating_add(weight);
        }
    };
    let to_frac = |p: (f64, f64)| (x.fraction(p.0), y.fraction(p.1));
    let cell = (x.width() / cells, y.width() / cells);
    for run in runs.iter().flatten() {
        let run = thinned(run, cell, 1.0);
        if let Some(&first) = run.first() {
            mark(to_frac(first), 1);
        }
        for pair in run.windows(2) {
            let (a, b) = (to_frac(pair[0]), to_frac(pair[1]));
            let reach = (b.0 - a.0).abs().max((b.1 - a.1).abs());
            let steps = (2.0 * reach * cells).ceil().clamp(1.0, 4.0 * cells) as u32;
            for k in 1..=steps {
                let t = f64::from(k) / f64::from(steps);
                mark((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), 1);
            }
        }
    }
    for m in markers {
        if m.x.is_finite() && m.y.is_finite() {
            mark(to_frac((m.x, m.y)), MARKER_WEIGHT);
        }
    }
    grid
}

/// The legend position covering the least data in `grid` (see [`occupancy`]; earlier
/// candidates win ties) and how much it covers. `size` is the legend box as fractions of the
/// plotting area.
fn best_legend_position(grid: &[u32], size: (f64, f64)) -> (SeriesLabelPosition, u64) {
    use SeriesLabelPosition as P;
    let n = OCCUPANCY_CELLS;
    let (w, h) = size;
    let left = (0.0, w);
    let centre = (0.5 - 0.5 * w, 0.5 + 0.5 * w);
    let right = (1.0 - w, 1.0);
    let bottom = (0.0, h);
    let middle = (0.5 - 0.5 * h, 0.5 + 0.5 * h);
    let top = (1.0 - h, 1.0);
    let candidates = [
        (P::UpperRight, right, top),
        (P::UpperLeft, left, top),
        (P::LowerRight, right, bottom),
        (P::LowerLeft, left, bottom),
        (P::UpperMiddle, centre, top),
        (P::LowerMiddle, centre, bottom),
        (P::MiddleRight, right, middle),
        (P::MiddleLeft, left, middle),
    ];
    // Cells whose range of fractions overlaps [lo, hi].
    let cells = |(lo, hi): (f64, f64)| {
        let first = (lo * n as f64).floor().clamp(0.0, n as f64) as usize;
        let last = (hi * n as f64).ceil().clamp(0.0, n as f64) as usize;
        first..last
    };
    let mut best = (P::UpperRight, u64::MAX);
    for (position, us, vs) in candidates {
        let covered: u64 = cells(vs)
            .flat_map(|j| cells(us).map(move |i| u64::from(grid[j * n + i])))
            .sum();
        if covered < best.1 {
            best = (position, covered);
        }
    }
    best
}

/// Outline, relative to its centre in pixels, of marker symbol number `kind`: diamond,
/// triangle, square or inverted triangle.
fn marker_vertices(kind: usize) -> Vec<(i32, i32)> {
    match kind % 4 {
        0 => vec![(0, -9), (9, 0), (0, 9), (-9, 0)],
        1 => vec![(0, -9), (8, 6), (-8, 6)],
        2 => vec![(-7, -7), (7, -7), (7, 7), (-7, 7)],
        _ => vec![(0, 9), (8, -6), (-8, -6)],
    }
}

/// Draws a thin black frame around the plotting area.
fn draw_frame<DB: DrawingBackend, X, Y>(
    chart: &ChartContext<DB, Cartesian2d<X, Y>>,
    x: Span,
    y: Span,
) -> Result<(), String>
where
    X: plotters::coord::ranged1d::Ranged<ValueType = f64>,
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64>,
{
    let corners = vec![
        (x.lo, y.lo),
        (x.hi, y.lo),
        (x.hi, y.hi),
        (x.lo, y.hi),
        (x.lo, y.lo),
    ];
    chart
        .plotting_area()
        .draw(&PathElement::new(corners, BLACK.stroke_width(1)))
        .map_err(draw_err)
}

/// Maps `t` in [0, 1] to viridis; values outside are clamped.
fn viridis(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (f64::from(p) + f * (f64::from(q) - f64::from(p))).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Texts of a shape figure.
struct Labels<'a> {
    title: &'a str,
    value: &'a str,
    x: &'a str,
    y: &'a str,
}

/// Input of one shape panel.
struct Panel<'a> {
    title: &'a str,
    positions: &'a [[f64; 2]],
    values: &'a [f64],
    tools: &'a [Vec<[f64; 2]>],
}

/// A quad ready to draw: corner positions in plot units and the mean of its finite corner
/// values (`None` if there is none).
struct FilledQuad {
    corners: [(f64, f64); 4],
    value: Option<f64>,
}

impl FilledQuad {
    /// The outline as a closed polyline.
    fn outline(&self) -> Vec<(f64, f64)> {
        let c = self.corners;
        vec![c[0], c[1], c[2], c[3], c[0]]
    }

    /// Mean length of the four edges.
    fn mean_edge(&self) -> f64 {
        let c = self.corners;
        (0..4)
            .map(|k| {
                let (a, b) = (c[k], c[(k + 1) % 4]);
                (b.0 - a.0).hypot(b.1 - a.1)
            })
            .sum::<f64>()
            / 4.0
    }
}

/// A panel's geometry in plot units (positions times scale), non-finite points removed.
struct PanelGeometry {
    /// Every quad whose corners all have finite positions.
    quads: Vec<FilledQuad>,
    /// Nodes with their values, drawn as dots when there are no quads.
    nodes: Vec<((f64, f64), f64)>,
    /// Tool polylines, split where a point is not finite.
    tools: Vec<Vec<(f64, f64)>>,
}

impl PanelGeometry {
    fn new(panel: &Panel, quads: &[[u32; 4]], scale: f64) -> PanelGeometry {
        let point = |p: &[f64; 2]| {
            let q = (p[0] * scale, p[1] * scale);
            (q.0.is_finite() && q.1.is_finite()).then_some(q)
        };
        let points: Vec<Option<(f64, f64)>> = panel.positions.iter().map(point).collect();
        let quads = quads
            .iter()
            .filter_map(|quad| {
                let corner = |k: usize| points.get(quad[k] as usize).copied().flatten();
                let corners = [corner(0)?, corner(1)?, corner(2)?, corner(3)?];
                let finite: Vec<f64> = quad
                    .iter()
                    .filter_map(|&i| panel.values.get(i as usize).copied())
                    .filter(|v| v.is_finite())
                    .collect();
                let count = finite.len() as f64;
                let value = (!finite.is_empty())
                    .then(|| finite.iter().map(|v| v / count).sum::<f64>())
                    .filter(|m| m.is_finite());
                Some(FilledQuad { corners, value })
            })
            .collect();
        let nodes = points
            .iter()
            .zip(panel.values)
            .filter_map(|(p, &v)| p.map(|p| (p, v)))
            .collect();
        let mut tools = Vec::new();
        for polyline in panel.tools {
            let mut run = Vec::new();
            for p in polyline {
                match point(p) {
                    Some(q) => run.push(q),
                    None if run.is_empty() => {}
                    None => tools.push(std::mem::take(&mut run)),
                }
            }
            if !run.is_empty() {
                tools.push(run);
            }
        }
        PanelGeometry {
            quads,
            nodes,
            tools,
        }
    }
}

/// Checks one panel's arrays against each other and the shared quads.
fn check_panel(
    stage: usize,
    panel: &Panel,
    quads: &[[u32; 4]],
    panels: usize,
) -> Result<(), String> {
    let which = if panels > 1 {
        format!("stage {} ('{}'): ", stage + 1, panel.title)
    } else {
        String::new()
    };
    let n = panel.positions.len();
    if panel.values.len() != n {
        return Err(format!(
            "{which}{} values given for {n} node positions",
            panel.values.len()
        ));
    }
    for (q, quad) in quads.iter().enumerate() {
        if let Some(&bad) = quad.iter().find(|&&i| i as usize >= n) {
            return Err(format!(
                "{which}quad {q} references node {bad} but there are only {n} nodes"
            ));
        }
    }
    Ok(())
}

/// The view box of all panels: workpiece nodes plus the tool parts near them, padded, with a
/// non-zero size in both directions.
fn view_box(geometries: &[PanelGeometry]) -> Result<(Span, Span), String> {
    let nodes = || geometries.iter().flat_map(|s| s.nodes.iter().map(|n| n.0));
    let tool_points = || {
        geometries
            .iter()
            .flat_map(|s| s.tools.iter().flatten().copied())
    };
    let work = Span::of(nodes().map(|p| p.0)).zip(Span::of(nodes().map(|p| p.1)));
    let (x, y) = match work {
        Some((x, y)) => {
            // Tools count only where they come near the workpiece, so that long dies do not
            // shrink it; what lies beyond is clipped away when drawing.
            let reach = TOOL_REACH * x.width().max(y.width());
            let near_x = x.with_width(x.width() + 2.0 * reach);
            let near_y = y.with_width(y.width() + 2.0 * reach);
            let near: Vec<(f64, f64)> = geometries
                .iter()
                .flat_map(|s| &s.tools)
                .flat_map(|polyline| clip_polyline(polyline, near_x, near_y))
                .flatten()
                .collect();
            let near_tools_x = Span::of(near.iter().map(|p| p.0));
            let near_tools_y = Span::of(near.iter().map(|p| p.1));
            (
                near_tools_x.map_or(x, |t| t.union(x)),
                near_tools_y.map_or(y, |t| t.union(y)),
            )
        }
        None => Span::of(tool_points().map(|p| p.0))
            .zip(Span::of(tool_points().map(|p| p.1)))
            .ok_or("nothing to plot: no finite node positions or tool points")?,
    };
    let (flat_x, flat_y) = (x.widened() != x, y.widened() != y);
    let (x, y) = match (flat_x, flat_y) {
        (false, false) => (x, y),
        (false, true) => (x, y.with_width(x.width())),
        (true, false) => (x.with_width(y.width()), y),
        (true, true) => {
            let side = x.widened().width().max(y.widened().width());
            (x.with_width(side), y.with_width(side))
        }
    };
    let pad = 0.05 * x.width().max(y.width());
    let x = x.with_width(x.width() + 2.0 * pad).checked()?;
    let y = y.with_width(y.width() + 2.0 * pad).checked()?;
    Ok((x, y))
}

/// Pixel layout of a shape figure with equal aspect ratio. Panels fill a grid row by row and
/// share the axes ranges; the first panel of each row carries the y tick labels and description.
struct ShapeLayout {
    size: (u32, u32),
    columns: usize,
    plot_w: u32,
    row_h: u32,
    panel_title_h: u32,
    y_area: u32,
    cbar_label_area: u32,
    x_span: Span,
    y_span: Span,
    ticks_x: Ticks,
    ticks_y: Ticks,
}

impl ShapeLayout {
    /// Lays out `panels` panels of the `view` box; `y_area` is the width of the y label area.
    fn new(
        view: (Span, Span),
        panels: usize,
        y_area: u32,
        cbar_label_area: u32,
        titled: bool,
    ) -> Result<Self, String> {
        let rows = panels.div_ceil(MAX_COLUMNS).max(1);
        let columns = panels.div_ceil(rows).max(1);
        let (rows_u, columns_u) = (rows as u32, columns as u32);
        let cbar_w = CBAR_GAP + CBAR_BAR + cbar_label_area + CBAR_RIGHT;
        let fixed = y_area + cbar_w + columns_u * (MARGIN_LEFT + MARGIN_RIGHT);
        let wanted = SHAPE_WIDTH + STAGE_EXTRA_WIDTH * (columns_u - 1);
        let width = wanted.max(fixed + columns_u * MIN_PLOT_W);
        let plot_w = (width - fixed) / columns_u;

        let panel_title_h = if titled { PANEL_TITLE_H } else { 0 };
        let row_overhead = panel_title_h + MARGIN_TOP + X_AREA + MARGIN_BOTTOM;
        let max_plot_h = ((MAX_HEIGHT - TITLE_H) / rows_u)
            .saturating_sub(row_overhead)
            .clamp(MIN_PLOT_H, MAX_PLOT_H);
        let (x, y) = view;
        let natural_h = f64::from(plot_w) * y.width() / x.width();
        let plot_h = natural_h
            .clamp(f64::from(MIN_PLOT_H), f64::from(max_plot_h))
            .round() as u32;
        // Units per pixel; the other direction is widened so both scales agree.
        let unit = (x.width() / f64::from(plot_w)).max(y.width() / f64::from(plot_h));
        let x_span = x.with_width(unit * f64::from(plot_w)).checked()?;
        let y_span = y.with_width(unit * f64::from(plot_h)).checked()?;
        let step = nice_step(unit * MIN_TICK_SPACING);
        let row_h = row_overhead + plot_h;
        Ok(ShapeLayout {
            size: (width, TITLE_H + rows_u * row_h),
            columns,
            plot_w,
            row_h,
            panel_title_h,
            y_area,
            cbar_label_area,
            x_span,
            y_span,
            ticks_x: Ticks::with_step(x_span, step),
            ticks_y: Ticks::with_step(y_span, step),
        })
    }

    /// Width of the y label area of panels in grid column `column`.
    fn y_area_of(&self, column: usize) -> u32 {
        if column == 0 {
            self.y_area
        } else {
            0
        }
    }

    /// Total width of the panels in grid column `column`.
    fn column_width(&self, column: usize) -> u32 {
        MARGIN_LEFT + self.y_area_of(column) + self.plot_w + MARGIN_RIGHT
    }
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

/// Shared implementation of [`shape_plot`] and [`stages_plot`].
fn render_shapes(
    path: &Path,
    labels: &Labels,
    quads: &[[u32; 4]],
    panels: &[Panel],
    scale: f64,
) -> Result<(), String> {
    let plan = ShapePlan::new(labels, quads, panels, scale)?;
    check_png_path(path)?;
    let root = BitMapBackend::new(path, plan.layout.size).into_drawing_area();
    plan.draw(&root)?;
    root.present().map_err(|e| write_err(path, e))
}

/// Everything needed to draw a shape figure, laid out before the image is created.
struct ShapePlan<'a> {
    labels: &'a Labels<'a>,
    titles: Vec<&'a str>,
    geometries: Vec<PanelGeometry>,
    colours: Option<(Span, Ticks)>,
    layout: ShapeLayout,
}

impl<'a> ShapePlan<'a> {
    fn new(
        labels: &'a Labels<'a>,
        quads: &[[u32; 4]],
        panels: &[Panel<'a>],
        scale: f64,
    ) -> Result<Self, String> {
        ensure_font()?;
        if panels.is_empty() {
            return Err("no stages to plot".into());
        }
        if !scale.is_finite() || scale == 0.0 {
            return Err(format!(
                "coordinate scale must be finite and non-zero, got {scale}"
            ));
        }
        for (k, panel) in panels.iter().enumerate() {
            check_panel(k, panel, quads, panels.len())?;
        }
        let panels = evenly_spaced(panels, MAX_STAGES);
        let geometries: Vec<PanelGeometry> = panels
            .iter()
            .map(|p| PanelGeometry::new(p, quads, scale))
            .collect();
        let view = view_box(&geometries)?;

        let colours = match Span::of(panels.iter().flat_map(|p| p.values.iter().copied())) {
            Some(span) => {
                let span = span.widened().checked()?;
                Some((span, Ticks::with_count(span, 6)))
            }
            None => None,
        };
        let cbar_label_area = colours.as_ref().map_or(0, |(_, t)| t.max_label_width())
            + 14
            + (1.3 * DESC_FONT) as u32
            + 6;
        let titled = panels.iter().any(|p| !p.title.is_empty());
        let count = panels.len();
        let mut layout = ShapeLayout::new(view, count, 90, cbar_label_area, titled)?;
        let y_area = y_area_width(&layout.ticks_y);
        if y_area != layout.y_area {
            layout = ShapeLayout::new(view, count, y_area, cbar_label_area, titled)?;
        }
        Ok(ShapePlan {
            labels,
            titles: panels.iter().map(|p| p.title).collect(),
            geometries,
            colours,
            layout,
        })
    }

    fn colour(&self, value: Option<f64>) -> RGBColor {
        match (value, &self.colours) {
            (Some(v), Some((span, _))) => viridis(span.fraction(v)),
            _ => NO_DATA,
        }
    }

    /// Draws the figure; returns the pixel size of every panel's plotting area.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<Vec<(u32, u32)>, String> {
        let layout = &self.layout;
        root.fill(&WHITE).map_err(draw_err)?;
        let (title_area, body) = root.split_vertically(TITLE_H);
        let centre = ((layout.size.0 / 2) as i32, (TITLE_H / 2) as i32);
        centred_text(&title_area, self.labels.title, TITLE_FONT, centre)?;

        let columns = layout.columns;
        let grid_w: u32 = (0..columns).map(|c| layout.column_width(c)).sum();
        let (grid, colour_bar) = body.split_horizontally(grid_w);
        let x_breaks: Vec<i32> = (0..columns - 1)
            .scan(0, |right, c| {
                *right += layout.column_width(c);
                Some(*right as i32)
            })
            .collect();
        let rows = self.geometries.len().div_ceil(columns);
        let y_breaks: Vec<i32> = (1..rows)
            .map(|r| (r as u32 * layout.row_h) as i32)
            .collect();
        let cells = grid.split_by_breakpoints(x_breaks, y_breaks);
        let mut plot_sizes = Vec::with_capacity(self.geometries.len());
        for (k, (geometry, title)) in self.geometries.iter().zip(&self.titles).enumerate() {
            let Some(cell) = cells.get(k) else { break };
            let y_area = layout.y_area_of(k % columns);
            let (strip, chart_area) = cell.split_vertically(layout.panel_title_h);
            if layout.panel_title_h > 0 {
                let x = MARGIN_LEFT + y_area + layout.plot_w / 2;
                let centre = (x as i32, (layout.panel_title_h / 2) as i32);
                centred_text(&strip, title, PANEL_TITLE_FONT, centre)?;
            }
            plot_sizes.push(self.draw_panel(&chart_area, geometry, y_area)?);
        }
        self.draw_colour_bar(&colour_bar)?;
        Ok(plot_sizes)
    }

    /// Draws one panel; returns the pixel size of its plotting area.
    fn draw_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        geometry: &PanelGeometry,
        y_area: u32,
    ) -> Result<(u32, u32), String> {
        let layout = &self.layout;
        let (x, y) = (layout.x_span, layout.y_span);
        let mut chart = ChartBuilder::on(area)
            .margin_top(MARGIN_TOP)
            .margin_bottom(MARGIN_BOTTOM)
            .margin_left(MARGIN_LEFT)
            .margin_right(MARGIN_RIGHT)
            .x_label_area_size(X_AREA)
            .y_label_area_size(y_area)
            .build_cartesian_2d(
                TickedAxis::new(x, &layout.ticks_x),
                TickedAxis::new(y, &layout.ticks_y),
            )
            .map_err(draw_err)?;
        let x_fmt = |v: &f64| layout.ticks_x.label(*v);
        let y_fmt = |v: &f64| layout.ticks_y.label(*v);
        chart
            .configure_mesh()
            .x_desc(self.labels.x)
            .y_desc(self.labels.y)
            .label_style(font(TICK_FONT))
            .axis_desc_style(font(DESC_FONT))
            .bold_line_style(GRID)
            .axis_style(BLACK)
            .set_all_tick_mark_size(TICK_MARK)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .draw()
            .map_err(draw_err)?;

        let unit = x.width() / f64::from(layout.plot_w);
        let fills = geometry
            .quads
            .iter()
            .map(|quad| Polygon::new(quad.corners.to_vec(), self.colour(quad.value).filled()));
        chart.draw_series(fills).map_err(draw_err)?;
        // Outline every quad in its own colour to close raster gaps between neighbours, then,
        // where quads are large enough for the mesh distortion to be readable, as a faint grid.
        let outlines = geometry
            .quads
            .iter()
            .map(|quad| PathElement::new(quad.outline(), self.colour(quad.value).stroke_width(1)));
        chart.draw_series(outlines).map_err(draw_err)?;
        let edges: f64 = geometry.quads.iter().map(FilledQuad::mean_edge).sum();
        let mean_edge_px = edges / geometry.quads.len().max(1) as f64 / unit;
        if mean_edge_px >= MIN_MESH_EDGE {
            let grid = geometry
                .quads
                .iter()
                .map(|quad| PathElement::new(quad.outline(), BLACK.mix(0.35).stroke_width(1)));
            chart.draw_series(grid).map_err(draw_err)?;
        }
        if geometry.quads.is_empty() {
            let dots = geometry.nodes.iter().map(|&(p, v)| {
                let value = v.is_finite().then_some(v);
                Circle::new(p, NODE_DOT_RADIUS, self.colour(value).filled())
            });
            chart.draw_series(dots).map_err(draw_err)?;
        }
        let tools = geometry
            .tools
            .iter()
            .flat_map(|polyline| clip_polyline(polyline, x, y))
            .map(|polyline| PathElement::new(polyline, TOOL.stroke_width(4)));
        chart.draw_series(tools).map_err(draw_err)?;
        draw_frame(&chart, x, y)?;
        Ok(chart.plotting_area().dim_in_pixel())
    }

    /// Draws the colour bar, spanning the plots from the first row's top to the last row's
    /// bottom.
    fn draw_colour_bar<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), String> {
        let top = MARGIN_TOP + self.layout.panel_title_h;
        let (span, ticks, label) = match &self.colours {
            Some((span, ticks)) => (*span, ticks.clone(), self.labels.value.to_string()),
            None => (
                Span { lo: 0.0, hi: 1.0 },
                Ticks::with_step(Span { lo: 0.0, hi: 1.0 }, 2.0),
                format!("{} (no finite values)", self.labels.value),
            ),
        };
        let mut chart = ChartBuilder::on(area)
            .margin_top(top)
            .margin_bottom(X_AREA + MARGIN_BOTTOM)
            .margin_left(CBAR_GAP)
            .margin_right(CBAR_RIGHT)
            .set_label_area_size(LabelAreaPosition::Right, self.layout.cbar_label_area)
            .build_cartesian_2d(0f64..1f64, span.lo..span.hi)
            .map_err(draw_err)?
            .set_secondary_coord(0f64..1f64, TickedAxis::new(span, &ticks));
        let steps = (0..CBAR_STEPS).map(|k| {
            let a = span.lo + span.width() * k as f64 / CBAR_STEPS as f64;
            let b = span.lo + span.width() * (k + 1) as f64 / CBAR_STEPS as f64;
            let colour = if self.colours.is_some() {
                viridis((k as f64 + 0.5) / CBAR_STEPS as f64)
            } else {
                NO_DATA
            };
            Rectangle::new([(0.0, a), (1.0, b)], colour.filled())
        });
        chart.draw_series(steps).map_err(draw_err)?;
        let frame = vec![
            (0.0, span.lo),
            (1.0, span.lo),
            (1.0, span.hi),
            (0.0, span.hi),
            (0.0, span.lo),
        ];
        chart
            .plotting_area()
            .draw(&PathElement::new(frame, BLACK.stroke_width(1)))
            .map_err(draw_err)?;
        let fmt = |v: &f64| ticks.label(*v);
        chart
            .configure_secondary_axes()
            .y_desc(label)
            .label_style(font(TICK_FONT))
            .axis_desc_style(font(DESC_FONT))
            .axis_style(BLACK)
            .set_all_tick_mark_size(TICK_MARK)
            .y_label_formatter(&fmt)
            .draw()
            .map_err(draw_err)
    }
}

/// Clips the segment a-b to the box (Liang-Barsky); `None` if it lies outside.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    x: Span,
    y: Span,
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    if !dx.is_finite() || !dy.is_finite() {
        return None;
    }
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x.lo),
        (dx, x.hi - a.0),
        (-dy, a.1 - y.lo),
        (dy, y.hi - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// The parts of a polyline inside the box, as separate polylines.
fn clip_polyline(points: &[(f64, f64)], x: Span, y: Span) -> Vec<Vec<(f64, f64)>> {
    let mut parts: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for pair in points.windows(2) {
        match clip_segment(pair[0], pair[1], x, y) {
            Some((c, d)) => {
                if current.last() != Some(&c) && !current.is_empty() {
                    parts.push(std::mem::take(&mut current));
                }
                if current.is_empty() {
                    current.push(c);
                }
                current.push(d);
            }
            None => {
                if !current.is_empty() {
                    parts.push(std::mem::take(&mut current));
                }
            }
        }
    }
    if !current.is_empty() {
        parts.push(current);
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A fresh directory for one test's images.
    fn temp_dir(test: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rkforge_plots_{}_{test}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        dir
    }

    /// Checks the PNG signature and returns width and height from the IHDR chunk.
    fn png_size(path: &Path) -> (u32, u32) {
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
    fn render(size: (u32, u32), draw: impl FnOnce(&DrawingArea<BitMapBackend, Shift>)) -> Vec<u8> {
        let mut pixels = vec![0u8; 3 * size.0 as usize * size.1 as usize];
        {
            let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
            draw(&root);
            root.present().expect("present to buffer");
        }
        pixels
    }

    /// Number of dark pixels in the rows `rows` of an RGB image `width` pixels wide.
    fn dark_pixels(pixels: &[u8], width: u32, rows: Range<u32>) -> usize {
        let row_bytes = 3 * width as usize;
        pixels[rows.start as usize * row_bytes..rows.end as usize * row_bytes]
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c < 100))
            .count()
    }

    /// A billet of `nx` x `ny` quads, bulged at mid-height, with a strain-like field.
    fn billet(nx: u32, ny: u32, bulge: f64) -> (Vec<[f64; 2]>, Vec<[u32; 4]>, Vec<f64>) {
        let (mut positions, mut values, mut quads) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..=ny {
            for i in 0..=nx {
                let (r, s) = (f64::from(i) / f64::from(nx), f64::from(j) / f64::from(ny));
                let b = 1.0 + bulge * (std::f64::consts::PI * s).sin();
                positions.push([0.01 * r * b, 0.015 * s]);
                values.push(bulge * (1.0 - (2.0 * s - 1.0).powi(2)) * (1.0 - 0.5 * r));
            }
        }
        for j in 0..ny {
            for i in 0..nx {
                let a = j * (nx + 1) + i;
                quads.push([a, a + 1, a + nx + 2, a + nx + 1]);
            }
        }
        (positions, quads, values)
    }

    fn dies() -> Vec<Vec<[f64; 2]>> {
        vec![
            vec![[-0.002, 0.015], [0.02, 0.015]],
            vec![[-0.002, 0.0], [0.02, 0.0]],
        ]
    }

    fn series(label: &str, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series {
            label: label.into(),
            x,
            y,
        }
    }

    #[test]
    fn line_plot_writes_png() {
        let path = temp_dir("line").join("force.png");
        let x: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.01).collect();
        let y: Vec<f64> = x.iter().map(|s| 120.0 * s.powf(0.8)).collect();
        let coarse: Vec<f64> = (0..10).map(|i| f64::from(i) * 0.2).collect();
        let coarse_y: Vec<f64> = coarse.iter().map(|s| 110.0 * s.powf(0.8)).collect();
        let markers = [Marker {
            label: "Published value".into(),
            x: 1.5,
            y: 165.0,
        }];
        line_plot(
            &path,
            "Punch force",
            "Stroke [mm]",
            "Force [kN]",
            &[series("RKPM", x, y), series("Coarse", coarse, coarse_y)],
            &markers,
        )
        .expect("line plot");
        assert_eq!(png_size(&path), LINE_SIZE);
    }

    #[test]
    fn line_plot_text_is_drawn_with_embedded_font() {
        let s = [series("a", vec![0.0, 1.0], vec![0.0, 1.0])];
        let plan = LinePlan::new("Title text", "x", "y", &s, &[]).expect("plan");
        let pixels = render(plan.size, |root| plan.draw(root).expect("draw"));
        assert!(
            dark_pixels(&pixels, plan.size.0, 0..TITLE_H) > 100,
            "title drawn"
        );
        let no_title = LinePlan::new("", "x", "y", &s, &[]).expect("plan");
        let pixels = render(no_title.size, |root| no_title.draw(root).expect("draw"));
        assert_eq!(dark_pixels(&pixels, plan.size.0, 0..TITLE_H), 0);
    }

    #[test]
    fn line_plot_degenerate_inputs_do_not_panic() {
        let dir = temp_dir("line_degenerate");
        let nan = f64::NAN;
        let inf = f64::INFINITY;
        let cases: Vec<(&str, Vec<Series>, Vec<Marker>)> = vec![
            ("nothing", vec![], vec![]),
            ("empty series", vec![series("e", vec![], vec![])], vec![]),
            (
                "all nan",
                vec![series("n", vec![nan, nan], vec![nan, 1.0])],
                vec![],
            ),
            (
                "infinities",
                vec![series("i", vec![0.0, inf, 2.0], vec![-inf, 1.0, 2.0])],
                vec![],
            ),
            (
                "all equal",
                vec![series("c", vec![1.0; 5], vec![3.0; 5])],
                vec![],
            ),
            (
                "single point",
                vec![series("p", vec![2.0], vec![0.0])],
                vec![],
            ),
            (
                "zeros",
                vec![series("", vec![0.0; 3], vec![0.0; 3])],
                vec![],
            ),
            (
                "tiny",
                vec![series("t", vec![0.0, 1e-300], vec![1e-310, 2e-310])],
                vec![],
            ),
            (
                "huge",
                vec![series("h", vec![-1e308, 1e308], vec![1e308, -1e308])],
                vec![],
            ),
            (
                "marker only",
                vec![],
                vec![Marker {
                    label: "m".into(),
                    x: 1.0,
                    y: 2.0,
                }],
            ),
            (
                "nan marker",
                vec![],
                vec![Marker {
                    label: "m".into(),
                    x: nan,
                    y: 2.0,
                }],
            ),
            (
                "many labels",
                (0..40)
                    .map(|k| series(&format!("series {k}"), vec![0.0, 1.0], vec![0.0, 1.0]))
                    .collect(),
                vec![],
            ),
        ];
        for (k, (case, series, markers)) in cases.iter().enumerate() {
            let path = dir.join(format!("case_{k}.png"));
            match line_plot(&path, case, "x", "y", series, markers) {
                Ok(()) => assert_eq!(png_size(&path), LINE_SIZE, "{case}"),
                Err(e) => assert!(!e.is_empty(), "{case}"),
            }
        }
        let mismatched = [series("bad", vec![0.0, 1.0], vec![0.0])];
        let err = line_plot(&dir.join("bad.png"), "t", "x", "y", &mismatched, &[])
            .expect_err("mismatched lengths");
        assert!(err.contains("bad"), "{err}");
        let ok = [series("ok", vec![0.0, 1.0], vec![0.0, 1.0])];
        assert!(line_plot(&dir.join("plot.jpg"), "t", "x", "y", &ok, &[]).is_err());
        let missing = dir.join("no_such_dir").join("plot.png");
        assert!(line_plot(&missing, "t", "x", "y", &ok, &[]).is_err());
    }

    #[test]
    fn legend_avoids_data() {
        // A diagonal through the lower right and a line along the upper right: the legend
        // goes to the upper left; a marker there moves it to the lower left.
        let unit = Span { lo: 0.0, hi: 1.0 };
        let runs = vec![vec![
            vec![(0.5, 0.5), (1.0, 0.0)],
            vec![(0.5, 0.95), (1.0, 0.95)],
        ]];
        let grid = occupancy(&runs, &[], unit, unit);
        let (position, covered) = best_legend_position(&grid, (0.3, 0.2));
        assert_eq!(position, SeriesLabelPosition::UpperLeft);
        assert_eq!(covered, 0);
        let marker = Marker {
            label: "m".into(),
            x: 0.1,
            y: 0.9,
        };
        let grid = occupancy(&runs, &[marker], unit, unit);
        let (position, covered) = best_legend_position(&grid, (0.3, 0.2));
        assert_eq!(position, SeriesLabelPosition::LowerLeft);
        assert_eq!(covered, 0);

        // Curves through the whole plot get head-room above them.
        let x: Vec<f64> = (0..500).map(|i| f64::from(i) * 0.02).collect();
        let s: Vec<Series> = (0..6)
            .map(|k| {
                series(
                    &format!("phase {k}"),
                    x.clone(),
                    x.iter().map(|t| (t + f64::from(k)).sin()).collect(),
                )
            })
            .collect();
        let plan = LinePlan::new("t", "x", "y", &s, &[]).expect("plan");
        assert_eq!(plan.legend, Some(SeriesLabelPosition::UpperRight));
        assert!(plan.y_span.hi > 1.2, "head-room added: {:?}", plan.y_span);
    }

    #[test]
    fn shape_plot_writes_png_with_equal_aspect() {
        let dir = temp_dir("shape");
        let (positions, quads, values) = billet(10, 15, 0.25);
        let path = dir.join("shape.png");
        shape_plot(
            &path,
            "Upset billet",
            &positions,
            &quads,
            &values,
            "Effective plastic strain [-]",
            &dies(),
            ("r [mm]", "z [mm]"),
            1e3,
        )
        .expect("shape plot");
        let (w, h) = png_size(&path);
        assert_eq!(w, SHAPE_WIDTH);
        assert!((400..=1300).contains(&h), "height {h}");

        let labels = Labels {
            title: "t",
            value: "v",
            x: "x",
            y: "y",
        };
        let tools = dies();
        let panel = Panel {
            title: "",
            positions: &positions,
            values: &values,
            tools: &tools,
        };
        let plan = ShapePlan::new(&labels, &quads, &[panel], 1e3).expect("plan");
        assert_eq!(plan.layout.size, (w, h));
        let pixels = render(plan.layout.size, |root| {
            let plots = plan.draw(root).expect("draw");
            let (pw, ph) = plots[0];
            assert_eq!(pw, plan.layout.plot_w);
            let mm_per_px_x = plan.layout.x_span.width() / f64::from(pw);
            let mm_per_px_y = plan.layout.y_span.width() / f64::from(ph);
            assert!(
                (mm_per_px_x / mm_per_px_y - 1.0).abs() < 1e-9,
                "equal aspect"
            );
        });
        assert!(dark_pixels(&pixels, w, 0..TITLE_H) > 10, "title drawn");
    }

    #[test]
    fn shape_plot_degenerate_inputs_do_not_panic() {
        let dir = temp_dir("shape_degenerate");
        let (positions, quads, values) = billet(4, 6, 0.2);
        let n = positions.len();
        let nan = f64::NAN;
        let mut nan_positions = positions.clone();
        nan_positions[3] = [nan, 0.0];
        nan_positions[7] = [f64::INFINITY, f64::NEG_INFINITY];
        let mut some_nan = values.clone();
        some_nan[0] = nan;
        some_nan[5] = f64::INFINITY;
        let same_point = vec![[0.001, 0.002]; n];
        let line = (0..n).map(|i| [i as f64 * 1e-3, 0.0]).collect::<Vec<_>>();
        let huge = vec![[1e307, -1e307]; n];
        let tools = dies();
        let no_tools: Vec<Vec<[f64; 2]>> = Vec::new();
        let odd_tools = vec![
            vec![],
            vec![[nan, 0.0]],
            vec![[0.0, 0.0]],
            vec![[0.0, 0.0], [nan, nan], [1.0, 1.0]],
        ];
        type Case<'a> = (
            &'a str,
            &'a [[f64; 2]],
            &'a [[u32; 4]],
            Vec<f64>,
            &'a [Vec<[f64; 2]>],
        );
        let cases: Vec<Case> = vec![
            ("all equal values", &positions, &quads, vec![2.5; n], &tools),
            ("all zero values", &positions, &quads, vec![0.0; n], &tools),
            ("some nan values", &positions, &quads, some_nan, &tools),
            ("all nan values", &positions, &quads, vec![nan; n], &tools),
            (
                "nan positions",
                &nan_positions,
                &quads,
                values.clone(),
                &tools,
            ),
            (
                "zero-size bounds",
                &same_point,
                &quads,
                values.clone(),
                &no_tools,
            ),
            ("zero height", &line, &quads, values.clone(), &no_tools),
            ("huge coordinates", &huge, &quads, values.clone(), &no_tools),
            ("no quads", &positions, &[], values.clone(), &tools),
            ("odd tools", &positions, &quads, values.clone(), &odd_tools),
            ("only tools", &[], &[], vec![], &tools),
            ("nothing", &[], &[], vec![], &no_tools),
        ];
        for (k, (case, positions, quads, values, tools)) in cases.iter().enumerate() {
            let path = dir.join(format!("case_{k}.png"));
            let result = shape_plot(
                &path,
                case,
                positions,
                quads,
                values,
                "v",
                tools,
                ("x", "y"),
                1e3,
            );
            match result {
                Ok(()) => assert_eq!(png_size(&path).0, SHAPE_WIDTH, "{case}"),
                Err(e) => assert!(!e.is_empty(), "{case}"),
            }
        }
        let path = dir.join("err.png");
        let plot = |positions: &[[f64; 2]], quads: &[[u32; 4]], values: &[f64], scale: f64| {
            shape_plot(
                &path,
                "t",
                positions,
                quads,
                values,
                "v",
                &tools,
                ("x", "y"),
                scale,
            )
        };
        assert!(plot(&[], &[], &[], 1e3).is_ok(), "tools alone can be drawn");
        assert!(plot(&[], &[], &[], 1e3).is_ok());
        assert!(
            plot(&positions, &quads, &values[1..], 1e3).is_err(),
            "values length"
        );
        assert!(
            plot(&positions, &[[0, 1, 2, n as u32]], &values, 1e3).is_err(),
            "quad index"
        );
        assert!(
            plot(&positions, &quads, &values, 0.0).is_err(),
            "zero scale"
        );
        assert!(plot(&positions, &quads, &values, nan).is_err(), "nan scale");
        let nothing = shape_plot(&path, "t", &[], &[], &[], "v", &[], ("x", "y"), 1.0);
        assert!(nothing.is_err(), "nothing to draw");
    }

    #[test]
    fn stages_plot_shares_axes_and_colours() {
        let dir = temp_dir("stages");
        let meshes: Vec<_> = [0.0, 0.15, 0.3].iter().map(|&b| billet(8, 12, b)).collect();
        let stages: Vec<Stage> = meshes
            .iter()
            .enumerate()
            .map(|(k, (positions, _, values))| Stage {
                title: format!("Stage {}", k + 1),
                positions,
                values,
                tools: dies(),
            })
            .collect();
        let quads = &meshes[0].1;
        let path = dir.join("stages.png");
        stages_plot(
            &path,
            "Forging sequence",
            quads,
            &stages,
            "strain",
            ("r [mm]", "z [mm]"),
            1e3,
        )
        .expect("stages plot");
        let (w, h) = png_size(&path);
        assert_eq!(w, SHAPE_WIDTH + 2 * STAGE_EXTRA_WIDTH);
        assert!(h >= MIN_PLOT_H, "height {h}");

        let one = stages_plot(
            &dir.join("one.png"),
            "t",
            quads,
            &stages[..1],
            "v",
            ("x", "y"),
            1e3,
        );
        assert!(one.is_ok());
        assert_eq!(png_size(&dir.join("one.png")).0, SHAPE_WIDTH);
        assert!(stages_plot(&path, "t", quads, &[], "v", ("x", "y"), 1e3).is_err());
        let many: Vec<Stage> = std::iter::repeat_n(stages[2].clone(), 41).collect();
        let grid = dir.join("grid.png");
        stages_plot(&grid, "t", quads, &many, "v", ("x", "y"), 1e3).expect("many stages");
        let (w, h) = png_size(&grid);
        assert_eq!(
            w,
            SHAPE_WIDTH + (MAX_COLUMNS as u32 - 1) * STAGE_EXTRA_WIDTH
        );
        assert!(h <= MAX_HEIGHT, "height {h}");
        let picked: Vec<usize> = evenly_spaced(&(0..41).collect::<Vec<usize>>(), 5)
            .into_iter()
            .copied()
            .collect();
        assert_eq!(picked, [0, 10, 20, 30, 40]);
        assert_eq!(evenly_spaced(&[1, 2, 3], 30).len(), 3);
        let short = Stage {
            values: &meshes[2].2[1..],
            ..stages[2].clone()
        };
        let err = stages_plot(
            &path,
            "t",
            quads,
            &[stages[0].clone(), short],
            "v",
            ("x", "y"),
            1e3,
        )
        .expect_err("stage with too few values");
        assert!(err.contains("stage 2"), "{err}");
    }

    #[test]
    fn random_inputs_do_not_panic() {
        // Deterministic pseudo-random garbage, drawn into memory.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let specials = [
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
        let value = move |r: u64| match r % 4 {
            0 => specials[(r >> 8) as usize % specials.len()],
            _ => (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0,
        };
        for round in 0..12 {
            let n = (next() % 12) as usize;
            let points: Vec<[f64; 2]> = (0..n).map(|_| [value(next()), value(next())]).collect();
            let values: Vec<f64> = (0..n).map(|_| value(next())).collect();
            let quads: Vec<[u32; 4]> = (0..next() % 6)
                .map(|_| [0; 4].map(|_: u32| (next() % (n as u64).max(1)) as u32))
                .collect();
            let tools = vec![(0..next() % 4)
                .map(|_| [value(next()), value(next())])
                .collect()];
            let panel = Panel {
                title: "p",
                positions: &points,
                values: &values,
                tools: &tools,
            };
            let labels = Labels {
                title: "t",
                value: "v",
                x: "x",
                y: "y",
            };
            if let Ok(plan) = ShapePlan::new(&labels, &quads, &[panel], 1e3) {
                render(plan.layout.size, |root| {
                    plan.draw(root)
                        .unwrap_or_else(|e| panic!("round {round}: {e}"));
                });
            }
            let s = [series(
                "r",
                points.iter().map(|p| p[0]).collect(),
                values.clone(),
            )];
            let markers = [Marker {
                label: "m".into(),
                x: value(next()),
                y: value(next()),
            }];
            if let Ok(plan) = LinePlan::new("t", "x", "y", &s, &markers) {
                render(plan.size, |root| {
                    plan.draw(root)
                        .unwrap_or_else(|e| panic!("round {round}: {e}"));
                });
            }
        }
    }

    #[test]
    fn ticks_are_nice_and_labelled_consistently() {
        assert_eq!(nice_step(0.13), 0.2);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(7.0), 10.0);
        assert_eq!(nice_step(1.0), 1.0);
        let ticks = Ticks::with_count(
            Span {
                lo: -0.03,
                hi: 1.03,
            },
            6,
        );
        let labels: Vec<String> = ticks.values.iter().map(|&v| ticks.label(v)).collect();
        assert_eq!(labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let ticks = Ticks::with_count(Span { lo: -1.0, hi: 55.0 }, 6);
        let labels: Vec<String> = ticks.values.iter().map(|&v| ticks.label(v)).collect();
        assert_eq!(labels, ["0", "10", "20", "30", "40", "50"]);
        let ticks = Ticks::with_count(
            Span {
                lo: 2.0e6,
                hi: 2.05e6,
            },
            5,
        );
        assert_eq!(ticks.label(2.01e6), "2.01e6");
        let ticks = Ticks::with_count(Span { lo: 0.0, hi: 5e-5 }, 5);
        assert_eq!(ticks.label(0.0), "0");
        assert_eq!(ticks.label(2e-5), "2e-5");
        let empty = Ticks::with_step(Span { lo: 0.0, hi: 1.0 }, 0.0);
        assert!(empty.values.is_empty());
    }

    #[test]
    fn spans_are_made_drawable() {
        let flat = Span { lo: 3.0, hi: 3.0 }.widened();
        assert!(flat.width() > 0.0 && flat.centre() == 3.0);
        let zero = Span { lo: 0.0, hi: 0.0 }.widened();
        assert_eq!(zero, Span { lo: -0.5, hi: 0.5 });
        assert_eq!(
            Span::of([f64::NAN, 2.0, f64::INFINITY, -1.0]),
            Some(Span { lo: -1.0, hi: 2.0 })
        );
        assert_eq!(Span::of([f64::NAN]), None);
        assert!(Span {
            lo: -f64::MAX,
            hi: f64::MAX
        }
        .checked()
        .is_err());
    }

    #[test]
    fn colour_map_and_clipping() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        assert_eq!(viridis(2.0), viridis(1.0));
        let unit = Span { lo: 0.0, hi: 1.0 };
        assert_eq!(
            clip_segment((-1.0, 0.5), (2.0, 0.5), unit, unit),
            Some(((0.0, 0.5), (1.0, 0.5)))
        );
        assert_eq!(clip_segment((2.0, 2.0), (3.0, 3.0), unit, unit), None);
        let parts = clip_polyline(
            &[(0.5, 0.5), (0.5, 2.0), (0.6, 2.0), (0.6, 0.5), (0.7, 0.5)],
            unit,
            unit,
        );
        assert_eq!(
            parts,
            vec![
                vec![(0.5, 0.5), (0.5, 1.0)],
                vec![(0.6, 1.0), (0.6, 0.5), (0.7, 0.5)]
            ]
        );
    }
}
