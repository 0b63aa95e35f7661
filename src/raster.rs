//! Triangle setup and the span loop.
//!
//! Depth. Each vertex gives `t = W_far * rhw = W_far / W` (Rogers, "W-Buffering in Direct3D" (NVIDIA): `W_TNT = RHW * dvRW_far`,
//! with the 16-bit fixed scale 1.0), so `W / W_far = 1/t`, the far plane is `t = 1` and the near plane `t = W_far/W_near`.
//! `t` is linear in screen space (Microsoft, "W-Buffering" (Direct3D DDK): interpolate 1/w linearly, take the reciprocal per
//! pixel). It is held as `T = t * 2^F` in an `i64`, with `F = 61 - bits(floor(t_max))` fraction bits chosen per
//! triangle from its largest vertex `t` (so `T < 2^61`; `F >= 30` since `t <= 2^30`; `F >= 47` when `t_max < 2^14`).
//! The plane is solved exactly in `i128` at setup: the per-pixel steps and the value at a reference pixel are each
//! rounded to nearest, so at a pixel `k` columns and `l` rows from the reference `T` errs by at most
//! `(1 + k + l) / 2` units of `2^-F`. Steps are added with wrapping arithmetic: for a sliver the plane's slope may
//! exceed `i64`, but every covered pixel's true `T` lies in `(-2^61, 2^62)` (see `depth_plane`), so the wrapped sum
//! is right modulo `2^64`, and the range test rejects whatever lies outside `[2^F, T_near]`.
//!
//! Which vertices. Coverage uses the vertices snapped to 1/256 px (the fill rule needs exact edge functions). The
//! depth plane (and the colour planes) go through the vertices **as given**: rounded only to a depth grid of
//! [`depth_grid_bits`] fraction bits (`2^-17` px for a box as large as the guard band, `2^-24` for one under 126 px,
//! `2^-29` within a pixel), exact for every f32 coordinate of magnitude `2^(23 - bits)` px or more. Through the snapped
//! vertices instead, the depth of a grazing plane moved by many codes (up to 127 on world-space triangles); through
//! the grid, a covered pixel's `t` differs from the true surface's by at most
//! `sum_k |lambda_k| |grad t . (q_k - v_k)|` (`q_k` the grid positions, `v_k` the given ones, `lambda_k` the pixel's
//! barycentrics): zero for vertices on the snap grid (then the snapped plane is this plane, and nothing extra runs),
//! below `1.3e-4` codes on the grazing tests. The fast tier gets the same plane without a second solve: its `T` at the
//! snapped vertices ([`t_at_snapped`]), through which its own set-ups solve.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::depth::{encode_w16, DepthBuffer, W16_FAR};
use crate::edge::{Edge, Sub};
use crate::fast::{Chord, Divide};
use crate::fixed::{div_u128, round_shift, split, Divisor};
use crate::input::VertexInput;
#[cfg(feature = "gouraud")]
use crate::recip::Inv;
use crate::recip::{normalise, Fast, SpanRecip, SpanWalker, WSpan};
use crate::state::{Compare, DepthMode};
use crate::state::{Cull, RenderState, MAX_T_LOG2};
use crate::Error;
#[cfg(feature = "gouraud")]
use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};

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
fn grid_bits(extent: i32) -> u32 {
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

/// Where [`Rasterizer::draw_memo`] finds and leaves a triangle's [`t_at_snapped`] values.
pub trait TMemo {
    /// The values remembered for this triangle, if any.
    fn get(&mut self) -> Option<Option<[i64; 3]>>;
    /// This triangle's values, and its last row (the memo keeps them only for a triangle that reaches a later band).
    fn put(&mut self, t: Option<[i64; 3]>, last_row: i32);
}

impl<M: TMemo> TMemo for Option<M> {
    #[inline(always)]
    fn get(&mut self) -> Option<Option<[i64; 3]>> {
        self.as_mut().and_then(|m| m.get())
    }
    #[inline(always)]
    fn put(&mut self, t: Option<[i64; 3]>, last_row: i32) {
        if let Some(m) = self {
            m.put(t, last_row);
        }
    }
}

/// No memo: every draw computes its values.
pub struct NoMemo;

impl TMemo for NoMemo {
    #[inline(always)]
    fn get(&mut self) -> Option<Option<[i64; 3]>> {
        None
    }
    #[inline(always)]
    fn put(&mut self, _: Option<[i64; 3]>, _: i32) {}
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

/// The frame rows `(first, last)` a triangle can cover (inclusive; empty when `first > last`), after snapping:
/// for binning triangles into bands without setting them up. Errors as [`Rasterizer::draw`] for x and y.
pub fn row_range<V: VertexInput>(v: &[V; 3]) -> Result<(i32, i32), Error> {
    let mut p = [Sub { x: 0, y: 0 }; 3];
    for (q, v) in p.iter_mut().zip(v) {
        let (x, y) = v.snapped()?;
        *q = Sub { x, y };
    }
    Ok(rows_of(&p))
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

/// Draws triangles into a colour target and a depth buffer, with `W` strategy `R` (a per-pixel reciprocal
/// [`SpanRecip`], or [`crate::recip::Quake`] for the packed formats).
pub struct Rasterizer<R: WSpan = Fast> {
    /// The render state used by the next draws.
    pub state: RenderState,
    pub(crate) recip: R,
    /// The Z constant of the packed path's Z formats, with the range it was computed for (once per range, not per
    /// primitive; see `crate::packed`).
    pub(crate) zc: Option<(crate::DepthRange, crate::state::ZConst)>,
}

impl<R: WSpan> Rasterizer<R> {
    /// A rasterizer with `state`.
    pub fn new(state: RenderState) -> Self {
        Rasterizer {
            state,
            recip: R::default(),
            zc: None,
        }
    }

    /// Snaps and checks `N` vertices and gives their `T` with a common fraction count.
    pub(crate) fn setup<V: VertexInput, const N: usize>(
        &self,
        v: &[V; N],
    ) -> Result<Setup<N>, Error> {
        let (_, fm, fe) = split(self.state.range.far()).ok_or(Error::NonFinite)?;
        let mut p = [Sub { x: 0, y: 0 }; N];
        let mut on_grid = true;
        let mut tm = [(0u64, 0i32); N];
        // The largest integer bit count of the `t` (0 for values below 1), for F below.
        let mut int_bits = 0;
        for k in 0..N {
            let (m, e) = v[k].rhw_exact()?;
            let (x, y, exact) = v[k].snapped_exact()?;
            p[k] = Sub { x, y };
            on_grid &= exact;
            // `t = rhw W_far` as an exact product of the mantissas (`m > 0`, `fm > 0`), `pm 2^pe`, and its bit count.
            let (pm, pe) = (crate::fast::mul_wide(m, fm), e + fe);
            let b = crate::fast::bits64(pm) as i32 + pe;
            if b > MAX_T_LOG2 {
                return Err(Error::DepthRange);
            }
            int_bits = int_bits.max(b);
            tm[k] = (pm, pe);
        }
        let mut q = [Sub { x: 0, y: 0 }; N];
        let (mut dbits, mut dorigin) = (SUBPIXEL_BITS, (0, 0));
        if N == 3 && !on_grid {
            let (ox, oy) = (
                p.iter().map(|s| s.x).min().unwrap_or(0) >> SUBPIXEL_BITS,
                p.iter().map(|s| s.y).min().unwrap_or(0) >> SUBPIXEL_BITS,
            );
            let xe = (p.iter().map(|s| s.x).max().unwrap_or(0) >> SUBPIXEL_BITS) - ox;
            let ye = (p.iter().map(|s| s.y).max().unwrap_or(0) >> SUBPIXEL_BITS) - oy;
            dbits = grid_bits(xe.max(ye));
            dorigin = (ox, oy);
            for k in 0..N {
                let (x, y) = v[k].depth_xy(dbits, ox, oy);
                q[k] = Sub { x, y };
            }
        }
        // F = 61 - bits(floor(t_max)), t_max < 2^30.
        let frac = (61 - int_bits) as u32;
        let t = tm.map(|(m, e)| round_shift(m, e + frac as i32) as i64);
        Ok(Setup {
            p,
            on_grid,
            q,
            dbits,
            dorigin,
            fast_t: None,
            t,
            frac,
        })
    }

    /// Snaps, checks, culls and clips a triangle to the buffer's rows, and solves its `t` plane.
    /// `Ok(Err(stats))` when there is nothing to walk (culled, or no row in the buffer).
    /// `rows` is the buffer's first frame row and its height.
    /// `fast`: the fast tier's set-up for small triangles (32-bit edges, the plane from a reciprocal of the area,
    /// [`Plane::solve_fast`]) where it applies; the exact set-up otherwise.
    pub(crate) fn prepare<V: VertexInput>(
        &self,
        v: &[V; 3],
        rows: (i32, u16),
        fast: bool,
    ) -> Result<Result<Walk, Stats>, Error> {
        self.prepare_setup(&self.setup(v)?, rows, fast)
    }

    /// [`Rasterizer::prepare`] from a snapped and checked triangle.
    pub(crate) fn prepare_setup(
        &self,
        s: &Setup,
        rows: (i32, u16),
        fast: bool,
    ) -> Result<Result<Walk, Stats>, Error> {
        let [p0, p1, p2] = s.p;
        let area = (p1.x - p0.x) as i64 * (p2.y - p0.y) as i64
            - (p2.x - p0.x) as i64 * (p1.y - p0.y) as i64;
        let culled = Stats {
            culled: 1,
            ..Stats::default()
        };
        match self.state.cull {
            _ if area == 0 => return Ok(Err(culled)),
            Cull::Cw if area > 0 => return Ok(Err(culled)),
            Cull::Ccw if area < 0 => return Ok(Err(culled)),
            _ => {}
        }
        // Orient so the doubled area is positive (inside = positive edge functions).
        let order = if area < 0 { [0, 2, 1] } else { [0, 1, 2] };
        let p = order.map(|k| s.p[k]);

        let (j_first, j_last) = crate::edge::flat_rows(&p, rows_of(&p));
        let j0 = j_first.max(rows.0);
        let j1 = j_last.min(rows.0.saturating_add(rows.1 as i32 - 1)); // a band's last row (saturating: any y0)
        if j0 > j1 {
            return Ok(Err(Stats::default()));
        }
        let xmin = p[0].x.min(p[1].x).min(p[2].x);
        let ymin = p[0].y.min(p[1].y).min(p[2].y);
        let mut t_or = order.map(|k| s.t[k]);
        let mut frac = s.frac;
        let area = area.unsigned_abs() as i64; // below 2^43
        let snapped_plane = (p, area, SUBPIXEL_BITS, (0, 0));
        // Small: every vertex within 127 px (minus a pixel for the origin's offset) of the box's origin pixel.
        let small = fast && {
            let xmax = p[0].x.max(p[1].x).max(p[2].x);
            let ymax = p[0].y.max(p[1].y).max(p[2].y);
            xmax - xmin < 126 << SUBPIXEL_BITS && ymax - ymin < 126 << SUBPIXEL_BITS
        };
        // The fast set-up solves through the snapped vertices, with the depth-grid plane's `T` there off the grid.
        let at_snapped = match small {
            true if !s.on_grid => s.fast_t.map(|t| order.map(|k| t[k])),
            _ => None,
        };
        if let Some(tv) = at_snapped {
            t_or = tv;
        }
        let (dq, darea, dbits, dorigin) = if s.on_grid || at_snapped.is_some() {
            snapped_plane
        } else {
            let q = order.map(|k| s.q[k]);
            // A sliver whose extrapolation needs more headroom is solved with fewer fraction bits (see
            // `depth_plane`); the snapped plane only for a degenerate depth-grid triangle or an absurd sliver.
            let mut plane = None;
            for _ in 0..4 {
                match depth_plane(&p, &q, &t_or, s.dbits, s.dorigin) {
                    Ok(a) => {
                        plane = Some((q, a, s.dbits, s.dorigin));
                        break;
                    }
                    Err(Some(e)) if frac > e + MIN_FRAC => {
                        t_or = t_or.map(|t| round_shift(t as u64, -(e as i32)) as i64);
                        frac -= e;
                    }
                    Err(_) => break,
                }
            }
            match plane {
                Some(pl) => pl,
                None => {
                    (t_or, frac) = (order.map(|k| s.t[k]), s.frac);
                    snapped_plane
                }
            }
        };
        let geom = Geom {
            p,
            area,
            dq,
            darea,
            dbits,
            dorigin,
            i_ref: (xmin >> SUBPIXEL_BITS) as i64,
            j_ref: j_first,
            j0,
        };
        let fast_plane = if small && (s.on_grid || at_snapped.is_some()) {
            Plane::solve_fast(t_or, &geom)
        } else {
            None
        };
        let t = match fast_plane {
            Some(t) => t,
            None => Plane::solve(t_or, &geom),
        };
        let edges = if small {
            let (ox, oy) = (xmin >> SUBPIXEL_BITS, ymin >> SUBPIXEL_BITS);
            [
                Edge::new_small(p[0], p[1], j0, ox, oy),
                Edge::new_small(p[1], p[2], j0, ox, oy),
                Edge::new_small(p[2], p[0], j0, ox, oy),
            ]
        } else {
            [
                Edge::new(p[0], p[1], j0),
                Edge::new(p[1], p[2], j0),
                Edge::new(p[2], p[0], j0),
            ]
        };
        let exact = edges.iter().map(Edge::rows_exact).min().unwrap_or(1 << 24);
        Ok(Ok(Walk {
            frac,
            t_vertex: t_or,
            edges,
            j: j0,
            exact,
            left: exact,
            geom,
            order,
            j1,
            t,
            span: SpanCtx {
                t_lo: 1u64 << frac,
                t_hi: self.state.range.t_max(frac),
                shift_base: 94 - frac,
                #[cfg(feature = "bias")]
                bias: bias_of(&self.state, &s.p, &s.t, s.frac),
            },
        }))
    }
}

impl<R: SpanRecip> Rasterizer<R> {
    /// The comparison and depth write of a W16 draw: `Off` passes everything and writes nothing, `Z` is refused
    /// (W16 stores W; see [`DepthMode`]).
    fn w16_test(&self) -> Result<(Compare, bool), Error> {
        match self.state.mode {
            DepthMode::Off => Ok((Compare::Always, false)),
            DepthMode::Z => Err(Error::ZWithWFormat),
            DepthMode::W => Ok((self.state.compare, self.state.depth_write)),
        }
    }

    /// What a remembered [`t_at_snapped`] value depends on besides the triangle: the strategy's way to it and the far
    /// plane (the vertices' `T`).
    pub(crate) fn memo_tag(&self) -> u64 {
        ((R::DIV_SEED as u64) << 32) | self.state.range.far().to_bits() as u64
    }

    /// [`Rasterizer::draw`], with `memo` keeping the fast tier's depth-grid values ([`t_at_snapped`]) across the
    /// bands of a frame (the mesh's [`crate::mesh::PlaneCache`]); the values are a function of the triangle alone, so
    /// a remembered one draws exactly what a computed one does.
    pub(crate) fn draw_memo<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        v: &[impl VertexInput<Color = D::Color>; 3],
        memo: &mut impl TMemo,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let (cmp, write) = self.w16_test()?;
        depth.note_compare(cmp, write);
        let mut s = self.setup(v)?;
        // Only for a triangle with rows in the buffer (a band's draws include triangles that only come near it):
        // one that has none draws nothing either way, and both paths find that before they look at `fast_t`.
        let (first, last) = rows_of(&s.p);
        if R::FAST_W16
            && !s.on_grid
            && first <= depth.y0().saturating_add(depth.height() as i32 - 1)
            && last >= depth.y0()
        {
            s.fast_t = match memo.get() {
                Some(t) => t,
                None if R::DIV_SEED => t_at_snapped::<true>(&s),
                None => t_at_snapped::<false>(&s),
            };
            memo.put(s.fast_t, last);
            #[cfg(test)]
            FAST_T_USED.with(|c| c.borrow_mut().push((s.p.map(|p| (p.x, p.y)), s.fast_t)));
        }
        if R::FAST_W16 && cmp == Compare::Less && write && !self.state.has_bias() {
            // The strategy's seed (a constant of `R`: the other branch is not compiled into the firmware).
            let small = if R::DIV_SEED {
                crate::small::draw::<Divide, D>(target, depth, &s, &self.state, v[0].color())?
            } else {
                crate::small::draw::<Chord, D>(target, depth, &s, &self.state, v[0].color())?
            };
            if let Some(stats) = small {
                return Ok(stats);
            }
        }
        let mut w = match self.prepare_setup(&s, (depth.y0(), depth.height()), R::FAST_W16)? {
            Ok(w) => w,
            Err(stats) => return Ok(stats),
        };
        let color = v[0].color();
        let mut stats = Stats::default();
        for j in w.geom.j0..=w.j1 {
            if let Some((lo, hi)) = w.row(depth.width()) {
                let t = w.t.at(lo as i64 - w.geom.i_ref) as u64;
                #[cfg(feature = "coarse")]
                let (row, seg) = depth.row_and_bound(j);
                #[cfg(not(feature = "coarse"))]
                let (row, seg) = (depth.row_mut(j), &mut [][..]);
                let row = &mut row[lo as usize..hi as usize];
                let mut runs = Runs::new(target, lo, j, color);
                span(
                    &mut self.recip,
                    row,
                    t,
                    w.t.sx,
                    &w.span,
                    cmp,
                    write,
                    &mut runs,
                    seg,
                )?;
                stats.fragments += (hi - lo) as u32;
                stats.written += (hi - lo) as u32 - runs.fails;
            }
            w.next_row();
        }
        Ok(stats)
    }

    /// Draws one triangle with its vertex colours interpolated perspective-correctly (feature `gouraud`): each
    /// channel `c` is carried as the plane of `c * t` (linear in screen space) and divided per pixel by `t` with the
    /// same reciprocal as the depth, then rounded to 8 bits. On an error nothing is written, except for a failing `target` ([`Error::Target`]).
    #[cfg(feature = "gouraud")]
    pub fn draw_gouraud<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor + From<Rgb888> + Into<Rgb888>,
    {
        let (cmp, write) = self.w16_test()?;
        depth.note_compare(cmp, write);
        let mut w = match self.prepare(v, (depth.y0(), depth.height()), false)? {
            Ok(w) => w,
            Err(stats) => return Ok(stats),
        };
        // Q = c * (T >> 8) < T for c <= 255, so Q << lz fits wherever T << lz does.
        let rgb = v.map(|q| {
            let c: Rgb888 = q.color().into();
            [c.r(), c.g(), c.b()]
        });
        // From the walk's `T` (oriented; with the walk's fraction bits, which a sliver may reduce).
        let mut planes = [0, 1, 2].map(|ch| {
            Plane::solve(
                [0, 1, 2].map(|j| rgb[w.order[j]][ch] as i64 * (w.t_vertex[j] >> 8)),
                &w.geom,
            )
        });
        let mut buf = [D::Color::from(Rgb888::BLACK); 32];
        let mut stats = Stats::default();
        for j in w.geom.j0..=w.j1 {
            if let Some((lo, hi)) = w.row(depth.width()) {
                let row = depth.row_mut(j);
                let off = lo as i64 - w.geom.i_ref;
                let mut t = w.t.at(off) as u64;
                let mut q = planes.map(|p| p.at(off));
                self.recip.begin_span(false);
                let (mut run_start, mut n) = (lo, 0usize);
                for i in lo..hi {
                    let mut pass = false;
                    if t >= w.span.t_lo && t <= w.span.t_hi {
                        let (m, lz) = normalise(t);
                        let inv = Inv {
                            x: self.recip.recip(m),
                            lz,
                        };
                        let code =
                            biased(encode_w16(inv.x, w.span.shift_base - inv.lz), w.span.bias());
                        let stored = &mut row[i as usize];
                        if cmp.test(code, *stored) {
                            if write {
                                *stored = code;
                            }
                            pass = true;
                            // c = 256 Q / T = q x 2^-54 with q = (Q << lz) >> 32 (ARCHITECTURE.md)
                            let ch = q.map(|qq| {
                                // Clamped to [0, T]: a pixel just outside the depth-grid triangle takes
                                // extrapolated planes (see `depth_plane`), and `Q <= T` keeps `Q << lz` in range.
                                let qn = ((qq.clamp(0, t as i64) as u64) << inv.lz) >> 32;
                                ((qn * inv.x as u64 + (1 << 53)) >> 54).min(255) as u8
                            });
                            buf[n] = D::Color::from(Rgb888::new(ch[0], ch[1], ch[2]));
                            n += 1;
                        }
                    }
                    if (!pass || n == buf.len()) && n > 0 {
                        let end = if pass { i + 1 } else { i };
                        let r = Rectangle::new(Point::new(run_start, j), Size::new(n as u32, 1));
                        target
                            .fill_contiguous(&r, buf[..n].iter().copied())
                            .map_err(|_| Error::Target)?;
                        run_start = end;
                        n = 0;
                    }
                    if !pass {
                        run_start = i + 1;
                    } else {
                        stats.written += 1;
                    }
                    t = t.wrapping_add(w.t.sx as u64);
                    for (qq, p) in q.iter_mut().zip(&planes) {
                        *qq = qq.wrapping_add(p.sx);
                    }
                }
                if n > 0 {
                    let r = Rectangle::new(Point::new(run_start, j), Size::new(n as u32, 1));
                    target
                        .fill_contiguous(&r, buf[..n].iter().copied())
                        .map_err(|_| Error::Target)?;
                }
                stats.fragments += (hi - lo) as u32;
            }
            w.next_row();
            for p in &mut planes {
                p.next_row();
            }
        }
        Ok(stats)
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
fn snap_rounding(p: Sub, q: Sub, bits: u32, (ox, oy): (i32, i32)) -> (i32, i32) {
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
fn depth_plane(
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

#[cfg(test)]
std::thread_local! {
    /// The snapped vertices of each call of [`t_at_snapped`] on this thread (tests of the mesh's plane cache count
    /// what it saves).
    pub(crate) static T_AT_SNAPPED_CALLS: core::cell::RefCell<std::vec::Vec<[(i32, i32); 3]>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
    /// The snapped vertices and the depth-grid values of each draw that used them (computed or remembered).
    #[allow(clippy::type_complexity)]
    pub(crate) static FAST_T_USED: core::cell::RefCell<std::vec::Vec<([(i32, i32); 3], Option<[i64; 3]>)>> =
        const { core::cell::RefCell::new(std::vec::Vec::new()) };
}

/// What [`t_at_snapped_narrow`] found.
enum Narrow {
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
fn t_at_snapped_narrow(s: &Setup) -> Narrow {
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
    let (am, al) = crate::transform::top32(a); // a = am 2^(32 - al), truncated
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
        let (nm, nl) = crate::transform::top32(n.unsigned_abs());
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
fn t_at_snapped_wide(s: &Setup) -> Option<[i64; 3]> {
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
const MIN_FRAC: u32 = 8;

/// `a b` exactly (two 32 x 32 -> 64 products).
#[inline]
fn mul_64_32(a: i64, b: i32) -> i128 {
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
fn mul_96_32(a: i128, b: i32) -> i128 {
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
#[derive(Clone, Copy)]
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
        .at_row(g)
    }
    /// From the reference row to the first row walked, by whole row steps (what walking there would give).
    #[inline]
    fn at_row(mut self, g: &Geom) -> Plane {
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
    #[inline(always)]
    pub(crate) fn next_row(&mut self) {
        self.row = self.row.wrapping_add(self.sy);
    }
}

/// A prepared triangle being walked row by row.
pub(crate) struct Walk {
    /// Fraction bits of `T`.
    pub(crate) frac: u32,
    /// The vertices' `T`, in oriented order.
    pub(crate) t_vertex: [i64; 3],
    edges: [Edge; 3],
    /// The current row, the rows between edge set-ups ([`Edge::rows_exact`]) and the rows left until the next.
    j: i32,
    exact: i32,
    left: i32,
    pub(crate) geom: Geom,
    /// Vertex order after orientation.
    #[cfg_attr(not(feature = "gouraud"), allow(dead_code))]
    order: [usize; 3],
    pub(crate) j1: i32,
    pub(crate) t: Plane,
    pub(crate) span: SpanCtx,
}

impl Walk {
    /// The covered columns `[lo, hi)` of the current row inside `[0, width)`, if any.
    #[inline(always)]
    pub(crate) fn row(&self, width: u16) -> Option<(i32, i32)> {
        let (mut lo, mut hi) = (0i32, width as i32);
        for e in &self.edges {
            let (l, h) = e.bound();
            lo = lo.max(l);
            hi = hi.min(h);
        }
        (lo < hi).then_some((lo, hi))
    }
    #[inline(always)]
    pub(crate) fn next_row(&mut self) {
        for e in &mut self.edges {
            e.step();
        }
        self.t.next_row();
        self.j += 1;
        self.left -= 1;
        if self.left == 0 {
            self.reset_edges();
        }
    }
    /// The edges set up again at the current row (exactly, from the snapped vertices), every `exact` rows: only
    /// triangles with a nearly horizontal edge and hundreds of rows get here (see `crate::edge`).
    #[inline(never)]
    fn reset_edges(&mut self) {
        let p = self.geom.p;
        self.edges = [
            Edge::new(p[0], p[1], self.j),
            Edge::new(p[1], p[2], self.j),
            Edge::new(p[2], p[0], self.j),
        ];
        self.left = self.exact;
    }
}

/// Per-triangle constants of the span loop: the `T` range drawn (far plane `2^F`, near plane) and `94 - F`.
pub(crate) struct SpanCtx {
    pub(crate) t_lo: u64,
    pub(crate) t_hi: u64,
    shift_base: u32,
    /// The triangle's depth bias in codes (feature `bias`).
    #[cfg(feature = "bias")]
    bias: i32,
}

impl SpanCtx {
    #[inline(always)]
    fn bias(&self) -> i32 {
        #[cfg(feature = "bias")]
        return self.bias;
        #[cfg(not(feature = "bias"))]
        0
    }
}

/// `code + bias`, saturated to the W16 range (a no-op for a zero bias).
#[inline(always)]
fn biased(code: u16, bias: i32) -> u16 {
    if bias == 0 {
        code
    } else {
        (code as i32 + bias).clamp(0, W16_FAR as i32) as u16
    }
}

/// Seed the Windows CE "Depth Buffering" docs' depth bias, `Offset = m * SLOPESCALEDEPTHBIAS + DEPTHBIAS`, in W16 codes.
/// W is not planar in screen space, so `m` is defined for a triangle as the larger of `|d code / dx|` and
/// `|d code / dy|` (codes per pixel) of the plane through its three vertices' exact codes `65535 W_i / W_far`: the
/// slope the triangle's depth has at its vertices' scale, which is what two coplanar triangles' rounding disagrees by.
/// Rounded to the nearest code; 0 when both terms are 0 (the common case costs no float work).
#[cfg(feature = "bias")]
fn bias_of(state: &RenderState, p: &[Sub; 3], t: &[i64; 3], frac: u32) -> i32 {
    if state.slope_scale_depth_bias == 0.0 && state.depth_bias == 0.0 {
        return 0;
    }
    let full = (1u64 << frac) as f32 * W16_FAR as f32;
    slope_bias(state, p, t.map(|v| full / v as f32), W16_FAR as f32)
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
    let r = if off >= 0.0 { off + 0.5 } else { off - 0.5 };
    r.clamp(-max, max) as i32
}

fn fill<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    x1: i32,
    y: i32,
    color: D::Color,
) -> Result<(), Error> {
    let r = Rectangle::new(Point::new(x0, y), Size::new((x1 - x0) as u32, 1));
    target.fill_solid(&r, color).map_err(|_| Error::Target)
}

/// The passing runs of a span, each sent to the target as one `fill_solid`; counts the failing pixels.
pub(crate) struct Runs<'a, D: DrawTarget> {
    pub(crate) target: &'a mut D,
    pub(crate) lo: i32,
    pub(crate) j: i32,
    pub(crate) color: D::Color,
    /// First pixel (span-relative) of the current run.
    pub(crate) start: usize,
    pub(crate) fails: u32,
}

impl<'a, D: DrawTarget> Runs<'a, D> {
    /// No run yet on row `j`, whose span starts at frame column `lo`.
    #[inline(always)]
    pub(crate) fn new(target: &'a mut D, lo: i32, j: i32, color: D::Color) -> Self {
        Runs {
            target,
            lo,
            j,
            color,
            start: 0,
            fails: 0,
        }
    }
    /// Pixels `start..end` pass: fill them.
    #[inline(always)]
    fn draw(&mut self, start: usize, end: usize) -> Result<(), Error> {
        fill(
            self.target,
            self.lo + start as i32,
            self.lo + end as i32,
            self.j,
            self.color,
        )
    }
    /// Pixel `k` failed: flush the run before it.
    #[inline(always)]
    pub(crate) fn fail(&mut self, k: usize) -> Result<(), Error> {
        self.fail_many(k, k + 1)
    }
    /// Pixels `a..b` fail (none when `a == b`): flush the run before `a`.
    #[inline(always)]
    pub(crate) fn fail_many(&mut self, a: usize, b: usize) -> Result<(), Error> {
        if a < b {
            self.fails += (b - a) as u32;
            let start = core::mem::replace(&mut self.start, b);
            if start < a {
                self.draw(start, a)?;
            }
        }
        Ok(())
    }
    #[inline(always)]
    pub(crate) fn finish(&mut self, n: usize) -> Result<(), Error> {
        if self.start < n {
            self.draw(self.start, n)?;
        }
        Ok(())
    }
}

/// W16 codes from `x` with a shift fixed while `lz` is: `round(65535 x / 2^sh)` as
/// `(hi32(x * (65535 << k)) + 2^(s-1)) >> s`, `s = sh + k - 32`, `k = min(16, 63 - sh)`. Exactly the value of
/// [`encode_w16`] (floor of a floor by a power of two), with one multiply, an add and a shift.
struct W16Enc {
    mul: u32,
    round: u32,
    s: u32,
}

impl W16Enc {
    /// Largest reciprocal error for which no clamp is needed: `x` may exceed `1/t` by this, and at `t = 1` the code
    /// `65535 (1 + e) + 1/2` still rounds down to 65535 while `65535 e < 1/2`.
    const CLAMP_FREE: f64 = 0.5 / 65536.0;
    /// `sh` is in `[30, 61]` on a span in range; anything else (after the step past a span's end) is kept harmless.
    #[inline(always)]
    fn new(sh: u32) -> Self {
        let k = 16u32.min(63u32.saturating_sub(sh));
        let s = (sh + k).saturating_sub(32).clamp(1, 31);
        W16Enc {
            mul: 65535 << k,
            round: 1 << (s - 1),
            s,
        }
    }
    #[inline(always)]
    fn code<R: SpanRecip>(&self, x: u32) -> u16 {
        let hi = ((x as u64 * self.mul as u64) >> 32) as u32;
        let c = (hi + self.round) >> self.s;
        if R::MAX_REL_ERROR >= Self::CLAMP_FREE {
            c.min(65535) as u16
        } else {
            debug_assert!(c <= 65535);
            c as u16
        }
    }
}

/// One span: `row` is the depth buffer under it, `t` its first `T`, `dt` the step. Tame spans whose ends are both
/// in range (so every pixel is) take the lean loop; the others check the range and normalise at every pixel.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn span<R: SpanRecip, D: DrawTarget>(
    recip: &mut R,
    row: &mut [u16],
    t: u64,
    dt: i64,
    ctx: &SpanCtx,
    cmp: Compare,
    write: bool,
    runs: &mut Runs<'_, D>,
    seg: &mut [u16],
) -> Result<(), Error> {
    let n = row.len();
    let last = t.wrapping_add((dt as u64).wrapping_mul(n as u64 - 1));
    let in_range = |v: u64| v >= ctx.t_lo && v <= ctx.t_hi;
    let (tame, smooth) = SpanWalker::classify(t, dt, n as u32);
    if R::FAST_W16
        && n >= crate::fast::MIN_SPAN
        && tame
        && in_range(t)
        && in_range(last)
        && cmp == Compare::Less
        && write
        && ctx.bias() == 0
    {
        let x0 = runs.lo as usize;
        if R::DIV_SEED {
            crate::fast::span::<Divide, D>(row, t, dt, 94 - ctx.shift_base, runs, seg, x0)?;
        } else {
            crate::fast::span::<Chord, D>(row, t, dt, 94 - ctx.shift_base, runs, seg, x0)?;
        }
    } else if tame && in_range(t) && in_range(last) {
        recip.begin_span(smooth);
        // The comparison is chosen once per span: the default (Less) gets its own loop, the rest share one.
        if cmp == Compare::Less && ctx.bias() == 0 {
            lean(recip, row, t, dt, ctx, |a, b| a < b, 0, write, runs)?;
        } else {
            lean(
                recip,
                row,
                t,
                dt,
                ctx,
                |a, b| cmp.test(a, b),
                ctx.bias(),
                write,
                runs,
            )?;
        }
    } else {
        recip.begin_span(false);
        let mut t = t;
        for (k, stored) in row.iter_mut().enumerate() {
            let mut pass = false;
            if in_range(t) {
                let (m, lz) = normalise(t);
                let code = biased(encode_w16(recip.recip(m), ctx.shift_base - lz), ctx.bias());
                if cmp.test(code, *stored) {
                    if write {
                        *stored = code;
                    }
                    pass = true;
                }
            }
            if !pass {
                runs.fail(k)?;
            }
            t = t.wrapping_add(dt as u64);
        }
    }
    runs.finish(n)
}

/// The lean loop of a tame span whose every pixel is in range: no range check, no leading-zero count.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lean<R: SpanRecip, D: DrawTarget>(
    recip: &mut R,
    row: &mut [u16],
    t: u64,
    dt: i64,
    ctx: &SpanCtx,
    test: impl Fn(u16, u16) -> bool,
    bias: i32,
    write: bool,
    runs: &mut Runs<'_, D>,
) -> Result<(), Error> {
    let mut walk = SpanWalker::new(t, dt);
    let mut enc = W16Enc::new(ctx.shift_base.wrapping_sub(walk.lz));
    for (k, stored) in row.iter_mut().enumerate() {
        let code = biased(enc.code::<R>(recip.recip(walk.m())), bias);
        if test(code, *stored) {
            if write {
                *stored = code;
            }
        } else {
            runs.fail(k)?;
        }
        if walk.step(recip) {
            enc = W16Enc::new(ctx.shift_base.wrapping_sub(walk.lz));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::fixed::div_u128_shift;

    /// Both ways to the depth-grid plane's `T` at the snapped vertices ([`t_at_snapped_narrow`], and
    /// [`t_at_snapped_wide`] where it declines) stay within their stated bound, `T_min 2^-35`, of the exact value
    /// `t_k + (gx rx_k + gy ry_k) / A` (formed in `i128`), whenever they answer: random off-grid triangles of 1 to
    /// 120 px, from gentle to grazing (`T` ratios up to 30 across the triangle) and slivers. Also that the narrow way
    /// answers for nearly every gentle triangle (it is the one the frames use).
    #[test]
    fn t_at_snapped_is_within_its_bound_both_ways() {
        let mut rnd = crate::xorshift(0x5DEE_CE66_D1CE_4E5D);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        let r = Rasterizer::<crate::recip::Fast>::new(RenderState::new(1.0, 100.0).unwrap());
        let (mut narrow, mut wide, mut gentle, mut gentle_narrow) = (0u32, 0u32, 0u32, 0u32);
        for k in 0..30_000 {
            let size = 1.0 + unit() * if k % 3 == 0 { 120.0 } else { 12.0 };
            let (cx, cy) = (40.0 + unit() * 100.0, 40.0 + unit() * 100.0);
            let sliver = k % 7 == 0;
            let mut v: [Vertex<()>; 3] = core::array::from_fn(|_| Vertex {
                x: (cx + unit() * size) as f32,
                y: (cy + unit() * size) as f32,
                z: 0.0,
                rhw: (1.0 / (2.0 + unit() * 60.0)) as f32,
                color: (),
            });
            if sliver {
                // The third vertex near the line through the first two.
                let f = unit();
                v[2].x = v[0].x + (v[1].x - v[0].x) * f as f32 + [0.01, 0.003, 0.0004][k % 3];
                v[2].y = v[0].y + (v[1].y - v[0].y) * f as f32;
            }
            let grazing = k % 5 == 0;
            if sliver && k % 2 == 0 {
                // A plane steep along the sliver and flat across it (1/W affine on the screen): the gradient's
                // numerators cancel, and their truncation is what the narrow way's bound covers.
                let f = ((v[2].x - v[0].x) / (v[1].x - v[0].x)).clamp(0.0, 1.0);
                v[0].rhw = 1.0 / 2.0;
                v[1].rhw = 1.0 / 60.0;
                v[2].rhw = v[0].rhw + (v[1].rhw - v[0].rhw) * f;
            } else if !grazing {
                // A gentle plane: the three 1/W within 2% of each other.
                let w = 2.0 + unit() * 60.0;
                for vk in v.iter_mut() {
                    vk.rhw = (1.0 / (w * (1.0 + unit() * 0.02))) as f32;
                }
            }
            let Ok(s) = r.setup(&v) else { continue };
            if s.on_grid {
                continue;
            }
            // The exact correction, as a numerator over the area.
            let [q0, q1, q2] = s.q.map(|q| (q.x as i128, q.y as i128));
            let (e1, e2) = ((q1.0 - q0.0, q1.1 - q0.1), (q2.0 - q0.0, q2.1 - q0.1));
            let a = e1.0 * e2.1 - e2.0 * e1.1;
            if a == 0 {
                continue;
            }
            let t = s.t.map(|v| v as i128);
            let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
            let (gx, gy) = (d1 * e2.1 - d2 * e1.1, d2 * e1.0 - d1 * e2.0);
            let t_min = t[0].min(t[1]).min(t[2]);
            let check = |out: [i64; 3], how: &str| {
                for j in 0..3 {
                    let (rx, ry) = snap_rounding(s.p[j], s.q[j], s.dbits, s.dorigin);
                    // c = num / a; |c' - c| |a| against the bound T_min 2^-35 |a|, without dividing (below 2^127).
                    let num = gx * rx as i128 + gy * ry as i128;
                    let err = ((out[j] as i128 - t[j]) * a - num).abs();
                    let bound = (t_min >> 35) * a.abs();
                    assert!(err <= bound, "{how} {k} vertex {j}: {err} > {bound}");
                }
            };
            let n = t_at_snapped_narrow(&s);
            let w = t_at_snapped_wide(&s);
            if let Narrow::Done(out) = n {
                narrow += 1;
                check(out, "narrow");
            }
            if let Narrow::Steep = n {
                assert!(
                    w.is_none(),
                    "{k}: steep for the narrow way, not for the wide one"
                );
            }
            if let Some(out) = w {
                wide += 1;
                check(out, "wide");
            }
            if !grazing && !sliver && size > 2.0 {
                gentle += 1;
                gentle_narrow += u32::from(matches!(n, Narrow::Done(_)));
            }
        }
        std::println!(
            "narrow {narrow}, wide {wide}, gentle {gentle} of which narrow {gentle_narrow}"
        );
        assert!(narrow > 10_000);
        // The narrow way's bound has about five bits of headroom on a gentle triangle of a few pixels.
        assert!(
            gentle_narrow * 100 >= gentle * 99,
            "{gentle_narrow} of {gentle}"
        );
    }

    /// The 32-bit targets' division equals `u128` division, on all of its paths and at their boundaries.
    #[test]
    fn div_u128_matches_u128_division() {
        let mut s: u64 = 0x2545_F491_4F6C_DD1D;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for k in 0..200_000 {
            let d = ((rnd() >> 2) >> (rnd() % 62)).max(1) | if k % 7 == 0 { 1 << 61 } else { 0 };
            let n = ((rnd() as u128) << 64 | rnd() as u128) >> (rnd() % 128);
            assert_eq!(div_u128_shift(n, d), n / d as u128, "{n} / {d}");
            for edge in [
                (d as u128) << 64,
                ((d as u128) << 64) - 1,
                ((d as u128) << 64) + 1,
                u128::MAX,
            ] {
                assert_eq!(div_u128_shift(edge, d), edge / d as u128, "{edge} / {d}");
            }
        }
        assert_eq!(div_round(-7, 2), -4);
        assert_eq!(div_round(7, 2), 4);
        assert_eq!(div_round(-5, 3), -2);
    }

    /// The plane solve's limb products equal the i128 products, at the ends of their ranges and on random values.
    #[test]
    fn limb_products_are_exact() {
        let mut rnd = crate::xorshift(0x51DE_CA75_0000_0001);
        let ends64 = [0, 1, -1, i64::MAX, i64::MIN + 1, 1 << 61, -(1 << 61)];
        let ends32 = [0, 1, -1, i32::MAX, i32::MIN, 1 << 30];
        for &a in &ends64 {
            for &b in &ends32 {
                assert_eq!(mul_64_32(a, b), a as i128 * b as i128, "{a} {b}");
            }
        }
        for _ in 0..200_000 {
            let a = (rnd() as i64) >> (rnd() % 64);
            let b = (rnd() as i32) >> (rnd() % 32);
            assert_eq!(mul_64_32(a, b), a as i128 * b as i128, "{a} {b}");
            let w = ((rnd() as i128) << 32 | rnd() as i128) >> (rnd() % 96) >> 1; // below 2^95
            let w = if rnd().is_multiple_of(2) { w } else { -w };
            assert_eq!(mul_96_32(w, b), w * b as i128, "{w} {b}");
        }
    }

    /// The depth grid's fraction bits are the finest that keep a box's positions in 31 bits: `(extent + 2) 2^bits`
    /// below `2^31`, and one bit more would reach it, for every extent up to the guard band's 8192 px; the
    /// documented values: 29 within one pixel, 24 under 126 px, 17 for the largest boxes. The set-up's `grid_bits` is
    /// the same.
    #[test]
    fn depth_grid_bits_is_the_finest_in_31_bits() {
        for e in 0..=8192i32 {
            let b = depth_grid_bits(e);
            assert_eq!(grid_bits(e), b);
            let span = (e as u64 + 2) << b;
            assert!(
                span < 1 << 31 && span << 1 >= 1 << 31,
                "extent {e}: {b} bits"
            );
        }
        assert_eq!(
            [0, 1, 5, 6, 125, 126, 8192].map(depth_grid_bits),
            [29, 29, 28, 27, 24, 23, 17]
        );
    }
}
