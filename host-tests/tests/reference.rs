//! The core against the independent f64 reference: coverage, depth, visibility, meshes.

use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::*;
use host_tests::{
    random_tri, reference_frame, reference_tri, reference_writes, render, Frame, Rng,
};
use wraster::recip::{PerPixel, PrevPixel, SpanRecip};
use wraster::{Compare, DepthBuffer, Rasterizer, RenderState, Vertex, W16_FAR};

const W: u16 = 96;
const H: u16 = 64;

struct Tally {
    pixels: u64,
    exact: u64,
    max_diff: i32,
}

/// Draws each triangle alone into a cleared buffer with `cmp` (`Always`, or `Less`, the fast tier's comparison), so
/// written pixels are the covered ones in range (with `Less`, but for those whose code may round to the cleared 65535),
/// and compares every pixel with the reference.
fn compare_each<R: SpanRecip>(
    cmp: Compare,
    seed: u64,
    count: usize,
    near: f32,
    far: f32,
    wmin: f64,
    wmax: f64,
) -> Tally {
    compare_each_of::<R>(cmp, seed, count, near, far, |rng| {
        random_tri(rng, wmin, wmax)
    })
}

/// [`compare_each`] over the triangles `tri` makes.
fn compare_each_of<R: SpanRecip>(
    cmp: Compare,
    seed: u64,
    count: usize,
    near: f32,
    far: f32,
    mut tri_of: impl FnMut(&mut Rng) -> [Vertex<Rgb565>; 3],
) -> Tally {
    let mut rng = Rng(seed);
    let mut state = RenderState::new(near, far).unwrap();
    state.compare = cmp;
    let mut r = Rasterizer::<R>::new(state);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut tally = Tally {
        pixels: 0,
        exact: 0,
        max_diff: 0,
    };
    for n in 0..count {
        let tri = tri_of(&mut rng);
        let mut frame = Frame::new(W as u32, H as u32);
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        let stats = r.draw(&mut frame, &mut buf, &tri).unwrap();
        let v = tri.map(|q| (q.x, q.y, q.rhw));
        let reference = reference_tri(&v, near, far, W as i32, 0..H as i32);
        let want: Vec<_> = reference
            .clone()
            .unwrap_or_default()
            .into_iter()
            .filter(|p| p.in_range)
            .collect();
        assert_eq!(
            stats.culled,
            u32::from(reference.is_none()),
            "triangle {n}: {tri:?}"
        );
        let mut expect_written = vec![false; frame.writes.len()];
        // With Less, a pixel whose exact code is within 1 of the cleared 65535 may round either way.
        let mut either = vec![false; frame.writes.len()];
        for p in &want {
            let k = p.y as usize * W as usize + p.x as usize;
            expect_written[k] = true;
            either[k] = cmp == Compare::Less && p.code >= W16_FAR - 1;
            let got = depth[k];
            let d = (got as i32 - p.code as i32).abs();
            assert!(
                d <= 1,
                "triangle {n} pixel ({}, {}): stored {got}, reference {} (t = {})",
                p.x,
                p.y,
                p.code,
                p.t
            );
            tally.max_diff = tally.max_diff.max(d);
            tally.exact += u64::from(d == 0);
        }
        tally.pixels += want.len() as u64;
        for (k, (&w, &e)) in frame.writes.iter().zip(&expect_written).enumerate() {
            if either[k] {
                assert!(w <= 1);
                continue;
            }
            assert_eq!(
                w,
                u32::from(e),
                "triangle {n}: coverage differs at ({}, {}) {tri:?}",
                k % W as usize,
                k / W as usize
            );
        }
        let unsure = either.iter().filter(|&&e| e).count();
        assert!((stats.written as usize).abs_diff(want.len()) <= unsure);
    }
    tally
}

/// Coverage equal to the reference on 100,000 random triangles (sub-pixel slivers to many times the frame, both
/// windings, vertices on pixel centres and on sub-pixel ties), with every depth in range, so written = covered.
#[test]
fn coverage_equals_reference_on_100k_triangles() {
    let t = compare_each::<PerPixel<wraster::recip::DefaultRecip>>(
        Compare::Always,
        1,
        100_000,
        1.0,
        1.0e4,
        1.5,
        9000.0,
    );
    println!("coverage: {} pixels, all equal to the reference", t.pixels);
    assert!(
        t.pixels > 10_000_000,
        "the sweep must cover many pixels: {}",
        t.pixels
    );
}

/// The same sweep through the fast tier, whose small triangles (box under 127 px) are set up in 32-bit arithmetic
/// relative to their box (`Edge::new_small`) with the plane from a reciprocal of the area: the same pixels.
#[test]
fn fast_tier_coverage_equals_reference_on_100k_triangles() {
    let t =
        compare_each::<wraster::recip::Fast>(Compare::Always, 1, 100_000, 1.0, 1.0e4, 1.5, 9000.0);
    println!(
        "fast tier coverage: {} pixels, all equal to the reference",
        t.pixels
    );
    assert!(t.pixels > 10_000_000);
}

/// Depth within 1 LSB everywhere and at least 99.9% exact, for far/near from 10 to 1e4 with vertices in and out of
/// the range (so the per-pixel clip is checked too).
///
/// The bound: the default reciprocal errs by at most 2^-28.4 relative (recip.rs) and normalising T by 2^-31; the
/// plane by (1 + k + l)/2 units of 2^-F with F >= 47 for t < 2^14, below 2^-33 relative here. So the code
/// `65535/t` errs by less than 65535 * 2^-28.1 < 2^-12 LSB: the stored value is the rounded exact one unless the exact
/// value lies within 2^-12 of a rounding boundary, never more than 1 LSB off, and at most 2 * 2^-12 = 0.05% of pixels
/// (for uniformly spread fractions) differ: at least 99.95% exact, asserted as derived.
#[test]
fn depth_within_one_lsb_and_almost_always_exact() {
    depth_suite::<PerPixel<wraster::recip::DefaultRecip>>(
        Compare::Always,
        "exact tier",
        1.0 - 2.0 * 2f64.powi(-12),
    );
}

/// The four depth ranges of the tests here: far/near 10 to 1e4, 12,000 random triangles each, vertices in and out of
/// the range; every code within 1 LSB (asserted by `compare_each`) and at least `bound` of them exact.
fn depth_suite<R: SpanRecip>(cmp: Compare, name: &str, bound: f64) {
    for (k, far) in [10.0f32, 100.0, 1000.0, 1.0e4].into_iter().enumerate() {
        let t = compare_each::<R>(
            cmp,
            100 + k as u64,
            12_000,
            1.0,
            far,
            0.8,
            far as f64 * 1.25,
        );
        let frac = t.exact as f64 / t.pixels as f64;
        println!(
            "{name} far/near={far}: {} pixels, {} exact ({:.5}%), max diff {}",
            t.pixels,
            t.exact,
            100.0 * frac,
            t.max_diff
        );
        assert!(t.pixels > 500_000);
        assert!(frac >= bound, "far/near {far}: only {frac} exact");
    }
}

/// The fast tier (the default strategy, `Less`): its bound is `FAST_MAX_REL_ERROR` = 2^-27.2 relative (src/fast.rs),
/// plus the plane's 2^-33 (as above), so a code errs by less than 65535 * 2^-27.1 < 2^-11.1 LSB: never more than 1 LSB
/// off, and exact unless the exact value lies within 2^-11.1 of a rounding boundary, so at least
/// 1 - 2 * 2^-11.1 = 99.9% exact (uniformly spread fractions). Same suites as the exact tier's test above; coverage
/// equal to the reference on every pixel.
#[test]
fn fast_tier_within_one_lsb_and_999_exact() {
    depth_suite::<wraster::recip::Fast>(Compare::Less, "fast tier", 1.0 - 2.0 * 2f64.powf(-11.1));
}

/// The fast tier seeded by division (`FastDiv`, the M4's and RV32's default): the same loops and the same derived
/// bound (its seed is below `2^-15 (1 + 2^-14)`, inside the `2^-14.8` the bound assumes), so the same contract.
#[test]
fn fast_div_tier_within_one_lsb_and_999_exact() {
    depth_suite::<wraster::recip::FastDiv>(
        Compare::Less,
        "fast-div tier",
        1.0 - 2.0 * 2f64.powf(-11.1),
    );
}

/// A random small triangle: a box of 1 to 127 px (log-uniform) anywhere over the 96 x 64 frame (so partly outside it
/// too), vertices on sub-pixel ties or pixel centres a quarter of the time each, both windings, and depths within a
/// factor `ratio` (log-uniform up to 64) of each other around a depth anywhere in `[wmin, wmax]`.
fn small_tri(rng: &mut Rng, wmin: f64, wmax: f64) -> [Vertex<Rgb565>; 3] {
    let size = rng.log(1.0, 127.0);
    let (x0, y0) = (rng.f(-20.0, 100.0), rng.f(-20.0, 70.0));
    let base = rng.log(wmin, wmax);
    let ratio = rng.log(1.0, 64.0);
    let c = Rgb565::new((rng.bits() % 32) as u8, (rng.bits() % 64) as u8, 0);
    [0; 3].map(|_| {
        let (mut x, mut y) = (x0 + rng.f(0.0, size), y0 + rng.f(0.0, size));
        match rng.bits() % 4 {
            0 => (x, y) = (x.floor() + 0.5, y.floor() + 0.5),
            1 => {
                (x, y) = (
                    (x * 256.0).floor() / 256.0 + 1.0 / 512.0,
                    (y * 256.0).floor() / 256.0 + 1.0 / 512.0,
                )
            }
            _ => {}
        }
        Vertex::new(x as f32, y as f32, (base * rng.log(1.0, ratio)) as f32, c)
    })
}

/// The fast tier on 100,000 small triangles (`small_tri`: boxes of 1 to 127 px, the ones its small-triangle loop
/// takes and their neighbours) at far/near 10, 100, 1000 and 1e4, with `Less`: coverage equal to the reference on
/// every pixel (asserted by `compare_each`: written = covered in range), every code within 1 LSB, and at least
/// `1 - 2 * 2^-11.1 = 99.9%` exact, the fast tier's derived share (see the test below; `src/small.rs` derives its
/// loop's `5.9e-9`, inside the tier's `2^-27.2`).
#[test]
fn fast_tier_small_triangles_cover_and_hold_the_contract() {
    small_suite::<wraster::recip::Fast>("fast tier");
}

/// The same 100,000 small triangles with the division-seeded fast tier (`FastDiv`): the same bound and contract.
#[test]
fn fast_div_tier_small_triangles_cover_and_hold_the_contract() {
    small_suite::<wraster::recip::FastDiv>("fast-div tier");
}

fn small_suite<R: SpanRecip>(name: &str) {
    let mut all = 0;
    for (k, far) in [10.0f32, 100.0, 1000.0, 1.0e4].into_iter().enumerate() {
        let t = compare_each_of::<R>(Compare::Less, 900 + k as u64, 25_000, 1.0, far, |rng| {
            small_tri(rng, 0.8, far as f64 * 1.25)
        });
        let frac = t.exact as f64 / t.pixels as f64;
        println!(
            "{name}, small triangles, far/near={far}: {} pixels, {} exact ({:.5}%), max diff {}",
            t.pixels,
            t.exact,
            100.0 * frac,
            t.max_diff
        );
        assert!(
            t.pixels > 400_000,
            "the sweep must cover many pixels: {}",
            t.pixels
        );
        assert!(
            frac >= 1.0 - 2.0 * 2f64.powf(-11.1),
            "far/near {far}: only {frac} exact"
        );
        all += t.pixels;
    }
    println!("{name}, small triangles: {all} pixels over 100,000 triangles");
}

/// The previous-pixel seed: bound 2^-21.98 (recip.rs), so codes err by at most 65535 * 2^-21.98 < 2^-5.9 LSB:
/// within 1 LSB always, and exact for at least 1 - 2 * 2^-5.9 = 96.6% of pixels.
#[test]
fn prev_pixel_depth_within_one_lsb() {
    let t = compare_each::<PrevPixel>(Compare::Always, 7, 20_000, 1.0, 1000.0, 1.0, 1000.0);
    let frac = t.exact as f64 / t.pixels as f64;
    println!(
        "prev-pixel: {} pixels, {:.4}% exact, max diff {}",
        t.pixels,
        100.0 * frac,
        t.max_diff
    );
    assert!(frac >= 1.0 - 2.0 * 2f64.powf(-5.9));
}

/// Triangles sharing edges cover every pixel exactly once: a jittered grid whose outer border is the frame's
/// rectangle, and a fan around an interior point.
#[test]
fn meshes_cover_every_pixel_exactly_once() {
    let mut rng = Rng(99);
    for round in 0..40 {
        let (nx, ny) = (8usize, 6usize);
        let mut grid = vec![(0f32, 0f32); (nx + 1) * (ny + 1)];
        for j in 0..=ny {
            for i in 0..=nx {
                let (mut x, mut y) = (
                    i as f32 * W as f32 / nx as f32,
                    j as f32 * H as f32 / ny as f32,
                );
                if i > 0 && i < nx && j > 0 && j < ny {
                    // interior vertices jittered (by at most 2.5 px on a 12 x 10.7 px grid, so every quad stays
                    // convex and no triangle folds over its neighbour), half of them onto pixel centres or sub-pixel ties
                    x += rng.f(-2.5, 2.5) as f32;
                    y += rng.f(-2.5, 2.5) as f32;
                    if round % 2 == 0 {
                        x = x.floor() + 0.5;
                        y = (y * 256.0).floor() / 256.0 + 1.0 / 512.0;
                    }
                }
                grid[j * (nx + 1) + i] = (x, y);
            }
        }
        let mut tris = Vec::new();
        let v = |k: usize| Vertex::new(grid[k].0, grid[k].1, 5.0, Rgb565::WHITE);
        for j in 0..ny {
            for i in 0..nx {
                let a = j * (nx + 1) + i;
                let (b, c, d) = (a + 1, a + nx + 2, a + nx + 1);
                if round % 3 == 0 {
                    tris.push([v(a), v(b), v(c)]);
                    tris.push([v(a), v(d), v(c)]); // the other winding
                } else {
                    tris.push([v(a), v(b), v(d)]);
                    tris.push([v(b), v(c), v(d)]);
                }
            }
        }
        let mut state = RenderState::new(1.0, 10.0).unwrap();
        state.compare = Compare::Always;
        let (frame, _, _) =
            render::<PerPixel<wraster::recip::DefaultRecip>>(&tris, state, W, H, H).unwrap();
        assert!(
            frame.writes.iter().all(|&n| n == 1),
            "round {round}: a pixel written {:?} times",
            frame.writes.iter().find(|&&n| n != 1)
        );
    }
    // A fan of 64 triangles around an interior point covering the frame's rectangle.
    let c = (37.3f32, 29.5f32);
    let mut border = Vec::new();
    for k in 0..16 {
        border.push((k as f32 * W as f32 / 16.0, 0.0));
    }
    for k in 0..16 {
        border.push((W as f32, k as f32 * H as f32 / 16.0));
    }
    for k in 0..16 {
        border.push((W as f32 - k as f32 * W as f32 / 16.0, H as f32));
    }
    for k in 0..16 {
        border.push((0.0, H as f32 - k as f32 * H as f32 / 16.0));
    }
    let tris: Vec<_> = (0..border.len())
        .map(|k| {
            let (a, b) = (border[k], border[(k + 1) % border.len()]);
            [
                Vertex::new(c.0, c.1, 3.0, Rgb565::RED),
                Vertex::new(a.0, a.1, 3.0, Rgb565::RED),
                Vertex::new(b.0, b.1, 3.0, Rgb565::RED),
            ]
        })
        .collect();
    let mut state = RenderState::new(1.0, 10.0).unwrap();
    state.compare = Compare::Always;
    let (frame, _, _) =
        render::<PerPixel<wraster::recip::DefaultRecip>>(&tris, state, W, H, H).unwrap();
    assert!(frame.writes.iter().all(|&n| n == 1));
}

/// Interpenetrating triangles: the final colour equals the reference's everywhere except where the two nearest
/// surfaces' exact depths are within 2 LSB (each stored value may be 1 LSB off, so either may win there).
#[test]
fn visibility_of_interpenetrating_triangles_matches_reference() {
    let mut rng = Rng(4242);
    let (mut pixels, mut differ, mut excused) = (0u64, 0u64, 0u64);
    for _ in 0..3000 {
        let far = 1000.0f32;
        // two large triangles whose depths cross: one leaning forward, one leaning back
        let mut tris = Vec::new();
        for k in 0..2 {
            let c = if k == 0 { Rgb565::RED } else { Rgb565::BLUE };
            let (wa, wb) = (rng.log(2.0, 900.0), rng.log(2.0, 900.0));
            let v = [
                Vertex::new(
                    rng.f(-20.0, 40.0) as f32,
                    rng.f(-20.0, 80.0) as f32,
                    wa as f32,
                    c,
                ),
                Vertex::new(
                    rng.f(60.0, 120.0) as f32,
                    rng.f(-20.0, 80.0) as f32,
                    wb as f32,
                    c,
                ),
                Vertex::new(
                    rng.f(0.0, 96.0) as f32,
                    rng.f(-30.0, 90.0) as f32,
                    rng.log(2.0, 900.0) as f32,
                    c,
                ),
            ];
            tris.push(v);
        }
        let state = RenderState::new(1.0, far).unwrap();
        let (frame, _, _) =
            render::<PerPixel<wraster::recip::DefaultRecip>>(&tris, state, W, H, H).unwrap();
        let reference = reference_frame(&tris, 1.0, far, W as u32, H as u32);
        for k in 0..frame.px.len() {
            if reference.px[k] != Rgb565::BLACK || frame.px[k] != Rgb565::BLACK {
                pixels += 1;
            }
            if frame.px[k] != reference.px[k] {
                let gap_lsb = (reference.runner_up[k] - reference.depth[k]) * 65535.0;
                assert!(
                    gap_lsb <= 2.0,
                    "pixel {k}: colour differs with surfaces {gap_lsb} LSB apart"
                );
                excused += 1;
            }
            differ += u64::from(frame.px[k] != reference.px[k]);
        }
    }
    println!("visibility: {pixels} pixels, {differ} differ, all of them where the surfaces are within 2 LSB ({excused})");
    assert!(pixels > 5_000_000);
}

/// The standard scenes drawn in bands of many heights equal the whole frame, colour and depth, bit for bit.
#[test]
fn banded_rendering_equals_whole_frame() {
    use wraster::scenes::{Scene, HEIGHT, WIDTH};
    for scene in Scene::ALL {
        let tris: Vec<_> = scene.tris().collect();
        let (n, f) = scene.depth_range();
        let state = RenderState::new(n, f).unwrap();
        let whole =
            render::<PerPixel<wraster::recip::DefaultRecip>>(&tris, state, WIDTH, HEIGHT, HEIGHT)
                .unwrap();
        assert!(whole.2.written > 10_000, "{}", scene.name());
        for band in [1u16, 7, 8, 16, 61] {
            let banded =
                render::<PerPixel<wraster::recip::DefaultRecip>>(&tris, state, WIDTH, HEIGHT, band)
                    .unwrap();
            assert!(
                banded.0.px == whole.0.px,
                "{} bands of {band}: colour differs",
                scene.name()
            );
            assert!(
                banded.1 == whole.1,
                "{} bands of {band}: depth differs",
                scene.name()
            );
            assert_eq!(banded.2.written, whole.2.written);
        }
        assert!(whole.1.iter().any(|&d| d != W16_FAR));
    }
}

#[test]
fn frame_target_reports_writes_outside() {
    // The checked target is what makes "no write outside the buffers" testable: it must catch one.
    let r = std::panic::catch_unwind(|| {
        let mut f = Frame::new(4, 4);
        let _ = Pixel(Point::new(4, 0), Rgb565::RED).draw(&mut f);
    });
    assert!(r.is_err());
}

/// Horizontal edges whose row of centres lies exactly on them (the only rows a horizontal edge can refuse: a
/// bottom edge is not top-left) and just off them, at the top and the bottom of triangles of both windings and both
/// strategies' set-ups (the fast tier's small triangles and the general one): coverage equal to the reference.
#[test]
fn horizontal_edges_on_pixel_centres_match_reference() {
    let mut checked = 0;
    for dy in [0.0f32, 1.0 / 512.0, -1.0 / 512.0] {
        for (w, h) in [(5.0f32, 4.0f32), (40.0, 30.0), (150.0, 60.0)] {
            for x0 in [3.5f32, 3.25, 4.0] {
                let y = 10.5 + dy;
                let shapes = [
                    // flat top, flat bottom
                    [(x0, y), (x0 + w, y), (x0 + w / 3.0, y + h)],
                    [(x0, y + h), (x0 + w, y + h), (x0 + w / 2.0, y)],
                ];
                for s in shapes {
                    for flip in [false, true] {
                        let mut v = s.map(|(x, y)| Vertex::new(x, y, 50.0, Rgb565::RED));
                        if flip {
                            v.swap(1, 2);
                        }
                        for strategy in 0..2 {
                            let mut state = RenderState::new(1.0, 1000.0).unwrap();
                            state.compare = Compare::Always;
                            let (ww, hh) = (200u16, 80u16);
                            let mut frame = Frame::new(ww as u32, hh as u32);
                            let mut depth = vec![W16_FAR; ww as usize * hh as usize];
                            let mut buf = DepthBuffer::new(&mut depth, ww, hh).unwrap();
                            if strategy == 0 {
                                Rasterizer::<wraster::recip::Fast>::new(state)
                                    .draw(&mut frame, &mut buf, &v)
                                    .unwrap();
                            } else {
                                Rasterizer::<wraster::recip::Exact>::new(state)
                                    .draw(&mut frame, &mut buf, &v)
                                    .unwrap();
                            }
                            let (expect, covered) =
                                reference_writes(&v, 1.0, 1000.0, ww as u32, hh as u32);
                            assert_eq!(frame.writes, expect, "{v:?} strategy {strategy}");
                            checked += covered;
                        }
                    }
                }
            }
        }
    }
    assert!(checked > 50_000, "{checked}");
}

/// `row_range` (the rows a triangle can cover, for binning into bands) against the rows whose centres `j + 0.5` lie in
/// the snapped vertices' y-range, computed here in f64 (exact: snapped values are multiples of 1/256), and every row
/// the reference covers lies inside it.
#[test]
fn row_range_is_the_rows_of_the_snapped_y_range() {
    let mut rng = Rng(0x0e0e_5eed);
    let mut covered = 0usize;
    for _ in 0..5_000 {
        let tri = random_tri(&mut rng, 10.0, 1000.0);
        let (first, last) = wraster::row_range(&tri).unwrap();
        let ys = tri.map(|v| host_tests::snap(v.y) as f64 / 256.0);
        let (lo, hi) = (
            ys.iter().cloned().fold(f64::MAX, f64::min),
            ys.iter().cloned().fold(f64::MIN, f64::max),
        );
        assert_eq!(
            (first, last),
            ((lo - 0.5).ceil() as i32, (hi - 0.5).floor() as i32),
            "{tri:?}"
        );
        let v = tri.map(|q| (q.x, q.y, q.rhw));
        for p in reference_tri(&v, 10.0, 1000.0, W as i32, -1000..1000).unwrap_or_default() {
            assert!(
                (first..=last).contains(&p.y),
                "row {} outside {first}..={last}: {tri:?}",
                p.y
            );
            covered += 1;
        }
    }
    assert!(covered > 100_000, "{covered} covered pixels checked");
}
