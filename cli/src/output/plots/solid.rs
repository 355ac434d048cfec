//! Solid plots: deformed 3D bodies meshed by hexahedra, drawn as their outer surface seen from
//! an oblique orthographic view, each face filled with the viridis colour of its cell's value
//! and shaded by the light falling on it, so that the shape reads; frames side by side, one
//! colour scale for all.
//!
//! The outer surface is every hex face no other hex shares (found by sorting the faces' node
//! sets); of a quarter model that includes the faces on its symmetry planes, so a view from the
//! positive x, y side shows the outside and one from the opposite side the sections. Faces are
//! painted from the farthest to the nearest (painter's algorithm), those that face away from
//! the viewer first and unlit: on a closed surface every face toward the viewer covers them,
//! and where the surface folds over (a crease of a coarse forging) the fold's underside shows,
//! where dropping them left a see-through hole that read as a crack.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::colour_bar::ColourScale;
use super::{centred_text, draw_err, ensure_font, evenly_spaced, font, png_canvas, save};
use super::{text_width, titled};
use super::{Span, MARGIN_BOTTOM, MARGIN_LEFT, MARGIN_RIGHT, MARGIN_TOP, PANEL_TITLE_FONT};
use super::{TICK_FONT, X_AREA};

/// Direction the body is seen from: azimuth in the x-y plane from +x towards +y, elevation
/// above it (degrees); z is up on screen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

impl View {
    /// From the positive x, y side, a little above: the outside of a quarter model.
    pub const OUTSIDE: View = View {
        azimuth_deg: 35.0,
        elevation_deg: 20.0,
    };
    /// From the negative x, y side, a little above: the symmetry planes of a quarter model.
    pub const SECTIONS: View = View {
        azimuth_deg: 215.0,
        elevation_deg: 20.0,
    };
}

impl Default for View {
    fn default() -> Self {
        View::OUTSIDE
    }
}

/// One frame of [`solid_plot`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SolidPanel {
    /// Time of the frame (s), the panel's title.
    pub time: f64,
    /// Node positions (m).
    pub positions: Vec<[f64; 3]>,
    /// Hexahedra of 8 nodes: corners `(-,-,-), (+,-,-), (+,+,-), (-,+,-)`, then the same at
    /// `+z` (the VTK order).
    pub hexes: Vec<[u32; 8]>,
    /// One value per hex, shown on the colour scale shared by all panels.
    pub cell_values: Vec<f64>,
    /// What the values are, e.g. "plastic strain", the colour bar's label.
    pub label: String,
    /// Where the body is seen from.
    pub view: View,
}

/// The faces of a hex as corner indices, counter-clockwise seen from outside (for a hex of
/// positive volume): z-, z+, y-, y+, x-, x+.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [2, 3, 7, 6],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
];
/// Largest number of panels in one figure, and per row.
const MAX_PANELS: usize = 12;
const MAX_COLUMNS: usize = 4;
/// Height of the strip holding a panel title.
const PANEL_TITLE_H: u32 = 34;
/// Preferred height of a panel's drawing area and bounds on its width (pixels).
const PLOT_H: u32 = 620;
const MIN_PLOT: u32 = 240;
const MAX_PLOT_W: u32 = 900;
/// Narrowest figure (pixels), so that titles fit.
const MIN_WIDTH: u32 = 800;
/// Free space around the body in its drawing area, as a fraction of the area's size.
const PAD: f64 = 0.03;
/// Share of the light every face gets whatever its direction.
const AMBIENT: f64 = 0.4;
/// Mean projected face edge (pixels) from which the mesh lines are drawn.
const MIN_MESH_EDGE: f64 = 7.0;
/// Darkening of a face's colour for its mesh lines.
const EDGE_SHADE: f64 = 0.55;
/// Length of the axes triad's arrows (pixels).
const TRIAD: f64 = 24.0;
/// Colour of the scale bar, the triad and notes.
const INK: RGBColor = RGBColor(40, 40, 40);

/// Deformed 3D bodies side by side in one PNG: each panel's hex mesh drawn as its shaded outer
/// surface from the panel's [`View`] (orthographic, equal aspect, the body filling the panel,
/// all panels at the same scale), faces coloured by their cell values on one viridis scale with
/// a colour bar labelled by the panels' labels, panel titles giving the time, a scale bar in mm
/// (positions are in m) and an x, y, z triad below each panel. Up to 4 panels sit in a row, more
/// go into further rows; of more than 12 an evenly spaced selection including the first and the
/// last is shown. `path` must end in `.png`.
///
/// Non-finite cell values are drawn grey; faces with a non-finite corner position are left out.
///
/// # Errors
///
/// No panels, a panel's values not matching its hexes, a hex index out of range, a non-finite
/// view angle, nothing finite to draw, a path not ending in `.png`, or a failure to render or
/// write.
pub fn solid_plot(path: &Path, title: &str, panels: &[SolidPanel]) -> Result<(), String> {
    let plan = SolidPlan::new(title, panels)?;
    let root = png_canvas(path, plan.layout.size)?;
    plan.draw(&root)?;
    save(&root, path)
}

/// The outer faces of a hex mesh: faces no other hex shares, as (hex index, corners
/// counter-clockwise seen from outside), in the order of the hexes. Faces are matched by their
/// sorted node sets.
fn outer_faces(hexes: &[[u32; 8]]) -> Vec<(usize, [u32; 4])> {
    let mut faces: Vec<([u32; 4], usize, usize)> = hexes
        .iter()
        .enumerate()
        .flat_map(|(h, hex)| {
            HEX_FACES.iter().enumerate().map(move |(f, corners)| {
                let mut key = corners.map(|c| hex[c]);
                key.sort_unstable();
                (key, h, f)
            })
        })
        .collect();
    faces.sort_unstable();
    let mut outer = Vec::new();
    for run in faces.chunk_by(|a, b| a.0 == b.0) {
        if let [(_, h, f)] = run {
            outer.push((*h, HEX_FACES[*f].map(|c| hexes[*h][c])));
        }
    }
    outer.sort_unstable();
    outer
}

type Vec3 = [f64; 3];

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn normalized(a: Vec3) -> Option<Vec3> {
    let norm = dot(a, a).sqrt();
    (norm > 0.0 && norm.is_finite()).then(|| a.map(|c| c / norm))
}

/// An orthographic camera: screen axes `right` and `up`, and `toward` the viewer.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Camera {
    right: Vec3,
    up: Vec3,
    toward: Vec3,
    /// Direction towards the light: from the viewer's side, a little above and to the left.
    light: Vec3,
}

impl Camera {
    fn new(view: View) -> Result<Camera, String> {
        let View {
            azimuth_deg,
            elevation_deg,
        } = view;
        if !azimuth_deg.is_finite() || !elevation_deg.is_finite() {
            return Err(format!(
                "view angles must be finite, got azimuth {azimuth_deg} and elevation {elevation_deg}"
            ));
        }
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        let (se, ce) = elevation_deg.to_radians().sin_cos();
        let toward = [ce * ca, ce * sa, se];
        let right = [-sa, ca, 0.0];
        let up = [-se * ca, -se * sa, ce];
        let mix = |k: usize| toward[k] + 0.5 * up[k] - 0.5 * right[k];
        let light = normalized([mix(0), mix(1), mix(2)]).unwrap_or(toward);
        Ok(Camera {
            right,
            up,
            toward,
            light,
        })
    }

    /// Screen position (m: right, up) and depth (larger is nearer) of `p`.
    fn project(&self, p: Vec3) -> ((f64, f64), f64) {
        ((dot(p, self.right), dot(p, self.up)), dot(p, self.toward))
    }
}

/// A face ready to paint: its nodes, projected corners (m), depth of its centre, its cell's
/// value and its Lambert light factor.
#[derive(Debug, Clone, PartialEq)]
struct ShadedFace {
    nodes: [u32; 4],
    corners: [(f64, f64); 4],
    /// Whether the face turns away from the viewer (painted before every face that does not).
    away: bool,
    depth: f64,
    value: f64,
    light: f64,
}

/// An outer face with finite corners: its hex, nodes, corner positions, centre and vector
/// area (half the cross product of the diagonals).
struct SurfaceFace {
    hex: usize,
    nodes: [u32; 4],
    corners: [Vec3; 4],
    centre: Vec3,
    area: Vec3,
}

/// A panel's visible faces, farthest first, and the box around them on screen.
struct PanelScene {
    title: String,
    faces: Vec<ShadedFace>,
    bounds: Option<(Span, Span)>,
    camera: Camera,
}

impl PanelScene {
    fn new(panel: &SolidPanel, title: String) -> Result<PanelScene, String> {
        let camera = Camera::new(panel.view)?;
        let point = |i: u32| {
            let p = panel.positions[i as usize];
            p.iter().all(|c| c.is_finite()).then_some(p)
        };
        let faces: Vec<SurfaceFace> = outer_faces(&panel.hexes)
            .into_iter()
            .filter_map(|(h, nodes)| {
                let c = [
                    point(nodes[0])?,
                    point(nodes[1])?,
                    point(nodes[2])?,
                    point(nodes[3])?,
                ];
                Some(SurfaceFace {
                    hex: h,
                    nodes,
                    corners: c,
                    centre: [0, 1, 2].map(|k| c.iter().map(|p| 0.25 * p[k]).sum::<f64>()),
                    area: cross(sub(c[2], c[0]), sub(c[3], c[1])).map(|a| 0.5 * a),
                })
            })
            .collect();
        // The sum of centre . area is three times the enclosed volume: negative if the hexes
        // are numbered inside out, then every normal is flipped. When it is not a clear sign
        // (open or garbled meshes), no face is taken as facing away.
        let volume: f64 = faces.iter().map(|f| dot(f.centre, f.area)).sum();
        let scale = faces
            .iter()
            .map(|f| dot(f.centre, f.centre).sqrt() * dot(f.area, f.area).sqrt())
            .sum::<f64>();
        let orientation = if !(volume.is_finite() && scale.is_finite()) {
            0.0
        } else if volume > 1e-9 * scale {
            1.0
        } else if volume < -1e-9 * scale {
            -1.0
        } else {
            0.0
        };
        let mut shaded: Vec<ShadedFace> = faces
            .iter()
            .map(|f| {
                let normal = normalized(f.area.map(|a| orientation * a));
                let facing = normal.map_or(0.0, |n| dot(n, camera.toward));
                let away = orientation != 0.0 && facing <= 0.0;
                let lit = normal.map_or(0.0, |n| dot(n, camera.light));
                let lit = match (orientation == 0.0, away) {
                    (true, _) => lit.abs(),
                    (false, true) => 0.0,
                    (false, false) => lit,
                };
                ShadedFace {
                    nodes: f.nodes,
                    corners: f.corners.map(|p| camera.project(p).0),
                    away,
                    depth: camera.project(f.centre).1,
                    value: panel.cell_values[f.hex],
                    light: AMBIENT + (1.0 - AMBIENT) * lit.max(0.0),
                }
            })
            .filter(|f| {
                f.depth.is_finite() && f.corners.iter().all(|p| p.0.is_finite() && p.1.is_finite())
            })
            .collect();
        shaded.sort_by(|a, b| b.away.cmp(&a.away).then(a.depth.total_cmp(&b.depth)));
        let xs = shaded.iter().flat_map(|f| f.corners.map(|p| p.0));
        let ys = shaded.iter().flat_map(|f| f.corners.map(|p| p.1));
        let bounds = Span::of(xs).zip(Span::of(ys));
        Ok(PanelScene {
            title,
            faces: shaded,
            bounds,
            camera,
        })
    }
}

/// Checks one panel's arrays against each other.
fn check_panel(k: usize, panel: &SolidPanel, panels: usize) -> Result<(), String> {
    let which = if panels > 1 {
        format!("panel {}: ", k + 1)
    } else {
        String::new()
    };
    let (n, cells) = (panel.positions.len(), panel.hexes.len());
    if panel.cell_values.len() != cells {
        return Err(format!(
            "{which}{} cell values given for {cells} hexes",
            panel.cell_values.len()
        ));
    }
    for (h, hex) in panel.hexes.iter().enumerate() {
        if let Some(&bad) = hex.iter().find(|&&i| i as usize >= n) {
            return Err(format!(
                "{which}hex {h} references node {bad} but there are only {n} nodes"
            ));
        }
    }
    Ok(())
}

/// Panel titles: the times in one unit (us, ms or s, by the largest) to 4 significant digits,
/// and the view where the panels' views differ (the azimuth, and the elevation if those differ).
fn panel_titles(panels: &[&SolidPanel]) -> Vec<String> {
    let largest = panels
        .iter()
        .map(|p| p.time.abs())
        .filter(|t| t.is_finite())
        .fold(0.0, f64::max);
    let (scale, unit) = if largest < 1e-3 {
        (1e6, "us")
    } else if largest < 1.0 {
        (1e3, "ms")
    } else {
        (1.0, "s")
    };
    let decimals = (3.0 - (largest * scale).log10().floor()).clamp(0.0, 6.0) as usize;
    let first = panels.first().map(|p| p.view).unwrap_or_default();
    let azimuths_differ = panels
        .iter()
        .any(|p| p.view.azimuth_deg != first.azimuth_deg);
    let elevations_differ = panels
        .iter()
        .any(|p| p.view.elevation_deg != first.elevation_deg);
    panels
        .iter()
        .map(|p| {
            let time = if p.time.is_finite() {
                let text = format!("{:.*}", decimals, p.time * scale);
                let text = match text.contains('.') {
                    true => text.trim_end_matches('0').trim_end_matches('.'),
                    false => &text,
                };
                let text = if text == "-0" { "0" } else { text };
                format!("t = {text} {unit}")
            } else {
                "t = ?".to_string()
            };
            let View {
                azimuth_deg: az,
                elevation_deg: el,
            } = p.view;
            match (azimuths_differ, elevations_differ) {
                (_, true) => format!("{time}, az {az}° el {el}°"),
                (true, false) => format!("{time}, az {az}°"),
                (false, false) => time,
            }
        })
        .collect()
}

/// Pixel layout: panels in a grid, each `plot` pixels of drawing area below its title strip
/// and above the strip of its scale bar, all at `unit` m per pixel in both directions.
#[derive(Debug, Clone, PartialEq)]
struct SolidLayout {
    size: (u32, u32),
    columns: usize,
    plot: (u32, u32),
    unit: f64,
}

impl SolidLayout {
    /// Lays out `panels` panels of bodies at most `extent` (m) wide and high on screen, with
    /// a colour bar `bar_w` wide.
    fn new(extent: (f64, f64), panels: usize, bar_w: u32) -> Result<SolidLayout, String> {
        let rows = panels.div_ceil(MAX_COLUMNS).max(1);
        let columns = panels.div_ceil(rows).max(1);
        let (w, h) = extent;
        let aspect = w / h;
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(format!(
                "the body's size on screen ({w:e} x {h:e} m) cannot be drawn"
            ));
        }
        let margins = MARGIN_LEFT + MARGIN_RIGHT;
        let mut plot_w = (f64::from(PLOT_H) * aspect)
            .clamp(f64::from(MIN_PLOT), f64::from(MAX_PLOT_W))
            .round() as u32;
        let plot_h = (f64::from(plot_w) / aspect)
            .clamp(f64::from(MIN_PLOT), f64::from(PLOT_H))
            .round() as u32;
        let columns_u = columns as u32;
        let narrowest = MIN_WIDTH.saturating_sub(bar_w) / columns_u;
        plot_w = plot_w.max(narrowest.saturating_sub(margins));
        let fill = 1.0 - 2.0 * PAD;
        let unit = (w / (fill * f64::from(plot_w))).max(h / (fill * f64::from(plot_h)));
        if !(unit.is_finite() && unit > 0.0) {
            return Err(format!(
                "the body's size on screen ({w:e} x {h:e} m) cannot be drawn"
            ));
        }
        let mut layout = SolidLayout {
            size: (0, 0),
            columns,
            plot: (plot_w, plot_h),
            unit,
        };
        let (cell_w, cell_h) = layout.cell_size();
        layout.size = (
            columns_u * cell_w + bar_w,
            super::TITLE_H + rows as u32 * cell_h,
        );
        Ok(layout)
    }

    /// Size of a panel's grid cell: title strip, drawing area and the strip below, margins.
    fn cell_size(&self) -> (u32, u32) {
        let (w, h) = self.plot;
        (
            w + MARGIN_LEFT + MARGIN_RIGHT,
            PANEL_TITLE_H + MARGIN_TOP + h + X_AREA + MARGIN_BOTTOM,
        )
    }

    /// Maps screen positions (m) of a body with the box `bounds` to pixels of its drawing
    /// area, the box centred.
    fn to_pixels(&self, bounds: (Span, Span)) -> impl Fn((f64, f64)) -> (i32, i32) {
        let centre = (
            0.5 * bounds.0.lo + 0.5 * bounds.0.hi,
            0.5 * bounds.1.lo + 0.5 * bounds.1.hi,
        );
        let middle = (0.5 * f64::from(self.plot.0), 0.5 * f64::from(self.plot.1));
        let unit = self.unit;
        move |(x, y)| {
            // `as` saturates and maps NaN to 0: nothing here can panic.
            let px = middle.0 + (x - centre.0) / unit;
            let py = middle.1 - (y - centre.1) / unit;
            (px.round() as i32, py.round() as i32)
        }
    }
}

/// Everything needed to draw a solid figure, laid out before the image is created.
struct SolidPlan<'a> {
    title: &'a str,
    scenes: Vec<PanelScene>,
    colours: ColourScale,
    layout: SolidLayout,
}

impl<'a> SolidPlan<'a> {
    fn new(title: &'a str, panels: &[SolidPanel]) -> Result<Self, String> {
        ensure_font()?;
        if panels.is_empty() {
            return Err("no panels to plot".into());
        }
        for (k, panel) in panels.iter().enumerate() {
            check_panel(k, panel, panels.len())?;
        }
        let panels = evenly_spaced(panels, MAX_PANELS);
        let titles = panel_titles(&panels);
        let scenes = panels
            .iter()
            .zip(titles)
            .map(|(panel, title)| PanelScene::new(panel, title))
            .collect::<Result<Vec<_>, _>>()?;
        let mut labels: Vec<&str> = Vec::new();
        for panel in &panels {
            if !labels.contains(&panel.label.as_str()) {
                labels.push(&panel.label);
            }
        }
        let values = scenes.iter().flat_map(|s| s.faces.iter().map(|f| f.value));
        let colours = ColourScale::new(values, &labels.join(" / "))?;
        let extents = scenes.iter().filter_map(|s| s.bounds);
        let extent = extents.fold(None, |e: Option<(f64, f64)>, (x, y)| {
            let (w, h) = e.unwrap_or((0.0, 0.0));
            Some((w.max(x.width()), h.max(y.width())))
        });
        let Some((w, h)) = extent else {
            return Err("nothing to plot: no outer face with finite corner positions".into());
        };
        // A body flat on screen still gets a drawing area of some height (or width).
        let side = w.max(h);
        let extent = (w.max(1e-3 * side), h.max(1e-3 * side));
        let layout = SolidLayout::new(extent, scenes.len(), colours.width())?;
        Ok(SolidPlan {
            title,
            scenes,
            colours,
            layout,
        })
    }

    /// Draws the figure.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let layout = &self.layout;
        let body = titled(root, self.title)?;
        let (cell_w, cell_h) = layout.cell_size();
        let columns = layout.columns;
        let (grid, colour_bar) = body.split_horizontally(cell_w * columns as u32);
        for (k, scene) in self.scenes.iter().enumerate() {
            let (row, column) = ((k / columns) as u32, (k % columns) as u32);
            let cell = grid
                .clone()
                .shrink((column * cell_w, row * cell_h), (cell_w, cell_h));
            self.draw_panel(&cell, scene)?;
        }
        self.colours.draw(&colour_bar, MARGIN_TOP + PANEL_TITLE_H)
    }

    /// Draws one panel into its grid cell.
    fn draw_panel<DB: DrawingBackend>(
        &self,
        cell: &DrawingArea<DB, Shift>,
        scene: &PanelScene,
    ) -> Result<(), String> {
        let layout = &self.layout;
        let (plot_w, plot_h) = layout.plot;
        let title_centre = (
            (MARGIN_LEFT + plot_w / 2) as i32,
            (PANEL_TITLE_H / 2) as i32,
        );
        // Smaller type for a title wider than its panel.
        let room = f64::from(plot_w + MARGIN_LEFT + MARGIN_RIGHT - 8);
        let wide = f64::from(text_width(PANEL_TITLE_FONT, &scene.title).max(1));
        let size = PANEL_TITLE_FONT * (room / wide).min(1.0);
        centred_text(cell, &scene.title, size, title_centre)?;
        let area = cell
            .clone()
            .shrink((MARGIN_LEFT, PANEL_TITLE_H + MARGIN_TOP), (plot_w, plot_h));
        let below = cell.clone().shrink(
            (MARGIN_LEFT, PANEL_TITLE_H + MARGIN_TOP + plot_h),
            (plot_w, X_AREA),
        );
        let Some(bounds) = scene.bounds else {
            let centre = ((plot_w / 2) as i32, (plot_h / 2) as i32);
            return centred_text(&area, "nothing to draw", TICK_FONT, centre);
        };
        let pixel = layout.to_pixels(bounds);
        let corners = |f: &ShadedFace| f.corners.map(&pixel);
        let perimeter: f64 = scene
            .faces
            .iter()
            .map(|f| {
                let c = corners(f);
                let edge = |k: usize| {
                    let (a, b) = (c[k], c[(k + 1) % 4]);
                    f64::from(a.0 - b.0).hypot(f64::from(a.1 - b.1))
                };
                (0..4).map(edge).sum::<f64>()
            })
            .sum();
        let mesh_lines = perimeter / (4 * scene.faces.len().max(1)) as f64 >= MIN_MESH_EDGE;
        for face in &scene.faces {
            let colour = shaded(self.colours.colour(Some(face.value)), face.light);
            let c = corners(face);
            area.draw(&Polygon::new(c.to_vec(), colour.filled()))
                .map_err(draw_err)?;
            // The outline in the face's own colour closes raster gaps between neighbours;
            // darker, it shows the mesh where its cells are large enough to read.
            let edge = match mesh_lines {
                true => shaded(colour, EDGE_SHADE),
                false => colour,
            };
            let outline = vec![c[0], c[1], c[2], c[3], c[0]];
            area.draw(&PathElement::new(outline, edge.stroke_width(1)))
                .map_err(draw_err)?;
        }
        draw_scale_bar(&below, layout.unit, plot_w)?;
        draw_triad(&below, &scene.camera, plot_w)
    }
}

/// `colour` scaled by the light factor `light` (0 black, 1 as is).
fn shaded(colour: RGBColor, light: f64) -> RGBColor {
    let f = light.clamp(0.0, 1.0);
    let scale = |c: u8| (f64::from(c) * f).round() as u8;
    RGBColor(scale(colour.0), scale(colour.1), scale(colour.2))
}

/// Length (m) of a scale bar about a quarter of `plot_w` pixels at `unit` m per pixel: 1, 2 or
/// 5 times a power of ten of mm.
fn scale_bar_length(unit: f64, plot_w: u32) -> f64 {
    let target_mm = 0.25 * f64::from(plot_w) * unit * 1e3;
    let power = 10f64.powf(target_mm.log10().floor());
    let step = [5.0, 2.0, 1.0]
        .into_iter()
        .find(|s| s * power <= target_mm)
        .unwrap_or(1.0);
    step * power * 1e-3
}

/// Draws the scale bar at the left of the strip below a panel.
fn draw_scale_bar<DB: DrawingBackend>(
    strip: &DrawingArea<DB, Shift>,
    unit: f64,
    plot_w: u32,
) -> Result<(), String> {
    let length = scale_bar_length(unit, plot_w);
    let pixels = (length / unit).round();
    if !(pixels.is_finite() && pixels >= 1.0) {
        return Ok(());
    }
    let (x0, y) = (8, (X_AREA / 2) as i32);
    let x1 = x0 + pixels as i32;
    let bar = [(x0, y - 5), (x0, y), (x1, y), (x1, y - 5)];
    strip
        .draw(&PathElement::new(bar.to_vec(), INK.stroke_width(2)))
        .map_err(draw_err)?;
    let mm = length * 1e3;
    let text = if mm >= 1.0 {
        format!("{mm:.0} mm")
    } else {
        format!("{mm} mm")
    };
    let style = font(TICK_FONT).pos(Pos::new(HPos::Left, VPos::Center));
    strip
        .draw(&Text::new(text, (x1 + 10, y - 2), style))
        .map_err(draw_err)
}

/// Draws the x, y, z axes as seen from the panel's view at the right of the strip below it.
fn draw_triad<DB: DrawingBackend>(
    strip: &DrawingArea<DB, Shift>,
    camera: &Camera,
    plot_w: u32,
) -> Result<(), String> {
    let origin = (plot_w as i32 - (TRIAD as i32) - 16, (X_AREA / 2) as i32 + 4);
    let style = font(TICK_FONT).pos(Pos::new(HPos::Center, VPos::Center));
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        let mut axis = [0.0; 3];
        axis[k] = 1.0;
        let ((sx, sy), _) = camera.project(axis);
        let tip = |length: f64| {
            (
                origin.0 + (length * sx).round() as i32,
                origin.1 - (length * sy).round() as i32,
            )
        };
        strip
            .draw(&PathElement::new(
                vec![origin, tip(TRIAD)],
                INK.stroke_width(2),
            ))
            .map_err(draw_err)?;
        if sx.hypot(sy) > 0.2 {
            strip
                .draw(&Text::new(name, tip(TRIAD + 9.0), style.clone()))
                .map_err(draw_err)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::tests::{png_size, render, temp_dir, Garbage};
    use super::*;
    use rkforge_core::cylinder_grid::{CylinderGrid, Sector};

    /// A box of `n[0]` x `n[1]` x `n[2]` unit hexes from the origin: positions and hexes in VTK
    /// order.
    fn block(n: [u32; 3]) -> (Vec<[f64; 3]>, Vec<[u32; 8]>) {
        let [nx, ny, nz] = n;
        let mut positions = Vec::new();
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    positions.push([f64::from(i), f64::from(j), f64::from(k)]);
                }
            }
        }
        let node = |i: u32, j: u32, k: u32| (k * (ny + 1) + j) * (nx + 1) + i;
        let mut hexes = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    hexes.push([
                        node(i, j, k),
                        node(i + 1, j, k),
                        node(i + 1, j + 1, k),
                        node(i, j + 1, k),
                        node(i, j, k + 1),
                        node(i + 1, j, k + 1),
                        node(i + 1, j + 1, k + 1),
                        node(i, j + 1, k + 1),
                    ]);
                }
            }
        }
        (positions, hexes)
    }

    /// Outward unit normal of a face of the unit-cube block.
    fn face_normal(positions: &[[f64; 3]], face: [u32; 4]) -> Vec3 {
        let p = face.map(|i| positions[i as usize]);
        normalized(cross(sub(p[2], p[0]), sub(p[3], p[1]))).expect("normal")
    }

    #[test]
    fn outer_faces_are_the_unshared_ones_facing_out() {
        let (positions, hexes) = block([1, 1, 1]);
        let faces = outer_faces(&hexes);
        assert_eq!(faces.len(), 6);
        let normals: Vec<Vec3> = faces.iter().map(|f| face_normal(&positions, f.1)).collect();
        for expected in [
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
        ] {
            assert!(normals.contains(&expected), "{expected:?} in {normals:?}");
        }

        let (positions, hexes) = block([2, 2, 2]);
        let faces = outer_faces(&hexes);
        assert_eq!(faces.len(), 24);
        for (h, face) in &faces {
            let n = face_normal(&positions, *face);
            let centre = [0, 1, 2]
                .map(|k| face.iter().map(|&i| positions[i as usize][k]).sum::<f64>() / 4.0);
            // On the cube's surface and facing out of it.
            let k = n.iter().position(|c| c.abs() == 1.0).expect("axis normal");
            assert_eq!(centre[k], if n[k] > 0.0 { 2.0 } else { 0.0 });
            assert!(face.iter().all(|i| hexes[*h].contains(i)));
        }
        let (_, hexes) = block([3, 2, 1]);
        assert_eq!(outer_faces(&hexes).len(), 2 * (6 + 3 + 2));
        assert!(outer_faces(&[]).is_empty());
    }

    #[test]
    fn projection_keeps_lengths_and_aspect() {
        for view in [
            View::OUTSIDE,
            View::SECTIONS,
            View {
                azimuth_deg: -70.0,
                elevation_deg: 55.0,
            },
        ] {
            let camera = Camera::new(view).expect("camera");
            for (a, b) in [
                (camera.right, camera.up),
                (camera.up, camera.toward),
                (camera.toward, camera.right),
            ] {
                assert!(dot(a, b).abs() < 1e-15);
                assert!((dot(a, a) - 1.0).abs() < 1e-15);
            }
            let handed = cross(camera.right, camera.up);
            assert!(sub(handed, camera.toward).iter().all(|c| c.abs() < 1e-15));
            // Segments parallel to the screen keep their length in every direction.
            for (s, t) in [(1.0, 0.0), (0.0, 2.0), (0.6, -0.8)] {
                let v = [0, 1, 2].map(|k| s * camera.right[k] + t * camera.up[k]);
                let ((x, y), _) = camera.project(v);
                assert!((x.hypot(y) - s.hypot(t)).abs() < 1e-14);
            }
        }
        // Seen along x, a box 2 wide (y) and 1 high (z) is 2 x 1 on screen, and so in pixels.
        let camera = Camera::new(View {
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
        })
        .expect("camera");
        assert_eq!(camera.project([5.0, 2.0, 1.0]), ((2.0, 1.0), 5.0));
        let layout = SolidLayout::new((2.0, 1.0), 1, 100).expect("layout");
        let x = Span { lo: 0.0, hi: 2.0 };
        let y = Span { lo: 0.0, hi: 1.0 };
        let pixel = layout.to_pixels((x, y));
        let (a, b) = (pixel((0.0, 0.0)), pixel((2.0, 1.0)));
        let (w, h) = (b.0 - a.0, a.1 - b.1);
        assert!(
            (f64::from(w) / f64::from(h) - 2.0).abs() < 0.01,
            "{w} x {h}"
        );
        // The body fills the drawing area in one direction, centred, and fits in the other.
        let fill = 1.0 - 2.0 * PAD;
        let (pw, ph) = layout.plot;
        let filled_w = (f64::from(w) - fill * f64::from(pw)).abs() <= 1.0;
        let filled_h = (f64::from(h) - fill * f64::from(ph)).abs() <= 1.0;
        assert!(filled_w || filled_h, "{w} x {h} in {pw} x {ph}");
        assert!(f64::from(w) <= f64::from(pw) && f64::from(h) <= f64::from(ph));
        assert!((a.0 + b.0 - pw as i32).abs() <= 1 && (a.1 + b.1 - ph as i32).abs() <= 1);
    }

    /// A quarter Taylor bar (R 3.8 mm, L 25.4 mm) after impact on its foot at z = 0: the foot
    /// bulged out and the bar shortened by `squash` (0 undeformed), with a plastic strain
    /// field largest at the foot's centre.
    fn taylor_bar(squash: f64) -> (Vec<[f64; 3]>, Vec<[u32; 8]>, Vec<f64>) {
        let (radius, length) = (3.8e-3, 25.4e-3);
        let grid = CylinderGrid::new(radius, length, [8, 4, 24], 0.4, Sector::Quarter)
            .expect("cylinder grid");
        let decay = 0.18 * length;
        let deformed = |p: &[f64; 3]| {
            let foot = (-p[2] / decay).exp();
            let r = 1.0 + squash * 1.6 * foot;
            let z = p[2] * (1.0 - squash * 0.55 * (1.0 - 0.5 * p[2] / length));
            [p[0] * r, p[1] * r, z]
        };
        let positions: Vec<[f64; 3]> = grid.positions.iter().map(deformed).collect();
        let values = grid
            .cells
            .iter()
            .map(|cell| {
                let centre = [0, 1, 2].map(|k| {
                    cell.iter()
                        .map(|&i| grid.positions[i as usize][k])
                        .sum::<f64>()
                        / 8.0
                });
                let r = centre[0].hypot(centre[1]) / radius;
                squash * 3.0 * (-centre[2] / decay).exp() * (1.0 - 0.35 * r * r)
            })
            .collect();
        (positions, grid.cells.clone(), values)
    }

    fn panel(time: f64, squash: f64, view: View) -> SolidPanel {
        let (positions, hexes, cell_values) = taylor_bar(squash);
        SolidPanel {
            time,
            positions,
            hexes,
            cell_values,
            label: "plastic strain [-]".into(),
            view,
        }
    }

    #[test]
    fn solid_plot_draws_a_deformed_bar() {
        let dir = temp_dir("solid");
        let panels = [
            panel(0.0, 0.0, View::OUTSIDE),
            panel(20e-6, 0.2, View::OUTSIDE),
            panel(80e-6, 0.4, View::OUTSIDE),
            panel(80e-6, 0.4, View::SECTIONS),
        ];
        let path = dir.path().join("taylor.png");
        solid_plot(&path, "Quarter Taylor bar", &panels).expect("solid plot");
        let plan = SolidPlan::new("t", &panels).expect("plan");
        assert_eq!(png_size(&path), plan.layout.size);
        let titles: Vec<&str> = plan.scenes.iter().map(|s| s.title.as_str()).collect();
        assert_eq!(titles[0], "t = 0 us, az 35°");
        assert_eq!(titles[3], "t = 80 us, az 215°");
        // From outside the symmetry planes turn away (painted first, under the rest), from
        // the other side they show.
        for axis in 0..2 {
            let on_plane = |k: usize| {
                let positions = &panels[k].positions;
                let on = |f: &&ShadedFace| {
                    !f.away && f.nodes.iter().all(|&i| positions[i as usize][axis] == 0.0)
                };
                plan.scenes[k].faces.iter().filter(on).count()
            };
            assert_eq!(on_plane(2), 0, "axis {axis}");
            // Per axial layer, 4 core cells and 4 ring layers meet each plane.
            assert_eq!(on_plane(3), (4 + 4) * 24, "axis {axis}");
        }
    }

    #[test]
    fn unit_cube_of_eight_hexes_is_drawn() {
        let (positions, hexes) = block([2, 2, 2]);
        let positions = positions.iter().map(|p| p.map(|c| 0.5e-3 * c)).collect();
        let dir = temp_dir("cube");
        let path = dir.path().join("cube.png");
        let panels = [SolidPanel {
            time: 1e-3,
            positions,
            hexes,
            cell_values: (0..8).map(f64::from).collect(),
            label: "v".into(),
            view: View::default(),
        }];
        solid_plot(&path, "Unit cube", &panels).expect("solid plot");
        let plan = SolidPlan::new("Unit cube", &panels).expect("plan");
        assert_eq!(png_size(&path), plan.layout.size);
        assert!(plan.layout.size.0 >= MIN_WIDTH);
        assert!(plan.layout.size.1 > PLOT_H / 2);
        // Three faces of four quads each face the viewer; the three others, turned away, are
        // painted first.
        let faces = &plan.scenes[0].faces;
        assert_eq!(faces.iter().filter(|f| !f.away).count(), 12);
        assert_eq!(faces.len(), 24);
        assert!(faces[..12].iter().all(|f| f.away && f.light == AMBIENT));
        assert_eq!(plan.scenes[0].title, "t = 1 ms");
        // Pixels in the drawing area take viridis colours, shaded.
        let pixels = render(plan.layout.size, |root| plan.draw(root).expect("draw"));
        let coloured = pixels
            .chunks(3)
            .filter(|p| p[0].abs_diff(p[1]) > 30 || p[1].abs_diff(p[2]) > 30)
            .count();
        assert!(coloured > 20_000, "{coloured} coloured pixels");
    }

    #[test]
    fn bad_inputs_are_errors_and_nothing_panics() {
        let dir = temp_dir("solid_bad");
        let path = dir.path().join("bad.png");
        let (positions, hexes) = block([2, 1, 1]);
        let good = SolidPanel {
            time: 0.0,
            positions,
            hexes,
            cell_values: vec![1.0, 2.0],
            label: "v".into(),
            view: View::default(),
        };
        assert!(solid_plot(&path, "t", &[]).is_err(), "no panels");
        let short = SolidPanel {
            cell_values: vec![1.0],
            ..good.clone()
        };
        let err = solid_plot(&path, "t", &[good.clone(), short]).expect_err("short values");
        assert!(err.contains("panel 2"), "{err}");
        let mut bad_hex = good.clone();
        bad_hex.hexes[1][7] = 99;
        assert!(solid_plot(&path, "t", &[bad_hex]).is_err(), "hex index");
        let bad_view = SolidPanel {
            view: View {
                azimuth_deg: f64::NAN,
                elevation_deg: 0.0,
            },
            ..good.clone()
        };
        assert!(solid_plot(&path, "t", &[bad_view]).is_err(), "view");
        assert!(solid_plot(
            &dir.path().join("bad.jpg"),
            "t",
            std::slice::from_ref(&good)
        )
        .is_err());
        let all_nan = SolidPanel {
            positions: vec![[f64::NAN; 3]; good.positions.len()],
            ..good.clone()
        };
        assert!(
            solid_plot(&path, "t", std::slice::from_ref(&all_nan)).is_err(),
            "nothing"
        );

        // Non-finite values are grey, non-finite positions drop their faces, flat or huge
        // bodies and inside-out hexes are drawn.
        let mut holes = good.clone();
        holes.positions[0] = [f64::INFINITY, 0.0, 0.0];
        let cases_inside_out = SolidPanel {
            hexes: good
                .hexes
                .iter()
                .map(|h| [h[4], h[5], h[6], h[7], h[0], h[1], h[2], h[3]])
                .collect(),
            ..good.clone()
        };
        let flat = SolidPanel {
            positions: good.positions.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            ..good.clone()
        };
        let point = SolidPanel {
            positions: vec![[1.0, 2.0, 3.0]; good.positions.len()],
            ..good.clone()
        };
        let huge = SolidPanel {
            positions: good
                .positions
                .iter()
                .map(|p| p.map(|c| c * 1e306))
                .collect(),
            ..good.clone()
        };
        let cases = [
            (
                "nan values",
                SolidPanel {
                    cell_values: vec![f64::NAN, f64::INFINITY],
                    ..good.clone()
                },
            ),
            ("holes", holes),
            ("inside out", cases_inside_out.clone()),
            ("flat", flat),
            ("point", point),
            ("huge", huge),
            (
                "nan time",
                SolidPanel {
                    time: f64::NAN,
                    ..good.clone()
                },
            ),
            (
                "no hexes",
                SolidPanel {
                    hexes: vec![],
                    cell_values: vec![],
                    ..good.clone()
                },
            ),
        ];
        for (k, (case, panel)) in cases.into_iter().enumerate() {
            let path = dir.path().join(format!("case_{k}.png"));
            match solid_plot(&path, case, &[good.clone(), panel, all_nan.clone()]) {
                Ok(()) => assert!(png_size(&path).0 >= MIN_WIDTH, "{case}"),
                Err(e) => assert!(!e.is_empty(), "{case}"),
            }
        }
        let plan = SolidPlan::new("t", &[good.clone(), cases_inside_out]).expect("plan");
        assert_eq!(
            plan.scenes[0].faces.iter().filter(|f| !f.away).count(),
            5,
            "2 x 1 x 1 hexes show 5 faces"
        );
        assert_eq!(
            plan.scenes[1].faces.iter().filter(|f| !f.away).count(),
            5,
            "so do inside-out ones"
        );
    }

    #[test]
    fn random_meshes_do_not_panic() {
        let mut garbage = Garbage(0x9e37_79b9_7f4a_7c15);
        for round in 0..12 {
            let n = (garbage.next() % 16) as usize + 1;
            let positions: Vec<[f64; 3]> = (0..n)
                .map(|_| [garbage.value(), garbage.value(), garbage.value()])
                .collect();
            let cells = (garbage.next() % 6) as usize;
            let hexes: Vec<[u32; 8]> = (0..cells)
                .map(|_| [0; 8].map(|_| (garbage.next() % n as u64) as u32))
                .collect();
            let cell_values = (0..cells).map(|_| garbage.value()).collect();
            let view = View {
                azimuth_deg: garbage.value() * 400.0,
                elevation_deg: garbage.value() * 100.0,
            };
            let panel = SolidPanel {
                time: garbage.value(),
                positions,
                hexes,
                cell_values,
                label: String::new(),
                view,
            };
            if let Ok(plan) = SolidPlan::new("t", &[panel]) {
                render(plan.layout.size, |root| {
                    plan.draw(root)
                        .unwrap_or_else(|e| panic!("round {round}: {e}"));
                });
            }
        }
    }
}
