//! The upper-bound calibration curve of the ring compression test for a shear friction
//! factor `m`: Avitzur's analysis of the compression of a hollow disc between flat platens
//! (Avitzur 1964, "Forging of hollow discs", Israel J. Technol. 2, 295-304; Avitzur 1968,
//! "Metal Forming: Processes and Analysis", McGraw-Hill), from which Male and DePierre (1970,
//! "The validity of mathematical solutions for determining friction from the ring compression
//! test", J. Lubr. Technol. 92, 389-397) computed their m-calibration curves. The curve is
//! recomputed here from the analysis, not digitised from a published figure.
//!
//! The analysis, derived here in full (every step is checked by the tests below):
//!
//! A ring of inner radius `Ri`, outer radius `Ro` and thickness `T` (full height) is
//! compressed between flat rigid platens closing at speed `U`; the material is
//! rigid-perfectly plastic (von Mises, flow stress `sigma0`), the interface shear stress is
//! `tau = m k` on both faces with `k = sigma0 / sqrt(3)`. The velocity field is "parallel"
//! (the radial velocity does not vary through the thickness, the free surfaces stay flat and
//! cylindrical): `u_z = -U z / T` and, by incompressibility `(1/r) d(r u_r)/dr = U / T`,
//!
//! `u_r = (U / (2 T)) (r - Rn^2 / r)`,
//!
//! the only kinematically admissible parallel field; its one free constant is the neutral
//! radius `Rn` (`u_r = 0`). The strain rates are `(U / (2T)) (1 + Rn^2/r^2)` (radial),
//! `(U / (2T)) (1 - Rn^2/r^2)` (hoop) and `-U / T` (axial), without shear, so the effective
//! strain rate is `(U / T) sqrt(1 + Rn^4 / (3 r^4))`. With `X = Rn^2` the power
//! (W = N m / s) is
//!
//! `J = 2 pi sigma0 U [ I(X) + m / (sqrt(3) T) F(X) ]`,
//!
//! internal `I(X) = int_Ri^Ro r sqrt(1 + X^2 / (3 r^4)) dr` and friction on both faces
//! `2 (m sigma0 / sqrt(3)) int_Ri^Ro |u_r| 2 pi r dr`, `F(X) = int_Ri^Ro |r^2 - X| dr`. The
//! upper bound picks the `X` in `[0, Ro^2]` that minimises `J`. `I` and `F` are convex in `X`,
//! so `J` is, and the minimum is where `dJ/dX` changes sign. Differentiating under the
//! integrals, with `a = X / sqrt(3)` (`int dr / (r sqrt(r^4 + a^2)) = -asinh(a / r^2) / (2 a)`)
//! and `Rc` the neutral radius clamped to `[Ri, Ro]`:
//!
//! - `dI/dX = (asinh(a / Ri^2) - asinh(a / Ro^2)) / (2 sqrt(3))`,
//! - `dF/dX = (Rc - Ri) - (Ro - Rc) = 2 Rc - Ri - Ro`.
//!
//! `dJ/dX = 0` is Avitzur's neutral-radius condition in its two cases,
//! `asinh(a / Ri^2) - asinh(a / Ro^2) = 2 m (Ro - Ri) / T` for `Rn <= Ri` (all material
//! flows outwards) and `= 2 m (Ro + Ri - 2 Rn) / T` for `Ri <= Rn <= Ro` (the material inside
//! `Rn` flows inwards). At `m = 0`, `Rn = 0` (homogeneous upsetting); `Rn` grows with `m`.
//!
//! The geometry then follows the field: in the true height strain `s = ln(T0 / T)`,
//! `dR/ds = (R - Rn^2 / R) / 2` for `R = Ri` and `R = Ro`, which keeps the volume
//! `pi (Ro^2 - Ri^2) T` exactly. The curve integrates this with classical Runge-Kutta steps of
//! at most `1 / STEPS_PER_STRAIN` in `s`, the neutral radius minimised afresh at every stage.
//! `sigma0` and `U` cancel: the curve depends on `m` and the ring's proportions only.

/// Runge-Kutta steps per unit of true height strain `ln(T0 / T)`: 50 % height reduction is
/// 0.69, about 700 steps. Halving the step changes the 6:3:2 curves by less than 2e-6 %
/// (percentage points of diameter decrease): about 1e-12 % where the neutral radius stays on
/// one side of the bore (m = 0, 0.4, 0.6, 1), up to 1.1e-6 % where it crosses it (m = 0.1,
/// 0.2), `Rn(s)` having a kink there that costs the Runge-Kutta steps two orders of accuracy
/// (`curve_converges_in_the_step_count`).
const STEPS_PER_STRAIN: f64 = 1000.0;

/// `1 / sqrt(3)`.
const INV_SQRT3: f64 = 0.577_350_269_189_625_8;

/// A ring's cross-section: radii and full height, in any one length unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ring {
    /// Inner radius `Ri`.
    pub inner: f64,
    /// Outer radius `Ro`.
    pub outer: f64,
    /// Thickness (height between the platens) `T`.
    pub thickness: f64,
}

impl Ring {
    /// `dI/dX = (asinh(a / Ri^2) - asinh(a / Ro^2)) / (2 sqrt(3))`, `a = X / sqrt(3)` (-).
    fn internal_slope(&self, x: f64) -> f64 {
        let a = x * INV_SQRT3;
        0.5 * INV_SQRT3 * ((a / self.inner.powi(2)).asinh() - (a / self.outer.powi(2)).asinh())
    }

    /// `Rn` clamped to `[Ri, Ro]`, the radius where `|r^2 - X|` changes sign in the ring.
    fn clamped_neutral(&self, x: f64) -> f64 {
        x.sqrt().clamp(self.inner, self.outer)
    }

    /// `dF/dX = 2 Rc - Ri - Ro` (length): minus the radial length flowing outwards plus the
    /// length flowing inwards.
    fn friction_slope(&self, x: f64) -> f64 {
        2.0 * self.clamped_neutral(x) - self.inner - self.outer
    }

    /// `dJ/dX / (2 pi sigma0 U) = dI/dX + m / (sqrt(3) T) dF/dX` (-) for the field with
    /// `Rn^2 = X` at friction factor `m`; increasing in `X` (J is convex).
    fn power_slope(&self, m: f64, x: f64) -> f64 {
        self.internal_slope(x) + m * INV_SQRT3 / self.thickness * self.friction_slope(x)
    }

    /// The squared neutral radius `Rn^2` (length^2) that minimises the power at friction
    /// factor `m`: bisection of `[0, Ro^2]` on the sign of `dJ/dX`, to the last bit. The
    /// slope is `-m (Ro - Ri) / (sqrt(3) T) <= 0` at `X = 0` and positive at `X = Ro^2`;
    /// `m = 0` gives 0.
    pub fn neutral_radius_sq(&self, m: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, self.outer.powi(2));
        if self.power_slope(m, lo) >= 0.0 {
            return lo;
        }
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                return mid;
            }
            if self.power_slope(m, mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }

    /// `d(Ri, Ro)/ds = ((R - Rn^2 / R) / 2)` for both radii (length), `s = ln(T0 / T)`.
    fn radius_rates(&self, m: f64) -> [f64; 2] {
        let x = self.neutral_radius_sq(m);
        [self.inner, self.outer].map(|r| 0.5 * (r - x / r))
    }

    /// The ring after a true height strain `ds` more, by one classical Runge-Kutta step.
    fn step(&self, m: f64, ds: f64) -> Ring {
        let at = |k: [f64; 2], h: f64| Ring {
            inner: self.inner + h * k[0],
            outer: self.outer + h * k[1],
            thickness: self.thickness * (-h).exp(),
        };
        let k1 = self.radius_rates(m);
        let k2 = at(k1, 0.5 * ds).radius_rates(m);
        let k3 = at(k2, 0.5 * ds).radius_rates(m);
        let k4 = at(k3, ds).radius_rates(m);
        let k = [0, 1].map(|i| (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]) / 6.0);
        at(k, ds)
    }

    /// The ring at each height reduction of `reductions_pct` (%, `100 (1 - T / T0)`,
    /// ascending, below 100), compressed from `self` at friction factor `m` with
    /// `steps_per_strain` Runge-Kutta steps per unit of true height strain.
    fn compressed(&self, m: f64, reductions_pct: &[f64], steps_per_strain: f64) -> Vec<Ring> {
        let mut ring = *self;
        let mut strain = 0.0;
        reductions_pct
            .iter()
            .map(|&r| {
                let target = -(1.0 - r / 100.0).ln();
                let n = ((target - strain) * steps_per_strain).ceil().max(0.0);
                for _ in 0..n as usize {
                    ring = ring.step(m, (target - strain) / n);
                }
                strain = strain.max(target);
                ring
            })
            .collect()
    }

    /// Avitzur's upper-bound calibration curve: the decrease of the inner diameter,
    /// `100 (1 - Ri / Ri0)` (%; negative when the hole grows), at each height reduction of
    /// `reductions_pct` (%, ascending, below 100) for friction factor `m`.
    pub fn inner_diameter_decrease_pct(&self, m: f64, reductions_pct: &[f64]) -> Vec<f64> {
        self.compressed(m, reductions_pct, STEPS_PER_STRAIN)
            .iter()
            .map(|r| 100.0 * (1.0 - r.inner / self.inner))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 6:3:2 ring: outer diameter 6, inner 3, height 2.
    const RING: Ring = Ring {
        inner: 1.5,
        outer: 3.0,
        thickness: 2.0,
    };
    const TABLE: [f64; 5] = [10.0, 20.0, 30.0, 40.0, 50.0];
    const FACTORS: [f64; 6] = [0.0, 0.1, 0.2, 0.4, 0.6, 1.0];

    /// Composite Simpson rule of `f` over `[a, b]` with `n` (even) intervals.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        let inner: f64 = (1..n)
            .map(|i| f64::from(if i % 2 == 1 { 4 } else { 2 }) * f(a + i as f64 * h))
            .sum();
        (f(a) + f(b) + inner) * h / 3.0
    }

    /// The power `J / (2 pi sigma0 U)` straight from the velocity field with `Rn^2 = x`, by
    /// quadrature: the effective strain rate `(U/T) sqrt(1 + Rn^4 / (3 r^4))` over the
    /// volume, `m k |u_r|` over both faces (`U = 1`).
    fn power(ring: &Ring, m: f64, x: f64) -> f64 {
        let (ri, ro, t) = (ring.inner, ring.outer, ring.thickness);
        let internal = simpson(
            |r| r * (1.0 + x * x / (3.0 * r.powi(4))).sqrt(),
            ri,
            ro,
            2000,
        );
        let u_r = |r: f64| (r - x / r) / (2.0 * t);
        let slip = |r: f64| u_r(r).abs() * r;
        let split = x.sqrt().clamp(ri, ro);
        let faces = simpson(slip, ri, split, 2000) + simpson(slip, split, ro, 2000);
        internal + 2.0 * m * INV_SQRT3 * faces
    }

    #[test]
    fn slope_is_the_derivative_of_the_power_of_the_field() {
        for m in [0.0, 0.3, 1.0] {
            for x in [0.5, 2.0, 2.3, 4.0, 8.5] {
                let h = 1e-4;
                let fd = (power(&RING, m, x + h) - power(&RING, m, x - h)) / (2.0 * h);
                let slope = RING.power_slope(m, x);
                assert!((fd - slope).abs() < 1e-7, "m {m} X {x}: {fd} {slope}");
            }
        }
    }

    #[test]
    fn neutral_radius_minimises_the_power() {
        for m in FACTORS {
            let x = RING.neutral_radius_sq(m);
            let j = power(&RING, m, x);
            for dx in [1e-3, 1e-2, 0.3] {
                assert!(power(&RING, m, x + dx) > j, "m {m}");
                assert!(x < dx || power(&RING, m, x - dx) > j, "m {m}");
            }
        }
    }

    #[test]
    fn no_friction_is_homogeneous_upsetting() {
        assert_eq!(RING.neutral_radius_sq(0.0), 0.0);
        let decrease = RING.inner_diameter_decrease_pct(0.0, &TABLE);
        for (r, d) in TABLE.iter().zip(decrease) {
            // Ri = Ri0 sqrt(T0 / T): the decrease is 1 - 1 / sqrt(1 - r).
            let exact = 100.0 * (1.0 - 1.0 / (1.0 - r / 100.0).sqrt());
            assert!((d - exact).abs() < 1e-9, "{r} %: {d} {exact}");
        }
        let at_half = RING.inner_diameter_decrease_pct(0.0, &[50.0])[0];
        assert!((at_half + 41.421).abs() < 1e-3, "{at_half}");
    }

    #[test]
    fn neutral_radius_reaches_the_bore_at_the_closed_form_factor() {
        // Rn = Ri where asinh(1 / sqrt(3)) - asinh(Ri^2 / (sqrt(3) Ro^2)) = 2 m (Ro - Ri) / T.
        let (ri, ro, t) = (RING.inner, RING.outer, RING.thickness);
        let m_bore =
            t * (INV_SQRT3.asinh() - (ri * ri * INV_SQRT3 / (ro * ro)).asinh()) / (2.0 * (ro - ri));
        let rn = RING.neutral_radius_sq(m_bore).sqrt();
        assert!((rn - ri).abs() < 1e-9 * ri, "m {m_bore}: Rn {rn}");
        // Below it the whole ring flows outwards, above it the neutral radius is in the ring.
        assert!(RING.neutral_radius_sq(0.9 * m_bore).sqrt() < ri);
        let high = RING.neutral_radius_sq(1.0).sqrt();
        assert!(high > ri && high < ro, "{high}");
        // The neutral radius moves outwards with friction.
        let rn: Vec<f64> = FACTORS.iter().map(|&m| RING.neutral_radius_sq(m)).collect();
        assert!(rn.windows(2).all(|w| w[1] > w[0]), "{rn:?}");
    }

    #[test]
    fn neutral_radius_satisfies_avitzurs_condition() {
        // asinh(a / Ri^2) - asinh(a / Ro^2) = 2 m (Ro + Ri - 2 Rc) / T, a = Rn^2 / sqrt(3).
        let (ri, ro, t) = (RING.inner, RING.outer, RING.thickness);
        for m in [0.1, 0.2, 0.6, 1.0] {
            let x = RING.neutral_radius_sq(m);
            let a = x * INV_SQRT3;
            let lhs = (a / (ri * ri)).asinh() - (a / (ro * ro)).asinh();
            let rhs = 2.0 * m * (ro + ri - 2.0 * x.sqrt().clamp(ri, ro)) / t;
            assert!((lhs - rhs).abs() < 1e-12, "m {m}: {lhs} {rhs}");
        }
    }

    #[test]
    fn curves_rise_with_friction_and_keep_the_volume() {
        let curves: Vec<Vec<f64>> = FACTORS
            .iter()
            .map(|&m| RING.inner_diameter_decrease_pct(m, &TABLE))
            .collect();
        for pair in curves.windows(2) {
            for (low, high) in pair[0].iter().zip(&pair[1]) {
                assert!(high > low, "{:?}", curves);
            }
        }
        // Sticking friction closes the hole, low friction opens it, at every reduction.
        assert!(curves[5].iter().all(|&d| d > 0.0));
        assert!(curves[1].iter().all(|&d| d < 0.0));
        let volume = |r: &Ring| (r.outer.powi(2) - r.inner.powi(2)) * r.thickness;
        for m in FACTORS {
            for ring in RING.compressed(m, &TABLE, STEPS_PER_STRAIN) {
                assert!((volume(&ring) / volume(&RING) - 1.0).abs() < 1e-10, "m {m}");
            }
        }
    }

    #[test]
    fn curve_converges_in_the_step_count() {
        let decrease = |m: f64, steps: f64| -> Vec<f64> {
            let rings = RING.compressed(m, &TABLE, steps);
            rings
                .iter()
                .map(|r| 100.0 * (1.0 - r.inner / RING.inner))
                .collect()
        };
        for m in FACTORS {
            let fine = decrease(m, 2.0 * STEPS_PER_STRAIN);
            for (c, f) in decrease(m, STEPS_PER_STRAIN).iter().zip(&fine) {
                assert!((c - f).abs() < 1e-5, "m {m}: {c} {f}");
            }
            // Ten times fewer steps is still within 1e-3 %.
            for (c, f) in decrease(m, 0.1 * STEPS_PER_STRAIN).iter().zip(&fine) {
                assert!((c - f).abs() < 1e-3, "m {m}: {c} {f}");
            }
        }
    }
}
