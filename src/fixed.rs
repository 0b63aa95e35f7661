//! Exact conversions from `f32` into the fixed-point formats of the pipeline, with integer operations only
//! (no soft-float on cores without an FPU, bit-identical results on every target).

/// An `f32` split into `(negative, mantissa, exponent)` with `|v| = mantissa * 2^exponent`; `None` for NaN and infinities.
/// Zero and subnormals give a mantissa without the implicit bit (zero gives mantissa 0).
#[inline]
pub(crate) fn split(v: f32) -> Option<(bool, u32, i32)> {
    let bits = v.to_bits();
    let neg = bits >> 31 != 0;
    let exp = ((bits >> 23) & 0xff) as i32;
    let frac = bits & 0x7f_ffff;
    match exp {
        0xff => None,
        0 => Some((neg, frac, -149)),
        _ => Some((neg, frac | 0x80_0000, exp - 150)),
    }
}

/// `round(m * 2^e)` (`m` an f32 mantissa times the far plane's, or a 32-bit fixed-point `1/W` times it, below `2^56`:
/// not normalised, so a small `m` may take a large `e`), ties to even, saturating at `i64::MAX` (callers
/// range-check the input first). Exact for any `m` down to `e = -63`, and below that for `m <= 2^63`, which then
/// rounds to 0 (tested against `u128`).
#[inline]
pub(crate) fn round_shift(m: u64, e: i32) -> u64 {
    if m == 0 {
        return 0;
    }
    if e >= 0 {
        // m * 2^e >= 2^63 when e reaches m's leading zeros.
        if e >= 64 - crate::fast::bits64(m) as i32 {
            return i64::MAX as u64;
        }
        crate::fast::shl64(m, e as u32)
    } else {
        let s = (-e) as u32;
        if s > 63 {
            return 0;
        }
        let q = crate::fast::shr64(m, s);
        let rem = m & (crate::fast::shl64(1, s) - 1);
        let half = crate::fast::shl64(1, s - 1);
        if rem > half || (rem == half && q & 1 == 1) {
            q + 1
        } else {
            q
        }
    }
}

/// [`round_shift`] for a product the caller knows to be below `2^63` (`e < 64 - bits(m)` where `e >= 0`): the same
/// value without the saturation's bit count, which on the cores without CLZ (the Cortex-M0, RV32IMAC) is a table
/// look-up of some 25 instructions. The set-up's `T` ([`crate::Rasterizer`]'s `round_t`) is one: its fraction bits
/// `F = 61 - max_k bits(T_k)` put every `T_k 2^F` below `2^61`. Measured on the M0's W3 (single-scene build, commit
/// aa8bafb): 6,000 calls of 53 instructions before; 6,714.9 -> 6,599.2 instructions a triangle.
#[inline]
pub(crate) fn round_shift_fits(m: u64, e: i32) -> u64 {
    debug_assert!(e < 0 || m == 0 || e < 64 - crate::fast::bits64(m) as i32);
    if (e as u32) < 64 {
        crate::fast::shl64(m, e as u32)
    } else {
        round_shift(m, e)
    }
}

/// `v * 2^frac_bits` rounded to nearest (ties to even), for `|v| <= limit`; `Err(true)` outside, `Err(false)` for
/// non-finite. The general 64-bit conversion, kept as the reference the 32-bit snap (`input::snap`) is tested against.
#[cfg(test)]
pub(crate) fn to_fixed(v: f32, frac_bits: i32, limit_log2: i32) -> Result<i64, bool> {
    let (neg, m, e) = split(v).ok_or(false)?;
    // |v| < 2^(e + 24): reject anything at or above 2^limit (m has at most 24 bits).
    if m != 0 && e + (32 - m.leading_zeros() as i32) > limit_log2 {
        return Err(true);
    }
    let r = round_shift(m as u64, e + frac_bits) as i64;
    Ok(if neg { -r } else { r })
}

/// `floor(n / d)` for `0 < d < 2^62`, shift-and-subtract with a 64-bit remainder (`r < 2d < 2^63`), the quotient
/// shifting into the dividend's register as the dividend shifts out. The plane solve divides numbers of up to ~90
/// bits by areas below 2^44; the generic `u128` division of 32-bit targets is large (about 1.5 KiB inlined on the
/// Cortex-M4) and takes a 128-bit step per quotient bit. When the quotient fits 64 bits (every triangle but extreme
/// slivers) only `lo`'s significant bits are walked, with a 32-bit remainder when `d < 2^31` (small triangles).
#[inline]
pub(crate) fn div_u128(n: u128, d: u64) -> u128 {
    // 64-bit hosts divide 128 by 64 bits in hardware: the same exact floor, faster.
    if cfg!(target_pointer_width = "64") {
        n / d as u128
    } else {
        div_u128_shift(n, d)
    }
}

/// [`div_u128`] by shift-and-subtract (what 32-bit targets run; tested on every host).
pub(crate) fn div_u128_shift(n: u128, d: u64) -> u128 {
    debug_assert!(d > 0 && d < 1 << 62);
    let hi = (n >> 64) as u64;
    if hi >= d {
        let (mut r, mut q) = (0u64, n);
        for _ in 0..128 {
            r = (r << 1) | (q >> 127) as u64;
            q <<= 1;
            if r >= d {
                r -= d;
                q |= 1;
            }
        }
        return q;
    }
    let mut lo = n as u64;
    // With no high word, the leading zeros of `lo` are zero quotient bits: skip them.
    let steps = if hi == 0 {
        let z = lo.leading_zeros();
        lo = lo.checked_shl(z).unwrap_or(0);
        64 - z
    } else {
        64
    };
    if d < 1 << 31 {
        let (d, mut r) = (d as u32, hi as u32);
        for _ in 0..steps {
            r = (r << 1) | (lo >> 63) as u32;
            lo <<= 1;
            if r >= d {
                r -= d;
                lo |= 1;
            }
        }
    } else {
        let mut r = hi;
        for _ in 0..steps {
            r = (r << 1) | (lo >> 63);
            lo <<= 1;
            if r >= d {
                r -= d;
                lo |= 1;
            }
        }
    }
    lo as u128
}

/// Exact `floor(n / d)` by one divisor `0 < d < 2^62`, several times (the plane solve divides three numerators by
/// its area, in every band a triangle reaches): the reciprocal of the normalised divisor is formed once (one
/// [`div_u128`]), then each quotient below `2^64` takes one 64 x 64 -> 128-bit product, one 64-bit product and at
/// most two corrections, where [`div_u128_shift`] takes a step per quotient bit (Moller and Granlund, "Improved
/// Division by Invariant Integers", IEEE Transactions on Computers, 2011, algorithm 4). A larger quotient (an extreme
/// sliver's step) takes [`div_u128`]. 64-bit hosts divide in hardware (the same exact floor).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Divisor {
    d: u64,
    /// `d`'s leading zeros, and `d` shifted by them (top bit set).
    s: u32,
    dn: u64,
    /// `floor((2^128 - 1) / dn) - 2^64`.
    v: u64,
}

impl Divisor {
    pub(crate) fn new(d: u64) -> Divisor {
        debug_assert!(d > 0 && d < 1 << 62);
        let s = d.leading_zeros();
        let dn = d << s;
        Divisor {
            d,
            s,
            dn,
            v: reciprocal(dn),
        }
    }

    /// `floor(n / d)`.
    #[inline]
    pub(crate) fn div(&self, n: u128) -> u128 {
        if cfg!(target_pointer_width = "64") {
            n / self.d as u128
        } else {
            self.div_preinv(n)
        }
    }

    /// `round(n / d)`, ties away from zero, for a signed `n` (`|n| + d/2` below `2^127`).
    #[inline]
    pub(crate) fn div_round(&self, n: i128) -> i128 {
        let q = self.div(n.unsigned_abs() + (self.d / 2) as u128) as i128;
        if n < 0 {
            -q
        } else {
            q
        }
    }

    /// [`Divisor::div`] by the reciprocal (what 32-bit targets run; tested on every host).
    fn div_preinv(&self, n: u128) -> u128 {
        if (n >> 64) as u64 >= self.d {
            return div_u128_shift(n, self.d);
        }
        // n < d 2^64, so n 2^s < dn 2^64: the normalised numerator fits, its high word below dn.
        let nn = n << self.s;
        let (u1, u0) = ((nn >> 64) as u64, nn as u64);
        let q = mul_64x64(self.v, u1).wrapping_add(((u1 as u128 + 1) << 64) | u0 as u128);
        let (mut q1, q0) = ((q >> 64) as u64, q as u64);
        let mut r = u0.wrapping_sub(q1.wrapping_mul(self.dn));
        if r > q0 {
            q1 = q1.wrapping_sub(1);
            r = r.wrapping_add(self.dn);
        }
        if r >= self.dn {
            q1 += 1;
        }
        q1 as u128
    }
}

/// `floor((2^128 - 1) / dn) - 2^64` for a normalised `dn` (top bit set): the quotient of `(2^64 - 1 - dn) 2^64 +
/// (2^64 - 1)` by `dn`, whose high word `!dn` is below `dn`, so it has 64 bits. Shift and subtract with the
/// remainder's carry bit kept (the remainder reaches `2^65` before a subtraction: [`div_u128_shift`] assumes a
/// divisor below `2^62` and would lose it). The same code on every target, so that the host's tests check what the
/// boards run.
fn reciprocal(dn: u64) -> u64 {
    debug_assert!(dn >> 63 == 1);
    let (mut r, mut q) = (!dn, u64::MAX);
    for _ in 0..64 {
        let carry = r >> 63;
        r = (r << 1) | (q >> 63);
        q <<= 1;
        if carry != 0 || r >= dn {
            r = r.wrapping_sub(dn);
            q |= 1;
        }
    }
    q
}

/// The exact 128-bit product of two `u64` from four 32 x 32 -> 64 products (`mul_wide`: four `MULS` each on the
/// Cortex-M0, `UMULL` on the M4), where a `u128` multiply is a library call on the 32-bit cores.
#[inline]
fn mul_64x64(a: u64, b: u64) -> u128 {
    use crate::fast::mul_wide;
    let (ah, al, bh, bl) = ((a >> 32) as u32, a as u32, (b >> 32) as u32, b as u32);
    let ll = mul_wide(al, bl) as u128;
    let mid = mul_wide(al, bh) as u128 + mul_wide(ah, bl) as u128;
    let hh = mul_wide(ah, bh) as u128;
    (hh << 64) + (mid << 32) + ll
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reciprocal division equals `u128` division for divisors of every size below `2^62` (and both ends of the
    /// range), numerators with quotients below and above `2^64`, and the edges of each: the reciprocal path taken
    /// explicitly (the host's own `div` divides in hardware); and `div_round` is the rounded quotient.
    #[test]
    fn reciprocal_division_is_exact() {
        let mut rnd = crate::xorshift(0x0DDB_A11C_0FFE_E123);
        let mut fast = 0;
        for k in 0..300_000 {
            let d = match k % 50 {
                0 => 1,
                1 => (1 << 62) - 1,
                2 => 1 << (rnd() % 62),
                _ => ((rnd() >> 2) >> (rnd() % 62)).max(1),
            };
            let dv = Divisor::new(d);
            assert_eq!(
                dv.v as u128,
                u128::MAX / ((d << d.leading_zeros()) as u128) - (1u128 << 64),
                "v of {d}"
            );
            let n = ((rnd() as u128) << 64 | rnd() as u128) >> (rnd() % 128);
            for n in [
                n,
                ((d as u128) << 64) - 1,
                (d as u128) << 64,
                n % ((d as u128) << 64),
                (n % ((d as u128) << 64)) / d as u128 * d as u128,
                ((n % ((d as u128) << 64)) / d as u128 * d as u128).saturating_sub(1),
            ] {
                fast += u32::from(n >> 64 < d as u128);
                assert_eq!(dv.div_preinv(n), n / d as u128, "{n} / {d}");
            }
            let m = (rnd() as i128) << 40 >> (rnd() % 60);
            let r = (m.unsigned_abs() + (d / 2) as u128) / d as u128;
            assert_eq!(
                dv.div_round(m),
                if m < 0 { -(r as i128) } else { r as i128 }
            );
        }
        assert!(fast > 1_000_000, "{fast}");
    }

    /// A mantissa that is not normalised (a 32-bit fixed-point `1/W` with leading zeros) takes a large left shift:
    /// exact up to 2^63, saturating from there. (Found by the fixed-point input's equality with f32: the old limit
    /// `e < 15` assumed a 48-bit mantissa and saturated `1.85e6 << 16`.)
    #[test]
    fn round_shift_left_is_exact_until_it_saturates() {
        assert_eq!(round_shift(1_850_000, 16), 1_850_000 << 16);
        assert_eq!(round_shift(1, 62), 1 << 62);
        assert_eq!(round_shift(1, 63), i64::MAX as u64);
        assert_eq!(round_shift(3, 62), i64::MAX as u64);
        assert_eq!(round_shift(u64::MAX >> 1, 0), u64::MAX >> 1);
        assert_eq!(round_shift(5, -1), 2); // 2.5 ties to even
        assert_eq!(round_shift(7, -1), 4); // 3.5 ties to even
    }

    /// `round_shift` against the exact value in `u128`, ties to even: every `m` for shifts down to `2^-63`, and the
    /// `m <= 2^63` below that (where `m 2^e <= 1/2` rounds to 0); up, exact below `2^63` and saturated from there.
    #[test]
    fn round_shift_is_the_rounded_product() {
        let exact = |m: u64, e: i32| -> u64 {
            if e >= 0 {
                let v = (m as u128) << e.min(64);
                return if v >= 1 << 63 {
                    i64::MAX as u64
                } else {
                    v as u64
                };
            }
            let s = (-e) as u32;
            let (q, rem) = ((m as u128) >> s.min(127), (m as u128) & ((1u128 << s) - 1));
            let half = 1u128 << (s - 1);
            (q + u128::from(rem > half || (rem == half && q & 1 == 1))) as u64
        };
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for k in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let m = x >> (k % 64);
            for e in -63..=64 {
                assert_eq!(round_shift(m, e), exact(m, e), "{m} {e}");
            }
            for e in -80..-63 {
                let m = m >> 1; // below 2^63
                assert_eq!(round_shift(m, e), exact(m, e), "{m} {e}");
            }
        }
        // The half-way points at the deepest shifts that keep every `m`.
        assert_eq!(round_shift(1 << 62, -63), 0); // 1/2, ties to even
        assert_eq!(round_shift((1 << 62) + 1, -63), 1);
        assert_eq!(round_shift(u64::MAX, -63), 2);
    }

    /// [`round_shift_fits`] is [`round_shift`] wherever its contract holds (`m 2^e < 2^63`), on every shift from
    /// `2^-80` up and every mantissa width.
    #[test]
    fn round_shift_fits_is_round_shift_below_its_bound() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut left = 0;
        for k in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let m = x >> (k % 64);
            for e in -80..64 {
                let fits = e < 0 || m == 0 || e < m.leading_zeros() as i32;
                if fits {
                    left += usize::from(e >= 0);
                    assert_eq!(round_shift_fits(m, e), round_shift(m, e), "{m} {e}");
                }
            }
        }
        assert!(left > 1_000_000, "{left}");
    }

    #[test]
    fn to_fixed_matches_exact_rounding() {
        // Each value is exactly representable, so f64 gives the exact product; ties to even.
        let cases: &[f32] = &[
            0.0,
            -0.0,
            1.0,
            0.5 / 256.0,
            1.5 / 256.0,
            2.5 / 256.0,
            -2.5 / 256.0,
            100.123,
            -4095.99,
            1e-30,
        ];
        for &v in cases {
            let exact = (v as f64) * 256.0;
            let want = exact.round_ties_even() as i64;
            assert_eq!(to_fixed(v, 8, 12), Ok(want), "{v}");
        }
        assert_eq!(to_fixed(4096.0, 8, 12), Err(true));
        assert_eq!(to_fixed(4095.9998, 8, 12), Ok(1_048_576)); // rounds up to 4096.0 * 256, inside the band
        assert_eq!(to_fixed(f32::NAN, 8, 12), Err(false));
        assert_eq!(to_fixed(f32::NEG_INFINITY, 8, 12), Err(false));
    }
}
