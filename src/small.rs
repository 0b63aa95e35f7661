//! The fast tier's small triangles: a triangle whose snapped box is under 32 px wide (so a row's run has at most 32
//! pixels, one bit each in a `u32` pass mask) and under 127 px high, drawn with `Less`, depth write and no bias,
//! whose vertices lie inside the depth range with a margin and within a factor of 32 of each other in `T`. Set up
//! and walked in one out-of-line function with its own coverage and depth arithmetic, and no plane solve: no 128-bit
//! product and no 64-bit division anywhere (the general set-up's are library calls on the 32-bit cores). Measured on
//! the boards, this path is cheaper than the general set-up and span walk up to that width: the torus (W4) costs 16%
//! fewer instructions on the Cortex-M4 and 12% fewer on the M0 than with the earlier 8 px limit (the scenes W1 to W3
//! do not change).
//!
//! **Coverage.** The three edge functions `E_k(P) = A_k (P.x - x_k) + B_k (P.y - y_k)` (`crate::edge`'s, oriented
//! so the inside is positive, less the top-left bias) are evaluated exactly in `i32` relative to the box's origin
//! pixel: `x` below `2^14` and `y` below `2^15` sub-pixels, `|A_k| < 2^15`, `|B_k| < 2^13`, so
//! `|E_k| < 2^29 + 2^28` at every pixel centre of the box. A pixel is covered iff all three are `>= 0`: the top-left
//! rule, exactly the general walk's pixels. Each row's covered run is found either from the column bounds of the two
//! edges that bound the row (the long edge and one short one, [`Halves`]): each bound either by one division a row,
//! which gives the exact column (`crate::edge::DivBound`), or by stepping its edge function from the bound's column
//! on the row above to where its sign turns ([`Step`]): [`ROWS_BY_DIVISION`] says which core takes which.
//! The depth loop then walks the run.
//!
//! **Depth without a plane solve.** The edge function of the edge opposite vertex `k` is `2A` (the doubled area) at
//! vertex `k` and 0 on that edge, so `S(P) = sum_k E_opp(k)(P) T'_k = 2A T'(P)`, with `T'(P)` the barycentric
//! interpolation of the vertices' `T'_k = round(T_k / 2^25)`. `S` is linear with integer steps: walked in wrapping
//! `u64` it is exact at every pixel, whatever the band (no rounding of steps at all); the Cortex-M0 forms its start
//! and steps from fewer wide products, the same integers ([`s_by_differences`]). `T'_k <= 2^36` and
//! `2A < 2^29`; the triangle is taken when `bits(2A) + bits(T'_max) <= 63`, and `S` is pre-shifted by
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
//! `T` at the snapped vertices (`crate::setup::t_at_snapped`, below `T_min 2^-35` off), so that `S` interpolates the
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
use crate::edge::{flat_rows, DivBound, Sub};
#[cfg(doc)]
use crate::fast::FAST_MAX_REL_ERROR;
use crate::fast::{
    bits64 as bits, fresh61, lz_small, mul_small, mul_wide, shl64, shr64, smul_wide, wmul,
    FreshSeed, HiFactor,
};
use crate::setup::{rows_of, Setup, Stats, SUBPIXEL_BITS};
use crate::state::{Cull, RenderState};
use crate::Error;

/// The range margin, in units of `T`: above both general set-ups' plane error bounds (`128` units for the exact
/// solve; `T_min 2^-34 + 2^16` for `Plane::solve_fast`), so the general path would find every pixel in range too.
#[inline(always)]
fn margin(t_max: u64) -> u64 {
    (t_max >> 32) + (1 << 17)
}

/// What a band keeps of a small triangle it drew for the next band of the frame ([`crate::setup::Remember::Small`]):
/// `S` pre-shifted at the centre of the box's origin pixel (column `ox`, row `oy`) and its steps a column and a row,
/// the code's shift `s0`, and the leading zeros where they are the same at every covered pixel (see `draw_as`). A
/// function of the triangle (its snapped vertices and their `T`) and the far plane alone, so a remembered one draws
/// exactly what a computed one does; the next band skips the depth range's checks, `T'`, the products of `S` and the
/// leading zeros (on the Cortex-M0's W4, about half of this path's set-up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kept {
    pub(crate) s_o: u64,
    pub(crate) sx: u64,
    pub(crate) sy: u64,
    /// `s0` (at most 32, at least 1) in the low byte, and in the high byte 1 more than the leading zeros where they
    /// are the same at every pixel (at most 8), else 0: not zero, so an `Option<Kept>` takes no more room (the
    /// Cortex-M0's stack).
    pub(crate) shifts: core::num::NonZeroU16,
}

impl Kept {
    /// The code's shift `s0`.
    #[inline(always)]
    pub(crate) fn s0(&self) -> u32 {
        (self.shifts.get() & 0xff) as u32
    }
    /// The leading zeros of `S` where they are the same at every covered pixel.
    #[inline(always)]
    pub(crate) fn lz(&self) -> Option<u32> {
        let z = (self.shifts.get() >> 8) as u32;
        (z != 0).then(|| z - 1)
    }
}

/// Draws the snapped triangle `s` in `color` if it is a small triangle this path takes (see the module doc), with
/// `Less`, depth write and no bias (the caller's conditions). `Ok(None)`, having written nothing, where it does not
/// apply: the general path then draws it. With `KEEP`, `kept` holds on entry what an earlier band of the frame kept
/// of it (then it is taken), and on return what to keep for the next band, where the triangle has rows below this
/// band's (`None` otherwise; one place for both, for the Cortex-M0's stack).
#[inline(never)]
pub(crate) fn draw<S: FreshSeed, D: DrawTarget, const KEEP: bool>(
    target: &mut D,
    depth: &mut DepthBuffer<'_>,
    s: &Setup,
    state: &RenderState,
    color: D::Color,
    kept: &mut Option<Kept>,
) -> Result<Option<Stats>, Error> {
    draw_as::<S, D, ROWS_BY_DIVISION, KEEP>(target, depth, s, state, color, kept)
}

/// [`draw`], finding each row's run by division (`DIV`) or by stepping (see [`ROWS_BY_DIVISION`]).
#[inline(always)]
fn draw_as<S: FreshSeed, D: DrawTarget, const DIV: bool, const KEEP: bool>(
    target: &mut D,
    depth: &mut DepthBuffer<'_>,
    s: &Setup,
    state: &RenderState,
    color: D::Color,
    kept: &mut Option<Kept>,
) -> Result<Option<Stats>, Error> {
    let p = s.p;
    let (xmin, xmax) = (
        p[0].x.min(p[1].x).min(p[2].x),
        p[0].x.max(p[1].x).max(p[2].x),
    );
    let (ymin, ymax) = (
        p[0].y.min(p[1].y).min(p[2].y),
        p[0].y.max(p[1].y).max(p[2].y),
    );
    if xmax - xmin >= 32 << SUBPIXEL_BITS || ymax - ymin >= 126 << SUBPIXEL_BITS {
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
    // `crate::setup::culls_area`'s rule, written out: through that function this function compiled differently (not
    // in the test: its registers throughout), and the Cortex-M4's W3 took 18 more instructions a triangle (2,322.5
    // against 2,304.3 in the single-scene build). `the_cull_rule_is_written_out_the_same` keeps the two the same.
    match state.cull {
        _ if area == 0 => return Ok(Some(culled)),
        Cull::Cw if area > 0 => return Ok(Some(culled)),
        Cull::Ccw if area < 0 => return Ok(Some(culled)),
        _ => {}
    }
    let q = if area < 0 { [q[0], q[2], q[1]] } else { q };
    let area2 = area.unsigned_abs() as u64;
    // Rows whose centres lie in the box, less a horizontal bottom edge's own row, clipped to the buffer.
    let pa = if area < 0 { [p[0], p[2], p[1]] } else { p };
    let (j_first, j_last) = flat_rows(&pa, rows_of(&pa));
    let j0 = j_first.max(depth.y0());
    let j1 = j_last.min(depth.y0().saturating_add(depth.height() as i32 - 1));
    // S at the centre of the box's origin column `ox` on row `j0`, and its steps per column and row; a covered
    // pixel's column is at least `ox` (its centre is right of `xmin >= 256 ox`).
    let cy = ((j0 - oy) << SUBPIXEL_BITS) + 128;
    // Without `KEEP` no band keeps anything (a constant: the branch is not compiled).
    let remembered = kept.take().filter(|_| KEEP);
    // No row in the buffer: nothing to draw (the general path would find none either).
    if j0 > j1 {
        return Ok(Some(Stats::default()));
    }
    let (walk, keep) = match remembered {
        Some(k) => {
            let (kn, _) = code_factor(area2);
            // `S` (pre-shifted, modulo 2^64) moved from the origin's row to `j0`: the same bits as computed there.
            let walk = Walk {
                j0,
                j1,
                ox,
                sr: k.s_o.wrapping_add(mul_small(k.sy, (j0 - oy) as u32)),
                sx: k.sx,
                sy: k.sy,
                kn,
                s0: k.s0(),
                lz: k.lz(),
            };
            (walk, (j_last > j1).then_some(k))
        }
        None => {
            let Some((walk, keep)) =
                constants::<KEEP>(s, state, &q, area, area2, (ox, oy), (j0, j1, j_last), cy)
            else {
                return Ok(None);
            };
            (walk, keep)
        }
    };
    // The box's columns from `ox` (a covered pixel's centre is at most `xmax`).
    let ncol = ((xmax - 128) >> SUBPIXEL_BITS) - ox + 1;
    let stats = if DIV {
        let Some(halves) = Halves::<DivBound>::new(&pa, (j0, j1), (ox, oy), ncol) else {
            return Ok(None);
        };
        walk.rows::<S, D, _>(target, depth, halves, color)?
    } else {
        let Some(halves) = Halves::<Step>::new(&pa, (j0, j1), (ox, oy), ncol) else {
            return Ok(None);
        };
        walk.rows::<S, D, _>(target, depth, halves, color)?
    };
    if KEEP {
        *kept = keep;
    }
    Ok(Some(stats))
}

#[cfg(test)]
std::thread_local! {
    /// The snapped vertices of each triangle whose depth constants [`constants`] computed and accepted, on this
    /// thread (the memo's tests count what it saves).
    pub(crate) static SMALL_CONSTANTS: core::cell::RefCell<std::vec::Vec<[(i32, i32); 3]>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
}

/// Edge `k -> k+1` of the oriented triangle `q` (relative to the box's origin pixel) at the centre of the origin
/// column on the row whose centre is `cy` sub-pixels below the origin: its edge function `E` (`|E| < 2^28`, the
/// module doc; without the top-left bias, which only coverage takes: [`Halves`]), and its steps a column and a row.
#[inline(always)]
fn edge_at(q: &[(i32, i32); 3], k: usize, cy: i32) -> (i32, i32, i32) {
    let (a, c) = (q[k], q[(k + 1) % 3]);
    let (ea, eb) = (a.1 - c.1, c.0 - a.0);
    let er = ea * (128 - a.0) + eb * (cy - a.1);
    (er, ea << SUBPIXEL_BITS, eb << SUBPIXEL_BITS)
}

/// `K = 65535 2A = kn 2^kz` for the doubled area `area2` (below `2^29`: the box is under 32 x 126 px), `kn` in
/// `[2^31, 2^32)` rounded to nearest.
#[inline(always)]
fn code_factor(area2: u64) -> (u32, i32) {
    let k = mul_wide(65535, area2 as u32);
    let kb = bits(k) as i32;
    let (kn, kz) = if kb > 32 {
        let r = shr64(k + shl64(1, (kb - 33) as u32), (kb - 32) as u32);
        if r >> 32 != 0 {
            (r >> 1, kb - 31)
        } else {
            (r, kb - 32)
        }
    } else {
        (shl64(k, (32 - kb) as u32), kb - 32)
    };
    (kn as u32, kz)
}

/// [`draw_as`]'s depth constants of a triangle no band kept ([`Kept`]): the walk from row `j0` (and, with `KEEP`,
/// what to keep where the triangle has rows below `j1`); `None` where the triangle is not one this path takes.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn constants<const KEEP: bool>(
    s: &Setup,
    state: &RenderState,
    q: &[(i32, i32); 3],
    area: i32,
    area2: u64,
    (ox, oy): (i32, i32),
    (j0, j1, j_last): (i32, i32, i32),
    cy: i32,
) -> Option<(Walk, Option<Kept>)> {
    // The depth-grid plane's `T` at the snapped vertices (the vertices' own where they lie on the snap grid): the
    // barycentric sum over the snapped triangle below is then the depth-grid plane.
    let st = if s.on_grid { s.t } else { s.fast_t? };
    let t = if area < 0 { [st[0], st[2], st[1]] } else { st };

    // Depth range and the conditions of the module doc.
    let t = t.map(|v| v as u64);
    let (t_min, t_max) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    let margin = margin(t_max);
    let t_hi = state.range.t_max(s.frac);
    // `T_min - margin < 2^F` by its bit count (no 64-bit shift: a library call on the Cortex-M0, a sequence elsewhere).
    if t_min < margin || bits(t_min - margin) <= s.frac || t_max + margin > t_hi || t_min < 1 << 56
    {
        return None;
    }
    let tp = t.map(|v| (v + (1 << 24)) >> 25); // T' = round(T / 2^25) in [2^31, 2^36]
                                               // The rounding is monotone: the extremes of `T'` are those of `T`, rounded. So on the Cortex-M4 (M4 W3 -0.5%);
                                               // the other cores take them from `T'` (this way measured W3 +0.4% on the M0, +2.5% on RV32), the M0 where it
                                               // needs the smallest.
    #[cfg(all(target_arch = "arm", target_has_atomic = "32"))]
    let (tp_max, tp_min) = ((t_max + (1 << 24)) >> 25, (t_min + (1 << 24)) >> 25);
    #[cfg(not(all(target_arch = "arm", target_has_atomic = "32")))]
    let tp_max = tp[0].max(tp[1]).max(tp[2]);
    let sh = 63u32.checked_sub(bits(area2) + bits(tp_max))?;
    let (kn, kz) = code_factor(area2);
    let s0 = 86 - kz - s.frac as i32 - sh as i32; // the code's shift is s0 - lz, lz >= 1
    if s0 > 32 {
        return None;
    }
    let s0 = s0 as u32;

    // S weights: the edge k -> k+1 carries T' of vertex k + 2.
    let w = [tp[2], tp[0], tp[1]];
    let (mut ex, mut ey) = ([0i32; 3], [0i32; 3]);
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    let (mut sr, mut sx, mut sy) = (0u64, 0u64, 0u64);
    // The Cortex-M0 (no 32 x 32 -> 64 multiply) takes `S` by differences ([`s_by_differences`]), the other cores
    // the sum of the three products in the loop; chosen by `cfg`, not by a constant's branch (with the M0's code
    // present but not taken, LLVM allocated this function's registers differently on RV32: W3 +1.6%).
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    let mut er_m0 = [0i32; 3];
    for k in 0..3 {
        let er;
        (er, ex[k], ey[k]) = edge_at(q, k, cy);
        #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
        {
            er_m0[k] = er;
        }
        // The products modulo 2^64 (the walk wraps).
        #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
        {
            sr = sr.wrapping_add(wmul(er, w[k]));
            sx = sx.wrapping_add(wmul(ex[k], w[k]));
            sy = sy.wrapping_add(wmul(ey[k], w[k]));
        }
    }
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    let (sr, sx, sy, (s_max, s_min)) = {
        let tp_min = tp[0].min(tp[1]).min(tp[2]);
        s_by_differences(&er_m0, &ex, &ey, &w, area2 as i32, tp_max, tp_min)
    };
    // Every covered pixel's `S 2^sh` lies between its values at the smallest and the largest vertex `T'` (a convex
    // combination): where those two have the same leading zeros, so has every pixel, and the loop takes them once.
    #[cfg(not(target_arch = "arm"))]
    let tp_min = tp[0].min(tp[1]).min(tp[2]);
    // `2A T'` below 2^63 (`bits(2A) + bits(T'_max) <= 63`), so the wrapping product is exact; `2A < 2^29`.
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    let (lz, same) = {
        // The leading zeros of the high word of `2A T' 2^sh` (below `2^63`, at least `2^55`): those of `2A T'`
        // less `sh`.
        let lz_of = |t: u64| 64 - bits(wmul(area2 as i32, t)) - sh;
        let lz = lz_of(tp_max);
        (lz, lz_of(tp_min) == lz)
    };
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    let (lz, same) = {
        let lz_of = |s: u64| lz_small((shl64(s, sh) >> 32) as u32);
        let lz = lz_of(s_max);
        (lz, lz_of(s_min) == lz)
    };
    // Where the leading zeros are the same, `S` is walked pre-shifted by them too ([`Walk::rows`]), in the same
    // shift: `sh + lz <= 30 + 8` (`sh <= 63 - 1 - 32`, and `S 2^sh >= 2^55` leaves at most 8 leading zeros).
    let shift = sh + if same { lz } else { 0 };
    let walk = Walk {
        j0,
        j1,
        ox,
        sr: shl64(sr, shift),
        sx: shl64(sx, shift),
        sy: shl64(sy, shift),
        kn,
        s0,
        lz: same.then_some(lz),
    };
    #[cfg(test)]
    SMALL_CONSTANTS.with(|c| c.borrow_mut().push(s.p.map(|p| (p.x, p.y))));
    // `S` moved back to the origin's row (exact modulo 2^64, as the walk), for a band that starts lower.
    // `s0 <= 32` and `lz <= 32`: a byte each.
    let shifts = s0 | walk.lz.map_or(0, |z| z + 1) << 8;
    let keep = match core::num::NonZeroU16::new(shifts as u16) {
        Some(shifts) if KEEP && j_last > j1 => Some(Kept {
            s_o: walk.sr.wrapping_sub(mul_small(walk.sy, (j0 - oy) as u32)),
            sx: walk.sx,
            sy: walk.sy,
            shifts,
        }),
        _ => None,
    };
    Some((walk, keep))
}

/// How the rows find their covered runs: by division where the core divides in one instruction (the Cortex-M4 and
/// RV32IMAC), by stepping the edge functions from the row above's bounds where it does not (the Cortex-M0: a division
/// is a library call of some 60 instructions, two a row). Both give exactly the pixels whose three edge functions are
/// `>= 0` (the unit tests compare them).
const ROWS_BY_DIVISION: bool = !cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// Each row's covered run from the two edges that bound it: sorted by `y`, the triangle's rows above its middle
/// vertex lie between the long edge (top to bottom vertex) and the top short edge, and the rows from it down between
/// the long edge and the bottom short edge. (Above the middle vertex the region between the long and the top edge lies
/// strictly inside the bottom edge's half-plane, which it meets only at the middle vertex, so that edge's function is
/// positive there and it binds no pixel; likewise below. On the row through the middle vertex both short edges cross
/// the row at the vertex, on the same side, with the same bias: either gives the same bound.) Each bound is one
/// division a row ([`DivBound`]: the exact columns, no division at set-up) or a few steps from the row above's
/// ([`Step`]), and the bottom edge takes the top edge's place once, at the middle vertex's row.
struct Halves<B> {
    l: B,
    r: B,
    /// The bottom short edge, positioned at its first row, and whether it replaces the right bound (else the left).
    next: B,
    next_right: bool,
    /// The row where `next` takes over (`i32::MAX`: none within the triangle's rows).
    from: i32,
}

impl<B: Bound> Halves<B> {
    /// The oriented snapped triangle `p`'s bounds from row `j0` to `j1`, relative to the box's origin pixel
    /// `(ox, oy)`, the box `ncol` columns wide (`None` where the triangle is not as the rows need: not reached for a
    /// triangle of positive area, whose long edge is not horizontal and whose short edges lie on the other side; the
    /// general path then draws it).
    #[inline(always)]
    fn new(
        p: &[Sub; 3],
        (j0, j1): (i32, i32),
        (ox, oy): (i32, i32),
        ncol: i32,
    ) -> Option<Halves<B>> {
        // Rotated (the orientation kept) so that vertex 0 is a topmost one; the directed edges are then `0 -> 1`,
        // `1 -> 2`, `2 -> 0`, and the bottom vertex is 1 or 2.
        let q = if p[0].y <= p[1].y && p[0].y <= p[2].y {
            *p
        } else if p[1].y <= p[2].y {
            [p[1], p[2], p[0]]
        } else {
            [p[2], p[0], p[1]]
        };
        // (long edge, top short edge, bottom short edge, the middle vertex's y).
        let (long_e, top_e, bottom_e, ym) = if q[1].y >= q[2].y {
            ((q[0], q[1]), (q[2], q[0]), (q[1], q[2]), q[2].y)
        } else {
            ((q[2], q[0]), (q[0], q[1]), (q[1], q[2]), q[1].y)
        };
        // The directed edge `(a, b)`, positioned at row `j`: whether it bounds the left side, and its bound.
        let edge = |(a, b): (Sub, Sub), j: i32| B::new(a, b, j, (ox, oy), ncol);
        // The first row whose centre is at or below the middle vertex.
        let jm = (ym - 128 + 255) >> SUBPIXEL_BITS;
        let (long_left, long) = edge(long_e, j0)?;
        let (short_left, short) = if jm > j0 {
            edge(top_e, j0)?
        } else {
            edge(bottom_e, j0)?
        };
        let (next, from) = if jm > j0 && jm <= j1 {
            let (next_left, next) = edge(bottom_e, jm)?;
            if next_left == long_left {
                return None;
            }
            (next, jm)
        } else {
            (short, i32::MAX)
        };
        if short_left == long_left {
            return None;
        }
        let (l, r) = if long_left {
            (long, short)
        } else {
            (short, long)
        };
        Some(Halves {
            l,
            r,
            next,
            next_right: long_left,
            from,
        })
    }
}

impl<B: Bound> Halves<B> {
    /// The current row's covered run `[lo, hi)` (columns of the frame; empty when `lo >= hi`).
    #[inline(always)]
    fn run(&mut self, ox: i32) -> (i32, i32) {
        (ox + self.l.lo(), ox + self.r.hi())
    }
    #[inline(always)]
    fn step(&mut self) {
        self.l.step();
        self.r.step();
    }
    /// The first row of the second stretch (`i32::MAX`: one stretch), where [`Halves::second`] switches edges.
    #[inline(always)]
    fn second_from(&self) -> i32 {
        self.from
    }
    /// The bottom short edge takes the top one's place.
    #[inline(always)]
    fn second(&mut self) {
        if self.next_right {
            self.r = self.next;
        } else {
            self.l = self.next;
        }
    }
}

/// One edge's bound on the current row for [`Halves`], relative to the box's origin column.
trait Bound: Copy {
    /// The directed edge `a -> b` at row `j`, relative to the pixel `(ox, oy)` (the box `ncol` columns wide):
    /// whether it bounds the left side, and its bound; `None` for a horizontal edge.
    fn new(a: Sub, b: Sub, j: i32, o: (i32, i32), ncol: i32) -> Option<(bool, Self)>;
    /// A left edge's first admitted column (0 where that is left of the box).
    fn lo(&mut self) -> i32;
    /// A right edge's column one past its last admitted one (at most 0 where that is left of the box).
    fn hi(&mut self) -> i32;
    /// Moves to the next row.
    fn step(&mut self);
}

impl Bound for DivBound {
    #[inline(always)]
    fn new(a: Sub, b: Sub, j: i32, (ox, oy): (i32, i32), _: i32) -> Option<(bool, DivBound)> {
        DivBound::new(a, b, j, ox, oy)
    }
    #[inline(always)]
    fn lo(&mut self) -> i32 {
        DivBound::lo(self)
    }
    #[inline(always)]
    fn hi(&mut self) -> i32 {
        DivBound::hi(self)
    }
    #[inline(always)]
    fn step(&mut self) {
        DivBound::step(self)
    }
}

/// One edge's bound found by stepping from where it was on the row above, for cores that divide by a library call
/// (the Cortex-M0): a bound moves little from row to row, so a row costs a few steps. It replaced a scan of each row
/// from the box's left column (one step a column up to the run's end, with all three edge functions): measured on
/// the M0 (`Fast`, `--features size-probe`): W3 -4.7% (12,334,061 to 11,755,748 instructions), the terrain -9.3%,
/// W4 -4.1% (60,126,781 to 57,634,223 over its 8 frames).
///
/// Its column `k` (relative to the box's origin, in `[0, ncol]`, `ncol` the box's columns), its edge function
/// less the bias there on the current row (`e`; below `2^30` in magnitude at any column of the box and one past it:
/// the module doc's `2^29 + 2^28` and a column's step, below `2^23`), and its steps a column (`ex`, `256 A`) and a row (`ey`, `256 B`). The edge function
/// grows to the right along a left edge (`ex > 0`), which admits the columns from
/// `L = min {k in [0, ncol] : e(k) >= 0}` (`ncol` for none), and falls along a right edge (`ex < 0`), which admits those
/// below `R = min {k in [0, ncol] : k = ncol or e(k) < 0}`. Both are where a monotone sequence changes sign, so
/// stepping from the last row's to where the inequality turns finds them exactly; they are [`DivBound`]'s clamped to
/// `[0, ncol]`, which changes no run (a nonempty run lies in the box), as the unit tests check.
#[derive(Clone, Copy, Debug)]
struct Step {
    k: i32,
    e: i32,
    ex: i32,
    ey: i32,
    ncol: i32,
}

impl Bound for Step {
    /// A left edge starts at column 0, a right edge at `ncol` (the box's ends). (From the column of the edge's end
    /// nearer to the row in `y` instead, measured on the Cortex-M0: W3 +1.1%, W4 +0.7%.)
    #[inline(always)]
    fn new(a: Sub, b: Sub, j: i32, (ox, oy): (i32, i32), ncol: i32) -> Option<(bool, Step)> {
        let (a_, n, ey, _) = crate::edge::small_edge(a, b, j, ox, oy)?;
        let ex = a_ << SUBPIXEL_BITS;
        let left = a_ > 0;
        let k = if left { 0 } else { ncol };
        Some((
            left,
            Step {
                k,
                e: n + k * ex,
                ex,
                ey,
                ncol,
            },
        ))
    }
    #[inline(always)]
    fn lo(&mut self) -> i32 {
        let (mut k, mut e, ex, ncol) = (self.k, self.e, self.ex, self.ncol);
        if e >= 0 {
            while k > 0 && e - ex >= 0 {
                e -= ex;
                k -= 1;
            }
        } else {
            while k < ncol && e < 0 {
                e += ex;
                k += 1;
            }
        }
        (self.k, self.e) = (k, e);
        k
    }
    #[inline(always)]
    fn hi(&mut self) -> i32 {
        let (mut k, mut e, ex, ncol) = (self.k, self.e, self.ex, self.ncol);
        if k < ncol && e >= 0 {
            while k < ncol && e >= 0 {
                e += ex;
                k += 1;
            }
        } else {
            while k > 0 && e - ex < 0 {
                e -= ex;
                k -= 1;
            }
        }
        (self.k, self.e) = (k, e);
        k
    }
    #[inline(always)]
    fn step(&mut self) {
        self.e += self.ey;
    }
}

/// The row walk: rows `j0..=j1`, S (pre-shifted) at column `ox` of the current row and its steps, the code's
/// constants.
struct Walk {
    j0: i32,
    j1: i32,
    ox: i32,
    sr: u64,
    sx: u64,
    sy: u64,
    kn: u32,
    s0: u32,
    /// The leading zeros of every covered pixel's `S` where they are the same (see `draw_as`).
    lz: Option<u32>,
}

impl Walk {
    #[inline(always)]
    fn rows<S: FreshSeed, D: DrawTarget, B: Bound>(
        self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        runs: Halves<B>,
        color: D::Color,
    ) -> Result<Stats, Error> {
        match self.lz {
            // `S` walked pre-shifted by its leading zeros too (exact: the walk is exact modulo 2^64, and every covered
            // pixel's shifted `S` has its top bit set), so that each pixel's normalised `m` is the high word.
            Some(lz) => self.rows_as::<S, D, B, true>(target, depth, runs, color, lz),
            None => self.rows_as::<S, D, B, false>(target, depth, runs, color, 0),
        }
    }

    /// [`Walk::rows`], with the leading zeros of `S` the same at every covered pixel (`SAME_LZ`, `lz0`; `S` walked
    /// pre-shifted by them) or found per pixel. The same bits either way: only where the work is done differs.
    #[inline(always)]
    fn rows_as<S: FreshSeed, D: DrawTarget, B: Bound, const SAME_LZ: bool>(
        self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        mut runs: Halves<B>,
        color: D::Color,
        lz0: u32,
    ) -> Result<Stats, Error> {
        let depth_y0 = depth.y0();
        let Walk {
            j0,
            j1,
            ox,
            mut sr,
            sx,
            sy,
            kn,
            s0,
            lz: _,
        } = self;
        let mut stats = Stats::default();
        let width = depth.width() as i32;
        let sc0 = s0.wrapping_sub(lz0 + 1);
        let kn = HiFactor::new(kn);
        // The rows are in the buffer (`j0 >= y0`, `j1` below its last row): row `j` starts at `(j - y0) width`, walked
        // by adding the width (no multiply and no overflow checks per row) where the core has the registers for it
        // (measured: 1.2% fewer instructions on the M4's W3, 3.3% more on the M0's, which takes the row by index).
        let mut base = (j0 - depth_y0) as usize * width as usize;
        // One row: its run, depth loop and colour (`sr` and `base` at the row); a macro, so that each stretch's loop
        // below has it inline.
        macro_rules! row {
            ($j:expr, $run:expr) => {
                'row: {
                    let j: i32 = $j;
                    let (lo, hi): (i32, i32) = $run;
                    let (lo, hi) = (lo.max(0), hi.min(width));
                    if lo >= hi {
                        break 'row;
                    }
                    let v = sr.wrapping_add(mul_small(sx, (lo - ox) as u32));
                    let row = if ROWS_BY_DIVISION {
                        match depth
                            .data_mut()
                            .get_mut(base + lo as usize..base + hi as usize)
                        {
                            Some(row) => row,
                            None => break 'row, // not reached: the row is in the buffer
                        }
                    } else {
                        &mut depth.row_mut(j)[lo as usize..hi as usize]
                    };
                    let pass = depth_run::<S, SAME_LZ>(row, v, sx, kn, s0, sc0);
                    let n = (hi - lo) as u32; // at most 32: the box is under 32 px wide
                    stats.fragments += n;
                    stats.written += emit(target, lo, j, n, pass, color)?;
                }
            };
        }
        // Rows in two stretches where the runs change edges between them ([`Halves::second`]): each loop then carries
        // only the bounds it steps (by division). The Cortex-M0's stepped bounds take one loop that switches at the
        // middle vertex's row: two loops doubled the row's code in every instantiation (its `.text` 8.3 KB larger)
        // and saved 0.3% of W3's and the terrain's instructions (W4 0.1% more).
        let mid = runs.second_from().min(j1 + 1);
        if ROWS_BY_DIVISION {
            for j in j0..mid {
                row!(j, runs.run(ox));
                runs.step();
                sr = sr.wrapping_add(sy);
                base += width as usize;
            }
            if mid <= j1 {
                runs.second();
                for j in mid..=j1 {
                    row!(j, runs.run(ox));
                    runs.step();
                    sr = sr.wrapping_add(sy);
                    base += width as usize;
                }
            }
        } else {
            for j in j0..=j1 {
                if j == mid {
                    runs.second();
                }
                row!(j, runs.run(ox));
                runs.step();
                sr = sr.wrapping_add(sy);
                base += width as usize;
            }
        }
        Ok(stats)
    }
}

/// One run's depth loop: each pixel's code from `S` (`v` at the run's first pixel, `sx` a column), tested against
/// the stored code and written where less. Bit `n - 1 - i` of the result for the run's pixel `i` that passed. Out of
/// line on the Cortex-M4, where inlined into the row walk its values did not fit the registers (three reloads from
/// the stack per pixel); walked by `split_first_mut`, whose loop LLVM sets up for fewer instructions than the slice
/// iterator's. Measured on the M4: 1.9% fewer instructions on W4 and 1.2% on W3 than inline with the iterator.
/// Inlined on the M0 and RV32, where the call measured 0.8% to 2.1% more (the walk by `split_first_mut` is within
/// 0.5% of the iterator's there, either way).
#[cfg_attr(all(target_arch = "arm", target_has_atomic = "32"), inline(never))]
#[cfg_attr(
    not(all(target_arch = "arm", target_has_atomic = "32")),
    inline(always)
)]
fn depth_run<S: FreshSeed, const SAME_LZ: bool>(
    row: &mut [u16],
    mut v: u64,
    sx: u64,
    kn: HiFactor,
    s0: u32,
    sc0: u32,
) -> u32 {
    let mut pass = 0u32;
    let mut row = row;
    while let Some((stored, rest)) = row.split_first_mut() {
        row = rest;
        let h = (v >> 32) as u32;
        let (m, sc) = if SAME_LZ {
            (h, sc0)
        } else {
            let lz = lz_small(h);
            ((h << lz) | ((v as u32) >> (32 - lz)), s0 - lz - 1)
        };
        let hi = kn.mul_hi(fresh61::<S>(m) as u32);
        // Below 2^16 (the module doc), compared as u32.
        let c = ((hi >> sc) + 1) >> 1;
        let ok = c < *stored as u32;
        pass = (pass << 1) | u32::from(ok);
        if ok {
            *stored = c as u16;
        }
        v = v.wrapping_add(sx);
    }
    pass
}

/// `S` at the origin and its steps (`sum_k E_k w_k` over the edge functions `er` at the origin and their steps `ex`,
/// `ey`), `2A T'_max` and `2A T'_min`, modulo 2^64, in fewer wide products for the Cortex-M0 (no 32 x 32 -> 64
/// multiply: each is four 16-bit ones). The three edge functions sum to `2A` at every point (each is `2A` at its
/// opposite vertex and their steps cancel), so with `j` the edge carrying `T'_max`,
/// `S = 2A T'_max + sum_(k != j) E_k (w_k - T'_max)`: the same integers, so the same bits modulo 2^64 as the sum of
/// all three products, from six products of an `i32` and a difference in `(-2^36, 0]` and two of `2A` (which the
/// leading zeros need anyway), eight against eleven. Where the differences fit an `i32` (`T'_max - T'_min < 2^31`,
/// as a small triangle's depth mostly does), the two of `S` and one of `2A` are a [`smul_wide`] each and the four of
/// the steps two `MULS` each. Measured on the M0: 3.1% fewer instructions on W3, 2.3% on W4. (The other cores'
/// 64-bit products are a few instructions: they keep the sum; the unit tests run this on the host.)
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn s_by_differences(
    er: &[i32; 3],
    ex: &[i32; 3],
    ey: &[i32; 3],
    w: &[u64; 3],
    area2: i32,
    tp_max: u64,
    tp_min: u64,
) -> (u64, u64, u64, (u64, u64)) {
    let j = if w[0] == tp_max {
        0
    } else if w[1] == tp_max {
        1
    } else {
        2
    };
    let narrow = tp_max - tp_min < 1 << 31;
    // `a d` modulo 2^64 for `d` in `(-2^36, 0]`.
    let prod = |a: i32, d: i64| {
        if narrow {
            smul_wide(a, d as i32) as u64
        } else {
            wmul(a, d as u64)
        }
    };
    // `a d` for `|a| < 2^15` and `d` an `i32`: `d = dh 2^16 + dl` (`0 <= dl < 2^16`), both partial products fit an
    // `i32` (below `2^30` and `2^31`), two `MULS` instead of a [`smul_wide`]. The steps are `256 a` with `|a|`
    // below `2^15` (`ey`'s below `2^13`: the box is under 126 px high and 32 px wide).
    let step = |a: i32, d: i64| {
        if narrow {
            let (a, d) = (a >> SUBPIXEL_BITS, d as i32);
            let ad = (((a * (d >> 16)) as i64) << 16).wrapping_add((a * (d & 0xffff)) as i64);
            (ad as u64) << SUBPIXEL_BITS
        } else {
            wmul(a, d as u64)
        }
    };
    let s_max = wmul(area2, tp_max);
    let (mut sr, mut sx, mut sy) = (s_max, 0u64, 0u64);
    for k in [(j + 1) % 3, (j + 2) % 3] {
        let d = w[k] as i64 - tp_max as i64;
        sr = sr.wrapping_add(prod(er[k], d));
        sx = sx.wrapping_add(step(ex[k], d));
        sy = sy.wrapping_add(step(ey[k], d));
    }
    let s_min = s_max.wrapping_add(prod(area2, tp_min as i64 - tp_max as i64));
    (sr, sx, sy, (s_max, s_min))
}

/// One row's `len` pixels from column `x` to the target, as one `fill_solid`.
#[inline(always)]
fn fill_run<D: DrawTarget>(t: &mut D, x: i32, j: i32, len: u32, c: D::Color) -> Result<(), Error> {
    let r = Rectangle::new(Point::new(x, j), Size::new(len, 1));
    t.fill_solid(&r, c).map_err(|_| Error::Target)
}

/// The passing runs of a run of `n <= 32` covered pixels from column `x0` of row `j` to the target: bit `n - 1 - k` of
/// `pass` set for a written pixel `x0 + k`. Returns how many were written.
#[inline(always)]
fn emit<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    j: i32,
    n: u32,
    pass: u32,
    color: D::Color,
) -> Result<u32, Error> {
    if pass == u32::MAX >> (32 - n) {
        fill_run(target, x0, j, n, color)?;
        return Ok(n);
    }
    if ROWS_BY_DIVISION {
        partial_out(target, x0, j, (n, pass), color)
    } else {
        partial(target, x0, j, (n, pass), color)
    }
}

/// [`partial`] out of line, so that the row walk keeps its registers for the common case (every pixel passed): where
/// rows are found by division (measured on the Cortex-M4: 1.6% fewer instructions on W3, 0.7% on W4; on the M0, whose
/// row stepping keeps other registers, inline is cheaper: out of line measured W3 +1.4%, W4 +1.0%).
#[inline(never)]
fn partial_out<D: DrawTarget>(
    t: &mut D,
    x0: i32,
    j: i32,
    np: (u32, u32),
    c: D::Color,
) -> Result<u32, Error> {
    partial(t, x0, j, np, c)
}

/// [`emit`] of a run not every pixel of which passed (`(n, pass)` as there).
#[inline(always)]
fn partial<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    j: i32,
    (n, pass): (u32, u32),
    color: D::Color,
) -> Result<u32, Error> {
    // Runs of set bits from the first pixel (bit n - 1) on: shifted to the top of a u64, whose leading zeros and
    // ones are the gap and the run (a u64 so that shifting out all 32 bits is defined).
    let (mut m, mut at) = (shl64(pass as u64, 64 - n), 0u32); // 1 <= n <= 32: a shift of 32 to 63
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

#[cfg(test)]
mod tests {
    use super::*;

    /// [`draw_as_t`] of `s` into `f` in `On`, the core's way ([`ROWS_BY_DIVISION`]).
    fn drawn<S: FreshSeed>(
        f: &mut Frame,
        db: &mut DepthBuffer<'_>,
        s: &Setup,
        state: &RenderState,
    ) -> Option<Stats> {
        draw_as_t::<S, _, ROWS_BY_DIVISION>(f, db, s, state, BinaryColor::On).unwrap()
    }

    /// [`draw_as`] without a memo: the stats, where taken.
    fn draw_as_t<S: FreshSeed, D: DrawTarget, const DIV: bool>(
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        s: &Setup,
        state: &RenderState,
        color: D::Color,
    ) -> Result<Option<Stats>, Error> {
        draw_as::<S, D, DIV, false>(target, depth, s, state, color, &mut None)
    }
    use crate::fast::{Chord, Divide};
    use crate::raster::Rasterizer;
    use crate::recip::Fast;
    use crate::setup::{t_at_snapped, Vertex};
    use embedded_graphics_core::pixelcolor::BinaryColor;
    use embedded_graphics_core::prelude::{OriginDimensions, Pixel};
    use std::vec;
    use std::vec::Vec;

    use crate::xorshift;

    /// A frame 64 pixels wide of `BinaryColor` pixels (0 unwritten), recording every pixel written.
    struct Frame(Vec<u8>);
    impl OriginDimensions for Frame {
        fn size(&self) -> Size {
            Size::new(64, self.0.len() as u32 / 64)
        }
    }
    impl DrawTarget for Frame {
        type Color = BinaryColor;
        type Error = core::convert::Infallible;
        fn draw_iter<I: IntoIterator<Item = Pixel<BinaryColor>>>(
            &mut self,
            pixels: I,
        ) -> Result<(), Self::Error> {
            for Pixel(p, c) in pixels {
                let h = self.0.len() as i32 / 64;
                assert!((0..64).contains(&p.x) && (0..h).contains(&p.y), "{p:?}");
                self.0[(p.y * 64 + p.x) as usize] = 1 + u8::from(c.is_on());
            }
            Ok(())
        }
    }

    /// Finding the runs by division and by stepping gives the same pixels, codes and counts: random small
    /// triangles on and off the snap grid, in the whole frame and in bands of 5 rows, over a depth buffer already
    /// holding a random surface (so some pixels fail), with both seeds.
    #[test]
    fn division_and_stepping_find_the_same_runs() {
        let mut rnd = xorshift(0x9E37_79B9_7F4A_7C15);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let r = Rasterizer::<Fast>::new(RenderState::new(1.0, 100.0).unwrap());
        let (mut taken, mut pixels) = (0, 0u32);
        for k in 0..20_000 {
            let (cx, cy) = (unit() * 70.0 - 3.0, unit() * 70.0 - 3.0);
            // Up to 40 px wide: some beyond the path's 32 px (those it leaves to the general path in both ways).
            let size = 1.0 + unit() * if k % 4 == 3 { 40.0 } else { 8.0 };
            // Off the grid, on it, and on pixel centres (edges through centres: the top-left rule decides).
            let grid = |v: f32| match k % 3 {
                0 => (v * 256.0).round() / 256.0,
                1 => v.round() + 0.5,
                _ => v,
            };
            let v: [Vertex<BinaryColor>; 3] = core::array::from_fn(|_| Vertex {
                x: grid(cx + unit() * size),
                y: grid(cy + unit() * size * 3.0),
                z: 0.0,
                rhw: 1.0 / (2.0 + unit() * 20.0),
                color: BinaryColor::On,
            });
            let mut setup = r.setup(&v).unwrap();
            if !setup.on_grid {
                // Both ways to the corrected `T` (`Fast`'s and `FastDiv`'s), alternately.
                setup.fast_t = if k % 2 == 0 {
                    t_at_snapped::<false>(&setup)
                } else {
                    t_at_snapped::<true>(&setup)
                };
            }
            let base: Vec<u16> = (0..64 * 64)
                .map(|_| 20_000 + (rnd() % 40_000) as u16)
                .collect();
            let band = if k % 5 < 2 { 64 } else { 5 };
            let y0 = if band == 64 { 0 } else { (rnd() % 60) as i32 };
            let mut out = [(vec![], vec![], None), (vec![], vec![], None)];
            for (m, o) in out.iter_mut().enumerate() {
                let mut d = base[(y0 * 64) as usize..((y0 + band) * 64) as usize].to_vec();
                let mut f = Frame(vec![0; 64 * 64]);
                let mut db = DepthBuffer::band(&mut d, 64, y0, band as u16).unwrap();
                let st = match (m, k % 4 == 1) {
                    (0, false) => draw_as_t::<Chord, _, true>(
                        &mut f,
                        &mut db,
                        &setup,
                        &r.state,
                        BinaryColor::On,
                    ),
                    (1, false) => draw_as_t::<Chord, _, false>(
                        &mut f,
                        &mut db,
                        &setup,
                        &r.state,
                        BinaryColor::On,
                    ),
                    (0, true) => draw_as_t::<Divide, _, true>(
                        &mut f,
                        &mut db,
                        &setup,
                        &r.state,
                        BinaryColor::On,
                    ),
                    _ => draw_as_t::<Divide, _, false>(
                        &mut f,
                        &mut db,
                        &setup,
                        &r.state,
                        BinaryColor::On,
                    ),
                };
                *o = (
                    d,
                    f.0,
                    st.unwrap().map(|s| (s.fragments, s.written, s.culled)),
                );
            }
            assert_eq!(out[0], out[1], "triangle {k}: {v:?}");
            if let Some((fr, _, _)) = out[0].2 {
                taken += 1;
                pixels += fr;
            }
        }
        // A guard that the comparison exercises the path: most triangles are taken (17,434 of 20,000 when written),
        // and they cover many pixels (104,494).
        assert!(taken > 10_000 && pixels > 50_000, "{taken} {pixels}");
    }

    /// The cull rule written out in [`draw_as`] is [`crate::setup::culls_area`]'s, and so is every other draw's:
    /// triangles on the snap grid (no early cull decides first) of both windings and degenerate ones (three
    /// collinear vertices), small (this path) and 40 px (the general set-up), with every cull mode. Each draw (the
    /// fast tier's with both seeds, table and division; the exact tier's; the generic span loop's; W16F's; the
    /// wireframe) culls exactly the triangles whose snapped doubled area (here in `i64` from the coordinates) is zero
    /// or of the culled sign.
    #[test]
    fn the_cull_rule_is_written_out_the_same() {
        use crate::format::W16F;
        use crate::recip::Exact;
        use crate::setup::culls_area;
        let mut seen = [0u32; 2];
        for cull in [Cull::None, Cull::Cw, Cull::Ccw] {
            for size in [6.0f32, 40.0] {
                for shape in 0..3 {
                    let (a, b) = ((10.0, 10.0), (10.0 + size, 10.0 + size / 2.0));
                    let c = match shape {
                        0 => (10.0 + size / 4.0, 10.0 + size),
                        1 => (10.0 + size / 2.0, 10.0 - size / 4.0),
                        _ => (10.0 + 2.0 * size, 10.0 + size), // a + 2 (b - a): collinear
                    };
                    let sub = |(x, y): (f32, f32)| ((x * 256.0) as i64, (y * 256.0) as i64);
                    let (pa, pb, pc) = (sub(a), sub(b), sub(c));
                    let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pc.0 - pa.0) * (pb.1 - pa.1);
                    let rule = area == 0
                        || (cull == Cull::Cw && area > 0)
                        || (cull == Cull::Ccw && area < 0);
                    assert_eq!(culls_area(cull, area), rule, "{cull:?} {area}");
                    assert_eq!(culls_area(cull, area as i32), rule, "{cull:?} {area}");
                    seen[usize::from(rule)] += 1;
                    let v: [Vertex<BinaryColor>; 3] = [a, b, c].map(|(x, y)| Vertex {
                        x,
                        y,
                        z: 0.0,
                        rhw: 1.0 / 10.0,
                        color: BinaryColor::On,
                    });
                    let mut state = RenderState::new(1.0, 100.0).unwrap();
                    state.cull = cull;
                    fn db(d: &mut [u16]) -> DepthBuffer<'_> {
                        DepthBuffer::new(d, 64, 64).unwrap()
                    }
                    let culled = |draw: &dyn Fn(&mut Frame, &mut [u16]) -> Stats| {
                        let (mut f, mut d) = (Frame(vec![0; 64 * 64]), vec![u16::MAX; 64 * 64]);
                        draw(&mut f, &mut d).culled
                    };
                    let got = [
                        culled(&|f, d| {
                            Rasterizer::<Fast>::new(state)
                                .draw(f, &mut db(d), &v)
                                .unwrap()
                        }),
                        culled(&|f, d| {
                            Rasterizer::<crate::recip::FastDiv>::new(state)
                                .draw(f, &mut db(d), &v)
                                .unwrap()
                        }),
                        culled(&|f, d| {
                            Rasterizer::<Exact>::new(state)
                                .draw(f, &mut db(d), &v)
                                .unwrap()
                        }),
                        culled(&|f, d| {
                            Rasterizer::<Fast>::new(state)
                                .draw_generic(f, &mut db(d), &v)
                                .unwrap()
                        }),
                        culled(&|f, _| {
                            let mut w = vec![0u16; 64 * 64];
                            let mut z = DepthBuffer::<W16F>::new_format(&mut w, 64, 64).unwrap();
                            z.clear_for(&state.range);
                            Rasterizer::<Exact>::new(state).draw(f, &mut z, &v).unwrap()
                        }),
                        culled(&|f, d| {
                            Rasterizer::<Fast>::new(state)
                                .draw_wireframe(f, &mut db(d), &v)
                                .unwrap()
                        }),
                    ];
                    assert_eq!(
                        got,
                        [u32::from(rule); 6],
                        "{cull:?} size {size} shape {shape}: area {area}"
                    );
                    if size < 32.0 && area != 0 {
                        // The small path took it (culled or drawn), so its own test decided.
                        let s = Rasterizer::<Exact>::new(state).setup(&v).unwrap();
                        let (mut f, mut d) = (Frame(vec![0; 64 * 64]), vec![u16::MAX; 64 * 64]);
                        let st = drawn::<Chord>(&mut f, &mut db(&mut d), &s, &state).unwrap();
                        assert_eq!(st.culled, u32::from(rule), "{cull:?} shape {shape}");
                    }
                }
            }
        }
        assert_eq!(seen, [8, 10]); // drawn and culled cases (6 degenerate, 4 by winding): the test sees both
    }

    /// The path against the exact tier (`Rasterizer<Exact>::draw`, the general set-up and the correctly rounded
    /// reciprocal) on random triangles it must take: boxes up to 24 px anywhere in a 64 x 192 frame (the box limits
    /// are on extents, not positions), off the snap grid and on it, every winding
    /// and culling mode, `W` in `[2, 22]` with the range `[1, 100]` (vertices inside it by far more than the margin,
    /// `T_max / T_min <= 11 < 32`), over a random stored surface, whole frame and bands of 5 rows.
    /// - It takes every such triangle with rows in the buffer (`Some`), both seeds, by division and by stepping.
    /// - The same counts: covered pixels (`fragments`) and culled triangles, exactly (coverage and culling are exact).
    /// - Every stored code within 1 of the exact tier's, the written colour the same wherever the codes agree, and
    ///   the same count written where all agree; the same triangle drawn again writes nothing (`Less` is strict).
    /// - At least 99.9% of the compared codes equal. Derived: against the true plane, this path's code errs by below
    ///   `2^-11.3` LSB (`5.91e-9` relative, module doc) and the exact tier's by below `2^-12`; both are the correctly
    ///   rounded code unless the true value lies within `2^-11.3` of a rounding tie, a window of `2^-10.3` of the
    ///   codes for uniformly spread fractions: at least `1 - 2^-10.3 = 99.92%` agree.
    #[test]
    fn agrees_with_the_exact_tier_and_takes_what_it_should() {
        let mut rnd = xorshift(0x2545_F491_4F6C_DD1D);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let mut surface = xorshift(0x9E37_79B9_7F4A_7C15);
        let (mut taken, mut culled, mut compared, mut equal) = (0u32, 0u32, 0u64, 0u64);
        for k in 0..12_000 {
            let cull = [Cull::None, Cull::Cw, Cull::Ccw][k % 3];
            let mut state = RenderState::new(1.0, 100.0).unwrap();
            state.cull = cull;
            let mut exact = Rasterizer::<crate::recip::Exact>::new(state);
            let (cx, cy) = (unit() * 50.0 + 2.0, unit() * 175.0 + 2.0);
            let size = 1.0 + unit() * if k % 4 == 3 { 23.0 } else { 8.0 };
            let grid = |v: f32| match k % 3 {
                0 => (v * 256.0).round() / 256.0,
                1 => v.round() + 0.5,
                _ => v,
            };
            let v: [Vertex<BinaryColor>; 3] = core::array::from_fn(|_| Vertex {
                x: grid(cx + unit() * size),
                y: grid(cy + unit() * size),
                z: 0.0,
                rhw: 1.0 / (2.0 + unit() * 20.0),
                color: BinaryColor::On,
            });
            let mut setup = exact.setup(&v).unwrap();
            if !setup.on_grid {
                setup.fast_t = if k % 2 == 0 {
                    t_at_snapped::<false>(&setup)
                } else {
                    t_at_snapped::<true>(&setup)
                };
            }
            let base: Vec<u16> = (0..64 * 192)
                .map(|_| 1_000 + (surface() % 64_000) as u16)
                .collect();
            let band = if k % 5 < 2 { 192 } else { 5 };
            let y0 = if band == 192 { 0 } else { (rnd() % 188) as i32 };
            let rows = (y0 * 64) as usize..((y0 + band) * 64) as usize;
            let (mut de, mut fe) = (base[rows.clone()].to_vec(), Frame(vec![0; 64 * 192]));
            let se = exact
                .draw(
                    &mut fe,
                    &mut DepthBuffer::band(&mut de, 64, y0, band as u16).unwrap(),
                    &v,
                )
                .unwrap();
            let (first, last) = rows_of(&setup.p);
            let has_rows = first <= last.min(y0 + band - 1) && last >= first.max(y0);
            for m in 0..4 {
                let (mut d, mut f) = (base[rows.clone()].to_vec(), Frame(vec![0; 64 * 192]));
                let mut db = DepthBuffer::band(&mut d, 64, y0, band as u16).unwrap();
                let st = match m {
                    // The entry the rasterizer calls (by division on the host).
                    0 => draw_as_t::<Chord, _, ROWS_BY_DIVISION>(
                        &mut f,
                        &mut db,
                        &setup,
                        &state,
                        BinaryColor::On,
                    ),
                    1 => draw_as_t::<Chord, _, false>(
                        &mut f,
                        &mut db,
                        &setup,
                        &state,
                        BinaryColor::On,
                    ),
                    2 => draw_as_t::<Divide, _, true>(
                        &mut f,
                        &mut db,
                        &setup,
                        &state,
                        BinaryColor::On,
                    ),
                    _ => draw_as_t::<Divide, _, false>(
                        &mut f,
                        &mut db,
                        &setup,
                        &state,
                        BinaryColor::On,
                    ),
                };
                let Some(st) = st.unwrap() else {
                    // Not taken: only a triangle off the snap grid whose plane has no `T` at the snapped vertices
                    // (`t_at_snapped` declines a plane steep over the snap's 1/512 px: the general path draws it).
                    assert!(
                        !setup.on_grid && setup.fast_t.is_none(),
                        "triangle {k} {m} not taken: {v:?}"
                    );
                    continue;
                };
                assert!(
                    has_rows || st == Stats::default() || st.culled == 1,
                    "triangle {k}: {st:?}"
                );
                assert_eq!(
                    (st.fragments, st.culled),
                    (se.fragments, se.culled),
                    "triangle {k} {m}: {v:?}"
                );
                for i in 0..d.len() {
                    let diff = d[i].abs_diff(de[i]);
                    assert!(
                        diff <= 1,
                        "triangle {k} {m} pixel {i}: {} vs {}",
                        d[i],
                        de[i]
                    );
                    if diff == 0 {
                        let p = (y0 as usize) * 64 + i;
                        assert_eq!(f.0[p], fe.0[p], "triangle {k} {m} colour at {i}");
                    }
                    if d[i] != base[rows.start + i] || de[i] != base[rows.start + i] {
                        compared += 1;
                        equal += u64::from(diff == 0);
                    }
                }
                if d == de {
                    assert_eq!(st.written, se.written, "triangle {k} {m}");
                }
                if m == 0 {
                    taken += 1;
                    culled += st.culled;
                    // `Less` is strict: the same triangle again writes nothing.
                    let mut again = Frame(vec![0; 64 * 192]);
                    let mut db = DepthBuffer::band(&mut d, 64, y0, band as u16).unwrap();
                    let st2 = draw_as_t::<Chord, _, ROWS_BY_DIVISION>(
                        &mut again,
                        &mut db,
                        &setup,
                        &state,
                        BinaryColor::On,
                    );
                    assert_eq!(st2.unwrap().map(|s| s.written), Some(0), "triangle {k}");
                    assert!(again.0.iter().all(|&c| c == 0), "triangle {k}");
                }
            }
        }
        // Guards that the comparison exercises the path (when written: 10,046 of 12,000 taken, 3,386 of them culled by
        // winding or area, 66,628 codes compared).
        assert!(
            taken > 9_000 && culled > 3_000 && compared > 60_000,
            "{taken} {culled} {compared}"
        );
        let share = equal as f64 / compared as f64;
        std::println!(
            "small path vs exact tier: {taken} taken ({culled} culled), {equal} of {compared} codes equal ({:.5}%)",
            100.0 * share
        );
        assert!(share >= 1.0 - 2f64.powf(-10.3), "{share}");
    }

    /// Which triangles the path takes, at the edges of its conditions (module doc), on the snap grid, with the range
    /// `[1, 64]` (`t = 64 rhw` exact): a vertex exactly on the far plane (`T_min = 2^F`, inside the range but not
    /// by the margin) or the near plane (`T_max = t_hi`), `T_max / T_min` exactly 32 (`T_min = 2^56`: taken) and
    /// just over it, a box exactly 32 px wide or 126 px high (declined) and one sub-pixel less (taken). A declined
    /// triangle is left to the general path (`None`, nothing written).
    #[test]
    fn takes_and_declines_at_its_limits() {
        let r = Rasterizer::<Fast>::new(RenderState::new(1.0, 64.0).unwrap());
        let taken = |v: [(f32, f32, f32); 3]| {
            let v = v.map(|(x, y, rhw)| Vertex {
                x,
                y,
                z: 0.0,
                rhw,
                color: BinaryColor::On,
            });
            let setup = r.setup(&v).unwrap();
            assert!(setup.on_grid);
            let mut d = vec![u16::MAX; 64 * 192];
            let mut f = Frame(vec![0; 64 * 192]);
            let mut db = DepthBuffer::new(&mut d, 64, 192).unwrap();
            let st = drawn::<Chord>(&mut f, &mut db, &setup, &r.state);
            if st.is_none() {
                assert!(d.iter().all(|&c| c == u16::MAX) && f.0.iter().all(|&c| c == 0));
            }
            st.is_some_and(|s| s.written > 0)
        };
        let w = |w: f32| 1.0 / w;
        // Inside by far more than the margin.
        assert!(taken([
            (10.5, 10.5, w(2.0)),
            (20.5, 12.5, w(3.0)),
            (14.5, 20.5, w(4.0))
        ]));
        // A vertex on the far plane (t = 1), the others near it (T_max / T_min < 2).
        assert!(!taken([
            (10.5, 10.5, w(64.0)),
            (20.5, 12.5, w(40.0)),
            (14.5, 20.5, w(50.0))
        ]));
        // A vertex on the near plane (t = 64).
        assert!(!taken([
            (10.5, 10.5, w(1.0)),
            (20.5, 12.5, w(1.5)),
            (14.5, 20.5, w(1.25))
        ]));
        // T_max / T_min: t in {2, 32, 42.67}, F = 61 - bits(42) = 55, so T_min = 2^56 exactly: taken; t_min one
        // f32 step below 2 (rhw = 2^-5 (1 - 2^-24), exact): declined.
        assert!(taken([
            (10.5, 10.5, w(32.0)),
            (20.5, 12.5, w(2.0)),
            (14.5, 20.5, w(1.5))
        ]));
        let below = f32::from_bits(w(32.0).to_bits() - 1);
        assert_eq!(below as f64, (1.0 - 2f64.powi(-24)) / 32.0);
        assert!(!taken([
            (10.5, 10.5, below),
            (20.5, 12.5, w(2.0)),
            (14.5, 20.5, w(1.5))
        ]));
        // The box: 32 px wide or 126 px high is declined; one sub-pixel less is taken.
        let wide = |x: f32| {
            [
                (10.5, 10.5, w(2.0)),
                (x, 14.5, w(3.0)),
                (14.5, 20.5, w(4.0)),
            ]
        };
        assert!(!taken(wide(42.5)));
        assert!(taken(wide(42.5 - 1.0 / 256.0)));
        let high = |y: f32| {
            [
                (10.5, 10.5, w(2.0)),
                (20.5, 12.5, w(3.0)),
                (14.5, y, w(4.0)),
            ]
        };
        assert!(!taken(high(136.5)));
        assert!(taken(high(136.5 - 1.0 / 256.0)));
    }

    /// The range margin's value: a vertex inside the far plane by less than the margin is declined. `W_far` has the
    /// mantissa `2^23 - 2892` and the vertex's `1/W` the mantissa `2^23 + 2893`, so `t = 1 + 22052 2^-46` exactly (the
    /// product of the two); with `t_max = 1.3457` (`F = 60`), `T_min - 2^60 = 22052 2^14 = 361,299,968` lies between
    /// `T_max >> 32 = 361,233,596` and the margin `361,233,596 + 2^17`: declined; a margin without its `2^17` term
    /// (or any smaller one) would take it.
    #[test]
    fn declines_a_vertex_inside_the_far_plane_by_less_than_the_margin() {
        let far = f32::from_bits(0x427f_e968);
        let r = Rasterizer::<Fast>::new(RenderState::new(1.0, far).unwrap());
        let v = [
            (10.5, 10.5, f32::from_bits(0x3c80_0b4d)),
            (20.5, 12.5, f32::from_bits(0x3cac_4f1b)),
            (14.5, 20.5, f32::from_bits(0x3c99_a729)),
        ]
        .map(|(x, y, rhw)| Vertex {
            x,
            y,
            z: 0.0,
            rhw,
            color: BinaryColor::On,
        });
        let setup = r.setup(&v).unwrap();
        assert_eq!(setup.frac, 60);
        let t = setup.t.map(|t| t as u64);
        assert_eq!(t[0] - (1 << 60), 22052 << 14);
        assert_eq!(t[1] >> 32, 361_233_596);
        assert_eq!(margin(t[1]), 361_233_596 + (1 << 17));
        let mut d = vec![u16::MAX; 64 * 64];
        let mut f = Frame(vec![0; 64 * 64]);
        let mut db = DepthBuffer::new(&mut d, 64, 64).unwrap();
        let st = drawn::<Chord>(&mut f, &mut db, &setup, &r.state);
        assert!(st.is_none());
        // Moved inside by more than the margin (t = 1 + 2^-22 + ...), the same triangle is taken.
        let mut v2 = v;
        v2[0].rhw = f32::from_bits(0x3c80_0b4d + 64);
        let setup = r.setup(&v2).unwrap();
        let mut db = DepthBuffer::new(&mut d, 64, 64).unwrap();
        let st = drawn::<Chord>(&mut f, &mut db, &setup, &r.state);
        assert!(st.is_some());
    }

    /// The code's shift `s0 - lz` (`lz >= 1`) must stay below 32, and `s0` grows with `bits(t_max)` (`sh`, `kz` and
    /// `F` of the module doc), so near the near plane of a deep range the path declines the triangle (the general path
    /// draws it): with `W` in `[2, 3]` and the range `[1, W_far]`, `W_far = 2^20` and `2^19` give `s0 = 34` and `33`
    /// (declined), `2^18` exactly 32 and `2^16` 30 (taken).
    #[test]
    fn declines_a_shift_past_32_bits() {
        // s0 = 34, 33, 32 and 30 (measured by a print in `draw_as`).
        for (far, take) in [
            (1048576.0f32, false),
            (524288.0, false),
            (262144.0, true),
            (65536.0, true),
        ] {
            let r = Rasterizer::<Fast>::new(RenderState::new(1.0, far).unwrap());
            let v =
                [(10.5, 10.5, 2.0), (20.5, 12.5, 3.0), (14.5, 20.5, 2.5)].map(|(x, y, w)| Vertex {
                    x,
                    y,
                    z: 0.0,
                    rhw: 1.0 / w,
                    color: BinaryColor::On,
                });
            let setup = r.setup(&v).unwrap();
            let mut d = vec![u16::MAX; 64 * 64];
            let mut f = Frame(vec![0; 64 * 64]);
            let mut db = DepthBuffer::new(&mut d, 64, 64).unwrap();
            let st = drawn::<Chord>(&mut f, &mut db, &setup, &r.state);
            assert_eq!(st.is_some(), take, "far {far}");
        }
    }

    /// The Cortex-M0's `S` set-up by differences ([`s_by_differences`], which only that core runs, so tested here) gives
    /// the same bits as the sum of all three products, on random oriented triangles in the path's box (under 32 x 126
    /// px, in sub-pixels) with vertex `T'` in `[2^31, 2^36]` within a factor of 32, both narrow (`T'_max - T'_min`
    /// below `2^31`) and not, every edge carrying the largest `T'` in turn, ties included.
    #[test]
    fn s_by_differences_is_the_sum_of_the_products() {
        let mut rnd = xorshift(0x243F_6A88_85A3_08D3);
        let (mut narrow, mut wide) = (0, 0);
        for k in 0..200_000 {
            let q: [(i32, i32); 3] =
                core::array::from_fn(|_| ((rnd() % (32 << 8)) as i32, (rnd() % (126 << 8)) as i32));
            let area =
                (q[1].0 - q[0].0) * (q[2].1 - q[0].1) - (q[2].0 - q[0].0) * (q[1].1 - q[0].1);
            if area == 0 {
                continue;
            }
            let q = if area < 0 { [q[0], q[2], q[1]] } else { q };
            let area2 = area.unsigned_abs() as u64;
            let base = (1u64 << 31) + rnd() % ((1 << 36) - (1 << 31));
            let spread = match k % 3 {
                0 => 1 << (rnd() % 31), // narrow
                1 => base,              // up to twice the base
                _ => 0,                 // ties
            };
            let tp: [u64; 3] = core::array::from_fn(|_| (base + rnd() % (spread + 1)).min(1 << 36));
            let tp_max = tp[0].max(tp[1]).max(tp[2]);
            let tp_min = tp[0].min(tp[1]).min(tp[2]);
            if bits(area2) + bits(tp_max) > 63 || tp_max > 32 * tp_min {
                continue;
            }
            let w = [tp[2], tp[0], tp[1]];
            let cy = (rnd() % (126 << 8)) as i32 + 128;
            let (mut er, mut ex, mut ey) = ([0i32; 3], [0i32; 3], [0i32; 3]);
            let (mut sr, mut sx, mut sy) = (0u64, 0u64, 0u64);
            for k in 0..3 {
                let (a, c) = (q[k], q[(k + 1) % 3]);
                let (ea, eb) = (a.1 - c.1, c.0 - a.0);
                er[k] = ea * (128 - a.0) + eb * (cy - a.1);
                (ex[k], ey[k]) = (ea << SUBPIXEL_BITS, eb << SUBPIXEL_BITS);
                sr = sr.wrapping_add((er[k] as i64).wrapping_mul(w[k] as i64) as u64);
                sx = sx.wrapping_add((ex[k] as i64).wrapping_mul(w[k] as i64) as u64);
                sy = sy.wrapping_add((ey[k] as i64).wrapping_mul(w[k] as i64) as u64);
            }
            let got = s_by_differences(&er, &ex, &ey, &w, area2 as i32, tp_max, tp_min);
            assert_eq!(
                got,
                (sr, sx, sy, (area2 * tp_max, area2 * tp_min)),
                "q {q:?} tp {tp:?} cy {cy}"
            );
            if tp_max - tp_min < 1 << 31 {
                narrow += 1;
            } else {
                wide += 1;
            }
        }
        assert!(
            narrow > 10_000 && wide > 10_000,
            "narrow {narrow}, wide {wide}"
        );
    }

    /// The path's codes, pinned (a golden test, as `host-tests/tests/golden.rs` pins whole frames): 40,000 random
    /// triangles of boxes up to 24 px, a quarter on the snap grid and the rest off it (where `T` has low bits to
    /// round), near the far plane (`W` in `[55, 100]`, range `[1, 100]`, so codes of 36,000 to 65,535; 1,743,640
    /// codes with `Fast`'s way to the corrected `T`, 1,743,833 with `FastDiv`'s, which takes a few more off-grid
    /// triangles), each drawn into a cleared buffer; FNV-1a over every written code, per seed. The accuracy tests judge
    /// the codes within the tier's derived bound, so a change of one unit of `2^-32` in a term of it (a rounding made a
    /// truncation) passes them; it moves the few codes that lie within some `2^-32 65535` LSB of a rounding tie, and
    /// so this hash. A deliberate change to the path's arithmetic updates the hashes (printed with `--nocapture`).
    #[test]
    fn golden_codes() {
        fn run<S: FreshSeed, const NARROW: bool>() -> (u64, u64) {
            let r = Rasterizer::<Fast>::new(RenderState::new(1.0, 100.0).unwrap());
            let mut rnd = xorshift(0x6A09_E667_F3BC_C909);
            let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
            let (mut hash, mut codes) = (0xcbf2_9ce4_8422_2325u64, 0u64);
            let mut d = vec![u16::MAX; 64 * 64];
            for k in 0..40_000 {
                let (cx, cy) = (unit() * 36.0 + 2.0, unit() * 36.0 + 2.0);
                let grid = |v: f32| {
                    if k % 4 == 0 {
                        (v * 256.0).round() / 256.0
                    } else {
                        v
                    }
                };
                let v: [Vertex<BinaryColor>; 3] = core::array::from_fn(|_| Vertex {
                    x: grid(cx + unit() * 24.0),
                    y: grid(cy + unit() * 24.0),
                    z: 0.0,
                    rhw: 1.0 / (55.0 + unit() * 45.0),
                    color: BinaryColor::On,
                });
                let mut setup = r.setup(&v).unwrap();
                if !setup.on_grid {
                    setup.fast_t = t_at_snapped::<NARROW>(&setup);
                }
                d.fill(u16::MAX);
                let mut f = Frame(vec![0; 64 * 64]);
                let mut db = DepthBuffer::new(&mut d, 64, 64).unwrap();
                if drawn::<S>(&mut f, &mut db, &setup, &r.state).is_none() {
                    continue;
                }
                for &c in d.iter().filter(|&&c| c != u16::MAX) {
                    for b in c.to_le_bytes() {
                        hash = (hash ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
                    }
                    codes += 1;
                }
            }
            (hash, codes)
        }
        // Each seed with its strategy's way to the corrected `T` (`Fast`: wide, `FastDiv`: narrow).
        let (chord, divide) = (run::<Chord, false>(), run::<Divide, true>());
        std::println!(
            "golden codes: chord {:016x} {}, divide {:016x} {}",
            chord.0,
            chord.1,
            divide.0,
            divide.1
        );
        assert_eq!(chord, (0x3ded_b611_72f7_c422, 1_743_640));
        assert_eq!(divide, (0xa89f_82f7_14ce_f000, 1_743_833));
    }
}
