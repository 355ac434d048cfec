//! The output sample schedule shared by every front end (`rkforge run`'s history rows, the
//! ROS node's published samples, the FMU's communication points): when a run samples, and how
//! many samples a scene may ask for.

use crate::math::Real;

/// Most output samples a run may take (history rows, published samples).
pub const MAX_SAMPLES: u64 = 10_000_000;

/// Output sample times after t = 0 for a run to `end` every `interval` (s): `k * interval`
/// for k = 1, 2, ... (the count rounded when `end / interval` is whole up to rounding errors,
/// else rounded down), then `end` if the last one falls short of it, so that stepping from
/// sample to sample always reaches the end. None if that is more than [`MAX_SAMPLES`].
#[must_use]
pub fn sample_times(end: Real, interval: Real) -> Option<Vec<Real>> {
    let ratio = end / interval;
    let n = if (ratio - ratio.round()).abs() < 1e-9 * ratio.max(1.0) {
        ratio.round()
    } else {
        ratio.floor()
    };
    if n.is_nan() || n > MAX_SAMPLES as Real {
        return None;
    }
    // n is a whole number in [0, MAX_SAMPLES]: the cast is exact.
    let mut times: Vec<Real> = (1..=n as u64)
        .map(|k| (k as Real * interval).min(end))
        .collect();
    if times.last().is_none_or(|&t| t < end * (1.0 - 1e-12)) {
        times.push(end);
    }
    Some(times)
}
