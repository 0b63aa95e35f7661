//! Newton-Raphson reciprocals in fixed point: the per-pixel `W = 1/RHW` of seed 003_0afae2e2ce9f2c57.txt
//! ("linearly interpolating the vertex 1/w term ..., computing its reciprocal per pixel").
//!
//! Formats. The input is a normalised mantissa `m` in `[2^31, 2^32)`, standing for `d = m / 2^32` in `[0.5, 1)`.
//! The output `X` is `1/d` in Q2.30 (`X / 2^30`), in `(2^30, 2^31]` up to the stated error.
//! One step is `x' = x (2 - d x)`: the relative error squares (`e' = e^2`), and the two truncating fixed-point
//! products add at most `2^-30` each, so `e' <= e^2 + 2^-29` (the bound each strategy states is built from that).
//!
//! Strategies are types, so a firmware links only the one it names (no table it does not use).

use core::marker::PhantomData;

/// `1/d` for `d = m / 2^32`, `m` in `[2^31, 2^32)`, as Q2.30.
pub trait Recip32 {
    /// Short name for reports.
    const NAME: &'static str;
    /// Largest `|X / (2^62/m) - 1|` over the whole input domain (derived; checked by a sweep in the tests).
    const MAX_REL_ERROR: f64;
    /// The reciprocal.
    fn recip(m: u32) -> u32;
}

/// A starting value for Newton-Raphson.
pub trait Seed {
    /// Short name for reports.
    const NAME: &'static str;
    /// Largest relative error of the seed (derived from its construction).
    const MAX_REL_ERROR: f64;
    /// The seed, Q2.30.
    fn seed(m: u32) -> u32;
}

/// The classic linear seed `48/17 - 32/17 d` (relative error at most `1/17`, 4.1 bits; no table).
pub struct Linear;

impl Seed for Linear {
    const NAME: &'static str = "linear";
    // The minimax linear approximation of 1/d on [0.5, 1] has relative error exactly 1/17 at d = 0.5, 0.75^.., 1;
    // the two Q2.30 constants and the truncating product add below 3 * 2^-30.
    const MAX_REL_ERROR: f64 = 1.0 / 17.0 + 3.0 / (1u64 << 30) as f64;
    #[inline]
    fn seed(m: u32) -> u32 {
        const C1: u32 = ((48u64 << 30) / 17) as u32;
        const C2: u64 = (32u64 << 30) / 17;
        C1 - ((C2 * m as u64) >> 32) as u32
    }
}

const CELL_SHIFT: u32 = 25; // bits of m below the 6-bit cell index (m has its top bit set)
const CELLS: usize = 64;

/// Cell `k` covers `d` in `[a, b)`, `a = 0.5 + k/128`, `b = a + 1/128`.
const fn cell(k: usize) -> (f64, f64) {
    let a = 0.5 + k as f64 / 128.0;
    (a, a + 1.0 / 128.0)
}

const fn table64() -> [u32; CELLS] {
    let mut t = [0u32; CELLS];
    let mut k = 0;
    while k < CELLS {
        let (a, b) = cell(k);
        // 2/(a+b) is the constant with the smallest largest relative error on [a, b]: (b-a)/(a+b).
        t[k] = (2.0 / (a + b) * (1u64 << 30) as f64 + 0.5) as u32;
        k += 1;
    }
    t
}

const fn table64_error() -> f64 {
    // Largest over cells of (b-a)/(a+b) (at k = 0), plus the rounding of the entry (half a Q2.30 unit, relative to >= 1).
    let (a, b) = cell(0);
    (b - a) / (a + b) + 0.5 / (1u64 << 30) as f64
}

/// A 64-entry table on the top 6 fraction bits of `d` (7.0 bits; 256 bytes of flash).
pub struct Table64;

impl Seed for Table64 {
    const NAME: &'static str = "table64";
    const MAX_REL_ERROR: f64 = table64_error();
    #[inline]
    fn seed(m: u32) -> u32 {
        const T: [u32; CELLS] = table64();
        T[((m >> CELL_SHIFT) & 63) as usize]
    }
}

/// Per cell: the chord of `1/d` through the cell's ends, lowered by half its largest gap to the curve, as
/// `(value at a, drop across the cell)` in Q2.30.
const fn lerp64() -> [(u32, u32); CELLS] {
    let mut t = [(0u32, 0u32); CELLS];
    let mut k = 0;
    while k < CELLS {
        let (a, b) = cell(k);
        let (ya, yb) = (1.0 / a, 1.0 / b);
        let s = lerp_shift(a, b);
        let q = (1u64 << 30) as f64;
        t[k] = (((ya - s) * q + 0.5) as u32, ((ya - yb) * q + 0.5) as u32);
        k += 1;
    }
    t
}

/// The chord lies above the convex `1/d`; its largest gap is at `d* = sqrt(a b)`: `(1/sqrt(a) - 1/sqrt(b))^2`.
/// Half of it is the shift that balances the error. `sqrt` is not `const`, so this uses the equal form
/// `(b - a)^2 / (a b (sqrt a + sqrt b)^2)` with `(sqrt a + sqrt b)^2 >= 4a` (a lower bound: the shift is at most 0.4%
/// smaller than optimal, and the bound below uses the gap itself, so it stays a bound).
const fn lerp_shift(a: f64, b: f64) -> f64 {
    (b - a) * (b - a) / (a * b * 4.0 * a) / 2.0
}

const fn lerp64_error() -> f64 {
    // Relative error at d is d * |L(d) - 1/d| <= b * max(s, gap - s), gap <= (b-a)^2/(4 a^2 b) (with
    // (sqrt a + sqrt b)^2 >= 4a), s as built; both are largest in cell 0. Entries round by half a unit each and the
    // product truncates: 3 units of 2^-30 in value, relative to a value >= 1.
    let (a, b) = cell(0);
    let gap = (b - a) * (b - a) / (a * b * 4.0 * a);
    let s = lerp_shift(a, b);
    let e = if s > gap - s { s } else { gap - s };
    b * e + 3.0 / (1u64 << 30) as f64
}

/// Piecewise linear over 64 cells (about 14 bits; 512 bytes of flash, one multiply).
pub struct Lerp64;

impl Seed for Lerp64 {
    const NAME: &'static str = "lerp64";
    const MAX_REL_ERROR: f64 = lerp64_error();
    #[inline]
    fn seed(m: u32) -> u32 {
        const T: [(u32, u32); CELLS] = lerp64();
        let (y, drop) = T[((m >> CELL_SHIFT) & 63) as usize];
        let u = (m & ((1 << CELL_SHIFT) - 1)) as u64; // position in the cell, Q0.25
        y - ((drop as u64 * u) >> CELL_SHIFT) as u32
    }
}

/// `x' = x (2 - d x)` in Q2.30 with truncating products.
#[inline(always)]
pub fn newton_step(m: u32, x: u32) -> u32 {
    let dx = ((m as u64 * x as u64) >> 32) as u32; // d x, Q2.30, close to 2^30
    let e = (2u32 << 30).wrapping_sub(dx); // 2 - d x, Q2.30
    ((x as u64 * e as u64) >> 30) as u32
}

const fn after_steps(seed: f64, steps: usize) -> f64 {
    let mut e = seed;
    let mut i = 0;
    while i < steps {
        e = e * e + 2.0 / (1u64 << 30) as f64;
        i += 1;
    }
    e
}

/// Seed `S` then `STEPS` Newton-Raphson steps.
pub struct Newton<S, const STEPS: usize>(PhantomData<S>);

impl<S: Seed, const STEPS: usize> Recip32 for Newton<S, STEPS> {
    const NAME: &'static str = S::NAME;
    const MAX_REL_ERROR: f64 = after_steps(S::MAX_REL_ERROR, STEPS);
    #[inline]
    fn recip(m: u32) -> u32 {
        let mut x = S::seed(m);
        let mut i = 0;
        while i < STEPS {
            x = newton_step(m, x);
            i += 1;
        }
        x
    }
}

/// The default: piecewise-linear seed and one step (about 28 bits, two multiplies and a table read per pixel).
pub type DefaultRecip = Newton<Lerp64, 1>;

/// `1/t` for a pixel, `t = T / 2^32` (see [`SpanRecip`]): `1/t = x * 2^(lz - 62)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inv {
    /// `1/d` in Q2.30, `d` the normalised mantissa of `T`.
    pub x: u32,
    /// Leading zeros of `T` (`T >= 2^32` gives `lz <= 31`).
    pub lz: u32,
}

impl Inv {
    /// `1/t` as f64 (for tests and reports).
    pub fn to_f64(self) -> f64 {
        self.x as f64 * libm_exp2(self.lz as i32 - 62)
    }
}

fn libm_exp2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

#[inline(always)]
fn normalise(t: u64) -> (u32, u32) {
    let lz = t.leading_zeros();
    (((t << lz) >> 32) as u32, lz)
}

/// How a span gets `1/t` per pixel, where `t = W_far * RHW` is held as `T = t * 2^32` (see ARCHITECTURE.md).
/// Normalising `T` to its top 32 bits truncates by less than `2^-31` relative; every bound below includes it.
pub trait SpanRecip: Default {
    /// Short name for reports.
    const NAME: &'static str;
    /// Largest relative error of `1/t` at any pixel (derived; a test sweeps spans and asserts it).
    const MAX_REL_ERROR: f64;
    /// Called before the first pixel of a span with `T` there, its step per pixel and the pixel count (>= 1).
    #[inline(always)]
    fn begin_span(&mut self, _t: u64, _dt: i64, _len: u32) {}
    /// `1/t` for the next pixel of the span (`2^32 <= t < 2^57`).
    fn recip(&mut self, t: u64) -> Inv;
}

/// Every pixel on its own: normalise (count leading zeros) and run `R`.
pub struct PerPixel<R>(PhantomData<R>);

impl<R> Default for PerPixel<R> {
    fn default() -> Self {
        PerPixel(PhantomData)
    }
}

impl<R: Recip32> SpanRecip for PerPixel<R> {
    const NAME: &'static str = R::NAME;
    const MAX_REL_ERROR: f64 = R::MAX_REL_ERROR + 1.0 / (1u64 << 31) as f64;
    #[inline(always)]
    fn recip(&mut self, t: u64) -> Inv {
        let (m, lz) = normalise(t);
        Inv { x: R::recip(m), lz }
    }
}

/// Seeded from the previous pixel of the span: one Newton-Raphson step, no table, no normalisation of the seed.
///
/// The seed's relative error is the relative change of `t` from the previous pixel plus that pixel's error.
/// A span uses it only when `|dt| <= t_min / 2^11` over the whole span (checked at `begin_span`, from the span's two
/// ends, since `t` is linear along it); other spans, and the first pixel of every span, take the full
/// [`DefaultRecip`]. With `delta <= 2^-11` the error stays below `(2^-11 + e)^2 + 2^-29`, whose fixed point
/// is below `2^-22 + 2^-29` (checked by the const below and by the span sweep in the tests).
#[derive(Default)]
pub struct PrevPixel {
    x: u32,
    lz: u32,
    /// The span qualifies for chaining.
    smooth: bool,
    /// A previous pixel of this span exists.
    chain: bool,
}

const PREV_SHIFT: u32 = 11;

const fn prev_fixed_point() -> f64 {
    let d = 1.0 / (1u64 << PREV_SHIFT) as f64;
    let mut e = PerPixel::<DefaultRecip>::MAX_REL_ERROR;
    let mut i = 0;
    while i < 64 {
        // the 2^-31 of normalising the new T enters the error of its exact reciprocal, as in PerPixel
        let n = (d + e) * (d + e) + 2.0 / (1u64 << 30) as f64 + 1.0 / (1u64 << 31) as f64;
        e = if n > e { n } else { e };
        i += 1;
    }
    e
}

impl SpanRecip for PrevPixel {
    const NAME: &'static str = "prev-pixel";
    const MAX_REL_ERROR: f64 = prev_fixed_point();
    #[inline]
    fn begin_span(&mut self, t: u64, dt: i64, len: u32) {
        let last = t.wrapping_add((dt as u64).wrapping_mul(len as u64 - 1));
        let tmin = if dt < 0 { last } else { t };
        self.chain = false;
        // Chain only when every step is small against the smallest t of the span.
        self.smooth = dt.unsigned_abs() <= (tmin >> PREV_SHIFT) && tmin >= 1 << 32;
    }
    #[inline]
    fn recip(&mut self, t: u64) -> Inv {
        let (m, lz) = normalise(t);
        if self.chain {
            // Re-express the previous 1/d for this pixel's binade: one binade down in t doubles 1/d's scale.
            let seed = if lz == self.lz {
                self.x
            } else if lz > self.lz {
                self.x >> 1
            } else {
                self.x << 1
            };
            self.x = newton_step(m, seed);
        } else {
            self.chain = self.smooth;
            self.x = DefaultRecip::recip(m);
        }
        self.lz = lz;
        Inv { x: self.x, lz }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sweeps `m` over every 2^8-th value of `[2^31, 2^32)` and both ends of every seed cell and returns the largest
    /// relative error against `2^62 / m` (exact to 2^-53 in f64), two-sided.
    fn sweep<R: Recip32>() -> f64 {
        let mut worst = 0.0f64;
        let mut check = |m: u32| {
            let exact = (1u64 << 62) as f64 / m as f64;
            let e = (R::recip(m) as f64 / exact - 1.0).abs();
            worst = worst.max(e);
        };
        let mut m: u64 = 1 << 31;
        while m < 1 << 32 {
            check(m as u32);
            m += 1 << 8;
        }
        for k in 0..64u64 {
            let lo = (1u64 << 31) | (k << CELL_SHIFT);
            check(lo as u32);
            check((lo + (1 << CELL_SHIFT) - 1) as u32);
        }
        worst
    }

    fn assert_bound<R: Recip32>(bits_at_least: f64) {
        let w = sweep::<R>();
        assert!(
            w <= R::MAX_REL_ERROR,
            "{}: measured {w:e} above the derived bound {:e}",
            R::NAME,
            R::MAX_REL_ERROR
        );
        // The bound must also be meaningful: the precision note's bit counts (shared/notes/precision.md).
        assert!(
            -R::MAX_REL_ERROR.log2() >= bits_at_least,
            "{}: bound {:e}",
            R::NAME,
            R::MAX_REL_ERROR
        );
        std::println!(
            "{} steps: measured {:.2} bits, bound {:.2} bits",
            R::NAME,
            -w.log2(),
            -R::MAX_REL_ERROR.log2()
        );
    }

    extern crate std;

    #[test]
    fn linear_seed_and_steps() {
        // precision.md: 4.1, 8.2, 16.3 bits after 0, 1, 2 steps; the fixed-point floor (2^-29) caps step 3.
        assert_bound::<Newton<Linear, 0>>(4.0);
        assert_bound::<Newton<Linear, 1>>(8.0);
        assert_bound::<Newton<Linear, 2>>(16.0);
        assert_bound::<Newton<Linear, 3>>(28.5);
    }

    #[test]
    fn table64_seed_and_steps() {
        // precision.md: 7.0, 14.0, 28.0 bits; with the 2^-29 floor of the truncating products 2 steps give 27.45.
        assert_bound::<Newton<Table64, 0>>(6.9);
        assert_bound::<Newton<Table64, 1>>(13.8);
        assert_bound::<Newton<Table64, 2>>(27.4);
    }

    #[test]
    fn lerp64_seed_and_step() {
        assert_bound::<Newton<Lerp64, 0>>(14.0);
        assert_bound::<Newton<Lerp64, 1>>(28.0);
    }

    /// Spans of every slope the previous-pixel seed accepts, and the steeper ones it must refuse, across binades:
    /// the error at every pixel stays within the stated bound, relative to the exact `2^32 / T`.
    #[test]
    fn prev_pixel_bound_holds_along_spans() {
        let mut worst = 0.0f64;
        let mut pixels = 0u64;
        let mut chained_spans = 0;
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..4000 {
            let t0 = (1u64 << 32) + rnd() % (1u64 << 50);
            let len = 1 + (rnd() % 400) as u32;
            // slopes from tiny to 4x the acceptance limit, both signs
            let lim = (t0 >> PREV_SHIFT) as i64;
            let dt = ((rnd() % (4 * lim as u64 + 1)) as i64 - 2 * lim) / (1 + (rnd() % 64) as i64);
            let end = t0 as i128 + dt as i128 * (len as i128 - 1);
            if !((1i128 << 32)..(1i128 << 57)).contains(&end) {
                continue;
            }
            let mut r = PrevPixel::default();
            r.begin_span(t0, dt, len);
            chained_spans += usize::from(r.smooth);
            let mut t = t0;
            for _ in 0..len {
                let inv = r.recip(t);
                let exact = (1u64 << 32) as f64 / t as f64;
                worst = worst.max((inv.to_f64() / exact - 1.0).abs());
                pixels += 1;
                t = t.wrapping_add(dt as u64);
            }
        }
        std::println!("prev-pixel: {pixels} pixels, {chained_spans} chained spans, worst {worst:e}, bound {:e}", PrevPixel::MAX_REL_ERROR);
        assert!(chained_spans > 500, "the sweep must exercise chaining");
        assert!(worst <= PrevPixel::MAX_REL_ERROR);
    }
}
