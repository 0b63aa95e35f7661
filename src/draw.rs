//! The draw methods' entry: which loop a primitive takes, chosen by the types of its depth argument (a buffer of any
//! format, an `Option` of one, or [`NoDepth`]) and of the rasterizer's strategy, at compile time. Above the stages
//! (`crate::setup`, the W16 loops of `crate::raster`, `crate::fast` and `crate::small`, and `crate::packed`'s loop
//! generic over the format): they do not import it.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;

use crate::format::W16;
use crate::input::VertexInput;
use crate::recip::WSpan;
use crate::{Codec, DepthBuffer, Error, Rasterizer, Stats};

/// What a draw method takes for depth: a buffer of any format (`&mut DepthBuffer<F>`), an `Option` of one, or
/// [`NoDepth`] (depth off: the rows and columns drawn are then the colour target's). One draw method per primitive
/// takes any of them; the format decides the loop (a W16 buffer with a per-pixel reciprocal: the fast tier's).
pub trait IntoDepth<'b, 'a: 'b> {
    /// The buffer's format ([`W16`] for [`NoDepth`], which stores nothing).
    type Format: Codec;
    /// The buffer, if any.
    fn into_depth(self) -> Option<&'b mut DepthBuffer<'a, Self::Format>>;
    /// [`crate::Rasterizer::draw`] of one triangle into it (the format's loops: [`Codec::draw_into`]), or with depth
    /// off. A method of this trait, so that a draw into a buffer instantiates no depth-off path, and one with depth
    /// off no format's.
    #[doc(hidden)]
    fn draw_triangle<R: WSpan, D, V>(
        &mut self,
        r: &mut Rasterizer<R>,
        target: &mut D,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>;
}

impl<'b, 'a: 'b, F: Codec> IntoDepth<'b, 'a> for &'b mut DepthBuffer<'a, F> {
    type Format = F;
    #[inline(always)]
    fn into_depth(self) -> Option<&'b mut DepthBuffer<'a, F>> {
        Some(self)
    }
    #[inline(always)]
    fn draw_triangle<R: WSpan, D, V>(
        &mut self,
        r: &mut Rasterizer<R>,
        target: &mut D,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>,
    {
        F::draw_into(r, target, self, v)
    }
}

impl<'b, 'a: 'b, F: Codec> IntoDepth<'b, 'a> for Option<&'b mut DepthBuffer<'a, F>> {
    type Format = F;
    #[inline(always)]
    fn into_depth(self) -> Option<&'b mut DepthBuffer<'a, F>> {
        self
    }
    #[inline(always)]
    fn draw_triangle<R: WSpan, D, V>(
        &mut self,
        r: &mut Rasterizer<R>,
        target: &mut D,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>,
    {
        match self {
            Some(d) => F::draw_into(r, target, d, v),
            None => r.draw_packed::<F, D>(target, None, v),
        }
    }
}

/// No depth buffer: depth off, every covered pixel in the depth range drawn, in the colour target's rows and
/// columns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoDepth;

impl IntoDepth<'static, 'static> for NoDepth {
    type Format = W16;
    #[inline(always)]
    fn into_depth(self) -> Option<&'static mut DepthBuffer<'static, W16>> {
        None
    }
    #[inline(always)]
    fn draw_triangle<R: WSpan, D, V>(
        &mut self,
        r: &mut Rasterizer<R>,
        target: &mut D,
        v: &[V; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        V: VertexInput<Color = D::Color>,
    {
        r.draw_packed::<W16, D>(target, None, v)
    }
}

impl<R: WSpan> Rasterizer<R> {
    /// Draws one flat-coloured triangle (the colour of its first vertex) into `target` and `depth`: a depth buffer
    /// of any format (`&mut DepthBuffer<F>`), an `Option` of one, or [`NoDepth`] (depth off; the
    /// rows and columns are then the target's). A W16 buffer with a per-pixel reciprocal ([`crate::recip::SpanRecip`]) takes the
    /// fast tier's loops (or the exact tier's, with [`crate::recip::Exact`]); any other format or strategy the span
    /// loop generic over both (`crate::packed`). The choice is the types', made at compile time: a firmware links
    /// only the loops of the format and strategy it names. The depth test runs before any colour work for the pixel
    /// (the Windows CE "Depth Buffering" docs): a passing pixel's colour is sent with its run. On an error nothing is
    /// written, except for a failing `target` ([`Error::Target`] says what is left).
    pub fn draw<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        mut depth: B,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        depth.draw_triangle(self, target, v)
    }

    /// [`Rasterizer::draw`] through the span loop generic over the format and the strategy whatever the format,
    /// W16 included (which `draw` gives to its own loops where the strategy is a per-pixel reciprocal): the tests
    /// compare the two on W16. Not for firmware.
    #[doc(hidden)]
    pub fn draw_generic<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        depth: B,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        self.draw_packed(target, depth.into_depth(), v)
    }

    /// Draws one point (the pixel containing it, at its own depth; never biased) into `depth` as
    /// [`Rasterizer::draw`] takes it. On an error nothing is written, except for a failing `target`
    /// ([`Error::Target`]).
    pub fn draw_point<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        depth: B,
        v: &impl VertexInput<Color = D::Color>,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        self.point_any(target, depth.into_depth(), v)
    }

    /// Draws one line from `v[0]` to `v[1]` (flat, `v[0]`'s colour; never biased) into `depth` as
    /// [`Rasterizer::draw`] takes it. On an error nothing is written, except for a failing `target`
    /// ([`Error::Target`]).
    ///
    /// Points, lines and wireframe triangles (the Windows CE "Depth Buffering" docs' primitives), through the same `T` (RHW) path, the same
    /// W strategy and the same depth test as solid triangles. Depth bias applies to wireframe triangles, never to points
    /// or lines (the Windows CE "Depth Buffering" docs).
    ///
    /// Rules. A point covers the pixel that contains it, `(floor x, floor y)`, at its own depth. A line covers, for each
    /// column (x-major, `|dx| >= |dy|`) or row (y-major) whose pixel centre lies in `[start, end)` of the snapped
    /// endpoints' major coordinate (ordered increasing), the pixel containing the line's point at that centre: one pixel
    /// per major step, the upper endpoint excluded, so connected lines share no pixel. `T` along it is the line's exact
    /// interpolation at the pixel centre, its step rounded once (as for triangles: at `k` steps it errs by at most
    /// `(1 + k) / 2` units of `2^-F`). A wireframe triangle is culled like a solid one and draws its three edges with the
    /// triangle's depth bias, in its first vertex's colour.
    pub fn draw_line<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        depth: B,
        v: &[impl VertexInput<Color = D::Color>; 2],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        self.line_any(target, depth.into_depth(), v)
    }

    /// Draws the three edges of a triangle, culled like a solid one, with its depth bias, into `depth` as
    /// [`Rasterizer::draw`] takes it. On an error nothing is written, except for a failing `target`
    /// ([`Error::Target`]).
    pub fn draw_wireframe<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        depth: B,
        v: &[impl VertexInput<Color = D::Color>; 3],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        self.wireframe_any(target, depth.into_depth(), v)
    }
}

#[cfg(test)]
mod tests {
    use crate::format::{W16, Z16};
    use crate::packed::code_tests::Sink;
    use crate::recip::{Fast, Quake};
    use crate::setup::T_AT_SNAPPED_CALLS;
    use crate::{DepthBuffer, NoDepth, Rasterizer, RenderState, Vertex};
    use embedded_graphics_core::pixelcolor::BinaryColor;
    use std::vec;

    /// Which loop a draw takes, seen from the fast tier's set-up: only the W16 draw of a per-pixel-reciprocal
    /// strategy computes the depth-grid values at the snapped vertices (`t_at_snapped`, for a triangle off the snap
    /// grid), so a W16 buffer given as `&mut` or as `Some` with `Fast` calls it once, and the generic loop
    /// (`draw_generic`, `Quake` with a W16 buffer, another format, `NoDepth`) never does.
    #[test]
    fn the_types_choose_the_loop() {
        let on = BinaryColor::On;
        let t = [
            Vertex::new(1.3, 1.7, 16.0, on),
            Vertex::new(30.1, 2.9, 20.0, on),
            Vertex::new(3.7, 29.2, 24.0, on),
        ];
        let state = RenderState::new(1.0, 64.0).unwrap();
        let calls = |f: &mut dyn FnMut()| {
            T_AT_SNAPPED_CALLS.with(|c| c.borrow_mut().clear());
            f();
            T_AT_SNAPPED_CALLS.with(|c| c.borrow().len())
        };
        let mut w16 = vec![0u16; 32 * 32];
        let mut z16 = vec![0u16; 32 * 32];
        let mut fast = Rasterizer::<Fast>::new(state);
        let mut quake = Rasterizer::<Quake<8>>::new(state);
        let mut d = DepthBuffer::new(&mut w16, 32, 32).unwrap();
        d.clear();
        assert_eq!(
            calls(&mut || {
                fast.draw(&mut Sink, &mut d, &t).unwrap();
            }),
            1
        );
        d.clear();
        assert_eq!(
            calls(&mut || {
                fast.draw(&mut Sink, Some(&mut d), &t).unwrap();
            }),
            1
        );
        d.clear();
        assert_eq!(
            calls(&mut || {
                fast.draw_generic(&mut Sink, &mut d, &t).unwrap();
            }),
            0
        );
        d.clear();
        assert_eq!(
            calls(&mut || {
                quake.draw(&mut Sink, &mut d, &t).unwrap();
            }),
            0
        );
        let mut z = DepthBuffer::<Z16>::new_format(&mut z16, 32, 32).unwrap();
        z.clear_for(&state.range);
        assert_eq!(
            calls(&mut || {
                fast.draw(&mut Sink, &mut z, &t).unwrap();
            }),
            0
        );
        assert_eq!(
            calls(&mut || {
                fast.draw(&mut Sink, NoDepth, &t).unwrap();
            }),
            0
        );
        let none = || None::<&mut DepthBuffer<'_, W16>>;
        assert_eq!(
            calls(&mut || {
                fast.draw(&mut Sink, none(), &t).unwrap();
            }),
            0
        );
        // The draws wrote: the dispatch is not an early return.
        assert!(w16.iter().filter(|&&c| c != 0xffff).count() > 300);
        assert!(z16.iter().filter(|&&c| c != 0xffff).count() > 300);
    }
}
