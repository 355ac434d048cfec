//! The colour scale of shape plots: values mapped through viridis (plotters' `ViridisRGB`),
//! grey where there is no finite value, and the labelled colour bar beside the panels.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{draw_axes, draw_err, Axis, Span, MARGIN_BOTTOM, X_AREA};

/// Colour of quads and nodes without a finite value.
const NO_DATA: RGBColor = RGBColor(190, 190, 190);
/// Colour bar geometry: gap to the plots, bar width, space right of the labels (pixels).
const GAP: u32 = 28;
const BAR: u32 = 26;
const RIGHT: u32 = 14;
/// Number of colour steps drawn in the bar.
const STEPS: u32 = 256;
/// Largest number of ticks on the bar.
const MAX_TICKS: usize = 7;

/// The range of values shown in colour and its label.
pub(super) struct ColourScale {
    /// `None` when no value is finite: everything is grey.
    span: Option<Span>,
    label: String,
    axis: Axis,
}

impl ColourScale {
    /// The scale spanning the finite `values` (widened if they are all equal), labelled `label`.
    ///
    /// # Errors
    ///
    /// Values spanning a range too large to draw.
    pub(super) fn new(values: impl IntoIterator<Item = f64>, label: &str) -> Result<Self, String> {
        let span = Span::of(values)
            .map(|s| s.widened().checked())
            .transpose()?;
        let (label, axis) = match span {
            Some(span) => (label.to_string(), Axis::new(span, MAX_TICKS)),
            None => (
                format!("{label} (no finite values)"),
                Axis::new(Span::UNIT, 0),
            ),
        };
        Ok(ColourScale { span, label, axis })
    }

    /// Viridis colour of `value` (clamped to the scale), grey for `None` or without a scale.
    pub(super) fn colour(&self, value: Option<f64>) -> RGBColor {
        match (value, self.span) {
            (Some(v), Some(span)) if v.is_finite() => {
                ViridisRGB::get_color(span.fraction(v).clamp(0.0, 1.0))
            }
            _ => NO_DATA,
        }
    }

    /// Width of the colour bar with its labels (pixels).
    pub(super) fn width(&self) -> u32 {
        GAP + BAR + self.axis.label_area() + RIGHT
    }

    /// Draws the bar into `area`, from `top` pixels below its upper edge down to the level of
    /// the plots' lower edge.
    pub(super) fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        top: u32,
    ) -> Result<(), String> {
        let span = self.axis.span;
        let mut chart = ChartBuilder::on(area)
            .margin_top(top)
            .margin_bottom(X_AREA + MARGIN_BOTTOM)
            .margin_left(GAP)
            .margin_right(RIGHT)
            .set_label_area_size(LabelAreaPosition::Right, self.axis.label_area())
            .build_cartesian_2d(Span::UNIT.coord(), span.coord())
            .map_err(draw_err)?;
        let steps = (0..STEPS).map(|k| {
            let at = |k: u32| span.lo + span.width() * f64::from(k) / f64::from(STEPS);
            let colour = self.colour(Some(0.5 * at(k) + 0.5 * at(k + 1)));
            Rectangle::new([(0.0, at(k)), (1.0, at(k + 1))], colour.filled())
        });
        chart.draw_series(steps).map_err(draw_err)?;
        let none = Axis::new(Span::UNIT, 0);
        draw_axes(&mut chart, (&none, &self.axis), ("", &self.label), false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_map_to_viridis_and_missing_ones_to_grey() {
        let scale = ColourScale::new([2.0, f64::NAN, 4.0], "v").expect("scale");
        assert_eq!(scale.colour(Some(2.0)), RGBColor(68, 1, 84));
        assert_eq!(scale.colour(Some(4.0)), RGBColor(254, 232, 37));
        assert_eq!(scale.colour(Some(9.0)), scale.colour(Some(4.0)));
        assert_eq!(scale.colour(Some(f64::NAN)), NO_DATA);
        assert_eq!(scale.colour(None), NO_DATA);
        let empty = ColourScale::new([f64::NAN], "v").expect("scale");
        assert_eq!(empty.colour(Some(1.0)), NO_DATA);
        assert!(empty.label.contains("no finite values"));
        assert!(ColourScale::new([-f64::MAX, f64::MAX], "v").is_err());
    }
}
