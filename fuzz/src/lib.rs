//! Shared pieces of the fuzz targets: a byte reader that yields any f32 bit pattern, a colour target that panics on a
//! write outside itself and can fail on demand, and buffers with guard areas on both sides.
//!
//! The checks live in plain functions (`check_*`), so `host-tests` replays every input that ever failed as an
//! ordinary test (`host-tests/tests/fuzz_regressions.rs`).

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{OriginDimensions, Size};
use embedded_graphics_core::pixelcolor::{Rgb565, RgbColor};
use embedded_graphics_core::Pixel;

pub mod checks;

/// Reads the fuzzer's bytes; past the end every read gives zeros.
pub struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    pub fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    pub fn bool(&mut self) -> bool {
        self.u8() & 1 == 1
    }
    /// Any f32: a raw bit pattern (NaN payloads, infinities, subnormals, huge and tiny values), a value on a coarse
    /// grid in the screen's range (so the fuzzer reaches drawing), a positive one, or one of the special values.
    pub fn f32(&mut self) -> f32 {
        const SPECIAL: [f32; 16] = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1.0e-45,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            4096.0,
            -4096.0,
            4095.998,
            1.0e30,
            1.0e-30,
            0.5,
            1.0,
        ];
        match self.u8() % 4 {
            0 => f32::from_bits(self.u32()),
            1 => self.u16() as i16 as f32 / 64.0,
            2 => self.u16() as f32 / 1024.0 + 1.0e-3,
            _ => SPECIAL[self.u8() as usize % SPECIAL.len()],
        }
    }
    pub fn color(&mut self) -> Rgb565 {
        let c = self.u16();
        Rgb565::new((c >> 11) as u8, (c >> 5) as u8 & 63, c as u8 & 31)
    }
}

/// A colour target of `w x h` pixels that panics on a write outside it, counts writes per pixel, and fails (returns
/// `Err(())`) once `budget` pixels have been sent, if a budget is set.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Canvas {
    pub w: u32,
    pub h: u32,
    pub px: Vec<Rgb565>,
    pub writes: Vec<u32>,
    pub budget: Option<u32>,
}

impl Canvas {
    pub fn new(w: u32, h: u32) -> Self {
        Canvas {
            w,
            h,
            px: vec![Rgb565::BLACK; (w * h) as usize],
            writes: vec![0; (w * h) as usize],
            budget: None,
        }
    }
    /// The pixels and write counts (the budget aside).
    pub fn same_picture(&self, o: &Canvas) -> bool {
        self.px == o.px && self.writes == o.writes
    }
}

impl OriginDimensions for Canvas {
    fn size(&self) -> Size {
        Size::new(self.w, self.h)
    }
}

impl DrawTarget for Canvas {
    type Color = Rgb565;
    type Error = ();
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, pixels: I) -> Result<(), ()> {
        for Pixel(p, c) in pixels {
            if let Some(b) = self.budget.as_mut() {
                if *b == 0 {
                    return Err(());
                }
                *b -= 1;
            }
            assert!(
                p.x >= 0 && p.y >= 0 && (p.x as u32) < self.w && (p.y as u32) < self.h,
                "write outside the {}x{} target at {p:?}",
                self.w,
                self.h
            );
            let k = (p.y as u32 * self.w + p.x as u32) as usize;
            self.px[k] = c;
            self.writes[k] += 1;
        }
        Ok(())
    }
}

/// A buffer with `GUARD` sentinel elements on both sides of its `len` elements.
pub struct Guarded<T: Copy + PartialEq + core::fmt::Debug> {
    v: Vec<T>,
    len: usize,
    sentinel: T,
}

pub const GUARD: usize = 64;

impl<T: Copy + PartialEq + core::fmt::Debug> Guarded<T> {
    pub fn new(len: usize, fill: T, sentinel: T) -> Self {
        let mut v = vec![sentinel; len + 2 * GUARD];
        v[GUARD..GUARD + len].fill(fill);
        Guarded { v, len, sentinel }
    }
    pub fn inner(&mut self) -> &mut [T] {
        &mut self.v[GUARD..GUARD + self.len]
    }
    pub fn data(&self) -> &[T] {
        &self.v[GUARD..GUARD + self.len]
    }
    /// Panics when a guard element changed.
    pub fn check(&self) {
        let (a, rest) = self.v.split_at(GUARD);
        let b = &rest[self.len..];
        assert!(
            a.iter().chain(b).all(|&x| x == self.sentinel),
            "a write outside the buffer"
        );
    }
}
