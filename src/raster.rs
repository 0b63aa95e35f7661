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
//! [`depth_grid_bits`](crate::setup::depth_grid_bits) fraction bits (`2^-17` px for a box as large as the guard band, `2^-24` for one under 126 px,
//! `2^-29` within a pixel), exact for every f32 coordinate of magnitude `2^(23 - bits)` px or more. Through the snapped
//! vertices instead, the depth of a grazing plane moved by many codes (up to 127 on world-space triangles); through
//! the grid, a covered pixel's `t` differs from the true surface's by at most
//! `sum_k |lambda_k| |grad t . (q_k - v_k)|` (`q_k` the grid positions, `v_k` the given ones, `lambda_k` the pixel's
//! barycentrics): zero for vertices on the snap grid (then the snapped plane is this plane, and nothing extra runs),
//! below `1.3e-4` codes on the grazing tests. The fast tier gets the same plane without a second solve: its `T` at the
//! snapped vertices ([`t_at_snapped`]), through which its own set-ups solve.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;
#[cfg(feature = "gouraud")]
use embedded_graphics_core::prelude::{Point, Size};
#[cfg(feature = "gouraud")]
use embedded_graphics_core::primitives::Rectangle;

use crate::depth::{encode_w16, DepthBuffer, W16_FAR};
use crate::edge::{Edge, Sub};
use crate::fast::{Chord, Divide};
use crate::fixed::{round_shift, split};
use crate::input::VertexInput;
#[cfg(feature = "gouraud")]
use crate::recip::Inv;
use crate::recip::{normalise, Fast, SpanRecip, SpanWalker, WSpan};
use crate::runs::Runs;
#[cfg(feature = "bias")]
use crate::setup::slope_bias;
#[cfg(test)]
use crate::setup::FAST_T_USED;
use crate::setup::{
    depth_plane, grid_bits, rows_of, t_at_snapped, t_at_snapped_unless_culled, Geom, Plane,
    Remember, Setup, Solved, Stats, TMemo, MIN_FRAC, SUBPIXEL_BITS,
};
use crate::state::{Compare, DepthMode};
use crate::state::{RenderState, MAX_T_LOG2};
use crate::Error;
#[cfg(feature = "gouraud")]
use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};

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

/// `t = rhw W_far` of one vertex as the exact product of the mantissas (`rhw = m 2^e`, `W_far = fm 2^fe`, both
/// positive), `pm 2^pe`, and its bit count; [`Error::DepthRange`] where `t` reaches `2^MAX_T_LOG2`.
#[inline(always)]
fn t_exact(m: u32, e: i32, fm: u32, fe: i32) -> Result<(u64, i32, i32), Error> {
    let (pm, pe) = (crate::fast::mul_wide(m, fm), e + fe);
    let b = crate::fast::bits64(pm) as i32 + pe;
    if b > MAX_T_LOG2 {
        return Err(Error::DepthRange);
    }
    Ok((pm, pe, b))
}

/// The vertices' exact `T` (mantissas and exponents) and the largest bit count, as [`Rasterizer::setup_unrounded`]
/// computes and checks them (`far` the far plane's `W`), for the memo draws ([`Rasterizer::setup_snapped_first`]).
/// Out of line: one copy for every strategy (the Cortex-M0's flash, whose standard firmware draws with four).
#[inline(never)]
fn t_values<V: VertexInput, const N: usize>(
    far: f32,
    v: &[V; N],
) -> Result<([(u64, i32); N], i32), Error> {
    let (_, fm, fe) = split(far).ok_or(Error::NonFinite)?;
    let mut tm = [(0u64, 0i32); N];
    let mut int_bits = 0;
    for k in 0..N {
        let (m, e) = v[k].rhw_exact()?;
        let (pm, pe, b) = t_exact(m, e, fm, fe)?;
        int_bits = int_bits.max(b);
        tm[k] = (pm, pe);
    }
    Ok((tm, int_bits))
}

/// The error [`Rasterizer::setup_unrounded`] reports where vertex `k` is the first that does not snap (`e`): its
/// checks come vertex by vertex (`1/W`, then the position, then `T`'s range), after the far plane's.
#[inline(never)]
#[cold]
fn snap_error<V: VertexInput>(far: f32, v: &[V], k: usize, e: Error) -> Error {
    let Some((_, fm, fe)) = split(far) else {
        return Error::NonFinite;
    };
    for (j, vj) in v.iter().enumerate().take(k + 1) {
        match vj.rhw_exact() {
            Err(e) => return e,
            Ok((m, ex)) if j < k => {
                if let Err(e) = t_exact(m, ex, fm, fe) {
                    return e;
                }
            }
            Ok(_) => {}
        }
    }
    e
}

/// A [`Setup`] without a depth grid from the snapped positions and the vertices' exact `T` (mantissas and
/// exponents), with the common fraction count `F = 61 - bits(floor(t_max))` (`t_max < 2^30`).
#[inline(always)]
fn assemble<const N: usize>(
    p: [Sub; N],
    on_grid: bool,
    tm: [(u64, i32); N],
    int_bits: i32,
) -> (Setup<N>, [i32; N]) {
    (
        Setup {
            p,
            on_grid,
            q: [Sub { x: 0, y: 0 }; N],
            dbits: SUBPIXEL_BITS,
            dorigin: (0, 0),
            fast_t: None,
            t: tm.map(|(m, _)| m as i64),
            frac: (61 - int_bits) as u32,
        },
        tm.map(|(_, e)| e),
    )
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

    /// Snaps and checks `N` vertices and gives their `T` with a common fraction count, and, for a triangle off the
    /// snap grid, its vertices on the depth grid ([`Rasterizer::depth_grid`]).
    pub(crate) fn setup<V: VertexInput, const N: usize>(
        &self,
        v: &[V; N],
    ) -> Result<Setup<N>, Error> {
        let (mut s, te) = self.setup_unrounded(v)?;
        Self::round_t(&mut s, te);
        Self::depth_grid(&mut s, v);
        Ok(s)
    }

    /// `T` of each vertex, rounded to the common fraction bits: from [`Rasterizer::setup_unrounded`]'s exact
    /// products (`s.t` their mantissas, `te` their exponents).
    #[inline(always)]
    pub(crate) fn round_t<const N: usize>(s: &mut Setup<N>, te: [i32; N]) {
        for (t, e) in s.t.iter_mut().zip(te) {
            // Below 2^61 (`frac = 61 - max_k bits(T_k)`): no saturation to test.
            *t = crate::fixed::round_shift_fits(*t as u64, e + s.frac as i32) as i64;
        }
    }

    /// [`Rasterizer::setup`] with each vertex's `T` left as the exact product `s.t[k] 2^te[k]` (the mantissas below
    /// `2^56`) and no depth grid (`q` at the origin), for a draw whose memo may stand in for them
    /// ([`Rasterizer::round_t`] and [`Rasterizer::depth_grid`] compute them where it does not). Every check of the
    /// input is made here.
    pub(crate) fn setup_unrounded<V: VertexInput, const N: usize>(
        &self,
        v: &[V; N],
    ) -> Result<(Setup<N>, [i32; N]), Error> {
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
            let (pm, pe, b) = t_exact(m, e, fm, fe)?;
            int_bits = int_bits.max(b);
            tm[k] = (pm, pe);
        }
        Ok(assemble(p, on_grid, tm, int_bits))
    }

    /// [`Rasterizer::setup_unrounded`] in two steps for a memo draw: the snapped positions first, and `T` only where
    /// `need_t` says, given them (it takes what a band remembered, which needs the positions); `T` is left 0 where it
    /// does not (the band that remembered the values checked these vertices, which the frame does not change). The
    /// same values and the same error as [`Rasterizer::setup_unrounded`] wherever `T` is computed, a vertex that
    /// does not snap included ([`snap_error`]).
    #[inline(always)]
    pub(crate) fn setup_snapped_first<V: VertexInput, const N: usize>(
        &self,
        v: &[V; N],
        need_t: impl FnOnce(&[Sub; N]) -> bool,
    ) -> Result<(Setup<N>, [i32; N]), Error> {
        let mut p = [Sub { x: 0, y: 0 }; N];
        let mut on_grid = true;
        for k in 0..N {
            let (x, y, exact) = match v[k].snapped_exact() {
                Ok(r) => r,
                Err(e) => return Err(snap_error(self.state.range.far(), v, k, e)),
            };
            p[k] = Sub { x, y };
            on_grid &= exact;
        }
        let (tm, int_bits) = if need_t(&p) {
            t_values(self.state.range.far(), v)?
        } else {
            ([(0, 0); N], 0)
        };
        Ok(assemble(p, on_grid, tm, int_bits))
    }

    /// A triangle's vertices `v` (snapped and checked as `s`) on the depth grid, where it is off the snap grid: `q`,
    /// `dbits` and `dorigin` of [`Setup`].
    pub(crate) fn depth_grid<V: VertexInput, const N: usize>(s: &mut Setup<N>, v: &[V; N]) {
        if N == 3 && !s.on_grid {
            let p = &s.p;
            let (ox, oy) = (
                p.iter().map(|s| s.x).min().unwrap_or(0) >> SUBPIXEL_BITS,
                p.iter().map(|s| s.y).min().unwrap_or(0) >> SUBPIXEL_BITS,
            );
            let xe = (p.iter().map(|s| s.x).max().unwrap_or(0) >> SUBPIXEL_BITS) - ox;
            let ye = (p.iter().map(|s| s.y).max().unwrap_or(0) >> SUBPIXEL_BITS) - oy;
            s.dbits = grid_bits(xe.max(ye));
            s.dorigin = (ox, oy);
            for (q, vk) in s.q.iter_mut().zip(v) {
                let (x, y) = vk.depth_xy(s.dbits, ox, oy);
                *q = Sub { x, y };
            }
        }
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
        Ok(self.prepare_memo(s, rows, fast, None)?.map(|(w, _)| w))
    }

    /// [`Rasterizer::prepare_setup`] with the plane of `T` remembered from an earlier band (`solved`: no depth grid,
    /// no solve), and the exact solve's plane to remember for the next (`None` where the fast set-up solved it). A
    /// walk from a remembered plane keeps the snapped vertices' `T` in `t_vertex` (the lean W16 loops, the only
    /// callers with a memo, do not read it).
    pub(crate) fn prepare_memo(
        &self,
        s: &Setup,
        rows: (i32, u16),
        fast: bool,
        solved: Option<Solved>,
    ) -> Result<Result<(Walk, Option<Solved>), Stats>, Error> {
        let [p0, p1, p2] = s.p;
        let area = (p1.x - p0.x) as i64 * (p2.y - p0.y) as i64
            - (p2.x - p0.x) as i64 * (p1.y - p0.y) as i64;
        let culled = Stats {
            culled: 1,
            ..Stats::default()
        };
        if crate::setup::culls_area(self.state.cull, area) {
            return Ok(Err(culled));
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
            true if !s.on_grid && solved.is_none() => s.fast_t.map(|t| order.map(|k| t[k])),
            _ => None,
        };
        if let Some(tv) = at_snapped {
            t_or = tv;
        }
        if let Some(sv) = solved {
            frac = sv.frac;
        }
        let (dq, darea, dbits, dorigin) = if s.on_grid || at_snapped.is_some() || solved.is_some() {
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
        let fast_plane = if small && solved.is_none() && (s.on_grid || at_snapped.is_some()) {
            Plane::solve_fast(t_or, &geom)
        } else {
            None
        };
        let (t, solved) = match (fast_plane, solved) {
            (Some(t), _) => (t, None),
            (None, Some(sv)) => (sv.plane.at_row(&geom), Some(sv)),
            (None, None) => {
                let plane = Plane::solve_ref(t_or, &geom);
                (plane.at_row(&geom), Some(Solved { plane, frac }))
            }
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
        Ok(Ok((
            Walk {
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
            },
            solved,
        )))
    }
}

/// Whether the snapped triangle's box is one the small-triangle path (`crate::small`) may take: under 32 px wide and
/// 126 px high. Outside it, that path declines whatever the band and the state.
#[inline(always)]
fn small_box(p: &[Sub; 3]) -> bool {
    let (w, h) = box_size(p);
    w < 32 << SUBPIXEL_BITS && h < 126 << SUBPIXEL_BITS
}

#[inline(always)]
fn box_size(p: &[Sub; 3]) -> (i32, i32) {
    let w = p[0].x.max(p[1].x).max(p[2].x) - p[0].x.min(p[1].x).min(p[2].x);
    let h = p[0].y.max(p[1].y).max(p[2].y) - p[0].y.min(p[1].y).min(p[2].y);
    (w, h)
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

    /// What a remembered [`t_at_snapped`] value, plane or small triangle's constants depend on besides the triangle:
    /// the strategy's way to it (its seed, and whether it is of the fast tier, whose set-up differs), the far plane
    /// (the vertices' `T`) and the near plane (the small-triangle path's range test, whose pass a remembered triangle
    /// skips). Both planes are positive (`DepthRange::new`), so their sign bits carry the strategy's two.
    pub(crate) fn memo_tag(&self) -> u64 {
        let r = &self.state.range;
        ((r.near().to_bits() as u64) << 32 | r.far().to_bits() as u64)
            | (R::FAST_W16 as u64) << 63
            | (R::DIV_SEED as u64) << 31
    }

    /// The fast tier's depth-grid values of `s` ([`t_at_snapped`], the strategy's way); none for a triangle the
    /// render state culls where the memo says the caller has not culled it (`early`, [`TMemo::early_cull`]): the
    /// draw culls it before it reads them.
    #[inline(always)]
    fn fast_t(&self, s: &Setup, early: bool) -> Option<[i64; 3]> {
        match (R::DIV_SEED, early) {
            (true, true) => t_at_snapped_unless_culled::<true>(s, self.state.cull),
            (false, true) => t_at_snapped_unless_culled::<false>(s, self.state.cull),
            (true, false) => t_at_snapped::<true>(s),
            (false, false) => t_at_snapped::<false>(s),
        }
    }

    /// What a memo draw computes of `s` when nothing remembered stands in for it: the depth grid, and on the fast
    /// tier the depth-grid values off the snap grid.
    #[inline(always)]
    fn depth_values<V: VertexInput>(&self, s: &mut Setup, v: &[V; 3], early: bool) {
        Self::depth_grid(s, v);
        if R::FAST_W16 && !s.on_grid {
            s.fast_t = self.fast_t(s, early);
        }
    }

    /// [`Rasterizer::draw`], with `memo` keeping the fast tier's depth-grid values ([`t_at_snapped`]) across the
    /// bands of a frame (the mesh's [`crate::mesh::PlaneCache`]); the values are a function of the triangle alone, so
    /// a remembered one draws exactly what a computed one does.
    pub(crate) fn draw_memo<D, M>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        v: &[impl VertexInput<Color = D::Color>; 3],
        memo: &mut M,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        M: TMemo,
    {
        let (cmp, write) = self.w16_test()?;
        depth.note_compare(cmp, write);
        // Only for a triangle with rows in the buffer (a band's draws include triangles that only come near it):
        // one that has none draws nothing either way, and both paths find that before they look at `fast_t`.
        let in_buffer = |p: &[Sub; 3], depth: &DepthBuffer<'_>| {
            let (y0, y_last) = (
                depth.y0(),
                depth.y0().saturating_add(depth.height() as i32 - 1),
            );
            let (first, last) = rows_of(p);
            (first <= y_last && last >= y0).then_some(last)
        };
        // With a memo, the snapped positions first, then what an earlier band remembered of a triangle with rows
        // here, then the vertices' `T` unless that is a small triangle's constants (which stand in for them: on the
        // Cortex-M0's W4, some 740 of a frame's 1,535 draws), then (below) `T` rounded and the depth grid only where
        // what it remembered does not stand in for them.
        let (mut taken, mut kept_row) = (None, None);
        let (mut s, te) = if M::KEEPS {
            self.setup_snapped_first(v, |p| {
                kept_row = in_buffer(p, depth);
                if kept_row.is_some() {
                    taken = memo.take();
                }
                !matches!(taken, Some(Remember::Small(_)))
            })?
        } else {
            (self.setup(v)?, [0; 3])
        };
        // Without a memo (`M::KEEPS` false, a constant: the branches below are not compiled) the values where a
        // path reads them, as ever. With one, what an earlier band of the frame remembered: the depth-grid values,
        // or the solved plane of a triangle the small-triangle path never takes (a fact of the triangle, whatever
        // the band or the state: its box, or an exact-tier strategy).
        let mut solved = None;
        let mut small_kept = None;
        let mut remembered_small = false;
        if M::KEEPS {
            if kept_row.is_some() {
                if let Some(Remember::Small(k)) = taken {
                    (small_kept, remembered_small) = (Some(k), true);
                } else {
                    Self::round_t(&mut s, te);
                }
                match taken {
                    Some(Remember::Plane(sv)) => solved = Some(sv),
                    Some(Remember::Small(_)) => {}
                    Some(Remember::T(Some(t))) => s.fast_t = Some(t),
                    // Declined there (a steep plane): the general set-up solves it from the depth grid.
                    Some(Remember::T(None)) => Self::depth_grid(&mut s, v),
                    None => self.depth_values(&mut s, v, memo.early_cull()),
                }
            } else {
                Self::round_t(&mut s, te);
            }
        } else if R::FAST_W16 && !s.on_grid && in_buffer(&s.p, depth).is_some() {
            s.fast_t = self.fast_t(&s, memo.early_cull());
        }
        // (A remembered small triangle's draw reads no depth-grid values: its constants stand for them.)
        #[cfg(test)]
        if R::FAST_W16
            && !s.on_grid
            && solved.is_none()
            && !remembered_small
            && in_buffer(&s.p, depth).is_some()
        {
            FAST_T_USED.with(|c| c.borrow_mut().push((s.p.map(|p| (p.x, p.y)), s.fast_t)));
        }
        // A remembered plane: a triangle the small-triangle path declines.
        if R::FAST_W16
            && solved.is_none()
            && cmp == Compare::Less
            && write
            && !self.state.has_bias()
        {
            // The strategy's seed and whether a memo keeps anything (constants: the other branches are not
            // compiled into the firmware).
            let (state, c) = (&self.state, v[0].color());
            // In: what a band remembered; out: what to keep.
            let k = &mut small_kept;
            let small = match (R::DIV_SEED, M::KEEPS) {
                (true, true) => {
                    crate::small::draw::<Divide, D, true>(target, depth, &s, state, c, k)?
                }
                (true, false) => {
                    crate::small::draw::<Divide, D, false>(target, depth, &s, state, c, k)?
                }
                (false, true) => {
                    crate::small::draw::<Chord, D, true>(target, depth, &s, state, c, k)?
                }
                (false, false) => {
                    crate::small::draw::<Chord, D, false>(target, depth, &s, state, c, k)?
                }
            };
            if let Some(stats) = small {
                if let (true, Some(last)) = (M::KEEPS, kept_row) {
                    match small_kept {
                        Some(k) => memo.keep(Remember::Small(k), last),
                        // Culled, or no row in this band: the depth-grid values it computed.
                        None if !s.on_grid && !remembered_small => {
                            memo.keep(Remember::T(s.fast_t), last)
                        }
                        None => {}
                    }
                }
                return Ok(stats);
            }
        }
        if remembered_small {
            // Remembered for the small-triangle path, which did not draw it here (its conditions changed): the
            // values the general set-up reads, `T` first (not computed above).
            let (tm, int_bits) = t_values(self.state.range.far(), v)?;
            let te;
            (s, te) = assemble(s.p, s.on_grid, tm, int_bits);
            Self::round_t(&mut s, te);
            self.depth_values(&mut s, v, memo.early_cull());
        }
        let (mut w, solved) =
            match self.prepare_memo(&s, (depth.y0(), depth.height()), R::FAST_W16, solved)? {
                Ok(w) => w,
                Err(stats) => return Ok(stats),
            };
        if let (true, Some(last)) = (M::KEEPS, kept_row) {
            // The plane of a triangle the small-triangle path never takes (its box: checked only here, off the
            // small triangles' way); the depth-grid values of the others, where the set-up reads them.
            match solved {
                Some(sv) if !R::FAST_W16 || !small_box(&s.p) => {
                    memo.keep(Remember::Plane(sv), last)
                }
                _ if R::FAST_W16 && !s.on_grid => memo.keep(Remember::T(s.fast_t), last),
                _ => {}
            }
        }
        let color = v[0].color();
        let mut stats = Stats::default();
        for j in w.geom.j0..=w.j1 {
            if let Some((lo, hi)) = w.row(depth.width()) {
                let t = w.t.at_col(lo as i64 - w.geom.i_ref) as u64;
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
    let last = crate::recip::span_last(t, dt, n as u32);
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
    use crate::setup::*;

    use crate::fixed::div_u128_shift;

    /// A memo draw whose memo remembers a small triangle's constants (so it skips the vertices' `T`) for a triangle
    /// the small-triangle path then declines (here: boxes of 40 to 120 px, beyond its 32) computes `T` after all and
    /// draws what [`Rasterizer::draw`] draws (codes, colours, statistics): that draw's fallback, which a real memo
    /// reaches only in rare cases, exercised directly; off and on the snap grid, for both fast-tier seeds.
    #[test]
    fn a_remembered_small_triangle_declined_draws_what_draw_draws() {
        use crate::{ColorBand, DepthBuffer};
        use embedded_graphics_core::pixelcolor::{raw::RawU16, Rgb565};
        // Remembers made-up small-triangle constants for every triangle.
        struct Liar;
        impl TMemo for Liar {
            fn take(&mut self) -> Option<Remember> {
                Some(Remember::Small(crate::small::Kept {
                    s_o: 1 << 62,
                    sx: 1 << 40,
                    sy: 1 << 41,
                    shifts: core::num::NonZeroU16::new(20).unwrap(),
                }))
            }
            fn keep(&mut self, _: Remember, _: i32) {}
        }
        fn check<R: SpanRecip + WSpan>() {
            let mut rnd = crate::xorshift(0x1234_5678_9ABC_DEF1);
            let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
            let mut r = Rasterizer::<R>::new(RenderState::new(1.0, 500.0).unwrap());
            let mut drawn = 0;
            for k in 0..200 {
                let size = 40.0 + unit() * 80.0;
                let c = Rgb565::from(RawU16::new((unit() * 65535.0) as u16));
                // The first two vertices `size` apart across: the box is at least 40 px wide.
                let v: [Vertex<Rgb565>; 3] = core::array::from_fn(|i| {
                    let (mut x, mut y) = ([1.0, 1.0 + size, unit() * size][i], unit() * size);
                    if k % 2 == 0 {
                        (x, y) = ((x * 256.0).round() / 256.0, (y * 256.0).round() / 256.0);
                    }
                    Vertex::new(x as f32, y as f32, (1.5 + unit() * 400.0) as f32, c)
                });
                let mut out: [_; 2] = core::array::from_fn(|_| {
                    (
                        std::vec![0u16; 128 * 128],
                        std::vec![0u16; 128 * 128],
                        Stats::default(),
                    )
                });
                for (i, (cp, zp, st)) in out.iter_mut().enumerate() {
                    let mut band = ColorBand::<Rgb565>::band(cp, 128, 0, 128).unwrap();
                    let mut depth = DepthBuffer::band(zp, 128, 0, 128).unwrap();
                    depth.clear();
                    *st = if i == 0 {
                        r.draw(&mut band, &mut depth, &v).unwrap()
                    } else {
                        r.draw_memo(&mut band, &mut depth, &v, &mut Liar).unwrap()
                    };
                }
                assert!(out[0] == out[1], "triangle {k}");
                drawn += u32::from(out[0].2.written > 0);
            }
            // Not vacuous: most of them write pixels (the rest are back faces or slivers between centres).
            assert!(drawn >= 80, "{drawn}");
        }
        check::<crate::recip::Fast>();
        check::<crate::recip::FastDiv>();
    }

    /// The memo draws' set-up (`setup_snapped_first`, which snaps every vertex before it computes any `T`, then finds
    /// the error with `snap_error`) reports the error every other draw's (`setup_unrounded`) does, in its order:
    /// vertex by vertex, `1/W`, then the position, then `T`'s range. Every triangle whose vertices are each good, bad
    /// in position, bad in `1/W`, or both (64 patterns), with each pair of bad values: positions NaN, infinite and
    /// beyond the guard band; `1/W` NaN, zero, negative and so large that `T` leaves its range.
    #[test]
    fn the_memo_set_up_reports_the_error_the_others_do() {
        let r = Rasterizer::<crate::recip::Fast>::new(RenderState::new(1.0, 100.0).unwrap());
        let good = [
            (10.3f32, 10.7f32, 0.5f32),
            (60.1, 12.9, 0.25),
            (30.6, 50.2, 0.125),
        ];
        let bad_pos = [f32::NAN, f32::INFINITY, 1.0e9];
        let bad_rhw = [f32::NAN, 0.0, -1.0, 1.0e30];
        // (the same vertex bad in `1/W` and position, reported as `1/W`'s; bad in `T`'s range and position, as the
        // position's)
        let (mut errors, mut rhw_first, mut position_first) = (0, 0, 0);
        for pattern in 0..64usize {
            for (pi, &bp) in bad_pos.iter().enumerate() {
                for (ri, &br) in bad_rhw.iter().enumerate() {
                    let v: [Vertex<()>; 3] = core::array::from_fn(|k| {
                        let (mut x, y, mut rhw) = good[k];
                        let kind = (pattern >> (2 * k)) & 3;
                        if kind & 1 != 0 {
                            x = bp;
                        }
                        if kind & 2 != 0 {
                            rhw = br;
                        }
                        Vertex {
                            x,
                            y,
                            z: 0.0,
                            rhw,
                            color: (),
                        }
                    });
                    let want = r.setup_unrounded(&v).err();
                    let got = r.setup_snapped_first(&v, |_| true).err();
                    assert_eq!(got, want, "pattern {pattern:06b}, position {pi}, 1/W {ri}");
                    errors += want.is_some() as u32;
                    // The first bad vertex bad in both ways.
                    let first = (0..3)
                        .map(|k| (pattern >> (2 * k)) & 3)
                        .find(|&kind| kind != 0);
                    if first == Some(3) {
                        match want {
                            Some(Error::DepthRange) => {}
                            Some(Error::RhwNotPositive) => rhw_first += 1,
                            Some(Error::NonFinite) if ri == 0 => rhw_first += 1,
                            Some(_) => position_first += 1,
                            None => {}
                        }
                    }
                }
            }
        }
        // Every case with a bad vertex is an error, and both orders within one vertex were reached.
        assert_eq!(errors, 63 * 12);
        assert!(
            rhw_first > 0 && position_first > 0,
            "{rhw_first} {position_first}"
        );
    }

    /// A sliver off the snap grid whose depth-grid plane cannot be walked with its `T`'s fraction bits
    /// ([`depth_plane`]'s `Err(Some(e))`) is solved with `e` fewer of them where more than [`MIN_FRAC`] remain; where
    /// fewer would (`frac <= e + MIN_FRAC`), or the depth-grid triangle is degenerate (`Err(None)`), it takes the
    /// snapped plane: the plane of the vertices' `T` through the snapped positions, which the same triangle given on
    /// the snap grid draws. Random slivers of three kinds (the third vertex 10^-3 to 10^-7 px off the line through the
    /// other two; exactly collinear positions off the snap grid; as nearly collinear as f32 allows, some 2^-40 px
    /// wide, through a pixel centre), `W` from 1.5 to 400 at far/near 500 or from 1 to 2^21 at far/near 2^29 (`T` with
    /// some 30 fraction bits, not 55), drawn by the exact tier (which takes no depth-grid values: the solve the general
    /// set-up reaches for every triangle):
    /// - each that takes the snapped plane draws what its snapped twin draws (codes, colours, statistics), among them
    ///   some at the rule's edge, `frac = e + MIN_FRAC`, that cover pixels;
    /// - most of those solved with fewer bits that cover pixels draw otherwise than their twins (their plane is the
    ///   depth-grid one, through the vertices as given: across a sliver, the snap's rounding of under 1/512 px moves it
    ///   by many codes).
    #[test]
    fn an_absurd_sliver_takes_the_snapped_plane_and_a_steep_one_fewer_bits() {
        use crate::{ColorBand, DepthBuffer};
        use embedded_graphics_core::pixelcolor::Rgb565;
        let mut rnd = crate::xorshift(0x511B_E125_0000_0001);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        // Two depth ranges: far/near 500, and 2^29 (the vertices' `T` then has some 30 fraction bits, not 55).
        let mut rs = [500.0, 536_870_900.0]
            .map(|far| Rasterizer::<crate::recip::Exact>::new(RenderState::new(1.0, far).unwrap()));
        let draw = |r: &mut Rasterizer<crate::recip::Exact>, v: &[Vertex<Rgb565>; 3]| {
            let (mut cp, mut zp) = (std::vec![0u16; 128 * 128], std::vec![0u16; 128 * 128]);
            let mut band = ColorBand::<Rgb565>::band(&mut cp, 128, 0, 128).unwrap();
            let mut depth = DepthBuffer::band(&mut zp, 128, 0, 128).unwrap();
            depth.clear();
            let st = r.draw(&mut band, &mut depth, v).unwrap();
            (cp, zp, st)
        };
        let (mut snapped, mut fewer, mut unlike, mut degenerate, mut edge) =
            (0u32, 0u32, 0u32, 0u32, 0u32);
        for k in 0..20_000 {
            let r = &mut rs[k % 2];
            let (x0, y0) = (5.0 + unit() * 50.0, 5.0 + unit() * 50.0);
            let (len, a) = (10.0 + unit() * 100.0, unit() * core::f64::consts::TAU);
            let (dx, dy) = (a.cos() * len * 0.6, a.sin() * len * 0.6);
            let (f, off) = (unit(), 10f64.powf(-3.0 - unit() * 4.0));
            let mut pos = [
                (x0, y0),
                (x0 + dx, y0 + dy),
                (x0 + f * dx - a.sin() * off, y0 + f * dy + a.cos() * off),
            ];
            if k % 3 == 0 {
                // Exactly collinear (multiples of 2^-12 px, exact in f32 and on any depth grid), off the snap grid:
                // the depth-grid triangle is degenerate where the snapped one is not.
                let g = |x: f64| (x * 4096.0).round() / 4096.0;
                let (ex, ey) = (g(dx / 2.0), g(dy / 2.0));
                pos = [
                    (g(x0), g(y0)),
                    (g(x0) + 2.0 * ex, g(y0) + 2.0 * ey),
                    (g(x0) + ex, g(y0) + ey),
                ];
            } else if k % 3 == 1 {
                // As nearly collinear as f32 allows: offsets of consecutive Fibonacci numbers of f32 steps (2^-18 px
                // from 32 to 64 px), whose cross product is one step squared: a depth-grid triangle some 2^-40 px
                // wide (the grid holds these positions exactly: 25 fraction bits below 64 px), up to 13 px long.
                let mut fib = [1u32, 1, 2];
                for _ in 0..20 + (unit() * 11.0) as u32 {
                    fib = [fib[1], fib[2], fib[1] + fib[2]];
                }
                let u = 2f64.powi(-18);
                let o = |a: u32, b: u32| if k % 4 < 2 { (a, b) } else { (b, a) };
                let (p1, p2) = (o(fib[2], fib[1]), o(fib[1], fib[0]));
                // The middle of the edge from the first vertex to the third within a step of a pixel centre (so
                // that the snapped triangle, some 1/512 px wide, may cover it); every position from 36 to 63 px.
                let (cx, cy) = (40.5 + (unit() * 8.0).floor(), 40.5 + (unit() * 8.0).floor());
                let (bx, by) = (cx - (p2.0 / 2) as f64 * u, cy - (p2.1 / 2) as f64 * u);
                pos = [
                    (bx, by),
                    (bx + p1.0 as f64 * u, by + p1.1 as f64 * u),
                    (bx + p2.0 as f64 * u, by + p2.1 as f64 * u),
                ];
            }
            // `W` from 1.5 to 400 with the nearer range, from 1 to 2^-8 of the far plane with the other.
            let w = [0, 1, 2].map(|_| match k % 2 {
                0 => 1.5 + unit() * unit() * 400.0,
                _ => (unit() * 21.0).exp2(),
            });
            let c = Rgb565::new((k % 32) as u8, 7, 9);
            let v: [Vertex<Rgb565>; 3] = core::array::from_fn(|i| {
                Vertex::new(pos[i].0 as f32, pos[i].1 as f32, w[i] as f32, c)
            });
            let Ok(s) = r.setup(&v) else { continue };
            let [p0, p1, p2] = s.p;
            let area = (p1.x - p0.x) as i64 * (p2.y - p0.y) as i64
                - (p2.x - p0.x) as i64 * (p1.y - p0.y) as i64;
            if s.on_grid || area == 0 {
                continue;
            }
            // `prepare_memo`'s orientation, then its first question to `depth_plane`.
            let order = if area < 0 { [0, 2, 1] } else { [0, 1, 2] };
            let (p, q, t) = (
                order.map(|k| s.p[k]),
                order.map(|k| s.q[k]),
                order.map(|k| s.t[k]),
            );
            let verdict = depth_plane(&p, &q, &t, s.dbits, s.dorigin);
            let takes_snapped = match verdict {
                Ok(_) => continue,
                Err(None) => {
                    degenerate += 1;
                    true
                }
                Err(Some(e)) => s.frac <= e + MIN_FRAC,
            };
            // The twin: the snapped positions given exactly (multiples of 1/256 px), the same `1/W`.
            let twin: [Vertex<Rgb565>; 3] = core::array::from_fn(|i| Vertex {
                x: s.p[i].x as f32 / 256.0,
                y: s.p[i].y as f32 / 256.0,
                ..v[i]
            });
            let (a, b) = (draw(r, &v), draw(r, &twin));
            if takes_snapped {
                snapped += 1;
                edge += u32::from(verdict == Err(Some(s.frac - MIN_FRAC)) && a.2.written > 0);
                assert!(a == b, "sliver {k}: {verdict:?} with frac {}", s.frac);
            } else {
                if a.2.written + b.2.written > 0 {
                    fewer += 1;
                    unlike += u32::from(a.1 != b.1);
                }
            }
        }
        std::println!(
            "snapped plane {snapped} ({degenerate} degenerate, {edge} at the edge with pixels), fewer bits {fewer} \
             ({unlike} unlike the twin)"
        );
        assert!(edge >= 20, "{edge} at the rule's edge with pixels");
        assert!(
            snapped >= 20 && fewer >= 20,
            "snapped plane {snapped}, fewer bits {fewer}"
        );
        assert!(unlike * 2 > fewer, "{unlike} of {fewer}");
    }

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
            // The exact correction, as a numerator over the area: `|c' - c| |a|` against the bound `T_min 2^-35
            // |a|`, without dividing (below 2^127).
            let x = Exact::of(&s);
            if x.a == 0 {
                continue;
            }
            let check = |out: [i64; 3], how: &str| assert!(x.within_bound(out), "{how} {k}");
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

    /// [`t_at_snapped`]'s plane in `i128`, from the definitions: the depth-grid triangle's edges and doubled area
    /// (0 for a degenerate one), the vertices' `T`, the gradient's numerators `(gx, gy)` and the snap's roundings
    /// `r_k = p_k - q_k` on the depth grid.
    struct Exact {
        e1: (i128, i128),
        e2: (i128, i128),
        a: i128,
        t: [i128; 3],
        gx: i128,
        gy: i128,
        r: [(i128, i128); 3],
    }

    impl Exact {
        fn of(s: &Setup) -> Exact {
            let q = s.q.map(|q| (q.x as i128, q.y as i128));
            let (e1, e2) = (
                (q[1].0 - q[0].0, q[1].1 - q[0].1),
                (q[2].0 - q[0].0, q[2].1 - q[0].1),
            );
            let t = s.t.map(|v| v as i128);
            let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
            let up = s.dbits - SUBPIXEL_BITS;
            let (ox, oy) = (s.dorigin.0 as i128 * 256, s.dorigin.1 as i128 * 256);
            Exact {
                e1,
                e2,
                a: e1.0 * e2.1 - e2.0 * e1.1,
                t,
                gx: d1 * e2.1 - d2 * e1.1,
                gy: d2 * e1.0 - d1 * e2.0,
                r: [0, 1, 2].map(|j| {
                    (
                        ((s.p[j].x as i128 - ox) << up) - q[j].0,
                        ((s.p[j].y as i128 - oy) << up) - q[j].1,
                    )
                }),
            }
        }
        fn t_min(&self) -> i128 {
            self.t[0].min(self.t[1]).min(self.t[2])
        }
        /// The numerator over the area of vertex `j`'s correction.
        fn num(&self, j: usize) -> i128 {
            self.gx * self.r[j].0 + self.gy * self.r[j].1
        }
        /// The exact corrections `c_k = (gx rx_k + gy ry_k) / A`, truncated toward 0 (the area not 0).
        fn c(&self) -> [i128; 3] {
            [0, 1, 2].map(|j| self.num(j) / self.a)
        }
        /// Whether `out` is within `T_min 2^-35` of the exact values, vertex by vertex (compared without dividing).
        fn within_bound(&self, out: [i64; 3]) -> bool {
            let bound = (self.t_min() >> 35) * self.a.abs();
            (0..3).all(|j| ((out[j] as i128 - self.t[j]) * self.a - self.num(j)).abs() <= bound)
        }
    }

    /// Just below the limit on the corrections (`T_min / 2^9`: the largest exact `|c_k|` within `2^-19` of it,
    /// found by bisecting one vertex's `1/W` over its `f32` bit patterns), the narrow way does not call the plane
    /// steep (which would skip the wide way): it does so only when even its value less its errors is beyond the
    /// limit by more than the wide way's error (`lim + lim / 2^19`). (The wide way may still decline there: it
    /// bounds the two terms' magnitudes, `|gx rx| + |gy ry|`, not their sum.) Just above it, both ways
    /// decline (beyond it by `2^-24`, above both ways' errors).
    #[test]
    fn t_at_snapped_answers_just_below_its_limit() {
        let mut rnd = crate::xorshift(0xB15E_C7ED_0000_1111);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        let r = Rasterizer::<crate::recip::Fast>::new(RenderState::new(1.0, 100.0).unwrap());
        let (mut below, mut above) = (0, 0);
        for _ in 0..300 {
            // A triangle of a pixel or two whose plane is steep (`T` doubling in about a pixel): its corrections near
            // the limit for some `1/W` of vertex 1.
            let (cx, cy, size) = (
                40.0 + unit() * 100.0,
                40.0 + unit() * 100.0,
                0.3 + unit() * 2.0,
            );
            let v: [Vertex<()>; 3] = core::array::from_fn(|_| Vertex {
                x: (cx + unit() * size) as f32,
                y: (cy + unit() * size) as f32,
                z: 0.0,
                rhw: 0.5,
                color: (),
            });
            // `ratio(bits)`: the largest |c_k| over the limit with vertex 1's `1/W` the f32 of these bits.
            let ratio = |bits: u32| -> Option<(f64, Setup)> {
                let mut v = v;
                v[1].rhw = f32::from_bits(bits);
                let s = r.setup(&v).ok().filter(|s| !s.on_grid)?;
                let x = Exact::of(&s);
                if x.a == 0 {
                    return None;
                }
                let lim = x.t_min() >> 9;
                Some((x.c().iter().map(|c| c.abs()).max()? as f64 / lim as f64, s))
            };
            // Bracket the limit between 1/W = 0.5 (a flat plane) and 0.5 / 30, then bisect the bit patterns.
            let (mut lo, mut hi) = (0.5f32.to_bits(), (0.5f32 / 30.0).to_bits());
            let (Some((r_lo, _)), Some((r_hi, _))) = (ratio(lo), ratio(hi)) else {
                continue;
            };
            if !(r_lo < 1.0 && r_hi > 1.0) {
                continue;
            }
            while lo.abs_diff(hi) > 1 {
                let mid = (lo + hi) / 2;
                match ratio(mid) {
                    Some((x, _)) if x < 1.0 => lo = mid,
                    Some(_) => hi = mid,
                    None => break,
                }
            }
            if let Some((x, s)) = ratio(lo) {
                if x > 1.0 - 2f64.powi(-19) && x <= 1.0 {
                    below += 1;
                    assert!(
                        !matches!(t_at_snapped_narrow(&s), Narrow::Steep),
                        "{x}: steep below the limit"
                    );
                }
            }
            if let Some((x, s)) = ratio(hi) {
                if x > 1.0 + 2f64.powi(-24) {
                    above += 1;
                    assert!(
                        t_at_snapped::<true>(&s).is_none() && t_at_snapped::<false>(&s).is_none(),
                        "{x}"
                    );
                }
            }
        }
        std::println!("just below the limit {below}, just above {above}");
        assert!(below >= 20 && above >= 20, "{below} {above}");
    }

    /// The wide way's decision ([`t_at_snapped_wide`]), against its stated rule evaluated in `i128`: it bounds each
    /// vertex's correction by its two terms' magnitudes, `(|gx rx| + |gy ry|) / |A|`, and declines where that is
    /// above `lim = T_min / 2^9` for some vertex (here: above it by `2^-20` and 4 units, beyond the way's errors, a
    /// relative `2^-26.5` and a unit a term; terms of `2^62` or more among them) or, with every one below the limit
    /// by as much, where a corrected `T` leaves `(0, 2^61)`; otherwise it answers, within `T_min 2^-35`. Counts in
    /// `seen` which of these it met: answered, beyond the limit (with terms of 2^62 or more), past 2^61.
    fn wide_decides(s: &Setup, seen: &mut [u32]) {
        let w = t_at_snapped_wide(s);
        let x = Exact::of(s);
        if x.a == 0 {
            assert!(w.is_none());
            return;
        }
        let (a, t, lim) = (x.a, x.t, x.t_min() >> 9);
        // Each vertex's two terms' magnitudes over the area (rounded up) and its exact correction.
        let m =
            x.r.map(|(rx, ry)| ((x.gx * rx).abs() + (x.gy * ry).abs() + a.abs() - 1) / a.abs());
        let c = x.c();
        let margin = |v: i128| (v >> 20) + 4;
        if m.iter().any(|&m| m > lim + margin(lim)) {
            assert!(
                w.is_none(),
                "a correction's terms beyond the limit, and it answered"
            );
            seen[1] += 1;
            if m.iter().any(|&m| m >= 1 << 62) {
                seen[2] += 1;
            }
            return;
        }
        if m.iter().any(|&m| m >= lim - margin(lim)) {
            return;
        }
        let v = [0, 1, 2].map(|j| t[j] + c[j]);
        if v.iter()
            .any(|&v| v >= (1 << 61) + (1 << 40) || v <= -(1 << 40))
        {
            if v.iter()
                .all(|&v| v >= (1 << 61) + (1 << 40) || (v > 1 << 40 && v < (1 << 61) - (1 << 40)))
            {
                assert!(w.is_none(), "a value past 2^61, and it answered");
                seen[3] += 1;
            }
            return;
        }
        if v.iter().all(|&v| v > 1 << 40 && v < (1 << 61) - (1 << 40)) {
            let out = w.expect("every correction below the limit, and it declined");
            assert!(x.within_bound(out));
            seen[0] += 1;
        }
    }

    /// The narrow way's decision is its stated rule, evaluated here in `i128` (no 32-bit pieces, no shift that could
    /// overflow): it declines ([`Narrow::Unsure`]) where the area is 0, where `T_min < 2^40`, and where its
    /// truncations' bound fails, `2^sd (2^su + W) R > |A| 2^(lt - 36)` (`sd`, `su` the shifts that bring the `T`
    /// differences and the gradient's numerators to 31 bits, `W` and `R` the edges' and roundings' sums, `T_min >=
    /// 2^lt`: [`t_at_snapped_narrow`]). Where the bound holds, vertex by vertex: an exact correction beyond its limit
    /// `lim = T_min / 2^9` by `2^-9` makes it steep ([`Narrow::Steep`]); one below its acceptance `lim - lim / 2^8`
    /// by `2^-9` that takes `T` past `2^61` makes it decline; if every one is below that and keeps `T` inside, it
    /// answers, within `T_min 2^-35` of the exact value (between those margins either may be right). Random
    /// off-grid triangles from 0.1 to 200 px and slivers, with planes from flat (equal `1/W`, some through
    /// vertices at whole pixels but for half a sub-pixel: the bound's `k >= 0` side, where `|A| 2^k` passes `2^64`)
    /// to steep, at far/near 100, 10^4 and 10^7, some beyond the far plane; some with the largest `T` within
    /// `2^-12` of `2^61`; and large triangles on the snap grid but for one ulp, from the near plane to 2^20 to 2^23
    /// times farther (`T_min < 2^40`, where only that test declines them).
    #[test]
    fn t_at_snapped_narrow_decides_by_its_stated_bound() {
        let bits = |v: u128| 128 - v.leading_zeros() as i32;
        let mut rnd = crate::xorshift(0x7A11_5EED_0B0D_D5ED);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        // Which sides of the rule the triangles reached: declined for small `T`, for the bound with `k >= 0` and
        // with `k < 0` (of which beyond 2^64 before the area's scale), answered with `k >= 0` and `k < 0` (with a
        // correction above half the limit), steep, and declined past 2^61; then the wide way's (`wide_decides`).
        let mut seen = [0u32; 13];
        for (far, w_hi, grid) in [
            (100.0f64, 99.0, false),
            (1e4, 2e4, false),
            (1e7, 3e7, false),
            (1e7, 3e7, true),
        ] {
            let r =
                Rasterizer::<crate::recip::Fast>::new(RenderState::new(1.0, far as f32).unwrap());
            for k in 0..20_000 {
                let size = [0.1, 2.0, 20.0, 200.0][k % 4] * (0.5 + unit());
                let (cx, cy) = (40.0 + unit() * 100.0, 40.0 + unit() * 100.0);
                let mut v: [Vertex<()>; 3] = core::array::from_fn(|_| Vertex {
                    x: (cx + unit() * size) as f32,
                    y: (cy + unit() * size) as f32,
                    z: 0.0,
                    rhw: 0.0,
                    color: (),
                });
                if k % 5 == 0 {
                    let f = unit();
                    v[2].x = v[0].x + (v[1].x - v[0].x) * f as f32 + [0.01, 0.003, 0.0004][k % 3];
                    v[2].y = v[0].y + (v[1].y - v[0].y) * f as f32;
                }
                // W from 1.5 to `w_hi` (beyond the far plane for the last two), within a spread of 10^-5 to 30x.
                let w = 1.5 + unit() * (w_hi - 1.5);
                let spread = [0.0, 1e-5, 1e-3, 0.03, 1.0, 30.0][(k / 4) % 6];
                for vk in v.iter_mut() {
                    vk.rhw = (1.0 / (w * (1.0 + unit() * spread))) as f32;
                    if spread == 0.0 && k % 3 == 0 {
                        // A flat plane through vertices half a sub-pixel off whole pixel centres: edges of whole
                        // pixels, so the area's low bits are zeros (`|A| 2^k` passes 2^64 with nothing left below).
                        vk.x = vk.x.floor() + 0.5 + 1.0 / 512.0;
                        vk.y = vk.y.floor() + 0.5 + 1.0 / 512.0;
                    }
                }
                if k % 5 == 0 && k % 2 == 0 {
                    // A plane steep along the sliver and flat across it (1/W affine on the screen): its gradient
                    // across the sliver is large, so corrections near and beyond the limit.
                    let f = ((v[2].x - v[0].x) / (v[1].x - v[0].x)).clamp(0.0, 1.0);
                    v[0].rhw = 1.0 / 2.0;
                    v[1].rhw = 1.0 / (2.0 + unit() as f32 * 60.0);
                    v[2].rhw = v[0].rhw + (v[1].rhw - v[0].rhw) * f;
                }
                if grid {
                    // Large triangles on the snap grid but for one ulp of one coordinate, from the near plane to
                    // 2^20 to 2^23 times farther: `T_min < 2^40` with roundings so small that the truncations'
                    // bound holds, the case the `T_min` test alone declines.
                    let (gx, gy, size) = (unit() * 2000.0, unit() * 2000.0, 250.0 + unit() * 500.0);
                    for vk in v.iter_mut() {
                        vk.x = (((gx + unit() * size) * 256.0).round() / 256.0 - 2000.0) as f32;
                        vk.y = (((gy + unit() * size) * 256.0).round() / 256.0 - 2000.0) as f32;
                    }
                    v[2].x = f32::from_bits(v[2].x.to_bits() + 1);
                    v[0].rhw = 1.0 / 1.5;
                    v[1].rhw = (1.0 / (1.5 * 2f64.powf(20.0 + 3.0 * unit()))) as f32;
                    v[2].rhw = (1.0 / (1.5 * 2f64.powf(23.0 * unit()))) as f32;
                }
                if k % 11 == 5 && !grid {
                    // The largest `t` just below a power of two, so its `T` within 2^-12 of 2^61, and a steep
                    // plane: a correction that takes it past 2^61 (which the way declines).
                    v[0].rhw = (7.998 / far) as f32;
                    v[1].rhw = v[0].rhw * (0.3 + 0.7 * unit()) as f32;
                    v[2].rhw = v[0].rhw * (0.3 + 0.7 * unit()) as f32;
                }
                if far > 1e6 && k % 7 == 3 && !grid {
                    // `T` is scaled to each triangle's largest, so `T_min < 2^40` takes a ratio of 2^21 in one
                    // triangle: from the near plane to beyond the far one (ratios from 2^10 to 2^23 here; the
                    // bound's products pass 2^64 below 2^21).
                    v[0].rhw = 1.0 / 1.5;
                    v[1].rhw = (1.0 / (1.5 * 2f64.powf(10.0 + 13.0 * unit()))) as f32;
                }
                let Ok(s) = r.setup(&v) else { continue };
                if s.on_grid {
                    continue;
                }
                let n = t_at_snapped_narrow(&s);
                let x = Exact::of(&s);
                let (e1, e2, a, t, t_min) = (x.e1, x.e2, x.a, x.t, x.t_min());
                wide_decides(&s, &mut seen[9..]);
                if a == 0 || t_min < 1 << 40 {
                    assert!(matches!(n, Narrow::Unsure), "{far} {k}: T_min {t_min}");
                    seen[0] += 1;
                    continue;
                }
                let lt = bits(t_min as u128) - 1;
                let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
                let sd = (bits(d1.unsigned_abs().max(d2.unsigned_abs())) - 30).max(0);
                let (dd1, dd2) = (d1 >> sd, d2 >> sd);
                let (g1, g2) = (dd1 * e2.1 - dd2 * e1.1, dd2 * e1.0 - dd1 * e2.0);
                let su = (bits(g1.unsigned_abs().max(g2.unsigned_abs())) - 30).max(0);
                let rr = x.r.iter().map(|r| r.0.abs() + r.1.abs()).max().unwrap();
                let wsum = (e1.1.abs() + e2.1.abs()).max(e1.0.abs() + e2.0.abs());
                let lhs = (1i128 << sd) * ((1i128 << su) + wsum) * rr;
                let kk = lt - 36;
                let fits = if kk >= 0 {
                    lhs <= a.abs() << kk
                } else {
                    lhs << -kk <= a.abs()
                };
                let k_side = lt - 36 - sd >= 0;
                if !fits {
                    assert!(matches!(n, Narrow::Unsure), "{far} {k}: the bound fails");
                    seen[if k_side { 1 } else { 2 }] += 1;
                    if !k_side
                        && bits(((1u128 << su) + wsum as u128) * rr as u128) - (lt - 36 - sd) >= 64
                    {
                        seen[3] += 1;
                    }
                    continue;
                }
                // The exact corrections against the limit `lim = T_min / 2^9`, vertex by vertex as the way goes:
                // one clearly above it (by 2^-9, far beyond the way's own error of about 2^-27 of it) is steep;
                // below its acceptance `ok = lim - lim / 2^8` by as much, with the value well inside `(0, 2^61)`,
                // the way goes on; at the end it answers, within `T_min 2^-35`. In between, either may be right.
                let c = x.c();
                let lim = t_min >> 9;
                let ok = lim - (lim >> 8);
                // Answers (`Some(0)`), steep (`Some(1)`), declines (`Some(2)`: a value past 2^61), or either.
                let mut expect = Some(0);
                for j in 0..3 {
                    if c[j].abs() > lim + (lim >> 9) {
                        expect = Some(1);
                        break;
                    }
                    let clear = c[j].abs() < ok - (ok >> 9);
                    if clear && t[j] + c[j] >= (1 << 61) + (1 << 40) {
                        expect = Some(2);
                        break;
                    }
                    let in_range = t[j] + c[j] > 1 << 20 && t[j] + c[j] < (1 << 61) - (1 << 40);
                    if !(clear && in_range) {
                        expect = None;
                        break;
                    }
                }
                match expect {
                    Some(0) => {
                        let Narrow::Done(out) = n else {
                            panic!("{far} {k}: the bound holds, the corrections are below the limit, and it declined");
                        };
                        assert!(x.within_bound(out), "{far} {k}");
                        seen[if k_side { 4 } else { 5 }] += 1;
                        if c.iter().any(|c| c.abs() > lim / 2) {
                            seen[6] += 1;
                        }
                    }
                    Some(1) => {
                        assert!(
                            matches!(n, Narrow::Steep),
                            "{far} {k}: a correction beyond the limit, not steep"
                        );
                        seen[7] += 1;
                    }
                    Some(_) => {
                        assert!(
                            matches!(n, Narrow::Unsure),
                            "{far} {k}: a value past 2^61, not declined"
                        );
                        seen[8] += 1;
                    }
                    None => {}
                }
            }
        }
        std::println!(
            "declined for T {}, for the bound {} / {} ({} beyond 2^64), answered {} / {} ({} above half the limit), steep {}, past 2^61 {}; the wide way: answered {}, beyond the limit {} (terms of 2^62 or more {}), past 2^61 {}",
            seen[0], seen[1], seen[2], seen[3], seen[4], seen[5], seen[6], seen[7], seen[8], seen[9], seen[10], seen[11], seen[12]
        );
        // Every side of the rule was reached.
        assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
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

    /// [`Rasterizer::draw_gouraud`] hands the target each row's passing run whole: one `fill_contiguous` a run, split
    /// only where its 32-pixel buffer fills, and no pixel by `draw_iter`. A 120 px triangle over a stored surface
    /// that fails in blocks of 7 columns (upper rows: runs of up to 14) and passes everywhere below (runs of up to
    /// 60, split at 32): the calls cover exactly the written pixels, each once; two calls meet on a row only where
    /// the first holds 32 pixels.
    #[cfg(feature = "gouraud")]
    #[test]
    fn a_gouraud_run_reaches_the_target_whole() {
        use embedded_graphics_core::geometry::OriginDimensions;
        use embedded_graphics_core::Pixel;
        struct Calls(std::vec::Vec<Rectangle>);
        impl OriginDimensions for Calls {
            fn size(&self) -> Size {
                Size::new(128, 64)
            }
        }
        impl DrawTarget for Calls {
            type Color = Rgb888;
            type Error = core::convert::Infallible;
            fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
                &mut self,
                _: I,
            ) -> Result<(), Self::Error> {
                panic!("a pixel outside a run");
            }
            fn fill_contiguous<I: IntoIterator<Item = Rgb888>>(
                &mut self,
                area: &Rectangle,
                colors: I,
            ) -> Result<(), Self::Error> {
                assert_eq!(
                    colors.into_iter().count() as u32,
                    area.size.width * area.size.height
                );
                self.0.push(*area);
                Ok(())
            }
        }
        let stored = |x: usize, y: usize| {
            if y < 32 && (x / 7).is_multiple_of(3) {
                0
            } else {
                u16::MAX
            }
        };
        let mut d: std::vec::Vec<u16> = (0..128 * 64).map(|k| stored(k % 128, k / 128)).collect();
        let v = [(2.0, 1.0), (122.0, 3.0), (60.0, 62.0)]
            .map(|(x, y)| Vertex::new(x, y, 10.0, Rgb888::new(x as u8, y as u8 * 4, 200)));
        let mut calls = Calls(std::vec::Vec::new());
        let mut r: Rasterizer = Rasterizer::new(RenderState::new(1.0, 100.0).unwrap());
        let st = r
            .draw_gouraud(
                &mut calls,
                &mut DepthBuffer::new(&mut d, 128, 64).unwrap(),
                &v,
            )
            .unwrap();
        let mut covered = std::vec![false; 128 * 64];
        for a in &calls.0 {
            assert!(
                a.size.height == 1 && (1..=32).contains(&a.size.width),
                "{a:?}"
            );
            for x in a.top_left.x..a.top_left.x + a.size.width as i32 {
                let k = (a.top_left.y * 128 + x) as usize;
                assert!(!covered[k], "written twice at {x}");
                covered[k] = true;
            }
        }
        let written: std::vec::Vec<bool> = (0..128 * 64)
            .map(|k| d[k] != stored(k % 128, k / 128))
            .collect();
        assert_eq!(covered, written);
        calls.0.sort_by_key(|a| (a.top_left.y, a.top_left.x));
        let (mut met, mut gaps) = (0, 0);
        for p in calls.0.windows(2) {
            if p[0].top_left.y == p[1].top_left.y {
                if p[0].top_left.x + p[0].size.width as i32 == p[1].top_left.x {
                    assert_eq!(
                        p[0].size.width, 32,
                        "a run split short: {:?} {:?}",
                        p[0], p[1]
                    );
                    met += 1;
                } else {
                    gaps += 1;
                }
            }
        }
        // Both cases occur: runs split at the buffer's size, and runs parted by failing pixels (14 and 118 when
        // written).
        assert!(met > 10 && gaps > 100, "{met} {gaps}");
        assert_eq!(st.written as usize, written.iter().filter(|&&w| w).count());
    }
}
