//! Line plots (time histories, tool forces, force against stroke, energy, sweep results): the
//! curves drawn about 3 pixels wide, labelled reference markers, and a legend put where it covers
//! the least data.

use std::path::Path;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::{axes_chart, centred_text, draw_err, ensure_font, font, png_canvas, save, titled};
use super::{Axis, Span, DESC_FONT, MARGIN_BOTTOM, MARGIN_LEFT, MARGIN_RIGHT, MARGIN_TOP};
use super::{TITLE_H, X_AREA};

/// One curve of a line plot.
///
/// `x` and `y` must have the same length. Points with a non-finite coordinate are skipped and
/// break the line. Series with few points also get a dot at every point.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend text; an empty label keeps the series out of the legend.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Line colour.
    pub colour: Colour,
    /// Dashed (e.g. a theoretical reference beside a computed curve) instead of solid.
    pub dashed: bool,
}

/// The colour of a [`Series`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Colour {
    /// The palette colour of the series' own position in the plot.
    #[default]
    Auto,
    /// The palette colour of position `k` (e.g. a reference drawn in its computed curve's
    /// colour).
    Palette(usize),
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

/// Size of a line plot.
const LINE_SIZE: (u32, u32) = (1000, 700);
/// Smallest distance between ticks (pixels) on the x and y axes.
const TICK_SPACING: (u32, u32) = (110, 70);
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
/// Series with at most this many finite points get a dot at every point.
const MAX_DOTTED_POINTS: usize = 30;
/// Radius of those dots (pixels).
const DOT_RADIUS: i32 = 5;
/// Dash and gap lengths of dashed curves (pixels).
const DASH_PX: i32 = 12;
const GAP_PX: i32 = 7;
/// Pixel offsets of the one-pixel lines that together draw a curve about 3 pixels wide.
const BRUSH: [(f64, f64); 5] = [(0.0, 0.0), (-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0)];
/// Shortest line segment drawn for dense curves (pixels).
const MIN_SEGMENT_PX: f64 = 2.0;
/// Legend font size and layout (pixels), matching plotters' legend drawing.
const LEGEND_FONT: f64 = 18.0;
const LEGEND_SAMPLE: u32 = 44;
const LEGEND_MARGIN: u32 = 10;
const LEGEND_OFFSET: f64 = 9.0;
/// Curves are sampled this many times per width or height of the plot to place the legend.
const SAMPLES_PER_SIDE: f64 = 100.0;
/// A marker counts like this many samples of curve when placing the legend.
const MARKER_WEIGHT: u64 = 20;
/// Largest fraction of the plot height given up as head-room for the legend.
const MAX_LEGEND_HEADROOM: f64 = 0.45;

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
    let plan = LinePlan::new(title, x_label, y_label, series, markers)?;
    let root = png_canvas(path, LINE_SIZE)?;
    plan.draw(&root)?;
    save(&root, path)
}

/// Splits a series into runs of consecutive points with finite coordinates.
fn finite_runs(x: &[f64], y: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let points: Vec<Option<(f64, f64)>> = x
        .iter()
        .zip(y)
        .map(|(&x, &y)| (x.is_finite() && y.is_finite()).then_some((x, y)))
        .collect();
    points
        .split(Option::is_none)
        .filter(|run| !run.is_empty())
        .map(|run| run.iter().flatten().copied().collect())
        .collect()
}

/// Everything needed to draw a line plot, laid out before the image is created.
struct LinePlan<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: &'a [Series],
    runs: Vec<Vec<Vec<(f64, f64)>>>,
    markers: &'a [Marker],
    has_data: bool,
    x: Axis,
    y: Axis,
    legend: Option<SeriesLabelPosition>,
}

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
        let all = runs.iter().flatten().flatten().copied();
        let points: Vec<(f64, f64)> = all.chain(finite_markers).collect();
        let span = |values: Vec<f64>, pad: f64| {
            let span = Span::of(values).unwrap_or(Span::UNIT);
            span.widened().padded(pad).checked()
        };
        let x_span = span(points.iter().map(|p| p.0).collect(), 0.03)?;
        let mut y_span = span(points.iter().map(|p| p.1).collect(), 0.06)?;

        let plot_h = LINE_SIZE.1 - TITLE_H - MARGIN_TOP - MARGIN_BOTTOM - X_AREA;
        let rough_plot_w = LINE_SIZE.0 - MARGIN_LEFT - MARGIN_RIGHT - 100;
        let labels: Vec<&str> = series
            .iter()
            .map(|s| s.label.as_str())
            .chain(markers.iter().map(|m| m.label.as_str()))
            .filter(|l| !l.is_empty())
            .collect();
        let legend = legend_size(&labels).map(|(w, h)| {
            let size = (
                (f64::from(w) + LEGEND_OFFSET) / f64::from(rough_plot_w),
                (f64::from(h) + LEGEND_OFFSET) / f64::from(plot_h),
            );
            let samples = data_samples(&runs, markers, x_span, y_span);
            let (position, covered) = best_legend_position(&samples, size);
            // If every placement covers data, make head-room above it for the legend.
            let grown = Span {
                lo: y_span.lo,
                hi: y_span.lo + y_span.width() / (1.0 - size.1 - 0.02),
            };
            match grown.checked() {
                Ok(grown) if covered > 0 && size.1 < MAX_LEGEND_HEADROOM => {
                    y_span = grown;
                    SeriesLabelPosition::UpperRight
                }
                _ => position,
            }
        });
        let y = Axis::new(y_span, (plot_h / TICK_SPACING.1) as usize);
        let plot_w = (LINE_SIZE.0 - MARGIN_LEFT - MARGIN_RIGHT).saturating_sub(y.label_area());
        Ok(LinePlan {
            title,
            x_label,
            y_label,
            series,
            runs,
            markers,
            has_data: !points.is_empty(),
            x: Axis::new(x_span, (plot_w / TICK_SPACING.0) as usize),
            y,
            legend,
        })
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let body = titled(root, self.title)?;
        let axes = (&self.x, &self.y);
        let descs = (self.x_label, self.y_label);
        let mut chart = axes_chart(&body, axes, descs, self.y.label_area())?;

        let (plot_w, plot_h) = chart.plotting_area().dim_in_pixel();
        let pixel = (
            self.x.span.width() / f64::from(plot_w.max(1)),
            self.y.span.width() / f64::from(plot_h.max(1)),
        );
        for (i, (series, runs)) in self.series.iter().zip(&self.runs).enumerate() {
            let colour = match series.colour {
                Colour::Auto => SERIES_COLOURS[i % SERIES_COLOURS.len()],
                Colour::Palette(k) => SERIES_COLOURS[k % SERIES_COLOURS.len()],
            };
            let style = colour.stroke_width(3);
            let dotted = runs.iter().map(Vec::len).sum::<usize>() <= MAX_DOTTED_POINTS;
            if !series.label.is_empty() {
                let dot = if dotted { DOT_RADIUS } else { 0 };
                let dashed = series.dashed;
                chart
                    .draw_series(LineSeries::new(std::iter::empty(), style))
                    .map_err(draw_err)?
                    .label(series.label.as_str())
                    .legend(move |at| {
                        let sample = vec![(0, 0), (34, 0)];
                        let line = if dashed {
                            DashedPathElement::new(sample, DASH_PX, GAP_PX, style).into_dyn()
                        } else {
                            PathElement::new(sample, style).into_dyn()
                        };
                        EmptyElement::at(at) + line + Circle::new((17, 0), dot, style.filled())
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
                    let thin = colour.stroke_width(1);
                    if series.dashed {
                        chart.draw_series(DashedLineSeries::new(shifted, DASH_PX, GAP_PX, thin))
                    } else {
                        chart.draw_series(LineSeries::new(shifted, thin))
                    }
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
            let symbol =
                |at| EmptyElement::at(at) + Polygon::new(marker_vertices(kind), BLACK.filled());
            let finite = marker.x.is_finite() && marker.y.is_finite();
            let anno = chart
                .draw_series(finite.then(|| symbol((marker.x, marker.y))))
                .map_err(draw_err)?;
            if !marker.label.is_empty() {
                anno.label(marker.label.as_str()).legend(move |(px, py)| {
                    EmptyElement::at((px + 17, py))
                        + Polygon::new(marker_vertices(kind), BLACK.filled())
                });
            }
        }

        if !self.has_data {
            let area = chart.plotting_area().strip_coord_spec();
            let (w, h) = area.dim_in_pixel();
            centred_text(
                &area,
                "no finite data",
                DESC_FONT,
                (w as i32 / 2, h as i32 / 2),
            )?;
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
    let widest = labels
        .iter()
        .map(|l| super::text_width(LEGEND_FONT, l))
        .max()?;
    let line_h = (1.25 * LEGEND_FONT) as u32;
    let w = widest + LEGEND_SAMPLE + 2 * LEGEND_MARGIN;
    Some((w, line_h * labels.len() as u32 + 2 * LEGEND_MARGIN))
}

/// Where the data lie, as fractions of the plotting area with a weight each: points along every
/// curve, at most 1 / [`SAMPLES_PER_SIDE`] apart, and the markers.
fn data_samples(
    runs: &[Vec<Vec<(f64, f64)>>],
    markers: &[Marker],
    x: Span,
    y: Span,
) -> Vec<((f64, f64), u64)> {
    let frac = |p: (f64, f64)| (x.fraction(p.0), y.fraction(p.1));
    let cell = (x.width() / SAMPLES_PER_SIDE, y.width() / SAMPLES_PER_SIDE);
    let mut samples = Vec::new();
    for run in runs.iter().flatten() {
        let run: Vec<(f64, f64)> = thinned(run, cell, 1.0).into_iter().map(frac).collect();
        samples.extend(run.first().map(|&p| (p, 1)));
        for pair in run.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let reach = (b.0 - a.0).abs().max((b.1 - a.1).abs());
            let steps = (2.0 * reach * SAMPLES_PER_SIDE).ceil().clamp(1.0, 1e3) as u32;
            samples.extend((1..=steps).map(|k| {
                let t = f64::from(k) / f64::from(steps);
                ((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), 1)
            }));
        }
    }
    let finite = markers
        .iter()
        .filter(|m| m.x.is_finite() && m.y.is_finite());
    samples.extend(finite.map(|m| (frac((m.x, m.y)), MARKER_WEIGHT)));
    samples
}

/// The legend position covering the least weight of `samples` (see [`data_samples`]; earlier
/// candidates win ties) and that weight. `size` is the legend box as fractions of the plotting
/// area.
fn best_legend_position(
    samples: &[((f64, f64), u64)],
    size: (f64, f64),
) -> (SeriesLabelPosition, u64) {
    use SeriesLabelPosition as P;
    let (w, h) = size;
    let (left, centre, right) = ((0.0, w), (0.5 - 0.5 * w, 0.5 + 0.5 * w), (1.0 - w, 1.0));
    let (bottom, middle, top) = ((0.0, h), (0.5 - 0.5 * h, 0.5 + 0.5 * h), (1.0 - h, 1.0));
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
    let inside = |v: f64, (lo, hi): (f64, f64)| (lo - 0.01..=hi + 0.01).contains(&v);
    let mut best = (P::UpperRight, u64::MAX);
    for (position, us, vs) in candidates {
        let covered = samples
            .iter()
            .filter(|(p, _)| inside(p.0, us) && inside(p.1, vs))
            .map(|s| s.1)
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

#[cfg(test)]
mod tests {
    use super::super::tests::{dark_pixels, png_size, render, temp_dir, Garbage};
    use super::*;

    fn series(label: &str, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series {
            label: label.into(),
            x,
            y,
            ..Series::default()
        }
    }

    fn marker(x: f64, y: f64) -> Marker {
        Marker {
            label: "m".into(),
            x,
            y,
        }
    }

    #[test]
    fn line_plot_writes_png() {
        let dir = temp_dir("line");
        let path = dir.path().join("force.png");
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
        let pixels = render(LINE_SIZE, |root| plan.draw(root).expect("draw"));
        assert!(
            dark_pixels(&pixels, LINE_SIZE.0, 0..TITLE_H) > 100,
            "title drawn"
        );
        let no_title = LinePlan::new("", "x", "y", &s, &[]).expect("plan");
        let pixels = render(LINE_SIZE, |root| no_title.draw(root).expect("draw"));
        assert_eq!(dark_pixels(&pixels, LINE_SIZE.0, 0..TITLE_H), 0);
    }

    #[test]
    fn line_plot_degenerate_inputs_do_not_panic() {
        let dir = temp_dir("line_degenerate");
        let (nan, inf) = (f64::NAN, f64::INFINITY);
        let one = |label: &str, x: Vec<f64>, y: Vec<f64>| vec![series(label, x, y)];
        let cases: Vec<(&str, Vec<Series>, Vec<Marker>)> = vec![
            ("nothing", vec![], vec![]),
            ("empty series", one("e", vec![], vec![]), vec![]),
            ("all nan", one("n", vec![nan, nan], vec![nan, 1.0]), vec![]),
            (
                "infinities",
                one("i", vec![0.0, inf, 2.0], vec![-inf, 1.0, 2.0]),
                vec![],
            ),
            ("all equal", one("c", vec![1.0; 5], vec![3.0; 5]), vec![]),
            ("single point", one("p", vec![2.0], vec![0.0]), vec![]),
            ("zeros", one("", vec![0.0; 3], vec![0.0; 3]), vec![]),
            (
                "tiny",
                one("t", vec![0.0, 1e-300], vec![1e-310, 2e-310]),
                vec![],
            ),
            (
                "huge",
                one("h", vec![-1e308, 1e308], vec![1e308, -1e308]),
                vec![],
            ),
            ("marker only", vec![], vec![marker(1.0, 2.0)]),
            ("nan marker", vec![], vec![marker(nan, 2.0)]),
            (
                "many labels",
                (0..40)
                    .map(|k| series(&format!("series {k}"), vec![0.0, 1.0], vec![0.0, 1.0]))
                    .collect(),
                vec![],
            ),
        ];
        for (k, (case, series, markers)) in cases.iter().enumerate() {
            let path = dir.path().join(format!("case_{k}.png"));
            match line_plot(&path, case, "x", "y", series, markers) {
                Ok(()) => assert_eq!(png_size(&path), LINE_SIZE, "{case}"),
                Err(e) => assert!(!e.is_empty(), "{case}"),
            }
        }
        let mismatched = [series("bad", vec![0.0, 1.0], vec![0.0])];
        let err = line_plot(&dir.path().join("bad.png"), "t", "x", "y", &mismatched, &[])
            .expect_err("mismatched lengths");
        assert!(err.contains("bad"), "{err}");
        let ok = [series("ok", vec![0.0, 1.0], vec![0.0, 1.0])];
        assert!(line_plot(&dir.path().join("plot.jpg"), "t", "x", "y", &ok, &[]).is_err());
        let missing = dir.path().join("no_such_dir").join("plot.png");
        assert!(line_plot(&missing, "t", "x", "y", &ok, &[]).is_err());
    }

    #[test]
    fn legend_avoids_data() {
        // A diagonal through the lower right and a line along the upper right: the legend
        // goes to the upper left; a marker there moves it to the lower left.
        let unit = Span::UNIT;
        let runs = vec![vec![
            vec![(0.5, 0.5), (1.0, 0.0)],
            vec![(0.5, 0.95), (1.0, 0.95)],
        ]];
        let samples = data_samples(&runs, &[], unit, unit);
        let (position, covered) = best_legend_position(&samples, (0.3, 0.2));
        assert_eq!(position, SeriesLabelPosition::UpperLeft);
        assert_eq!(covered, 0);
        let samples = data_samples(&runs, &[marker(0.1, 0.9)], unit, unit);
        let (position, covered) = best_legend_position(&samples, (0.3, 0.2));
        assert_eq!(position, SeriesLabelPosition::LowerLeft);
        assert_eq!(covered, 0);

        // Curves through the whole plot get head-room above them.
        let x: Vec<f64> = (0..500).map(|i| f64::from(i) * 0.02).collect();
        let s: Vec<Series> = (0..6)
            .map(|k| {
                let y = x.iter().map(|t| (t + f64::from(k)).sin()).collect();
                series(&format!("phase {k}"), x.clone(), y)
            })
            .collect();
        let plan = LinePlan::new("t", "x", "y", &s, &[]).expect("plan");
        assert_eq!(plan.legend, Some(SeriesLabelPosition::UpperRight));
        assert!(plan.y.span.hi > 1.2, "head-room added: {:?}", plan.y.span);
    }

    #[test]
    fn random_inputs_do_not_panic() {
        let mut garbage = Garbage(0x2545_f491_4f6c_dd1d);
        for round in 0..12 {
            let n = (garbage.next() % 12) as usize;
            let x = (0..n).map(|_| garbage.value()).collect();
            let y = (0..n).map(|_| garbage.value()).collect();
            let s = [series("r", x, y)];
            let markers = [marker(garbage.value(), garbage.value())];
            if let Ok(plan) = LinePlan::new("t", "x", "y", &s, &markers) {
                render(LINE_SIZE, |root| {
                    plan.draw(root)
                        .unwrap_or_else(|e| panic!("round {round}: {e}"));
                });
            }
        }
    }

    /// Pixels of exactly the colour `c` in an RGB image.
    fn pixels_of(pixels: &[u8], c: RGBColor) -> usize {
        pixels.chunks(3).filter(|p| p == &[c.0, c.1, c.2]).count()
    }

    #[test]
    fn dashed_series_leave_gaps_and_take_the_colour_asked_for() {
        let x: Vec<f64> = (0..100).map(f64::from).collect();
        let line = |dashed: bool, colour: Colour| {
            let s = [
                series("first", vec![0.0, 99.0], vec![-1.0, -1.0]),
                Series {
                    colour,
                    dashed,
                    ..series("", x.clone(), vec![0.5; 100])
                },
            ];
            let plan = LinePlan::new("t", "x", "y", &s, &[]).expect("plan");
            render(LINE_SIZE, |root| plan.draw(root).expect("draw"))
        };
        let (second, first) = (SERIES_COLOURS[1], SERIES_COLOURS[0]);
        let solid = pixels_of(&line(false, Colour::Auto), second);
        let dashed = pixels_of(&line(true, Colour::Auto), second);
        // Dashes of 12 pixels with gaps of 7 cover about 12/19 of the length.
        let share = dashed as f64 / solid as f64;
        assert!((0.55..0.75).contains(&share), "{dashed} of {solid}");
        // In the first series' colour, the second series adds its pixels to the first's.
        let alone = pixels_of(&line(false, Colour::Auto), first);
        let shared = pixels_of(&line(false, Colour::Palette(0)), first);
        assert!(shared > alone + solid / 2, "{shared} {alone}");
        assert_eq!(pixels_of(&line(false, Colour::Palette(0)), second), 0);
    }

    #[test]
    fn non_finite_points_break_the_line() {
        let nan = f64::NAN;
        let runs = finite_runs(
            &[0.0, 1.0, nan, 3.0, 4.0, 5.0],
            &[0.0, 1.0, 2.0, nan, 4.0, 5.0],
        );
        assert_eq!(
            runs,
            vec![vec![(0.0, 0.0), (1.0, 1.0)], vec![(4.0, 4.0), (5.0, 5.0)]]
        );
        assert!(finite_runs(&[nan], &[1.0]).is_empty());
    }
}
