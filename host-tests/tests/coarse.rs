//! The coarse depth bound (feature `coarse`, `DepthBuffer::with_bound`): it only skips work. With it, every frame
//! and every stored code equal those drawn without it; it always bounds what the buffer holds; it is tight (the
//! exact largest code) on segments the W16 spans drew; and a draw that may raise codes switches it off until the
//! next clear.

use embedded_graphics::pixelcolor::Rgb565;
use host_tests::{random_tri, Frame, Rng};
use wraster::recip::{Exact, Fast, FastDiv, SpanRecip};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::{bound_len, Compare, DepthBuffer, Rasterizer, RenderState, Stats, Vertex};

type Tri = [Vertex<Rgb565>; 3];

/// Draws `tris` in bands of `band_h` rows, with the bound or without it. After every draw with the bound, each
/// segment's bound is at least the largest code stored in it. Returns the frame, the depth and the stats.
fn draw<R: SpanRecip>(
    tris: &[Tri],
    state: RenderState,
    (w, h): (u16, u16),
    band_h: u16,
    with_bound: bool,
) -> (Frame, Vec<u16>, Stats) {
    let mut frame = Frame::new(w as u32, h as u32);
    let mut depth = vec![0u16; w as usize * h as usize];
    let mut r = Rasterizer::<R>::new(state);
    let mut stats = Stats::default();
    let mut y0 = 0u16;
    while y0 < h {
        let bh = band_h.min(h - y0);
        let n = w as usize * bh as usize;
        let slice = &mut depth[y0 as usize * w as usize..][..n];
        let mut seg = vec![0u16; bound_len(w as usize, bh as usize)];
        let mut buf = DepthBuffer::band(slice, w, y0 as i32, bh).unwrap();
        if with_bound {
            buf = buf.with_bound(&mut seg).unwrap();
        }
        buf.clear();
        for t in tris {
            stats += r.draw(&mut frame, &mut buf, t).unwrap();
            if with_bound {
                assert_bounds(&buf);
            }
        }
        y0 += bh;
    }
    (frame, depth, stats)
}

/// Every segment's bound is at least every code stored in it.
fn assert_bounds(buf: &DepthBuffer<'_>) {
    let bound = buf.bound().expect("a Less draw keeps the bound in use");
    let w = buf.width() as usize;
    let segs = w.div_ceil(8);
    for (r, row) in buf.data().chunks(w).enumerate() {
        for (i, px) in row.chunks(8).enumerate() {
            let max = *px.iter().max().unwrap();
            assert!(
                bound[r * segs + i] >= max,
                "row {r} segment {i}: bound {} below the stored {max}",
                bound[r * segs + i]
            );
        }
    }
}

fn same_with_and_without<R: SpanRecip>(
    tris: &[Tri],
    state: RenderState,
    size: (u16, u16),
    band_h: u16,
) {
    let (fa, da, sa) = draw::<R>(tris, state, size, band_h, false);
    let (fb, db, sb) = draw::<R>(tris, state, size, band_h, true);
    assert!(da == db, "{}: the depth differs with the bound", R::NAME);
    assert!(
        fa.px == fb.px,
        "{}: the frame differs with the bound",
        R::NAME
    );
    assert_eq!(
        (sa.fragments, sa.written),
        (sb.fragments, sb.written),
        "{}",
        R::NAME
    );
}

/// The standard scenes (W1-W3 and terrain), whole-frame and in 8-row bands: the same frames, codes and counts with
/// the bound, for the fast tier (both seeds) and the exact tier.
#[test]
fn the_standard_scenes_are_the_same_with_the_bound() {
    for scene in Scene::ALL {
        let (near, far) = scene.depth_range();
        let tris: Vec<Tri> = scene.tris().collect();
        let state = RenderState::new(near, far).unwrap();
        for band_h in [HEIGHT, 8] {
            same_with_and_without::<FastDiv>(&tris, state, (WIDTH, HEIGHT), band_h);
            same_with_and_without::<Fast>(&tris, state, (WIDTH, HEIGHT), band_h);
            same_with_and_without::<Exact>(&tris, state, (WIDTH, HEIGHT), band_h);
        }
    }
}

/// Random overlapping triangles, far/near from 10 to 1e4, in a frame whose width is not a multiple of 8 (the last
/// segment of a row is short) and in bands of 5 rows: the same frames and codes with the bound.
#[test]
fn random_overdraw_is_the_same_with_the_bound() {
    let mut rng = Rng(0xC0A5_0001);
    for (wmax, frames) in [(10.0, 40), (1e3, 40), (1e4, 40)] {
        for _ in 0..frames {
            let tris: Vec<Tri> = (0..24).map(|_| random_tri(&mut rng, 1.0, wmax)).collect();
            let state = RenderState::new(1.0, wmax as f32).unwrap();
            same_with_and_without::<FastDiv>(&tris, state, (100, 64), 64);
            same_with_and_without::<Fast>(&tris, state, (100, 64), 5);
        }
    }
}

/// After one big triangle (W1) the bound of the aligned segments that the fast tier's span loop drew whole is within
/// one code above each segment's largest code, not the far code it started from: the bound is lowered as the
/// buffer is written, to one above the larger end code of the segment (the fast tier's codes are within `2^-11.1`
/// of the exact ones, which are monotone along a span, so no middle code exceeds the larger end's by more than one).
/// Spans drawn by the per-pixel loop (short or steep ones) leave their segments' bounds as they were, still above.
#[test]
fn the_bound_is_the_largest_code_where_a_span_drew() {
    let tris: Vec<Tri> = Scene::Big.tris().collect();
    let (near, far) = Scene::Big.depth_range();
    let mut r = Rasterizer::<FastDiv>::new(RenderState::new(near, far).unwrap());
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let mut data = vec![0u16; w * h];
    let mut seg = vec![0u16; bound_len(w, h)];
    let mut buf = DepthBuffer::new(&mut data, WIDTH, HEIGHT)
        .unwrap()
        .with_bound(&mut seg)
        .unwrap();
    buf.clear();
    let mut frame = Frame::new(w as u32, h as u32);
    r.draw(&mut frame, &mut buf, &tris[0]).unwrap();
    let bound = buf.bound().unwrap().to_vec();
    let mut tight = 0;
    for (row, px) in buf.data().chunks(w).enumerate() {
        for (i, s) in px.chunks(8).enumerate() {
            let covered = (0..8).all(|k| frame.writes[row * w + i * 8 + k] > 0);
            let (b, max) = (bound[row * (w / 8) + i], *s.iter().max().unwrap());
            assert!(
                b >= max,
                "row {row} segment {i}: bound {b} below the largest code {max}"
            );
            if covered && b <= max + 1 {
                tight += 1;
            }
        }
    }
    // W1 covers about 32,000 pixels: some 3,000 whole segments, each now within a code of its largest.
    assert!(tight > 3000, "{tight} whole segments");
}

/// A draw that may raise stored codes (`Greater`, `GreaterEqual`, `NotEqual`, `Always` with depth write) stops
/// the bound's use until the next clear, and the frames after it still equal those drawn without a bound.
#[test]
fn a_draw_that_may_raise_codes_switches_the_bound_off_until_a_clear() {
    let mut rng = Rng(0xC0A5_0002);
    let tris: Vec<Tri> = (0..40).map(|_| random_tri(&mut rng, 1.0, 1e3)).collect();
    for cmp in [
        Compare::Greater,
        Compare::GreaterEqual,
        Compare::NotEqual,
        Compare::Always,
    ] {
        let run = |with_bound: bool| {
            let mut data = vec![0u16; 100 * 64];
            let mut seg = vec![0u16; bound_len(100, 64)];
            let mut buf = DepthBuffer::new(&mut data, 100, 64).unwrap();
            if with_bound {
                buf = buf.with_bound(&mut seg).unwrap();
            }
            buf.clear();
            let mut frame = Frame::new(100, 64);
            let less = RenderState::new(1.0, 1e3).unwrap();
            let mut raise = less;
            raise.compare = cmp;
            let (mut a, mut b) = (
                Rasterizer::<FastDiv>::new(less),
                Rasterizer::<FastDiv>::new(raise),
            );
            let mut off = false;
            for (k, t) in tris.iter().enumerate() {
                // every fifth triangle raises codes; the rest are Less
                if k % 5 == 4 {
                    b.draw(&mut frame, &mut buf, t).unwrap();
                    off = true;
                } else {
                    a.draw(&mut frame, &mut buf, t).unwrap();
                }
                if with_bound {
                    assert_eq!(buf.bound().is_none(), off, "{cmp:?} after triangle {k}");
                }
            }
            buf.clear();
            if with_bound {
                assert!(buf.bound().is_some(), "a clear puts the bound back in use");
            }
            for t in &tris {
                a.draw(&mut frame, &mut buf, t).unwrap();
            }
            (frame.px, data)
        };
        assert!(run(false) == run(true), "{cmp:?}");
    }
}

/// A bound of the wrong length is an error, not a panic.
#[test]
fn a_bound_of_the_wrong_length_is_an_error() {
    let mut data = vec![0u16; 100 * 64];
    let mut seg = vec![0u16; bound_len(100, 64) - 1];
    let err = DepthBuffer::new(&mut data, 100, 64)
        .unwrap()
        .with_bound(&mut seg)
        .unwrap_err();
    assert_eq!(
        err,
        wraster::Error::BufferSize {
            expected: 13 * 64,
            actual: 13 * 64 - 1
        }
    );
}
