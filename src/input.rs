//! Vertex input: the f32 [`Vertex`] and the fixed-point [`FixedVertex`], behind one sealed trait, [`VertexInput`].
//!
//! A core without an FPU can feed the rasterizer without a single float operation: `x` and `y` as
//! [`I24F8`] (the 16.8 snap grid itself, so snapping is a range check), and `1/W` as any 32-bit unsigned
//! [`fixed`] type, the integer/fraction split chosen for the scene's depth range (`U1F31` resolves `1/W` to
//! 2^-31, which keeps 17 significant bits at `W = 10^4`; a scene with `W < 1` needs integer bits for `1/W > 1`).
//! The depth arithmetic is exact on either input (the product `rhw * W_far` is formed from the mantissas), so a
//! fixed-point vertex whose values equal an f32 vertex's gives the same pixels and the same codes.

use crate::edge::Sub;
use crate::fixed::split;
use crate::setup::{rows_of, Vertex, GUARD_BAND, SUBPIXEL_BITS};
use crate::Error;
pub use fixed::traits::Fixed;
pub use fixed::types::{I24F8, U16F16, U1F31, U8F24};

mod sealed {
    pub trait Sealed {}
}

/// A vertex the rasterizer takes: [`Vertex`] (f32) or [`FixedVertex`] (fixed point). Sealed: the methods are the
/// crate's exact conversions, not an extension point.
pub trait VertexInput: sealed::Sealed + Copy {
    /// The colour type.
    type Color: Copy;
    /// `x` and `y` on the 16.8 grid (round to nearest, ties to even), checked against [`GUARD_BAND`].
    #[doc(hidden)]
    fn snapped(&self) -> Result<(i32, i32), Error>;
    /// [`VertexInput::snapped`], and whether `x` and `y` lie on the 16.8 snap grid (then the snapped vertex is the
    /// vertex as given).
    #[doc(hidden)]
    fn snapped_exact(&self) -> Result<(i32, i32, bool), Error>;
    /// `x - ox` and `y - oy` on the depth grid of `bits` fraction bits (round to nearest, ties to even; see
    /// `crate::setup::depth_grid_bits`): the positions the depth plane goes through. Only called after
    /// [`VertexInput::snapped`] accepted the vertex, with an origin and `bits` that keep the results below `2^31`.
    #[doc(hidden)]
    fn depth_xy(&self, bits: u32, ox: i32, oy: i32) -> (i32, i32);
    /// `rhw` as an exact `(mantissa, exponent)` pair, `rhw = mantissa * 2^exponent`, mantissa below 2^32.
    /// `Err(NonFinite)` for NaN and infinities (and a non-finite `z`), `Err(RhwNotPositive)` for `rhw <= 0`.
    #[doc(hidden)]
    fn rhw_exact(&self) -> Result<(u32, i32), Error>;
    /// The vertex colour.
    fn color(&self) -> Self::Color;
}

/// [`snap_exact`]'s value alone (the unit tests' name for it).
#[cfg(test)]
fn snap(v: f32) -> Result<i32, Error> {
    snap_exact(v).map(|(r, _)| r)
}

/// Whether this core rounds f32 in hardware (the Cortex-M4F's FPU; the hosts' SSE or NEON): [`snap_exact`] then
/// rounds with two additions instead of integer operations on the bits. The same results either way (both are
/// round-to-nearest-even of the same exact product; a unit test compares them), so frames stay bit-identical across
/// cores. An ARM target with the hard-float ABI has an FPU; the Cortex-M0 and RV32IMAC have none.
pub(crate) const HARD_FLOAT: bool = cfg!(any(
    target_abi = "eabihf",
    target_arch = "x86_64",
    target_arch = "aarch64",
    all(target_arch = "riscv32", target_feature = "f")
));

/// `round(v * 256)`, ties to even, and whether it was exact, as [`snap_bits`] (its range checks and results), rounded
/// by the FPU where the core has one ([`HARD_FLOAT`]): `v * 256` is exact (a power-of-two scale of `|v| < 2^12`), and
/// for `|s| < 2^22` the sum `s + 1.5 2^23` lies in `[2^23, 2^24)`, where the f32 spacing is 1, so IEEE 754's default
/// rounding of that sum rounds `s` to the nearest integer, ties to even; subtracting `1.5 2^23` again is exact. On the
/// Cortex-M4F that is six FPU instructions and one conversion, against some 35 integer ones.
#[inline]
fn snap_exact(v: f32) -> Result<(i32, bool), Error> {
    if !HARD_FLOAT {
        return snap_bits(v);
    }
    let mag = v.to_bits() & 0x7fff_ffff;
    if mag >= 0x7f80_0000 {
        return Err(Error::NonFinite);
    }
    if mag >= 0x4580_0000 {
        return Err(Error::OutOfGuardBand);
    }
    Ok(snap_fpu(v))
}

/// The doubled signed area of the triangle `v` (screen `(x, y)`, y down; positive is clockwise on the display) after
/// snapping, in units of `2^-16` px², exactly: the area whose sign the rasterizer culls by. `None` where a coordinate
/// does not snap (NaN, infinite, or beyond the guard band). Snapped coordinates are below `2^20` units, so their
/// differences are below `2^21` and each product below `2^42` ([`crate::fast::smul_wide`]: no `__aeabi_lmul` call on
/// the Cortex-M0).
#[inline(never)] // the rare fallback of the culls' filters: one copy
pub(crate) fn snapped_area(v: [(f32, f32); 3]) -> Option<i64> {
    let mut p = [(0i32, 0i32); 3];
    for (q, &(x, y)) in p.iter_mut().zip(v.iter()) {
        *q = (snap_exact(x).ok()?.0, snap_exact(y).ok()?.0);
    }
    let (ux, uy) = (p[1].0 - p[0].0, p[1].1 - p[0].1);
    let (vx, vy) = (p[2].0 - p[0].0, p[2].1 - p[0].1);
    Some(crate::fast::smul_wide(ux, vy) - crate::fast::smul_wide(vx, uy))
}

/// `v * 256` truncated toward zero, from the bits, for a finite `|v| < 2^12` (a cheaper neighbour of the snap for
/// filters: within one unit of it, or of `v * 256`).
#[inline(always)]
pub(crate) fn fixed_trunc(v: f32) -> i32 {
    let b = v.to_bits();
    let mag = b & 0x7fff_ffff;
    let s = 142i32 - (mag >> 23) as i32; // v * 256 = m 2^-s, s >= 4 below 2^12
    let m = (mag & 0x7f_ffff) | 0x80_0000;
    // s >= 24: below 1 (zero and subnormals too); `s < 4` (outside the domain) shifts by 0, a value but no panic.
    let r = if s >= 24 { 0 } else { (m >> s.max(0)) as i32 };
    if b >> 31 != 0 {
        -r
    } else {
        r
    }
}

/// [`snap_exact`]'s FPU rounding, for a finite `|v| < 2^12`.
#[inline(always)]
fn snap_fpu(v: f32) -> (i32, bool) {
    const ROUND: f32 = 12_582_912.0; // 1.5 2^23
    let s = v * 256.0;
    let r = (s + ROUND) - ROUND;
    (r as i32, r == s)
}

/// `round(v * 256)`, ties to even, for `|v| < GUARD_BAND = 2^12` (else `OutOfGuardBand`; NaN and infinities
/// `NonFinite`), in 32-bit integer operations on the bits: `|v| < 2^12` means a biased exponent of at most 138, so
/// `v * 256 = m 2^-s` with the 24-bit mantissa `m` and `s = 142 - exp >= 4`: a right shift with round-to-nearest-even
/// of a 32-bit value (no 64-bit shift, which is a library call on the Cortex-M0). The same value as
/// `fixed::to_fixed(v, 8, 12)` (tested on every bit pattern class in the unit tests).
/// Also says whether the snap was exact (`v` on the 1/256 grid: no remainder), which costs one shift.
#[inline(always)]
fn snap_bits(v: f32) -> Result<(i32, bool), Error> {
    let w = snap_packed(v);
    match (w >> 32) as u32 {
        0 => Ok((w as u32 as i32, false)),
        1 => Ok((w as u32 as i32, true)),
        SNAP_NON_FINITE => Err(Error::NonFinite),
        _ => Err(Error::OutOfGuardBand),
    }
}

/// [`snap_bits`] of `x` and `y`, and whether both were exact, their high words tested together (the flags are 0 and
/// 1, the errors 2 and 3): one branch where both snap, instead of a match on each `Result`. `x`'s error first, as
/// `snap_exact(x)?` then `snap_exact(y)?` report them. Measured on the M0's W3 (single-scene build, commit 7acade5):
/// 6,782.5 -> 6,714.9 instructions a triangle.
#[inline(always)]
fn snap_pair(x: f32, y: f32) -> Result<(i32, i32, bool), Error> {
    let (wx, wy) = (snap_packed(x), snap_packed(y));
    let (hx, hy) = ((wx >> 32) as u32, (wy >> 32) as u32);
    if hx | hy < 2 {
        return Ok((wx as u32 as i32, wy as u32 as i32, hx & hy != 0));
    }
    let h = if hx >= 2 { hx } else { hy };
    Err(if h == SNAP_NON_FINITE {
        Error::NonFinite
    } else {
        Error::OutOfGuardBand
    })
}

/// [`snap_packed`]'s high word for NaN and infinities (`OutOfGuardBand` is 3).
const SNAP_NON_FINITE: u32 = 2;

/// [`snap_bits`] out of line, its result in one `u64` (two registers, where a `Result` of a pair is returned through
/// memory on the Cortex-M0): the value's bits in the low word; the high word 1 when exact, 0 when not, 2 for NaN and
/// infinities, 3 beyond the guard band. Measured on the M0's W3: 34 instructions a call, against 48 when it rounded
/// by `(m + 2^(s-1) - 1 + (q & 1)) >> s` and tested values below `2^-10` in two branches, and 58 when it returned the
/// `Result` (stored through a pointer) and tested the remainder with a mask. The same bits as those on every `f32`
/// (compared over all `2^32` patterns when it changed; the unit tests compare it with the FPU's rounding).
// Out of line: one copy instead of one per coordinate (flash), for a few instructions per vertex.
#[inline(never)]
fn snap_packed(v: f32) -> u64 {
    const _: () = assert!(GUARD_BAND == 1 << 12 && SUBPIXEL_BITS == 8);
    let bits = v.to_bits();
    let mag = bits & 0x7fff_ffff;
    if mag >= 0x4580_0000 {
        // 4096.0 and above; infinities and NaN from 0x7f80_0000.
        return if mag >= 0x7f80_0000 {
            (SNAP_NON_FINITE as u64) << 32
        } else {
            3 << 32
        };
    }
    let exp = mag >> 23;
    if exp < 117 {
        // Below 2^-10 (`v * 256 < 1/4`), zero and subnormals too: rounds to 0, exactly only for zero.
        return u64::from(mag == 0) << 32;
    }
    let m = (mag & 0x7f_ffff) | 0x80_0000;
    // v * 256 = m 2^-s with 4 <= s <= 25. The remainder's `s` bits at the top of a word, and round half to even
    // without branches: the quotient goes up when the remainder is above half (`rem > 2^31`, whatever `q & 1`), or is
    // half and `q` odd (`2^31 | 1`); a remainder below half stays below `2^31` with the low bit set. Exact when no
    // remainder.
    let s = 142 - exp;
    let (q, rem) = (m >> s, m << (32 - s));
    let r = q + u32::from((rem | (q & 1)) > 0x8000_0000);
    let exact = rem == 0;
    let r = if bits >> 31 != 0 {
        (r as i32).wrapping_neg()
    } else {
        r as i32
    };
    r as u32 as u64 | u64::from(exact) << 32
}

/// `round(v * 2^bits)`, ties to even, for a finite `|v| < GUARD_BAND` (checked by [`snap_exact`] first) and `bits <= 31`:
/// `v * 2^bits = m 2^(exp - 150 + bits)` with the 24-bit mantissa `m`; a left shift (exact, below `2^43`) where that
/// exponent is not negative, else a rounded right shift as in [`snap_exact`].
#[inline(always)]
fn depth_grid(v: f32, bits: u32) -> i64 {
    const _: () = assert!(GUARD_BAND == 1 << 12);
    let b = v.to_bits();
    let mag = b & 0x7fff_ffff;
    let exp = (mag >> 23) as i32;
    if exp == 0 {
        return 0; // zero or subnormal: far below half a grid step
    }
    let m = (mag & 0x7f_ffff) | 0x80_0000;
    let sh = exp + bits as i32 - 150;
    let r = if sh >= 0 {
        (m as i64) << sh.min(19)
    } else {
        let s = (-sh) as u32;
        if s >= 26 {
            0
        } else {
            ((m + (1 << (s - 1)) - 1 + ((m >> s) & 1)) >> s) as i64
        }
    };
    if b >> 31 != 0 {
        -r
    } else {
        r
    }
}

/// A vertex's position on the depth grid of `bits` fraction bits ([`depth_grid`]) relative to the pixel `(ox, oy)`:
/// `x` in the low word, `y` in the high one. Out of line, one call a vertex (flash), its pair in one `u64` (two
/// registers, where a pair of `i32` is returned through memory on the 32-bit ARM cores).
#[inline(never)]
fn depth_pair(x: f32, y: f32, bits: u32, ox: i32, oy: i32) -> u64 {
    let rel = |v: f32, o: i32| {
        (depth_grid(v, bits) - crate::fast::shl64(o as i64 as u64, bits) as i64) as i32
    };
    rel(x, ox) as u32 as u64 | (rel(y, oy) as u32 as u64) << 32
}

impl<C> sealed::Sealed for Vertex<C> {}
impl<C: Copy> VertexInput for Vertex<C> {
    type Color = C;
    #[inline]
    fn snapped(&self) -> Result<(i32, i32), Error> {
        Ok((snap_exact(self.x)?.0, snap_exact(self.y)?.0))
    }
    #[inline]
    fn snapped_exact(&self) -> Result<(i32, i32, bool), Error> {
        if !HARD_FLOAT {
            return snap_pair(self.x, self.y);
        }
        let ((x, ex), (y, ey)) = (snap_exact(self.x)?, snap_exact(self.y)?);
        Ok((x, y, ex & ey))
    }
    #[inline]
    fn depth_xy(&self, bits: u32, ox: i32, oy: i32) -> (i32, i32) {
        let p = depth_pair(self.x, self.y, bits, ox, oy);
        (p as i32, (p >> 32) as i32)
    }
    #[inline]
    fn rhw_exact(&self) -> Result<(u32, i32), Error> {
        if !self.z.is_finite() {
            return Err(Error::NonFinite);
        }
        let (neg, m, e) = split(self.rhw).ok_or(Error::NonFinite)?;
        if neg || m == 0 {
            return Err(Error::RhwNotPositive);
        }
        Ok((m, e))
    }
    #[inline]
    fn color(&self) -> C {
        self.color
    }
}

/// A screen-space vertex in fixed point: `x`, `y` in pixels on the 16.8 snap grid (pixel centres at `i + 0.5`),
/// `rhw = 1/W` in the unsigned 32-bit fixed type `R` (default [`U1F31`], for `W > 0.5`). Draws exactly like the
/// [`Vertex`] with the same values.
///
/// Ranges, checked at the draw: `|x|, |y| <` [`GUARD_BAND`] (else [`Error::OutOfGuardBand`]), `rhw > 0` (else
/// [`Error::RhwNotPositive`]), `rhw * W_far` below [`crate::MAX_T`] (else [`Error::DepthRange`]).
///
/// ```
/// use embedded_graphics_core::pixelcolor::Rgb565;
/// use embedded_graphics_core::prelude::*;
/// use wraster::input::{I24F8, U1F31};
/// use wraster::{DepthStore, FixedVertex, Rasterizer, RenderState, Vertex};
///
/// # struct Screen;
/// # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(32, 16) } }
/// # impl DrawTarget for Screen {
/// #     type Color = Rgb565; type Error = core::convert::Infallible;
/// #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
/// # }
/// // x, y on the 16.8 grid and 1/W as integers: a core without an FPU never touches a float.
/// let v = |x: i32, y: i32, rhw_bits: u32| FixedVertex {
///     x: I24F8::from_bits(x << 8 | 128), // pixel centre x + 0.5
///     y: I24F8::from_bits(y << 8 | 128),
///     rhw: U1F31::from_bits(rhw_bits), // 1/W = bits / 2^31
///     color: Rgb565::RED,
/// };
/// let tri = [v(1, 1, 1 << 26), v(30, 4, 1 << 22), v(6, 14, 1 << 24)]; // W = 32, 512, 128
/// let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0)?);
/// let mut depth = DepthStore::<32, 16>::new();
/// let fixed = r.draw(&mut Screen, &mut depth.view(), &tri)?;
///
/// // The f32 twin (the same values) draws the same pixels with the same codes.
/// let mut twin = DepthStore::<32, 16>::new();
/// let f = tri.map(|q| Vertex::new(q.x.to_num(), q.y.to_num(), 1.0 / q.rhw.to_num::<f32>(), q.color));
/// assert_eq!(r.draw(&mut Screen, &mut twin.view(), &f)?, fixed);
/// assert_eq!(depth.view().data(), twin.view().data());
/// assert!(fixed.written > 100);
/// # Ok::<(), wraster::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedVertex<C, R = U1F31> {
    /// Pixels, right.
    pub x: I24F8,
    /// Pixels, down.
    pub y: I24F8,
    /// `1 / W`.
    pub rhw: R,
    /// Colour.
    pub color: C,
}

impl<C, R> sealed::Sealed for FixedVertex<C, R> {}
impl<C: Copy, R: Fixed<Bits = u32>> VertexInput for FixedVertex<C, R> {
    type Color = C;
    #[inline]
    fn snapped(&self) -> Result<(i32, i32), Error> {
        let lim = GUARD_BAND << SUBPIXEL_BITS;
        let (x, y) = (self.x.to_bits(), self.y.to_bits());
        // The f32 path rejects |v| >= GUARD_BAND; the grid values are exact, so the same test.
        if x <= -lim || x >= lim || y <= -lim || y >= lim {
            return Err(Error::OutOfGuardBand);
        }
        Ok((x, y))
    }
    #[inline]
    fn snapped_exact(&self) -> Result<(i32, i32, bool), Error> {
        self.snapped().map(|(x, y)| (x, y, true))
    }
    #[inline]
    fn depth_xy(&self, bits: u32, ox: i32, oy: i32) -> (i32, i32) {
        // On the snap grid, which the depth grid refines (bits >= 8): exact.
        let up = bits - SUBPIXEL_BITS;
        (
            ((self.x.to_bits() as i64 - ((ox as i64) << SUBPIXEL_BITS)) << up) as i32,
            ((self.y.to_bits() as i64 - ((oy as i64) << SUBPIXEL_BITS)) << up) as i32,
        )
    }
    #[inline]
    fn rhw_exact(&self) -> Result<(u32, i32), Error> {
        match self.rhw.to_bits() {
            0 => Err(Error::RhwNotPositive),
            m => Ok((m, -(R::FRAC_NBITS as i32))),
        }
    }
    #[inline]
    fn color(&self) -> C {
        self.color
    }
}

/// The frame rows `(first, last)` a triangle can cover (inclusive; empty when `first > last`), after snapping:
/// for binning triangles into bands without setting them up. Errors as [`crate::Rasterizer::draw`] for x and y.
pub fn row_range<V: VertexInput>(v: &[V; 3]) -> Result<(i32, i32), Error> {
    let mut p = [Sub { x: 0, y: 0 }; 3];
    for (q, v) in p.iter_mut().zip(v) {
        let (x, y) = v.snapped()?;
        *q = Sub { x, y };
    }
    Ok(rows_of(&p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every exponent with mantissas at both ends, the middle and one off each, both signs; then `random` xorshift32
    /// bit patterns from `seed`, each also masked to mostly fall inside the guard band.
    fn each_bit_class(random: usize, seed: u32, mut check: impl FnMut(f32)) {
        for exp in 0..=255u32 {
            for frac in [
                0, 1, 2, 3, 0x40_0000, 0x40_0001, 0x3f_ffff, 0x7f_ffff, 0x7f_fffe, 0x7f_ff00,
            ] {
                for sign in [0, 1u32 << 31] {
                    check(f32::from_bits(sign | exp << 23 | frac));
                }
            }
        }
        let mut s = seed;
        for _ in 0..random {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            check(f32::from_bits(s));
            check(f32::from_bits(s & 0x45ff_ffff));
        }
    }

    /// The cores without an FPU snap a vertex with [`snap_pair`]: the values, the joint exactness flag and the
    /// first error as the two snaps one after the other give them, on every pair of a set of values that covers each
    /// outcome (exact, inexact, beyond the guard band, NaN and infinities, both signs).
    #[test]
    fn a_pair_snaps_as_its_two_coordinates() {
        let mut values = std::vec::Vec::new();
        each_bit_class(2_000, 0x1234_5679, |v| values.push(v));
        values.extend([
            0.5f32,
            1.0 / 256.0,
            3.0 / 512.0,
            4095.99,
            -4096.0,
            4096.0,
            f32::NAN,
            f32::INFINITY,
        ]);
        for &x in &values {
            for &y in values.iter().step_by(7) {
                let want = snap_exact(x)
                    .and_then(|(sx, ex)| snap_exact(y).map(|(sy, ey)| (sx, sy, ex & ey)));
                assert_eq!(snap_pair(x, y), want, "{x:e} {y:e}");
            }
        }
    }

    /// The 32-bit snap equals the general exact conversion (`to_fixed`, 64-bit) on every exponent, on ties (half a
    /// sub-pixel, odd and even), at the guard band, on subnormals, zeros, NaN and infinities, and on random bits.
    #[test]
    fn snap_equals_the_exact_conversion() {
        let reference = |v: f32| match crate::fixed::to_fixed(v, SUBPIXEL_BITS as i32, 12) {
            Ok(s) => Ok(s as i32),
            Err(false) => Err(Error::NonFinite),
            Err(true) => Err(Error::OutOfGuardBand),
        };
        let check = |v: f32| assert_eq!(snap(v), reference(v), "{v:e} ({:#x})", v.to_bits());
        each_bit_class(1_000_000, 0x9E37_79B9, check);
        for k in -8192i32..=8192 {
            // every half sub-pixel: the ties
            check(k as f32 / 512.0);
            check(k as f32 / 512.0 + 4000.0 * k.signum() as f32);
        }
        for v in [
            4096.0,
            -4096.0,
            4095.999,
            -4095.999,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ] {
            check(v);
        }
    }

    /// `fixed_trunc` is `v * 256` truncated toward zero on its domain (finite, `|v| < 2^12`): every bit class there,
    /// and every sub-pixel boundary and its neighbours.
    #[test]
    fn fixed_trunc_truncates() {
        let check = |v: f32| {
            if v.is_finite() && v.abs() < 4096.0 {
                assert_eq!(fixed_trunc(v), (v as f64 * 256.0).trunc() as i32, "{v:e}");
            }
        };
        each_bit_class(1_000_000, 0x1234_5678, check);
        for k in -(1i32 << 20)..(1 << 20) {
            let t = k as f32 / 256.0;
            check(t);
            check(f32::from_bits(t.to_bits() + 1));
            check(f32::from_bits(t.to_bits().wrapping_sub(1)));
        }
    }

    /// The FPU's rounding ([`snap_exact`] on this host) and the integer one on the bits ([`snap_bits`], the cores
    /// without an FPU) agree on the value, the exactness flag and the error, on every bit class, every tie of the
    /// snap grid and its neighbours, and a stride through every f32 bit pattern: the frames are the same on every core.
    #[test]
    fn fpu_and_integer_snaps_agree() {
        const { assert!(HARD_FLOAT, "the host takes the FPU path") };
        let check = |v: f32| assert_eq!(snap_exact(v), snap_bits(v), "{v:e} ({:#x})", v.to_bits());
        each_bit_class(1_000_000, 0x7CC1_B727, check);
        for k in -(1i32 << 21)..(1 << 21) {
            let t = k as f32 / 512.0; // every half sub-pixel below 2^12: the ties, then their neighbours
            check(t);
            check(f32::from_bits(t.to_bits() + 1));
            check(f32::from_bits(t.to_bits().wrapping_sub(1)));
        }
        for b in (0..=u32::MAX).step_by(4099) {
            check(f32::from_bits(b));
        }
    }

    /// The depth grid equals the general exact conversion at every width it takes (17 to 29 fraction bits) wherever
    /// `snap` accepts the value (every exponent, the grid's ties, random bits), a value on the 1/256 grid lands on
    /// `snap << (bits - 8)`, and `snap_exact` says exactly when the snap is exact.
    #[test]
    fn depth_grid_equals_the_exact_conversion() {
        let check = |v: f32| {
            if let Ok(sn) = snap(v) {
                for bits in 17..=29 {
                    let want = crate::fixed::to_fixed(v, bits, 12).unwrap();
                    assert_eq!(
                        depth_grid(v, bits as u32),
                        want,
                        "{v:e} ({:#x}) {bits}",
                        v.to_bits()
                    );
                }
                // v * 256 is exact in f64 (an f32 times a power of two).
                let exact = v as f64 * 256.0 == sn as f64;
                assert_eq!(snap_exact(v).unwrap().1, exact, "{v:e}");
            }
        };
        each_bit_class(200_000, 0x2545_F491, check);
        for k in -(1i32 << 16)..(1 << 16) {
            check(k as f32 / (1 << 19) as f32); // ties of the 18-bit grid near 0
            check(k as f32 / (1 << 24) as f32 + 0.25); // and of finer grids
            check(k as f32 / 256.0); // the snap grid
        }
    }
}
