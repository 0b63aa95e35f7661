//! The mesh vertex transform in integer arithmetic, for cores without an FPU: no float operation per vertex (the
//! Cortex-M0's soft-float multiply alone calls a 64-bit multiply, about 100 instructions; a vertex took about 5,600),
//! and the same bits on every core.
//!
//! **Formats** (chosen once per frame, block floating point). The positions share one exponent `P`: every coordinate
//! is below `2^P` and is held as `round(p 2^(30 - P))`, an `i32` of at most 31 bits (exact for any coordinate within
//! `2^7` of the largest: an f32 has 24 bits). Each output row (the viewport map folded into the matrix: `X' = sx X +
//! ox W`, `Y' = -sy Y + oy W`, and `W`) has its own exponent `e`: its three linear entries, held as `round(a
//! 2^(30 - e))`, are below `2^30`, and its translation, held as `round(t 2^(60 - P - e))`, below `2^60`. A row's value
//! is then `sum_j A_j P_j + T` exactly, in `i64` (below `3 2^60 + 2^60 = 2^62`), in units of `2^(P + e - 60)`. The
//! scales change per frame with the mesh and the matrix, so the values are raw integers beside their exponents rather
//! than the `fixed` crate's types, whose fraction bits are fixed at compile time.
//!
//! **Projection.** With `W` at least `W_near` (else the vertex is marked for clipping, as the f32 path marks it),
//! `rhw = 1/W` and `x = X'/W`, `y = Y'/W` come from one reciprocal of `W`'s top 32 bits (the fast tier's,
//! `2^-27.9`) and one 32 x 32 -> 64 product each, rounded once to f32 (to nearest, even). A vertex whose `x` or `y`
//! lies beyond the clip guard band (`4000` px) is marked for clipping.
//!
//! **Error** against exact arithmetic on the given f32 positions and matrix: the viewport folded in f32 (two products
//! and a sum per entry, `3 2^-24` of the larger term, once per frame); the positions' and entries' roundings to
//! 31 bits (`2^-31` of the largest term each); the reciprocal `2^-27.9`, `W`'s and `X'`'s top 32 bits `2^-31` each;
//! the final f32 rounding `2^-24`. A screen position is within about `|x_px| 2^-22` px (`8e-5` px at 320 px) and `rhw`
//! within `2^-23.8` relative: inside the f32 path's own bound (`crate::clip::Planes`), which the ray-caster tests
//! (`host-tests/tests/mesh.rs`) allow for.

use crate::clip::{Planes, CLIP_BAND};
use crate::fast::{bits64, clz32, fresh61, mul_wide, smul_wide, top32, Chord};
use crate::fixed::{round_shift, split};
use crate::projection::Mat4;
use crate::Error;

/// A transformed vertex: screen `x`, `y` and `rhw` when it is in front of the near plane and inside the guard band;
/// `rhw == 0` marks the others (the triangles using them are clipped from their positions). 12 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Projected {
    /// Pixels, right.
    pub x: f32,
    /// Pixels, down.
    pub y: f32,
    /// `1 / W`, or 0 for a vertex that needs clipping.
    pub rhw: f32,
}

/// One output row: `A_j` for the three coordinates, `T`, and the row's exponent `e`.
#[derive(Clone, Copy, Debug)]
struct Row {
    a: [i32; 3],
    t: i64,
    e: i32,
}

/// A frame's integer transform: the three rows (`X'`, `Y'`, `W`), the positions' exponent, and `W_near` in `W`'s
/// units.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntTransform {
    rows: [Row; 3],
    p: i32,
    /// The smallest `W` (in its row's units) at or above `W_near`: `ceil(W_near / u_W)`, saturated.
    near: i64,
}

/// `round(v 2^s)` as a signed `i64` for `|v 2^s| <= 2^62` (the callers' bounds), from an f32's exact split.
fn scaled(v: f32, s: i32) -> i64 {
    let (neg, m, e) = split(v).unwrap_or((false, 0, 0));
    let r = round_shift(m as u64, e + s) as i64;
    if neg {
        -r
    } else {
        r
    }
}

/// The exponent `b` with `|v| < 2^b` for a finite f32 (`i32::MIN` for 0): its mantissa's bits above its exponent.
fn magnitude(v: f32) -> i32 {
    match split(v) {
        Some((_, m, e)) if m != 0 => e + bits64(m as u64) as i32, // `bits64`: no `leading_zeros` library call
        _ => i32::MIN,
    }
}

impl IntTransform {
    /// The frame's formats for `positions` (all finite) under `m` (finite) and `planes`' viewport. [`Error::NonFinite`]
    /// for a non-finite position; [`Error::WorldTooLarge`] when folding the viewport into the matrix overflows f32.
    pub(crate) fn new(
        m: &Mat4,
        planes: &Planes,
        positions: &[[f32; 3]],
    ) -> Result<IntTransform, Error> {
        let mut p = i32::MIN;
        for v in positions.iter().flatten() {
            if !v.is_finite() {
                return Err(Error::NonFinite);
            }
            p = p.max(magnitude(*v));
        }
        // All positions zero (or none): any exponent works.
        let p = if p == i32::MIN { 0 } else { p };
        // Column `i` of `m` is output `i`: c_i = sum_j q_j m[j][i] + m[3][i].
        let col = |i: usize| [m.0[0][i], m.0[1][i], m.0[2][i], m.0[3][i]];
        let (cx, cy, cw) = (col(0), col(1), col(3));
        let (sx, sy, ox, oy) = planes.map_constants();
        let fold_x: [f32; 4] = core::array::from_fn(|j| sx * cx[j] + ox * cw[j]);
        let fold_y: [f32; 4] = core::array::from_fn(|j| oy * cw[j] - sy * cy[j]);
        let rows_f = [fold_x, fold_y, cw];
        if rows_f.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::WorldTooLarge);
        }
        let rows = rows_f.map(|r| {
            // |a_j| < 2^e and |t| < 2^(e + p); at least one bit above the lowest f32 exponent keeps the shifts sane.
            let e = (0..3)
                .map(|j| magnitude(r[j]))
                .chain([magnitude(r[3]).saturating_sub(p)])
                .max()
                .unwrap_or(0)
                .max(-200);
            Row {
                a: [0, 1, 2].map(|j| scaled(r[j], 30 - e) as i32),
                t: scaled(r[3], 60 - p - e),
                e,
            }
        });
        let w = rows[2];
        // W_near in W's units 2^(p + e - 60), rounded up; beyond 2^62 no W reaches it.
        let near = ceil_scaled(planes.near(), 60 - p - w.e);
        Ok(IntTransform { rows, p, near })
    }

    /// The projected vertex, or `None` where it needs clipping (behind `W_near`, or beyond the clip guard band).
    /// [`Error::WorldTooLarge`] where `rhw` leaves the f32 range (a `W_near` below about `3e-39`).
    pub(crate) fn project(&self, q: &[f32; 3]) -> Result<Option<Projected>, Error> {
        let pq = q.map(|v| to_31(v, 30 - self.p));
        let value = |r: &Row| -> i64 {
            r.a.iter()
                .zip(pq)
                .fold(r.t, |s, (&a, p)| s.wrapping_add(smul_wide(a, p)))
        };
        let w = value(&self.rows[2]);
        if w < self.near || w <= 0 {
            return Ok(None);
        }
        // W = wm 2^(32 - lw) units (wm its top 32 bits), so 1/W = r 2^(lw - 93) per unit, r = 2^61 / wm.
        let (wm, lw) = top32(w as u64);
        let r = fresh61::<Chord>(wm) as u32;
        // rhw = r 2^(lw - 93) / 2^(p + e_w - 60).
        let ew = self.rows[2].e;
        let rhw = f32_of(false, r, false, lw - 33 - self.p - ew);
        if !(rhw.is_finite() && rhw > 0.0) {
            return Err(Error::WorldTooLarge);
        }
        // x = X' / W: X' = xm 2^(32 - lx) units of 2^(p + e_x - 60); times r 2^(lw - 93) / 2^(p + e_w - 60).
        let screen = |row: &Row| -> f32 {
            let v = value(row);
            if v == 0 {
                return 0.0;
            }
            let (xm, lx) = top32(v.unsigned_abs());
            let p = mul_wide(xm, r);
            f32_of(
                v < 0,
                (p >> 32) as u32,
                p as u32 != 0,
                lw - lx - 29 + row.e - ew,
            )
        };
        let (x, y) = (screen(&self.rows[0]), screen(&self.rows[1]));
        // `|x| <= CLIP_BAND` on the bits (a float compare is a library call on a core without an FPU): the
        // magnitudes of non-negative floats order as their bits, and a NaN's lie above every finite one's.
        let within = |v: f32| v.to_bits() & 0x7fff_ffff <= CLIP_BAND.to_bits();
        if !(within(x) && within(y)) {
            return Ok(None);
        }
        Ok(Some(Projected { x, y, rhw }))
    }
}

/// `ceil(v 2^s)` for a positive finite `v`, saturated at `i64::MAX` from `2^62` on (no `W` reaches that).
fn ceil_scaled(v: f32, s: i32) -> i64 {
    let Some((_, m, e)) = split(v) else {
        return i64::MAX;
    };
    if m == 0 {
        return 0;
    }
    let sh = e + s;
    if sh >= 0 {
        if sh + (32 - m.leading_zeros() as i32) > 62 {
            i64::MAX
        } else {
            (m as i64) << sh
        }
    } else if sh > -40 {
        let k = (-sh) as u32;
        ((m as u64 + (1u64 << k) - 1) >> k) as i64
    } else {
        1
    }
}

/// `round(v 2^s)` for a finite coordinate below `2^(30 - s)` in magnitude: at most 31 bits, in 32-bit arithmetic
/// (the mantissa shifted left by below 7 bits, or by up to 29 for a subnormal's shorter mantissa, or to the right with
/// rounding to nearest, ties up). A shift left was cut at 7 bits before: a mesh whose largest coordinate is
/// subnormal got half or less of its subnormal coordinates (found by `to_31_rounds_to_nearest`'s sweep of every bit
/// pattern class).
#[inline]
fn to_31(v: f32, s: i32) -> i32 {
    let Some((neg, m, e)) = split(v) else {
        return 0;
    };
    let sh = e + s;
    let r = if sh >= 0 {
        m << sh.min(31) // below 30 within the domain: `31` only keeps an input outside it from panicking
    } else if sh > -32 {
        let k = (-sh) as u32;
        (m >> k) + ((m >> (k - 1)) & 1)
    } else {
        0
    };
    if neg {
        -(r as i32)
    } else {
        r as i32
    }
}

/// `(-1)^neg (m + f) 2^s` rounded to the nearest f32 (ties to even), for `m != 0` and a fraction `0 <= f < 1` that
/// is nonzero exactly when `sticky`, where `m >= 2^25` whenever `sticky` (the rounding position then lies in `m`, and
/// `f` only breaks a tie): the normal range in 32-bit operations, the rest through [`to_f32`].
#[inline(always)]
fn f32_of(neg: bool, m: u32, sticky: bool, s: i32) -> f32 {
    let l = clz32(m);
    let exp = 31 - l as i32 + s;
    if !(-126..=127).contains(&exp) {
        // Subnormal or infinite: the sticky fraction as one bit below `m`.
        return to_f32(neg, (m as u64) << 1 | u64::from(sticky), s - 1);
    }
    let n = m << l;
    let (mant, rem) = (n >> 8, n & 0xff);
    let up = rem > 0x80 || (rem == 0x80 && (sticky || mant & 1 == 1));
    // The leading bit of `mant` adds one to the exponent field; a rounding carry to 2^24 one more (to infinity
    // from the top binade, as it should).
    let v = f32::from_bits((((exp + 126) as u32) << 23) + mant + u32::from(up));
    if neg {
        -v
    } else {
        v
    }
}

/// `(-1)^neg m 2^s` rounded to the nearest f32 (ties to even), subnormals included, infinity above the range; `m > 0`.
fn to_f32(neg: bool, m: u64, s: i32) -> f32 {
    let b = bits64(m) as i32;
    // Value = m 2^s, with its leading bit at 2^(b - 1 + s): the f32 exponent.
    let exp = b - 1 + s;
    if exp > 127 {
        return if neg { -f32::INFINITY } else { f32::INFINITY };
    }
    // Keep 24 bits (fewer for a subnormal: its last bit is 2^-149).
    let keep = if exp < -126 { 24 - (-126 - exp) } else { 24 };
    let drop = b - keep;
    let mant = if drop > 64 {
        0
    } else if drop == 64 {
        u64::from(m > 1 << 63)
    } else if drop > 0 {
        let q = m >> drop;
        let rem = m & ((1u64 << drop) - 1);
        let half = 1u64 << (drop - 1);
        q + u64::from(rem > half || (rem == half && q & 1 == 1))
    } else {
        m << (-drop)
    };
    // mant below 2^24 (or 2^keep); a rounding carry to 2^24 moves the exponent: from_bits' addition handles it.
    let bits = if exp < -126 {
        mant as u32
    } else {
        (((exp + 126) as u32) << 23) + mant as u32
    };
    let v = f32::from_bits(bits);
    if neg {
        -v
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::Viewport;

    /// `to_f32` is the correctly rounded conversion (the host's f64 -> f32 cast of the exact value, which is exact in
    /// f64 for `m < 2^53`), for random mantissas and exponents across the normal and subnormal range.
    #[test]
    fn to_f32_rounds_to_nearest_even() {
        let mut rnd = crate::xorshift(0x1234_5678_9ABC_DEF1);
        for _ in 0..200_000 {
            let m = rnd() >> (11 + rnd() % 40);
            if m == 0 {
                continue;
            }
            // Down to 2^-260: past the smallest subnormal by more than 64 bits of `m` (everything rounds to 0).
            let e = (rnd() % 360) as i32 - 260;
            let exact = m as f64 * 2f64.powi(e);
            assert_eq!(to_f32(false, m, e), exact as f32, "{m} 2^{e}");
            assert_eq!(to_f32(true, m, e), -(exact as f32), "{m} 2^{e}");
        }
        // Ties: 2^24 + 1 rounds down to even, 2^24 + 3 up.
        assert_eq!(to_f32(false, (1 << 25) + 1, -1), 16_777_216.0);
        assert_eq!(to_f32(false, (1 << 25) + 3, -1), 16_777_218.0);
        // `m` of 64 bits all dropped (`2^63 m'` at `2^-213` is `m' 2^-150`, half the smallest subnormal): above half
        // it rounds up to `2^-149`, half exactly ties to even (0); dropping more than 64 bits gives 0.
        assert_eq!(to_f32(false, (1 << 63) + 1, -213).to_bits(), 1);
        assert_eq!(to_f32(false, u64::MAX, -213).to_bits(), 1);
        assert_eq!(to_f32(false, 1 << 63, -213).to_bits(), 0);
        assert_eq!(to_f32(true, u64::MAX, -214).to_bits(), 0x8000_0000);
        assert_eq!(to_f32(false, u64::MAX, -300).to_bits(), 0);
    }

    /// `f32_of` equals `to_f32` of the same value (with the fraction as one bit below `m`), and `top32` the top 32
    /// bits, for random values and every leading-zero count; `clz32` is `leading_zeros`.
    #[test]
    fn f32_of_top32_and_clz32_are_exact() {
        let mut rnd = crate::xorshift(0x7777_1234_0000_0001);
        for _ in 0..200_000 {
            let v = rnd() >> (rnd() % 64);
            if v == 0 {
                continue;
            }
            let (m, l) = top32(v);
            assert_eq!(l as u32, v.leading_zeros(), "{v}");
            assert_eq!(m as u64, (v << l) >> 32, "{v}");
            assert_eq!(clz32(v as u32 | 1), (v as u32 | 1).leading_zeros());
            let m = (v >> 32) as u32 | 1;
            let sticky = v as u32 & 1 == 1 && m >= 1 << 25;
            let e = (rnd() % 320) as i32 - 200;
            for neg in [false, true] {
                assert_eq!(
                    f32_of(neg, m, sticky, e).to_bits(),
                    to_f32(neg, (m as u64) << 1 | u64::from(sticky), e - 1).to_bits(),
                    "{m} {sticky} {e}"
                );
            }
        }
    }

    /// A finite f32's bits as `(mantissa, exponent)`, `|v| = m 2^e`, decoded here (not by `split`), for the exact
    /// references below.
    fn bits_of(b: u32) -> (u128, i32) {
        let (be, f) = (((b >> 23) & 0xff) as i32, (b & 0x7f_ffff) as u128);
        if be == 0 {
            (f, -149)
        } else {
            (f | 1 << 23, be - 150)
        }
    }

    /// `W_near` and the viewport map of a 320 x 240 screen.
    fn planes(near: f32) -> Planes {
        Planes::new(near, &Viewport::new(0.0, 0.0, 320.0, 240.0)).unwrap()
    }

    /// `ceil_scaled` is `ceil(v 2^s)`, saturated at `i64::MAX` from `2^62` on, over the whole exponent range: exact
    /// values from the f32's bits in `u128` (shifts up to 100 bits; a positive value below `2^-76` has the ceiling 1).
    #[test]
    fn ceil_scaled_is_the_ceiling() {
        let exact = |v: f32, s: i32| -> i64 {
            let (m, e) = bits_of(v.to_bits());
            let sh = e + s;
            let c = if m == 0 {
                0
            } else if sh >= 0 {
                if sh > 100 {
                    u128::MAX
                } else {
                    m << sh
                }
            } else if sh > -100 {
                (m + (1u128 << -sh) - 1) >> -sh
            } else {
                1
            };
            if c >= 1 << 62 {
                i64::MAX
            } else {
                c as i64
            }
        };
        let mut rnd = crate::xorshift(0xCE11_5CA1_ED00_0001);
        let mut seen = [0u32; 4]; // saturated, shifted left, a shift right with rounding up, below 1 (so 1)
        for _ in 0..400_000 {
            // Every positive finite f32 bit pattern class: subnormals, and exponents across the range.
            let v = f32::from_bits((rnd() as u32) % 0x7f80_0000);
            let s = (rnd() % 400) as i32 - 200;
            let got = ceil_scaled(v, s);
            assert_eq!(got, exact(v, s), "{v:e} 2^{s}");
            let sh = crate::fixed::split(v).map_or(0, |(_, _, e)| e + s);
            match () {
                _ if got == i64::MAX => seen[0] += 1,
                _ if sh >= 0 => seen[1] += 1,
                // Below `2^-24` of the shift's unit the ceiling of a positive value is 1 whichever branch takes it.
                _ if sh > -24 => seen[2] += 1,
                _ => seen[3] += 1,
            }
        }
        // The boundaries: `2^62` saturates, the largest mantissa just below it does not; a shift of 39 and of 40 to
        // the right (the branches' seam); a value exactly on the grid is its own ceiling.
        assert_eq!(ceil_scaled(1.0, 62), i64::MAX);
        assert_eq!(
            ceil_scaled(f32::from_bits(0x3fff_ffff), 61),
            (0xff_ffffi64) << 38
        );
        assert_eq!(ceil_scaled(3.0, -1), 2);
        assert_eq!(ceil_scaled(f32::from_bits(0x3fff_ffff), -1), 1);
        assert_eq!(ceil_scaled(1.5, -40 + 23), 1);
        assert_eq!(ceil_scaled(1.5, 1), 3);
        assert_eq!(ceil_scaled(1.25, 1), 3);
        assert_eq!(ceil_scaled(0.0, 10), 0);
        assert_eq!(ceil_scaled(f32::INFINITY, 0), i64::MAX);
        assert!(seen.iter().all(|&n| n > 1000), "{seen:?}");
    }

    /// `to_31` equals the exact rounding (ties up) of `v 2^s` for coordinates below `2^(30 - s)`.
    #[test]
    fn to_31_rounds_to_nearest() {
        let mut rnd = crate::xorshift(0x0BAD_5EED_0000_0001);
        for _ in 0..200_000 {
            let p = (rnd() % 40) as i32 - 20;
            let v = ((rnd() >> 11) as f64 / 2f64.powi(53) * 2.0 - 1.0) as f32 * 2f32.powi(p);
            let s = 30 - p;
            let exact = (v as f64 * 2f64.powi(s)).abs();
            let want = (exact + 0.5).floor() as i64 * if v < 0.0 { -1 } else { 1 };
            assert_eq!(to_31(v, s) as i64, want, "{v} {s}");
        }
        // Every f32 bit pattern class, each at scales from its own limit `|v 2^s| < 2^30` down to `2^-70` of it (the
        // right shifts past 31 bits, which give 0): exact in `u128` from the bits, ties up.
        let mut rnd = crate::xorshift(0x0BAD_5EED_0000_0002);
        let mut seen = [0u32; 3]; // shifted left, rounded by a shift right, below one unit
        for _ in 0..200_000 {
            let b = (rnd() as u32) & 0x7fff_ffff;
            if b >> 23 == 0xff {
                continue;
            }
            let (m, e) = bits_of(b);
            if m == 0 {
                continue;
            }
            let top = e + (128 - m.leading_zeros() as i32); // |v| < 2^top
            let s = 30 - top - (rnd() % 71) as i32;
            let sh = e + s;
            let r = if sh >= 0 {
                m << sh
            } else if sh > -100 {
                (m + (1u128 << (-sh - 1))) >> -sh
            } else {
                0
            };
            seen[if sh >= 0 {
                0
            } else if sh > -32 {
                1
            } else {
                2
            }] += 1;
            for neg in [false, true] {
                let v = f32::from_bits(b | u32::from(neg) << 31);
                let want = if neg { -(r as i64) } else { r as i64 };
                assert_eq!(to_31(v, s) as i64, want, "{v:e} 2^{s}");
            }
        }
        // The seam of the right shifts: 31 and 32 bits (half a unit rounds up; below it, 0).
        assert_eq!(to_31(1.0, -1), 1);
        assert_eq!(to_31(1.5, -1), 1);
        assert_eq!(to_31(-1.5, 0), -2);
        assert_eq!(to_31(f32::from_bits(0x3fff_ffff), -31 + 23), 0); // the mantissa shifted 31 bits right
        assert_eq!(to_31(f32::from_bits(0x3fff_ffff), -32 + 23), 0); // 32 bits: past a u32's shift
        assert!(seen.iter().all(|&n| n > 1000), "{seen:?}");
    }

    /// `W = z` and the viewport map of a 320 x 240 screen, for the boundary cases below.
    fn w_is_z(near: f32, w_scale: f32, pos: &[[f32; 3]]) -> IntTransform {
        let planes = planes(near);
        let mut m = Mat4::IDENTITY;
        m.0[2][3] = w_scale;
        m.0[3][3] = 0.0;
        IntTransform::new(&m, &planes, pos).unwrap()
    }

    /// The near plane is inclusive, as the f32 path's outcode has it (`W - W_near < 0` is outside): a vertex exactly
    /// at `W_near` is projected, the f32 just below it is marked for clipping. `rhw` outside the f32 range is
    /// [`Error::WorldTooLarge`], above it (`W_near` subnormal) and below it (`W` past `2^149`), as `project` says.
    #[test]
    fn near_plane_and_rhw_range() {
        let at = [[0.0, 0.0, 0.5]];
        let it = w_is_z(0.5, 1.0, &at);
        let p = it
            .project(&at[0])
            .unwrap()
            .expect("exactly at W_near: drawn");
        assert_eq!((p.x, p.y, p.rhw), (160.0, 120.0, 2.0));
        let planes = planes(0.5);
        assert_eq!(planes.outcode(&[0.0, 0.0, 0.5, 0.5]) & 1, 0);
        let below = [0.0, 0.0, f32::from_bits(0.5f32.to_bits() - 1)];
        assert_eq!(it.project(&below).unwrap(), None);
        assert_eq!(planes.outcode(&[0.0, 0.0, below[2], below[2]]) & 1, 1);
        // rhw = 1 / 2e-39 overflows f32.
        let tiny = [[0.0, 0.0, 2e-39]];
        assert_eq!(
            w_is_z(1e-39, 1.0, &tiny).project(&tiny[0]),
            Err(Error::WorldTooLarge)
        );
        // W = 2^30 1e38, about 2^156: rhw underflows to 0.
        let far = [[0.0, 0.0, 1e38]];
        let it = w_is_z(0.5, (1u64 << 30) as f32, &far);
        assert_eq!(it.project(&far[0]), Err(Error::WorldTooLarge));
        // 2^100 is still in range (rhw 2^-130, subnormal) and projects to the centre.
        let big = [[0.0, 0.0, 2f32.powi(100)]];
        let p = w_is_z(0.5, 1.0, &big).project(&big[0]).unwrap().unwrap();
        assert_eq!((p.x, p.y), (160.0, 120.0));
        assert!(
            (p.rhw as f64 * 2f64.powi(100) - 1.0).abs() < 2f64.powi(-10),
            "{:e}",
            p.rhw
        );
    }

    /// A mesh whose every coordinate is zero (all at the model's origin): the positions' exponent is then any, and the
    /// translation alone places them; and one whose largest coordinate is subnormal. Both against the f64 values.
    #[test]
    fn origin_and_subnormal_meshes_project() {
        let planes = planes(0.5);
        let m = Mat4::translation([0.25, -0.5, 2.0]);
        let mut m = m;
        m.0[2][3] = 1.0; // W = z
        m.0[3][3] = 2.0; // ... + 2
        let zero = [[0.0f32; 3]];
        let p = IntTransform::new(&m, &planes, &zero)
            .unwrap()
            .project(&zero[0])
            .unwrap()
            .unwrap();
        // x = 160 + 160 (0.25 / 2), y = 120 - 120 (-0.5 / 2), rhw = 1/2: all exact.
        assert_eq!((p.x, p.y, p.rhw), (180.0, 150.0, 0.5));
        let sub = [[1e-39f32, -3e-39, 2e-39], [0.0, 0.0, 0.0]];
        let it = IntTransform::new(&m, &planes, &sub).unwrap();
        for q in &sub {
            let p = it.project(q).unwrap().unwrap();
            // Against the f64 values; the coordinates move x by below 1e-36 px, so x, y, rhw are those of the
            // origin's to within the bound of `projection_is_within_its_bound` (2^-22.3 M + 2^-23.9 |x|, M <= 640).
            let w = 2.0 + q[2] as f64;
            let (x, y) = (
                160.0 + 160.0 * (0.25 + q[0] as f64) / w,
                120.0 - 120.0 * (-0.5 + q[1] as f64) / w,
            );
            let b = |v: f64| 2f64.powf(-22.3) * 640.0 + 2f64.powf(-23.9) * v;
            assert!(
                (p.x as f64 - x).abs() <= b(x) && (p.y as f64 - y).abs() <= b(y),
                "{p:?}"
            );
            assert!((p.rhw as f64 * w - 1.0).abs() <= 2f64.powf(-23.9) + 2f64.powi(-29) * 2.0);
        }
        // The integer positions themselves: every coordinate at the positions' exponent, exactly.
        let pq = sub[0].map(|v| to_31(v, 30 - it.p));
        for (k, &v) in sub[0].iter().enumerate() {
            assert_eq!(
                pq[k] as f64,
                (v as f64 * 2f64.powi(30 - it.p)).round(),
                "{v:e}"
            );
        }
    }

    /// Screen `x` and `y` are the product of the top 32 bits of `X'` (or `Y'`) and `W`'s reciprocal, rounded once
    /// to f32, to nearest and ties to even, with the product's low word as the sticky fraction (the module doc):
    /// against [`to_f32`] of the whole 64-bit product, over random vertices.
    #[test]
    fn screen_coordinates_round_the_whole_product() {
        let planes = planes(0.5);
        let mut rnd = crate::xorshift(0x5C8E_E000_0000_0001);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let (mut checked, mut ties) = (0, 0);
        for _ in 0..200 {
            let (s, c) = crate::projection::sin_cos(unit() * 6.0);
            let m = Mat4([
                [c * 1.3, 0.0, -s, -s],
                [0.0, 1.7, 0.0, 0.0],
                [s * 1.3, 0.0, c, c],
                [0.0, 0.0, 4.0, 4.0],
            ]);
            let pos: std::vec::Vec<[f32; 3]> = (0..64)
                .map(|_| [0, 1, 2].map(|_| unit() * 2.0 - 1.0))
                .collect();
            let it = IntTransform::new(&m, &planes, &pos).unwrap();
            for q in &pos {
                let Some(p) = it.project(q).unwrap() else {
                    continue;
                };
                let pq = q.map(|v| to_31(v, 30 - it.p));
                let value = |r: &Row| {
                    r.a.iter()
                        .zip(pq)
                        .fold(r.t, |s, (&a, p)| s + a as i64 * p as i64)
                };
                let (wm, lw) = top32(value(&it.rows[2]) as u64);
                let r = fresh61::<Chord>(wm) as u32 as u64;
                for (row, got) in [(&it.rows[0], p.x), (&it.rows[1], p.y)] {
                    let v = value(row);
                    if v == 0 {
                        continue;
                    }
                    let (xm, lx) = top32(v.unsigned_abs());
                    let prod = xm as u64 * r;
                    let want = to_f32(v < 0, prod, lw - lx - 29 + row.e - it.rows[2].e - 32);
                    assert_eq!(got.to_bits(), want.to_bits(), "{q:?}");
                    // A tie of the top 32 bits that the low word breaks.
                    let n = (prod >> 32) as u32;
                    let n = n << n.leading_zeros();
                    ties += usize::from(n & 0xff == 0x80 && prod as u32 != 0);
                    checked += 1;
                }
            }
        }
        assert!(checked > 20_000 && ties > 50, "{checked} {ties}");
    }

    /// Projected vertices against f64 arithmetic on the same f32 positions and matrix, for random rotations, scales
    /// from `2^-10` to `2^10`, distances and a W-friendly perspective, within the module doc's derived bounds:
    /// `x` (and `y`) within `2^-22.3 M + 2^-23.9 |x|` px, where `M` is the sum of the magnitudes of the folded row's
    /// terms over `W` (in pixels; the fold's f32 roundings scale with it), and `rhw` within `2^-23.9 + 2^-29 M_w`
    /// relative (`M_w` the same for `W`). And the same vertices marked for clipping as the exact test says, away from
    /// its boundaries by more than the bound.
    #[test]
    fn projection_is_within_its_bound() {
        use crate::projection::Mat4;
        use std::vec::Vec;
        let vp = Viewport::new(0.0, 0.0, 320.0, 240.0);
        let planes = Planes::new(0.5, &vp).unwrap();
        let (sx, sy, ox, oy) = planes.map_constants();
        let (sx, sy, ox, oy) = (sx as f64, sy as f64, ox as f64, oy as f64);
        let mut rnd = crate::xorshift(0xFEED_0000_1111_2222);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let (mut worst_xy, mut worst_rhw, mut drawn) = (0.0f64, 0.0f64, 0);
        for _ in 0..400 {
            let scale = 2f32.powi((unit() * 20.0) as i32 - 10);
            let (a, b) = (unit() * 6.3, unit() * 6.3);
            let (ca, sa, cb, sb) = (
                micromath::F32(a).cos().0,
                micromath::F32(a).sin().0,
                micromath::F32(b).cos().0,
                micromath::F32(b).sin().0,
            );
            let dist = scale * (2.0 + unit() * 8.0);
            let f = 1.7f32;
            let m = Mat4([
                [ca * f, sa * sb * f * 0.75, -sa * cb, -sa * cb],
                [0.0, cb * f * 0.75, sb, sb],
                [sa * f, -ca * sb * f * 0.75, ca * cb, ca * cb],
                [0.0, 0.0, dist, dist],
            ]);
            let pos: Vec<[f32; 3]> = (0..64)
                .map(|_| [0, 1, 2].map(|_| (unit() * 2.0 - 1.0) * scale))
                .collect();
            let it = IntTransform::new(&m, &planes, &pos).unwrap();
            for q in &pos {
                let qq = [q[0] as f64, q[1] as f64, q[2] as f64, 1.0];
                let col = |i: usize| -> [f64; 4] { core::array::from_fn(|j| m.0[j][i] as f64) };
                let (cx, cy, cw) = (col(0), col(1), col(3));
                let dot = |r: [f64; 4]| (0..4).map(|j| r[j] * qq[j]).sum::<f64>();
                let mag = |r: [f64; 4]| (0..4).map(|j| (r[j] * qq[j]).abs()).sum::<f64>();
                let w = dot(cw);
                let (xe, ye) = (ox + sx * dot(cx) / w, oy - sy * dot(cy) / w);
                let fx: [f64; 4] =
                    core::array::from_fn(|j| (sx * cx[j]).abs() + (ox * cw[j]).abs());
                let fy: [f64; 4] =
                    core::array::from_fn(|j| (sy * cy[j]).abs() + (oy * cw[j]).abs());
                let (mx, my, mw) = (mag(fx) / w.abs(), mag(fy) / w.abs(), mag(cw) / w.abs());
                let inside = w >= 0.5 && xe.abs() <= 4000.0 && ye.abs() <= 4000.0;
                let near_edge = (w - 0.5).abs() < 1e-6 * w.abs()
                    || (xe.abs() - 4000.0).abs() < 1e-2 * (1.0 + mx)
                    || (ye.abs() - 4000.0).abs() < 1e-2 * (1.0 + my);
                match it.project(q).unwrap() {
                    Some(p) => {
                        assert!(inside || near_edge, "{q:?} drawn, exact outside");
                        let bx = 2f64.powf(-22.3) * mx + 2f64.powf(-23.9) * xe.abs();
                        let by = 2f64.powf(-22.3) * my + 2f64.powf(-23.9) * ye.abs();
                        let (dx, dy) = ((p.x as f64 - xe).abs(), (p.y as f64 - ye).abs());
                        worst_xy = worst_xy.max(dx / bx).max(dy / by);
                        assert!(dx <= bx && dy <= by, "{q:?}: {} {} vs {xe} {ye}", p.x, p.y);
                        let rel = (p.rhw as f64 * w - 1.0).abs();
                        let br = 2f64.powf(-23.9) + 2f64.powi(-29) * mw;
                        worst_rhw = worst_rhw.max(rel / br);
                        assert!(rel <= br, "{q:?}: rhw {rel:e}");
                        drawn += 1;
                    }
                    None => assert!(!inside || near_edge, "{q:?} marked, exact inside"),
                }
            }
        }
        std::println!(
            "integer transform: {drawn} vertices, worst x/y {worst_xy:.3} of the bound, rhw {worst_rhw:.3}"
        );
        assert!(drawn > 10_000, "{drawn}");
    }
}
