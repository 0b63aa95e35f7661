//! The crate's own colour target: [`ColorBand`], rows of a frame in the colour's raw storage (`u16` for RGB565), the
//! buffer a firmware sends to its display over SPI or DMA, band by band or whole.
//!
//! Any embedded-graphics `DrawTarget` takes the draws; this one is for when the pixels live in RAM anyway. The
//! rasterizer hands its colour to the target as one `fill_solid` a run of passing pixels, and a small triangle's runs
//! are a few pixels long, so what that call costs counts: here a run under 16 pixels is a bounds check and a store per
//! pixel, inline in the draw, and a longer one is filled a 32-bit word at a time, out of line. (A general target's
//! `fill_solid` clips a rectangle of any height; embedded-graphics' own `Framebuffer` has a size fixed at compile time,
//! no band offset, and draws a rectangle pixel by pixel.)

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{Dimensions, Point, Size};
use embedded_graphics_core::pixelcolor::raw::RawData;
use embedded_graphics_core::pixelcolor::PixelColor;
use embedded_graphics_core::primitives::Rectangle;
use embedded_graphics_core::Pixel;

use bytemuck::Pod;

use crate::Error;

/// The raw storage of a pixel of colour `C` (`u16` for `Rgb565`).
pub type Raw<C> = <<C as PixelColor>::Raw as RawData>::Storage;

/// `height` rows of a frame `width` pixels wide, from frame row `y0`, in the colours' raw storage: a whole frame when
/// `y0 = 0` and `height` is the frame's height, a band otherwise (the depth buffer's layout, [`crate::DepthBuffer`]).
/// Pixel `(x, y)` of the frame is element `(y - y0) * width + x`. Its bounding box is its own rows, and writes
/// outside them are dropped (never out of bounds), so a frame drawn band by band draws every band with the same
/// calls.
///
/// ```
/// use embedded_graphics_core::pixelcolor::Rgb565;
/// use embedded_graphics_core::prelude::*;
/// use embedded_graphics_core::primitives::Rectangle;
/// use wraster::ColorBand;
///
/// let mut px = [0u16; 32 * 8];
/// let mut band = ColorBand::<Rgb565>::band(&mut px, 32, 8, 8)?; // frame rows 8..16
/// band.fill_solid(&Rectangle::new(Point::new(30, 4), Size::new(4, 6)), Rgb565::RED).unwrap();
/// assert_eq!(band.row(9).unwrap()[30..], [0xF800, 0xF800]); // clipped to the band's columns
/// assert_eq!(band.row(8).unwrap()[29..], [0, 0xF800, 0xF800]);
/// assert_eq!(band.row(10).unwrap()[30], 0); // the rectangle's rows are 4..10: the band holds 8 and 9
/// assert!(band.row(16).is_none());
/// # Ok::<(), wraster::Error>(())
/// ```
pub struct ColorBand<'a, C: PixelColor> {
    px: &'a mut [Raw<C>],
    width: usize,
    height: usize,
    y0: i32,
}

impl<'a, C> ColorBand<'a, C>
where
    C: PixelColor + Into<C::Raw>,
    Raw<C>: Pod,
{
    /// A whole frame; `px.len()` must be `width * height` (else [`Error::BufferSize`], as for zero sizes).
    pub fn new(px: &'a mut [Raw<C>], width: u16, height: u16) -> Result<Self, Error> {
        Self::band(px, width, 0, height)
    }

    /// A band of `height` rows from frame row `y0`; `px.len()` must be `width * height` (else
    /// [`Error::BufferSize`], as for zero sizes).
    pub fn band(px: &'a mut [Raw<C>], width: u16, y0: i32, height: u16) -> Result<Self, Error> {
        let expected = width as usize * height as usize;
        if px.len() != expected || width == 0 || height == 0 {
            return Err(Error::BufferSize {
                expected,
                actual: px.len(),
            });
        }
        Ok(ColorBand {
            px,
            width: width as usize,
            height: height as usize,
            y0,
        })
    }

    /// Moves the band to frame rows `y0..y0 + height` (its pixels are kept: clear them for the next band).
    pub fn set_y0(&mut self, y0: i32) {
        self.y0 = y0;
    }

    /// The first frame row of the band.
    pub fn y0(&self) -> i32 {
        self.y0
    }

    /// The band's pixels, row by row.
    pub fn pixels(&self) -> &[Raw<C>] {
        self.px
    }

    /// Frame row `y`, or `None` outside the band.
    pub fn row(&self, y: i32) -> Option<&[Raw<C>]> {
        let r = self.row_index(y)?;
        self.px.get(r * self.width..(r + 1) * self.width)
    }

    /// Every pixel set to `color`.
    pub fn fill(&mut self, color: C) {
        self.px.fill(color.into().into_inner());
    }

    /// The rectangle at `(x, y)`, `w` by `h`, clipped to the band, filled with the raw colour `v`, one slice fill a
    /// row. (Scalars, not a `Rectangle`: the inline fast path then builds none.)
    #[inline(never)]
    fn fill_clipped(&mut self, x: i32, y: i32, w: u32, h: u32, v: Raw<C>) {
        let x0 = x.max(0) as usize;
        let x1 = (x.saturating_add_unsigned(w).max(0) as usize).min(self.width);
        if x0 >= x1 {
            return;
        }
        for j in y..y.saturating_add_unsigned(h) {
            if let Some(r) = self.row_index(j) {
                let base = r * self.width;
                if let Some(run) = self.px.get_mut(base + x0..base + x1) {
                    fill_row(run, v);
                }
            }
        }
    }

    /// The band's row of frame row `y`.
    #[inline(always)]
    fn row_index(&self, y: i32) -> Option<usize> {
        let r = y.wrapping_sub(self.y0) as u32 as usize; // below y0: wraps above `height`
        (r < self.height).then_some(r)
    }
}

/// Runs at least this long are filled a word at a time, out of line ([`ColorBand::fill_clipped`]); shorter ones a
/// pixel a store, inline.
const WORD_RUN: usize = 16;

/// One row's run set to `v`. A run of 8- or 16-bit pixels of [`WORD_RUN`] or more is filled a 32-bit word (two or
/// four pixels) a store, between the pixels before the first aligned word and after the last: on the M4's W1 the
/// run's `strh` per pixel was 3 instructions a pixel. `bytemuck`'s safe `pod_align_to_mut` splits the run (no
/// `unsafe` here); the pixels are the same either way.
#[inline(always)]
fn fill_row<T: Pod>(run: &mut [T], v: T) {
    let size = core::mem::size_of::<T>();
    if (size == 1 || size == 2) && run.len() >= WORD_RUN {
        let (head, words, tail) = bytemuck::pod_align_to_mut::<T, u32>(run);
        // `v` repeated over the word's bytes.
        let mut w = [0u8; 4];
        for c in w.chunks_exact_mut(size) {
            c.copy_from_slice(bytemuck::bytes_of(&v));
        }
        head.fill(v);
        words.fill(u32::from_ne_bytes(w));
        tail.fill(v);
    } else {
        run.fill(v);
    }
}

impl<C: PixelColor> core::fmt::Debug for ColorBand<'_, C> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ColorBand")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("y0", &self.y0)
            .finish_non_exhaustive()
    }
}

impl<C> Dimensions for ColorBand<'_, C>
where
    C: PixelColor + Into<C::Raw>,
    Raw<C>: Pod,
{
    fn bounding_box(&self) -> Rectangle {
        Rectangle::new(
            Point::new(0, self.y0),
            Size::new(self.width as u32, self.height as u32),
        )
    }
}

impl<C> DrawTarget for ColorBand<'_, C>
where
    C: PixelColor + Into<C::Raw>,
    Raw<C>: Pod,
{
    type Color = C;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<C>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if let (Some(r), Ok(x)) = (self.row_index(p.y), usize::try_from(p.x)) {
                if x < self.width {
                    if let Some(px) = self.px.get_mut(r * self.width + x) {
                        *px = c.into().into_inner();
                    }
                }
            }
        }
        Ok(())
    }

    /// A rasterizer's short run (one row under 16 pixels, inside the columns) takes a bounds check and the
    /// stores, inline; any other rectangle is clipped to the band and filled a word at a time, out of line.
    #[inline(always)]
    fn fill_solid(&mut self, area: &Rectangle, color: C) -> Result<(), Self::Error> {
        let v = color.into().into_inner();
        // A negative `x` becomes a large `usize`: not inside, so clipped below.
        let (x, w) = (area.top_left.x as u32 as usize, area.size.width as usize);
        if area.size.height == 1 && w < WORD_RUN && w <= self.width && x <= self.width - w {
            if let Some(r) = self.row_index(area.top_left.y) {
                let at = r * self.width + x;
                if let Some(run) = self.px.get_mut(at..at + w) {
                    run.fill(v);
                }
            }
            return Ok(());
        }
        let (p, size) = (area.top_left, area.size);
        self.fill_clipped(p.x, p.y, size.width, size.height, v);
        Ok(())
    }

    fn clear(&mut self, color: C) -> Result<(), Self::Error> {
        self.fill(color);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics_core::pixelcolor::{Rgb565, Rgb888};
    use embedded_graphics_core::prelude::RgbColor;
    use std::vec;

    /// Every rectangle (inside, across every side, empty, far outside) fills exactly its pixels inside the band, and
    /// `draw_iter` writes exactly the pixels inside: checked against a per-pixel model. Bands 13 and 61 pixels wide
    /// (runs of 16 and more take the word fill, from every alignment), in 16-, 8- and 32-bit storage.
    fn fills_exactly<C>(w: usize, colour: impl Fn(u32) -> C)
    where
        C: PixelColor + Into<C::Raw>,
        Raw<C>: Pod + PartialEq + core::fmt::Debug,
    {
        let (h, y0) = (5usize, 7i32);
        let mut state = 0x1234_5678_9abc_def1u64;
        let mut rnd = move |n: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as i32
        };
        let wi = w as i32;
        for k in 0..4000 {
            let mut px = vec![bytemuck::Zeroable::zeroed(); w * h];
            let mut model = px.clone();
            let mut band = ColorBand::<C>::band(&mut px, w as u16, y0, h as u16).unwrap();
            let (x, y) = (rnd(wi + 27) - 20, rnd(30) - 5);
            let (sw, sh) = (rnd(wi + 12) as u32, rnd(12) as u32);
            let c = colour(rnd(i32::MAX) as u32);
            let v = c.into().into_inner();
            if k % 2 == 0 {
                band.fill_solid(&Rectangle::new(Point::new(x, y), Size::new(sw, sh)), c)
                    .unwrap();
            } else {
                let pts: std::vec::Vec<_> = (0..sw as i32)
                    .flat_map(|i| (0..sh as i32).map(move |j| Pixel(Point::new(x + i, y + j), c)))
                    .collect();
                band.draw_iter(pts).unwrap();
            }
            for i in 0..sw as i32 {
                for j in 0..sh as i32 {
                    let (fx, fy) = (x + i, y + j);
                    if (0..wi).contains(&fx) && (y0..y0 + h as i32).contains(&fy) {
                        model[(fy - y0) as usize * w + fx as usize] = v;
                    }
                }
            }
            assert_eq!(px, model, "width {w}, rect ({x}, {y}) {sw} x {sh}");
        }
    }

    #[test]
    fn fills_and_draws_exactly_the_pixels_inside_the_band() {
        use embedded_graphics_core::pixelcolor::Gray8;
        for w in [13, 61] {
            fills_exactly(w, |r| {
                Rgb565::new(r as u8 & 31, (r >> 5) as u8 & 63, 1 + (r >> 11) as u8 % 31)
            });
            fills_exactly(w, |r| Gray8::new(1 + (r % 255) as u8));
            fills_exactly(w, |r| {
                Rgb888::new(r as u8, (r >> 8) as u8, 1 + (r >> 16) as u8 % 255)
            });
        }
    }

    #[test]
    fn sizes_rows_and_bounding_box() {
        let mut px = [0u32; 6];
        assert_eq!(
            ColorBand::<Rgb888>::new(&mut px, 4, 2).unwrap_err(),
            Error::BufferSize {
                expected: 8,
                actual: 6
            }
        );
        assert!(ColorBand::<Rgb888>::new(&mut px, 0, 2).is_err());
        // Zero sizes are refused even where the storage matches them.
        assert!(ColorBand::<Rgb888>::new(&mut [], 0, 2).is_err());
        assert!(ColorBand::<Rgb888>::new(&mut [], 3, 0).is_err());
        let mut band = ColorBand::<Rgb888>::band(&mut px, 3, -1, 2).unwrap();
        assert_eq!(
            band.bounding_box(),
            Rectangle::new(Point::new(0, -1), Size::new(3, 2))
        );
        band.clear(Rgb888::WHITE).unwrap();
        assert_eq!(band.pixels(), [0xFF_FFFF; 6]);
        let shown = std::format!("{band:?}");
        assert!(
            shown.starts_with("ColorBand")
                && shown.contains("width: 3")
                && shown.contains("y0: -1")
        );
        band.set_y0(4);
        assert_eq!(band.y0(), 4);
        assert!(band.row(3).is_none() && band.row(6).is_none());
        assert_eq!(band.row(5).unwrap().len(), 3);
    }
}
