//! The fast tier's W16 span loop ([`crate::recip::Fast`]): 32-bit arithmetic per pixel, a derived bound of well
//! under one code, and the depth test ahead of the reciprocal wherever the stored depth already rules a pixel out.
//!
//! **Scaling.** The W16 code is `c = round(65535 / t) = round(2^(F+16) / V)` with `V = T * 65536/65535`: folding the
//! 65535 into the walked value makes the code a power-of-two shift of the reciprocal. `V` and its step are formed
//! once per span (`x / 65535 = x (2^-16 + 2^-32 + 2^-48 + ...)`, shifts and adds, after normalising `T` to 63 bits:
//! error below `2^-59` relative) and walked in 64 bits (`ADDS`/`ADC`), so no error builds up along the span. The
//! high word is `tau`, normalised per binade: in `[2^31, 2^32)` when `T` falls along the span (`DOWN`), in
//! `[2^30, 2^31)` when it rises (`UP`), so leaving the binade is the top bit changing (one flag test per pixel).
//! Then `x = 2^X / tau` (`X = 61` down, `60` up) lies in `(2^29, 2^30]`, and `c = (x + 2^(s-1)) >> s` with
//! `s = X + 16 - F - lz` (`lz` the normalising shift): two instructions.
//!
//! **The reciprocal.** With `Divide` (`FastDiv`), on a binade where `tau` changes by at most `2^-8` of itself per
//! pixel (*chained*), `x` is carried from pixel to pixel: the seed `x_k + (x_k - x_(k-1))` (a linear extrapolation,
//! relative error at most `2 r^2 (1 + 2^-6)` for a relative step `r`, plus three times the carried error), then one
//! Newton-Raphson step `x' = x - x (tau x - 1)`, which squares the seed's error and adds the products' truncation.
//! Steeper binades, and every pixel with `Chord` (`Fast`, [`Chord`] says why), take a fresh reciprocal per pixel
//! (a seed and one step). How each strategy seeds and steps is its
//! [`FreshSeed`]: `Divide` in 32 x 32 -> 64 products (`UMULL`, `SMMUL`), `Chord` in products that fit 32 bits (the
//! Cortex-M0's `MULS`). [`FAST_MAX_REL_ERROR`] is the bound over all of them, derived below and swept in the tests;
//! times 65535 it is the largest code error: `2^-11.2` LSB (`65535 * 6.5e-9 = 4.3e-4`).
//!
//! **The test before the reciprocal.** With the `Less` comparison, a pixel whose stored code `s` satisfies
//! `2^G / tau >= s` (`G = X - s`) fails whatever the rounding, since the computed code errs by far less than 1/2.
//! With `A = tau >> 17` (so `tau < (A + 1) 2^17`) that is implied by `(A + 1) s <= 2^(G - 17)`, and that by
//! `A s <= 2^(G-17) (1 - 2^-13) - 1` (`A >= 2^13`): one multiply and a compare. After the first failing pixel the loop only runs this test; the first pixel it cannot rule out gets a
//! fresh reciprocal and the real test. So a pixel is written exactly when its computed code is below the stored
//! one, as in the plain loop, and hidden fragments cost no reciprocal.

use embedded_graphics_core::draw_target::DrawTarget;

use crate::runs::Runs;
use crate::sentinel::{with_sentinel, Cursor};
use crate::Error;

/// Largest relative error of the fast tier's `x` against the exact `2^X / tau_exact` (`tau_exact` the unrounded
/// high word of the exact `V`), over both modes (only `Divide` chains):
/// - fresh: `< 2^-27.6` (`Divide`: a division seed and a 64-bit step) or `< 2^-27.9` (`Chord`: a 17-bit chord
///   seed and the half-word step, [`half_step`]);
/// - chained, `Divide`: seed error `e_s <= 2 r^2 (1 + 2^-6) + 3 e` with `r <= 2^-8`, so `e_s < 2^-14.9` for any
///   `e <= 2^-20`; the step gives `e_s^2 + 2^-29` (truncated `tau x` product: one unit of `2^-29` in the residual)
///   `+ 2^-29` (truncated `SMMUL`) `< 2^-27.6`; the fixed point of `e = (2^-14.9 + 3e)^2 + 2^-28` stays below
///   `2^-27.5`;
/// - `tau` itself: the truncated high word is below the exact one by less than one unit of `2^-30` relative.
///
/// Sum: `2^-27.5 + 2^-30 < 2^-27.2`.
pub const FAST_MAX_REL_ERROR: f64 = 6.5e-9; // 2^-27.2 = 6.46e-9

/// Shorter spans take the per-pixel reciprocal (the exact tier's loop): below this the fast loop's span set-up costs
/// more than it saves (measured on the M4 board's small scene, whose spans are 3 pixels long).
pub(crate) const MIN_SPAN: usize = 8;

/// Per-binade constants: the code shift and rounding, and the prefilter's limit.
struct Bin {
    s: u32,
    round: u32,
    lim: u32,
}

impl Bin {
    /// The constants of the binade of `lz` (`frac` the span's fraction bits). On a fast span the code's shift
    /// `s = X + 16 - frac - lz` lies in `[13, 31]`: every `T` walked (and the one a step past the last pixel) is at
    /// least `2^frac (3/4)` (`T >= t_lo = 2^frac` in range, and a tame step is at most `T_min / 4`), so `v`'s binade
    /// has `lz <= 63 - frac` (`v = V 2^lz < 2^64`, `V >= T`), `s >= 13`; `s >= 32` only where every code of the
    /// binade is 0 (far / near above `2^17`). There the shift, the rounding and the limit take a few instructions
    /// (`g - 17 = X - 17 - s` in `[12, 31]`: no clamp, and `l - l / 2^13 >= 2^12`: no saturation); any other `s`
    /// takes [`Bin::general`], out of line (the same values: a unit test compares them over every `frac` and `lz`).
    /// Measured on the M4 (`FastDiv`, `--features size-probe`): W1 731,960 -> 724,800 instructions (-1.0%), W2
    /// 4,266,320 -> 4,179,800 (-2.0%); RV32 W2 -1.3%. The M0 keeps the general computation inline (below).
    /// ([`Bin::shift`], in `fresh_run`'s loop, keeps its clamps inline: there the out-of-line call measured W1 +7%.)
    #[inline(always)]
    fn new<const UP: bool>(frac: u32, lz: i32) -> Bin {
        let x_bits = if UP { 60 } else { 61 };
        let s = x_bits + 16 - frac as i32 - lz;
        if NO_WIDE {
            // The Cortex-M0 keeps the general computation inline: the split measured within 0.2% there, and it
            // grew the mesh draw's stack frame by 68 bytes (W4's deepest stack to 212 bytes from the statics, under
            // CI's 256).
            Bin::general_inline::<UP>(frac, lz)
        } else if (s - 13) as u32 <= 18 {
            let l = 1u32 << (x_bits - 17 - s);
            Bin {
                s: s as u32,
                round: 1 << (s - 1),
                lim: l - (l >> 13) - 1,
            }
        } else {
            Bin::general::<UP>(frac, lz)
        }
    }
    /// [`Bin::new`] for any `frac` and `lz`, out of line.
    #[cold]
    #[inline(never)]
    fn general<const UP: bool>(frac: u32, lz: i32) -> Bin {
        Bin::general_inline::<UP>(frac, lz)
    }
    /// [`Bin::general`] inline.
    #[inline(always)]
    fn general_inline<const UP: bool>(frac: u32, lz: i32) -> Bin {
        let x_bits = if UP { 60 } else { 61 };
        let s = x_bits + 16 - frac as i32 - lz;
        // G = X - s; the exact code is 2^G / tau.
        let g = x_bits - s;
        // (A + 1) s <= 2^(G-17) is implied by A s <= L (1 - 2^-13) - 1, since A >= 2^13 (tau >= 2^30), so
        // (A + 1) s <= A s (1 + 2^-13): the compare needs no +1.
        let lim = if g < 17 {
            0
        } else {
            let l = 1u32 << (g - 17).min(31);
            (l - (l >> 13)).saturating_sub(1)
        };
        let (s, round) = Bin::shift::<UP>(frac, lz);
        Bin { s, round, lim }
    }
    /// The code's shift and rounding on the binade of `lz` (`c = (x + round) >> s`), [`Bin::new`]'s, for any `frac`
    /// and `lz` (inline: see [`Bin::new`]).
    #[inline(always)]
    fn shift<const UP: bool>(frac: u32, lz: i32) -> (u32, u32) {
        let x_bits = if UP { 60 } else { 61 };
        let s = x_bits + 16 - frac as i32 - lz;
        if s >= 32 {
            // x <= 2^30 (1 + 2^-27): every code on this binade is round(x / 2^s) = 0, which x >> 31 gives.
            (31, 0)
        } else {
            (s.max(1) as u32, 1 << (s.max(1) - 1))
        }
    }
    #[inline(always)]
    fn code(&self, x: i32) -> u16 {
        ((x as u32).wrapping_add(self.round) >> self.s) as u16
    }
}

/// Whether the stored code `stored` rules out any computed code below it (`Less` fails for sure), with the binade's
/// prefilter limit `lim` ([`Bin`]).
#[inline(always)]
fn ruled_out(tau: u32, stored: u16, lim: u32) -> bool {
    (tau >> 17) * stored as u32 <= lim
}

/// Cells of the division-free seed: 256 over `d = m / 2^32` in `[1/2, 1)`.
const CELLS: usize = 256;

/// Per cell `[a, b)`, `a = 1/2 + k/512`, `b = a + 1/512`, one word `y << 11 | drop`: `y = 2^19 / a` lowered by half
/// the chord's largest gap, plus 4 (so that the seed's `>> 3` rounds), and `drop = (2^19 / a - 2^19 / b) / 2`, both
/// rounded. The chord of the convex `1/d` lies above it by `(d - a)(b - d) / (a b d) <= (b - a)^2 / (4 a^2 b)` (in
/// units of `1/d`), so the halved chord errs by at most `(b - a)^2 / (8 a^2 b)`: below one unit of `2^-19` at `a = 1/2`.
/// `y < 2^21` and `drop < 2^11` (`2^19 (1/a - 1/b) <= 2^12 (1 - 2^-8)`), so both fit one `u32`.
const fn seed_table() -> [u32; CELLS] {
    let mut t = [0u32; CELLS];
    let mut k = 0;
    while k < CELLS {
        let a = 0.5 + k as f64 / 512.0;
        let b = a + 1.0 / 512.0;
        let q = (1u64 << 19) as f64;
        let gap = (b - a) * (b - a) / (4.0 * a * a * b);
        let y = ((1.0 / a - gap / 2.0) * q + 4.0 + 0.5) as u32;
        let drop = ((1.0 / a - 1.0 / b) * q / 2.0 + 0.5) as u32;
        t[k] = y << 11 | drop;
        k += 1;
    }
    t
}

/// How a strategy's fast loops take the reciprocal `2^61 / m` (`m` in `[2^31, 2^32)`, `x` in `(2^29, 2^30]`): fresh,
/// or carried from the previous pixel. A type, so that each strategy's loops are compiled with one reciprocal and link
/// no other. Both implementations err by less than `2^-27.6` relative (derived at each, swept in the tests), so the fast
/// tier's bound [`FAST_MAX_REL_ERROR`] holds for either. They differ in the last bits of `x`, so a strategy's frames
/// are the same on every core only with the same reciprocal: each is its own strategy ([`crate::recip::Fast`],
/// [`crate::recip::FastDiv`]).
pub(crate) trait FreshSeed: Sized {
    /// Whether the chained loop carries `x` from pixel to pixel on a binade whose step of `v` (the walked 64-bit
    /// value) is `dv`: at most the strategy's bound on `r = |dv| / v`. A strategy that never chains says `false` (a
    /// constant: its loops are compiled without the chained one).
    fn chains<const UP: bool>(dv: i64) -> bool;
    /// `2^61 / m`, fresh.
    fn fresh61(m: u32) -> i32;
    /// `2^X / tau` (`X = 60` up, `61` down) from the extrapolated seed `xs`, whose relative error is below
    /// `2 r^2 (1 + 2^-6) + 3 e` for the step bound `r` of [`FreshSeed::chains`] (`e` the previous pixel's error). A
    /// strategy that never chains is not asked; for it, the fresh reciprocal.
    #[inline(always)]
    fn chain<const UP: bool>(tau: u32, _xs: i32) -> i32 {
        fresh::<UP, Self>(tau)
    }
}

/// The Cortex-M0's reciprocal (the default strategy, [`crate::recip::Fast`]): no division, and no product wider than
/// the 32 bits `MULS` keeps. A 256-cell chord seed of 17 bits, then one Newton-Raphson step whose three products are
/// 17 x 15, 14 x 17 and 15 x 16 bits ([`half_step`]), where a 32-bit seed would need two 32 x 32 -> 64 products (four
/// `MULS` and their carries each, about 45 instructions per pixel on the M0).
///
/// Seed: `X = y - ((drop u) >> 10)` with `u` the 11 bits of `m` below the cell index (one `MULS`: `drop u < 2^22`),
/// then `x0 = X >> 3` (rounded by the table's `+4`). Error of `X`, relative (`X > 2^19`): the halved chord
/// `(b - a)^2 / (8 a b) < 2^-19`; `y` rounded, `2^-20`; `drop` rounded, doubled, one unit: `2^-19`; the position's
/// 12 dropped bits, `2^-11` of the cell's drop `2^19 (1/a - 1/b) < X 2^-8`: `2^-19`; the product's floor, `2^-19`.
/// Sum `4.5 2^-19 < 2^-16.8`; then `x0`'s rounding, half a unit of `x0 > 2^16`: `|delta| < 2^-16.8 + 2^-17 <
/// 2^-15.9`. The step then gives `< 2^-27.9` ([`half_step`]).
///
/// It never chains: the chained loop (the extrapolated seed rounded to 17 bits and the same step, within bound for
/// `r <= 2^-9`) took 54 instructions a pixel on the M0 against the fresh loop's 50 (its carried values spill from
/// the eight low registers), and without it (and with [`quarter_product`]'s residual) the M0's W1 went from 64.9 to
/// 62.7 instructions a pixel and W2 from 39.9 to 39.0 a fragment.
pub(crate) struct Chord;

impl FreshSeed for Chord {
    #[inline(always)]
    fn chains<const UP: bool>(_dv: i64) -> bool {
        false
    }
    #[inline(always)]
    fn fresh61(m: u32) -> i32 {
        half_step(m, chord_seed(m))
    }
}

/// [`Chord`]'s seed `x0`, near `2^48 / m` (within `2^-15.9`): [`chord_unmasked`] on the Cortex-M0, [`chord_masked`]
/// elsewhere (the same bits; a unit test compares them).
#[inline(always)]
fn chord_seed(m: u32) -> u32 {
    if cfg!(all(target_arch = "arm", not(target_has_atomic = "32"))) {
        chord_unmasked(m)
    } else {
        chord_masked(m)
    }
}

/// [`chord_seed`] as defined: the cell `(m >> 23) & 255` and `u`, the 11 bits below it, by masks (the cores other
/// than the M0 extract a field in one instruction).
#[inline(always)]
fn chord_masked(m: u32) -> u32 {
    const T: [u32; CELLS] = seed_table();
    let w = T[((m >> 23) & 255) as usize];
    let u = (m << 9) >> 21;
    ((w >> 11) - (((w & 2047) * u) >> 10)) >> 3
}

/// [`chord_seed`] without a mask, for the Cortex-M0, which has no immediate for one (each a constant loaded and a
/// register held: measured W1 62.7 -> 59.7 instructions a pixel, W2 39.0 -> 38.0 a fragment against [`chord_masked`]). Its table has 512 cells whose
/// first half is never read, indexed by `c = m >> 23` alone (`256 + k`); and with `m >> 12 = 2048 c + u`,
/// `(drop (m >> 12)) >> 10 = ((drop u) >> 10) + 2 c drop` exactly (the added product is a multiple of `2^10`), so
/// the cell holds `y' = y + 2 c drop` (below `2^21`, checked as the table is built) with `drop` on top: the same `X`
/// from `m >> 12` unmasked (`drop (m >> 12) < 2^31`).
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn chord_unmasked(m: u32) -> u32 {
    const T: [u32; 2 * CELLS] = {
        let (mut t, s) = ([0u32; 2 * CELLS], seed_table());
        let mut k = 0;
        while k < CELLS {
            let (y, drop) = (s[k] >> 11, s[k] & 2047);
            let y2 = y + 2 * (CELLS + k) as u32 * drop;
            assert!(y2 < 1 << 21);
            t[CELLS + k] = drop << 21 | y2;
            k += 1;
        }
        t
    };
    let w = T[(m >> 23) as usize];
    let drop = w >> 21;
    // `w - P = X + drop 2^21` (`X > 0`), and `drop 2^21` is a multiple of 8: `X >> 3` is `((w - P) >> 3) - drop 2^18`
    // (taken so rather than by masking `w`, which would load the mask).
    ((w - ((drop * (m >> 12)) >> 10)) >> 3) - (drop << 18)
}

/// One Newton-Raphson step on `2^61 / m` from a 17-bit seed `x0` near `2^48 / m` with relative error `|delta| <
/// 2^-15.5` (`x0 <= 2^17 + 5`), in 32-bit products only. With `m = mh 2^14 + ml` (`mh` 18 bits, `ml` 14), the
/// residual `E = 2^48 - m x0 = 2^48 delta'` (`|E| < 2^32.5`) is formed as `e = E >> 2 = -((mh x0) << 12) - ((ml x0)
/// >> 2)` modulo `2^32` ([`quarter_product`], which the M0 forms from other pieces of `m`, the same bits) (exact: `|e| < 2^30.5`; `ml x0 < 2^14 (2^17 + 5) < 2^32` does not wrap; the first product
/// may, harmlessly), and `x = x0 2^13 (1 + delta') = (x0 << 13) + floor((x0 >> 2)(e >> 15) / 2^16)` (the product is
/// below `2^15.1 2^15.5 < 2^31`).
///
/// Error relative to `2^61 / m`: the step leaves `delta^2 < 2^-31`; `x0 >> 2` drops at most 3 units of `x0 >= 2^16`
/// from the correction (itself `|delta| x`): `3 2^-16 2^-15.5 < 2^-29.9`; the floors of `E >> 2` and `e >> 15`
/// below `2^17` units of `E`, `2^-31`; the final floor one unit of `x > 2^29`, `2^-29` (rounding it would halve
/// that for two more instructions a pixel on the M0). Sum `(0.47 + 1.0 + 0.47 + 1.87) 10^-9 < 2^-27.9`.
#[inline(always)]
fn half_step(m: u32, x0: u32) -> i32 {
    let e = 0u32.wrapping_sub(quarter_product(m, x0)) as i32;
    let corr = ((x0 >> 2) as i32 * (e >> 15)) >> 16;
    ((x0 << 13) as i32).wrapping_add(corr)
}

/// `floor(m x0 / 4)` modulo `2^32` for `x0 < 2^18` ([`half_step`]'s residual), from 32-bit products. On the
/// Cortex-M0 as `(m >> 2) x0 + floor((m & 3) x0 / 4)` (`m = 4 a + b`: `m x0 / 4 = a x0 + b x0 / 4`), whose 14-bit
/// mask it has no immediate for (measured: M0 W1 64.7 -> 62.7 instructions a pixel); elsewhere as
/// `(m >> 14) x0 2^12 + floor((m & 0x3fff) x0 / 4)` (the M4's W4 0.2% lower so). The same bits (a unit test compares
/// them).
#[inline(always)]
fn quarter_product(m: u32, x0: u32) -> u32 {
    if NO_WIDE {
        (m >> 2).wrapping_mul(x0).wrapping_add(((m & 3) * x0) >> 2)
    } else {
        quarter_by_halves(m, x0)
    }
}

/// [`quarter_product`] by `m`'s 18 high and 14 low bits (`(m & 0x3fff) x0 < 2^32`).
#[inline(always)]
fn quarter_by_halves(m: u32, x0: u32) -> u32 {
    ((m >> 14).wrapping_mul(x0) << 12).wrapping_add(((m & 0x3fff) * x0) >> 2)
}

/// The division seed, for cores with a divide instruction (the Cortex-M3/M4, RV32IM): `2^13 floor((2^32 - 1) / d)`
/// with `d = floor(m / 2^16)` (in `[2^15, 2^16)`), one `UDIV`, then a Newton-Raphson step in 32 x 32 -> 64 products
/// ([`newton`]: `UMULL`, `SMMUL`). `d` lies below `m / 2^16` by less than one unit (`2^-15` of it), so `2^45 / d`
/// exceeds `2^61 / m` by less than `2^-15 (1 + 2^-14)`; the quotient's floor (of a value of at least `2^16`) and
/// `2^32 - 1` for `2^32` lower it by less than `2^-16 + 2^-32`: the seed errs by less than `2^-15 (1 + 2^-14)` either
/// way, so the step gives `(2^-14.99)^2 + 2^-28 < 2^-27.6`. Chained (`r <= 2^-8`), the same step from the
/// extrapolated seed ([`FAST_MAX_REL_ERROR`]'s derivation).
pub(crate) struct Divide;

impl Divide {
    #[inline(always)]
    fn seed61(m: u32) -> i32 {
        // `m >= 2^31`, so bit 15 of `m >> 16` is already set: the OR only tells the compiler the divisor is not 0 (and
        // it drops the OR where a dominating test already tells it `m >= 2^31`: [`fresh_run`]'s downward loop).
        let d =
            core::num::NonZeroU32::new((m >> 16) | 1 << 15).unwrap_or(core::num::NonZeroU32::MIN);
        ((0xFFFF_FFFF / d) << 13) as i32
    }
}

impl FreshSeed for Divide {
    /// `r <= 2^-8`: `|dv| <= 2^55` at the downward binade's scale `[2^63, 2^64)`, half that upward (`[2^62, 2^63)`).
    #[inline(always)]
    fn chains<const UP: bool>(dv: i64) -> bool {
        dv.unsigned_abs() <= if UP { 1 << 54 } else { 1 << 55 }
    }
    #[inline(always)]
    fn fresh61(m: u32) -> i32 {
        newton::<false>(m, Self::seed61(m))
    }
    #[inline(always)]
    fn chain<const UP: bool>(tau: u32, xs: i32) -> i32 {
        newton::<UP>(tau, xs)
    }
}

/// `2^61 / m` for `m` in `[2^31, 2^32)`, the strategy's fresh reciprocal: `< 2^-27.6` ([`FreshSeed`]).
#[inline(always)]
pub(crate) fn fresh61<S: FreshSeed>(m: u32) -> i32 {
    S::fresh61(m)
}

/// `2^X / tau`, fresh (no previous pixel).
#[inline(always)]
fn fresh<const UP: bool, S: FreshSeed>(tau: u32) -> i32 {
    // Up: 2^60 / tau = 2^61 / (2 tau), and 2 tau is in [2^31, 2^32).
    fresh61::<S>(if UP { tau << 1 } else { tau })
}

/// One Newton-Raphson step on `2^X / tau` from the seed `xs` (relative error `e_s < 2^-14.8`), in 32 x 32 -> 64
/// products: `e_s^2` plus the two products' truncation, one unit of `2^-29` each.
#[inline(always)]
fn newton<const UP: bool>(tau: u32, xs: i32) -> i32 {
    let p = mul_hi(tau, xs as u32); // tau xs / 2^32, about 2^(X - 32)
    let e = (p << if UP { 4 } else { 3 }) as i32; // (tau xs / 2^X - 1) 2^32, small
    xs.wrapping_sub(smul_hi(xs, e))
}

/// The high word of the 64-bit product (`UMULL` where the core has it).
#[inline(always)]
pub(crate) fn mul_hi(a: u32, b: u32) -> u32 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    return mul_hi_halves(a, b);
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    return ((a as u64 * b as u64) >> 32) as u32;
}

/// The high word of the signed 64-bit product (`SMMUL` where the core has it).
#[inline(always)]
fn smul_hi(a: i32, b: i32) -> i32 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    return smul_hi_halves(a, b);
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    return ((a as i64 * b as i64) >> 32) as i32;
}

/// The exact high word of `a b` from four 16 x 16 -> 32 products: ARMv6-M (Cortex-M0/M0+) has only `MULS`, which keeps
/// the low 32 bits, and a 64-bit product is a library call there (about 45 instructions). The high word of
/// [`mul_wide_halves`]: the same bits as the 64-bit product, so frames stay bit-identical across cores. (Written as
/// the high word's own sum, [`halves_hi`], LLVM recognised a 64-bit product and called the library again unless a
/// half was made opaque, a store and a load each time; this way measured on the M0: W4 -0.7%, W3 -0.3%.)
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn mul_hi_halves(a: u32, b: u32) -> u32 {
    (mul_wide_halves(a, b) >> 32) as u32
}

/// The high word of `a b` from the halves `ah`, `al` of `a` (made opaque once, by [`HiFactor`]): `ah bh + (al bh >>
/// 16) + (ah bl >> 16)` plus the carry out of the middle column, `((al bl >> 16) + (al bh & 0xffff) + (ah bl &
/// 0xffff)) >> 16` (below `3 2^16`, no overflow). (The carries of [`mul_wide_halves`] instead: the M0's W4 +0.5%.)
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn halves_hi(ah: u32, al: u32, b: u32) -> u32 {
    let (bh, bl) = (b >> 16, b & 0xffff);
    let (lh, hl) = (al * bh, ah * bl);
    let mid = ((al * bl) >> 16) + (lh & 0xffff) + (hl & 0xffff);
    (ah * bh) + (lh >> 16) + (hl >> 16) + (mid >> 16)
}

/// A factor of many [`mul_hi`] products (a loop's constant), prepared once before the loop: on the Cortex-M0 its
/// 16-bit halves, made opaque to LLVM here ([`halves_hi`]: otherwise it recognises a 64-bit product and calls the
/// library). The same bits as [`mul_hi`] on every core.
#[derive(Clone, Copy)]
pub(crate) struct HiFactor {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    halves: (u32, u32),
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    a: u32,
}

impl HiFactor {
    /// The factor `a`.
    #[inline(always)]
    pub(crate) fn new(a: u32) -> Self {
        #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
        return HiFactor {
            halves: core::hint::black_box((a >> 16, a & 0xffff)),
        };
        #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
        return HiFactor { a };
    }
    /// The high word of `a b` (as [`mul_hi`]).
    #[inline(always)]
    pub(crate) fn mul_hi(self, b: u32) -> u32 {
        #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
        return halves_hi(self.halves.0, self.halves.1, b);
        #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
        return mul_hi(self.a, b);
    }
}

/// The signed high word from the unsigned one: `a b = ua ub - 2^32 (b [a < 0] + a [b < 0])` modulo `2^64`.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn smul_hi_halves(a: i32, b: i32) -> i32 {
    let h = mul_hi_halves(a as u32, b as u32) as i32;
    let h = if a < 0 { h.wrapping_sub(b) } else { h };
    if b < 0 {
        h.wrapping_sub(a)
    } else {
        h
    }
}

/// The first-order difference `x_(k+1) - x_k = -x r`, `r = delta / tau = delta x / 2^X`, to start the extrapolation.
#[inline(always)]
fn slope<const UP: bool>(x: i32, delta: i32) -> i32 {
    let shift = if UP { 28 } else { 29 };
    // 32-bit products (`smul_hi`, four `MULS` on the M0 rather than `__aeabi_lmul` calls), the same bits as the
    // 64-bit products wherever the slope is used: a chaining binade, `|delta| <= 2^24` ([`FreshSeed::chains`]), so
    // `|r32| < 2^25`. (On a steeper binade `r32` may not fit and the slope is garbage, unused: a chained binade
    // after it takes a fresh slope, `walk`.)
    let p = smul_wide(delta, x);
    let r32 = (p >> shift) as i32;
    smul_hi(x, r32)
        .wrapping_neg()
        .wrapping_sub(i32::from(x.wrapping_mul(r32) != 0))
}

/// The exact signed 64-bit product from 32-bit pieces ([`smul_hi`] and one wrapping multiply: no `__aeabi_lmul` call
/// on the Cortex-M0).
#[inline(always)]
pub(crate) fn smul_wide(a: i32, b: i32) -> i64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    return smul_wide_halves(a, b);
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    return ((smul_hi(a, b) as i64) << 32) | (a.wrapping_mul(b) as u32 as i64);
}

/// [`smul_wide`] on the Cortex-M0: the unsigned product of the bits ([`mul_wide_halves`], whose low word is the
/// signed product's), its high word corrected as in [`smul_hi_halves`] (`a b = ua ub - 2^32 (b [a < 0] + a [b < 0])`
/// modulo `2^64`): four multiplies, not five.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn smul_wide_halves(a: i32, b: i32) -> i64 {
    let w = mul_wide_halves(a as u32, b as u32);
    let mut hi = (w >> 32) as u32;
    if a < 0 {
        hi = hi.wrapping_sub(b as u32);
    }
    if b < 0 {
        hi = hi.wrapping_sub(a as u32);
    }
    ((hi as u64) << 32 | (w as u32 as u64)) as i64
}

/// `a w` modulo `2^64` (the `i64` product's bits): where the core has no 32 x 32 -> 64 multiply (the Cortex-M0), from
/// [`mul_wide`] of the low words and two wrapping multiplies, with `a = ua - 2^32 [a < 0]` and
/// `w = wh 2^32 + wl`: `a w = ua wl + 2^32 (ua wh - wl [a < 0])` modulo `2^64` (no `__aeabi_lmul` call); elsewhere the
/// 64-bit product itself.
#[inline(always)]
pub(crate) fn wmul(a: i32, w: u64) -> u64 {
    if NO_WIDE {
        wmul_pieces(a, w)
    } else {
        (a as i64).wrapping_mul(w as i64) as u64
    }
}

/// The Cortex-M0 (ARMv6-M, which has no 32-bit atomics either): no 32 x 32 -> 64 multiply, and a variable 64-bit
/// shift is a library call (`__aeabi_llsl`/`__aeabi_llsr`, some 15 instructions and a call each).
pub(crate) const NO_WIDE: bool = cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// `v << s` for `s < 64` (the bits shifted out lost): in 32-bit pieces on the Cortex-M0 ([`NO_WIDE`]), where
/// set-up code shifts by a variable amount a dozen times a triangle; the 64-bit shift elsewhere.
#[inline(always)]
pub(crate) fn shl64(v: u64, s: u32) -> u64 {
    debug_assert!(s < 64);
    if NO_WIDE {
        shl_pieces(v, s)
    } else {
        v << s
    }
}

/// `v >> s` for `s < 64`: as [`shl64`].
#[inline(always)]
pub(crate) fn shr64(v: u64, s: u32) -> u64 {
    debug_assert!(s < 64);
    if NO_WIDE {
        shr_pieces(v, s)
    } else {
        v >> s
    }
}

/// [`shl64`] from 32-bit shifts (tested against the 64-bit shift on every host).
#[inline(always)]
fn shl_pieces(v: u64, s: u32) -> u64 {
    let (hi, lo) = ((v >> 32) as u32, v as u32);
    if s >= 32 {
        ((lo << (s - 32)) as u64) << 32
    } else {
        // `lo >> 1 >> (31 - s)`: `lo >> (32 - s)` without a shift by 32 at `s = 0`.
        (((hi << s) | ((lo >> 1) >> (31 - s))) as u64) << 32 | (lo << s) as u64
    }
}

/// [`shr64`] from 32-bit shifts (tested against the 64-bit shift on every host); also `t_at_snapped`'s shift on
/// every core.
#[inline(always)]
pub(crate) fn shr_pieces(v: u64, s: u32) -> u64 {
    let (hi, lo) = ((v >> 32) as u32, v as u32);
    if s >= 32 {
        (hi >> (s - 32)) as u64
    } else {
        ((hi >> s) as u64) << 32 | ((lo >> s) | ((hi << 1) << (31 - s))) as u64
    }
}

/// [`wmul`] in 32-bit pieces (tested against the 64-bit product on every host).
#[inline(always)]
fn wmul_pieces(a: i32, w: u64) -> u64 {
    let (ua, wl, wh) = (a as u32, w as u32, (w >> 32) as u32);
    let hi = ua.wrapping_mul(wh).wrapping_sub(if a < 0 { wl } else { 0 });
    mul_wide(ua, wl).wrapping_add((hi as u64) << 32)
}

/// Whether a binade whose step is `dv` chains ([`FreshSeed::chains`]). Renormalising downward doubles the step, so
/// a binade that does not chain is never followed by one that does when `T` falls.
#[inline(always)]
fn chains<const UP: bool, S: FreshSeed>(dv: i64) -> bool {
    S::chains::<UP>(dv)
}

/// Draws one `Less`, depth-write span whose every pixel is in range and whose step is tame (`|dt| <= T_min / 4`).
/// `t0` is the first pixel's `T` (`t 2^frac`), `dt` the step. Fails are reported to `runs`, passing runs filled.
/// `seg` is the row's coarse bound (feature `coarse`; empty for none) and `x0` the frame column of `row[0]`.
#[inline(always)]
pub(crate) fn span<S: FreshSeed, D: DrawTarget>(
    row: &mut [u16],
    t0: u64,
    dt: i64,
    frac: u32,
    runs: &mut Runs<'_, D>,
    seg: &mut [u16],
    x0: usize,
) -> Result<(), Error> {
    #[cfg(feature = "coarse")]
    if !seg.is_empty() {
        return span_as::<S, D, true>(row, t0, dt, frac, runs, seg, x0);
    }
    span_as::<S, D, false>(row, t0, dt, frac, runs, seg, x0)
}

/// [`span`], with the coarse bound's test (`COARSE`) or without.
#[inline(always)]
fn span_as<S: FreshSeed, D: DrawTarget, const COARSE: bool>(
    row: &mut [u16],
    t0: u64,
    dt: i64,
    frac: u32,
    runs: &mut Runs<'_, D>,
    seg: &mut [u16],
    x0: usize,
) -> Result<(), Error> {
    let c = Coarse { seg, x0 };
    // T normalised to [2^62, 2^63), then V = T + T/65535 (error below 4 units of 2^62).
    let l0 = 64 - bits64(t0) as i32 - 1; // `bits64`: no library call on cores without CLZ
    let tn = t0 << l0;
    let dn = dt << l0;
    let (v, dv) = (by_65535(tn), by_65535_signed(dn));
    if dt >= 0 {
        // tau in [2^30, 2^31): bit 62 on top.
        let (v, dv, lz) = if v >> 63 != 0 {
            (v >> 1, dv >> 1, l0 - 1)
        } else {
            (v, dv, l0)
        };
        walk::<true, S, D, COARSE>(row, v, dv, lz, frac, runs, c)
    } else {
        let (v, dv, lz) = if v >> 63 == 0 {
            (v << 1, dv << 1, l0 + 1)
        } else {
            (v, dv, l0)
        };
        walk::<false, S, D, COARSE>(row, v, dv, lz, frac, runs, c)
    }
}

/// The pixels of a span, binade by binade. State between pixels: in a passing run (`x`, `dx` current) or not.
#[inline(always)]
fn walk<const UP: bool, S: FreshSeed, D: DrawTarget, const COARSE: bool>(
    row: &mut [u16],
    mut v: u64,
    mut dv: i64,
    mut lz: i32,
    frac: u32,
    runs: &mut Runs<'_, D>,
    mut coarse: Coarse<'_>,
) -> Result<(), Error> {
    let n = row.len();
    let (mut x, mut dx) = (0i32, 0i32);
    let mut in_run = false;
    // With `COARSE`: the first pixel of the current passing run.
    let mut run_from = 0usize;
    let mut k = 0usize;
    let crossed = left_binade::<UP>;
    'bins: loop {
        let mut b = Bin::new::<UP>(frac, lz);
        let chain = chains::<UP, S>(dv);
        loop {
            if k >= n {
                break 'bins;
            }
            if in_run {
                // Passing run: reciprocal, code, test, store (one loop per mode, chosen per binade).
                let end = if chain {
                    let r = chain_to_end::<UP, S>(&mut row[k..], v, dv as u64, x, dx, b.round, b.s);
                    (v, x, dx) = (r.v, r.x, r.dx);
                    k += r.k;
                    r.end
                } else {
                    let lz0 = lz;
                    let r = fresh_to_end::<UP, S>(&mut row[k..], v, dv, lz, frac);
                    (v, dv, lz) = (r.v, r.dv, r.lz);
                    k += r.k;
                    let end = r.end;
                    if lz != lz0 && end != End::Binade {
                        // The run crossed binades that do not chain: this binade's constants for what follows.
                        b = Bin::new::<UP>(frac, lz);
                    }
                    // Should the next binade chain (only upward, where the renormalised step halves), its loop
                    // extrapolates from the last pixel drawn: that pixel's reciprocal, in this binade's scale.
                    if UP && end == End::Binade && chains::<UP, S>(dv >> 1) {
                        x = fresh::<UP, S>((v.wrapping_sub(dv as u64) >> 32) as u32);
                        dx = slope::<UP>(x, (dv >> 32) as i32);
                    }
                    end
                };
                let (failed, cross) = (end == End::Fail, end == End::Binade);
                if cross {
                    renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                    continue 'bins;
                }
                if failed {
                    // pixel k fails: close the run before it
                    in_run = false;
                    if COARSE {
                        coarse.lower(row, run_from, k);
                    }
                    runs.fail(k)?;
                    k += 1;
                    v = v.wrapping_add(dv as u64);
                    if crossed(v) {
                        renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                        continue 'bins;
                    }
                }
            } else {
                // Not in a run: the prefilter alone, until a pixel it cannot rule out.
                let start = k;
                let (skipped, vv, end) =
                    skip_run::<UP, COARSE>(&row[k..], v, dv as u64, b.lim, &coarse, k);
                v = vv;
                k += skipped;
                let (maybe, left) = (end == End::Fail, end == End::Binade);
                runs.fail_many(start, k)?;
                if left {
                    renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                    continue 'bins;
                }
                if !maybe {
                    continue;
                }
                // Pixel k: a fresh reciprocal and the real test. The slope only where a chained loop may start from
                // it: on this binade, or upward on the next, where the renormalised step halves (downward it doubles).
                let tau = (v >> 32) as u32;
                x = fresh::<UP, S>(tau);
                if chain || (UP && chains::<UP, S>(dv >> 1)) {
                    dx = slope::<UP>(x, (dv >> 32) as i32);
                }
                let c = b.code(x);
                if c < row[k] {
                    row[k] = c;
                    in_run = true;
                    run_from = k;
                } else {
                    runs.fail(k)?;
                }
                k += 1;
                v = v.wrapping_add(dv as u64);
                if crossed(v) {
                    renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                    continue 'bins;
                }
            }
        }
    }
    if COARSE && in_run {
        coarse.lower(row, run_from, n);
    }
    Ok(())
}

/// Cores without a count-leading-zeros instruction, where `leading_zeros` is a library call: ARMv6-M (Cortex-M0,
/// which has no 32-bit atomics either) and RV32IMAC (no Zbb).
pub(crate) const NO_CLZ: bool = cfg!(any(
    all(target_arch = "arm", not(target_has_atomic = "32")),
    target_arch = "riscv32"
));

/// The leading zeros of `h` in `[2^18, 2^32)`: `CLZ` where the core has it; on the Cortex-M0 and RV32IMAC (no
/// count-leading-zeros instruction; there `leading_zeros` is a library call of about 27 instructions) [`lz_search`].
#[inline(always)]
pub(crate) fn lz_small(h: u32) -> u32 {
    debug_assert!(h >= 1 << 18);
    if NO_CLZ {
        lz_search(h)
    } else {
        h.leading_zeros()
    }
}

/// The bits of `v` (`64 - leading_zeros`, 0 for 0), for set-up code. ARMv6-M (Cortex-M0) and RV32IMAC have no
/// count-leading-zeros instruction: `leading_zeros` is a library call there (`__clzsi2`, about 35 instructions, two of
/// them for a `u64`), so they take [`bits_search`] inline (tested against `leading_zeros`).
#[inline(always)]
pub(crate) fn bits64(v: u64) -> u32 {
    if NO_CLZ {
        bits_search(v)
    } else {
        64 - v.leading_zeros()
    }
}

/// The bit count of each byte value (`8 - leading_zeros`), for [`bits_search`]: 256 bytes of flash.
static BITS8: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut v = 1;
    while v < 256 {
        t[v] = 8 - (v as u8).leading_zeros() as u8;
        v += 1;
    }
    t
};

/// Three compares narrow `v` to a byte, whose bits a table gives (the last three steps of a six-step binary search,
/// which the M0's set-up would otherwise run many times a triangle).
#[inline(always)]
fn bits_search(v: u64) -> u32 {
    let (mut x, mut n) = if v >> 32 != 0 {
        ((v >> 32) as u32, 32)
    } else {
        (v as u32, 0)
    };
    if x >> 16 != 0 {
        x >>= 16;
        n += 16;
    }
    if x >> 8 != 0 {
        x >>= 8;
        n += 8;
    }
    n + BITS8[(x & 0xff) as usize] as u32
}

/// The exact 64-bit product of two `u32`: the high word by [`mul_hi`] and the low by a wrapping multiply where the
/// core multiplies 32 x 32 -> 64 (written as `a as u64 * b as u64`, RV32's W3 measured 0.5% dearer: the same bits),
/// on the Cortex-M0 from four 16 x 16 -> 32 products ([`mul_wide_halves`]) instead of the `__aeabi_lmul` call.
#[inline(always)]
pub(crate) fn mul_wide(a: u32, b: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    return mul_wide_halves(a, b);
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    return ((mul_hi(a, b) as u64) << 32) | a.wrapping_mul(b) as u64;
}

/// `x k` (wrapping, so `x` may be a signed step's bits) for `k < 2^16` (a row or column offset: a span is at most a
/// buffer row, under `2^16` pixels), without a 64-bit multiply (a library call on the Cortex-M0). There the low word's
/// carry takes two 16-bit products instead of [`mul_wide`]'s four: with `x_lo = h 2^16 + l`,
/// `x_lo k = h k 2^16 + l k`, so its high word is `floor((h k + floor(l k / 2^16)) / 2^16)` (floors of floors), and
/// the sum is at most `(2^16 - 1)^2 + 2^16 - 1 < 2^32`. Measured on the M0, with [`HiFactor`]: 2.2% fewer instructions
/// on W3 and 1.6% on W4 (the small triangles' rows and columns). The M4 takes the carry from [`mul_wide`] (one
/// `UMULL`; the two products measured 1.6% more on W3) and adds it to the high word (0.3% fewer on W4 than the 64-bit
/// sum, which RV32 keeps: 0.1% fewer there). Tested against the wrapping 64-bit product.
#[inline(always)]
pub(crate) fn mul_small(x: u64, k: u32) -> u64 {
    debug_assert!(k < 1 << 16);
    let (lo, hi) = (x as u32, ((x >> 32) as u32).wrapping_mul(k));
    if cfg!(target_arch = "arm") {
        let carry = if cfg!(target_has_atomic = "32") {
            (mul_wide(lo, k) >> 32) as u32
        } else {
            carry_halves(lo, k)
        };
        (hi.wrapping_add(carry) as u64) << 32 | lo.wrapping_mul(k) as u64
    } else {
        mul_wide(lo, k).wrapping_add((hi as u64) << 32)
    }
}

/// The high word of `lo k` for `k < 2^16` from two 16-bit products ([`mul_small`]'s Cortex-M0 way; compiled on every
/// core, so the host tests check it).
#[inline(always)]
fn carry_halves(lo: u32, k: u32) -> u32 {
    ((lo >> 16) * k + (((lo & 0xffff) * k) >> 16)) >> 16
}

/// [`mul_wide`] from four 16 x 16 -> 32 products: with `a = ah 2^16 + al` and `b = bh 2^16 + bl`, the middle column
/// `al bh + ah bl` (below `2^33`: its carry is bit 48 of the product), the low word `al bl + (mid << 16)` modulo
/// `2^32` with its carry, and the high word `ah bh + (mid >> 16)` plus both carries (the product is below `2^64`, so
/// nothing overflows). LLVM does not take this for a 64-bit product (it did the high word's own sum, [`halves_hi`]),
/// so no value has to be made opaque. Measured on the M0 against the high word by [`mul_hi`] and a fifth multiply
/// for the low: W4 -1.7%, the terrain -1.3%, W3 -0.5% (the depth-grid correction and the vertices' `T` take several).
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn mul_wide_halves(a: u32, b: u32) -> u64 {
    let (ah, al) = (a >> 16, a & 0xffff);
    let (bh, bl) = (b >> 16, b & 0xffff);
    let (mid, c) = (al * bh).overflowing_add(ah * bl);
    let (lo, c2) = (al * bl).overflowing_add(mid << 16);
    let hi = (ah * bh) + (mid >> 16) + ((c as u32) << 16) + c2 as u32;
    (hi as u64) << 32 | lo as u64
}

/// The leading zeros of `h >= 2^18` (so in `[0, 13]`) by four compares of a binary search (tested against
/// `leading_zeros` on every host).
#[inline(always)]
fn lz_search(h: u32) -> u32 {
    let (mut h, mut n) = (h, 0);
    if h < 1 << 24 {
        n += 8;
        h <<= 8;
    }
    if h < 1 << 28 {
        n += 4;
        h <<= 4;
    }
    if h < 1 << 30 {
        n += 2;
        h <<= 2;
    }
    n + u32::from(h < 1 << 31)
}

/// `x 65536 / 65535` as `x (1 + 2^-16 + 2^-32 + 2^-48)`: the series cut after four terms (below `2^-64` of `x`
/// left out) and each shifted term floored, so at most 4 units below the exact value.
#[inline(always)]
fn by_65535(x: u64) -> u64 {
    x + (x >> 16) + (x >> 32) + (x >> 48)
}

/// [`by_65535`] for a signed step: arithmetic shifts floor too (at most 4 units below), and for a negative step the
/// left-out tail is negative, below one unit, so the result may also be up to one unit above the exact value.
#[inline(always)]
fn by_65535_signed(x: i64) -> i64 {
    x + (x >> 16) + (x >> 32) + (x >> 48)
}

/// How a passing run ended: at a failing pixel (not drawn, not stepped past), with `tau` leaving its binade (past
/// the last pixel drawn), or at the end of the row.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum End {
    Fail,
    Binade,
    Row,
}

/// A chained run's state on leaving: pixels drawn, `v` and the reciprocal state after them, and why it ended.
struct ChainEnd {
    k: usize,
    v: u64,
    x: i32,
    dx: i32,
    end: End,
}

/// A row's coarse bound (feature `coarse`): `seg[i]` is at least every code stored in frame columns
/// `8 i .. 8 i + 8`; `x0` is the frame column of the span's first pixel.
pub(crate) struct Coarse<'a> {
    seg: &'a mut [u16],
    x0: usize,
}

impl Coarse<'_> {
    /// Span pixels `a..b` were all just written by one passing run: lower the bound of each aligned segment they
    /// cover whole to one above the larger of its two end codes. That bounds all eight: the exact codes along a
    /// span are monotone (W is, on a line in screen space), and each computed code is within
    /// `65535 FAST_MAX_REL_ERROR < 2^-11.1` of its exact value, so a middle code `round(y_m)` with
    /// `y_m < y_end + 2^-10.1` is at most one above the larger end's.
    #[inline(always)]
    fn lower(&mut self, row: &[u16], a: usize, b: usize) {
        const SEG: usize = crate::depth::SEGMENT;
        let mut s = a + (SEG - (self.x0 + a) % SEG) % SEG;
        while s + SEG <= b {
            if let (Some(px), Some(g)) =
                (row.get(s..s + SEG), self.seg.get_mut((self.x0 + s) / SEG))
            {
                let top = px[0].max(px[SEG - 1]).saturating_add(1);
                *g = (*g).min(top);
            }
            s += SEG;
        }
    }
}

/// The prefilter alone from `row[0]` (span pixel `k0`), out of line like the runs: pixels whose stored code rules
/// them out ([`ruled_out`] with the binade's limit `lim`) are skipped. Returns the pixels skipped, `v` after them,
/// and how it ended: at a pixel the prefilter cannot rule out (`End::Fail`, not stepped past), with `tau` leaving
/// its binade, or at the end of the row.
///
/// With `COARSE`, an aligned 8-pixel segment wholly in the span and in the binade is first tested as a whole: its
/// largest `tau` against the segment's bound `B`. `ruled_out(tau_max, B)` implies `ruled_out(tau_i, s_i)` for each
/// of its pixels (`tau_i <= tau_max` and `s_i <= B`, and the test is monotone in both), so the segment is skipped in
/// one step exactly when the per-pixel loop would skip all 8 pixels, with the same `v` after them (eight wrapping
/// adds of `dv` are one add of `8 dv`): the frames are the same with the bound and without it.
#[inline(never)]
fn skip_run<const UP: bool, const COARSE: bool>(
    row: &[u16],
    mut v: u64,
    dv: u64,
    lim: u32,
    coarse: &Coarse<'_>,
    k0: usize,
) -> (usize, u64, End) {
    const SEG: usize = crate::depth::SEGMENT;
    let n = row.len();
    if !COARSE {
        return skip_groups::<UP, { !NO_UNALIGNED_WORDS }>(row, v, dv, lim);
    }
    // Pixel by pixel up to the first aligned segment.
    let x0 = coarse.x0 + k0;
    let mut k = ((SEG - x0 % SEG) % SEG).min(n);
    v = match pixels::<UP>(row, 0, k, v, dv, lim) {
        Ok(v) => v,
        Err(end) => return end,
    };
    // tau rises along the span upward, falls downward: a segment's largest is at its last pixel or its first. The
    // last is on this binade when `7 |dv|` is below the room left in it (`|dv| >= 2^61` leaves the binade, `2^62`
    // wide, within 7 steps; below it `7 |dv|` fits in 64 bits).
    let mag = if UP { dv } else { dv.wrapping_neg() };
    let seven = (mag << 3).wrapping_sub(mag);
    let steep = mag >= 1 << 61;
    let mut seg = coarse.seg.get((x0 + k) / SEG..).unwrap_or_default().iter();
    while k + SEG <= n {
        let bound = seg.next().copied().unwrap_or(u16::MAX);
        let room = if UP {
            (1u64 << 63).wrapping_sub(v)
        } else {
            v.wrapping_sub(1u64 << 63)
        };
        if !steep && (if UP { seven < room } else { seven <= room }) {
            // In range (`seven` is below the room left): the wrapping forms only keep a debug build panic-free.
            let last = if UP {
                v.wrapping_add(seven)
            } else {
                v.wrapping_sub(seven)
            };
            if ruled_out(((if UP { last } else { v }) >> 32) as u32, bound, lim) {
                k += SEG;
                v = last.wrapping_add(dv);
                if left_binade::<UP>(v) {
                    return (k, v, End::Binade);
                }
                continue;
            }
        }
        v = match pixels::<UP>(row, k, k + SEG, v, dv, lim) {
            Ok(v) => v,
            Err(end) => return end,
        };
        k += SEG;
    }
    match pixels::<UP>(row, k, n, v, dv, lim) {
        Ok(v) => (n, v, End::Row),
        Err(end) => end,
    }
}

/// Where the prefilter reads a group's stored codes as four aligned words (`WORDS`) or as eight `u16`s: the
/// Cortex-M0 (ARMv6-M), whose eight low registers the word loop spills (M0 W2 +0.8%; the M4's -2.6%).
const NO_UNALIGNED_WORDS: bool = cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// [`skip_run`] without a coarse bound, eight pixels a step: all eight are ruled out when the OR of their stored
/// codes (at least the largest) is with the largest `tau` (the last pixel's upward, the first's downward; upward the
/// value past them stands in for it, larger still) and the step ends on the binade: one multiply, compare and binade
/// test for the eight ([`ruled_out`] is monotone in both). Otherwise the eight are taken one at a time as the pixel
/// loop ([`pixels`]) takes them: the same pixels skipped, the same `v` and end, so the frames are the same (a unit
/// test compares the two on random rows). `WORDS`: the groups are read as four aligned words (`bytemuck`'s safe
/// split finds them; pixels before the first are taken one at a time), else as eight `u16`s from `row[0]`. On the M4's
/// W2 the prefilter went from 11.0 instructions a failing fragment to 6.2 (calls and partial groups included).
#[inline(always)]
fn skip_groups<const UP: bool, const WORDS: bool>(
    row: &[u16],
    mut v: u64,
    dv: u64,
    lim: u32,
) -> (usize, u64, End) {
    let n = row.len();
    // A span's first pixel, or the one after a failing pixel, that the prefilter cannot rule out: at once.
    if let Some(&s0) = row.first() {
        if !ruled_out((v >> 32) as u32, s0, lim) {
            return (0, v, End::Fail);
        }
    }
    // Eight steps stay inside 64 bits where `|dv| < 2^59` (upward `v < 2^63`, downward `v >= 2^63`); a steeper step
    // (over 1/16 of `v` a pixel) leaves the binade within a few pixels anyway: the pixel loop.
    if (if UP { dv } else { dv.wrapping_neg() }) >= 1 << 59 {
        return match pixels::<UP>(row, 0, n, v, dv, lim) {
            Ok(v) => (n, v, End::Row),
            Err(end) => end,
        };
    }
    let dv8 = dv.wrapping_mul(8);
    // The group at `start + 8 i` for `i` in `0..count`, its stored codes' OR from `or(i)`: walked by the group, the
    // index found from what is left; `v` stepped in place (the slow path steps back).
    macro_rules! groups {
        ($start:expr, $count:expr, $iter:expr, $or:expr) => {{
            let (start, count) = ($start, $count);
            let mut it = $iter;
            while let Some(g) = it.next() {
                let first = (v >> 32) as u32;
                v = v.wrapping_add(dv8);
                let top = if UP { (v >> 32) as u32 } else { first };
                #[allow(clippy::redundant_closure_call)]
                let or: u16 = $or(g);
                if ruled_out(top, or, lim) && !left_binade::<UP>(v) {
                    continue;
                }
                let k = start + 8 * (count - 1 - it.len());
                v = match pixels::<UP>(row, k, k + 8, v.wrapping_sub(dv8), dv, lim) {
                    Ok(v) => v,
                    Err(end) => return end,
                };
            }
            start + 8 * count
        }};
    }
    let rest = if WORDS {
        let (head, body, _) = bytemuck::pod_align_to::<u16, [u32; 4]>(row);
        v = match pixels::<UP>(row, 0, head.len(), v, dv, lim) {
            Ok(v) => v,
            Err(end) => return end,
        };
        groups!(head.len(), body.len(), body.iter(), |g: &[u32; 4]| {
            let w = g[0] | g[1] | g[2] | g[3];
            (w | (w >> 16)) as u16
        })
    } else {
        groups!(0, n / 8, row.chunks_exact(8), |g: &[u16]| g[0]
            | g[1]
            | g[2]
            | g[3]
            | g[4]
            | g[5]
            | g[6]
            | g[7])
    };
    match pixels::<UP>(row, rest, n, v, dv, lim) {
        Ok(v) => (n, v, End::Row),
        Err(end) => end,
    }
}

/// The prefilter on `row[a..b]` (the coarse path of [`skip_run`]): `v` after them, or how it ended, with the pixels
/// skipped from `row[0]`.
#[inline(always)]
fn pixels<const UP: bool>(
    row: &[u16],
    a: usize,
    b: usize,
    mut v: u64,
    dv: u64,
    lim: u32,
) -> Result<u64, (usize, u64, End)> {
    for (k, &stored) in row.get(a..b).unwrap_or_default().iter().enumerate() {
        if !ruled_out((v >> 32) as u32, stored, lim) {
            return Err((a + k, v, End::Fail));
        }
        v = v.wrapping_add(dv);
        if left_binade::<UP>(v) {
            return Err((a + k + 1, v, End::Binade));
        }
    }
    Ok(v)
}

/// The passing run from the cursor's pixel with a fresh reciprocal per pixel: its own function, so that its few live values
/// (`v`, its step, the row, the code's rounding and shift) stay in registers. `tau` leaving its binade is handled here
/// (`v`, `dv` and `lz` renormalised, the code's shift and rounding taken again) where the next binade does not chain
/// either: always downward (renormalising doubles the step, [`chains`]), upward where the halved step is still above
/// the bound; a run then continues across binades without returning (on the M4's W1, 642 of its 835 runs ended at
/// a binade). Returns the pixels drawn, `v`, `dv` and `lz` after them, and how it ended ([`End`]; `End::Binade` only
/// where the next binade chains, not yet renormalised; `End::Fail` at a failing pixel or at the sentinel, which
/// [`to_end`] tells apart).
#[inline(never)]
fn fresh_run<const UP: bool, S: FreshSeed>(
    mut px: Cursor<'_>,
    mut v: u64,
    mut dv: i64,
    mut lz: i32,
    frac: u32,
) -> FreshEnd {
    let end = 'bins: loop {
        let (s, round) = Bin::shift::<UP>(frac, lz);
        // One pixel's code.
        let code = |v: u64| {
            let x = fresh::<UP, S>((v >> 32) as u32);
            // Compared as a `u32` (no zero-extension); `x <= 2^30 (1 + 2^-27)`, so the code fits 16 bits.
            (x as u32).wrapping_add(round) >> s
        };
        if !UP {
            // Downward, the binade is also tested before the first pixel (`v` is in it on entry, and the span is tame,
            // so a step leaves at most one binade and one renormalisation brings `v` back: the same pixels):
            // a test then dominates every pixel's reciprocal, so the compiler knows `tau >= 2^31` there, and
            // [`Divide`]'s divisor needs no OR to be nonzero (measured: the M4's W1 loop 17 instructions a pixel to
            // 16, W1 -3.9%, W2 -0.7%; RV32's W1 -3.2%; [`Chord`] within 0.15% on the M4 and M0).
            if !left_binade::<UP>(v) {
                loop {
                    if !px.pass(code(v)) {
                        break 'bins End::Fail;
                    }
                    v = v.wrapping_add(dv as u64);
                    if left_binade::<UP>(v) {
                        break;
                    }
                }
            }
            let (mut x, mut dx) = (0, 0); // no reciprocal carried on this path
            renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
            continue 'bins;
        }
        loop {
            if !px.pass(code(v)) {
                break 'bins End::Fail;
            }
            v = v.wrapping_add(dv as u64);
            if left_binade::<UP>(v) {
                if UP && chains::<UP, S>(dv >> 1) {
                    break 'bins End::Binade;
                }
                let (mut x, mut dx) = (0, 0); // no reciprocal carried on this path
                renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                continue 'bins;
            }
        }
    };
    FreshEnd {
        k: px.pos(),
        v,
        dv,
        lz,
        end,
    }
}

/// [`fresh_run`] over `row` (not empty), to its end: as [`to_end`], but the last pixel, where the run got to it, is
/// taken here rather than by a second call beside a sentinel of its own: its reciprocal, code and step as the loop
/// takes them (`r.v` and `r.lz` are the last pixel's: the loop stopped on it), so the same state as one loop over the
/// row (a unit test compares them). Written out here, not shared with [`fresh_run`]'s loop: with the step as a helper
/// of both, LLVM compiled that loop differently (measured: M4 W2 +0.9%, RV32 W1 +41%); with only the code's line
/// shared, the boards' counts moved both ways by up to 0.2%.
#[inline(always)]
fn fresh_to_end<const UP: bool, S: FreshSeed>(
    row: &mut [u16],
    v: u64,
    dv: i64,
    lz: i32,
    frac: u32,
) -> FreshEnd {
    let n = row.len();
    let r = with_sentinel(row, |px| fresh_run::<UP, S>(px, v, dv, lz, frac));
    let Some(last) = row.last_mut() else {
        return r;
    };
    if r.end != End::Fail || r.k + 1 < n {
        return r;
    }
    let (s, round) = Bin::shift::<UP>(frac, r.lz);
    let c = (fresh::<UP, S>((r.v >> 32) as u32) as u32).wrapping_add(round) >> s;
    if c >= u32::from(*last) {
        return r;
    }
    // `c` is below a `u16`: it fits. Then the step past it, as the loop takes it.
    *last = c as u16;
    let (mut v, mut dv, mut lz) = (r.v.wrapping_add(r.dv as u64), r.dv, r.lz);
    let mut end = End::Row;
    if left_binade::<UP>(v) {
        if UP && chains::<UP, S>(dv >> 1) {
            end = End::Binade;
        } else {
            renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut 0, &mut 0);
        }
    }
    FreshEnd {
        k: n,
        v,
        dv,
        lz,
        end,
    }
}

/// A passing run over `row` (not empty), to its last pixel: `first` walks it to the pixel before the last, which is
/// the sentinel ([`with_sentinel`]); where it got there, `then` walks the last pixel alone, beside a sentinel of its
/// own, from the state `first` left (so the arithmetic of one loop over the row). The pixels drawn, and `End::Row`
/// where every one passed.
#[inline(always)]
fn to_end<R: RunEnd>(
    row: &mut [u16],
    first: impl FnOnce(Cursor<'_>) -> R,
    then: impl FnOnce(Cursor<'_>, &R) -> R,
) -> R {
    let n = row.len();
    let r = with_sentinel(row, first);
    let Some(last) = row.last_mut() else {
        return r;
    };
    if r.end() != End::Fail || r.drawn() + 1 < n {
        return r;
    }
    let mut one = [*last, 0];
    let mut e = with_sentinel(&mut one, |px| then(px, &r));
    *last = one[0];
    let (k, end) = (e.drawn(), e.end());
    e.set(
        r.drawn() + k,
        if end == End::Fail && k == 1 {
            End::Row
        } else {
            end
        },
    );
    e
}

/// A run's pixels drawn and how it ended ([`to_end`]).
trait RunEnd {
    fn drawn(&self) -> usize;
    fn end(&self) -> End;
    fn set(&mut self, drawn: usize, end: End);
}

/// Both runs' states carry `k` and `end`.
macro_rules! run_end {
    ($($t:ty),*) => {$(
        impl RunEnd for $t {
            #[inline(always)]
            fn drawn(&self) -> usize {
                self.k
            }
            #[inline(always)]
            fn end(&self) -> End {
                self.end
            }
            #[inline(always)]
            fn set(&mut self, drawn: usize, end: End) {
                (self.k, self.end) = (drawn, end);
            }
        }
    )*};
}
run_end!(FreshEnd, ChainEnd);

/// A fresh run's state on leaving: pixels drawn, `v`, its step and binade after them, and why it ended.
struct FreshEnd {
    k: usize,
    v: u64,
    dv: i64,
    lz: i32,
    end: End,
}

/// The passing run from the cursor's pixel with the reciprocal carried from pixel to pixel (`x` the previous pixel's,
/// `dx` its difference): the chained loop, out of line like [`fresh_run`], ending as it does.
#[inline(never)]
fn chain_run<const UP: bool, S: FreshSeed>(
    mut px: Cursor<'_>,
    mut v: u64,
    dv: u64,
    mut x: i32,
    mut dx: i32,
    round: u32,
    s: u32,
) -> ChainEnd {
    let end = loop {
        let xn = S::chain::<UP>((v >> 32) as u32, x.wrapping_add(dx));
        let c = (xn as u32).wrapping_add(round) >> s;
        if !px.pass(c) {
            break End::Fail;
        }
        (dx, x) = (xn.wrapping_sub(x), xn);
        v = v.wrapping_add(dv);
        if left_binade::<UP>(v) {
            break End::Binade;
        }
    };
    ChainEnd {
        k: px.pos(),
        v,
        x,
        dx,
        end,
    }
}

/// [`chain_run`] over `row` (not empty), to its end ([`to_end`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn chain_to_end<const UP: bool, S: FreshSeed>(
    row: &mut [u16],
    v: u64,
    dv: u64,
    x: i32,
    dx: i32,
    round: u32,
    s: u32,
) -> ChainEnd {
    to_end(
        row,
        |px| chain_run::<UP, S>(px, v, dv, x, dx, round, s),
        |px, r| chain_run::<UP, S>(px, r.v, dv, r.x, r.dx, round, s),
    )
}

/// Whether stepping `v` left the binade: the top bit set (up) or cleared (down).
#[inline(always)]
fn left_binade<const UP: bool>(v: u64) -> bool {
    if UP {
        (v as i64) < 0
    } else {
        (v as i64) >= 0
    }
}

/// `tau` left its binade: shift `v` and its step by one, and rescale `x` (and its difference) to the new `tau`.
#[cold]
fn renormalise<const UP: bool>(v: &mut u64, dv: &mut i64, lz: &mut i32, x: &mut i32, dx: &mut i32) {
    if UP {
        *v >>= 1;
        *dv >>= 1;
        *lz -= 1;
        *x <<= 1;
        *dx <<= 1;
    } else {
        *v <<= 1;
        *dv <<= 1;
        *lz += 1;
        *x >>= 1;
        *dx >>= 1;
    }
}

/// The leading zeros of `v != 0`, by [`bits64`] (`CLZ` where the core has one, an inline binary search where
/// `leading_zeros` is a library call: the Cortex-M0 and RV32IMAC).
#[inline(always)]
pub(crate) fn clz32(v: u32) -> u32 {
    64 - bits64(v as u64) - 32
}

/// The top 32 bits of `v != 0` and its leading zeros `l`: `v` is `m 2^(32 - l)`, truncated (below `2^-31`), with `m`
/// in `[2^31, 2^32)`. 32-bit shifts only (a variable 64-bit shift is a library call on the 32-bit cores).
#[inline(always)]
pub(crate) fn top32(v: u64) -> (u32, i32) {
    let (hi, lo) = ((v >> 32) as u32, v as u32);
    if hi != 0 {
        let l = clz32(hi);
        let m = if l == 0 {
            hi
        } else {
            (hi << l) | (lo >> (32 - l))
        };
        (m, l as i32)
    } else {
        let l = clz32(lo);
        (lo << l, 32 + l as i32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rnd(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    /// [`Bin::new`] (a few instructions where `s` is in `[13, 31]`) is [`Bin::general`] for every `frac` and `lz` a
    /// span can have and beyond (`s` from -60 to 84), both ways.
    #[test]
    fn bin_constants_are_the_general_ones() {
        fn check<const UP: bool>() -> u32 {
            let mut fast = 0;
            for frac in 0..=64u32 {
                for lz in -8..=72i32 {
                    let (b, g) = (Bin::new::<UP>(frac, lz), Bin::general::<UP>(frac, lz));
                    assert_eq!(
                        (b.s, b.round, b.lim),
                        (g.s, g.round, g.lim),
                        "frac {frac} lz {lz}"
                    );
                    let s = (if UP { 60 } else { 61 }) + 16 - frac as i32 - lz;
                    fast += u32::from((13..=31).contains(&s));
                }
            }
            fast
        }
        // Both ways cover the fast range (each of its 19 values of `s` at many `frac`).
        assert!(check::<true>() > 19 * 40 && check::<false>() > 19 * 40);
    }

    /// The fresh reciprocal over every 2^7-th `m` of `[2^31, 2^32)` and both ends of every seed cell, two-sided,
    /// against the exact `2^61 / m`: each strategy within its derived bound (`Chord` `2^-27.9`, [`half_step`];
    /// `Divide` `2^-27.6`, at [`Divide`]), both inside the tier's; and each seed within the bound its step assumes.
    #[test]
    fn fresh_reciprocal_holds_its_bound() {
        let chord_seed_err = |m: u32| chord_seed(m) as f64 / (2f64.powi(48) / m as f64) - 1.0;
        let divide_seed_err = |m: u32| Divide::seed61(m) as f64 / (2f64.powi(61) / m as f64) - 1.0;
        fresh_holds::<Chord>("chord", 2f64.powf(-27.9), chord_seed_err, 2f64.powf(-15.9));
        fresh_holds::<Divide>(
            "divide",
            2f64.powf(-27.6),
            divide_seed_err,
            2f64.powi(-15) * (1.0 + 2f64.powi(-14)),
        );
    }

    fn fresh_holds<S: FreshSeed>(
        name: &str,
        bound: f64,
        seed_err: impl Fn(u32) -> f64,
        seed_bound: f64,
    ) {
        assert!(bound < FAST_MAX_REL_ERROR);
        let (mut worst, mut worst_seed) = (0.0f64, 0.0f64);
        let mut check = |m: u32| {
            let exact = 2f64.powi(61) / m as f64;
            worst = worst.max((fresh61::<S>(m) as f64 / exact - 1.0).abs());
            worst_seed = worst_seed.max(seed_err(m).abs());
        };
        let mut m: u64 = 1 << 31;
        while m < 1 << 32 {
            check(m as u32);
            m += 1 << 7;
        }
        for k in 0..CELLS as u64 {
            let lo = (1u64 << 31) | (k << 23);
            check(lo as u32);
            check((lo + (1 << 23) - 1) as u32);
        }
        std::println!(
            "fresh ({name}): worst {:.2} bits, bound {:.2}; seed {:.2} bits, bound {:.2}",
            -worst.log2(),
            -bound.log2(),
            -worst_seed.log2(),
            -seed_bound.log2()
        );
        assert!(worst <= bound, "{worst:e}");
        assert!(worst_seed <= seed_bound, "{worst_seed:e}");
    }

    /// The half-word step from any 17-bit seed within the `2^-15.5` it allows (both extremes, and random seeds in
    /// between, for random `m` and both ends of the range), two-sided against `2^61 / m`: within its derived
    /// `2^-27.9`, and no product overflows (overflow checks are on in tests).
    #[test]
    fn half_step_holds_its_bound_from_any_allowed_seed() {
        let allowed = 2f64.powf(-15.5);
        let mut state = 0x5EED_0000_0000_0017_u64;
        let mut worst = 0.0f64;
        let mut check = |m: u32, rel: f64| {
            let x0 = (2f64.powi(48) / m as f64 * (1.0 + rel)).round();
            if (x0 / (2f64.powi(48) / m as f64) - 1.0).abs() > allowed {
                return; // rounding pushed it out of the allowed range
            }
            let exact = 2f64.powi(61) / m as f64;
            worst = worst.max((half_step(m, x0 as u32) as f64 / exact - 1.0).abs());
        };
        for m in [1u32 << 31, (1 << 31) + 1, u32::MAX, u32::MAX - 1] {
            for rel in [-allowed, 0.0, allowed, -allowed * 0.999, allowed * 0.999] {
                check(m, rel);
            }
        }
        for _ in 0..2_000_000 {
            let m = (1u32 << 31) | (rnd(&mut state) as u32 >> 1);
            let f = (rnd(&mut state) >> 11) as f64 / 2f64.powi(53);
            check(m, allowed * (2.0 * f - 1.0));
        }
        std::println!("half step: worst {:.2} bits, bound 27.9", -worst.log2());
        assert!(worst <= 2f64.powf(-27.9), "{worst:e}");
    }

    /// The M0's products from 16-bit halves ([`mul_hi_halves`], [`mul_wide_halves`], [`halves_hi`]) against the
    /// `u64` product of `a` and `b`.
    fn halves_products_are_exact(a: u32, b: u32) {
        let exact = a as u64 * b as u64;
        assert_eq!(mul_hi_halves(a, b), (exact >> 32) as u32, "{a} {b}");
        assert_eq!(mul_wide_halves(a, b), exact, "{a} {b}");
        assert_eq!(
            halves_hi(a >> 16, a & 0xffff, b),
            (exact >> 32) as u32,
            "{a} {b}"
        );
    }

    /// The set-up's bit count and wide product equal `leading_zeros` and the `u64` product (all single bits, their
    /// neighbours, and a million xorshift values).
    #[test]
    fn bits_search_and_the_wide_products_are_exact() {
        let check = |v: u64| {
            assert_eq!(bits_search(v), 64 - v.leading_zeros(), "{v}");
            assert_eq!(bits64(v), 64 - v.leading_zeros(), "{v}");
            let (a, b) = (v as u32, (v >> 32) as u32);
            assert_eq!(mul_wide(a, b), a as u64 * b as u64, "{a} {b}");
            halves_products_are_exact(a, b);
            // The wrapping product of a signed word and a 64-bit value, both signs of `a`.
            // The M0's pieces (the other cores, the host among them, take the 64-bit operations themselves).
            for a in [a as i32, v.rotate_left(17) as i32] {
                let w = v.rotate_right(23);
                assert_eq!(wmul_pieces(a, w), (a as i64).wrapping_mul(w as i64) as u64);
            }
            for s in 0..64 {
                assert_eq!(shl_pieces(v, s), v << s, "{v} << {s}");
                assert_eq!(shr_pieces(v, s), v >> s, "{v} >> {s}");
            }
        };
        for v in [0u64, 1, 2, 3, u64::MAX] {
            check(v);
        }
        for b in 0..64 {
            for v in [1u64 << b, (1u64 << b) - 1, (1u64 << b) + 1] {
                check(v);
            }
        }
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..1_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(x >> (x & 63));
        }
    }

    /// The Cortex-M0's leading-zero search equals `leading_zeros` over its whole domain `[2^18, 2^32)` (every
    /// 2^5-th value, and both ends of every binade).
    #[test]
    fn lz_search_is_leading_zeros() {
        let mut h: u64 = 1 << 18;
        while h < 1 << 32 {
            assert_eq!(lz_search(h as u32), (h as u32).leading_zeros(), "{h}");
            h += 1 << 5;
        }
        for b in 18..32 {
            for h in [1u32 << b, ((1u64 << (b + 1)) - 1) as u32] {
                assert_eq!(lz_search(h), h.leading_zeros(), "{h}");
            }
        }
    }

    #[test]
    fn mul_small_is_the_wrapping_product() {
        // Every `k` below 2^16 (the largest included) with a random `x`, and the extreme low words, where the carry's
        // sum is largest (`(2^16 - 1)^2 + 2^16 - 1`, the bound in the doc).
        let mut rnd = crate::xorshift(0x6D75_6C5F_736D_616C);
        for k in 0..1u32 << 16 {
            for x in [rnd(), u64::MAX, 0xFFFF_FFFF, 0xFFFF_0000_FFFF_FFFF, 1 << 63] {
                let want = x.wrapping_mul(k as u64);
                assert_eq!(mul_small(x, k), want, "{x:#x} {k}");
                assert_eq!(
                    carry_halves(x as u32, k) as u64,
                    (x as u32 as u64 * k as u64) >> 32
                );
            }
        }
    }

    /// `by_65535` is within 4 units below `x 65536 / 65535` (exact in u128/i128 here), for `x` in the range the
    /// span gives it (`T` normalised to `[2^62, 2^63)`), and within `[-1, 4]` units for steps of both signs (a
    /// negative step's left-out tail is below one unit above).
    #[test]
    fn by_65535_is_within_four_units() {
        let mut s = 0xC0FF_EE00_1234_5678u64;
        for _ in 0..100_000 {
            let x = (1u64 << 62) | (rnd(&mut s) >> 2);
            let exact = (x as u128 * 65536).div_euclid(65535);
            let d = exact - by_65535(x) as u128;
            assert!(d <= 4, "{x}: {d}");
            let y = (rnd(&mut s) >> 2) as i64 * if rnd(&mut s).is_multiple_of(2) { 1 } else { -1 };
            let exact = (y as i128 * 65536).div_euclid(65535);
            let d = exact - by_65535_signed(y) as i128;
            assert!((-1..=4).contains(&d), "{y}: {d}");
        }
    }

    /// The seed table is its documented definition, rounded to nearest (a `const fn` cannot call `f64::round`):
    /// cell `k` is `[a, b)`, `a = 1/2 + k/512`, `b = a + 1/512`; `y` is `2^19 / a` lowered by half the gap bound
    /// `(b - a)^2 / (4 a^2 b)` plus 4, `drop` half of `2^19 (1/a - 1/b)`, packed `y << 11 | drop`. (Recomputed here
    /// with `powi` and `round`; the sweep above cannot see a table entry off by a unit, as the Newton step squares the
    /// seed's error away.)
    #[test]
    fn seed_table_is_its_definition_rounded() {
        let q = 2f64.powi(19);
        for (k, &w) in seed_table().iter().enumerate() {
            let a = 0.5 + k as f64 / 512.0;
            let b = a + 2f64.powi(-9);
            let gap = 2f64.powi(-18) / (4.0 * a * a * b);
            let y = ((1.0 / a - gap / 2.0) * q + 4.0).round() as u32;
            let drop = ((1.0 / a - 1.0 / b) * q / 2.0).round() as u32;
            assert!(y < 1 << 21 && drop < 1 << 11, "cell {k}: {y} {drop}");
            assert_eq!(w, y << 11 | drop, "cell {k}");
        }
    }

    /// Chained spans: `tau` walked as the loop walks it (64 bits, renormalised per binade), `x` carried by the
    /// extrapolated seed and one step wherever the binade allows chaining, fresh elsewhere; every pixel's `x` against
    /// the exact `2^X / tau` of the exact 64-bit value, within [`FAST_MAX_REL_ERROR`]. Returns (pixels, chained).
    fn sweep<const UP: bool, S: FreshSeed>() -> (u64, u64) {
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let (mut pixels, mut chained, mut worst) = (0u64, 0u64, 0.0f64);
        for _ in 0..3000 {
            // v normalised as the span set-up leaves it, a step up to a quarter of v, spans up to 400 px.
            let top = if UP { 1u64 << 62 } else { 1u64 << 63 };
            let mut v = top + rnd(&mut state) % top;
            let mag = (v >> 2) >> (rnd(&mut state) % 40);
            let mut dv = (rnd(&mut state) % (mag + 1)) as i64;
            if !UP {
                dv = -dv;
            }
            let mut x = 0i32;
            let mut dx = 0i32;
            let mut have = false;
            for _ in 0..1 + rnd(&mut state) % 400 {
                // Only tame spans reach the loop: |dt| <= T / 4 at every pixel (here, at the same scale).
                if dv.unsigned_abs() > v >> 2 {
                    break;
                }
                let chain = chains::<UP, S>(dv);
                let tau = (v >> 32) as u32;
                let xn = if have && chain {
                    S::chain::<UP>(tau, x.wrapping_add(dx))
                } else if have {
                    // The fresh loop's last pixel, and the slope the chained loop of the next binade starts from.
                    let f = fresh::<UP, S>(tau);
                    x = f.wrapping_sub(slope::<UP>(f, (dv >> 32) as i32));
                    f
                } else {
                    let f = fresh::<UP, S>(tau);
                    dx = slope::<UP>(f, (dv >> 32) as i32);
                    x = f.wrapping_sub(dx); // so that dx = xn - x below
                    f
                };
                chained += u64::from(have && chain);
                have = true;
                dx = xn.wrapping_sub(x);
                x = xn;
                let exact =
                    if UP { 2f64.powi(60) } else { 2f64.powi(61) } / (v as f64 / 2f64.powi(32));
                worst = worst.max((x as f64 / exact - 1.0).abs());
                pixels += 1;
                v = v.wrapping_add(dv as u64);
                if left_binade::<UP>(v) {
                    let mut lz = 0;
                    renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut x, &mut dx);
                }
            }
        }
        std::println!(
            "chained spans ({}): {pixels} pixels, {chained} chained, worst {:.2} bits, bound {:.2}",
            if UP { "up" } else { "down" },
            -worst.log2(),
            -FAST_MAX_REL_ERROR.log2()
        );
        assert!(worst <= FAST_MAX_REL_ERROR, "{worst:e}");
        (pixels, chained)
    }

    #[test]
    fn chained_and_fresh_spans_hold_the_bound() {
        for (pixels, chained) in [sweep::<true, Divide>(), sweep::<false, Divide>()] {
            assert!(chained > pixels / 4, "the sweep must exercise chaining");
        }
        // `Chord` never chains: every pixel fresh.
        for (pixels, chained) in [sweep::<true, Chord>(), sweep::<false, Chord>()] {
            assert!(pixels > 100_000 && chained == 0);
        }
    }

    /// The passing runs walked to a sentinel ([`to_end`]) draw what a loop that counts the row's pixels draws: the
    /// same codes, pixels drawn, state after them and ending, for rows of 1 to 40 pixels whose stored codes end the
    /// run anywhere (or nowhere), with binades left anywhere (the last pixel included).
    fn runs_to_end<const UP: bool, S: FreshSeed>() -> [u32; 3] {
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut ends = [0u32; 3];
        for _ in 0..20_000 {
            let n = 1 + (rnd(&mut state) % 40) as usize;
            let top = if UP { 1u64 << 62 } else { 1u64 << 63 };
            let v0 = top + rnd(&mut state) % top;
            let mag = (v0 >> 2) >> (rnd(&mut state) % 12);
            // Tame, as every span the fast loops take ([`crate::recip::SpanWalker::classify`]): the step at most a
            // quarter of the smallest `v`, so a step leaves at most one binade (downward, `v` at the row's end).
            let mag = if UP {
                mag
            } else {
                mag.min(v0 / (n as u64 + 3))
            };
            let dv0 = (rnd(&mut state) % (mag + 1)) as i64 * if UP { 1 } else { -1 };
            let (frac, lz0) = (62, 0);
            // Stored codes: the far code, with one pixel (or none) that every code fails.
            let mut row = std::vec![u16::MAX; n];
            let stop = if rnd(&mut state) & 1 == 0 {
                n
            } else {
                (rnd(&mut state) % n as u64) as usize
            };
            if let Some(c) = row.get_mut(stop) {
                *c = 0;
            }
            let (x0, dx0) = (fresh::<UP, S>((v0 >> 32) as u32), 0);
            let (s, round) = Bin::shift::<UP>(frac, lz0);
            // Fresh: the loop as it was, counting the row.
            let (mut a, mut b) = (row.clone(), row.clone());
            let (mut v, mut dv, mut lz, mut k) = (v0, dv0, lz0, 0);
            let want = 'bins: loop {
                let (s, round) = Bin::shift::<UP>(frac, lz);
                loop {
                    let Some(stored) = a.get_mut(k) else {
                        break 'bins End::Row;
                    };
                    let c = (fresh::<UP, S>((v >> 32) as u32) as u32).wrapping_add(round) >> s;
                    if c >= *stored as u32 {
                        break 'bins End::Fail;
                    }
                    (*stored, k) = (c as u16, k + 1);
                    v = v.wrapping_add(dv as u64);
                    if left_binade::<UP>(v) {
                        if UP && chains::<UP, S>(dv >> 1) {
                            break 'bins End::Binade;
                        }
                        renormalise::<UP>(&mut v, &mut dv, &mut lz, &mut 0, &mut 0);
                        continue 'bins;
                    }
                }
            };
            let got = fresh_to_end::<UP, S>(&mut b, v0, dv0, lz0, frac);
            assert_eq!(
                (a, got.k, got.v, got.dv, got.lz, got.end),
                (b, k, v, dv, lz, want)
            );
            ends[want as usize] += 1;
            // Chained: likewise.
            let (mut a, mut b) = (row.clone(), row);
            let (mut v, mut x, mut dx, mut k) = (v0, x0, dx0, 0);
            let want = loop {
                let Some(stored) = a.get_mut(k) else {
                    break End::Row;
                };
                let xn = S::chain::<UP>((v >> 32) as u32, x.wrapping_add(dx));
                let c = (xn as u32).wrapping_add(round) >> s;
                if c >= *stored as u32 {
                    break End::Fail;
                }
                (*stored, k) = (c as u16, k + 1);
                (dx, x) = (xn.wrapping_sub(x), xn);
                v = v.wrapping_add(dv0 as u64);
                if left_binade::<UP>(v) {
                    break End::Binade;
                }
            };
            let got = chain_to_end::<UP, S>(&mut b, v0, dv0 as u64, x0, dx0, round, s);
            assert_eq!(
                (a, got.k, got.v, got.x, got.dx, got.end),
                (b, k, v, x, dx, want)
            );
            ends[want as usize] += 1;
        }
        ends
    }

    #[test]
    fn runs_to_a_sentinel_draw_what_counted_runs_draw() {
        for ends in [
            runs_to_end::<true, Divide>(),
            runs_to_end::<false, Divide>(),
            runs_to_end::<true, Chord>(),
            runs_to_end::<false, Chord>(),
        ] {
            // Every way a run ends is exercised: at a fail, at a binade, at the row's end.
            assert!(ends.iter().all(|&e| e > 1000), "{ends:?}");
        }
    }

    /// The M0's chord seed equals the seed as defined, at both ends of every cell and at random points.
    #[test]
    fn unmasked_chord_seed_is_the_masked_one() {
        let mut state = 0x5EED_C0DE_0123_4567_u64;
        for k in 0..3_000_000u32 {
            let m = match k {
                0..=511 => (256 + k / 2) << 23 | if k % 2 == 0 { 0 } else { (1 << 23) - 1 },
                _ => rnd(&mut state) as u32 | 1 << 31,
            };
            assert_eq!(chord_unmasked(m), chord_masked(m), "{m:#x}");
        }
    }

    /// Both forms of [`quarter_product`] are `floor(m x0 / 4)` modulo `2^32`, for every `m` and `x0 < 2^18` tried
    /// (so the M0 and the other cores compute the same frames).
    #[test]
    fn quarter_products_agree() {
        let mut state = 0x0DDB_1A5E_5BAD_5EED_u64;
        for k in 0..1_000_000u32 {
            let m = if k < 16 {
                u32::MAX - k
            } else {
                rnd(&mut state) as u32 | 1 << 31
            };
            let x0 = if k < 16 {
                (1 << 18) - 1 - k
            } else {
                (rnd(&mut state) >> 46) as u32
            };
            let exact = ((m as u64 * x0 as u64) >> 2) as u32;
            let m0 = (m >> 2).wrapping_mul(x0).wrapping_add(((m & 3) * x0) >> 2);
            assert_eq!((m0, quarter_by_halves(m, x0)), (exact, exact), "{m} {x0}");
        }
    }

    /// The M0's high-word and full products equal the 64-bit ones (so every core computes the same frames).
    #[test]
    fn halves_products_equal_64_bit_products() {
        let mut state = 0x1234_5678_9ABC_DEF1_u64;
        let edges = [
            0u32,
            1,
            0xffff,
            0x1_0000,
            0x7fff_ffff,
            0x8000_0000,
            u32::MAX,
        ];
        for k in 0..400_000 {
            let (a, b) = if k < 49 {
                (edges[k / 7], edges[k % 7])
            } else {
                (rnd(&mut state) as u32, (rnd(&mut state) >> 32) as u32)
            };
            halves_products_are_exact(a, b);
            let (sa, sb) = (a as i32, b as i32);
            assert_eq!(smul_wide_halves(sa, sb), sa as i64 * sb as i64, "{sa} {sb}");
            assert_eq!(
                smul_hi_halves(sa, sb),
                ((sa as i64 * sb as i64) >> 32) as i32,
                "{sa} {sb}"
            );
        }
    }

    /// Which pixels the coarse test skips without reading them: with a limit of 0 the per-pixel test rules out no
    /// stored code above 0, so a bound of 0 (below the stored codes, which a real buffer never has) marks exactly the
    /// segments skipped whole. From an aligned first pixel, the leading segments whose bound is 0 are skipped (`v`
    /// moved by 8 steps each) and the walk stops at the first pixel of the next; from an unaligned one, it stops at
    /// once; without `COARSE`, at once. Both directions, spans starting at several segments.
    #[test]
    fn the_coarse_test_skips_whole_segments_by_their_bound() {
        fn check<const UP: bool>() {
            let v = if UP {
                (1u64 << 62) + (1 << 40)
            } else {
                u64::MAX - (1 << 40)
            };
            let dv = if UP {
                1u64 << 32
            } else {
                (1u64 << 32).wrapping_neg()
            };
            let row = [7u16; 48];
            for x0 in [0usize, 8, 16, 24, 3, 13] {
                for zeros in 0..4 {
                    let mut seg = std::vec![1u16; 16];
                    for g in seg.iter_mut().skip(x0 / 8).take(zeros) {
                        *g = 0;
                    }
                    let c = Coarse { seg: &mut seg, x0 };
                    let got = skip_run::<UP, true>(&row, v, dv, 0, &c, 0);
                    let k = if x0 % 8 == 0 { 8 * zeros } else { 0 };
                    let want = (k, v.wrapping_add(dv.wrapping_mul(k as u64)), End::Fail);
                    assert_eq!(got, want, "up {UP} x0 {x0} zeros {zeros}");
                    assert_eq!(
                        skip_run::<UP, false>(&row, v, dv, 0, &c, 0),
                        (0, v, End::Fail)
                    );
                }
            }
        }
        check::<true>();
        check::<false>();
        // At the binade's edge: upward, a segment whose last pixel would reach 2^63 (outside the binade) is not
        // tested whole; downward, one whose last pixel is exactly 2^63 (inside) is, and the step after it leaves.
        let (row, d) = ([7u16; 16], 1u64 << 32);
        let mut seg = std::vec![0u16; 2];
        let c = Coarse {
            seg: &mut seg,
            x0: 0,
        };
        let up = (1u64 << 63) - 7 * d;
        assert_eq!(
            skip_run::<true, true>(&row, up, d, 0, &c, 0),
            (0, up, End::Fail)
        );
        let down = (1u64 << 63) + 7 * d;
        assert_eq!(
            skip_run::<false, true>(&row, down, d.wrapping_neg(), 0, &c, 0),
            (8, (1u64 << 63) - d, End::Binade)
        );
    }

    /// The eight-pixel prefilter ([`skip_groups`], words or `u16`s) skips exactly the pixels the pixel loop skips,
    /// with the same `v` after them and the same end, on random rows at every alignment: stored codes ruled out
    /// everywhere, around the first pixel's boundary, or all at the boundary of one pixel of the first group (ruled
    /// out there and not where `tau` is larger: a group test with the wrong pixel's `tau` fails here), both
    /// directions, steps up to a quarter of `v`, rows near the binade's end, any binade's limit. It also counts that
    /// rows reaching a group end each way.
    #[test]
    fn the_grouped_prefilter_skips_what_the_pixel_loop_skips() {
        fn check<const UP: bool, const WORDS: bool>(state: &mut u64) -> [u32; 3] {
            // (rows ending at a pixel it cannot rule out, past a binade, at the row's end)
            let mut ends = [0u32; 3];
            let mut buf = std::vec![0u16; 84];
            for _ in 0..20_000 {
                let top = if UP { 1u64 << 62 } else { 1u64 << 63 };
                let v = top + rnd(state) % top;
                let mag = (v >> 2) >> (rnd(state) % 48);
                let dv = rnd(state) % (mag + 1);
                // A third of the rows start within 40 steps of the binade's end.
                let v = match rnd(state) % 3 {
                    0 if UP => {
                        (1u64 << 63)
                            - 1
                            - rnd(state) % dv.saturating_mul(40).saturating_add(1).min(top)
                    }
                    0 => {
                        (1u64 << 63) + rnd(state) % dv.saturating_mul(40).saturating_add(1).min(top)
                    }
                    _ => v,
                };
                let dv = if UP { dv } else { dv.wrapping_neg() };
                let lim =
                    Bin::new::<UP>(20 + (rnd(state) % 30) as u32, (rnd(state) % 40) as i32).lim;
                // Codes ruled out at any `tau` (`tau >> 17 < 2^15`), and the first pixel's boundary.
                let low = (lim >> 15).min(65535);
                let edge = (lim / ((v >> 49) as u32).max(1)).min(65535);
                let spread = 1 + (rnd(state) % 64) as u32;
                // One code for the whole row, at the boundary of the pixel `i` steps on: ruled out there, not
                // where `tau` is larger.
                let at = v.wrapping_add(dv.wrapping_mul(rnd(state) % 9));
                let at_edge = (lim / ((at >> 49) as u32).max(1)).min(65535) as u16;
                let mode = rnd(state) % 4;
                for c in buf.iter_mut() {
                    *c = match (mode, rnd(state) % 60) {
                        (3, _) => at_edge,
                        (_, 0) => 65535,
                        (0, _) => (rnd(state) % (low as u64 + 1)) as u16,
                        (1, _) => low as u16,
                        _ => (edge + spread)
                            .saturating_sub((rnd(state) % (2 * spread as u64 + 1)) as u32)
                            .min(65535) as u16,
                    };
                }
                let off = (rnd(state) % 4) as usize;
                let row = &buf[off..off + (rnd(state) % 80) as usize];
                let want = match pixels::<UP>(row, 0, row.len(), v, dv, lim) {
                    Ok(v) => (row.len(), v, End::Row),
                    Err(end) => end,
                };
                let got = skip_groups::<UP, WORDS>(row, v, dv, lim);
                assert_eq!(
                    got, want,
                    "up {UP} words {WORDS} v {v:#x} dv {dv:#x} lim {lim} row {row:?}"
                );
                ends[match want.2 {
                    End::Fail => 0,
                    End::Binade => 1,
                    End::Row => 2,
                }] += u32::from(want.0 >= 8);
            }
            ends
        }
        let mut state = 0x5EED_0F08_u64;
        for ends in [
            check::<true, true>(&mut state),
            check::<true, false>(&mut state),
            check::<false, true>(&mut state),
            check::<false, false>(&mut state),
        ] {
            // Rows that reached a group and ended each way.
            assert!(ends.iter().all(|&e| e > 100), "{ends:?}");
        }
    }

    /// `Coarse::lower` lowers exactly the aligned 8-pixel segments (in frame columns) that the run `a..b` covers
    /// whole, each to one above the larger of its two end codes (never raising one), and leaves every other alone:
    /// for every span offset within a segment, every run start and end.
    #[test]
    fn lower_takes_every_whole_segment_of_a_run_and_no_other() {
        let mut state = 0xC0A5_E000_0000_0002_u64;
        let n = 40usize;
        for x0 in 0..16usize {
            for a in 0..n {
                for b in a..=n {
                    let row: std::vec::Vec<u16> =
                        (0..n).map(|_| (rnd(&mut state) % 60_000) as u16).collect();
                    let old = (rnd(&mut state) % 65_536) as u16;
                    let mut seg = std::vec![old; (x0 + n).div_ceil(8)];
                    Coarse { seg: &mut seg, x0 }.lower(&row, a, b);
                    for (i, &g) in seg.iter().enumerate() {
                        let (lo, hi) = (i * 8, i * 8 + 8);
                        let want = if lo >= x0 + a && hi <= x0 + b {
                            old.min(row[lo - x0].max(row[hi - 1 - x0]) + 1)
                        } else {
                            old
                        };
                        assert_eq!(g, want, "x0 {x0} run {a}..{b} segment {i}");
                    }
                }
            }
        }
    }

    /// With a valid coarse bound (each segment's at least its largest stored code), the prefilter with the bound ends
    /// where the per-pixel one does, with the same `v`: on random rows, both directions, spans starting anywhere in
    /// a segment, bounds exact or above the largest code; and it does skip whole segments (the test is not vacuous).
    #[test]
    fn the_coarse_prefilter_ends_where_the_per_pixel_one_does() {
        fn check<const UP: bool>(state: &mut u64) -> (u32, u32) {
            let frac = 40 + (rnd(state) % 16) as u32;
            let lz = (rnd(state) % 8) as i32;
            let b = Bin::new::<UP>(frac, lz);
            let n = 1 + (rnd(state) % 60) as usize;
            let x0 = (rnd(state) % 40) as usize;
            let v = if UP {
                (1u64 << 62) | (rnd(state) >> 2 >> (rnd(state) % 8))
            } else {
                (1u64 << 63) | (rnd(state) >> 1)
            };
            // Steps up to a quarter of `v` (a tame span), steep ones that leave the binade within a segment too.
            let mag = ((rnd(state) >> (2 + rnd(state) % 50)).min(v / 4)) as i64;
            let dv = (if UP { mag } else { -mag }) as u64;
            // Stored codes near each pixel's ruled-out boundary `lim / A` (where the per-pixel test decides),
            // mostly just below it (ruled out), one in 40 above.
            let row: std::vec::Vec<u16> = (0..n)
                .map(|k| {
                    let vk = v.wrapping_add(dv.wrapping_mul(k as u64));
                    let edge = (b.lim / ((vk >> 49) as u32).max(1)).min(65535) as i64;
                    let d = if rnd(state).is_multiple_of(40) {
                        1 + (rnd(state) % 8) as i64
                    } else {
                        -((rnd(state) % 4) as i64)
                    };
                    (edge + d).clamp(0, 65535) as u16
                })
                .collect();
            let segs = (x0 + n).div_ceil(8);
            let mut seg = std::vec![0u16; segs];
            for (i, bnd) in seg.iter_mut().enumerate() {
                let lo = (i * 8).max(x0) - x0;
                let hi = ((i + 1) * 8).min(x0 + n).saturating_sub(x0);
                let max = row[lo.min(hi)..hi].iter().copied().max().unwrap_or(0);
                *bnd = max.saturating_add((rnd(state) % 3) as u16 * (rnd(state) % 4) as u16);
            }
            let c = Coarse { seg: &mut seg, x0 };
            let k0 = (rnd(state) % 3) as usize;
            let k0 = k0.min(n - 1);
            let plain = skip_run::<UP, false>(&row[k0..], v, dv, b.lim, &c, k0);
            let coarse = skip_run::<UP, true>(&row[k0..], v, dv, b.lim, &c, k0);
            assert!(
                plain.0 == coarse.0 && plain.1 == coarse.1 && plain.2 == coarse.2,
                "up {UP} {plain:?} {coarse:?}"
            );
            // Whether a whole aligned segment in the span was skipped (every pixel ruled out).
            let skipped_whole =
                (0..plain.0).any(|k| (x0 + k0 + k).is_multiple_of(8) && k + 8 <= plain.0);
            (1, u32::from(skipped_whole))
        }
        let mut state = 0xC0A5_E000_0000_0001_u64;
        let (mut runs, mut whole) = (0, 0);
        for _ in 0..100_000 {
            let (a, b) = check::<true>(&mut state);
            let (c, d) = check::<false>(&mut state);
            (runs, whole) = (runs + a + c, whole + b + d);
        }
        assert!(
            whole > runs / 20,
            "{whole} of {runs} runs skipped a whole segment"
        );
    }

    /// The prefilter never rules out a pixel whose computed code is below the stored one: for random `tau` on a
    /// binade and stored codes around the computed one, `ruled_out` implies `code >= stored`.
    #[test]
    fn prefilter_is_conservative() {
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut tested = 0;
        for _ in 0..200_000 {
            let up = rnd(&mut state).is_multiple_of(2);
            let frac = 30 + (rnd(&mut state) % 32) as u32;
            let lz = (rnd(&mut state) % 34) as i32;
            // Spans in range have t >= 1, so codes <= 65535: the shift is at least 15 (x <= 2^30).
            let shift = if up { 60 } else { 61 } + 16 - frac as i32 - lz;
            if shift < 15 {
                continue;
            }
            let (b, tau, x) = if up {
                let tau = (1u32 << 30) | (rnd(&mut state) as u32 >> 2);
                (Bin::new::<true>(frac, lz), tau, fresh::<true, Chord>(tau))
            } else {
                let tau = (1u32 << 31) | (rnd(&mut state) as u32 >> 1);
                (Bin::new::<false>(frac, lz), tau, fresh::<false, Chord>(tau))
            };
            let code = b.code(x) as i32;
            for d in -3..=3 {
                let stored = (code + d).clamp(0, 65535) as u16;
                if ruled_out(tau, stored, b.lim) {
                    tested += 1;
                    assert!(
                        code >= stored as i32,
                        "tau {tau} code {code} stored {stored}"
                    );
                }
            }
        }
        assert!(tested > 50_000, "{tested}");
    }
}
