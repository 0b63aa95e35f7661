//! Edges and the exact edge walk.
//!
//! Positions are in sub-pixels (1/256 px, [`crate::SUBPIXEL_BITS`]). A triangle is oriented so that its doubled area
//! is positive; then the edge function of the directed edge `a -> b`,
//! `E(p) = (b.x - a.x)(p.y - a.y) - (b.y - a.y)(p.x - a.x) = A p.x + B p.y + C`, is positive inside.
//! A pixel whose centre `(256 i + 128, 256 j + 128)` has `E = 0` is covered only for a top edge (`A = 0, B > 0`:
//! horizontal, interior below) or a left edge (`A > 0`: interior to the right): the top-left rule.
//! So a pixel is covered iff `E(p) - bias >= 0` for all three edges, `bias = 0` on top-left edges and 1 otherwise.
//!
//! Per row, a left edge (`A > 0`) admits `i >= -floor(N / D)` and a right edge (`A < 0`) admits `i <= floor(N / D)`, with
//! `N(j) = B (256 j + 128) + C - bias + 128 A` and `D = 256 |A|`. `N` grows by `256 B` a row, so `floor(N / D)` is
//! walked exactly with a quotient and a remainder (a DDA): no division per row or pixel, only at setup.
//! A horizontal edge admits a whole row or none, and only the row whose centres lie exactly on it can be refused
//! (a bottom edge, which is not top-left): [`flat_rows`] folds that into the triangle's row range at set-up, so the
//! row walk skips horizontal edges.
//!
//! Ranges: with vertices inside the guard band (`|x|, |y| < 2^20` sub-pixels) `|A|, |B| < 2^21`, `|C| < 2^42`, and
//! `|N| < 2^44`: the set-up runs in `i64` (see ARCHITECTURE.md). The walk per row is 32-bit:
//! `0 <= r < D = 256 |A| < 2^29`, `|floor(256 B / D)| < 2^21`, and the quotient `q`, the column where the edge's line
//! crosses the row, is kept within `i32` as follows. A nearly horizontal edge (`|A|` a few sub-pixels) crosses rows
//! a few pixels away at up to `2^21` px a row, so over the triangle's rows `|q|` reaches `2^36` (a fuzz finding: the
//! `i32` quotient overflowed there). But wherever `|q|` is beyond the guard band the edge does not bind: the triangle
//! spans the row, inside the edge's half-plane, so the line crosses the row beyond the triangle, on the far side.
//! So the set-up clamps `q` to `+-2^30` (the same side, as far as matters), and the walk sets the edges up again
//! every [`Edge::rows_exact`] rows, few enough (`K (|step| + 1) <= 2^29`) that `q` neither overflows nor, when it
//! started clamped, comes back within `2^29` of the frame: within a stretch, an exact `q` stays exact, a clamped one
//! stays beyond the guard band.

/// A sub-pixel position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Sub {
    pub x: i32,
    pub y: i32,
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Side {
    Left,
    Right,
    /// Horizontal: no bound on a row of the triangle's range (see [`flat_rows`]).
    Flat,
}

/// One edge, walked row by row: `N = q D + r`, `0 <= r < D`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Edge {
    pub side: Side,
    q: i32,
    r: i32,
    d: i32,
    step_q: i32,
    step_r: i32,
}

impl Edge {
    const FLAT: Edge = Edge {
        side: Side::Flat,
        q: 0,
        r: 0,
        d: 0,
        step_q: 0,
        step_r: 0,
    };

    /// The edge `a -> b` of a triangle with positive doubled area, positioned at row `j`.
    pub fn new(a: Sub, b: Sub, j: i32) -> Edge {
        let a_ = (a.y - b.y) as i64;
        let b_ = (b.x - a.x) as i64;
        if a_ == 0 {
            return Edge::FLAT;
        }
        let top_left = a_ > 0;
        let bias = i64::from(!top_left);
        let n = a_ * (128 - a.x as i64) + b_ * (256 * j as i64 + 128 - a.y as i64) - bias;
        // `|s|, d < 2^29`: the step's quotient in 32 bits. One division each (a 64-bit one is a library call on the
        // 32-bit cores): each remainder from its quotient, exactly, modulo 2^32 (`0 <= r < d < 2^29`). A band sets
        // its large triangles' edges up again (measured on the M0: W2 2.3% and W1 0.9% fewer instructions than with
        // three 64-bit divisions an edge).
        let (s, d) = (256 * b_ as i32, 256 * a_.unsigned_abs() as i32);
        let q = n.div_euclid(d as i64);
        let step_q = s.div_euclid(d);
        const FAR: i64 = 1 << 30;
        Edge {
            side: if a_ > 0 { Side::Left } else { Side::Right },
            q: q.clamp(-FAR, FAR) as i32,
            r: (n as i32).wrapping_sub((q as i32).wrapping_mul(d)),
            d,
            step_q,
            step_r: s.wrapping_sub(step_q.wrapping_mul(d)),
        }
    }

    /// [`Edge::new`] for a triangle whose snapped box is under 127 px each way (the fast tier's small triangles):
    /// the same walk, set up in 32-bit arithmetic relative to the box's origin pixel `(ox, oy)`
    /// (`ox = floor(xmin / 256)`, `oy = floor(ymin / 256)`).
    ///
    /// Relative coordinates are below `2^15`, so `|A|, |B| < 2^15` and both terms of
    /// `N = A (128 - a.x) + B (256 (j - oy) + 128 - a.y) - bias` are below `2^30`: `N` fits `i32`, and the two
    /// divisions are 32-bit (one `SDIV` each on the Cortex-M4, where the 64-bit ones are library calls). Moving the
    /// origin by `ox` pixels adds `256 A ox` to `N`, so the quotient moves by `ox` (left edges) or `-ox` (right edges)
    /// and the remainder is unchanged: the walk is the one [`Edge::new`] sets up.
    pub fn new_small(a: Sub, b: Sub, j: i32, ox: i32, oy: i32) -> Edge {
        let Some((a_, n, s, d)) = small_edge(a, b, j, ox, oy) else {
            return Edge::FLAT;
        };
        let q = n.div_euclid(d);
        Edge {
            side: if a_ > 0 { Side::Left } else { Side::Right },
            q: if a_ > 0 { q - ox } else { q + ox },
            r: n.rem_euclid(d),
            d,
            step_q: s.div_euclid(d),
            step_r: s.rem_euclid(d),
        }
    }

    /// How many rows the walk may step from a set-up before `q` could leave the range the module doc allows:
    /// a power of two `K` with `K (|step_q| + 1) <= 2^29` (at least 128, as `|step_q| < 2^21`).
    pub fn rows_exact(&self) -> i32 {
        let m = self.step_q.unsigned_abs() + 1;
        1 << (29 - (32 - m.leading_zeros())).min(24)
    }

    /// Moves to the next row.
    #[inline(always)]
    pub fn step(&mut self) {
        self.q += self.step_q;
        self.r += self.step_r;
        if self.r >= self.d && self.d != 0 {
            self.r -= self.d;
            self.q += 1;
        }
    }

    /// The bound this edge puts on the current row, as a half-open column range `[lo, hi)`.
    #[inline(always)]
    pub fn bound(&self) -> (i32, i32) {
        match self.side {
            Side::Left => (-self.q, i32::MAX),
            Side::Right => (i32::MIN, self.q + 1),
            Side::Flat => (i32::MIN, i32::MAX),
        }
    }
}

/// [`Edge::new_small`]'s `A`, `N` (below `2^30`), `S = 256 B` (the growth of `N` a row) and `D = 256 |A|` for the
/// directed edge `a -> b` at row `j`, relative to the pixel `(ox, oy)`; `None` for a horizontal edge. Shared with
/// [`DivBound`].
#[inline(always)]
pub(crate) fn small_edge(a: Sub, b: Sub, j: i32, ox: i32, oy: i32) -> Option<(i32, i32, i32, i32)> {
    let (ax, ay) = (a.x - 256 * ox, a.y - 256 * oy);
    let (bx, by) = (b.x - 256 * ox, b.y - 256 * oy);
    let (a_, b_) = (ay - by, bx - ax);
    if a_ == 0 {
        return None;
    }
    let bias = i32::from(a_ < 0);
    let n = a_ * (128 - ax) + b_ * (256 * (j - oy) + 128 - ay) - bias;
    Some((a_, n, 256 * b_, 256 * a_.abs()))
}

/// One edge's column bound on the current row by one division a row, for the small triangles' rows on cores that
/// divide in one instruction (`crate::small`), relative to the box's origin pixel `(ox, oy)`: `N` and `D` of
/// [`Edge::new_small`] (`N` the edge function at the centre of column `ox`, less the bias, below `2^30`; `D = 256 |A|`
/// below `2^23`). A left edge admits the columns from `ceil(-N / D) = floor((D - 1 - N) / D)`, a right edge those up
/// to `floor(N / D)`, one past them `floor((N + D) / D)`; each numerator grows by a constant a row (`-256 B`, `256 B`).
/// The quotient truncates toward zero, which is the floor for a numerator `>= 0`; for a negative one it is at most 0,
/// as is the floor. So [`DivBound::lo`] (`max(0, ...)`) is the left edge's first column exactly where that is in the
/// box, else 0; and [`DivBound::hi`] is the right edge's bound exactly where it is positive, else at most 0. A
/// covered pixel lies in the box (column `>= 0`), so a row's run `[lo, hi)` from them is the exact run, and empty where
/// that is (the unit tests compare them with [`Edge`]'s walk). One `SDIV` and one add a row on the Cortex-M4 and
/// RV32IM, and no set-up division: against the fixed-point walk it replaced (six 32-bit divisions and a call an edge
/// at set-up, then one 64-bit add a row), measured M4 W3 -5.7% and W4 -3.9%, RV32 W3 -7.5% and W4 -4.8%.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DivBound {
    n: i32,
    s: i32,
    d: i32,
}

impl DivBound {
    /// The directed edge `a -> b` of an oriented triangle whose snapped box (origin pixel `(ox, oy)`) is under 127 px
    /// each way, at row `j`: whether it bounds the row on the left, and its bound; `None` for a horizontal edge.
    #[inline(always)]
    pub fn new(a: Sub, b: Sub, j: i32, ox: i32, oy: i32) -> Option<(bool, DivBound)> {
        let (a_, n, s, d) = small_edge(a, b, j, ox, oy)?;
        let left = a_ > 0;
        Some((
            left,
            if left {
                DivBound {
                    n: d - 1 - n,
                    s: -s,
                    d,
                }
            } else {
                DivBound { n: n + d, s, d }
            },
        ))
    }

    /// A left edge's first admitted column on the current row, relative to `ox` (0 where that is left of the box).
    #[inline(always)]
    pub fn lo(&self) -> i32 {
        (self.n / self.d).max(0)
    }

    /// A right edge's column one past its last admitted one on the current row, relative to `ox` (at most 0 where
    /// that is left of the box).
    #[inline(always)]
    pub fn hi(&self) -> i32 {
        self.n / self.d
    }

    /// Moves to the next row.
    #[inline(always)]
    pub fn step(&mut self) {
        self.n += self.s;
    }
}

/// The rows `(first, last)` of a triangle with positive doubled area (`p` oriented), from the rows whose centre lies
/// in its vertices' y-range, less the row whose centres lie exactly on a horizontal bottom edge: with `A = 0` and
/// `B < 0` (interior above) the edge is not top-left, and its `N = B (256 j + 128 - y) - 1` is negative exactly from
/// that row down. A horizontal top edge (`B > 0`) admits every row of the range, its own included.
pub(crate) fn flat_rows(p: &[Sub; 3], (first, mut last): (i32, i32)) -> (i32, i32) {
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        if a.y == b.y && b.x < a.x && (a.y - 128).rem_euclid(256) == 0 && (a.y - 128) / 256 == last
        {
            last -= 1;
        }
    }
    (first, last)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The division bound gives the same columns as the exact quotient-and-remainder walk, row by row, for 126 rows
    /// (the small triangles' most), on random small edges of either side, set up at any row: a left edge's first
    /// column where it is in the box (else 0), a right edge's bound where it is positive (else at most 0).
    #[test]
    fn division_bounds_walk_the_exact_columns() {
        let mut rnd = crate::xorshift(0xfeed_5eed_dead_beef);
        let mut coord = move |n: i64| (rnd() % n as u64) as i32;
        let (mut left, mut right, mut outside) = (0u32, 0u32, 0u32);
        for _ in 0..200_000 {
            // Vertices in a box under 32 x 126 px, relative to origin (ox, oy).
            let (ox, oy) = (coord(600) - 300, coord(600) - 300);
            let sub = |x: i32, y: i32| Sub {
                x: 256 * ox + x,
                y: 256 * oy + y,
            };
            let (a, b) = (
                sub(coord(32 * 256), coord(126 * 256)),
                sub(coord(32 * 256), coord(126 * 256)),
            );
            let j = oy + coord(8);
            let mut e = Edge::new_small(a, b, j, ox, oy);
            let Some((is_left, mut f)) = DivBound::new(a, b, j, ox, oy) else {
                assert!(matches!(e.side, Side::Flat));
                continue;
            };
            assert_eq!(is_left, matches!(e.side, Side::Left));
            for _ in 0..126 {
                // The walk's bound, relative to `ox` (`Edge::new_small` adds `ox` to a right edge's quotient and
                // subtracts it from a left edge's).
                match e.side {
                    Side::Left => {
                        let want = -e.q - ox;
                        assert_eq!(f.lo(), want.max(0), "{a:?} {b:?}");
                        left += 1;
                    }
                    Side::Right => {
                        let want = e.q + 1 - ox;
                        if want > 0 {
                            assert_eq!(f.hi(), want, "{a:?} {b:?}");
                            right += 1;
                        } else {
                            assert!(f.hi() <= 0, "{a:?} {b:?}");
                            outside += 1;
                        }
                    }
                    Side::Flat => unreachable!(),
                }
                e.step();
                f.step();
            }
        }
        // Both sides and both cases of a right edge are exercised.
        assert!(
            left > 1_000_000 && right > 1_000_000 && outside > 100_000,
            "{left} {right} {outside}"
        );
    }
}
