//! The crate's one `unsafe` module: a cursor that walks a row of W16 codes with no count, stopped by a sentinel.
//!
//! The fast tier's passing runs ([`crate::fast`]) test each pixel's code against the stored one and stop at the first
//! that fails. With a 0 after the run's last pixel, that test also ends the row: no code is below 0, so the cursor
//! can never step past it, and the loop needs neither a count nor a bounds check (three of the Cortex-M4's 22
//! instructions a pixel in the fresh loop went to the count; measured in the README). [`with_sentinel`] puts the 0
//! in place and restores the element it replaced; the cursor is only ever made by it, and only moves by
//! [`Cursor::pass`], so every pointer it holds stays inside the row.
#![allow(unsafe_code)]

use core::marker::PhantomData;

/// A position in a row whose last element is 0 for the cursor's whole life (see the module doc).
pub(crate) struct Cursor<'a> {
    p: *mut u16,
    start: *mut u16,
    _row: PhantomData<&'a mut [u16]>,
}

impl Cursor<'_> {
    /// Tests `c` against the code under the cursor: where `c` is below it, writes `c` there, moves to the next
    /// element and returns `true`; else `false`, the cursor staying on the failing element.
    #[inline(always)]
    pub(crate) fn pass(&mut self, c: u32) -> bool {
        // SAFETY: `p` starts at the row's first element and only moves past an element that is not the row's last
        // (below), so it points at an element of the row, which the cursor borrows exclusively for `'a`.
        let stored = unsafe { &mut *self.p };
        if c < *stored as u32 {
            // `c` is below a `u16`: it fits.
            *stored = c as u16;
            // SAFETY: the element passed was not the last: that one is 0 (`with_sentinel`), and no `u32` is below 0.
            // So `p + 1` is at most the last element, inside the same allocation.
            self.p = unsafe { self.p.add(1) };
            true
        } else {
            false
        }
    }

    /// The elements passed so far: the index of the cursor's element in the row.
    #[inline(always)]
    pub(crate) fn pos(&self) -> usize {
        (self.p as usize - self.start as usize) / core::mem::size_of::<u16>()
    }
}

/// Runs `f` with a cursor at `row[0]`, the row's last element replaced by the sentinel 0 for the duration and
/// restored after: the cursor can pass at most `row.len() - 1` elements, and stops at the last (its
/// [`Cursor::pos`] then `row.len() - 1`) if no earlier one fails. An empty row is walked as a row of one sentinel.
#[inline(always)]
pub(crate) fn with_sentinel<R>(row: &mut [u16], f: impl FnOnce(Cursor<'_>) -> R) -> R {
    let mut lone = [0u16];
    let row = if row.is_empty() { &mut lone[..] } else { row };
    let last = row.len() - 1;
    let saved = core::mem::replace(&mut row[last], 0);
    let start = row.as_mut_ptr();
    // By value: a cursor behind a reference is written back to memory at every step (LLVM cannot tell that the
    // row's stores do not reach it).
    let r = f(Cursor {
        p: start,
        start,
        _row: PhantomData,
    });
    row[last] = saved;
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_at_the_first_fail_or_the_sentinel_and_restores_it() {
        // Codes below the stored ones pass and are written; the first not below stops the cursor.
        let mut row = [10u16, 10, 3, 10, 7];
        let pos = with_sentinel(&mut row, |mut c| {
            let mut n = 0;
            while c.pass(5) {
                n += 1;
            }
            assert_eq!(n, c.pos());
            c.pos()
        });
        assert_eq!((pos, row), (2, [5, 5, 3, 10, 7]));
        // Every element passes but the last, which is restored: the cursor stops on it.
        let mut row = [9u16, 9, 9, 4];
        let pos = with_sentinel(&mut row, |mut c| {
            while c.pass(0) {}
            c.pos()
        });
        assert_eq!((pos, row), (3, [0, 0, 0, 4]));
        // A last element that would pass, and a code that passes everything: still stopped there.
        let mut row = [u16::MAX; 3];
        let pos = with_sentinel(&mut row, |mut c| {
            while c.pass(0) {}
            c.pos()
        });
        assert_eq!((pos, row), (2, [0, 0, u16::MAX]));
        // An empty row: nothing passes.
        let mut row: [u16; 0] = [];
        assert_eq!(
            with_sentinel(&mut row, |mut c| (c.pass(0), c.pos())),
            (false, 0)
        );
    }
}
