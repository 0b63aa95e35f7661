//! Depth buffers of any [`DepthFormat`], packed 2, 3 or 4 bytes a pixel, and the span loop that fills them.
//!
//! Every format goes through the same edge walk and the same screen-linear `T = t 2^F`, `t = W_far / W`
//! (see ARCHITECTURE.md). What a pixel stores is computed from it in integers, never in f64:
//! - W formats ([`Input::W`]) take `u = W / W_far` in Q0.62 from the rasterizer's `W` strategy (a per-pixel reciprocal
//!   or [`crate::recip::Quake`]);
//! - Z formats ([`Input::Z`]) take D3D's `[0, 1]` Z, which is affine in `1/W` and so needs no reciprocal:
//!   `Z = 1 - rz`, `rz = (t - 1) n / (f - n)` (the reversed Z), in Q0.60, from `T` with one multiply;
//! - the linear-Z trick ([`Input::LinearZ`], Dunlop's "Linear Depth" `z * w / far`) computes each vertex's
//!   `(W - n) / (f - n)` exactly and interpolates it linearly in screen space, as the hardware interpolates any
//!   vertex z: right at the vertices, wrong inside (the error the seed does not mention, shown by the tests).
//!
//! [`crate::Rasterizer::draw`] gives W16 buffers to the tiers' own W16 loops (where the strategy is a per-pixel
//! reciprocal) and every other format to this loop, which serves every format with every strategy and gives the
//! same W16 codes as those loops (a test checks it, through `Rasterizer::draw_generic`).

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::edge::Sub;
use crate::fixed::{div_u128, split};
use crate::format::{DepthFormat, W24FScaled, LZ16, RZ32F, W16, W16F, W24F, W32F, Z16, Z24, Z32F};
use crate::input::VertexInput;
#[cfg(feature = "bias")]
use crate::recip::exact_u;
use crate::recip::WSpan;
use crate::runs::Runs;
#[cfg(feature = "bias")]
use crate::setup::slope_bias;
use crate::setup::{div_round, Plane, Stats};
use crate::state::{DepthMode, ZConst};
use crate::{DepthBuffer, Error, Rasterizer};

/// What a format's code is computed from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// `u = W / W_far`, Q0.62 (`2^62` at the far plane).
    W,
    /// D3D Z of the pixel's `1/W`, Q0.60 (`2^60` at the far plane).
    Z,
    /// The linear-Z trick's value, interpolated linearly in screen space from the vertices, Q0.60.
    LinearZ,
}

/// A format the rasterizer can store into: the integer encoder of [`DepthFormat`]'s f64 definition.
pub trait Codec: DepthFormat + 'static {
    /// What the code is computed from.
    const INPUT: Input;
    /// Nearer is a larger code (reversed Z): comparisons are evaluated with their operands swapped, so `Less` still
    /// keeps the nearest surface.
    const REVERSED: bool = false;
    /// The code of `q` (in [`Codec::INPUT`]'s units, at most its far-plane value) with `W_far = far.0 * 2^far.1`.
    fn code(q: u64, far: (u32, i32)) -> u32;
    /// [`crate::Rasterizer::draw`] of one triangle into a buffer of this format: the span loop generic over the
    /// format and the strategy, except for W16, whose draws take the strategy's own W16 loops
    /// ([`WSpan::draw_w16`]). Resolved at compile time, so a firmware links only its format's loops.
    #[doc(hidden)]
    #[inline(always)]
    fn draw_into<R: WSpan, D, V>(
        r: &mut Rasterizer<R>,
        target: &mut D,
        depth: &mut DepthBuffer<'_, Self>,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        Self: Sized,
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>,
    {
        r.draw_packed(target, Some(depth), v)
    }
    /// The code of the far plane, which a cleared buffer holds.
    fn far_code(far: (u32, i32)) -> u32 {
        Self::code(Self::far_q(), far)
    }
    /// The far plane in [`Codec::INPUT`]'s units.
    fn far_q() -> u64 {
        match Self::INPUT {
            Input::W => 1 << 62,
            Input::Z | Input::LinearZ => 1 << 60,
        }
    }
}

/// `round(q * max / 2^frac)` exactly.
#[inline(always)]
fn unorm_code(q: u64, frac: u32, max: u32) -> u32 {
    (((q as u128 * max as u128) + (1u128 << (frac - 1))) >> frac).min(max as u128) as u32
}

/// The bits of the positive value `p * 2^e2` in an IEEE-style float with an 8-bit exponent (bias 127) and `mbits`
/// mantissa bits, rounded to nearest (ties up); 0 for `p = 0`. The value must be in the normal range.
#[inline(always)]
fn float_bits(p: u64, e2: i32, mbits: u32) -> u32 {
    if p == 0 {
        return 0;
    }
    let b = 63 - p.leading_zeros() as i32;
    let mut e = b + e2;
    let mut m = if b > mbits as i32 {
        let sh = (b - mbits as i32) as u32;
        ((p as u128 + (1u128 << (sh - 1))) >> sh) as u64
    } else {
        p << (mbits as i32 - b)
    };
    if m >> (mbits + 1) != 0 {
        m >>= 1;
        e += 1;
    }
    (((e + 127) as u32) << mbits) | (m as u32 & ((1 << mbits) - 1))
}

/// `W` itself, as `(p, e2)` with `W = p * 2^e2`: `u / 2^62 * W_far`, from the top 32 bits of the normalised `u`
/// (relative error below `2^-31`; `u > 0`).
#[inline(always)]
fn w_of(u: u64, far: (u32, i32)) -> (u64, i32) {
    let lz = u.leading_zeros();
    (
        ((u << lz) >> 32) * far.0 as u64,
        far.1 - 62 + 32 - lz as i32,
    )
}

impl Codec for W16 {
    const INPUT: Input = Input::W;
    #[inline(always)]
    fn draw_into<R: WSpan, D, V>(
        r: &mut Rasterizer<R>,
        target: &mut D,
        depth: &mut DepthBuffer<'_, W16>,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>,
    {
        R::draw_w16(r, target, depth, v)
    }
    #[inline(always)]
    fn code(u: u64, _far: (u32, i32)) -> u32 {
        unorm_code(u, 62, 0xffff)
    }
}

impl Codec for W16F {
    const INPUT: Input = Input::W;
    /// `v = 256 u / 2^62 = u / 2^54`: denormal below `2^-6` (`u < 2^48`), `round(v / 2^-18)`; else exponent
    /// `floor(log2 v) + 7` and 12 mantissa bits rounded (a carry moves to the next exponent, as in the f64 encode).
    #[inline(always)]
    fn code(u: u64, _far: (u32, i32)) -> u32 {
        if u < 1 << 48 {
            return ((u + (1 << 35)) >> 36) as u32;
        }
        let b = 63 - u.leading_zeros();
        let sh = b - 12;
        let m = (u + (1 << (sh - 1))) >> sh; // [4096, 8192]
        (((b as i32 - 54 + 7) as u32) << 12) + (m as u32 - 4096)
    }
}

impl Codec for W24F {
    const INPUT: Input = Input::W;
    /// The f32 of `W`, then its low byte rounded off (the double rounding of the f64 definition).
    #[inline(always)]
    fn code(u: u64, far: (u32, i32)) -> u32 {
        let (p, e) = w_of(u, far);
        (float_bits(p, e, 23) + 0x80) >> 8
    }
}

impl Codec for W24FScaled {
    const INPUT: Input = Input::W;
    /// `W / W_far * 2^127 = u * 2^65`.
    #[inline(always)]
    fn code(u: u64, _far: (u32, i32)) -> u32 {
        (float_bits(u, 65, 23) + 0x80) >> 8
    }
}

impl Codec for W32F {
    const INPUT: Input = Input::W;
    #[inline(always)]
    fn code(u: u64, far: (u32, i32)) -> u32 {
        let (p, e) = w_of(u, far);
        float_bits(p, e, 23)
    }
}

impl Codec for Z16 {
    const INPUT: Input = Input::Z;
    #[inline(always)]
    fn code(z: u64, _far: (u32, i32)) -> u32 {
        unorm_code(z, 60, 0xffff)
    }
}

impl Codec for Z24 {
    const INPUT: Input = Input::Z;
    #[inline(always)]
    fn code(z: u64, _far: (u32, i32)) -> u32 {
        unorm_code(z, 60, 0xff_ffff)
    }
}

impl Codec for Z32F {
    const INPUT: Input = Input::Z;
    #[inline(always)]
    fn code(z: u64, _far: (u32, i32)) -> u32 {
        float_bits(z, -60, 23)
    }
}

impl Codec for RZ32F {
    const INPUT: Input = Input::Z;
    const REVERSED: bool = true;
    #[inline(always)]
    fn code(z: u64, _far: (u32, i32)) -> u32 {
        float_bits((1u64 << 60) - z.min(1 << 60), -60, 23)
    }
}

impl Codec for LZ16 {
    const INPUT: Input = Input::LinearZ;
    #[inline(always)]
    fn code(z: u64, _far: (u32, i32)) -> u32 {
        unorm_code(z, 60, 0xffff)
    }
}

/// The linear-Z trick's value `(W - n) / (f - n) = Z * u` at a vertex (exact `u`), Q0.60, saturated to `+-2^61` so
/// vertices beyond the range still give a plane (pixels outside the range are not drawn).
fn linear_z60(zc: &ZConst, t: i64, frac: u32) -> i64 {
    let t = t.max(1) as u64;
    let z = (1i128 << 60) - zc.rz60(t, frac) as i128;
    // |z| < 2^63 (rz60 is saturated to 2^62) and u <= 2^64 after the clamp, so the product fits i128
    let u = div_u128((1u128 << (62 + frac).min(125)) + (t as u128 >> 1), t).min(1 << 64) as i128;
    ((z * u) >> 62).clamp(-(1 << 61), 1 << 61) as i64
}

impl<F: Codec> DepthBuffer<'_, F> {
    /// Sets every pixel to the far plane's code for `range` (0 for reversed Z; a W16 buffer's far code, 65535, does
    /// not depend on the range: [`DepthBuffer::clear`]).
    pub fn clear_for(&mut self, range: &crate::DepthRange) {
        let (_, fm, fe) = split(range.far()).unwrap_or((false, 0, 0));
        self.fill(crate::format::Storage::from_code(F::far_code((fm, fe))));
    }
}

/// The depth buffering a draw gets after Dunlop's "Using W-Buffers" capability check (see [`DepthMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resolved {
    /// What the draw does.
    pub mode: DepthMode,
    /// W was asked for, the format stores Z: Z is used instead.
    pub fell_back: bool,
}

/// Seed 002's capability check for format `F`: W where asked and `F` stores W, Z when `F` stores Z (falling back
/// from W), off without a buffer or when asked; Z asked with a W format is an error.
pub fn resolve<F: Codec>(asked: DepthMode, has_buffer: bool) -> Result<Resolved, Error> {
    let stores_w = F::INPUT == Input::W;
    let mode = match (asked, has_buffer) {
        (DepthMode::Off, _) | (_, false) => DepthMode::Off,
        (DepthMode::Z, true) if stores_w => return Err(Error::ZWithWFormat),
        (DepthMode::Z, true) => DepthMode::Z,
        (DepthMode::W, true) if stores_w => DepthMode::W,
        (DepthMode::W, true) => DepthMode::Z,
    };
    Ok(Resolved {
        mode,
        fell_back: asked == DepthMode::W && mode == DepthMode::Z,
    })
}

impl<R: WSpan> Rasterizer<R> {
    /// `n / (f - n)` of the state's depth range for the Z formats: computed when the range changes, not per primitive.
    fn zconst(&mut self) -> ZConst {
        match self.zc {
            Some((range, zc)) if range == self.state.range => zc,
            _ => {
                let zc = ZConst::new(&self.state.range);
                self.zc = Some((self.state.range, zc));
                zc
            }
        }
    }

    /// What a draw into a buffer of format `F` (or into none) does with the state's [`DepthMode`].
    pub fn resolve<F: Codec>(&self, has_buffer: bool) -> Result<Resolved, Error> {
        resolve::<F>(self.state.mode, has_buffer)
    }

    /// Draws one flat-coloured triangle into `target` and a depth buffer of any format (or none: depth off; the rows
    /// and columns are then the target's). The depth test runs before any colour work for the pixel (the Windows CE "Depth Buffering" docs): a
    /// passing pixel's colour is sent with its run. On an error nothing is written, except for a failing `target` ([`Error::Target`]).
    pub(crate) fn draw_packed<F: Codec, D>(
        &mut self,
        target: &mut D,
        mut depth: Option<&mut DepthBuffer<'_, F>>,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let res = self.resolve::<F>(depth.is_some())?;
        let (y0, height, width) = extent(&depth, target);
        let mut w = match self.prepare(v, (y0, height), false)? {
            Ok(w) => w,
            Err(stats) => return Ok(stats),
        };
        let (_, fm, fe) = split(self.state.range.far()).ok_or(Error::NonFinite)?;
        let far = (fm, fe);
        let frac = w.frac;
        let zc = self.zconst();
        let mut lin = (F::INPUT == Input::LinearZ)
            .then(|| Plane::solve(w.t_vertex.map(|t| linear_z60(&zc, t, frac)), &w.geom));
        let ctx = DepthCtx {
            far,
            zc,
            frac,
            t_lo: w.span.t_lo,
            t_hi: w.span.t_hi,
            bias: self.format_bias::<F>(
                &zc,
                &w.geom.p,
                &w.t_vertex,
                frac,
                (w.span.t_lo, w.span.t_hi),
            ),
            cmp: self.state.compare,
            write: self.state.depth_write,
        };
        let color = v[0].color();
        let mut stats = Stats::default();
        for j in w.geom.j0..=w.j1 {
            if let Some((lo, hi)) = w.row(width) {
                let n = (hi - lo) as usize;
                let off = lo as i64 - w.geom.i_ref;
                let t0 = w.t.at(off) as u64;
                let mut runs = Runs::new(target, lo, j, color);
                if let (Some(buf), true) = (depth.as_deref_mut(), res.mode != DepthMode::Off) {
                    let row = &mut buf.row_mut(j)[lo as usize..hi as usize];
                    let z0 = lin.map_or(0, |p| p.at(off));
                    let dz = lin.map_or(0, |p| p.sx);
                    let line = Line1 {
                        t0,
                        dt: w.t.sx,
                        z0,
                        dz,
                    };
                    codes::<F, R, Error>(&mut self.recip, &ctx, &line, n, |k, code| {
                        let px = &mut row[k];
                        match code {
                            Some(c) if ctx.test::<F>(px, c) => Ok(()),
                            _ => runs.fail(k),
                        }
                    })?;
                } else {
                    // depth off: every covered pixel in the depth range passes (the range clips, as for points and
                    // lines)
                    let mut t = t0;
                    for k in 0..n {
                        if t < ctx.t_lo || t > ctx.t_hi {
                            runs.fail(k)?;
                        }
                        t = t.wrapping_add(w.t.sx as u64);
                    }
                }
                runs.finish(n)?;
                stats.fragments += n as u32;
                stats.written += n as u32 - runs.fails;
            }
            w.next_row();
            if let Some(p) = &mut lin {
                p.next_row();
            }
        }
        Ok(stats)
    }

    /// The triangle's depth bias in `F`'s codes (feature `bias`): the Windows CE "Depth Buffering" docs' offset with `m` from the plane of the
    /// vertices' codes (see [`crate::RenderState::depth_bias`]).
    #[cfg(feature = "bias")]
    fn format_bias<F: Codec>(
        &self,
        zc: &ZConst,
        p: &[Sub; 3],
        t: &[i64; 3],
        frac: u32,
        range: (u64, u64),
    ) -> i32 {
        let st = &self.state;
        if st.slope_scale_depth_bias == 0.0 && st.depth_bias == 0.0 {
            return 0;
        }
        let (_, fm, fe) = split(st.range.far()).unwrap_or((false, 1, 0));
        // T is at most 2^61 here; t_max may saturate to u64::MAX: clamp in u64.
        let codes = t.map(|t| {
            let tc = (t.max(0) as u64).clamp(range.0, range.1.max(range.0));
            let q = match F::INPUT {
                Input::W => exact_u(tc, frac),
                Input::Z => zc.z60(tc, frac),
                Input::LinearZ => linear_z60(zc, tc as i64, frac).clamp(0, 1 << 60) as u64,
            };
            F::code(q, (fm, fe)) as f32
        });
        slope_bias(st, p, codes, F::MAX_CODE as f32)
    }
    #[cfg(not(feature = "bias"))]
    #[inline(always)]
    #[allow(clippy::extra_unused_type_parameters)] // the bias build's signature, so that callers need no `cfg`
    fn format_bias<F: Codec>(
        &self,
        _: &ZConst,
        _: &[Sub; 3],
        _: &[i64; 3],
        _: u32,
        _: (u64, u64),
    ) -> i32 {
        0
    }
}

/// Points, lines and wireframe triangles into any format (the rules: [`Rasterizer::draw_line`]).
impl<R: WSpan> Rasterizer<R> {
    /// [`Rasterizer::draw_point`] into a buffer of format `F` or none.
    pub(crate) fn point_any<F: Codec, D>(
        &mut self,
        target: &mut D,
        depth: Option<&mut DepthBuffer<'_, F>>,
        v: &impl VertexInput<Color = D::Color>,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let s = self.setup(core::array::from_ref(v))?;
        let z = linear_z60(&self.zconst(), s.t[0], s.frac);
        let line = Line1 {
            t0: s.t[0] as u64,
            dt: 0,
            z0: z,
            dz: 0,
        };
        let at = |_k: usize| (s.p[0].x >> 8, s.p[0].y >> 8);
        self.pixels::<F, D>(target, depth, &line, 1, at, 0, s.frac, v.color())
    }

    /// [`Rasterizer::draw_line`] into a buffer of format `F` or none.
    pub(crate) fn line_any<F: Codec, D>(
        &mut self,
        target: &mut D,
        depth: Option<&mut DepthBuffer<'_, F>>,
        v: &[impl VertexInput<Color = D::Color>; 2],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let s = self.setup(v)?;
        self.line_inner::<F, D>(
            target,
            depth,
            (s.p[0], s.p[1]),
            (s.t[0], s.t[1]),
            s.frac,
            0,
            v[0].color(),
        )
    }

    /// [`Rasterizer::draw_wireframe`] into a buffer of format `F` or none.
    pub(crate) fn wireframe_any<F: Codec, D>(
        &mut self,
        target: &mut D,
        mut depth: Option<&mut DepthBuffer<'_, F>>,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let s = self.setup(v)?;
        let [p0, p1, p2] = s.p;
        let area = (p1.x - p0.x) as i64 * (p2.y - p0.y) as i64
            - (p2.x - p0.x) as i64 * (p1.y - p0.y) as i64;
        if crate::setup::culls_area(self.state.cull, area) {
            return Ok(Stats {
                culled: 1,
                ..Stats::default()
            });
        }
        let range = (1u64 << s.frac, self.state.range.t_max(s.frac));
        let zc = self.zconst();
        let bias = self.format_bias::<F>(&zc, &s.p, &s.t, s.frac, range);
        let mut stats = Stats::default();
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            stats += self.line_inner::<F, D>(
                target,
                depth.as_deref_mut(),
                (s.p[a], s.p[b]),
                (s.t[a], s.t[b]),
                s.frac,
                bias,
                v[0].color(),
            )?;
        }
        Ok(stats)
    }

    #[allow(clippy::too_many_arguments)]
    fn line_inner<F: Codec, D>(
        &mut self,
        target: &mut D,
        depth: Option<&mut DepthBuffer<'_, F>>,
        (a, b): (Sub, Sub),
        (ta, tb): (i64, i64),
        frac: u32,
        bias: i32,
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let (dx, dy) = ((b.x - a.x) as i64, (b.y - a.y) as i64);
        if dx == 0 && dy == 0 {
            return Ok(Stats {
                culled: 1,
                ..Stats::default()
            });
        }
        let x_major = dx.abs() >= dy.abs();
        let major = |p: Sub| {
            if x_major {
                (p.x as i64, p.y as i64)
            } else {
                (p.y as i64, p.x as i64)
            }
        };
        let ((mut ua, mut va), (mut ub, mut vb)) = (major(a), major(b));
        let (mut ta, mut tb) = (ta, tb);
        if ua > ub {
            core::mem::swap(&mut ua, &mut ub);
            core::mem::swap(&mut va, &mut vb);
            core::mem::swap(&mut ta, &mut tb);
        }
        // major pixels i with 256 i + 128 in [ua, ub)
        let i0 = (ua - 128 + 255).div_euclid(256);
        let i1 = (ub - 128 + 255).div_euclid(256); // exclusive
        if i1 <= i0 {
            return Ok(Stats::default());
        }
        let n = (i1 - i0) as usize;
        let du = (ub - ua) as i128;
        let off = (256 * i0 + 128 - ua) as i128;
        let step = |v0: i64, v1: i64| {
            let d = v1 as i128 - v0 as i128;
            (
                (v0 as i128 + div_round(d * off, du)) as i64,
                div_round(d * 256, du) as i64,
            )
        };
        let (t0, dt) = step(ta, tb);
        let zc = self.zconst();
        let (z0, dz) = if F::INPUT == Input::LinearZ {
            step(linear_z60(&zc, ta, frac), linear_z60(&zc, tb, frac))
        } else {
            (0, 0)
        };
        let line = Line1 {
            t0: t0 as u64,
            dt,
            z0,
            dz,
        };
        let at = |k: usize| {
            let i = i0 + k as i64;
            // the minor coordinate at the centre, floor-divided into a pixel (|num| < 2^63: |du|, |dv| < 2^21)
            let vv = va + ((256 * i + 128 - ua) * (vb - va)).div_euclid(ub - ua);
            let j = vv.div_euclid(256);
            let (x, y) = if x_major { (i, j) } else { (j, i) };
            (
                x.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
                y.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
            )
        };
        self.pixels::<F, D>(target, depth, &line, n, at, bias, frac, color)
    }

    /// The shared pixel loop of points and lines: pixel `k` of `n` is at `at(k)`, its depth from `line`.
    #[allow(clippy::too_many_arguments)]
    fn pixels<F: Codec, D>(
        &mut self,
        target: &mut D,
        depth: Option<&mut DepthBuffer<'_, F>>,
        line: &Line1,
        n: usize,
        at: impl Fn(usize) -> (i32, i32),
        bias: i32,
        frac: u32,
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let res = self.resolve::<F>(depth.is_some())?;
        let (y0, height, width) = extent(&depth, target);
        let (_, fm, fe) = split(self.state.range.far()).ok_or(Error::NonFinite)?;
        let ctx = DepthCtx {
            far: (fm, fe),
            zc: self.zconst(),
            frac,
            t_lo: 1 << frac,
            t_hi: self.state.range.t_max(frac),
            bias,
            cmp: self.state.compare,
            write: self.state.depth_write,
        };
        let inside = |x: i32, y: i32| {
            x >= 0 && x < width as i32 && y >= y0 && (y as i64) < y0 as i64 + height as i64
        };
        let mut stats = Stats::default();
        let mut put = |x: i32, y: i32| -> Result<(), Error> {
            stats.written += 1;
            let r = Rectangle::new(Point::new(x, y), Size::new(1, 1));
            target.fill_solid(&r, color).map_err(|_| Error::Target)
        };
        let mut frags = 0u32;
        match depth {
            Some(buf) if res.mode != DepthMode::Off => {
                codes::<F, R, Error>(&mut self.recip, &ctx, line, n, |k, code| {
                    let (x, y) = at(k);
                    if !inside(x, y) {
                        return Ok(());
                    }
                    frags += 1;
                    let pass = match (code, buf.pixel_mut(x, y)) {
                        (Some(c), Some(px)) => ctx.test::<F>(px, c),
                        _ => false,
                    };
                    if pass {
                        put(x, y)?;
                    }
                    Ok(())
                })?;
            }
            _ => {
                // depth off: every pixel in the depth range passes
                let in_range = |t: u64| t >= ctx.t_lo && t <= ctx.t_hi;
                let mut t = line.t0;
                for k in 0..n {
                    let (x, y) = at(k);
                    if inside(x, y) {
                        frags += 1;
                        if in_range(t) {
                            put(x, y)?;
                        }
                    }
                    t = t.wrapping_add(line.dt as u64);
                }
            }
        }
        stats.fragments = frags;
        Ok(stats)
    }
}

/// The rows (first, count) and columns a draw covers: the buffer's, or the target's without one.
fn extent<F: Codec, D: DrawTarget>(
    depth: &Option<&mut DepthBuffer<'_, F>>,
    target: &D,
) -> (i32, u16, u16) {
    match depth {
        Some(d) => (d.y0(), d.height(), d.width()),
        None => {
            let b = target.bounding_box();
            let w = (b.top_left.x.max(0) as u32 + b.size.width).min(u16::MAX as u32);
            (
                b.top_left.y,
                b.size.height.min(u16::MAX as u32) as u16,
                w as u16,
            )
        }
    }
}

/// Per-draw constants of the depth path.
struct DepthCtx {
    far: (u32, i32),
    zc: ZConst,
    frac: u32,
    t_lo: u64,
    t_hi: u64,
    bias: i32,
    cmp: crate::Compare,
    write: bool,
}

impl DepthCtx {
    /// The depth test of one pixel's stored bytes against `code` (biased), writing on a pass when enabled.
    #[inline(always)]
    fn test<F: Codec>(&self, px: &mut F::Word, code: u32) -> bool {
        let c = biased::<F>(code, self.bias);
        let stored = crate::format::Storage::code(*px);
        let pass = if F::REVERSED {
            self.cmp.test(stored, c)
        } else {
            self.cmp.test(c, stored)
        };
        if pass && self.write {
            *px = crate::format::Storage::from_code(c);
        }
        pass
    }
}

/// `n` consecutive pixels along which `T = t0 + k dt` and the linear-Z value `z0 + k dz` (used by `LinearZ` only).
struct Line1 {
    t0: u64,
    dt: i64,
    z0: i64,
    dz: i64,
}

/// The codes of the pixels of `line`: `f(k, Some(code))` for those in the depth range, `f(k, None)` for the others.
#[inline(always)]
fn codes<F: Codec, R: WSpan, E>(
    recip: &mut R,
    ctx: &DepthCtx,
    line: &Line1,
    n: usize,
    mut f: impl FnMut(usize, Option<u32>) -> Result<(), E>,
) -> Result<(), E> {
    let in_range = |t: u64| t >= ctx.t_lo && t <= ctx.t_hi;
    match F::INPUT {
        Input::W => recip.walk(line.t0, line.dt, n, ctx.frac, ctx.t_lo, ctx.t_hi, |k, u| {
            f(k, u.map(|u| F::code(u, ctx.far)))
        }),
        Input::Z => {
            let mut t = line.t0;
            for k in 0..n {
                f(
                    k,
                    in_range(t).then(|| F::code(ctx.zc.z60(t, ctx.frac), ctx.far)),
                )?;
                t = t.wrapping_add(line.dt as u64);
            }
            Ok(())
        }
        Input::LinearZ => {
            let (mut t, mut z) = (line.t0, line.z0);
            for k in 0..n {
                let q = z.clamp(0, 1 << 60) as u64;
                f(k, in_range(t).then(|| F::code(q, ctx.far)))?;
                t = t.wrapping_add(line.dt as u64);
                z = z.wrapping_add(line.dz);
            }
            Ok(())
        }
    }
}

/// `code` moved `bias` codes away from the eye in depth order (towards smaller codes for reversed formats),
/// saturated to `[0, MAX_CODE]`.
#[inline(always)]
fn biased<F: Codec>(code: u32, bias: i32) -> u32 {
    if bias == 0 {
        return code;
    }
    let b = if F::REVERSED {
        -(bias as i64)
    } else {
        bias as i64
    };
    (code as i64 + b).clamp(0, F::MAX_CODE as i64) as u32
}

#[cfg(test)]
mod float_bits_tests {
    use super::float_bits;

    /// `float_bits(p, e2, 23)` is the f32 nearest to `p 2^e2` (f64 holds `p < 2^53` exactly, and its conversion to
    /// f32 rounds to nearest), with ties going up where f32 goes to even: every bit length of `p` from 1 to 53 (so
    /// the short `p` shifted left as well as the long one rounded), random and all-ones mantissas (whose rounding
    /// carries into the exponent), and exact ties.
    #[test]
    fn float_bits_is_f32_rounding_with_ties_up() {
        let mut s = 0x0123_4567_89AB_CDEFu64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for bits in 1..=53u32 {
            for k in 0..200 {
                let top = 1u64 << (bits - 1);
                let p = match k {
                    0 => (top << 1) - 1, // all ones
                    1 => top,
                    _ => top | (rnd() & (top - 1)),
                };
                let e2 = (rnd() % 120) as i32 - 60 - bits as i32;
                let v = p as f64 * 2f64.powi(e2);
                let sh = bits.saturating_sub(24);
                let tie = sh > 0 && p & ((1 << sh) - 1) == 1 << (sh - 1);
                let want = if tie {
                    // Ties up: the f32 above the halfway point.
                    ((p + (1 << (sh - 1))) as f64 * 2f64.powi(e2)) as f32
                } else {
                    v as f32
                };
                assert_eq!(float_bits(p, e2, 23), want.to_bits(), "p {p:#x} e2 {e2}");
            }
        }
        assert_eq!(float_bits(0, 5, 23), 0);
        // A tie: 2^24 + 1 has one bit too many and it is a half: up to 2^24 + 2 (f32 itself would go to even, 2^24).
        assert_eq!(float_bits((1 << 24) + 1, 0, 23), 16_777_218f32.to_bits());
        // A carry: 2^25 - 1 rounds up to 2^25, the next exponent with a zero mantissa.
        assert_eq!(float_bits((1 << 25) - 1, 0, 23), 33_554_432f32.to_bits());
    }
}

#[cfg(test)]
mod zconst_tests {
    use crate::state::ZConst;
    use crate::DepthRange;

    /// `rz60` is `(t - 1) n / (f - n) 2^60` within the constant's truncation (`2^-31` relative) and the final shift's
    /// floor, for `T = t 2^frac` with a small `frac` (a triangle with a vertex very near the eye, `t` up to `2^40`),
    /// where the product is shifted left (`s + frac < 60`: a narrow range `[10, 11]`, `s = 29`), and a large one.
    #[test]
    fn rz60_is_the_reversed_z_for_any_fraction_bits() {
        let zc = ZConst::new(&DepthRange::new(10.0, 11.0).unwrap());
        for frac in [20u32, 28, 40, 60] {
            for k in 0..=100u64 {
                // t from 1 (the far plane) to 1.1 (the near plane), exactly representable in `frac` bits
                let t = (1u64 << frac) + ((k << frac) / 1000);
                let exact =
                    (t - (1 << frac)) as f64 / (1u64 << frac) as f64 * 10.0 * (1u64 << 60) as f64;
                let got = zc.rz60(t, frac) as f64;
                // Derived: `k` truncated (below `2^-31` relative), the shift's floor (one unit), and the two f64
                // roundings of values below `2^61` (`2^-52` relative each).
                assert!(
                    (got - exact).abs() <= exact * (2f64.powi(-31) + 2f64.powi(-51)) + 1.0,
                    "frac {frac} t {t}: {got} vs {exact}"
                );
            }
        }
    }

    /// The linear-Z value `(W - n) / (f - n)` at a vertex beyond the far plane (`W = 25` in `[10, 20]`: 1.5, so
    /// `rz60` is negative there and must not be clamped to 0), one inside (`W = 15`: 0.5) and one in front of the
    /// near plane (`W = 5`: -0.5, kept negative), in Q0.60.
    #[test]
    fn linear_z_beyond_the_far_plane() {
        let zc = ZConst::new(&DepthRange::new(10.0, 20.0).unwrap());
        let frac = 40;
        for (t, want) in [(0.8f64, 1.5f64), (20.0 / 15.0, 0.5), (4.0, -0.5)] {
            let tt = (t * (1u64 << frac) as f64) as i64;
            let got = super::linear_z60(&zc, tt, frac) as f64 / (1u64 << 60) as f64;
            // Derived: `k`'s truncation (`2^-31` of `|rz| <= 3`) times `u <= 1.25` with `|rz| u <= 0.75`, `u`'s
            // rounding (`2^-62` relative) and the floors (units of `2^-60`): below `2^-30`.
            assert!(
                (got - want).abs() < 2f64.powi(-30),
                "t {t}: {got} vs {want}"
            );
        }
    }
}

#[cfg(test)]
pub(crate) mod code_tests {
    use crate::format::{DepthFormat, Storage, W16F, W32F};
    use crate::raster::Rasterizer;
    use crate::recip::Fast;
    use crate::setup::Vertex;
    use crate::DepthBuffer;
    use crate::{Codec, RenderState};
    use embedded_graphics_core::pixelcolor::BinaryColor;
    use embedded_graphics_core::prelude::{DrawTarget, OriginDimensions, Pixel, Size};
    use std::vec;

    /// A 32 x 32 target that takes every pixel and keeps none (the draw tests read the depth buffer).
    pub(crate) struct Sink;
    impl OriginDimensions for Sink {
        fn size(&self) -> Size {
            Size::new(32, 32)
        }
    }
    impl DrawTarget for Sink {
        type Color = BinaryColor;
        type Error = core::convert::Infallible;
        fn draw_iter<I: IntoIterator<Item = Pixel<BinaryColor>>>(
            &mut self,
            _: I,
        ) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    /// A triangle facing the eye at `W = 16` in `[1, 64]` stores `W / W_far = 1/4`, a value every W format holds
    /// exactly, so each covered pixel's code decodes to exactly 0.25 and the clear code stays elsewhere. This test
    /// runs in every build, including one without the `bias` feature, where no offset may reach the code (the
    /// mutation run judges a build without `bias` too: the all-features build never compiles that path).
    #[test]
    fn a_flat_triangle_stores_its_exact_w() {
        fn check<F: Codec + DepthFormat>() {
            let state = RenderState::new(1.0, 64.0).unwrap();
            let mut words = vec![F::Word::default(); 32 * 32];
            let mut buf = DepthBuffer::<F>::new_format(&mut words, 32, 32).unwrap();
            buf.clear_for(&state.range);
            let on = BinaryColor::On;
            let t = [
                Vertex::new(1.0, 1.0, 16.0, on),
                Vertex::new(30.0, 2.0, 16.0, on),
                Vertex::new(3.0, 29.0, 16.0, on),
            ];
            let stats = Rasterizer::<Fast>::new(state)
                .draw(&mut Sink, &mut buf, &t)
                .unwrap();
            let mut n = 0;
            for c in words.iter().map(|w| w.code()) {
                let v = F::fraction(c, 1.0, 64.0);
                if v != 1.0 {
                    assert_eq!(v, 0.25, "{}: code {c}", F::NAME);
                    n += 1;
                }
            }
            assert!(
                n > 300 && n == stats.written as usize,
                "{}: {n} pixels",
                F::NAME
            );
        }
        check::<W16F>();
        check::<W32F>();
    }
}
