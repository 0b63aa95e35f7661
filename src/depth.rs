//! The packed 16-bit W-buffer: `round(W / W_far * 65535)`, the "16-bit fixed, scale 1.0" row of the format table in
//! Rogers, "W-Buffering in Direct3D" (NVIDIA) (`W_scaled = W / W_far * scale_factor`).

use crate::format::{DepthFormat, Storage, W16};
use crate::Error;

/// The code of the far plane, and of a cleared buffer.
pub const W16_FAR: u16 = u16::MAX;

/// A borrowed depth buffer of format `F` (W16 unless named: the fast tier's) covering `height` rows of a frame
/// `width` pixels wide, from frame row `y0` (a whole frame when `y0 = 0` and `height` is the frame's height; a band
/// otherwise): one [`DepthFormat::Word`] a pixel (`u16`, `[u8; 3]` or `u32`, so 2, 3 or 4 bytes), row-major; element
/// `(x, y)` of the frame is at `(y - y0) * width + x`. Every draw method takes one of any format (or none:
/// [`crate::NoDepth`]); a firmware that names one format links that format's code alone.
///
/// ```
/// use wraster::{format::Z24, DepthBuffer, DepthRange};
/// let mut words = [[0u8; 3]; 64 * 16];                  // 3 bytes a pixel
/// let mut z = DepthBuffer::<Z24>::new_format(&mut words, 64, 16)?;
/// z.clear_for(&DepthRange::new(1.0, 100.0)?);
/// assert_eq!(z.code(3, 4), Some(0xff_ffff));            // the far plane's Z
/// # Ok::<(), wraster::Error>(())
/// ```
///
/// With feature `coarse`, a buffer may also keep a coarse bound (`DepthBuffer::with_bound`): for each aligned
/// 8-pixel segment of each row, a code at least as large as every code stored in it. The fast tier's W16 span
/// ([`crate::recip::Fast`], `Less`) rejects a whole segment whose nearest pixel is at or behind its bound before any
/// per-pixel work.
#[derive(Debug)]
pub struct DepthBuffer<'a, F: DepthFormat = W16> {
    data: &'a mut [F::Word],
    width: u16,
    height: u16,
    y0: i32,
    #[cfg(feature = "coarse")]
    bound: Bound<'a>,
}

/// The coarse bound of a [`DepthBuffer`] (feature `coarse`): one code per aligned 8-pixel row segment, at least the
/// largest code stored in the segment while `valid`. Empty when the buffer keeps none.
#[cfg(feature = "coarse")]
#[derive(Debug)]
struct Bound<'a> {
    seg: &'a mut [u16],
    /// False after a draw that may raise a stored code (a comparison other than `Less`, `LessEqual`, `Equal` or
    /// `Never` with depth write): the bound is then unused until [`DepthBuffer::clear`].
    valid: bool,
}

/// Pixels per segment of the coarse bound.
pub(crate) const SEGMENT: usize = 8;

/// The length of the coarse bound of a `width x height` buffer (feature `coarse`): one `u16` per aligned 8-pixel
/// segment of each row, `ceil(width / 8) * height` (an eighth of the depth buffer's RAM).
#[cfg(feature = "coarse")]
pub const fn bound_len(width: usize, height: usize) -> usize {
    width.div_ceil(SEGMENT) * height
}

impl<'a> DepthBuffer<'a, W16> {
    /// A whole-frame W16 buffer; `data.len()` must be `width * height`. (Any format: [`DepthBuffer::new_format`].)
    pub fn new(data: &'a mut [u16], width: u16, height: u16) -> Result<Self, Error> {
        Self::band_format(data, width, 0, height)
    }

    /// A W16 band of `height` rows starting at frame row `y0`; `data.len()` must be `width * height`. (Any format:
    /// [`DepthBuffer::band_format`].)
    pub fn band(data: &'a mut [u16], width: u16, y0: i32, height: u16) -> Result<Self, Error> {
        Self::band_format(data, width, y0, height)
    }
}

impl<'a, F: DepthFormat> DepthBuffer<'a, F> {
    /// A whole-frame buffer of format `F`; `data.len()` must be `width * height`.
    pub fn new_format(data: &'a mut [F::Word], width: u16, height: u16) -> Result<Self, Error> {
        Self::band_format(data, width, 0, height)
    }

    /// A band of format `F`, `height` rows from frame row `y0`; `data.len()` must be `width * height`.
    pub fn band_format(
        data: &'a mut [F::Word],
        width: u16,
        y0: i32,
        height: u16,
    ) -> Result<Self, Error> {
        let expected = width as usize * height as usize;
        if data.len() != expected || width == 0 || height == 0 {
            return Err(Error::BufferSize {
                expected,
                actual: data.len(),
            });
        }
        Ok(DepthBuffer {
            data,
            width,
            height,
            y0,
            #[cfg(feature = "coarse")]
            bound: Bound {
                seg: &mut [],
                valid: false,
            },
        })
    }

    /// Sets every pixel to `w` and the coarse bound (W16's, feature `coarse`) to the far code, which bounds any
    /// content.
    pub(crate) fn fill(&mut self, w: F::Word) {
        self.data.fill(w);
        #[cfg(feature = "coarse")]
        {
            self.bound.seg.fill(W16_FAR);
            self.bound.valid = true;
        }
    }

    /// Frame width in pixels.
    pub fn width(&self) -> u16 {
        self.width
    }
    /// Rows held.
    pub fn height(&self) -> u16 {
        self.height
    }
    /// First frame row held.
    pub fn y0(&self) -> i32 {
        self.y0
    }
    /// The stored words, row-major.
    pub fn data(&self) -> &[F::Word] {
        self.data
    }
    /// The word at frame pixel `(x, y)`, if it is in this buffer (a W16 buffer's: the code itself).
    pub fn get(&self, x: i32, y: i32) -> Option<F::Word> {
        self.index(x, y).map(|k| self.data[k])
    }
    /// The code at frame pixel `(x, y)`, if it is in this buffer.
    pub fn code(&self, x: i32, y: i32) -> Option<u32> {
        self.get(x, y).map(Storage::code)
    }
    /// The index of frame pixel `(x, y)` in the data, if it is in this buffer.
    fn index(&self, x: i32, y: i32) -> Option<usize> {
        let r = y.checked_sub(self.y0)?;
        if x < 0 || x >= self.width as i32 || r < 0 || r >= self.height as i32 {
            return None;
        }
        Some(r as usize * self.width as usize + x as usize)
    }
    /// The word of frame pixel `(x, y)`, to write, if it is in this buffer.
    #[inline]
    pub(crate) fn pixel_mut(&mut self, x: i32, y: i32) -> Option<&mut F::Word> {
        let k = self.index(x, y)?;
        self.data.get_mut(k)
    }
    /// The stored words, row-major, to write.
    #[inline]
    pub(crate) fn data_mut(&mut self) -> &mut [F::Word] {
        self.data
    }
    #[inline]
    pub(crate) fn row_mut(&mut self, y: i32) -> &mut [F::Word] {
        let r = (y - self.y0) as usize * self.width as usize;
        &mut self.data[r..r + self.width as usize]
    }
}

impl<'a> DepthBuffer<'a, W16> {
    /// Keeps a coarse bound in `seg` (feature `coarse`), whose length must be [`bound_len`]`(width, height)`. It
    /// starts at the far code, which bounds any content; [`DepthBuffer::clear`] resets it, and the W16 draws lower it
    /// as they write. The frames and codes are the same with and without it: it only skips work.
    ///
    /// ```
    /// use wraster::{bound_len, DepthBuffer};
    /// let mut data = [0u16; 64 * 16];
    /// let mut seg = [0u16; bound_len(64, 16)];
    /// let mut depth = DepthBuffer::new(&mut data, 64, 16)?.with_bound(&mut seg)?;
    /// depth.clear();
    /// # Ok::<(), wraster::Error>(())
    /// ```
    #[cfg(feature = "coarse")]
    pub fn with_bound(mut self, seg: &'a mut [u16]) -> Result<Self, Error> {
        let expected = bound_len(self.width as usize, self.height as usize);
        if seg.len() != expected {
            return Err(Error::BufferSize {
                expected,
                actual: seg.len(),
            });
        }
        seg.fill(W16_FAR);
        self.bound = Bound { seg, valid: true };
        Ok(self)
    }

    /// The coarse bound, one code per aligned 8-pixel segment of each row, if the buffer keeps one and it is in use.
    #[cfg(feature = "coarse")]
    pub fn bound(&self) -> Option<&[u16]> {
        (self.bound.valid && !self.bound.seg.is_empty()).then_some(&*self.bound.seg)
    }

    /// Sets every element to the far plane (and the coarse bound with it).
    pub fn clear(&mut self) {
        self.fill(W16_FAR);
    }

    /// A draw with `cmp` (and depth write `write`) may raise stored codes: stop using the coarse bound until the
    /// next clear.
    #[inline(always)]
    pub(crate) fn note_compare(&mut self, cmp: crate::Compare, write: bool) {
        #[cfg(feature = "coarse")]
        {
            use crate::Compare::*;
            if write && matches!(cmp, Greater | GreaterEqual | NotEqual | Always) {
                self.bound.valid = false;
            }
        }
        #[cfg(not(feature = "coarse"))]
        let _ = (cmp, write);
    }

    /// Row `y` and, if the buffer keeps a coarse bound in use, that row's segments.
    #[cfg(feature = "coarse")]
    #[inline]
    pub(crate) fn row_and_bound(&mut self, y: i32) -> (&mut [u16], &mut [u16]) {
        let r = (y - self.y0) as usize;
        let w = self.width as usize;
        let row = &mut self.data[r * w..(r + 1) * w];
        let segs = w.div_ceil(SEGMENT);
        let seg = if self.bound.valid {
            self.bound
                .seg
                .get_mut(r * segs..(r + 1) * segs)
                .unwrap_or_default()
        } else {
            &mut []
        };
        (row, seg)
    }
}

/// Owned storage for a `W x H` buffer (a band when `H` is less than the frame's height).
pub struct DepthStore<const W: usize, const H: usize> {
    data: [[u16; W]; H],
}

impl<const W: usize, const H: usize> Default for DepthStore<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize, const H: usize> DepthStore<W, H> {
    const CHECK: () = assert!(W > 0 && H > 0 && W <= u16::MAX as usize && H <= u16::MAX as usize);
    /// A cleared store.
    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let _ = Self::CHECK;
        DepthStore {
            data: [[W16_FAR; W]; H],
        }
    }
    /// A view of it as the band starting at frame row `y0`.
    pub fn band(&mut self, y0: i32) -> DepthBuffer<'_> {
        DepthBuffer {
            data: self.data.as_flattened_mut(),
            width: W as u16,
            height: H as u16,
            y0,
            #[cfg(feature = "coarse")]
            bound: Bound {
                seg: &mut [],
                valid: false,
            },
        }
    }
    /// A view of it as a whole frame.
    pub fn view(&mut self) -> DepthBuffer<'_> {
        self.band(0)
    }
}

/// `round(65535 / t)` from the reciprocal: `1/t = x * 2^(frac + lz - 94)` (see [`crate::raster`]), `shift = 94 - frac - lz`
/// (at least 31 because `t >= 1`).
#[inline(always)]
pub(crate) fn encode_w16(x: u32, shift: u32) -> u16 {
    let p = 65535 * x as u64;
    // An overshooting reciprocal at t = 1 could round to 65536: clamp to the far code.
    ((p + (1u64 << (shift - 1))) >> shift).min(W16_FAR as u64) as u16
}
