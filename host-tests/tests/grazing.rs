//! Coplanar pairs and interpenetrating surfaces at grazing angles, where W changes fast across the screen.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{reference_frame, render, Frame};
use wraster::recip::{DefaultRecip, PerPixel};
use wraster::{DepthBuffer, Rasterizer, RenderState, Vertex};

const W: u16 = 96;
const H: u16 = 64;
const FAR: f32 = 1000.0;

/// A grazing floor: 1/W affine in screen space, W from about 20 at the bottom row to 600 at the top.
fn rhw(x: f64, y: f64) -> f64 {
    1.0 / 600.0 + (1.0 / 20.0 - 1.0 / 600.0) * (y / 64.0) + 0.00002 * x
}

/// A triangle on the floor with vertices off the sub-pixel grid (snapping moves them off the plane).
fn tri(p: [(f64, f64); 3], c: Rgb565) -> [Vertex<Rgb565>; 3] {
    p.map(|(x, y)| Vertex {
        x: x as f32,
        y: y as f32,
        z: 0.5,
        rhw: rhw(x, y) as f32,
        color: c,
    })
}

const A: [(f64, f64); 3] = [(1.313, 0.771), (95.137, 1.229), (3.921, 63.417)];
const B: [(f64, f64); 3] = [(10.271, 8.113), (70.519, 12.377), (14.733, 52.651)];

/// B's covered pixels and how many show B after drawing A then B with `state`.
fn visible(state: RenderState) -> (usize, usize) {
    let mut frame = Frame::new(W as u32, H as u32);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
    buf.clear();
    let mut first = state;
    first.depth_bias = 0.0;
    first.slope_scale_depth_bias = 0.0;
    Rasterizer::<PerPixel<DefaultRecip>>::new(first)
        .draw(&mut frame, &mut buf, &tri(A, Rgb565::RED))
        .unwrap();
    let mut r: Rasterizer = Rasterizer::new(state);
    let s = r.draw(&mut frame, &mut buf, &tri(B, Rgb565::BLUE)).unwrap();
    let shown = frame.px.iter().filter(|&&c| c == Rgb565::BLUE).count();
    (s.fragments as usize, shown)
}

/// Coplanar at a grazing angle. Snapping moves each vertex by at most 1/512 px in x and y, so the `t` of each
/// triangle's plane errs by at most `|grad t| sqrt(2) / 512` at its vertices and so everywhere inside; two triangles
/// disagree by twice that, in codes `2 sqrt(2) / 512 |grad code| <= (4 / 512) g` with `g` the larger axis slope of the
/// code at the pixel. The code `65535 / t` is not planar: along a segment from `t0` to `t1` its local slope is at most
/// `t_max / t_min = r` times its secant slope, and the Windows CE "Depth Buffering" docs' `m` (the bias's slope) is that secant slope of B's vertex
/// codes, so `g <= r m`. With the 3 codes of rounding (bias.rs), an offset of `-(3 + r m / 128)` codes is enough:
/// `depth_bias = -4` and `slope_scale_depth_bias = -r / 128`. Without bias the pair fights.
#[test]
fn coplanar_pair_at_a_grazing_angle_needs_slope_scaled_bias() {
    let base = RenderState::new(1.0, FAR).unwrap();
    let (covered, shown) = visible(base);
    println!("grazing coplanar, no bias: B shows on {shown} of {covered}");
    assert!(
        covered > 1000 && shown < covered,
        "without bias the pair fights"
    );

    let ts = B.map(|(x, y)| rhw(x, y));
    let r = ts.iter().cloned().fold(0.0, f64::max) / ts.iter().cloned().fold(f64::MAX, f64::min);
    let biased = RenderState {
        depth_bias: -4.0,
        slope_scale_depth_bias: -(r / 128.0) as f32,
        ..base
    };
    let (covered, shown) = visible(biased);
    println!(
        "grazing coplanar, bias -4 and slope scale -{:.3} (r = {r:.1}): {shown} of {covered}",
        r / 128.0
    );
    assert_eq!(shown, covered, "B must show on every pixel it covers");
}

/// Two floors crossing at a grazing angle (their W differs by under 0.5%; they cross along the middle column). Every pixel whose two
/// exact depths are more than 2 LSB apart shows the nearer surface, as in the f64 reference: each stored code is within
/// 1 LSB of its exact value (the core's bound), so a 2 LSB gap cannot be reversed. Pixels within 2 LSB may go either way.
#[test]
fn interpenetrating_surfaces_at_a_grazing_angle_resolve_outside_the_two_lsb_band() {
    let quad = |f: &dyn Fn(f64, f64) -> f64, c: Rgb565| {
        let v = |x: f64, y: f64| Vertex::new(x as f32, y as f32, (1.0 / f(x, y)) as f32, c);
        [
            [v(0.3, 0.2), v(95.7, 0.4), v(95.6, 63.8)],
            [v(0.3, 0.2), v(95.6, 63.8), v(0.1, 63.7)],
        ]
    };
    let tilted = |x: f64, y: f64| rhw(x, y) * (1.0 + 0.01 * (x / 96.0 - 0.5));
    let mut tris = Vec::new();
    tris.extend(quad(&|x, y| rhw(x, y), Rgb565::RED));
    tris.extend(quad(&tilted, Rgb565::BLUE));
    let state = RenderState::new(1.0, FAR).unwrap();
    let (frame, _, _) = render::<PerPixel<DefaultRecip>>(&tris, state, W, H, H).unwrap();
    let rf = reference_frame(&tris, 1.0, FAR, W as u32, H as u32);
    let (mut decided, mut band, mut blue) = (0, 0, 0);
    for k in 0..frame.px.len() {
        if !rf.covered[k] {
            continue;
        }
        let gap = (rf.runner_up[k] - rf.depth[k]) * 65535.0;
        if gap > 2.0 {
            assert_eq!(frame.px[k], rf.px[k], "pixel {k}: gap {gap:.2} LSB");
            decided += 1;
            blue += (rf.px[k] == Rgb565::BLUE) as usize;
        } else {
            band += 1;
        }
    }
    println!("interpenetrating: {decided} px decided as the reference ({blue} show the tilted floor), {band} within 2 LSB");
    assert!(
        decided > 3000 && blue > 500 && decided - blue > 500,
        "both surfaces show"
    );
}
