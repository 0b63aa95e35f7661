//! The set-up stage, below every span loop: the vertex and its snapped, checked form ([`Setup`]), the depth grid
//! ([`depth_grid_bits`]) and the depth-grid plane's `T` at the snapped vertices ([`t_at_snapped`], the fast tier's way
//! to it), the exact `T` plane ([`Plane`]), the rows a triangle covers, and the colour runs and counts every loop
//! reports through ([`Stats`]; the colour runs: `crate::runs`). The W16 loops (`crate::raster`, `crate::fast`, `crate::small`) and the
//! loop generic over the format (`crate::packed`) build on it; it imports none of them.

use crate::edge::Sub;
use crate::fixed::{div_u128, Divisor};
use crate::state::Cull;
#[cfg(feature = "bias")]
use crate::state::RenderState;

/// Fraction bits of snapped x and y (Direct3D 11's 16.8): coverage (the edge functions) uses the snapped vertices.
pub const SUBPIXEL_BITS: u32 = 8;

/// Fraction bits of the depth grid of a triangle whose snapped box spans `extent` whole pixels (its larger side,
/// `0..=8192`): `31 - bits(extent + 2)`, from 29 (a box within one pixel) down to 17 (the guard band). The depth plane
/// (and the colour planes) go through the vertices as given, rounded to this grid relative to the box's first pixel,
/// not through the snapped ones: positions then fit 31 bits (the exact plane solve's budget). An f32 coordinate of
/// magnitude `2^(23 - bits)` px or more lies on the grid exactly (`2^-6` px for a box under 6 px, 64 px for the
/// largest boxes); a smaller one moves by at most half a grid step. Vertices on the 16.8 snap grid (integer and
/// fixed-point input, most meshes' pixel-aligned vertices) give the same plane either way and skip this.
pub const fn depth_grid_bits(extent: i32) -> u32 {
    31 - (32 - ((extent + 2) as u32).leading_zeros())
}

/// [`depth_grid_bits`] for the set-up, for `extent` in `0..=8192`: the same value (tested), with the crate's bit count
/// ([`crate::fast::bits64`]) instead of `leading_zeros`, a library call on the cores without `CLZ`.
#[inline(always)]
pub(crate) fn grid_bits(extent: i32) -> u32 {
    31 - crate::fast::bits64((extent + 2) as u32 as u64)
}
/// Vertices must have `|x|, |y| < GUARD_BAND` pixels (see ARCHITECTURE.md for why this is safe in i64).
pub const GUARD_BAND: i32 = 4096;

/// A transformed-and-lit vertex, like Direct3D's TLVERTEX: `x`, `y` in pixels (pixel centres at `i + 0.5`), `z`,
/// `rhw = 1/W`, and a colour. Every depth mode takes its depth from `rhw` and the depth range (Z modes compute D3D's
/// `Z = f/(f-n) (1 - n rhw)`, which is what a D3D projection puts in `z`), so `z` is only checked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex<C> {
    /// Pixels, right.
    pub x: f32,
    /// Pixels, down.
    pub y: f32,
    /// Post-projection z (checked for finiteness; depth comes from `rhw`).
    pub z: f32,
    /// `1 / W`, `W` the eye-space depth; must be > 0.
    pub rhw: f32,
    /// Colour.
    pub color: C,
}

impl<C> Vertex<C> {
    /// A vertex at `(x, y)` with eye-space depth `w` (`rhw = 1/w`, `z = 0`).
    pub fn new(x: f32, y: f32, w: f32, color: C) -> Self {
        Vertex {
            x,
            y,
            z: 0.0,
            rhw: 1.0 / w,
            color,
        }
    }
}

/// What one draw call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Covered pixels inside the buffer's rows and the frame's columns (passing the depth test or not).
    pub fragments: u32,
    /// Pixels that passed the range and depth tests and were written.
    pub written: u32,
    /// Triangles culled (zero snapped area or by winding).
    pub culled: u32,
}

impl core::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Stats) {
        self.fragments += o.fragments;
        self.written += o.written;
        self.culled += o.culled;
    }
}

/// A triangle after snapping and checks.
pub(crate) struct Setup<const N: usize = 3> {
    /// Snapped positions (coverage).
    pub(crate) p: [Sub; N],
    /// Whether every vertex lies on the snap grid: then `p` is the vertices as given, and `q` is not computed.
    pub(crate) on_grid: bool,
    /// Otherwise (triangles): positions on the depth grid of `dbits` fraction bits ([`depth_grid_bits`]) relative
    /// to the pixel `dorigin` (the box's first column and row).
    pub(crate) q: [Sub; N],
    pub(crate) dbits: u32,
    pub(crate) dorigin: (i32, i32),
    /// The fast tier's depth-grid plane `T` at the snapped vertices ([`t_at_snapped`]), where computed and accepted.
    pub(crate) fast_t: Option<[i64; 3]>,
    pub(crate) t: [i64; N],
    pub(crate) frac: u32,
}

/// A triangle's plane of `T` as the exact solve gives it ([`Plane::solve_ref`]: at the reference row, before
/// [`Plane::at_row`] moves it to a band's first row) and the fraction bits it was solved with: a function of the
/// triangle, the far plane and the strategy alone, so a remembered one draws exactly what a computed one does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Solved {
    pub(crate) plane: Plane,
    pub(crate) frac: u32,
}

/// What a memo keeps of a triangle from one band of a frame for the next ([`TMemo`]): the fast tier's depth-grid
/// values ([`t_at_snapped`]; `None` where declined), or, for a triangle the small-triangle path never takes, its
/// solved plane, or, for one it drew, its depth constants ([`crate::small::Kept`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Remember {
    T(Option<[i64; 3]>),
    Plane(Solved),
    Small(crate::small::Kept),
}

/// Where [`crate::Rasterizer::draw_memo`] finds and leaves what it remembers of a triangle ([`Remember`]).
pub trait TMemo {
    /// Whether this memo keeps anything ([`NoMemo`] does not: its draws compile to the code without a memo).
    const KEEPS: bool = true;
    /// Whether a fast-tier draw tests the render state's [`crate::Cull`] before the depth-grid values of a triangle
    /// off the snap grid, so that a culled one does not pay for them: where triangles reach the draw as they come
    /// (lists). Not where the caller has culled them by the same test (the mesh's screen triangles): there the test
    /// would only cost its instructions. Nor with a plane cache (`crate::mesh`'s memo: one instance of the draw for
    /// a list frame's triangles and a mesh's, whose values it keeps across bands).
    #[inline(always)]
    fn early_cull(&self) -> bool {
        true
    }
    /// What was remembered for this triangle, if anything (taken: each band keeps it again for the next).
    fn take(&mut self) -> Option<Remember>;
    /// This triangle's values, and its last row (the memo keeps them only for a triangle that reaches a later band).
    fn keep(&mut self, r: Remember, last_row: i32);
}

impl<M: TMemo> TMemo for Option<M> {
    #[inline(always)]
    fn early_cull(&self) -> bool {
        self.as_ref().is_some_and(|m| m.early_cull())
    }
    #[inline(always)]
    fn take(&mut self) -> Option<Remember> {
        self.as_mut().and_then(|m| m.take())
    }
    #[inline(always)]
    fn keep(&mut self, r: Remember, last_row: i32) {
        if let Some(m) = self {
            m.keep(r, last_row);
        }
    }
}

/// No memo: every draw computes its values. `EARLY_CULL` is its [`TMemo::early_cull`]: true for triangles as they
/// come ([`crate::Rasterizer::draw`]), false ([`Culled`]) for triangles the caller has culled with the draw's own test.
pub struct NoMemo<const EARLY_CULL: bool = true>;

/// [`NoMemo`] for triangles the caller has culled with the draw's own test: the mesh's (a piece of a clipped
/// triangle, culled before clipping by its winding seen from the eye, that the render state still culls on the
/// screen, or a degenerate one, is culled by the draw after its values, as before this test).
pub type Culled = NoMemo<false>;

impl<const EARLY_CULL: bool> TMemo for NoMemo<EARLY_CULL> {
    const KEEPS: bool = false;
    #[inline(always)]
    fn early_cull(&self) -> bool {
        EARLY_CULL
    }
    #[inline(always)]
    fn take(&mut self) -> Option<Remember> {
        None
    }
    #[inline(always)]
    fn keep(&mut self, _: Remember, _: i32) {}
}

/// Rows whose pixel centre lies in the snapped vertices' y-range (possibly empty: first > last).
pub(crate) fn rows_of(p: &[Sub; 3]) -> (i32, i32) {
    let ymin = p[0].y.min(p[1].y).min(p[2].y);
    let ymax = p[0].y.max(p[1].y).max(p[2].y);
    // |y| < 2^20 sub-pixels (the guard band): no overflow in i32, and `>>` is the floor division.
    let first = (ymin - 128 + 255) >> SUBPIXEL_BITS; // ceil((ymin - 128) / 256)
    let last = (ymax - 128) >> SUBPIXEL_BITS;
    (first, last)
}

/// Rounded `n / d` for `d > 0` (ties away from zero).
pub(crate) fn div_round(n: i128, d: i128) -> i128 {
    let (neg, a) = (n < 0, n.unsigned_abs() + (d as u128) / 2);
    let q = div_u128(a, d as u64);
    if neg {
        -(q as i128)
    } else {
        q as i128
    }
}

/// Positions of the oriented triangle, the reference pixel of its planes (column `i_ref`, row `j_ref`: the box's
/// left column and the triangle's first row, whatever the buffer), and the first row walked, `j0`.
///
/// The planes are rounded at the reference pixel and stepped from there to `j0` with their rounded row step, so a
/// pixel's value does not depend on which band (or buffer) walks it: a frame drawn in bands equals the frame drawn
/// whole, codes and range tests included. (A fuzz finding: with the planes rounded at each band's first row, pixels
/// exactly on the near plane flipped between bands.)
pub(crate) struct Geom {
    /// Snapped positions (coverage; and the bias's slope), and their doubled area (positive).
    pub(crate) p: [Sub; 3],
    pub(crate) area: i64,
    /// The positions the planes go through, in units of `2^-dbits` px from the pixel `dorigin`, and their doubled
    /// signed area in those units (nonzero; negative when rounding flipped the triangle against `p`'s orientation):
    /// the depth grid's, or the snapped ones where the vertices lie on the snap grid, where the fast tier solves
    /// through them with [`t_at_snapped`]'s values, or where [`depth_plane`] refuses.
    pub(crate) dq: [Sub; 3],
    pub(crate) darea: i64,
    pub(crate) dbits: u32,
    /// The pixel `dq` is relative to.
    pub(crate) dorigin: (i32, i32),
    pub(crate) i_ref: i64,
    pub(crate) j_ref: i32,
    pub(crate) j0: i32,
}

/// The snap's rounding against the depth grid at one vertex, `r = p - q` in units of the grid (`bits` fraction bits,
/// relative to the pixel `origin`): the snapped position there is below `2^31` units (the grid's choice), and
/// `|r|` at most `2^(bits - 9)` (half a sub-pixel plus half a grid step), so `i32` throughout.
#[inline(always)]
pub(crate) fn snap_rounding(p: Sub, q: Sub, bits: u32, (ox, oy): (i32, i32)) -> (i32, i32) {
    let up = bits - SUBPIXEL_BITS;
    (
        ((p.x - (ox << SUBPIXEL_BITS)) << up).wrapping_sub(q.x),
        ((p.y - (oy << SUBPIXEL_BITS)) << up).wrapping_sub(q.y),
    )
}

/// The doubled signed area of the depth-grid triangle `q` (oriented like `p`), if the plane of `t` through it can be
/// walked (`Err` otherwise: see below).
///
/// A covered pixel lies in the snapped triangle `p`, so it is a convex combination of the `p_k = q_k - r_k` (`r_k`
/// the rounding of the snap against the depth grid): `P = Q - R` with `Q` in `q`'s triangle and each coordinate of
/// `R` at most `r = max |r_k|`. So its `T` is within `(|T_x| + |T_y|) r` of a value in `[T_min, T_max]` (`T_x`, `T_y`
/// the plane's gradient per grid unit). Accepted when `(|gx| + |gy|) r <= 2^61 |area|` (`T < 2^61`): every covered
/// pixel's `T` then lies in `(-2^61, 2^62)` and its walked value is exact modulo `2^64` (module doc); the range test
/// rejects the extrapolated pixels whose `T` leaves `[2^F, T_near]`. Otherwise `Err(Some(e))`: with `T` shifted
/// right by `e` bits (`F - e` fraction bits, the plane's rounding then `2^e` times coarser) it is accepted; `Err(None)`
/// for a degenerate `q`. Ranges: positions below `2^31` units (the grid's choice), so differences below `2^31`,
/// `|g| < 2^93`, `r <= 2^(bits - 9) < 2^21`, `|area| < 2^63`.
#[inline(never)] // once per triangle: out of line, one copy (flash)
pub(crate) fn depth_plane(
    p: &[Sub; 3],
    q: &[Sub; 3],
    t: &[i64; 3],
    bits: u32,
    (ox, oy): (i32, i32),
) -> Result<i64, Option<u32>> {
    let [q0, q1, q2] = *q;
    let (e1x, e1y) = ((q1.x - q0.x) as i128, (q1.y - q0.y) as i128);
    let (e2x, e2y) = ((q2.x - q0.x) as i128, (q2.y - q0.y) as i128);
    let area = e1x * e2y - e2x * e1y;
    if area == 0 {
        return Err(None);
    }
    let (d1, d2) = (t[1] as i128 - t[0] as i128, t[2] as i128 - t[0] as i128);
    let gx = d1 * e2y - d2 * e1y;
    let gy = d2 * e1x - d1 * e2x;
    let r = (0..3)
        .map(|k| {
            let (rx, ry) = snap_rounding(p[k], q[k], bits, (ox, oy));
            rx.unsigned_abs().max(ry.unsigned_abs())
        })
        .max()
        .unwrap_or(0) as i128;
    let (lhs, rhs) = ((gx.abs() + gy.abs()) * r, area.abs() << 61);
    if lhs <= rhs {
        return Ok(area as i64); // below 2^63
    }
    // lhs < rhs 2^e; one more bit for the rounding of the shifted `T` (which moves `g` by at most `2^32`).
    Err(Some(rhs.leading_zeros() - lhs.leading_zeros() + 2))
}

/// The fast tier's way to the depth-grid plane without solving it: its `T` at the three snapped vertices, so that the
/// plane through `(p_k, T_q(p_k))` (what the fast set-ups solve, from the snapped positions they already have) is the
/// depth-grid plane itself (an affine function is fixed by three points).
///
/// `T_q(p_k) = t_k + grad T_q . r_k` with `r_k = p_k - q_k` (the snap's rounding against the depth grid, below
/// `2^(bits - 9) <= 2^21` units). The gradient's numerators `(gx, gy)` are exact (`i64 x i32` products from two
/// 32-bit multiplies each, below `2^94`); each is divided by the doubled area with its top 32 bits (`2^-31`) and one
/// 32-bit reciprocal of the area's top 32 bits ([`crate::fast::fresh61`]: `2^-27.6`, the area's truncation `2^-31`), kept to 32
/// bits (`2^-28`): below `2^-26.5` relative; then times `r` exactly, truncated (one unit). Accepted when
/// `|c_k|`'s bound is at most `T_min / 2^9` for every `k` (a plane gentle over the snap's 1/512 px), so the corrected
/// values err by below `T_min 2^-35`, far inside both fast set-ups' margins; `None` otherwise (the exact solve then
/// runs). 32- and 64-bit arithmetic only (no 128-bit product: those are library calls on the 32-bit cores). Only for
/// vertices off the snap grid.
///
/// Two ways to these values, the same bound: [`t_at_snapped_wide`] (described here) and [`t_at_snapped_narrow`],
/// which falls back to the wide way where it cannot vouch for its result. The narrow way is `NARROW`, the choice of
/// the strategy that seeds its reciprocal by division ([`crate::recip::FastDiv`], for cores with `UMULL` and a divider):
/// on the Cortex-M4 it takes about 73% of the wide way's instructions (550 against 753 a call on W4: 3.6% fewer a
/// frame). On the Cortex-M0, whose 64-bit products are four `MULS` each, it is the dearer (1,491 against 1,241
/// instructions a call on the terrain), so [`crate::recip::Fast`] keeps the wide way. The two round differently within
/// the bound, so the strategy decides, and each strategy's frames stay the same on every core.
#[inline(never)] // once per triangle: out of line, one copy (flash)
pub(crate) fn t_at_snapped<const NARROW: bool>(s: &Setup) -> Option<[i64; 3]> {
    #[cfg(test)]
    T_AT_SNAPPED_CALLS.with(|c| c.borrow_mut().push(s.p.map(|p| (p.x, p.y))));
    if !NARROW {
        return t_at_snapped_wide(s);
    }
    match t_at_snapped_narrow(s) {
        Narrow::Done(t) => Some(t),
        Narrow::Steep => None,
        Narrow::Unsure => t_at_snapped_wide(s),
    }
}

/// [`t_at_snapped`] of a triangle as it reaches a draw of a list: none, without their work, where the render state's
/// `cull` drops it (a culled triangle reads no values; the draw culls it by the same test before it would), where a
/// triangle of a mesh is culled before its draw ([`TMemo::early_cull`]). Out of line beside it: the terrain drawn
/// with [`Cull::Ccw`] on the M4 takes 23.6% fewer instructions (README, "Culling a list's triangles"), and a draw that
/// never culls keeps its code but for the call's argument (a culled triangle's early return from the draw itself saved
/// more, but took the M0's standard scenes 72 bytes deeper into its stack).
#[inline(never)]
pub(crate) fn t_at_snapped_unless_culled<const NARROW: bool>(
    s: &Setup,
    cull: Cull,
) -> Option<[i64; 3]> {
    if culls(cull, &s.p) {
        return None;
    }
    t_at_snapped::<NARROW>(s)
}

/// The draw's cull rule on the doubled area of a snapped triangle (in any integer type that holds it exactly): a
/// zero area is dropped whatever `cull` says, a non-zero one when its sign is the culled one. Every set-up of
/// [`crate::Rasterizer::draw`] (any format) and of [`crate::Rasterizer::draw_wireframe`] tests it, and [`culls`]
/// before them.
#[inline(always)]
pub(crate) fn culls_area<A: PartialOrd + Default>(cull: Cull, area: A) -> bool {
    let zero = A::default();
    match cull {
        _ if area == zero => true,
        Cull::Cw if area > zero => true,
        Cull::Ccw if area < zero => true,
        _ => false,
    }
}

/// Whether `cull` drops the snapped triangle `p` ([`culls_area`]), tested only where `cull` culls: without culling
/// the draw drops a degenerate triangle itself. Snapped coordinates lie in the guard band (below `2^20` units):
/// differences below `2^21`, products below `2^42` ([`crate::fast::smul_wide`]: no `__aeabi_lmul` call on the
/// Cortex-M0).
#[inline]
pub(crate) fn culls(cull: Cull, p: &[Sub; 3]) -> bool {
    use crate::fast::smul_wide;
    let [p0, p1, p2] = *p;
    match cull {
        Cull::None => false,
        _ => culls_area(
            cull,
            smul_wide(p1.x - p0.x, p2.y - p0.y) - smul_wide(p2.x - p0.x, p1.y - p0.y),
        ),
    }
}

#[cfg(test)]
std::thread_local! {
    /// The snapped vertices of each call of [`t_at_snapped`] on this thread (tests of the mesh's plane cache count
    /// what it saves).
    pub(crate) static T_AT_SNAPPED_CALLS: core::cell::RefCell<std::vec::Vec<[(i32, i32); 3]>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
    /// The snapped vertices of each exact plane solve ([`Plane::solve_ref`]) on this thread (tests of the memo count
    /// what it saves).
    pub(crate) static PLANE_SOLVES: core::cell::RefCell<std::vec::Vec<[(i32, i32); 3]>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
    /// The snapped vertices and the depth-grid values of each draw that used them (computed or remembered).
    #[allow(clippy::type_complexity)]
    pub(crate) static FAST_T_USED: core::cell::RefCell<std::vec::Vec<([(i32, i32); 3], Option<[i64; 3]>)>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
}

/// What [`t_at_snapped_narrow`] found.
pub(crate) enum Narrow {
    /// The values, within the bound.
    Done([i64; 3]),
    /// Some `|c_k|` is certainly above `T_min / 2^9`: [`t_at_snapped_wide`], whose bound on `|c_k|` is an upper
    /// bound, would decline too.
    Steep,
    /// It cannot vouch for its result: [`t_at_snapped_wide`] decides.
    Unsure,
}

/// `floor(v / 2^s)` for `s <= 40` whose result fits `i32`, from 32-bit shifts (a variable 64-bit shift is a library
/// call on the 32-bit cores).
#[inline(always)]
fn sar_to_i32(v: i64, s: u32) -> i32 {
    let (hi, lo) = ((v >> 32) as i32, v as u32);
    if s == 0 {
        lo as i32
    } else if s >= 32 {
        hi >> (s - 32)
    } else {
        ((hi << (32 - s)) as u32 | (lo >> s)) as i32
    }
}

/// `floor(v / 2^s)` for any `s` (0 from 64 on), from 32-bit shifts ([`crate::fast::shr_pieces`]).
#[inline(always)]
fn shr_u64(v: u64, s: u32) -> u64 {
    if s < 64 {
        crate::fast::shr_pieces(v, s)
    } else {
        0
    }
}

/// [`t_at_snapped`] in 32- and 64-bit pieces with a bound checked per triangle: the values ([`Narrow::Done`]), a plane
/// certainly too steep ([`Narrow::Steep`]), or [`Narrow::Unsure`] where the bound is not small enough, and the caller
/// then takes [`t_at_snapped_wide`].
///
/// `c_k = (gx rx_k + gy ry_k) / A` with the gradient's numerators `gx = d1 e2y - d2 e1y`, `gy = d2 e1x - d1 e2x`
/// (`d_i = t_i - t_0`, `e_i = q_i - q_0`, `A` the doubled area, exact in `i64`). Here:
/// - `d_i = D_i 2^sd + rho_i` (`D_i` the floor, `|D_i| <= 2^30`, `0 <= rho_i < 2^sd`);
/// - `g' = D1 e2y - D2 e1y` (and `gy'`) exact in `i64` (below `2^62`), `g' = G 2^su + sigma` (`|G| <= 2^30`,
///   `0 <= sigma < 2^su`);
/// - `N_k = Gx rx_k + Gy ry_k` exact (below `2^52`); `c~_k = N_k 2^(sd + su) / A`.
///
/// Then `c_k - c~_k = (2^sd (sigma_x rx + sigma_y ry) + (rho1 e2y - rho2 e1y) rx + (rho2 e1x - rho1 e2x) ry) / A`,
/// so `|c_k - c~_k| <= 2^sd (2^su + W) R / |A|` with `W = max(|e1y| + |e2y|, |e1x| + |e2x|)` and
/// `R = max_k (|rx_k| + |ry_k|)`. Taken only when that is at most `T_min 2^-36` (`T_min >= 2^lt`; compared exactly in
/// integers). `c~_k` is formed as `top32(|N_k|) x fresh61(top32(|A|))` (a 64-bit product, then a shift):
/// truncations `2^-31` (each top) and the reciprocal `2^-27.9` (`Chord`, the same on every core and strategy), so
/// within `2^-27.7 |c~_k|` plus one unit of the final shift. Accepted only when every computed `|c_k|` is at most
/// `lim - lim / 2^8` (`lim = T_min / 2^9`), so the exact `|c_k|` is below `lim` as [`t_at_snapped`] asks, and
/// `T_min >= 2^40`. Error: `T_min (2^-36 + 2^-9 2^-27.7) + 1 <= T_min (1.455 + 1.1 + 0.09) 10^-11 < T_min 2^-35`
/// (`2.91 10^-11`), the bound [`t_at_snapped`] states.
#[inline(always)]
pub(crate) fn t_at_snapped_narrow(s: &Setup) -> Narrow {
    use crate::fast::{bits64, fresh61, mul_wide, smul_wide, Chord};
    let (p, q, t) = (s.p, s.q, s.t);
    let [q0, q1, q2] = q;
    let (e1x, e1y) = (q1.x.wrapping_sub(q0.x), q1.y.wrapping_sub(q0.y));
    let (e2x, e2y) = (q2.x.wrapping_sub(q0.x), q2.y.wrapping_sub(q0.y));
    // Differences below 2^31: the doubled area below 2^63.
    let area = smul_wide(e1x, e2y) - smul_wide(e2x, e1y);
    let t_min = t[0].min(t[1]).min(t[2]);
    if area == 0 || t_min < 1 << 40 {
        return Narrow::Unsure;
    }
    let lt = bits64(t_min as u64) as i32 - 1; // T_min >= 2^lt
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]); // below 2^61
    let sd = (bits64(d1.unsigned_abs() | d2.unsigned_abs()) as i32 - 30).max(0) as u32;
    let (dd1, dd2) = (sar_to_i32(d1, sd), sar_to_i32(d2, sd)); // |D| <= 2^30
    let gx = smul_wide(dd1, e2y) - smul_wide(dd2, e1y); // below 2^62
    let gy = smul_wide(dd2, e1x) - smul_wide(dd1, e2x);
    let su = (bits64(gx.unsigned_abs() | gy.unsigned_abs()) as i32 - 30).max(0) as u32;
    let (ggx, ggy) = (sar_to_i32(gx, su), sar_to_i32(gy, su)); // |G| <= 2^30
    let r = [0, 1, 2].map(|k| snap_rounding(p[k], q[k], s.dbits, s.dorigin));
    // R, below 2^22; W, below 2^32 (two magnitudes below 2^31 each).
    let rr = r
        .iter()
        .map(|&(x, y)| x.unsigned_abs() + y.unsigned_abs())
        .max()
        .unwrap_or(0);
    let w = (e1y.unsigned_abs() + e2y.unsigned_abs()).max(e1x.unsigned_abs() + e2x.unsigned_abs());
    let a = area.unsigned_abs();
    // 2^sd (2^su + W) R / |A| <= 2^(lt - 36), compared exactly: `bn = (2^su + W) R` below 2^55 (`su <= 32`), `a`
    // below 2^63.
    let bn = ((rr as u64) << su) + mul_wide(w, rr);
    let k = lt - 36 - sd as i32;
    let fits = if k >= 0 {
        bits64(a) as i32 + k >= 56 || bn <= a << k
    } else {
        bits64(bn) as i32 - k < 64 && bn << -k <= a
    };
    if !fits {
        return Narrow::Unsure;
    }
    let (am, al) = crate::fast::top32(a); // a = am 2^(32 - al), truncated
    let x = fresh61::<Chord>(am) as u32; // about 2^61 / am, in (2^29, 2^30]
    let lim = (t_min >> 9) as u64;
    let ok = lim - (lim >> 8);
    let mut out = t;
    for k in 0..3 {
        let (rx, ry) = r[k];
        let n = smul_wide(ggx, rx) + smul_wide(ggy, ry); // below 2^52
        if n == 0 {
            continue;
        }
        let (nm, nl) = crate::fast::top32(n.unsigned_abs());
        // c~ = nm x 2^(sd + su + al - nl - 61), the product in [2^60, 2^64).
        let e = sd as i32 + su as i32 + al - nl - 61;
        if e >= 0 {
            return Narrow::Steep; // |c| >= 2^60 (1 - 2^-27)
        }
        let c = shr_u64(mul_wide(nm, x), (-e) as u32);
        if c > ok {
            // Steep for certain when even less its errors (below `2^-27 |c| + 2 + T_min 2^-36`) it exceeds `lim` by
            // more than the wide way's own relative error (`2^-26.5`), so that way's value is above `lim` too.
            return if c - (c >> 26) - 2 - (lim >> 20) > lim + (lim >> 19) {
                Narrow::Steep
            } else {
                Narrow::Unsure
            };
        }
        let c = if (n < 0) != (area < 0) {
            -(c as i64)
        } else {
            c as i64
        };
        out[k] = t[k] + c;
        if out[k] >= 1 << 61 || out[k] <= 0 {
            return Narrow::Unsure;
        }
    }
    Narrow::Done(out)
}

/// [`t_at_snapped`]'s exact gradient numerators (described there): `Fast`'s way, and `FastDiv`'s for the triangles
/// [`t_at_snapped_narrow`] cannot vouch for (slivers, steep planes). Out of line: one copy for both (flash).
#[inline(never)]
pub(crate) fn t_at_snapped_wide(s: &Setup) -> Option<[i64; 3]> {
    use crate::fast::{bits64, fresh61, mul_wide, shl64, shr64, smul_wide, Chord};
    let (p, q, t) = (s.p, s.q, s.t);
    // `a b` exactly for `|a| < 2^63`, `|b| < 2^31`, as (sign, magnitude): two 32 x 32 -> 64 products.
    #[inline(always)]
    fn mul_wide_signed(a: i64, b: i32) -> (bool, u128) {
        let (ua, ub) = (a.unsigned_abs(), b.unsigned_abs());
        let m = ((mul_wide((ua >> 32) as u32, ub) as u128) << 32) + mul_wide(ua as u32, ub) as u128;
        ((a < 0) != (b < 0), m)
    }
    // `x - y` of two (sign, magnitude) pairs, as (sign, magnitude).
    #[inline(always)]
    fn sub((sx, x): (bool, u128), (sy, y): (bool, u128)) -> (bool, u128) {
        if sx != sy {
            (sx, x + y)
        } else if x >= y {
            (sx, x - y)
        } else {
            (!sx, y - x)
        }
    }
    // `v` (nonzero, below 2^96) normalised to [2^31, 2^32) and the shift back: `v` is about `top 2^sh`, truncated by
    // below `2^-31`.
    #[inline(always)]
    fn top(v: u128) -> (u32, i32) {
        // Constant shifts of the u128 only (a variable one is a library call on the 32-bit cores): below 2^96, so
        // `v >> 32` fits a u64 whenever `v` does not, and its truncation is inside the 2^-31 kept.
        let (w, extra) = if (v >> 64) as u64 != 0 {
            ((v >> 32) as u64, 32)
        } else {
            (v as u64, 0)
        };
        let b = bits64(w) as i32;
        let n = if b <= 32 {
            shl64(w, (32 - b) as u32)
        } else {
            shr64(w, (b - 32) as u32)
        };
        (n as u32, b - 32 + extra)
    }
    let [q0, q1, q2] = q;
    let (e1x, e1y) = (q1.x.wrapping_sub(q0.x), q1.y.wrapping_sub(q0.y));
    let (e2x, e2y) = (q2.x.wrapping_sub(q0.x), q2.y.wrapping_sub(q0.y));
    // Differences below 2^31: each product below 2^62, the doubled area below 2^63 (products by `mul_wide`: the
    // M0's four `MULS` rather than an `__aeabi_lmul` call).
    let area = smul_wide(e1x, e2y) - smul_wide(e2x, e1y);
    if area == 0 {
        return None;
    }
    let a = area.unsigned_abs();
    let la = 64 - bits64(a);
    let m = (shl64(a, la) >> 32) as u32; // in [2^31, 2^32): a = m 2^(32 - la), truncated
    let x = fresh61::<Chord>(m) as u32; // about 2^61 / m (set-up: one seed for every strategy)
                                        // The gradient's numerators `g = (d1 e2y - d2 e1y, d2 e1x - d1 e2x)`, exact (below 2^94), each divided by the
                                        // area as `gh x 2^(sg + la - 93)` (`gh x` below 2^62), kept as its top 32 bits `G` and exponent `sg + la - 61`.
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let grad = |g: (bool, u128)| -> (bool, u32, i32) {
        if g.1 == 0 {
            return (false, 0, 0);
        }
        let (gh, sg) = top(g.1);
        (
            g.0 != (area < 0),
            (mul_wide(gh, x) >> 32) as u32,
            sg + la as i32 - 61,
        )
    };
    let gx = grad(sub(mul_wide_signed(d1, e2y), mul_wide_signed(d2, e1y)));
    let gy = grad(sub(mul_wide_signed(d2, e1x), mul_wide_signed(d1, e2x)));
    // `c_k = grad . r_k` (`r_k` the snap's rounding against the grid, below 2^21): each term `G |r| 2^e`, `G |r|`
    // below 2^53, with its truncation (`+ 1`) in the bound.
    let term = |(neg, gm, e): (bool, u32, i32), r: i32| -> Option<(i64, u64)> {
        if gm == 0 || r == 0 {
            return Some((0, 0));
        }
        let v = mul_wide(gm, r.unsigned_abs());
        let v = if e >= 0 {
            if e >= 10 || shr64(v, (62 - e) as u32) != 0 {
                return None; // a term of 2^62 or more
            }
            shl64(v, e as u32)
        } else {
            shr64(v, ((-e) as u32).min(63))
        };
        Some((
            if neg != (r < 0) {
                -(v as i64)
            } else {
                v as i64
            },
            v + 1,
        ))
    };
    let t_min = t[0].min(t[1]).min(t[2]);
    let lim = (t_min >> 9) as u64;
    let mut out = t;
    for k in 0..3 {
        let (rx, ry) = snap_rounding(p[k], q[k], s.dbits, s.dorigin);
        let (cx, bx) = term(gx, rx)?;
        let (cy, by) = term(gy, ry)?;
        if bx + by > lim {
            return None;
        }
        out[k] = t[k] + cx + cy;
        if out[k] >= 1 << 61 || out[k] <= 0 {
            return None;
        }
    }
    Some(out)
}

/// The fewest fraction bits a sliver's `T` is solved with (see [`depth_plane`]); below, the snapped plane.
pub(crate) const MIN_FRAC: u32 = 8;

/// `a b` exactly (two 32 x 32 -> 64 products).
#[inline]
pub(crate) fn mul_64_32(a: i64, b: i32) -> i128 {
    use crate::fast::mul_wide;
    let (ua, ub) = (a.unsigned_abs(), b.unsigned_abs());
    let m = ((mul_wide((ua >> 32) as u32, ub) as u128) << 32) + mul_wide(ua as u32, ub) as u128;
    if (a < 0) != (b < 0) {
        -(m as i128)
    } else {
        m as i128
    }
}

/// `a b` exactly for `|a| < 2^96` (three 32 x 32 -> 64 products; the plane's gradients are below `2^94`).
#[inline]
pub(crate) fn mul_96_32(a: i128, b: i32) -> i128 {
    use crate::fast::mul_wide;
    debug_assert!(a.unsigned_abs() < 1 << 96);
    let (ua, ub) = (a.unsigned_abs(), b.unsigned_abs());
    let m = ((mul_wide((ua >> 64) as u32, ub) as u128) << 64)
        + ((mul_wide((ua >> 32) as u32, ub) as u128) << 32)
        + mul_wide(ua as u32, ub) as u128;
    if (a < 0) != (b < 0) {
        -(m as i128)
    } else {
        m as i128
    }
}

/// A quantity linear in screen space: its value at `(i_ref, current row)` and its steps per column and row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Plane {
    pub(crate) row: i64,
    pub(crate) sx: i64,
    pub(crate) sy: i64,
}

impl Plane {
    /// Solves `V(X, Y) = V0 + (gx (X - X0) + gy (Y - Y0)) / area` exactly in i128 through the positions `g.dq`
    /// (X, Y in units of `2^-dbits` px) and rounds the steps and the reference value once each. Steps may wrap for
    /// slivers (see the module doc). Ranges (`|V| < 2^61`; positions, their differences and the offset of the
    /// reference pixel below `2^31` units, by the choice of the grid): `|g| < 2^93`, the numerator below `2^125`,
    /// `area < 2^63`.
    pub(crate) fn solve(v: [i64; 3], g: &Geom) -> Plane {
        Plane::solve_ref(v, g).at_row(g)
    }
    /// [`Plane::solve`] at the reference row `g.j_ref` (what a memo keeps across bands: [`Solved`]).
    pub(crate) fn solve_ref(v: [i64; 3], g: &Geom) -> Plane {
        #[cfg(test)]
        PLANE_SOLVES.with(|c| c.borrow_mut().push(g.p.map(|p| (p.x, p.y))));
        let [p0, p1, p2] = g.dq;
        // |v| < 2^61, so the differences fit i64; the products by 32-bit position differences are exact limb
        // products (`mul_64_32`), where an i128 multiply is a chain of library calls on the 32-bit cores.
        let (d1, d2) = (v[1] - v[0], v[2] - v[0]);
        let mut gx = mul_64_32(d1, p2.y - p0.y) - mul_64_32(d2, p1.y - p0.y);
        let mut gy = mul_64_32(d2, p1.x - p0.x) - mul_64_32(d1, p2.x - p0.x);
        let mut area = g.darea as i128;
        if area < 0 {
            (gx, gy, area) = (-gx, -gy, -area);
        }
        let u = 1i128 << g.dbits;
        let (rx, ry) = (
            u * (g.i_ref - g.dorigin.0 as i64) as i128 + u / 2 - p0.x as i128,
            u * (g.j_ref - g.dorigin.1) as i128 + u / 2 - p0.y as i128,
        );
        // The reference offset is below 2^31 units (the grid's choice): three limb products then; any other offset
        // takes the general i128 product (the same exact value).
        let num = match (i32::try_from(rx), i32::try_from(ry)) {
            (Ok(x), Ok(y)) => mul_96_32(gx, x) + mul_96_32(gy, y),
            _ => gx * rx + gy * ry,
        };
        // Three divisions by the area: its reciprocal once (exact quotients, `Divisor`).
        let dv = Divisor::new(area as u64);
        Plane {
            row: (v[0] as i128 + dv.div_round(num)) as i64,
            sx: dv.div_round(gx << g.dbits) as i64,
            sy: dv.div_round(gy << g.dbits) as i64,
        }
    }
    /// From the reference row to the first row walked, by whole row steps (what walking there would give).
    #[inline]
    pub(crate) fn at_row(mut self, g: &Geom) -> Plane {
        self.row = self
            .row
            .wrapping_add(self.sy.wrapping_mul((g.j0 - g.j_ref) as i64));
        self
    }
    /// The fast tier's plane of `T` for a small triangle (box under 127 px), from one 64-bit reciprocal of the
    /// doubled area instead of three exact 128-bit divisions; `None` where its error bound does not hold (then the
    /// exact solve runs).
    ///
    /// The vertices' `T` (below `2^61`) are rounded to `T' = T >> 16` (at most `2^15` off each, so at most `2^15` at any
    /// point inside the triangle, a convex combination of them). With edge vectors below `2^15` sub-pixels the
    /// gradients `g` of `T'` times the doubled area fit `i64` (`< 2^61`). `inv = floor(2^62 / area)`, and a step in
    /// `T` per pixel is `floor(g inv / 2^38)`, below the exact `g 2^24 / area` by at most `eps = |g| 2^-38 + 1`.
    /// The value at the reference pixel is `T'_0 2^16` plus the steps times its offset from vertex 0 (at most 128 px
    /// each way), and a covered pixel is at most 127 px further: at most `510 eps + 1` from the steps.
    /// Total, at any covered pixel: `2^15 + 510 (|g| 2^-38 + 1) + 1 < |g| 2^-29 + 2^16`. This is accepted when
    /// `|gx| + |gy| <= T_min / 2^5` and `T_min >= 2^51` (`T_min` the smallest vertex `T`, a lower bound of every covered
    /// pixel's): then the error is below `T_min (2^-34 + 2^-35) < 2^-33` relative, the exact solve's own bound on
    /// these triangles. Steps must also fit: `|g| < area 2^38`.
    pub(crate) fn solve_fast(v: [i64; 3], g: &Geom) -> Option<Plane> {
        let [p0, p1, p2] = g.p;
        let t_min = v[0].min(v[1]).min(v[2]);
        if t_min < 1 << 51 {
            return None;
        }
        let tp = v.map(|t| (t + (1 << 15)) >> 16);
        let (d1, d2) = (tp[1] - tp[0], tp[2] - tp[0]);
        let (e1x, e1y) = ((p1.x - p0.x) as i64, (p1.y - p0.y) as i64);
        let (e2x, e2y) = ((p2.x - p0.x) as i64, (p2.y - p0.y) as i64);
        let gx = d1 * e2y - d2 * e1y;
        let gy = d2 * e1x - d1 * e2x;
        let area = g.area as u64;
        let (ax, ay) = (gx.unsigned_abs(), gy.unsigned_abs());
        // `|g| < area 2^38`, written so that nothing overflows (`area << 38` would for areas above 2^26).
        if ax + ay > (t_min >> 5) as u64 || (ax >> 38) >= area || (ay >> 38) >= area {
            return None;
        }
        let inv = (1u64 << 62) / area;
        let step = |g: i64| ((g as i128 * inv as i128) >> 38) as i64;
        let (sx, sy) = (step(gx), step(gy));
        let rx = 256 * g.i_ref + 128 - p0.x as i64;
        let ry = 256 * g.j_ref as i64 + 128 - p0.y as i64;
        let off = (sx as i128 * rx as i128 + sy as i128 * ry as i128) >> 8;
        Some(
            Plane {
                row: (tp[0] << 16).wrapping_add(off as i64),
                sx,
                sy,
            }
            .at_row(g),
        )
    }

    #[inline(always)]
    pub(crate) fn at(&self, di: i64) -> i64 {
        self.row.wrapping_add(self.sx.wrapping_mul(di))
    }
    /// [`Plane::at`] at a covered column's offset `di` from the box's left column (`0 <= di`, at most the box's width:
    /// under `2^13` px inside the guard band). On the Cortex-M0, where `di < 2^16`, by [`crate::fast::mul_small`]:
    /// no 64-bit multiply (a library call there; see [`crate::recip::span_last`]). The same bits either way.
    #[inline(always)]
    pub(crate) fn at_col(&self, di: i64) -> i64 {
        if crate::fast::NO_WIDE && (di as u64) < 1 << 16 {
            self.row
                .wrapping_add(crate::fast::mul_small(self.sx as u64, di as u32) as i64)
        } else {
            self.at(di)
        }
    }
    #[inline(always)]
    pub(crate) fn next_row(&mut self) {
        self.row = self.row.wrapping_add(self.sy);
    }
}

/// Seed 001's offset `m * slope + constant` for a triangle whose vertices' codes are `c` (any format's codes, as
/// `f32`): `m` is the larger of `|d code / dx|` and `|d code / dy|` (codes per pixel) of the plane through them.
/// Rounded to the nearest code and clamped to `[-max, max]`.
#[cfg(feature = "bias")]
pub(crate) fn slope_bias(state: &RenderState, p: &[Sub; 3], c: [f32; 3], max: f32) -> i32 {
    let (slope, constant) = (state.slope_scale_depth_bias, state.depth_bias);
    let (dx1, dy1) = ((p[1].x - p[0].x) as f32, (p[1].y - p[0].y) as f32);
    let (dx2, dy2) = ((p[2].x - p[0].x) as f32, (p[2].y - p[0].y) as f32);
    let area = dx1 * dy2 - dx2 * dy1;
    let (c1, c2) = (c[1] - c[0], c[2] - c[0]);
    // per sub-pixel, times 256 per pixel
    let gx = (c1 * dy2 - c2 * dy1) / area * 256.0;
    let gy = (c2 * dx1 - c1 * dx2) / area * 256.0;
    let m = if gx.abs() > gy.abs() {
        gx.abs()
    } else {
        gy.abs()
    };
    let off = m * slope + constant;
    if !off.is_finite() {
        return 0;
    }
    round_half_away(off).clamp(-max, max) as i32
}

/// A finite `v` rounded to the nearest integer, ties away from zero. (`f32::round` is not in `core`, and `micromath`'s
/// `round`, like the sum `v + 0.5` truncated, is not this: the sum rounds in f32, so `0.5 - 2^-25` becomes 1 and
/// `2^23 + 1` becomes `2^23 + 2`.) Below `2^23`, `t = floor(|v|)` is exact through `u32`, and so are `|v| - t` (the
/// fraction of `|v|`) and `t + 1`; from `2^23` on every f32 is an integer.
#[cfg(feature = "bias")]
fn round_half_away(v: f32) -> f32 {
    let a = v.abs();
    let r = if a >= 8_388_608.0 {
        a
    } else {
        let t = a as u32 as f32;
        if a - t >= 0.5 {
            t + 1.0
        } else {
            t
        }
    };
    if v < 0.0 {
        -r
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`sar_to_i32`] is `floor(v / 2^s)` on its whole stated domain (`s <= 40`, the result an `i32`): each of its
    /// three ways (no shift, the high word alone from 32 on, the two words between) against the 64-bit shift.
    #[test]
    fn sar_to_i32_is_the_floor_shift() {
        let mut rnd = crate::xorshift(0x0DDB_A11C_AFE5_EED5);
        for k in 0..200_000u64 {
            let s = (k % 41) as u32;
            // A value whose quotient fits an i32: a random i32 shifted back up, plus a remainder below 2^s.
            let q = rnd() as i32 as i64;
            let rem = if s == 0 {
                0
            } else {
                (rnd() >> (64 - s)) as i64
            };
            // (From `s = 32` on every `i64` has such a quotient: the shift may drop `q`'s top bits.)
            let v = (q << s).wrapping_add(rem);
            assert_eq!(sar_to_i32(v, s), (v >> s) as i32, "{v} >> {s}");
        }
        // The ends: the largest and smallest quotients, with and without a remainder.
        for s in 0..=40u32 {
            let (hi, lo) = (
                (i32::MAX as i64).min(i64::MAX >> s) << s,
                (i32::MIN as i64).max(i64::MIN >> s) << s,
            );
            for v in [-1, 0, 1, hi, hi | ((1 << s) - 1), lo, lo | ((1 << s) - 1)] {
                assert_eq!(sar_to_i32(v, s), (v >> s) as i32, "{v} >> {s}");
            }
        }
    }

    /// [`depth_plane`] accepts exactly where its stated rule holds, `(|gx| + |gy|) r <= 2^61 |A|` (the gradient's
    /// numerators and the area from the depth-grid triangle, `r` the largest coordinate of the snap's roundings,
    /// all formed here from the definitions in `i128`), and otherwise names the fewest extra bits `e` with a margin:
    /// `lhs < rhs 2^(e - 1)`, and not more than 3 bits beyond the fewest that would do. Random triangles on the
    /// depth grid from slivers to 100 px, with `T` up to `2^61` and planes from flat to steep, so that both sides
    /// of the rule are met.
    #[test]
    fn depth_plane_accepts_by_its_stated_rule() {
        let mut rnd = crate::xorshift(0xDE97_0B1A_7E00_5EED);
        let (mut ok, mut shifted) = (0u32, 0u32);
        for k in 0..100_000u64 {
            let bits = 17 + (rnd() % 13) as u32; // 17 to 29 fraction bits
            let up = bits - SUBPIXEL_BITS;
            let size = 1i64 << (rnd() % (31 - bits) as u64).min(7); // up to 128 px, positions below 2^30 units
            let origin = ((rnd() % 200) as i32, (rnd() % 200) as i32);
            // Depth-grid positions relative to the origin pixel, within `size` pixels; the snapped ones their
            // rounding to 1/256 px (absolute sub-pixels).
            let mut pos = || (rnd() % ((size as u64) << (bits - 1))) as i64;
            let mut q = [0; 3].map(|_| Sub {
                x: pos() as i32,
                y: pos() as i32,
            });
            if k % 3 == 0 {
                // A sliver: the third vertex near the line through the first two.
                let f = (rnd() % 1024) as i64;
                let off = 1 + (rnd() % 64) as i64;
                q[2].x = (q[0].x as i64 + (q[1].x as i64 - q[0].x as i64) * f / 1024 + off)
                    .min(i32::MAX as i64) as i32;
                q[2].y = (q[0].y as i64 + (q[1].y as i64 - q[0].y as i64) * f / 1024) as i32;
            }
            let snap =
                |v: i32, o: i32| ((v as i64 + (1 << (up - 1))) >> up) as i32 + (o << SUBPIXEL_BITS);
            let p = q.map(|q| Sub {
                x: snap(q.x, origin.0),
                y: snap(q.y, origin.1),
            });
            let top = 1i64 << (40 + rnd() % 21); // T up to 2^61
            let spread = top >> (rnd() % 40);
            let t = [0; 3].map(|_| top - (rnd() % spread as u64) as i64);
            // The rule, from the definitions.
            let (e1, e2) = (
                ((q[1].x - q[0].x) as i128, (q[1].y - q[0].y) as i128),
                ((q[2].x - q[0].x) as i128, (q[2].y - q[0].y) as i128),
            );
            let area = e1.0 * e2.1 - e2.0 * e1.1;
            let got = depth_plane(&p, &q, &t, bits, origin);
            if area == 0 {
                assert_eq!(got, Err(None));
                continue;
            }
            let (d1, d2) = (t[1] as i128 - t[0] as i128, t[2] as i128 - t[0] as i128);
            let (gx, gy) = (d1 * e2.1 - d2 * e1.1, d2 * e1.0 - d1 * e2.0);
            let r = (0..3)
                .map(|j| {
                    let rx = ((p[j].x as i128 - ((origin.0 as i128) << SUBPIXEL_BITS)) << up)
                        - q[j].x as i128;
                    let ry = ((p[j].y as i128 - ((origin.1 as i128) << SUBPIXEL_BITS)) << up)
                        - q[j].y as i128;
                    rx.abs().max(ry.abs())
                })
                .max()
                .unwrap();
            let (lhs, rhs) = ((gx.abs() + gy.abs()) * r, area.abs() << 61);
            match got {
                Ok(a) => {
                    assert!(lhs <= rhs, "{k}: accepted beyond the rule");
                    assert_eq!(a as i128, area);
                    ok += 1;
                }
                Err(Some(e)) => {
                    assert!(lhs > rhs, "{k}: declined within the rule");
                    assert!(lhs < rhs << (e - 1), "{k}: {e} extra bits are too few");
                    assert!(
                        e < 3 || lhs >= rhs << (e - 3),
                        "{k}: {e} extra bits are more than needed"
                    );
                    shifted += 1;
                }
                Err(None) => panic!("{k}: degenerate, with area {area}"),
            }
        }
        std::println!("accepted {ok}, shifted {shifted}");
        assert!(ok > 1000 && shifted > 1000, "{ok} {shifted}");
    }

    /// [`Plane::solve_fast`] answers exactly where its stated rule holds (`T_min >= 2^51`, `|gx| + |gy| <= T_min /
    /// 2^5` and each `|g| < 2A 2^38`, with `g` the gradient's numerators of `T' = round(T / 2^16)`, formed here in
    /// `i128`), and then its plane is within its derivation's total, `2^15 + 510 (|g| 2^-38 + 1) + 1` (below `|g|
    /// 2^-29 + 2^16`), so within `T_min 2^-33` (the exact solve's bound, which it stands in for), of the
    /// exact plane through the vertices at every pixel centre in the triangle. Random triangles under 127 px
    /// on the snap grid and slivers, with `T` from `2^48` to `2^61` and planes from flat to beyond the rule.
    #[test]
    fn solve_fast_answers_by_its_rule_within_its_bound() {
        let mut rnd = crate::xorshift(0x50F7_FA57_0000_D1CE);
        let (mut answered, mut declined) = (0u32, 0u32);
        for k in 0..20_000u64 {
            let size = 1 + (rnd() % 127) as i32;
            let (x0, y0) = (256 * (rnd() % 100) as i32, 256 * (rnd() % 100) as i32);
            let mut p = [0; 3].map(|_| Sub {
                x: x0 + (rnd() % (256 * size as u64)) as i32,
                y: y0 + (rnd() % (256 * size as u64)) as i32,
            });
            if k % 4 == 0 {
                // A sliver: the third vertex a few sub-pixels off the line through the first two (small areas
                // with long edges, where a step may not fit: `|g| >= 2A 2^38`).
                let f = (rnd() % 256) as i32;
                p[2].x = p[0].x + (p[1].x - p[0].x) * f / 256 + 1 + (rnd() % 8) as i32;
                p[2].y = p[0].y + (p[1].y - p[0].y) * f / 256;
            }
            let cross = |p: &[Sub; 3]| {
                (p[1].x - p[0].x) as i64 * (p[2].y - p[0].y) as i64
                    - (p[2].x - p[0].x) as i64 * (p[1].y - p[0].y) as i64
            };
            if cross(&p) < 0 {
                p.swap(1, 2);
            }
            let area = cross(&p);
            if area == 0 {
                continue;
            }
            let top = 1i64 << (48 + rnd() % 13);
            let spread = (top >> [2, 6, 10, 20, 40][(k % 5) as usize]).max(1);
            let v = [0; 3].map(|_| top - (rnd() % spread as u64) as i64);
            let (xmin, ymin) = (
                p.iter().map(|p| p.x).min().unwrap(),
                p.iter().map(|p| p.y).min().unwrap(),
            );
            let (xmax, ymax) = (
                p.iter().map(|p| p.x).max().unwrap(),
                p.iter().map(|p| p.y).max().unwrap(),
            );
            let (j_ref, j0) = (ymin >> 8, (ymin >> 8) + (rnd() % 3) as i32);
            let g = Geom {
                p,
                area,
                dq: p,
                darea: area,
                dbits: SUBPIXEL_BITS,
                dorigin: (0, 0),
                i_ref: (xmin >> 8) as i64,
                j_ref,
                j0,
            };
            // The rule, from the definitions.
            let t_min = v[0].min(v[1]).min(v[2]) as i128;
            let tp = v.map(|t| ((t as i128) + (1 << 15)) >> 16);
            let (e1, e2) = (
                ((p[1].x - p[0].x) as i128, (p[1].y - p[0].y) as i128),
                ((p[2].x - p[0].x) as i128, (p[2].y - p[0].y) as i128),
            );
            let (d1, d2) = (tp[1] - tp[0], tp[2] - tp[0]);
            let (gx, gy) = (d1 * e2.1 - d2 * e1.1, d2 * e1.0 - d1 * e2.0);
            let rule = t_min >= 1 << 51
                && gx.abs() + gy.abs() <= t_min >> 5
                && gx.abs() < (area as i128) << 38
                && gy.abs() < (area as i128) << 38;
            let got = Plane::solve_fast(v, &g);
            assert_eq!(got.is_some(), rule, "{k}");
            let Some(plane) = got else {
                declined += 1;
                continue;
            };
            answered += 1;
            // The exact plane through the vertices (unrounded `T`), at pixel centres of the box, against the walked
            // plane (row `j0` given, stepped by whole rows and columns from the box's left column).
            let (dx1, dx2) = (v[1] as i128 - v[0] as i128, v[2] as i128 - v[0] as i128);
            let (hx, hy) = (dx1 * e2.1 - dx2 * e1.1, dx2 * e1.0 - dx1 * e2.0);
            for j in (ymin >> 8)..=(ymax >> 8) {
                for i in (xmin >> 8)..=(xmax >> 8) {
                    let (cx, cy) = (256 * i as i64 + 128, 256 * j as i64 + 128);
                    let inside = (0..3).all(|m| {
                        let (a, b) = (p[m], p[(m + 1) % 3]);
                        (b.x - a.x) as i64 * (cy - a.y as i64)
                            - (b.y - a.y) as i64 * (cx - a.x as i64)
                            >= 0
                    });
                    if !inside {
                        continue;
                    }
                    let (px, py) = ((cx - p[0].x as i64) as i128, (cy - p[0].y as i64) as i128);
                    let exact = v[0] as i128 + (hx * px + hy * py) / area as i128;
                    // Walked modulo 2^64, as the span loops do (exact at a covered pixel, whose `T` fits).
                    let walked = plane
                        .at(i as i64 - g.i_ref)
                        .wrapping_add(plane.sy.wrapping_mul((j - j0) as i64))
                        as i128;
                    // The derivation's total (`2^15` from `T'`, `510 eps + 1` from the steps, `eps = |g| 2^-38 + 1`
                    // a step's; one more for `exact`'s floor), and what the rule makes of it.
                    let err = (walked - exact).abs();
                    let eps = (gx.abs().max(gy.abs()) >> 38) + 1;
                    assert!(err <= (1 << 15) + 510 * eps + 2, "{k} at ({i}, {j}): {err}");
                    assert!(err <= t_min >> 33, "{k} at ({i}, {j}): {err}");
                }
            }
        }
        std::println!("answered {answered}, declined {declined}");
        assert!(answered > 1000 && declined > 1000, "{answered} {declined}");
    }

    /// [`shr_u64`] is `floor(v / 2^s)` for every `s`, 0 from 64 on.
    #[test]
    fn shr_u64_is_the_shift_for_any_count() {
        let mut rnd = crate::xorshift(0x005E_ED0F_5A1F_u64);
        for s in 0..=200u32 {
            for _ in 0..200 {
                let v = rnd() >> (rnd() % 64);
                assert_eq!(shr_u64(v, s), v.checked_shr(s).unwrap_or(0), "{v} >> {s}");
            }
            assert_eq!(shr_u64(u64::MAX, s), u64::MAX.checked_shr(s).unwrap_or(0));
        }
    }

    /// [`Plane::solve_ref`] is the plane through the positions `dq` with each of its three terms rounded once (ties
    /// away from zero), formed here in `i128` from the definitions: the value at the reference pixel's centre,
    /// `v_0 + round((gx rx + gy ry) / 2A)`, and the steps `round(g 2^dbits / 2A)` (kept modulo 2^64, as the walk
    /// does). On grids of 8 to 30 fraction bits, both orientations, with the reference pixel's offset from vertex 0
    /// inside an `i32` (the limb products) and beyond it (the general product; the drawing paths' grids keep them
    /// from needing it, so only this test reaches it).
    #[test]
    fn solve_ref_is_the_plane_rounded_once() {
        let round = |n: i128, d: i128| (2 * n.abs() + d) / (2 * d) * n.signum();
        let mut rnd = crate::xorshift(0x50_1BE0_EF00_0D1E);
        let (mut narrow, mut wide) = (0u32, 0u32);
        for k in 0..20_000u64 {
            let dbits = 8 + (rnd() % 23) as u32;
            // Positions below 2^30 units; the triangle up to 127 px (fewer on the finest grids).
            let size = 1 + rnd() % 127u64.min(1 << (30 - dbits));
            let dq = [0; 3].map(|_| Sub {
                x: (rnd() % (size << dbits)) as i32,
                y: (rnd() % (size << dbits)) as i32,
            });
            let (e1, e2) = (
                ((dq[1].x - dq[0].x) as i128, (dq[1].y - dq[0].y) as i128),
                ((dq[2].x - dq[0].x) as i128, (dq[2].y - dq[0].y) as i128),
            );
            let darea = e1.0 * e2.1 - e2.0 * e1.1;
            if darea == 0 {
                continue;
            }
            // `T` below 2^61, spread so that the numerator stays below 2^126 at the widest offsets.
            let top = 1i64 << (30 + rnd() % 31);
            let v = [0; 3].map(|_| top - (rnd() % (top as u64 >> (rnd() % 30)).max(1)) as i64);
            // The reference pixel up to 2^(30 - dbits) px from the grid's origin (within 2^31 units) or, every
            // other triangle, up to 2^(33 - dbits) px (mostly beyond).
            let far = 1u64 << (if k % 2 == 0 { 30 } else { 33 } - dbits);
            let (i_off, j_off) = ((rnd() % far) as i64, (rnd() % far) as i32);
            let dorigin = ((rnd() % 100) as i32, (rnd() % 100) as i32);
            let g = Geom {
                p: dq,
                area: darea.abs() as i64,
                dq,
                darea: darea as i64,
                dbits,
                dorigin,
                i_ref: dorigin.0 as i64 + i_off,
                j_ref: dorigin.1 + j_off,
                j0: dorigin.1 + j_off,
            };
            let (d1, d2) = (v[1] as i128 - v[0] as i128, v[2] as i128 - v[0] as i128);
            let (mut gx, mut gy) = (d1 * e2.1 - d2 * e1.1, d2 * e1.0 - d1 * e2.0);
            let mut a = darea;
            if a < 0 {
                (gx, gy, a) = (-gx, -gy, -a);
            }
            let u = 1i128 << dbits;
            let (rx, ry) = (
                u * i_off as i128 + u / 2 - dq[0].x as i128,
                u * j_off as i128 + u / 2 - dq[0].y as i128,
            );
            if i32::try_from(rx).is_ok() && i32::try_from(ry).is_ok() {
                narrow += 1;
            } else {
                wide += 1;
            }
            let got = Plane::solve_ref(v, &g);
            let want = Plane {
                row: (v[0] as i128 + round(gx * rx + gy * ry, a)) as i64,
                sx: round(gx << dbits, a) as i64,
                sy: round(gy << dbits, a) as i64,
            };
            assert_eq!(got, want, "{k}: dbits {dbits}, offsets ({rx}, {ry})");
        }
        assert!(narrow > 5000 && wide > 5000, "{narrow} {wide}");
    }

    /// [`slope_bias`] is `m s + c` rounded to the nearest code and clamped (`m` the larger of the plane's
    /// `|d code / dx|` and `|d code / dy|` in codes a pixel, `s` the slope scale, `c` the constant bias), against
    /// `m` formed here in f64 from the definitions. Random triangles up to 16 px anywhere in the guard band, with
    /// integer codes below 2^11: every f32 product and difference before the division is then exact (below 2^24),
    /// so the f32 path rounds three times, the quotient and the product (`2^-24` of `|m s|` each) and the sum
    /// (`2^-24` of the result; half an ulp each, and the `+ 1` of `err` below covers the second-order terms, under
    /// `2^-48 |m s|`), and each triangle is checked wherever the f64 value is farther than that from a tie.
    #[cfg(feature = "bias")]
    #[test]
    fn slope_bias_is_the_largest_slope_times_scale_plus_constant() {
        let mut rnd = crate::xorshift(0x510B_EB1A_5000_0001);
        let mut st = RenderState::new(1.0, 100.0).unwrap();
        let (mut checked, mut clamped) = (0u32, 0u32);
        for k in 0..100_000u64 {
            let o = [0; 2].map(|_| (rnd() % (1 << 21)) as i32 - (1 << 20));
            let p = [0; 3].map(|_| Sub {
                x: o[0] + (rnd() % 4096) as i32,
                y: o[1] + (rnd() % 4096) as i32,
            });
            let c = [0; 3].map(|_| (rnd() % 2048) as f32);
            st.slope_scale_depth_bias = (rnd() % 2001) as f32 / 250.0 - 4.0;
            st.depth_bias = (rnd() % 20001) as f32 / 100.0 - 100.0;
            let d = |a: i32, b: i32| (b - a) as f64;
            let (dx1, dy1, dx2, dy2) = (
                d(p[0].x, p[1].x),
                d(p[0].y, p[1].y),
                d(p[0].x, p[2].x),
                d(p[0].y, p[2].y),
            );
            let area = dx1 * dy2 - dx2 * dy1;
            if area == 0.0 {
                continue;
            }
            let (c1, c2) = ((c[1] - c[0]) as f64, (c[2] - c[0]) as f64);
            let gx = (c1 * dy2 - c2 * dy1) / area * 256.0;
            let gy = (c2 * dx1 - c1 * dx2) / area * 256.0;
            let ms = gx.abs().max(gy.abs()) * st.slope_scale_depth_bias as f64;
            let off = ms + st.depth_bias as f64;
            let max = 65535.0;
            let got = slope_bias(&st, &p, c, max as f32);
            if off.abs() > max + 1.0 {
                assert_eq!(got as f64, max * off.signum(), "{k}");
                clamped += 1;
                continue;
            }
            let err = (2.0 * ms.abs() + off.abs() + 1.0) * f32::EPSILON as f64 / 2.0;
            let frac = off - off.floor();
            if (frac - 0.5).abs() <= err {
                continue;
            }
            let r = if frac > 0.5 {
                off.floor() + 1.0
            } else {
                off.floor()
            };
            assert_eq!(got as f64, r.clamp(-max, max), "{k}: offset {off}");
            checked += 1;
        }
        assert!(checked > 50_000 && clamped > 100, "{checked} {clamped}");
    }

    /// [`slope_bias`] of a triangle whose vertex codes are equal (slope 0, so the offset is the constant bias alone)
    /// is that constant rounded to the nearest code, ties away from zero, then clamped to `[-max, max]`: at the f32
    /// values where adding 0.5 rounds the sum (`0.5 - 2^-25`; odd integers from `2^23`), at ties, and at random
    /// constants against the f64 rounding (exact: an f32 and its floor are exact in f64).
    #[cfg(feature = "bias")]
    #[test]
    fn slope_bias_rounds_to_nearest_ties_away() {
        let p = [(0, 0), (2560, 0), (0, 2560)].map(|(x, y)| Sub { x, y });
        let mut st = RenderState::new(1.0, 100.0).unwrap();
        st.slope_scale_depth_bias = 3.0;
        let mut bias = |c: f32, max: f32| {
            st.depth_bias = c;
            slope_bias(&st, &p, [1000.0; 3], max)
        };
        let below_half = 0.5 - f32::EPSILON / 4.0; // 0.5 - 2^-25, the largest f32 below 0.5
        let max24 = 16_777_215.0; // a 24-bit format's largest code
        for (c, max, want) in [
            (below_half, 65535.0, 0),
            (-below_half, 65535.0, 0),
            (0.5, 65535.0, 1),
            (-0.5, 65535.0, -1),
            (1.5, 65535.0, 2),
            (2.5, 65535.0, 3),
            (-2.5, 65535.0, -3),
            (8_388_609.0, max24, 8_388_609),
            (-8_388_609.0, max24, -8_388_609),
            (8_388_607.5, max24, 8_388_608),
            (70_000.0, 65535.0, 65535),
            (-70_000.4, 65535.0, -65535),
        ] {
            assert_eq!(bias(c, max), want, "constant {c}");
        }
        let mut rnd = crate::xorshift(0xB1A5_0FF5_E7ED_6E5D);
        for k in 0..100_000 {
            // Magnitudes from 2^-8 to 2^25, either sign.
            let mag = (1u64 << (k % 33)) as f64 / 256.0;
            let c = ((rnd() % 1_000_000) as f64 / 1e6 * mag) as f32
                * if rnd() & 1 == 0 { 1.0 } else { -1.0 };
            let a = (c as f64).abs();
            let r = (a.floor() + if a - a.floor() >= 0.5 { 1.0 } else { 0.0 }).min(max24 as f64);
            let want = (if c < 0.0 { -r } else { r }) as i32;
            assert_eq!(bias(c, max24), want, "constant {c}");
        }
    }
}
