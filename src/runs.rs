//! The colour stage of every span loop: the passing pixels of a span go to the target as runs, one `fill_solid` each.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::prelude::{Point, Size};
use embedded_graphics_core::primitives::Rectangle;

use crate::Error;

fn fill<D: DrawTarget>(
    target: &mut D,
    x0: i32,
    x1: i32,
    y: i32,
    color: D::Color,
) -> Result<(), Error> {
    let r = Rectangle::new(Point::new(x0, y), Size::new((x1 - x0) as u32, 1));
    target.fill_solid(&r, color).map_err(|_| Error::Target)
}

/// The passing runs of a span, each sent to the target as one `fill_solid`; counts the failing pixels.
pub(crate) struct Runs<'a, D: DrawTarget> {
    pub(crate) target: &'a mut D,
    pub(crate) lo: i32,
    pub(crate) j: i32,
    pub(crate) color: D::Color,
    /// First pixel (span-relative) of the current run.
    pub(crate) start: usize,
    pub(crate) fails: u32,
}

impl<'a, D: DrawTarget> Runs<'a, D> {
    /// No run yet on row `j`, whose span starts at frame column `lo`.
    #[inline(always)]
    pub(crate) fn new(target: &'a mut D, lo: i32, j: i32, color: D::Color) -> Self {
        Runs {
            target,
            lo,
            j,
            color,
            start: 0,
            fails: 0,
        }
    }
    /// Pixels `start..end` pass: fill them.
    #[inline(always)]
    fn draw(&mut self, start: usize, end: usize) -> Result<(), Error> {
        fill(
            self.target,
            self.lo + start as i32,
            self.lo + end as i32,
            self.j,
            self.color,
        )
    }
    /// Pixel `k` failed: flush the run before it.
    #[inline(always)]
    pub(crate) fn fail(&mut self, k: usize) -> Result<(), Error> {
        self.fail_many(k, k + 1)
    }
    /// Pixels `a..b` fail (none when `a == b`): flush the run before `a`.
    #[inline(always)]
    pub(crate) fn fail_many(&mut self, a: usize, b: usize) -> Result<(), Error> {
        if a < b {
            self.fails += (b - a) as u32;
            let start = core::mem::replace(&mut self.start, b);
            if start < a {
                self.draw(start, a)?;
            }
        }
        Ok(())
    }
    #[inline(always)]
    pub(crate) fn finish(&mut self, n: usize) -> Result<(), Error> {
        if self.start < n {
            self.draw(self.start, n)?;
        }
        Ok(())
    }
}
