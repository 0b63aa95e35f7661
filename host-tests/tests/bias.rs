//! Depth bias (Microsoft, "Depth Buffering (Windows CE 5.0)": `Offset = m * SLOPESCALEDEPTHBIAS + DEPTHBIAS`), in W16 codes.
//!
//! Two triangles in one plane (1/W affine in screen space, both evaluated from the same plane) fight: each stored
//! code is within 1 LSB of its exact value (the core's depth bound), and the two exact values differ only by the
//! f32 rounding of the vertices' RHW (about 65535 * 2^-22 codes, far below 1), so at a pixel the two stored codes
//! differ by at most 3. With `Less`, a second triangle biased by -4 codes therefore wins at every pixel it covers
//! (no fighting, no gaps), and one whose plane lies 2% farther (over 100 codes here) still loses everywhere.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::Frame;
use wraster::{Compare, DepthBuffer, Rasterizer, RenderState, Vertex};

const W: u16 = 64;
const H: u16 = 48;
const FAR: f32 = 1000.0;

/// 1/W of the plane at a screen point.
fn rhw(x: f32, y: f32) -> f32 {
    (0.05 - 0.0007 * x as f64 - 0.0006 * y as f64) as f32
}

fn tri(p: [(f32, f32); 3], scale: f32, c: Rgb565) -> [Vertex<Rgb565>; 3] {
    p.map(|(x, y)| Vertex {
        x,
        y,
        z: 0.5,
        rhw: rhw(x, y) * scale,
        color: c,
    })
}

const A: [(f32, f32); 3] = [(2.0, 2.0), (62.0, 4.0), (4.0, 46.0)];
const B: [(f32, f32); 3] = [(8.0, 7.0), (50.0, 12.0), (12.0, 38.0)];

/// Pixels B covers, and how many of them show B after drawing A then B.
fn visible(state: RenderState, b_scale: f32) -> (usize, usize) {
    visible_pair(A, B, state, b_scale)
}

/// [`visible`] for any pair of triangles `a`, `b` (`b` inside `a`) in the plane.
fn visible_pair(
    a: [(f32, f32); 3],
    b: [(f32, f32); 3],
    state: RenderState,
    b_scale: f32,
) -> (usize, usize) {
    let mut frame = Frame::new(W as u32, H as u32);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
    buf.clear();
    let mut first = state;
    first.depth_bias = 0.0;
    first.slope_scale_depth_bias = 0.0;
    Rasterizer::<wraster::recip::PerPixel<wraster::recip::DefaultRecip>>::new(first)
        .draw(&mut frame, &mut buf, &tri(a, 1.0, Rgb565::RED))
        .unwrap();
    let before = frame.writes.clone();
    let mut r: Rasterizer = Rasterizer::new(state);
    r.draw(&mut frame, &mut buf, &tri(b, b_scale, Rgb565::BLUE))
        .unwrap();
    // B's coverage, drawn alone
    let mut alone = Frame::new(W as u32, H as u32);
    let mut d2 = vec![0u16; W as usize * H as usize];
    let mut b2 = DepthBuffer::new(&mut d2, W, H).unwrap();
    b2.clear();
    let mut any = state;
    any.compare = Compare::Always;
    Rasterizer::<wraster::recip::PerPixel<wraster::recip::DefaultRecip>>::new(any)
        .draw(&mut alone, &mut b2, &tri(b, b_scale, Rgb565::BLUE))
        .unwrap();
    let covered: Vec<usize> = (0..alone.px.len())
        .filter(|&p| alone.writes[p] > 0)
        .collect();
    assert!(covered.iter().all(|&p| before[p] > 0), "B lies inside A");
    let shown = covered
        .iter()
        .filter(|&&p| frame.px[p] == Rgb565::BLUE)
        .count();
    (covered.len(), shown)
}

/// m of B as the bias defines it, computed here in f64: the larger screen gradient of the plane through B's
/// vertex codes `65535 W / W_far`.
fn m_of_b() -> f64 {
    let c: Vec<f64> = B
        .iter()
        .map(|&(x, y)| 65535.0 / (FAR as f64 * rhw(x, y) as f64))
        .collect();
    let (x, y): (Vec<f64>, Vec<f64>) = B.iter().map(|&(x, y)| (x as f64, y as f64)).unzip();
    let area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    let gx = ((c[1] - c[0]) * (y[2] - y[0]) - (c[2] - c[0]) * (y[1] - y[0])) / area;
    let gy = ((c[2] - c[0]) * (x[1] - x[0]) - (c[1] - c[0]) * (x[2] - x[0])) / area;
    gx.abs().max(gy.abs())
}

#[test]
fn bias_removes_coplanar_fighting_without_gaps() {
    let base = RenderState::new(1.0, FAR).unwrap();
    let (covered, shown) = visible(base, 1.0);
    println!("no bias: B shows on {shown} of {covered} pixels");
    assert!(
        covered > 300 && shown < covered,
        "without bias the coplanar pair fights (B is not fully shown)"
    );

    let constant = RenderState {
        depth_bias: -4.0,
        ..base
    };
    let (covered, shown) = visible(constant, 1.0);
    println!("depth_bias -4: {shown} of {covered}");
    assert_eq!(
        shown, covered,
        "with bias -4 (> the 3-code bound) B shows everywhere, no gaps"
    );

    let m = m_of_b();
    assert!(m > 1.0, "a sloped plane: m = {m}");
    // slope scale alone: offset = m * (-4.5 / m) = -4.5, rounded to -5 (or -4 with f32 rounding of m): enough.
    let sloped = RenderState {
        slope_scale_depth_bias: (-4.5 / m) as f32,
        ..base
    };
    let (covered, shown) = visible(sloped, 1.0);
    println!(
        "slope scale {:.4} (m = {m:.2}): {shown} of {covered}",
        -4.5 / m
    );
    assert_eq!(shown, covered);

    // a surface 2% farther (its codes over 100 larger here) stays hidden under the same bias: no bleeding
    let (covered, shown) = visible(constant, 1.0 / 1.02);
    assert_eq!(shown, 0, "{shown} of {covered} pixels bled through");
}

/// The offset's value, not only its sufficiency: a triangle whose vertex codes change by 3 codes a pixel across and
/// 1.5 down (so `max(|gx|, |gy|) = 3`, while `|gx| + |gy| = 4.5`) stores, at every pixel, its unbiased code plus
/// `round(m * SLOPESCALEDEPTHBIAS + DEPTHBIAS)`: 3 for (1, 0), 5 for (2, -1.25) (4.75), -2 for (0, -2.4), 2 for
/// (0.6, 0) (1.8), -30 for (-10, 0) (where an m 2% off moves the code). A slope term taken as the sum (4.5 -> 5, 9 - 1.25 -> 8) or scaled wrongly moves every code. Two
/// triangles, one with axis-aligned legs and one with none (so a wrong cross term of the plane's area or gradients
/// shows too), and two gradients, `(3, 1.5)` and `(1.5, -3)` (the larger term across, then down and negative).
/// The slope is taken from the vertices' codes in f32 (src/raster.rs), exact to about 2^-20 of a code here, far from
/// the .5 ties of these offsets.
#[test]
fn bias_offset_is_max_slope_times_scale_plus_constant() {
    let triangles = [
        [(0.5f32, 0.5f32), (40.5, 0.5), (0.5, 30.5)],
        [(0.5, 0.5), (40.5, 6.5), (8.5, 30.5)],
    ];
    for corners in triangles {
        for (gx, gy) in [(3.0, 1.5), (1.5, -3.0)] {
            offsets_are(corners, gx, gy);
        }
    }
}

/// Draws the triangle with corners `p` whose codes `c = 65535 W / W_far` at pixel centres are
/// `20000 + gx (x - 0.5) + gy (y - 0.5)` (`max(|gx|, |gy|) = 3`) and checks [`bias_offset_is_max_slope_times_scale_plus_constant`]'s
/// offsets. W is not affine in screen space, but the bias's m is defined from the three vertices' codes (the plane
/// through them), which is what this sets.
fn offsets_are(p: [(f32, f32); 3], gx: f64, gy: f64) {
    let code = |x: f64, y: f64| 20_000.0 + gx * (x - 0.5) + gy * (y - 0.5);
    let v = |(x, y): (f32, f32)| Vertex {
        x,
        y,
        z: 0.5,
        rhw: (65535.0 / (code(x as f64, y as f64) * FAR as f64)) as f32,
        color: Rgb565::WHITE,
    };
    let t = p.map(v);
    let draw = |slope: f32, constant: f32| {
        let mut state = RenderState::new(1.0, FAR).unwrap();
        state.compare = Compare::Always;
        state.slope_scale_depth_bias = slope;
        state.depth_bias = constant;
        let mut depth = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        let s = Rasterizer::<wraster::recip::Fast>::new(state)
            .draw(&mut Frame::new(W as u32, H as u32), &mut buf, &t)
            .unwrap();
        assert!(s.written > 400);
        depth
    };
    let base = draw(0.0, 0.0);
    for (slope, constant, offset) in [
        (1.0, 0.0, 3),
        (2.0, -1.25, 5),
        (0.0, -2.4, -2),
        (0.6, 0.0, 2),
        (-10.0, 0.0, -30),
    ] {
        let got = draw(slope, constant);
        let mut n = 0;
        for (k, (&g, &b)) in got.iter().zip(&base).enumerate() {
            if b != wraster::W16_FAR {
                assert_eq!(
                    g as i32 - b as i32,
                    offset,
                    "pixel {k}, slope {slope}, constant {constant}, corners {p:?}, gradient ({gx}, {gy})"
                );
                n += 1;
            }
        }
        assert!(n > 400);
    }
}

/// The bias on small triangles (boxes under 32 px, which the fast tier draws on its own small-triangle path when no
/// bias is set): the coplanar pair fights without bias and not with a constant bias of -4, nor with a slope-scaled
/// one alone (the path must be left for either). B is drawn with the default strategy, the fast tier.
#[test]
fn bias_applies_to_small_triangles() {
    const AS: [(f32, f32); 3] = [(2.0, 2.0), (30.0, 4.0), (4.0, 28.0)];
    const BS: [(f32, f32); 3] = [(8.0, 7.0), (22.0, 10.0), (10.0, 20.0)];
    let base = RenderState::new(1.0, FAR).unwrap();
    let (covered, shown) = visible_pair(AS, BS, base, 1.0);
    assert!(covered > 80 && shown < covered, "{shown} of {covered}");
    for (constant, slope) in [(-4.0, 0.0), (0.0, -4.5 / m_of_b() as f32)] {
        let state = RenderState {
            depth_bias: constant,
            slope_scale_depth_bias: slope,
            ..base
        };
        let (covered, shown) = visible_pair(AS, BS, state, 1.0);
        assert_eq!(shown, covered, "bias {constant}, slope scale {slope}");
    }
}

/// The other formats take the bias too (the generic span loop): a constant bias of `k` codes moves every stored code by
/// exactly `k` (none saturates here: the triangle lies well inside the range), and a slope-scaled bias alone moves
/// every code of a sloped triangle by the same positive amount (its `m` times the scale, one offset per triangle).
#[test]
fn packed_formats_take_constant_and_slope_bias() {
    use host_tests::render_format;
    use wraster::format::{LZ16, W16F, Z16};
    use wraster::recip::Fast;
    use wraster::Codec;
    fn check<F: Codec>() {
        let c = Rgb565::WHITE;
        // W from 20 to 60 across the triangle: codes change along x and y.
        let t = [
            Vertex::new(4.0, 4.0, 20.0, c),
            Vertex::new(60.0, 8.0, 60.0, c),
            Vertex::new(10.0, 40.0, 40.0, c),
        ];
        let base = RenderState::new(1.0, 100.0).unwrap();
        let codes = |s: RenderState| render_format::<F, Fast>(&[t], s, 64, 48).unwrap().1;
        let plain = codes(base);
        let clear = plain[0];
        let mut k = base;
        k.depth_bias = 3.0;
        let constant = codes(k);
        let mut sl = base;
        sl.slope_scale_depth_bias = 1.0;
        let slope = codes(sl);
        let sign = if F::REVERSED { -1 } else { 1 };
        let (mut n, mut offsets) = (0, std::collections::BTreeSet::new());
        for ((&p, &q), &s) in plain.iter().zip(&constant).zip(&slope) {
            if p == clear {
                assert_eq!(
                    (q, s),
                    (clear, clear),
                    "{}: a pixel outside the triangle",
                    F::NAME
                );
                continue;
            }
            n += 1;
            assert_eq!(q as i64 - p as i64, 3 * sign, "{}: constant bias", F::NAME);
            offsets.insert(s as i64 - p as i64);
        }
        assert!(n > 500, "{}", F::NAME);
        assert_eq!(
            offsets.len(),
            1,
            "{}: one slope offset per triangle, {offsets:?}",
            F::NAME
        );
        let o = *offsets.first().unwrap() * sign;
        assert!(
            o >= 1,
            "{}: a slope bias moves the codes back, by {o}",
            F::NAME
        );
    }
    check::<W16F>();
    check::<Z16>();
    check::<LZ16>();
}
