//! Depth storage formats: what a code means, in eye-space depth. Each format is a type, so a build links only the
//! ones it names. These are the formats' definitions (encode with round to nearest, decode, the step between
//! neighbouring codes, packed storage), in f64: the reference every renderer and the precision tool measure against.
//!
//! Sources: Rogers, "W-Buffering in Direct3D" (NVIDIA) (the table: 16-bit float W with scale 2^8, 16-bit fixed W with scale 1.0,
//! 24-bit float W stored directly or scaled by 2^127 / W_far: `W_scaled = W / W_far * scale_factor`), seed
//! Microsoft, "W-Buffering" (Direct3D DDK) (24-bit: IEEE single without the low mantissa byte; 32-bit IEEE), seed
//! Dunlop, "Linear Depth" (linear Z, `z * w / far`), and Direct3D's `[0, 1]` Z, `Z = f / (f - n) * (1 - n / d)`.
//! `n`, `f` are `W_near`, `W_far`; `d` is eye depth. Depths outside `[n, f]` saturate to the end codes.

/// One pixel's storage in a depth buffer: `u16` (2-byte formats), `[u8; 3]` (3-byte formats, little-endian, no
/// padding) or `u32` (4-byte formats). A [`crate::DepthBuffer`] of format `F` borrows a slice of `F::Word`.
pub trait Storage: Copy + Default + PartialEq + core::fmt::Debug {
    /// The word holding `code` (below `2^(8 BYTES)`).
    fn from_code(code: u32) -> Self;
    /// The code this word holds.
    fn code(self) -> u32;
}

impl Storage for u16 {
    #[inline(always)]
    fn from_code(code: u32) -> Self {
        code as u16
    }
    #[inline(always)]
    fn code(self) -> u32 {
        self as u32
    }
}

impl Storage for [u8; 3] {
    #[inline(always)]
    fn from_code(code: u32) -> Self {
        let b = code.to_le_bytes();
        [b[0], b[1], b[2]]
    }
    #[inline(always)]
    fn code(self) -> u32 {
        u32::from_le_bytes([self[0], self[1], self[2], 0])
    }
}

impl Storage for u32 {
    #[inline(always)]
    fn from_code(code: u32) -> Self {
        code
    }
    #[inline(always)]
    fn code(self) -> u32 {
        self
    }
}

/// A depth storage format.
pub trait DepthFormat {
    /// Name, as the precision tool prints it.
    const NAME: &'static str;
    /// Bytes per pixel of packed storage.
    const BYTES: usize;
    /// A pixel's storage: [`Storage`] of `BYTES` bytes.
    type Word: Storage;
    /// Largest code.
    const MAX_CODE: u32;
    /// The code of eye depth `d` (round to nearest).
    fn encode(d: f64, n: f64, f: f64) -> u32;
    /// The eye depth a code stands for.
    fn decode(code: u32, n: f64, f: f64) -> f64;
    /// The stored quantity as a fraction of its full scale (the value at the far plane for W, Z itself for Z).
    fn fraction(code: u32, n: f64, f: f64) -> f64;
    /// The eye-space distance between the code of `d` and its neighbour (towards larger codes; at the last code,
    /// towards smaller ones): what the format can resolve at `d`.
    fn step(d: f64, n: f64, f: f64) -> f64 {
        let c = Self::encode(d, n, f);
        let o = if c < Self::MAX_CODE { c + 1 } else { c - 1 };
        (Self::decode(o, n, f) - Self::decode(c, n, f)).abs()
    }
    /// Writes `code` little-endian into `out[..BYTES]` (real 2-, 3- or 4-byte storage).
    fn pack(code: u32, out: &mut [u8]) {
        out[..Self::BYTES].copy_from_slice(&code.to_le_bytes()[..Self::BYTES]);
    }
    /// Reads a code written by [`DepthFormat::pack`].
    fn unpack(bytes: &[u8]) -> u32 {
        let mut b = [0u8; 4];
        b[..Self::BYTES].copy_from_slice(&bytes[..Self::BYTES]);
        u32::from_le_bytes(b)
    }
}

/// `round(x)` for `x >= 0`, ties up, clamped to `[0, max]` (no `f64::round` in `core`). Below `max < 2^32`,
/// `floor(x)` and the fraction `x - floor(x)` are exact; `x + 0.5` is not (it rounds `0.5 - 2^-54` up to 1).
fn unorm(x: f64, max: u32) -> u32 {
    if x.is_nan() || x <= 0.0 {
        0
    } else if x >= max as f64 {
        max
    } else {
        let t = x as u32;
        if x - t as f64 >= 0.5 {
            t + 1
        } else {
            t
        }
    }
}

fn clamp_d(d: f64, n: f64, f: f64) -> f64 {
    if d < n {
        n
    } else if d > f {
        f
    } else {
        d
    }
}

/// D3D's `[0, 1]` Z of eye depth `d`.
pub fn z_of(d: f64, n: f64, f: f64) -> f64 {
    f / (f - n) * (1.0 - n / d)
}

/// Eye depth of a D3D Z value.
pub fn d_of_z(z: f64, n: f64, f: f64) -> f64 {
    n / (1.0 - z * (f - n) / f)
}

/// Reversed Z (near 1, far 0), computed directly rather than as `1 - Z`: `n (f/d - 1) / (f - n)`.
pub fn rz_of(d: f64, n: f64, f: f64) -> f64 {
    n * (f / d - 1.0) / (f - n)
}

macro_rules! unorm_format {
    ($(#[$m:meta])* $t:ident, $name:literal, $bytes:literal, $word:ty, $max:expr, $enc:expr, $dec:expr) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct $t;
        impl DepthFormat for $t {
            const NAME: &'static str = $name;
            const BYTES: usize = $bytes;
            type Word = $word;
            const MAX_CODE: u32 = $max;
            fn encode(d: f64, n: f64, f: f64) -> u32 {
                let v: fn(f64, f64, f64) -> f64 = $enc;
                unorm(v(clamp_d(d, n, f), n, f) * $max as f64, $max)
            }
            fn decode(code: u32, n: f64, f: f64) -> f64 {
                let g: fn(f64, f64, f64) -> f64 = $dec;
                g(code as f64 / $max as f64, n, f)
            }
            fn fraction(code: u32, _n: f64, _f: f64) -> f64 {
                code as f64 / $max as f64
            }
        }
    };
}

unorm_format!(
    /// Linear W, 16-bit unorm: `round(W / W_far * 65535)` (Rogers: "16-bit fixed, scale 1.0"). The core's format.
    W16, "W16", 2, u16, 0xffff, |d, _n, f| d / f, |v, _n, f| v * f
);
unorm_format!(
    /// D3D Z, 16-bit unorm.
    Z16, "Z16", 2, u16, 0xffff, z_of, d_of_z
);
unorm_format!(
    /// D3D Z, 24-bit unorm (3 bytes).
    Z24, "Z24", 3, [u8; 3], 0xff_ffff, z_of, d_of_z
);
unorm_format!(
    /// Linear Z in a 16-bit Z buffer: the value of Dunlop's "Linear Depth" `z * w / far` trick at a vertex, `(d - n) / (f - n)`.
    LZ16, "LZ16", 2, u16, 0xffff, |d, n, f| (d - n) / (f - n), |v, n, f| n + v * (f - n)
);

/// The 16-bit float W of Rogers's table ("16-bit floating point, scale 2^8"): unsigned E4M12 (4-bit exponent,
/// bias 7, 12-bit mantissa, implicit one; largest value 511.9375), storing `W / W_far * 2^8`. Values below the
/// smallest normal, `2^-6`, are denormals (`m / 4096 * 2^-6`): with `f / n <= 2^14` every depth is normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct W16F;

impl W16F {
    /// Largest representable value.
    pub const MAX_VALUE: f64 = 511.9375;
    /// The stored value of a code.
    pub fn value(code: u32) -> f64 {
        let (e, m) = (code >> 12, (code & 0xfff) as f64 / 4096.0);
        if e == 0 {
            m * pow2(-6)
        } else {
            (1.0 + m) * pow2(e as i32 - 7)
        }
    }
}

/// `2^e` exactly, for `|e| < 1000`.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

impl DepthFormat for W16F {
    const NAME: &'static str = "W16F";
    const BYTES: usize = 2;
    type Word = u16;
    const MAX_CODE: u32 = 0xffff;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        let v = clamp_d(d, n, f) / f * 256.0;
        if v < pow2(-6) {
            // denormal: code = round(v / 2^-18); 4096 carries into the smallest normal, as in IEEE
            return unorm(v / pow2(-18), 1 << 12);
        }
        let e = ((v.to_bits() >> 52) as i32) - 1023; // floor(log2 v), v normal in f64
        let m = v / pow2(e) - 1.0; // [0, 1)
                                   // the mantissa may round up to 4096: adding it to the exponent field carries, keeping codes monotone
        (((e + 7) as u32) << 12) + unorm(m * 4096.0, 4096)
    }
    fn decode(code: u32, _n: f64, f: f64) -> f64 {
        Self::value(code) / 256.0 * f
    }
    fn fraction(code: u32, _n: f64, _f: f64) -> f64 {
        Self::value(code) / 256.0
    }
}

/// f32 bits of a positive value with the low mantissa byte rounded off (the DDK's "W-Buffering" 24-bit float).
fn f24_of(v: f64) -> u32 {
    ((v as f32).to_bits() + 0x80) >> 8
}

fn f24_value(code: u32) -> f64 {
    f32::from_bits(code << 8) as f64
}

/// The 24-bit float W (the DDK's "W-Buffering": an IEEE single without its low mantissa byte, 3 bytes), W stored directly
/// (Rogers's first option: "load the W value in directly", losing the low mantissa bits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct W24F;

impl DepthFormat for W24F {
    const NAME: &'static str = "W24F";
    const BYTES: usize = 3;
    type Word = [u8; 3];
    const MAX_CODE: u32 = 0x7f_7fff;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        f24_of(clamp_d(d, n, f))
    }
    fn decode(code: u32, _n: f64, _f: f64) -> f64 {
        f24_value(code)
    }
    fn fraction(code: u32, _n: f64, f: f64) -> f64 {
        f24_value(code) / f
    }
}

/// The 24-bit float W scaled by `2^127 / W_far` (Rogers's second option), so the far plane is `2^127`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct W24FScaled;

impl DepthFormat for W24FScaled {
    const NAME: &'static str = "W24F-scaled";
    const BYTES: usize = 3;
    type Word = [u8; 3];
    const MAX_CODE: u32 = 0x7f_7fff;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        f24_of(clamp_d(d, n, f) / f * pow2(127))
    }
    fn decode(code: u32, _n: f64, f: f64) -> f64 {
        f24_value(code) / pow2(127) * f
    }
    fn fraction(code: u32, _n: f64, _f: f64) -> f64 {
        f24_value(code) / pow2(127)
    }
}

/// IEEE single W (the DDK's "W-Buffering" 32-bit format), 4 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct W32F;

impl DepthFormat for W32F {
    const NAME: &'static str = "W32F";
    const BYTES: usize = 4;
    type Word = u32;
    const MAX_CODE: u32 = 0x7f7f_ffff;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        (clamp_d(d, n, f) as f32).to_bits()
    }
    fn decode(code: u32, _n: f64, _f: f64) -> f64 {
        f32::from_bits(code) as f64
    }
    fn fraction(code: u32, _n: f64, f: f64) -> f64 {
        f32::from_bits(code) as f64 / f
    }
}

/// IEEE single D3D Z, 4 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Z32F;

impl DepthFormat for Z32F {
    const NAME: &'static str = "Z32F";
    const BYTES: usize = 4;
    type Word = u32;
    const MAX_CODE: u32 = 0x3f80_0000;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        (z_of(clamp_d(d, n, f), n, f) as f32).to_bits()
    }
    fn decode(code: u32, n: f64, f: f64) -> f64 {
        d_of_z(f32::from_bits(code) as f64, n, f)
    }
    fn fraction(code: u32, _n: f64, _f: f64) -> f64 {
        f32::from_bits(code) as f64
    }
}

/// Reversed float Z (near 1, far 0; compare reversed), the modern baseline: IEEE single of `n (f/d - 1) / (f - n)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RZ32F;

impl DepthFormat for RZ32F {
    const NAME: &'static str = "RZ32F";
    const BYTES: usize = 4;
    type Word = u32;
    const MAX_CODE: u32 = 0x3f80_0000;
    fn encode(d: f64, n: f64, f: f64) -> u32 {
        (rz_of(clamp_d(d, n, f), n, f) as f32).to_bits()
    }
    fn decode(code: u32, n: f64, f: f64) -> f64 {
        f / (1.0 + f32::from_bits(code) as f64 * (f - n) / n)
    }
    fn fraction(code: u32, _n: f64, _f: f64) -> f64 {
        f32::from_bits(code) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGES: [(f64, f64); 5] = [
        (1.0, 10.0),
        (10.0, 1000.0),
        (10.0, 10000.0),
        (0.1, 1e5),
        (1e-3, 1e3),
    ];

    fn depths(n: f64, f: f64) -> impl Iterator<Item = f64> {
        (0..=2000).map(move |k| n * (f / n).powf(k as f64 / 2000.0))
    }

    /// Round to nearest: the decoded depth is within half the step to the nearer neighbouring code (plus f64
    /// rounding and, for the float formats, the f32 rounding of the input, 2^-24 relative); codes are monotone.
    fn round_trip<F: DepthFormat>() {
        for (n, f) in RANGES {
            let mut last: Option<u32> = None;
            for d in depths(n, f) {
                let c = F::encode(d, n, f);
                let back = F::decode(c, n, f);
                let up = if c < F::MAX_CODE {
                    (F::decode(c + 1, n, f) - back).abs()
                } else {
                    f64::MAX
                };
                let down = if c > 0 {
                    (F::decode(c - 1, n, f) - back).abs()
                } else {
                    f64::MAX
                };
                let tol = 0.5
                    * up.max(if down == f64::MAX { 0.0 } else { down })
                        .min(f64::MAX)
                    + d * 1e-7;
                assert!(
                    (back - d).abs() <= tol,
                    "{} n={n} f={f} d={d}: code {c} decodes to {back}",
                    F::NAME
                );
                if let Some(p) = last {
                    // W and Z codes grow with depth; reversed Z shrinks
                    let ok = if F::NAME == "RZ32F" { c <= p } else { c >= p };
                    assert!(ok, "{} not monotone at d={d}", F::NAME);
                }
                last = Some(c);
            }
        }
    }

    #[test]
    fn every_format_rounds_to_nearest_and_is_monotone() {
        round_trip::<W16>();
        round_trip::<W16F>();
        round_trip::<W24F>();
        round_trip::<W24FScaled>();
        round_trip::<W32F>();
        round_trip::<Z16>();
        round_trip::<Z24>();
        round_trip::<Z32F>();
        round_trip::<RZ32F>();
        round_trip::<LZ16>();
    }

    /// `unorm` rounds to nearest, ties up, and clamps: at the ties, at the largest f64 below one half (where
    /// `x + 0.5` itself rounds up to 1), next to `max`, and outside `[0, max]` and at NaN.
    #[test]
    fn unorm_rounds_to_nearest() {
        let below_half = 0.5 - f64::EPSILON / 4.0; // 0.5 - 2^-54
        for (x, max, want) in [
            (below_half, 10, 0),
            (0.5, 10, 1),
            (1.5, 10, 2),
            (2.5, 10, 3),
            (2.499_999_999, 10, 2),
            (9.5, 10, 10),
            (9.499_999, 10, 9),
            (10.0, 10, 10),
            (1e300, 10, 10),
            (-0.4, 10, 0),
            (f64::NAN, 10, 0),
            (4_294_967_294.5, u32::MAX, u32::MAX),
            (4_294_967_293.25, u32::MAX, 4_294_967_293),
        ] {
            assert_eq!(unorm(x, max), want, "{x}");
        }
    }

    /// The step at the last code is the distance to the code below it, and elsewhere to the code above. The last
    /// code is the far plane's for W16 and the Z formats and the near plane's for reversed Z; the float W formats put
    /// the far plane below their largest value (W16F's is 256, code `0xF000`), so no depth in range reaches it.
    #[test]
    fn step_at_the_last_code_looks_down() {
        fn check<F: DepthFormat>(reaches_last: bool) {
            let (n, f) = (10.0, 1000.0);
            let at = |c: u32| F::decode(c, n, f);
            let up = |c: u32| (at(c + 1) - at(c)).abs();
            for d in [if F::NAME == "RZ32F" { n } else { f }, (n * f).sqrt()] {
                let c = F::encode(d, n, f);
                let want = if c == F::MAX_CODE {
                    (at(c) - at(c - 1)).abs()
                } else {
                    up(c)
                };
                assert_eq!(F::step(d, n, f), want, "{} {d}", F::NAME);
            }
            let last = F::encode(if F::NAME == "RZ32F" { n } else { f }, n, f);
            assert_eq!(last == F::MAX_CODE, reaches_last, "{}", F::NAME);
        }
        check::<W16>(true);
        check::<W16F>(false);
        check::<W24F>(false);
        check::<W24FScaled>(false);
        check::<W32F>(false);
        check::<Z16>(true);
        check::<Z24>(true);
        check::<Z32F>(true);
        check::<RZ32F>(true);
        check::<LZ16>(true);
    }

    /// W16's step is `W_far / 65535` everywhere (the precision notes in ARCHITECTURE.md: unorm W, constant step).
    #[test]
    fn w16_step_is_constant() {
        for (n, f) in RANGES {
            for d in depths(n, f).step_by(50) {
                let s = W16::step(d, n, f);
                assert!((s / (f / 65535.0) - 1.0).abs() < 1e-9, "{d}: {s}");
            }
        }
    }

    /// E4M12 as Rogers defines it: the far plane is 256 (code 0xF000), the largest value 511.9375,
    /// the smallest normal 2^-6 (code 0x1000), and every depth is normal exactly while f / n <= 2^14.
    #[test]
    fn w16f_layout() {
        assert_eq!(W16F::value(0xffff), W16F::MAX_VALUE);
        assert_eq!(W16F::encode(1000.0, 1.0, 1000.0), 0xf000);
        assert_eq!(W16F::value(0x1000), 1.0 / 64.0);
        assert_eq!(W16F::value(0x0fff), 4095.0 / 4096.0 / 64.0);
        assert!(
            W16F::encode(1.0, 1.0, 16384.0) >= 0x1000,
            "f/n = 2^14: near is the smallest normal"
        );
        // (at 16385 the near value 4095.75 / 2^18 still rounds up to the smallest normal)
        assert!(
            W16F::encode(1.0, 1.0, 16400.0) < 0x1000,
            "beyond 2^14 the near depths go denormal"
        );
    }

    /// Float formats with m stored mantissa bits resolve between `d 2^-(m+1)` and `d 2^-m` while normal
    /// (the precision notes in ARCHITECTURE.md: float W, constant relative step): m = 12 (W16F), 15 (24-bit), 23 (32-bit).
    #[test]
    fn float_w_relative_steps() {
        fn check<F: DepthFormat>(m: i32) {
            let (n, f) = (10.0, 10000.0);
            for d in depths(n, f).take(1990) {
                let r = F::step(d, n, f) / d;
                let (lo, hi) = (
                    2f64.powi(-(m + 1)) * (1.0 - 1e-3),
                    2f64.powi(-m) * (1.0 + 1e-3),
                );
                assert!(r >= lo && r <= hi, "{} d={d}: relative step {r:e}", F::NAME);
            }
        }
        check::<W16F>(12);
        check::<W24F>(15);
        check::<W24FScaled>(15);
        check::<W32F>(23);
    }

    /// Packed storage is 2, 3 or 4 bytes and round-trips every code's low bytes; a buffer's word (`F::Word`) is
    /// `BYTES` bytes and holds every code, whose little-endian bytes are the ones `pack` writes.
    #[test]
    fn packing() {
        fn check<F: DepthFormat>(bytes: usize) {
            assert_eq!(F::BYTES, bytes);
            assert_eq!(core::mem::size_of::<F::Word>(), bytes);
            for c in [0, 1, 0x5a, F::MAX_CODE / 3, F::MAX_CODE - 1, F::MAX_CODE] {
                let w = F::Word::from_code(c);
                assert_eq!(w.code(), c);
                let mut b = [0u8; 4];
                F::pack(c, &mut b);
                let mem = match bytes {
                    2 => (w.code() as u16).to_le_bytes().to_vec(),
                    _ => w.code().to_le_bytes()[..bytes].to_vec(),
                };
                assert_eq!(&mem[..], &b[..bytes], "{} {c}", F::NAME);
            }
            for c in [0, 1, F::MAX_CODE / 3, F::MAX_CODE - 1, F::MAX_CODE] {
                let mut b = [0xAAu8; 4];
                F::pack(c, &mut b);
                assert_eq!(F::unpack(&b), c);
                assert!(
                    b[bytes..].iter().all(|&x| x == 0xAA),
                    "wrote past its bytes"
                );
            }
        }
        check::<W16>(2);
        check::<W16F>(2);
        check::<Z16>(2);
        check::<LZ16>(2);
        check::<W24F>(3);
        check::<W24FScaled>(3);
        check::<Z24>(3);
        check::<W32F>(4);
        check::<Z32F>(4);
        check::<RZ32F>(4);
    }
}
