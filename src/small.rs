//! The fast tier's small triangles: a triangle whose snapped box is under 8 px wide (so every span is shorter than the
//! fast span loop's [`MIN_SPAN`]) and under 127 px high, drawn with `Less`, depth write and no bias, whose vertices
//! lie inside the depth range with a margin and within a factor of 32 of each other in `T`. Set up and walked in one
//! out-of-line function with its own coverage and depth arithmetic, and no plane solve: no division and no 128-bit
//! product anywhere (the general set-up's are library calls on the 32-bit cores).
//!
//! **Coverage.** The three edge functions `E_k(P) = A_k (P.x - x_k) + B_k (P.y - y_k)` (`crate::edge`'s, oriented
//! so the inside is positive, less the top-left bias) are evaluated exactly in `i32` relative to the box's origin
//! pixel: coordinates there are below `2^15` sub-pixels, `|A_k| < 2^15`, `|B_k| < 2^11`, so `|E_k| < 2^28` at every
//! pixel centre of the box. A pixel is covered iff all three are `>= 0`: the top-left rule, exactly the general
//! walk's pixels. Each row of the box is scanned from its left column with the edge functions alone: past the
//! uncovered pixels, then to the end of the covered run (the triangle is convex); the depth loop then walks the run.
//!
//! **Depth without a plane solve.** The edge function of the edge opposite vertex `k` is `2A` (the doubled area) at
//! vertex `k` and 0 on that edge, so `S(P) = sum_k E_opp(k)(P) T'_k = 2A T'(P)`, with `T'(P)` the barycentric
//! interpolation of the vertices' `T'_k = round(T_k / 2^25)`. `S` is linear with integer steps: walked in wrapping
//! `u64` it is exact at every pixel, whatever the band (no rounding of steps at all). `T'_k <= 2^36` and
//! `2A < 2^27`; the triangle is taken when `bits(2A) + bits(T'_max) <= 63`, and `S` is pre-shifted by
//! `sh = 63 - bits(2A) - bits(T'_max)`, so every covered pixel's `S 2^sh` is below `2^63` (at least one leading zero). With `T'_min >= 2^31` (so `T_max / T_min < 32`), every covered `S` is at least `2^55`:
//! its high word is never 0 and has at most 8 leading zeros.
//!
//! **The code.** `code = 65535 2^F / T = K 2^(F - 25 + sh) / S` with `K = 65535 2A`, held as `kn 2^kz`
//! (`kn` in `[2^31, 2^32)`, rounded). Per pixel: `lz` the leading zeros of `S`'s high word, `m = (S << lz) >> 32`, the
//! fresh reciprocal `x = fresh61(m)` (`2^61 / m`, so `2^(93 - lz) / S`), `P = kn x` (64-bit), and
//! `code = round(P / 2^(118 - kz - F - sh - lz))`; that shift is at least 44, so the rounding needs only `P`'s high
//! word: `((hi >> (s - 1)) + 1) >> 1` with `s = 86 - kz - F - sh - lz` (floors of floors). The triangle is taken when
//! `s <= 31` at every pixel.
//!
//! **Which plane.** The `T_k` are the vertices' own where they lie on the snap grid; off it, the depth-grid plane's
//! `T` at the snapped vertices (`crate::raster::t_at_snapped`, below `T_min 2^-35` off), so that `S` interpolates the
//! plane through the vertices as given (to the depth grid), not the snapped ones.
//!
//! **Error** (relative, of the computed code's value against the exact `65535 2^F / T` of that plane):
//! `x` `2^-27.6` ([`fresh61`]); `m` truncated below `2^-31` (`m >= 2^31`); `kn` rounded, `2^-32`; `T'` rounded, half a
//! unit of `T'_min >= 2^31`, `2^-32`; the `T_k` off the grid, `2^-35`. Sum:
//! `4.95e-9 + 0.47e-9 + 0.23e-9 + 0.23e-9 + 0.03e-9 = 5.91e-9`, inside the tier's
//! [`FAST_MAX_REL_ERROR`] (`6.5e-9`), so the contract (every code within 1 LSB, at least 99.9% exact) holds as derived
//! there. The code never exceeds 65535 (`65535 (1 + 5.9e-9) < 65535.5`).
//!
//! **Range.** Every covered pixel's exact `T` lies in `[T_min, T_max]` (a convex combination); the triangle is taken
//! only when `T_min - margin >= t_lo` and `T_max + margin <= t_hi`, with a margin above the general set-up's plane
//! error, so every pixel the general path would draw is in range there too, and no pixel needs a range test here.
//!
//! **Colour.** Each covered run is tested pixel by pixel, each passing pixel a bit of a mask; the run goes to the
//! target as one `fill_solid` when every pixel passed, else as its passing runs, after the depth loop.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::depth::DepthBuffer;
#[cfg(doc)]
use crate::fast::FAST_MAX_REL_ERROR;
use crate::fast::{bits64 as bits, fresh61, lz_small, mul_hi, mul_wide, FreshSeed, MIN_SPAN};
use crate::raster::{rows_of, Setup, Stats, SUBPIXEL_BITS};
use crate::state::{Cull, RenderState};
use crate::Error;

/// The range margin, in units of `T`: above both general set-ups' plane error bounds (`128` units for the exact
/// solve; `T_min 2^-34 + 2^16` for `Plane::solve_fast`), so the general path would find every pixel in range too.
#[inline(always)]
fn margin(t_max: u64) -> u64 {
    (t_max >> 32) + (1 << 17)
}

/// Draws the snapped triangle `s` in `color` if it is a small triangle this path takes (see the module doc), with
/// `Less`, depth write and no bias (the caller's conditions). `Ok(None)`, having written nothing, where it does not
/// apply: the general path then draws it.
#[inline(never)]
pub(crate) fn draw<S: FreshSeed, D: DrawTarget>(
    target: &mut D,
    depth: &mut DepthBuffer<'_>,
    s: &Setup,
    state: &RenderState,
    color: D::Color,
) -> Result<Option<Stats>, Error> {
    // The depth-grid plane's `T` at the snapped vertices (the vertices' own where they lie on the snap grid): the
    // barycentric sum over the snapped triangle below is then the depth-grid plane.
    let st = if s.on_grid {
        s.t
    } else {
        match s.fast_t {
            Some(t) => t,
            None => return Ok(None),
        }
    };
    let p = s.p;
    let (xmin, xmax) = (
        p[0].x.min(p[1].x).min(p[2].x),
        p[0].x.max(p[1].x).max(p[2].x),
    );
    let (ymin, ymax) = (
        p[0].y.min(p[1].y).min(p[2].y),
        p[0].y.max(p[1].y).max(p[2].y),
    );
    if xmax - xmin >= (MIN_SPAN as i32) << SUBPIXEL_BITS || ymax - ymin >= 126 << SUBPIXEL_BITS {
        return Ok(None);
    }
    // Relative to the box's origin pixel: below 2^15 sub-pixels, so the doubled area fits i32.
    let (ox, oy) = (xmin >> SUBPIXEL_BITS, ymin >> SUBPIXEL_BITS);
    let q = p.map(|v| (v.x - (ox << SUBPIXEL_BITS), v.y - (oy << SUBPIXEL_BITS)));
    let area = (q[1].0 - q[0].0) * (q[2].1 - q[0].1) - (q[2].0 - q[0].0) * (q[1].1 - q[0].1);
    let culled = Stats {
        culled: 1,
        ..Stats::default()
    };
    match state.cull {
        _ if area == 0 => return Ok(Some(culled)),
        Cull::Cw if area > 0 => return Ok(Some(culled)),
        Cull::Ccw if area < 0 => return Ok(Some(culled)),
        _ => {}
    }
    let (q, t) = if area < 0 {
        ([q[0], q[2], q[1]], [st[0], st[2], st[1]])
    } else {
        (q, st)
    };
    let area2 = area.unsigned_abs() as u64;

    // Depth range and the conditions of the module doc.
    let t = t.map(|v| v as u64);
    let (t_min, t_max) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    let e = margin(t_max);
    let t_hi = state.range.t_max(s.frac);
    if t_min < e || t_min - e < 1u64 << s.frac || t_max + e > t_hi || t_min < 1 << 56 {
        return Ok(None);
    }
    let tp = t.map(|v| (v + (1 << 24)) >> 25); // T' = round(T / 2^25) in [2^31, 2^36]
    let tp_max = tp[0].max(tp[1]).max(tp[2]);
    let Some(sh) = 63u32.checked_sub(bits(area2) + bits(tp_max)) else {
        return Ok(None);
    };
    // K = 65535 2A = kn 2^kz, kn in [2^31, 2^32) rounded to nearest.
    let k = mul_wide(65535, area2 as u32); // area2 < 2^27 (box under 8 x 126 px)
    let kb = bits(k) as i32;
    let (kn, kz) = if kb > 32 {
        let r = (k + (1 << (kb - 33))) >> (kb - 32);
        if r >> 32 != 0 {
            (r >> 1, kb - 31)
        } else {
            (r, kb - 32)
        }
    } else {
        (k << (32 - kb), kb - 32)
    };
    let s0 = 86 - kz - s.frac as i32 - sh as i32; // the code's shift is s0 - lz, lz >= 1
    if s0 > 32 {
        return Ok(None);
    }
    let (kn, s0) = (kn as u32, s0 as u32);

    // Edges k -> k+1, opposite vertex k+2: E = A (x - x_k) + B (y - y_k) - bias.
    let edge = |a: (i32, i32), b: (i32, i32)| {
        let (ea, eb) = (a.1 - b.1, b.0 - a.0);
        let bias = i32::from(!(ea > 0 || (ea == 0 && eb > 0)));
        (ea, eb, a, bias)
    };
    let edges = [edge(q[0], q[1]), edge(q[1], q[2]), edge(q[2], q[0])];
    // S weights: edge k carries T' of vertex k + 2.
    let w = [tp[2], tp[0], tp[1]];

    // Rows and columns whose centres lie in the box, clipped to the buffer.
    let (j_first, j_last) = rows_of(&p);
    let j0 = j_first.max(depth.y0());
    let j1 = j_last.min(depth.y0() + depth.height() as i32 - 1);
    let i_first = (xmin - 128 + 255) >> SUBPIXEL_BITS; // ceil((xmin - 128) / 256)
    let i0 = i_first.max(0);
    let i1 = ((xmax - 128) >> SUBPIXEL_BITS).min(depth.width() as i32 - 1);
    let mut stats = Stats::default();
    if j0 > j1 || i0 > i1 {
        return Ok(Some(stats));
    }
    let ncol = (i1 - i0 + 1) as usize;
    // The edge functions and S at the centre of (i0, j0), and their steps per column and row.
    let (cx, cy) = (
        ((i0 - ox) << SUBPIXEL_BITS) + 128,
        ((j0 - oy) << SUBPIXEL_BITS) + 128,
    );
    let mut er = [0i32; 3];
    let (mut sr, mut sx, mut sy) = (0u64, 0u64, 0u64);
    let mut ex = [0i32; 3];
    let mut ey = [0i32; 3];
    for k in 0..3 {
        let (ea, eb, a, bias) = edges[k];
        er[k] = ea * (cx - a.0) + eb * (cy - a.1) - bias;
        ex[k] = ea << SUBPIXEL_BITS;
        ey[k] = eb << SUBPIXEL_BITS;
        sr = sr.wrapping_add((er[k] as i64 + bias as i64).wrapping_mul(w[k] as i64) as u64);
        sx = sx.wrapping_add((ex[k] as i64).wrapping_mul(w[k] as i64) as u64);
        sy = sy.wrapping_add((ey[k] as i64).wrapping_mul(w[k] as i64) as u64);
    }
    let (sr, sx, sy) = (sr << sh, sx << sh, sy << sh);

    let (mut sr, mut er) = (sr, er);
    for j in j0..=j1 {
        let row = &mut depth.row_mut(j)[i0 as usize..=i1 as usize];
        let [mut e0, mut e1, mut e2] = er;
        let mut v = sr;
        let mut k = 0usize;
        while k < ncol && (e0 | e1 | e2) < 0 {
            e0 += ex[0];
            e1 += ex[1];
            e2 += ex[2];
            v = v.wrapping_add(sx);
            k += 1;
        }
        let lo = k;
        // The covered run: edges only (the triangle is convex), then the depth loop over it with few live values.
        while k < ncol && (e0 | e1 | e2) >= 0 {
            e0 += ex[0];
            e1 += ex[1];
            e2 += ex[2];
            k += 1;
        }
        // Bit `n - 1 - i` for the run's pixel `i`.
        let mut pass = 0u32;
        for stored in row[lo..k].iter_mut() {
            let h = (v >> 32) as u32;
            let lz = lz_small(h);
            let m = (h << lz) | ((v as u32) >> (32 - lz));
            let hi = mul_hi(kn, fresh61::<S>(m) as u32);
            let c = (((hi >> (s0 - lz - 1)) + 1) >> 1) as u16;
            let ok = c < *stored;
            if ok {
                *stored = c;
            }
            pass = (pass << 1) | u32::from(ok);
            v = v.wrapping_add(sx);
        }
        let n = (k - lo) as u32;
        if n > 0 {
            stats.fragments += n;
            stats.written += emit(target, i0 + lo as i32, j, n, pass, color)?;
        }
        for (e, d) in er.iter_mut().zip(ey) {
            *e += d;
        }
        sr = sr.wrapping_add(sy);
    }
    Ok(Some(stats))
}

/// The passing runs of a run of `n <= 32` covered pixels from column `x0` of row `j`: bit `n - 1 - k` of `pass` set
/// for a written pixel `x0 + k`. Returns how many were written.
#[inline(always)]
fn emit<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    j: i32,
    n: u32,
    pass: u32,
    color: D::Color,
) -> Result<u32, Error> {
    #[inline(always)]
    fn fill_run<D: DrawTarget>(
        t: &mut D,
        x: i32,
        j: i32,
        len: u32,
        c: D::Color,
    ) -> Result<(), Error> {
        let r = Rectangle::new(Point::new(x, j), Size::new(len, 1));
        t.fill_solid(&r, c).map_err(|_| Error::Target)
    }
    if pass == u32::MAX >> (32 - n) {
        fill_run(target, x0, j, n, color)?;
        return Ok(n);
    }
    // Runs of set bits from the first pixel (bit n - 1) on: shifted to the top of a u64, whose leading zeros and
    // ones are the gap and the run (a u64 so that shifting out all 32 bits is defined).
    let (mut m, mut at) = ((pass as u64) << (64 - n), 0u32);
    while m != 0 {
        let skip = m.leading_zeros();
        m <<= skip;
        let len = (!m).leading_zeros();
        fill_run(target, x0 + (at + skip) as i32, j, len, color)?;
        m = m.checked_shl(len).unwrap_or(0);
        at += skip + len;
    }
    Ok(pass.count_ones())
}
