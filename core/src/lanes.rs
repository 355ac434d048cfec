//! Lanes: the stress stage updates [`LANES`] integration points at once, one per SIMD lane.
//!
//! Every function here is branch-free per lane and written with IEEE operations only
//! (`+ - * /`, `sqrt`, comparisons, bit moves), never a fused multiply-add, so a lane gives
//! the same bits whether the compiler emits scalar, SSE2 or AVX2 code, and whatever the
//! other lanes hold.
//!
//! The logarithm and exponential follow fdlibm (Sun Microsystems 1993, `e_log.c`,
//! `e_exp.c`; the algorithms of glibc and musl): errors below 1 ulp, checked against the
//! C library over the arguments the material sees in `tests` below. They are written here,
//! rather than taken from a SIMD crate, because those crates pick fused or unfused
//! arithmetic at compile time, which would tie the results to the build's target features.

use crate::math::Real;

/// Points per batch: eight `f64`, two AVX2 registers (four SSE2 registers) per quantity.
/// Two independent registers per quantity let the core overlap the latency chains of the
/// update (divisions, square roots, the polynomials of `ln` and `exp`), which one register
/// left idle: on the Taylor bar (q2, 2 threads) the stress stage took 0.70 s against
/// 0.79 s with four lanes; sixteen lanes spill registers and were 6 % slower than eight
/// (issue 35, docs/performance.md). The bits do not depend on it.
pub const LANES: usize = 8;

/// One value per lane.
pub type Lanes = [Real; LANES];

/// `2^52`: adding it to a whole number below `2^52` puts that number in the low mantissa bits.
const TWO_52: Real = 4_503_599_627_370_496.0;

/// `ln 2` split as in fdlibm: `LN2_HI` has 32 trailing zero bits, so `k LN2_HI` is exact.
const LN2_HI: Real = f64::from_bits(0x3FE6_2E42_FEE0_0000);
/// `ln 2 - LN2_HI`.
const LN2_LO: Real = f64::from_bits(0x3DEA_39EF_3579_3C76);

/// Natural logarithm of a positive normal finite `x` (fdlibm `e_log.c`): with
/// `x = 2^k (1 + f)`, `sqrt(2)/2 <= 1 + f < sqrt(2)`, `s = f / (2 + f)`,
/// `ln(1 + f) = f - f^2/2 + s (f^2/2 + R(s^2))`, `R` the fdlibm minimax polynomial.
/// Other arguments (zero, negative, subnormal, infinite, NaN) give an unspecified finite
/// or NaN value; callers check their arguments first.
#[inline(always)]
pub fn ln(x: Real) -> Real {
    // fdlibm's coefficients, given by their bits as in its source.
    const LG1: Real = f64::from_bits(0x3FE5_5555_5555_5593);
    const LG2: Real = f64::from_bits(0x3FD9_9999_9997_FA04);
    const LG3: Real = f64::from_bits(0x3FD2_4924_9422_9359);
    const LG4: Real = f64::from_bits(0x3FCC_71C5_1D8E_78AF);
    const LG5: Real = f64::from_bits(0x3FC7_4664_96CB_03DE);
    const LG6: Real = f64::from_bits(0x3FC3_9A09_D078_C69F);
    const LG7: Real = f64::from_bits(0x3FC2_F112_DF3E_5244);
    let bits = x.to_bits();
    let m = f64::from_bits((bits & 0x000F_FFFF_FFFF_FFFF) | 0x3FF0_0000_0000_0000);
    let big = m > std::f64::consts::SQRT_2;
    let m = if big { 0.5 * m } else { m };
    let e = (bits >> 52) + big as u64;
    // k = e - 1023 as a float without an integer conversion (AVX2 has none for 64 bits).
    let k = f64::from_bits(TWO_52.to_bits() | e) - (TWO_52 + 1023.0);
    let f = m - 1.0;
    let hfsq = 0.5 * f * f;
    let s = f / (2.0 + f);
    let z = s * s;
    let w = z * z;
    let t1 = w * (LG2 + w * (LG4 + w * LG6));
    let t2 = z * (LG1 + w * (LG3 + w * (LG5 + w * LG7)));
    let r = t2 + t1;
    k * LN2_HI - ((hfsq - (s * (hfsq + r) + k * LN2_LO)) - f)
}

/// Exponential (fdlibm `e_exp.c`) of `x` clamped to `[-700, 700]`: `x = k ln 2 + r`,
/// `|r| <= ln 2 / 2`, `exp(r) = 1 + 2 r / (2 - c)` with `c = r - r^2 P(r^2)`, times `2^k`.
/// NaN gives an unspecified value; callers pass finite arguments.
#[inline(always)]
pub fn exp(x: Real) -> Real {
    const P1: Real = f64::from_bits(0x3FC5_5555_5555_553E);
    const P2: Real = f64::from_bits(0xBF66_C16C_16BE_BD93);
    const P3: Real = f64::from_bits(0x3F11_566A_AF25_DE2C);
    const P4: Real = f64::from_bits(0xBEBB_BD41_C5D2_6BF1);
    const P5: Real = f64::from_bits(0x3E66_3769_72BE_A4D0);
    /// `1.5 * 2^52`: `y + SHIFT - SHIFT` rounds `y` to the nearest whole number.
    const SHIFT: Real = 6_755_399_441_055_744.0;
    let x = if x > 700.0 { 700.0 } else { x };
    let x = if x < -700.0 { -700.0 } else { x };
    let t = x * std::f64::consts::LOG2_E + SHIFT;
    let k = t - SHIFT;
    let hi = x - k * LN2_HI;
    let lo = k * LN2_LO;
    let r = hi - lo;
    let r2 = r * r;
    let c = r - r2 * (P1 + r2 * (P2 + r2 * (P3 + r2 * (P4 + r2 * P5))));
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    // 2^k from the low bits of t, which hold k + 2^51 (two's complement for k < 0).
    let kbits = t.to_bits().wrapping_sub(SHIFT.to_bits());
    y * f64::from_bits(kbits.wrapping_add(1023) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two finite values of one sign.
    fn ulps(a: Real, b: Real) -> u64 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
    }

    /// Pseudo-random values in `[lo, hi)` (a fixed linear congruential sequence).
    fn samples(lo: Real, hi: Real, n: usize) -> impl Iterator<Item = Real> {
        let mut s: u64 = 0x2545_F491_4F6C_DD1D;
        (0..n).map(move |_| {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            lo + (hi - lo) * ((s >> 11) as Real / (1u64 << 53) as Real)
        })
    }

    #[test]
    fn logarithm_is_within_one_ulp_of_the_c_library() {
        // Squared elastic stretches lie near 1; the wider ranges cover extreme states.
        let near_one = samples(0.98, 1.02, 200_000);
        let moderate = samples(0.05, 20.0, 200_000);
        let powers = (-1000..1000).map(|e| (e as Real).exp2() * 1.3);
        let mut worst = 0;
        for x in near_one
            .chain(moderate)
            .chain(powers)
            .chain([1.0, 0.5, 2.0])
        {
            let (got, want) = (ln(x), x.ln());
            if want == 0.0 {
                assert_eq!(got, 0.0, "ln({x})");
                continue;
            }
            let d = ulps(got, want);
            assert!(d <= 1, "ln({x}) = {got:e}, C library {want:e}: {d} ulp");
            worst = worst.max(d);
        }
        assert!(worst <= 1);
    }

    #[test]
    fn exponential_is_within_one_ulp_of_the_c_library() {
        let small = samples(-0.05, 0.05, 200_000);
        let wide = samples(-700.0, 700.0, 200_000);
        for x in small
            .chain(wide)
            .chain([0.0, -0.0, 1.0, -1.0, 700.0, -700.0])
        {
            let (got, want) = (exp(x), x.exp());
            let d = ulps(got, want);
            assert!(d <= 1, "exp({x}) = {got:e}, C library {want:e}: {d} ulp");
        }
        // Clamped, not overflowing to infinity or zero.
        assert_eq!(exp(1e6), exp(700.0));
        assert_eq!(exp(-1e6), exp(-700.0));
    }
}
