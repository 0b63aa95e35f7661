//! Triangle setup and the span loop.
//!
//! Depth. Each vertex gives `t = W_far * rhw = W_far / W` (seed 000_92e7aa22df8423f2.txt: `W_TNT = RHW * dvRW_far`,
//! with the 16-bit fixed scale 1.0), so `W / W_far = 1/t`, the far plane is `t = 1` and the near plane `t = W_far/W_near`.
//! `t` is linear in screen space (seed 003_0afae2e2ce9f2c57.txt: interpolate 1/w linearly, take the reciprocal per
//! pixel). It is held as `T = t * 2^F` in an `i64`, with `F = 61 - bits(floor(t_max))` fraction bits chosen per
//! triangle from its largest vertex `t` (so `T < 2^61`; `F >= 30` since `t <= 2^30`; `F >= 47` when `t_max < 2^14`).
//! The plane is solved exactly in `i128` at setup: the per-pixel steps and the value at a reference pixel are each
//! rounded to nearest, so at a pixel `k` columns and `l` rows from the reference `T` errs by at most
//! `(1 + k + l) / 2` units of `2^-F`. Steps are added with wrapping arithmetic: for a sliver the plane's slope may
//! exceed `i64`, but every covered pixel's true `T` lies in `[0, 2^61]`, so the wrapped sum is right modulo `2^64`.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::depth::{encode_w16, DepthBuffer};
use crate::edge::{Edge, Sub};
use crate::fixed::{round_shift, split, to_fixed};
use crate::recip::{DefaultRecip, PerPixel, SpanRecip};
use crate::state::{Cull, RenderState, MAX_T_LOG2};
use crate::Error;

/// Fraction bits of snapped x and y (Direct3D 11's 16.8).
pub const SUBPIXEL_BITS: u32 = 8;
/// Vertices must have `|x|, |y| < GUARD_BAND` pixels (see ARCHITECTURE.md for why this is safe in i64).
pub const GUARD_BAND: i32 = 4096;
const GUARD_LOG2: i32 = 12;

/// A transformed-and-lit vertex, like Direct3D's TLVERTEX: `x`, `y` in pixels (pixel centres at `i + 0.5`), `z`
/// (kept for Z modes), `rhw = 1/W`, and a colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex<C> {
    /// Pixels, right.
    pub x: f32,
    /// Pixels, down.
    pub y: f32,
    /// Post-projection z (unused by the W-buffer, checked for finiteness).
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

/// A triangle after snapping and checks, ready to walk.
struct Setup {
    p: [Sub; 3],
    t: [i64; 3],
    frac: u32,
}

fn snap(v: f32) -> Result<i32, Error> {
    match to_fixed(v, SUBPIXEL_BITS as i32, GUARD_LOG2) {
        Ok(s) => Ok(s as i32),
        Err(false) => Err(Error::NonFinite),
        Err(true) => Err(Error::OutOfGuardBand),
    }
}

/// `rhw * W_far` as an exact product of mantissas, `(m, e)` with the value `m * 2^e`.
fn t_of(rhw: f32, far: (u32, i32)) -> Result<(u64, i32), Error> {
    let (neg, m, e) = split(rhw).ok_or(Error::NonFinite)?;
    if neg || m == 0 {
        return Err(Error::RhwNotPositive);
    }
    let pm = m as u64 * far.0 as u64;
    let pe = e + far.1;
    if 64 - pm.leading_zeros() as i32 + pe > MAX_T_LOG2 {
        return Err(Error::DepthRange);
    }
    Ok((pm, pe))
}

/// Rounded `n / d` for `d > 0` (ties away from zero).
fn div_round(n: i128, d: i128) -> i128 {
    if n >= 0 {
        (n + d / 2) / d
    } else {
        -((-n + d / 2) / d)
    }
}

/// Draws triangles into a colour target and a W16 buffer, with reciprocal strategy `R`.
pub struct Rasterizer<R: SpanRecip = PerPixel<DefaultRecip>> {
    /// The render state used by the next draws.
    pub state: RenderState,
    recip: R,
}

impl<R: SpanRecip> Rasterizer<R> {
    /// A rasterizer with `state`.
    pub fn new(state: RenderState) -> Self {
        Rasterizer {
            state,
            recip: R::default(),
        }
    }

    fn setup<C>(&self, v: &[Vertex<C>; 3]) -> Result<Setup, Error> {
        let (_, fm, fe) = split(self.state.range.far()).ok_or(Error::NonFinite)?;
        let mut p = [Sub { x: 0, y: 0 }; 3];
        let mut tm = [(0u64, 0i32); 3];
        for k in 0..3 {
            if !v[k].z.is_finite() {
                return Err(Error::NonFinite);
            }
            p[k] = Sub {
                x: snap(v[k].x)?,
                y: snap(v[k].y)?,
            };
            tm[k] = t_of(v[k].rhw, (fm, fe))?;
        }
        // F = 61 - bits(floor(t_max)), t_max < 2^30.
        let int_bits = tm
            .iter()
            .map(|&(m, e)| (64 - m.leading_zeros() as i32 + e).max(0))
            .max()
            .unwrap_or(0);
        let frac = (61 - int_bits) as u32;
        let t = tm.map(|(m, e)| round_shift(m, e + frac as i32) as i64);
        Ok(Setup { p, t, frac })
    }

    /// Draws one triangle. On an error nothing is written.
    pub fn draw<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        v: &[Vertex<D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let s = self.setup(v)?;
        let [p0, mut p1, mut p2] = s.p;
        let [t0, mut t1, mut t2] = s.t;
        let area = (p1.x - p0.x) as i64 * (p2.y - p0.y) as i64
            - (p2.x - p0.x) as i64 * (p1.y - p0.y) as i64;
        let culled = Stats {
            culled: 1,
            ..Stats::default()
        };
        match self.state.cull {
            _ if area == 0 => return Ok(culled),
            Cull::Cw if area > 0 => return Ok(culled),
            Cull::Ccw if area < 0 => return Ok(culled),
            _ => {}
        }
        if area < 0 {
            core::mem::swap(&mut p1, &mut p2);
            core::mem::swap(&mut t1, &mut t2);
        }
        let area = area.abs();

        // Rows whose centre lies in the vertices' y-range, clipped to the buffer.
        let ymin = p0.y.min(p1.y).min(p2.y);
        let ymax = p0.y.max(p1.y).max(p2.y);
        let j_first = ((ymin - 128) as i64).div_euclid(256) as i32 + 1
            - i32::from((ymin - 128).rem_euclid(256) == 0);
        let j_last = ((ymax - 128) as i64).div_euclid(256) as i32;
        let j0 = j_first.max(depth.y0());
        let j1 = j_last.min(depth.y0() + depth.height() as i32 - 1);
        if j0 > j1 {
            return Ok(Stats::default());
        }

        // The t plane, exactly: T(X, Y) = T0 + (gx (X - X0) + gy (Y - Y0)) / area, X, Y in sub-pixels.
        let (dt1, dt2) = (t1 as i128 - t0 as i128, t2 as i128 - t0 as i128);
        let gx = dt1 * (p2.y - p0.y) as i128 - dt2 * (p1.y - p0.y) as i128;
        let gy = dt2 * (p1.x - p0.x) as i128 - dt1 * (p2.x - p0.x) as i128;
        let a = area as i128;
        let step_x = div_round(gx * 256, a) as i64; // wraps for slivers: see the module doc
        let step_y = div_round(gy * 256, a) as i64;
        let xmin = p0.x.min(p1.x).min(p2.x);
        let i_ref = (xmin >> SUBPIXEL_BITS) as i64;
        let (rx, ry) = (
            256 * i_ref as i128 + 128 - p0.x as i128,
            256 * j0 as i128 + 128 - p0.y as i128,
        );
        let mut t_row = (t0 as i128 + div_round(gx * rx + gy * ry, a)) as i64;

        let mut edges = [
            Edge::new(p0, p1, j0),
            Edge::new(p1, p2, j0),
            Edge::new(p2, p0, j0),
        ];
        let t_near = self.state.range.t_max(s.frac);
        let span = SpanCtx {
            t_lo: 1u64 << s.frac,
            t_hi: t_near,
            shift_base: 94 - s.frac,
            step_x,
        };
        let width = depth.width() as i64;
        let color = v[0].color;
        let mut stats = Stats::default();
        for j in j0..=j1 {
            let (mut lo, mut hi) = (0i64, width);
            for e in &edges {
                let (l, h) = e.bound();
                lo = lo.max(l);
                hi = hi.min(h);
            }
            if lo < hi {
                let t = t_row.wrapping_add(step_x.wrapping_mul(lo - i_ref));
                let st = self.span(target, depth, j, lo as i32, hi as i32, t, &span, color)?;
                stats += st;
            }
            for e in &mut edges {
                e.step();
            }
            t_row = t_row.wrapping_add(step_y);
        }
        Ok(stats)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn span<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        j: i32,
        lo: i32,
        hi: i32,
        t: i64,
        c: &SpanCtx,
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
    {
        let (cmp, write) = (self.state.compare, self.state.depth_write);
        let row = depth.row_mut(j);
        let mut t = t as u64;
        self.recip.begin_span(t, c.step_x, (hi - lo) as u32);
        let mut run_start = lo;
        let mut written = 0;
        for i in lo..hi {
            let mut pass = false;
            if t >= c.t_lo && t <= c.t_hi {
                let inv = self.recip.recip(t);
                let code = encode_w16(inv.x, c.shift_base - inv.lz);
                let stored = &mut row[i as usize];
                if cmp.test(code, *stored) {
                    if write {
                        *stored = code;
                    }
                    pass = true;
                }
            }
            if !pass {
                if run_start < i {
                    fill(target, run_start, i, j, color)?;
                }
                run_start = i + 1;
            } else {
                written += 1;
            }
            t = t.wrapping_add(c.step_x as u64);
        }
        if run_start < hi {
            fill(target, run_start, hi, j, color)?;
        }
        Ok(Stats {
            fragments: (hi - lo) as u32,
            written,
            culled: 0,
        })
    }
}

struct SpanCtx {
    t_lo: u64,
    t_hi: u64,
    shift_base: u32,
    step_x: i64,
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
