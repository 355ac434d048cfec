//! Shape plots: deformed workpieces as quads filled by a field, at equal aspect ratio, with the
//! tools drawn over them; one panel ([`shape_plot`]) or a grid of forging stages sharing axes
//! and one colour scale ([`stages_plot`]).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::clip::clip_polyline;
use super::colour_bar::ColourScale;
use super::PANEL_TITLE_FONT;
use super::{axes_chart, centred_text, draw_err, ensure_font, evenly_spaced, png_canvas};
use super::{save, titled};
use super::{Axis, Span, MARGIN_BOTTOM, MARGIN_LEFT, MARGIN_RIGHT, MARGIN_TOP, TITLE_H, X_AREA};

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
    /// Marked points of the tools (m) and whether each is filled: the tools' fill points,
    /// drawn as a filled green dot when the material reached them, a hollow red ring when not.
    pub marks: Vec<([f64; 2], bool)>,
    /// Laps of the workpiece's surface, drawn as magenta dots on their particles, labelled.
    pub laps: Vec<Lap>,
}

/// A lap (the surface folded onto itself) as a shape plot marks it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Lap {
    /// Its label, e.g. "lap 1".
    pub label: String,
    /// The positions of its surface particles (m).
    pub points: Vec<[f64; 2]>,
}

/// Height of the strip holding a panel title in [`stages_plot`].
const PANEL_TITLE_H: u32 = 34;
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
/// Smallest distance between ticks (pixels).
const TICK_SPACING: u32 = 80;
/// Bounds on the height of a shape's plotting area (pixels).
const MIN_PLOT_H: u32 = 240;
const MAX_PLOT_H: u32 = 1100;
/// Narrowest plotting area of a shape panel (pixels).
const MIN_PLOT_W: u32 = 160;
/// Radius of the dots drawn for nodes when there are no quads (pixels).
const NODE_DOT_RADIUS: i32 = 3;
/// Mean quad edge length (pixels) from which mesh lines are drawn.
const MIN_MESH_EDGE: f64 = 14.0;
/// Colour of the tools.
const TOOL: RGBColor = RGBColor(25, 25, 25);
/// Colours and radius (pixels) of the fill points, filled and empty.
const FILLED: RGBColor = RGBColor(0, 150, 60);
const EMPTY: RGBColor = RGBColor(210, 30, 30);
const MARK_RADIUS: i32 = 6;
/// Colour and radius (pixels) of the laps' particles.
const LAP: RGBColor = RGBColor(200, 0, 200);
const LAP_RADIUS: i32 = 4;

/// Deformed shape, one [`Stage`] without its title: quads filled with a colour map of the mean
/// of their corner values, a colour bar labelled `value_label`, equal aspect ratio (1 m in x =
/// 1 m in y on screen), tool polylines drawn as thick dark lines, fill points and laps marked,
/// coordinates multiplied by `scale` for the axes (e.g. 1e3 with axis labels in mm). PNG
/// about 1000 px wide, height following the aspect ratio (clamped to a sane range).
///
/// Non-finite corner values are left out of the mean; quads without any finite value are grey,
/// quads with a non-finite corner position are skipped. Without quads, nodes are drawn as
/// coloured dots. Tools are shown where they come near the workpiece. `path` must end in `.png`.
///
/// # Errors
///
/// `values` not matching `positions`, a quad index out of range, a non-finite or zero `scale`,
/// nothing finite to draw, a path not ending in `.png`, or a failure to render or write.
pub fn shape_plot(
    path: &Path,
    title: &str,
    quads: &[[u32; 4]],
    stage: Stage<'_>,
    value_label: &str,
    axis_labels: (&str, &str),
    scale: f64,
) -> Result<(), String> {
    stages_plot(
        path,
        title,
        quads,
        &[stage],
        value_label,
        axis_labels,
        scale,
    )
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
    let labels = Labels {
        title,
        x: axis_labels.0,
        y: axis_labels.1,
    };
    let plan = ShapePlan::new(&labels, quads, stages, value_label, scale)?;
    let root = png_canvas(path, plan.layout.size)?;
    plan.draw(&root)?;
    save(&root, path)
}

/// Texts of a shape figure.
struct Labels<'a> {
    title: &'a str,
    x: &'a str,
    y: &'a str,
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
        let edge = |k: usize| (c[(k + 1) % 4].0 - c[k].0).hypot(c[(k + 1) % 4].1 - c[k].1);
        (0..4).map(edge).sum::<f64>() / 4.0
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
    /// Fill points and whether each is filled.
    marks: Vec<((f64, f64), bool)>,
    /// Laps: label and particle positions.
    laps: Vec<(String, Vec<(f64, f64)>)>,
}

impl PanelGeometry {
    fn new(stage: &Stage, quads: &[[u32; 4]], scale: f64) -> PanelGeometry {
        let point = |p: &[f64; 2]| {
            let q = (p[0] * scale, p[1] * scale);
            (q.0.is_finite() && q.1.is_finite()).then_some(q)
        };
        let points: Vec<Option<(f64, f64)>> = stage.positions.iter().map(point).collect();
        let quads = quads
            .iter()
            .filter_map(|quad| {
                let corner = |k: usize| points.get(quad[k] as usize).copied().flatten();
                let corners = [corner(0)?, corner(1)?, corner(2)?, corner(3)?];
                let finite: Vec<f64> = quad
                    .iter()
                    .filter_map(|&i| stage.values.get(i as usize).copied())
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
            .zip(stage.values)
            .filter_map(|(p, &v)| p.map(|p| (p, v)))
            .collect();
        let tools = stage
            .tools
            .iter()
            .flat_map(|polyline| {
                let points: Vec<Option<(f64, f64)>> = polyline.iter().map(point).collect();
                let runs: Vec<Vec<(f64, f64)>> = points
                    .split(Option::is_none)
                    .map(|run| run.iter().flatten().copied().collect())
                    .collect();
                runs
            })
            .filter(|run| !run.is_empty())
            .collect();
        let marks = stage
            .marks
            .iter()
            .filter_map(|(p, filled)| point(p).map(|q| (q, *filled)))
            .collect();
        let laps = stage
            .laps
            .iter()
            .map(|lap| {
                (
                    lap.label.clone(),
                    lap.points.iter().filter_map(point).collect(),
                )
            })
            .collect();
        PanelGeometry {
            quads,
            nodes,
            tools,
            marks,
            laps,
        }
    }
}

/// Checks one stage's arrays against each other and the shared quads.
fn check_stage(k: usize, stage: &Stage, quads: &[[u32; 4]], stages: usize) -> Result<(), String> {
    let which = if stages > 1 {
        format!("stage {} ('{}'): ", k + 1, stage.title)
    } else {
        String::new()
    };
    let n = stage.positions.len();
    if stage.values.len() != n {
        return Err(format!(
            "{which}{} values given for {n} node positions",
            stage.values.len()
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
    let bounds = |points: Vec<(f64, f64)>| {
        Span::of(points.iter().map(|p| p.0)).zip(Span::of(points.iter().map(|p| p.1)))
    };
    let (x, y) = match bounds(nodes().collect()) {
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
            bounds(near).map_or((x, y), |(tx, ty)| (tx.union(x), ty.union(y)))
        }
        None => bounds(tool_points().collect())
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
    x: Axis,
    y: Axis,
}

impl ShapeLayout {
    /// Lays out `panels` panels of the `view` box; `y_area` is the width of the y label area and
    /// `bar_w` that of the colour bar.
    fn new(
        view: (Span, Span),
        panels: usize,
        y_area: u32,
        bar_w: u32,
        titled: bool,
    ) -> Result<Self, String> {
        let rows = panels.div_ceil(MAX_COLUMNS).max(1);
        let columns = panels.div_ceil(rows).max(1);
        let (rows_u, columns_u) = (rows as u32, columns as u32);
        let fixed = y_area + bar_w + columns_u * (MARGIN_LEFT + MARGIN_RIGHT);
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
        let x = x.with_width(unit * f64::from(plot_w)).checked()?;
        let y = y.with_width(unit * f64::from(plot_h)).checked()?;
        let row_h = row_overhead + plot_h;
        Ok(ShapeLayout {
            size: (width, TITLE_H + rows_u * row_h),
            columns,
            plot_w,
            row_h,
            panel_title_h,
            y_area,
            x: Axis::new(x, (plot_w / TICK_SPACING) as usize),
            y: Axis::new(y, (plot_h / TICK_SPACING) as usize),
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

/// Everything needed to draw a shape figure, laid out before the image is created.
struct ShapePlan<'a> {
    labels: &'a Labels<'a>,
    titles: Vec<&'a str>,
    geometries: Vec<PanelGeometry>,
    colours: ColourScale,
    layout: ShapeLayout,
}

impl<'a> ShapePlan<'a> {
    fn new(
        labels: &'a Labels<'a>,
        quads: &[[u32; 4]],
        stages: &'a [Stage<'a>],
        value_label: &str,
        scale: f64,
    ) -> Result<Self, String> {
        ensure_font()?;
        if stages.is_empty() {
            return Err("no stages to plot".into());
        }
        if !scale.is_finite() || scale == 0.0 {
            return Err(format!(
                "coordinate scale must be finite and non-zero, got {scale}"
            ));
        }
        for (k, stage) in stages.iter().enumerate() {
            check_stage(k, stage, quads, stages.len())?;
        }
        let stages = evenly_spaced(stages, MAX_STAGES);
        let geometries: Vec<PanelGeometry> = stages
            .iter()
            .map(|s| PanelGeometry::new(s, quads, scale))
            .collect();
        let view = view_box(&geometries)?;
        let values = stages.iter().flat_map(|s| s.values.iter().copied());
        let colours = ColourScale::new(values, value_label)?;
        let titled = stages.iter().any(|s| !s.title.is_empty());
        let count = stages.len();
        let mut layout = ShapeLayout::new(view, count, 90, colours.width(), titled)?;
        let y_area = layout.y.label_area();
        if y_area != layout.y_area {
            layout = ShapeLayout::new(view, count, y_area, colours.width(), titled)?;
        }
        Ok(ShapePlan {
            labels,
            titles: stages.iter().map(|s| s.title.as_str()).collect(),
            geometries,
            colours,
            layout,
        })
    }

    /// Draws the figure; returns the pixel size of every panel's plotting area.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<Vec<(u32, u32)>, String> {
        let layout = &self.layout;
        let body = titled(root, self.labels.title)?;
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
        let y_breaks = (1..rows).map(|r| (r as u32 * layout.row_h) as i32);
        let cells = grid.split_by_breakpoints(x_breaks, y_breaks.collect::<Vec<_>>());
        let mut plot_sizes = Vec::with_capacity(self.geometries.len());
        for ((geometry, title), cell) in self.geometries.iter().zip(&self.titles).zip(&cells) {
            let y_area = layout.y_area_of(plot_sizes.len() % columns);
            let (strip, chart_area) = cell.split_vertically(layout.panel_title_h);
            if layout.panel_title_h > 0 {
                let x = MARGIN_LEFT + y_area + layout.plot_w / 2;
                let centre = (x as i32, (layout.panel_title_h / 2) as i32);
                centred_text(&strip, title, PANEL_TITLE_FONT, centre)?;
            }
            plot_sizes.push(self.draw_panel(&chart_area, geometry, y_area)?);
        }
        let bar_top = MARGIN_TOP + layout.panel_title_h;
        self.colours.draw(&colour_bar, bar_top)?;
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
        let (x, y) = (&layout.x, &layout.y);
        let descs = (self.labels.x, self.labels.y);
        let mut chart = axes_chart(area, (x, y), descs, y_area)?;
        let colour = |quad: &FilledQuad| self.colours.colour(quad.value);
        let quads = &geometry.quads;
        let fills = quads
            .iter()
            .map(|quad| Polygon::new(quad.corners.to_vec(), colour(quad).filled()));
        chart.draw_series(fills).map_err(draw_err)?;
        // Outline every quad in its own colour to close raster gaps between neighbours, then,
        // where quads are large enough for the mesh distortion to be readable, as a faint grid.
        let outlines = quads
            .iter()
            .map(|quad| PathElement::new(quad.outline(), colour(quad).stroke_width(1)));
        chart.draw_series(outlines).map_err(draw_err)?;
        let unit = x.span.width() / f64::from(layout.plot_w);
        let edges: f64 = quads.iter().map(FilledQuad::mean_edge).sum();
        if edges / quads.len().max(1) as f64 / unit >= MIN_MESH_EDGE {
            let grid = quads
                .iter()
                .map(|quad| PathElement::new(quad.outline(), BLACK.mix(0.35).stroke_width(1)));
            chart.draw_series(grid).map_err(draw_err)?;
        }
        if quads.is_empty() {
            let dots = geometry.nodes.iter().map(|&(p, v)| {
                let colour = self.colours.colour(Some(v));
                Circle::new(p, NODE_DOT_RADIUS, colour.filled())
            });
            chart.draw_series(dots).map_err(draw_err)?;
        }
        let tools = geometry
            .tools
            .iter()
            .flat_map(|polyline| clip_polyline(polyline, x.span, y.span))
            .map(|polyline| PathElement::new(polyline, TOOL.stroke_width(4)));
        chart.draw_series(tools).map_err(draw_err)?;
        let inside = |p: &(f64, f64)| {
            (x.span.lo..=x.span.hi).contains(&p.0) && (y.span.lo..=y.span.hi).contains(&p.1)
        };
        let marks = geometry
            .marks
            .iter()
            .filter(|(p, _)| inside(p))
            .map(|&(p, filled)| {
                let style = match filled {
                    true => FILLED.filled(),
                    false => EMPTY.stroke_width(3),
                };
                Circle::new(p, MARK_RADIUS, style)
            });
        chart.draw_series(marks).map_err(draw_err)?;
        for (label, points) in &geometry.laps {
            let dots = points
                .iter()
                .filter(|p| inside(p))
                .map(|&p| Circle::new(p, LAP_RADIUS, LAP.filled()));
            chart.draw_series(dots).map_err(draw_err)?;
            if let Some(&p) = points.iter().find(|p| inside(p)) {
                let text = Text::new(label.clone(), p, ("sans-serif", 16).into_font().color(&LAP));
                chart.draw_series(std::iter::once(text)).map_err(draw_err)?;
            }
        }
        Ok(chart.plotting_area().dim_in_pixel())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{dark_pixels, png_size, render, temp_dir, Garbage};
    use super::*;

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

    fn stage<'a>(
        positions: &'a [[f64; 2]],
        values: &'a [f64],
        tools: &[Vec<[f64; 2]>],
    ) -> Stage<'a> {
        Stage {
            title: "p".into(),
            positions,
            values,
            tools: tools.to_vec(),
            marks: vec![([0.01, 0.01], true), ([0.02, 0.0], false)],
            laps: Vec::new(),
        }
    }

    const LABELS: Labels = Labels {
        title: "t",
        x: "x",
        y: "y",
    };

    #[test]
    fn shape_plot_writes_png_with_equal_aspect() {
        let dir = temp_dir("shape");
        let (positions, quads, values) = billet(10, 15, 0.25);
        let path = dir.path().join("shape.png");
        let marked = Stage {
            title: String::new(),
            marks: vec![([0.01, 0.0], true), ([0.03, 0.0], false)],
            laps: vec![Lap {
                label: "lap 1".into(),
                points: vec![[0.02, 0.001], [0.021, 0.001]],
            }],
            ..stage(&positions, &values, &dies())
        };
        shape_plot(
            &path,
            "Upset billet",
            &quads,
            marked,
            "Effective plastic strain [-]",
            ("r [mm]", "z [mm]"),
            1e3,
        )
        .expect("shape plot");
        let (w, h) = png_size(&path);
        assert_eq!(w, SHAPE_WIDTH);
        assert!((400..=1300).contains(&h), "height {h}");

        let mut panel = stage(&positions, &values, &dies());
        panel.title.clear();
        let panels = [panel];
        let plan = ShapePlan::new(&LABELS, &quads, &panels, "v", 1e3).expect("plan");
        assert_eq!(plan.layout.size, (w, h));
        let pixels = render(plan.layout.size, |root| {
            let plots = plan.draw(root).expect("draw");
            let (pw, ph) = plots[0];
            assert_eq!(pw, plan.layout.plot_w);
            let mm_per_px_x = plan.layout.x.span.width() / f64::from(pw);
            let mm_per_px_y = plan.layout.y.span.width() / f64::from(ph);
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
        let v = || values.clone();
        let cases: Vec<Case> = vec![
            ("all equal values", &positions, &quads, vec![2.5; n], &tools),
            ("all zero values", &positions, &quads, vec![0.0; n], &tools),
            ("some nan values", &positions, &quads, some_nan, &tools),
            ("all nan values", &positions, &quads, vec![nan; n], &tools),
            ("nan positions", &nan_positions, &quads, v(), &tools),
            ("zero-size bounds", &same_point, &quads, v(), &no_tools),
            ("zero height", &line, &quads, v(), &no_tools),
            ("huge coordinates", &huge, &quads, v(), &no_tools),
            ("no quads", &positions, &[], v(), &tools),
            ("odd tools", &positions, &quads, v(), &odd_tools),
            ("only tools", &[], &[], vec![], &tools),
            ("nothing", &[], &[], vec![], &no_tools),
        ];
        for (k, (case, positions, quads, values, tools)) in cases.iter().enumerate() {
            let path = dir.path().join(format!("case_{k}.png"));
            let labels = ("x", "y");
            match shape_plot(
                &path,
                case,
                quads,
                stage(positions, values, tools),
                "v",
                labels,
                1e3,
            ) {
                Ok(()) => assert_eq!(png_size(&path).0, SHAPE_WIDTH, "{case}"),
                Err(e) => assert!(!e.is_empty(), "{case}"),
            }
        }
        let path = dir.path().join("err.png");
        let plot = |positions: &[[f64; 2]], quads: &[[u32; 4]], values: &[f64], scale: f64| {
            let labels = ("x", "y");
            shape_plot(
                &path,
                "t",
                quads,
                stage(positions, values, &tools),
                "v",
                labels,
                scale,
            )
        };
        assert!(plot(&[], &[], &[], 1e3).is_ok(), "tools alone can be drawn");
        let short = &values[1..];
        assert!(
            plot(&positions, &quads, short, 1e3).is_err(),
            "values length"
        );
        let bad_quad = [[0, 1, 2, n as u32]];
        assert!(
            plot(&positions, &bad_quad, &values, 1e3).is_err(),
            "quad index"
        );
        assert!(
            plot(&positions, &quads, &values, 0.0).is_err(),
            "zero scale"
        );
        assert!(plot(&positions, &quads, &values, nan).is_err(), "nan scale");
        let nothing = shape_plot(&path, "t", &[], stage(&[], &[], &[]), "v", ("x", "y"), 1.0);
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
                ..stage(positions, values, &dies())
            })
            .collect();
        let quads = &meshes[0].1;
        let path = dir.path().join("stages.png");
        let plot = |path: &Path, stages: &[Stage]| {
            stages_plot(path, "t", quads, stages, "v", ("r [mm]", "z [mm]"), 1e3)
        };
        plot(&path, &stages).expect("stages plot");
        let (w, h) = png_size(&path);
        assert_eq!(w, SHAPE_WIDTH + 2 * STAGE_EXTRA_WIDTH);
        assert!(h >= MIN_PLOT_H, "height {h}");

        plot(&dir.path().join("one.png"), &stages[..1]).expect("one stage");
        assert_eq!(png_size(&dir.path().join("one.png")).0, SHAPE_WIDTH);
        assert!(plot(&path, &[]).is_err());
        let many: Vec<Stage> = std::iter::repeat_n(stages[2].clone(), 41).collect();
        let grid = dir.path().join("grid.png");
        plot(&grid, &many).expect("many stages");
        let (w, h) = png_size(&grid);
        let columns = MAX_COLUMNS as u32;
        assert_eq!(w, SHAPE_WIDTH + (columns - 1) * STAGE_EXTRA_WIDTH);
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
        let err = plot(&path, &[stages[0].clone(), short]).expect_err("too few values");
        assert!(err.contains("stage 2"), "{err}");
    }

    #[test]
    fn random_inputs_do_not_panic() {
        let mut garbage = Garbage(0x2545_f491_4f6c_dd1d);
        for round in 0..12 {
            let n = (garbage.next() % 12) as usize;
            let mut point = || [garbage.value(), garbage.value()];
            let points: Vec<[f64; 2]> = (0..n).map(|_| point()).collect();
            let values: Vec<f64> = (0..n).map(|_| garbage.value()).collect();
            let corner = |g: &mut Garbage| (g.next() % (n as u64).max(1)) as u32;
            let quads: Vec<[u32; 4]> = (0..garbage.next() % 6)
                .map(|_| [0; 4].map(|_| corner(&mut garbage)))
                .collect();
            let tools = [(0..garbage.next() % 4)
                .map(|_| [garbage.value(), garbage.value()])
                .collect()];
            let panels = [stage(&points, &values, &tools)];
            if let Ok(plan) = ShapePlan::new(&LABELS, &quads, &panels, "v", 1e3) {
                render(plan.layout.size, |root| {
                    plan.draw(root)
                        .unwrap_or_else(|e| panic!("round {round}: {e}"));
                });
            }
        }
    }
}
