//! Gather and scatter of a pair (q2 cell) or a quad (q4 cell) of points sharing a particle
//! list, with explicit 256-bit vectors: a neighbour's entries `[N.., N_x.., N_y..]` give
//! `F_xX`, `F_xY` of all the group's points from products with `d_x`, and `F_yX`, `F_yY`
//! from products with `d_y`. Each lane does the fused multiply-adds of
//! [`super::StressContext::gather`] and [`super::StressContext::scatter`] in their order (the generic
//! build's `mul_add` rounds once, as the FMA instruction does), so the bits are the
//! generic build's; left to itself the compiler splits these loops into 128-bit pieces and
//! shuffles (the quad gather took some 70 instructions per neighbour). `index` holds the
//! particles as offsets from the group's first particle, where `d` and `buf` start.

use crate::lanes::Lanes;
use crate::math::Real;
use std::arch::x86_64::*;

/// Loads 4 values.
#[inline(always)]
fn load4(x: &[Real]) -> __m256d {
    assert!(x.len() >= 4);
    // SAFETY: 4 values are in bounds (checked above).
    unsafe { _mm256_loadu_pd(x.as_ptr()) }
}

/// Loads 2 values.
#[inline(always)]
fn load2(x: &[Real]) -> __m128d {
    assert!(x.len() >= 2);
    // SAFETY: 2 values are in bounds (checked above).
    unsafe { _mm_loadu_pd(x.as_ptr()) }
}

/// The 4 values of a vector.
#[inline(always)]
fn store4(x: __m256d) -> [Real; 4] {
    let mut out = [0.0; 4];
    // SAFETY: `out` holds 4 values.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), x) };
    out
}

/// Adds `[b0, b1]` pairs to a buffer entry in order: `((b + p[0]) + p[1]) + ..`.
#[inline(always)]
fn add_to(b: &mut [Real; 2], pairs: &[__m128d]) {
    // SAFETY: `b` holds 2 values.
    unsafe {
        let mut acc = _mm_loadu_pd(b.as_ptr());
        for &p in pairs {
            acc = _mm_add_pd(acc, p);
        }
        _mm_storeu_pd(b.as_mut_ptr(), acc);
    }
}

/// `F` and `u_r` of a pair into lanes `l0, l0 + 1` of `f`; neighbour entries
/// `[N_1, N_2, N_1,x, N_2,x, N_1,y, N_2,y]`.
#[target_feature(enable = "avx2,fma")]
pub(super) fn gather2(
    index: &[u32],
    table: &[Real],
    d: &[[Real; 2]],
    f: &mut [Lanes; 5],
    l0: usize,
) {
    // [F_xX 1, F_xX 2, F_xY 1, F_xY 2] and [F_yX 1, F_yX 2, F_yY 1, F_yY 2].
    let mut fx = _mm256_setr_pd(1.0, 1.0, 0.0, 0.0);
    let mut fy = _mm256_setr_pd(0.0, 0.0, 1.0, 1.0);
    let mut ur = _mm_setzero_pd();
    for (&i, e) in index.iter().zip(table.chunks_exact(6)) {
        let di = d[i as usize];
        let (v, g) = (load2(e), load4(&e[2..]));
        fx = _mm256_fmadd_pd(_mm256_set1_pd(di[0]), g, fx);
        fy = _mm256_fmadd_pd(_mm256_set1_pd(di[1]), g, fy);
        ur = _mm_fmadd_pd(_mm_set1_pd(di[0]), v, ur);
    }
    let (a, b) = (store4(fx), store4(fy));
    let mut u = [0.0; 2];
    // SAFETY: `u` holds 2 values.
    unsafe { _mm_storeu_pd(u.as_mut_ptr(), ur) };
    f[0][l0..l0 + 2].copy_from_slice(&a[..2]);
    f[1][l0..l0 + 2].copy_from_slice(&a[2..]);
    f[2][l0..l0 + 2].copy_from_slice(&b[..2]);
    f[3][l0..l0 + 2].copy_from_slice(&b[2..]);
    f[4][l0..l0 + 2].copy_from_slice(&u);
}

/// `w_p (P grad N_I + e_r P_33 N_I / R_p)` of lanes `l0, l0 + 1` into `buf`.
#[target_feature(enable = "avx2,fma")]
pub(super) fn scatter2(
    index: &[u32],
    table: &[Real],
    pw: &[Lanes; 3],
    px: &[Lanes; 2],
    l0: usize,
    buf: &mut [[Real; 2]],
) {
    let w = |x: &Lanes| load2(&x[l0..]);
    let (wxx, wxy, wv, wyx, wyy) = (w(&pw[0]), w(&pw[1]), w(&pw[2]), w(&px[0]), w(&px[1]));
    for (&i, e) in index.iter().zip(table.chunks_exact(6)) {
        let (v, x, y) = (load2(e), load2(&e[2..]), load2(&e[4..]));
        // Per point j: fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R)), fma(P_yX, N_x, P_yY N_y).
        let sx = _mm_fmadd_pd(wxx, x, _mm_fmadd_pd(wxy, y, _mm_mul_pd(wv, v)));
        let sy = _mm_fmadd_pd(wyx, x, _mm_mul_pd(wyy, y));
        add_to(
            &mut buf[i as usize],
            &[_mm_unpacklo_pd(sx, sy), _mm_unpackhi_pd(sx, sy)],
        );
    }
}

/// `F` and `u_r` of a quad into lanes `l0..l0 + 4` of `f`; neighbour entries
/// `[N_1..N_4, N_1,x..N_4,x, N_1,y..N_4,y]`.
#[target_feature(enable = "avx2,fma")]
pub(super) fn gather4(
    index: &[u32],
    table: &[Real],
    d: &[[Real; 2]],
    f: &mut [Lanes; 5],
    l0: usize,
) {
    gather_quad(index, table, f, l0, |i| {
        let di = d[i];
        (_mm256_set1_pd(di[0]), _mm256_set1_pd(di[1]))
    });
}

/// The quad gather with each neighbour offset's `d_x` and `d_y` in the lanes from
/// `spread(i)`.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn gather_quad(
    index: &[u32],
    table: &[Real],
    f: &mut [Lanes; 5],
    l0: usize,
    spread: impl Fn(usize) -> (__m256d, __m256d),
) {
    let one = _mm256_set1_pd(1.0);
    let zero = _mm256_setzero_pd();
    let (mut fxx, mut fxy, mut fyx, mut fyy, mut ur) = (one, zero, zero, one, zero);
    for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
        let (d0, d1) = spread(i as usize);
        let (v, x, y) = (load4(e), load4(&e[4..]), load4(&e[8..]));
        fxx = _mm256_fmadd_pd(d0, x, fxx);
        fxy = _mm256_fmadd_pd(d0, y, fxy);
        fyx = _mm256_fmadd_pd(d1, x, fyx);
        fyy = _mm256_fmadd_pd(d1, y, fyy);
        ur = _mm256_fmadd_pd(d0, v, ur);
    }
    for (c, x) in [fxx, fxy, fyx, fyy, ur].into_iter().enumerate() {
        f[c][l0..l0 + 4].copy_from_slice(&store4(x));
    }
}

/// The weighted stresses `[w P_xX, w P_xY, w P_33 / R, w P_yX, w P_yY]` of lanes
/// `l0..l0 + 4`.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn quad_weights(pw: &[Lanes; 3], px: &[Lanes; 2], l0: usize) -> [__m256d; 5] {
    let w = |x: &Lanes| load4(&x[l0..]);
    [w(&pw[0]), w(&pw[1]), w(&pw[2]), w(&px[0]), w(&px[1])]
}

/// A quad's four contributions `[f_x, f_y]` for a neighbour's entries `e`, point by point:
/// `fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R))`, `fma(P_yX, N_x, P_yY N_y)`.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn quad_terms(w: &[__m256d; 5], e: &[Real]) -> [__m128d; 4] {
    let [wxx, wxy, wv, wyx, wyy] = *w;
    let (v, x, y) = (load4(e), load4(&e[4..]), load4(&e[8..]));
    let sx = _mm256_fmadd_pd(wxx, x, _mm256_fmadd_pd(wxy, y, _mm256_mul_pd(wv, v)));
    let sy = _mm256_fmadd_pd(wyx, x, _mm256_mul_pd(wyy, y));
    let (x01, y01) = (_mm256_castpd256_pd128(sx), _mm256_castpd256_pd128(sy));
    let (x23, y23) = (
        _mm256_extractf128_pd::<1>(sx),
        _mm256_extractf128_pd::<1>(sy),
    );
    [
        _mm_unpacklo_pd(x01, y01),
        _mm_unpackhi_pd(x01, y01),
        _mm_unpacklo_pd(x23, y23),
        _mm_unpackhi_pd(x23, y23),
    ]
}

/// `w_p (P grad N_I + e_r P_33 N_I / R_p)` of lanes `l0..l0 + 4` into `buf`.
#[target_feature(enable = "avx2,fma")]
pub(super) fn scatter4(
    index: &[u32],
    table: &[Real],
    pw: &[Lanes; 3],
    px: &[Lanes; 2],
    l0: usize,
    buf: &mut [[Real; 2]],
) {
    let w = quad_weights(pw, px, l0);
    for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
        add_to(&mut buf[i as usize], &quad_terms(&w, e));
    }
}

/// [`gather4`] for a strip ([`crate::solver::layout::Scatter::strip`]): lanes `l0, l0 + 1`
/// read particle `i`, lanes `l0 + 2, l0 + 3` particle `i + 1`, both loaded as one vector
/// `[x_i, y_i, x_i+1, y_i+1]` and spread to `[x_i, x_i, x_i+1, x_i+1]` and the `y` likewise.
#[target_feature(enable = "avx2,fma")]
pub(super) fn gather_strip(
    index: &[u32],
    table: &[Real],
    d: &[[Real; 2]],
    f: &mut [Lanes; 5],
    l0: usize,
) {
    gather_quad(index, table, f, l0, |i| {
        let pair = load4(d[i..i + 2].as_flattened());
        (_mm256_movedup_pd(pair), _mm256_permute_pd::<0b1111>(pair))
    });
}

/// [`scatter4`] for a strip: particle `i` takes lanes `l0, l0 + 1` at its offset and then
/// lanes `l0 + 2, l0 + 3` at the offset one below (held from the last offset when the
/// offsets run on), in that order.
#[target_feature(enable = "avx2,fma")]
pub(super) fn scatter_strip(
    index: &[u32],
    table: &[Real],
    pw: &[Lanes; 3],
    px: &[Lanes; 2],
    l0: usize,
    buf: &mut [[Real; 2]],
) {
    let w = quad_weights(pw, px, l0);
    let mut pending: Option<(usize, [__m128d; 2])> = None;
    for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
        let i = i as usize;
        let [a, b, c, d] = quad_terms(&w, e);
        let first = [a, b];
        match pending {
            Some((j, second)) if j == i => {
                add_to(&mut buf[i], &[first[0], first[1], second[0], second[1]])
            }
            Some((j, second)) => {
                add_to(&mut buf[j], &second);
                add_to(&mut buf[i], &first);
            }
            None => add_to(&mut buf[i], &first),
        }
        pending = Some((i + 1, [c, d]));
    }
    if let Some((j, second)) = pending {
        add_to(&mut buf[j], &second);
    }
}
