//! The packed 16-bit W-buffer: `round(W / W_far * 65535)`, the "16-bit fixed, scale 1.0" row of the format table in
//! Rogers, "W-Buffering in Direct3D" (NVIDIA) (`W_scaled = W / W_far * scale_factor`).

use crate::Error;

/// The code of the far plane, and of a cleared buffer.
pub const W16_FAR: u16 = u16::MAX;

/// A borrowed W16 buffer covering `height` rows of a frame `width` pixels wide, from frame row `y0`
/// (a whole frame when `y0 = 0` and `height` is the frame's height; a band otherwise).
/// Element `(x, y)` of the frame is at `(y - y0) * width + x`.
#[derive(Debug)]
pub struct DepthBuffer<'a> {
    data: &'a mut [u16],
    width: u16,
    height: u16,
    y0: i32,
}

impl<'a> DepthBuffer<'a> {
    /// A whole-frame buffer; `data.len()` must be `width * height`.
    pub fn new(data: &'a mut [u16], width: u16, height: u16) -> Result<Self, Error> {
        Self::band(data, width, 0, height)
    }

    /// A band of `height` rows starting at frame row `y0`; `data.len()` must be `width * height`.
    pub fn band(data: &'a mut [u16], width: u16, y0: i32, height: u16) -> Result<Self, Error> {
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
        })
    }

    /// Sets every element to the far plane.
    pub fn clear(&mut self) {
        self.data.fill(W16_FAR);
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
    /// The stored codes, row-major.
    pub fn data(&self) -> &[u16] {
        self.data
    }
    /// The code at frame pixel `(x, y)`, if it is in this buffer.
    pub fn get(&self, x: i32, y: i32) -> Option<u16> {
        let r = y.checked_sub(self.y0)?;
        if x < 0 || x >= self.width as i32 || r < 0 || r >= self.height as i32 {
            return None;
        }
        Some(self.data[r as usize * self.width as usize + x as usize])
    }
    #[inline]
    pub(crate) fn row_mut(&mut self, y: i32) -> &mut [u16] {
        let r = (y - self.y0) as usize * self.width as usize;
        &mut self.data[r..r + self.width as usize]
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
