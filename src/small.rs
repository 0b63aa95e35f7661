//! The fast tier's small triangles: a triangle whose snapped box is under 8 px wide (so every span is shorter than the
//! fast span loop's [`MIN_SPAN`]) and under 127 px high, drawn with `Less` and
//! depth write, whose every vertex lies inside the depth range with a margin, walked by one out-of-line loop with
//! few live values (inlined into the general draw, the same work spilled most of its registers: 51 instructions a
//! pixel on the Cortex-M4 where this loop takes about 40).
//!
//! **Rows.** The edges and the plane of `T` are the fast tier's small set-up ([`crate::raster`]'s `prepare`): 32-bit
//! edge walks and the plane from one reciprocal of the area. Each row gives the covered columns `[lo, hi)`, exactly
//! the general walk's.
//!
//! **Range.** Every covered pixel's exact `T` is a convex combination of the vertices' (the plane through them), so
//! lies in `[T_min, T_max]`; the computed plane errs by at most `(1 + k + l) / 2 <= 128` units (the exact solve) or
//! `T_min 2^-34 + 2^16` units (`Plane::solve_fast`), both below [`margin`]. With `T_min - margin >= t_lo` and
//! `T_max + margin <= t_hi` every computed `T` is in range, so the loop tests none.
//!
//! **Depth.** Per row `V = T 65536 / 65535` at the row's first pixel ([`by_65535`], at most 4 units below) and its
//! step once per triangle ([`by_65535_signed`], at most 5 units off): after at most 126 steps `V` is within
//! `4 + 126 * 5 < 2^10` units of exact, and the loop runs only when every `V` is at least `2^50` (checked on the
//! vertices, less the margin), so below `2^-40` relative. Each pixel's code is [`fresh_code`]: a fresh reciprocal,
//! `2^-27.2` with its truncations. Total `2^-27.2 + 2^-40`, inside [`FAST_MAX_REL_ERROR`]'s `6.5e-9`
//! (`2^-27.2 = 6.46e-9`, `2^-40 < 1e-12`).
//!
//! **Colour.** A row's pixels are tested in chunks of 32, each passing pixel a bit of a mask; the runs of set bits
//! go to the target as `fill_solid` calls after the chunk (one call for a chunk that passes whole), so the depth
//! loop calls nothing.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::depth::DepthBuffer;
#[cfg(doc)]
use crate::fast::FAST_MAX_REL_ERROR;
use crate::fast::{by_65535, by_65535_signed, fresh_code, MIN_SPAN};
use crate::raster::{Plane, Stats, Walk, SUBPIXEL_BITS};
use crate::Error;

/// The plane's largest error at a covered pixel, in units of `T`, for a triangle whose largest vertex `T` is
/// `t_max`: above both set-ups' bounds (`128`, and `T_min 2^-34 + 2^16 <= t_max 2^-34 + 2^16`).
#[inline(always)]
fn margin(t_max: u64) -> u64 {
    (t_max >> 32) + (1 << 17)
}

/// Whether [`draw`] applies to the prepared small triangle `w` (the caller has checked the comparison, the depth
/// write and the bias): every pixel in range and `V` within [`fresh_code`]'s conditions.
#[inline(always)]
pub(crate) fn applies(w: &Walk) -> bool {
    let t = w.t_vertex.map(|t| t as u64);
    let (t_min, t_max) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    // Boxes under MIN_SPAN columns only: every span is short. Wider spans of small triangles keep the fast span
    // loop, whose chained reciprocal costs less per pixel than a fresh one (measured on the terrain scene).
    let x = w.geom.p.map(|p| p.x);
    if x[0].max(x[1]).max(x[2]) - x[0].min(x[1]).min(x[2]) >= (MIN_SPAN as i32) << SUBPIXEL_BITS {
        return false;
    }
    let e = margin(t_max);
    let (lo, hi) = (t_min.wrapping_sub(e), t_max + e);
    // t_min >= e keeps `lo` from wrapping; V(lo) >= lo >= 2^50; V(hi) < 2^62 as hi < 2^61 + 2^30.
    t_min >= e
        && lo >= 1 << 50
        && lo >= w.span.t_lo
        && hi <= w.span.t_hi
        && 77 - w.frac as i32 - by_65535(hi).leading_zeros() as i32 <= 31
}

/// Draws the prepared small triangle `w` (see [`applies`]) in `color`: `Less`, depth write, no bias.
#[inline(never)]
pub(crate) fn draw<D: DrawTarget>(
    target: &mut D,
    depth: &mut DepthBuffer<'_>,
    w: &mut Walk,
    color: D::Color,
) -> Result<Stats, Error> {
    let width = depth.width();
    let dv = by_65535_signed(w.t.sx) as u64;
    let base = 77 - w.frac;
    let mut stats = Stats::default();
    for j in w.geom.j0..=w.j1 {
        if let Some((lo, hi)) = w.row(width) {
            let mut v = by_65535(at_small(&w.t, (lo as i64 - w.geom.i_ref) as u32));
            let row = &mut depth.row_mut(j)[lo as usize..hi as usize];
            let mut x0 = lo;
            for chunk in row.chunks_mut(32) {
                // Bit `n - 1 - k` for pixel `k`: a shift and an OR a pixel.
                let mut pass = 0u32;
                for stored in chunk.iter_mut() {
                    let c = fresh_code(v, base);
                    let p = c < *stored;
                    if p {
                        *stored = c;
                    }
                    pass = (pass << 1) | u32::from(p);
                    v = v.wrapping_add(dv);
                }
                let n = chunk.len() as u32;
                stats.written += emit(target, x0, j, n, pass, color)?;
                x0 += n as i32;
            }
            stats.fragments += (hi - lo) as u32;
        }
        w.next_row();
    }
    Ok(stats)
}

/// `T` at `di` columns right of the plane's reference column, `0 <= di < 2^7` (a small triangle's box): the
/// wrapping `row + sx di` of [`Plane::at`] from two 16-bit halves of `sx`'s low word (each product below `2^23`)
/// and its high word, so no 64-bit multiply (a library call on the Cortex-M0).
#[inline(always)]
fn at_small(t: &Plane, di: u32) -> u64 {
    debug_assert!(di < 1 << 7);
    let sx = t.sx as u64;
    let (lo, hi) = (sx as u32, (sx >> 32) as u32);
    let low = ((((lo >> 16) * di) as u64) << 16) + ((lo & 0xffff) * di) as u64;
    (t.row as u64)
        .wrapping_add(low)
        .wrapping_add((hi.wrapping_mul(di) as u64) << 32)
}

/// The passing runs of a chunk of `n <= 32` pixels from column `x0` of row `j`: bit `n - 1 - k` of `pass` set for a
/// written pixel `x0 + k`. Returns how many were written.
#[inline(always)]
fn emit<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    j: i32,
    n: u32,
    pass: u32,
    color: D::Color,
) -> Result<u32, Error> {
    let fill = |target: &mut D, a: u32, len: u32| {
        let r = Rectangle::new(Point::new(x0 + a as i32, j), Size::new(len, 1));
        target.fill_solid(&r, color).map_err(|_| Error::Target)
    };
    if pass == u32::MAX >> (32 - n) {
        fill(target, 0, n)?;
        return Ok(n);
    }
    // Runs of set bits from the first pixel (bit n - 1) on: shifted to the top of a u64, whose leading zeros and
    // ones are the gap and the run (a u64 so that shifting out all 32 bits is defined).
    let (mut m, mut at) = ((pass as u64) << (64 - n), 0u32);
    while m != 0 {
        let skip = m.leading_zeros();
        m <<= skip;
        let len = (!m).leading_zeros();
        fill(target, at + skip, len)?;
        m = m.checked_shl(len).unwrap_or(0);
        at += skip + len;
    }
    Ok(pass.count_ones())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `at_small` is `Plane::at` for every column offset of a small box, on planes of any sign and size.
    #[test]
    fn at_small_is_the_plane() {
        let mut s = 0x1234_5678_9ABC_DEF1u64;
        for _ in 0..20_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let p = Plane {
                row: s as i64,
                sx: (s.rotate_left(17) as i64) >> (s % 40),
                sy: 0,
            };
            for di in 0..128u32 {
                assert_eq!(at_small(&p, di), p.at(di as i64) as u64);
            }
        }
    }
}
