//! Clipping of polylines to a plot's view box (Liang and Barsky 1984), so that a tool that
//! reaches far beyond the workpiece is drawn only where the view shows it.

use super::Span;

/// Clips the segment a-b to the box (Liang-Barsky); `None` if it lies outside.
pub(super) fn clip_segment(
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
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// The parts of a polyline inside the box, as separate polylines.
pub(super) fn clip_polyline(points: &[(f64, f64)], x: Span, y: Span) -> Vec<Vec<(f64, f64)>> {
    let mut parts: Vec<Vec<(f64, f64)>> = Vec::new();
    for pair in points.windows(2) {
        let Some((c, d)) = clip_segment(pair[0], pair[1], x, y) else {
            parts.push(Vec::new());
            continue;
        };
        match parts.last_mut() {
            Some(part) if part.last() == Some(&c) => part.push(d),
            _ => parts.push(vec![c, d]),
        }
    }
    parts.retain(|part| !part.is_empty());
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tools_are_clipped_to_the_view() {
        let unit = Span::UNIT;
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
