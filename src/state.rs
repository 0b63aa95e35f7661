//! Render state: depth range, comparison, depth write, culling.

use crate::fixed::{div_u128, split};
use crate::Error;

/// The largest `W_far / W_near`, and the largest `rhw * W_far` of a vertex: `2^30`.
/// It keeps `t = W_far * rhw` in the plane's 62 bits with at least 30 fraction bits (see ARCHITECTURE.md).
pub const MAX_T: f32 = (1u32 << 30) as f32;
pub(crate) const MAX_T_LOG2: i32 = 30;

/// The depth comparison `new CMP stored` of Microsoft, "Depth Buffering (Windows CE 5.0)" (D3DMCMPFUNC). For the W-buffer, smaller is
/// nearer, so `Less` keeps the nearest surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compare {
    /// Never passes.
    Never,
    /// `new < stored`.
    Less,
    /// `new == stored`.
    Equal,
    /// `new <= stored`.
    LessEqual,
    /// `new > stored`.
    Greater,
    /// `new != stored`.
    NotEqual,
    /// `new >= stored`.
    GreaterEqual,
    /// Always passes.
    Always,
}

impl Compare {
    /// The comparison on two stored codes (of any width).
    #[inline(always)]
    pub fn test<T: PartialOrd>(self, new: T, stored: T) -> bool {
        match self {
            Compare::Never => false,
            Compare::Less => new < stored,
            Compare::Equal => new == stored,
            Compare::LessEqual => new <= stored,
            Compare::Greater => new > stored,
            Compare::NotEqual => new != stored,
            Compare::GreaterEqual => new >= stored,
            Compare::Always => true,
        }
    }
}

/// What the depth buffer holds, like the Windows CE "Depth Buffering" docs' `D3DMRS_ZENABLE` (FALSE / TRUE / USEW).
/// The format decides what it can store: W formats hold W, Z formats Z. Asking for W with a Z format falls back to Z
/// (Dunlop's "Using W-Buffers" capability check: `USEW` if the device can, else `TRUE`), and the draw says so
/// ([`crate::Resolved`]); asking for Z with a W format is an error. Without a depth buffer depth is off, whatever is
/// asked (the Windows CE "Depth Buffering" docs: depth buffering needs a depth buffer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthMode {
    /// No depth test, no depth write (`D3DZB_FALSE`).
    Off,
    /// Z buffering (`D3DZB_TRUE`).
    Z,
    /// W buffering (`D3DZB_USEW`).
    W,
}

/// Which screen-space winding is dropped. Pixel y grows downwards, so "clockwise" is as seen on the display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cull {
    /// Draw both windings.
    None,
    /// Drop triangles whose vertices run clockwise on screen.
    Cw,
    /// Drop triangles whose vertices run counter-clockwise on screen (Direct3D's default).
    Ccw,
}

/// The eye-space depth range `[W_near, W_far]`, checked: `0 < W_near < W_far`, both finite, ratio at most [`MAX_T`].
/// Seed Rogers, "W-Buffering in Direct3D" (NVIDIA): "W_near must be greater than zero. W_far must be greater than W_near."
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthRange {
    near: f32,
    far: f32,
    /// `floor(far / near * 2^TMAX_FRAC)`, so that `t_max(frac)` is a shift (a floor of a floor by a power of two).
    t_max_q: u128,
}

/// Fraction bits of [`DepthRange`]'s stored `far / near`: at least the largest `frac` a triangle uses (61).
const TMAX_FRAC: u32 = 64;

impl DepthRange {
    /// Checks and stores the range.
    pub fn new(w_near: f32, w_far: f32) -> Result<Self, Error> {
        let (nn, mn, en) = split(w_near).ok_or(Error::NonFinite)?;
        let (nf, mf, ef) = split(w_far).ok_or(Error::NonFinite)?;
        if nn || nf || mn == 0 || w_far <= w_near {
            return Err(Error::InvalidDepthRange);
        }
        // far/near <= 2^30  <=>  mf * 2^ef <= mn * 2^(en + 30), compared exactly.
        let lhs = mf as u128;
        let sh = en + MAX_T_LOG2 - ef;
        let ok = if sh >= 0 {
            sh >= 100 || lhs <= (mn as u128) << sh
        } else {
            (-sh) < 100 && lhs <= (mn as u128) >> (-sh)
        };
        if !ok {
            return Err(Error::InvalidDepthRange);
        }
        // far/near = mf / mn * 2^(ef - en) exactly (the f32 mantissas); it is below 2^31, so the quotient is below 2^95.
        let (ratio_m, ratio_d, ratio_e) = (mf as u64, mn as u64, ef - en);
        let e = ratio_e + TMAX_FRAC as i32;
        let t_max_q = if e >= 0 {
            div_u128((ratio_m as u128) << e, ratio_d)
        } else {
            div_u128((ratio_m as u128) >> (-e).min(127), ratio_d)
        };
        Ok(DepthRange {
            near: w_near,
            far: w_far,
            t_max_q,
        })
    }
    /// `W_near`.
    pub fn near(&self) -> f32 {
        self.near
    }
    /// `W_far`.
    pub fn far(&self) -> f32 {
        self.far
    }
    /// `floor(far / near * 2^frac)`: the largest `T = t * 2^frac` still at or beyond the near plane.
    /// Saturates at `i64::MAX`, not `u64::MAX`: a plane value is an `i64` (below `2^62` where it is meaningful), and a
    /// rounding just below zero (a vertex `t` that rounds to 0, `W` beyond `2^61 W_far`) wraps to a `u64` above
    /// `i64::MAX`, which the range test must refuse. (A fuzz finding: with `2^frac W_far / W_near` above `2^64` the
    /// bound saturated at `u64::MAX` and let such a span into the fast loop, whose shift overflowed.)
    ///
    /// In 64-bit pieces (a variable `u128` shift is a long sequence on the 32-bit cores): `t_max_q < 2^95`
    /// (`far / near <= 2^30` with 64 fraction bits), so its high part `hi = t_max_q >> 32` is below `2^63`, and
    /// `t_max_q / 2^s = hi 2^(32 - s) + floor(lo / 2^s)` for `s < 32`, at least `2^63` exactly when `hi >= 2^(31 + s)`;
    /// for `s >= 32` the low part adds less than one unit before the floor.
    pub(crate) fn t_max(&self, frac: u32) -> u64 {
        let (hi, lo) = ((self.t_max_q >> 32) as u64, self.t_max_q as u32);
        let s = TMAX_FRAC - frac.min(TMAX_FRAC); // 0..=64
                                                 // Variable shifts in 32-bit pieces on the Cortex-M0 (`crate::fast::shl64`).
        use crate::fast::{bits64, shl64, shr64};
        if s >= 32 {
            shr64(hi, s - 32)
        } else if if crate::fast::NO_CLZ {
            shr64(hi, 31 + s) != 0
        } else {
            bits64(hi) > 31 + s
        } {
            // `hi >= 2^(31 + s)`: by its bit count where the core counts leading zeros (M4 W3 -0.3%), by the shift
            // where it does not (the bit count's search measured W3 +1.3% on the M0, +3.6% on RV32 with the change
            // below in `small::constants`).
            i64::MAX as u64
        } else {
            shl64(hi, 32 - s) | (lo >> s) as u64
        }
    }
}

/// Everything a draw call needs besides the geometry and the buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderState {
    /// The depth range; W outside it is not drawn.
    pub range: DepthRange,
    /// Depth buffering asked for (see [`DepthMode`]).
    pub mode: DepthMode,
    /// The depth comparison.
    pub compare: Compare,
    /// Whether passing pixels store their depth.
    pub depth_write: bool,
    /// Face culling.
    pub cull: Cull,
    /// Constant depth bias, in W16 codes (feature `bias`; the Windows CE "Depth Buffering" docs' DEPTHBIAS). Negative pulls towards the eye.
    #[cfg(feature = "bias")]
    pub depth_bias: f32,
    /// Slope-scaled depth bias (feature `bias`; the Windows CE "Depth Buffering" docs' SLOPESCALEDEPTHBIAS), times the triangle's `m`.
    #[cfg(feature = "bias")]
    pub slope_scale_depth_bias: f32,
}

impl RenderState {
    /// Whether a depth bias is set (feature `bias`; never without it).
    #[inline(always)]
    pub(crate) fn has_bias(&self) -> bool {
        #[cfg(feature = "bias")]
        return self.depth_bias != 0.0 || self.slope_scale_depth_bias != 0.0;
        #[cfg(not(feature = "bias"))]
        false
    }

    /// W buffering, `Less`, depth write on, no culling, over `[w_near, w_far]`.
    pub fn new(w_near: f32, w_far: f32) -> Result<Self, Error> {
        Ok(RenderState {
            range: DepthRange::new(w_near, w_far)?,
            mode: DepthMode::W,
            compare: Compare::Less,
            depth_write: true,
            cull: Cull::None,
            #[cfg(feature = "bias")]
            depth_bias: 0.0,
            #[cfg(feature = "bias")]
            slope_scale_depth_bias: 0.0,
        })
    }
}

/// `n / (f - n)` as `k / 2^s` with `k` in `[2^31, 2^33)` (truncated: relative error below `2^-31`), for the reversed
/// Z `rz = (t - 1) n / (f - n)`.
#[derive(Clone, Copy)]
pub(crate) struct ZConst {
    k: u64,
    s: i32,
}

impl ZConst {
    pub(crate) fn new(range: &DepthRange) -> Self {
        // Both are positive and finite (checked by DepthRange).
        let (_, nm, ne) = split(range.near()).unwrap_or((false, 1, 0));
        let (_, fm, fe) = split(range.far()).unwrap_or((false, 2, 0));
        let e = ne.min(fe);
        // f / n <= 2^30 and both mantissas are below 2^24, so the aligned values stay below 2^(24 + 30 + 24).
        let nv = (nm as u128) << (ne - e).min(100);
        let fv = (fm as u128) << (fe - e).min(100);
        let d = (fv - nv).max(1);
        let bits = |v: u128| 128 - v.leading_zeros() as i32;
        let s = 32 + bits(d) - bits(nv);
        let k = if s >= 0 {
            (nv << s as u32) / d
        } else {
            (nv >> (-s) as u32) / d
        };
        ZConst { k: k as u64, s }
    }
    /// `rz * 2^60` of `T = t 2^frac` (signed: negative beyond the far plane), saturated to `[-2^62, 2^62]`.
    #[inline(always)]
    pub(crate) fn rz60(&self, t: u64, frac: u32) -> i64 {
        let d = t as i128 - (1i128 << frac);
        let p = d * self.k as i128; // |d| < 2^62, k < 2^33
        let sh = self.s + frac as i32 - 60;
        let v = if sh >= 0 {
            p >> sh.min(127)
        } else {
            p << (-sh).min(40)
        };
        v.clamp(-(1 << 62), 1 << 62) as i64
    }
    /// D3D Z in Q0.60 of a pixel in range (`t` in `[1, f/n]`).
    #[inline(always)]
    pub(crate) fn z60(&self, t: u64, frac: u32) -> u64 {
        ((1i64 << 60) - self.rz60(t, frac)).clamp(0, 1 << 60) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `t_max` in 64-bit pieces equals its definition, `min(floor(t_max_q / 2^(64 - frac)), 2^63 - 1)` in `u128`, at
    /// every `frac` for ranges from the narrowest to the widest allowed (the saturation included: wide ranges at
    /// large `frac`).
    #[test]
    fn t_max_is_its_u128_definition() {
        let mut rnd = crate::xorshift(0x5eed_0f7a_c0de_1234);
        let mut ranges = std::vec![
            (1.0f32, 1.0000001f32),
            (1.0, 2.0),
            (0.5, 100.0),
            (1.0, (1u32 << 30) as f32)
        ];
        for _ in 0..20_000 {
            let near = f32::from_bits(0x3000_0000 + (rnd() % 0x1800_0000) as u32);
            let ratio = 1.0 + (rnd() % (1 << 30)) as f32 / (1u32 << (rnd() % 31) as u32) as f32;
            ranges.push((near, near * ratio));
        }
        let mut checked = 0;
        for (near, far) in ranges {
            let Ok(r) = DepthRange::new(near, far) else {
                continue;
            };
            for frac in 0..=70 {
                let want =
                    (r.t_max_q >> (TMAX_FRAC - frac.min(TMAX_FRAC))).min(i64::MAX as u128) as u64;
                assert_eq!(r.t_max(frac), want, "near {near} far {far} frac {frac}");
            }
            checked += 1;
        }
        assert!(checked > 19_000, "{checked}");
    }
}
