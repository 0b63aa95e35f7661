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

/// Coplanar at a grazing angle. The depth planes go through the vertices rounded to the depth grid (`2^-17` px or
/// finer), so each triangle's `t` errs by at most `|grad t| 2^-18` at its vertices and everywhere inside (with the
/// bounded extrapolation of `wraster::raster`'s `depth_plane` at covered pixels just outside); two triangles disagree
/// by twice that, in codes `2^-17 |grad code| <= 2^-17 g` with `g` the larger axis slope of the code at the pixel. The
/// code `65535 / t` is not planar: along a segment from `t0` to `t1` its local slope is at most `t_max / t_min = r`
/// times its secant slope, and the Windows CE "Depth Buffering" docs' `m` (the bias's slope) is that secant slope of
/// B's vertex codes, so `g <= r m`. With the 3 codes of rounding (bias.rs), an offset of `-(3 + r m 2^-17)` codes is
/// enough: `depth_bias = -4` alone here (`r m 2^-17` is far below a code), and the slope term (`-r / 128`, what the
/// snapped vertices' 1/512 px needed when the planes went through them) changes nothing. Without bias the pair fights.
#[test]
fn coplanar_pair_at_a_grazing_angle_needs_bias() {
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

    // The depth planes go through the vertices as given (on the depth grid of `2^-17` px or finer), not the snapped
    // ones: the two triangles' planes are the same plane up to that grid, so the constant offset alone is enough now.
    let constant = RenderState {
        depth_bias: -4.0,
        slope_scale_depth_bias: 0.0,
        ..base
    };
    let (covered, shown) = visible(constant);
    println!("grazing coplanar, bias -4 alone: {shown} of {covered}");
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

/// Depth from the vertices as given, not as snapped, on grazing triangles: 4,000 random triangles (1 to 40 px, off
/// the snap grid) lying on floors where W runs from `W_near` to `W_far` over 64 rows, each drawn alone, against the
/// true surface through the given vertices (`reference_tri`). Derived bounds: every code within half a code plus the
/// strategy's error (`2^-11.1` codes for the fast tier, `2^-12` for the exact tier) plus the depth grid's term
/// (`RefPixel::grid_lsb`) of the exact value, so within 1 LSB while those stay under half a code; and off the
/// correctly rounded code only within that sum of a rounding tie. The same triangles' planes through the *snapped*
/// vertices (what the core used before) miss the true surface by many codes: counted and asserted, so this test
/// tells the two apart.
#[test]
fn depth_comes_from_the_vertices_as_given_on_grazing_triangles() {
    use host_tests::{reference_tri, snap, Rng};
    use wraster::recip::{Exact, Fast, FastDiv, SpanRecip};
    use wraster::Compare;
    fn run<R: SpanRecip>(tie: f64) -> (u64, u64, u64, i64, f64) {
        let mut rng = Rng(77);
        let (near, far) = (1.0f32, FAR);
        let mut state = RenderState::new(near, far).unwrap();
        state.compare = Compare::Always;
        let mut r = Rasterizer::<R>::new(state);
        let mut depth = vec![0u16; W as usize * H as usize];
        let (mut pixels, mut exact, mut snapped_over_1, mut snapped_worst, mut grid_max) =
            (0u64, 0u64, 0u64, 0i64, 0f64);
        for _ in 0..4000 {
            // A floor: 1/W affine in y from 1/W_far at row 0 to about 1/W_near at row 64, with a random tilt.
            let (a, b) = (rng.f(-0.002, 0.002), rng.f(0.9, 1.0));
            let floor = move |x: f64, y: f64| {
                (1.0 / far as f64 + (b - 1.0 / far as f64) * (y / 64.0) + a * (x / 96.0))
                    .max(1.2 / far as f64)
            };
            let size = rng.log(1.0, 40.0);
            let (cx, cy) = (rng.f(0.0, 96.0), rng.f(0.0, 64.0));
            let tri = [0, 1, 2].map(|_| {
                let (x, y) = (cx + rng.f(-size, size), cy + rng.f(-size, size));
                Vertex::new(x as f32, y as f32, (1.0 / floor(x, y)) as f32, Rgb565::RED)
            });
            let mut frame = Frame::new(W as u32, H as u32);
            let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
            buf.clear();
            r.draw(&mut frame, &mut buf, &tri).unwrap();
            let v = tri.map(|q| (q.x, q.y, q.rhw));
            let snapped = v.map(|(x, y, w)| (snap(x) as f32 / 256.0, snap(y) as f32 / 256.0, w));
            let truth = reference_tri(&v, near, far, W as i32, 0..H as i32).unwrap_or_default();
            let old = reference_tri(&snapped, near, far, W as i32, 0..H as i32).unwrap_or_default();
            for p in truth.iter().filter(|p| p.in_range) {
                let k = p.y as usize * W as usize + p.x as usize;
                let e = 65535.0 / p.t;
                let got = depth[k] as f64;
                let g = p.grid_lsb;
                grid_max = grid_max.max(g);
                assert!(frame.writes[k] == 1, "covered pixel drawn");
                assert!(
                    (got - e).abs() <= 0.5 + tie + g + 1e-9
                        && ((got - p.code as f64).abs() <= 1.0 || tie + g >= 0.5),
                    "{}: code {got}, exact {e} (grid term {g}): {tri:?}",
                    R::NAME
                );
                let from_tie = (e - e.floor() - 0.5).abs();
                assert!(got == p.code as f64 || from_tie <= tie + g + 1e-9);
                pixels += 1;
                exact += u64::from(got == p.code as f64);
                if let Some(o) = old.iter().find(|o| o.x == p.x && o.y == p.y && o.in_range) {
                    let d = (o.code as i64 - p.code as i64).abs();
                    snapped_over_1 += u64::from(d > 1);
                    snapped_worst = snapped_worst.max(d);
                }
            }
        }
        (pixels, exact, snapped_over_1, snapped_worst, grid_max)
    }
    for (name, (pixels, exact, over, worst, grid_max)) in [
        ("fast", run::<Fast>(2f64.powf(-11.1))),
        ("fast-div", run::<FastDiv>(2f64.powf(-11.1))),
        ("exact", run::<Exact>(2f64.powi(-12))),
    ] {
        println!(
            "grazing, depth from the given vertices, {name}: {pixels} px, {exact} exact ({:.4}%), largest grid term \
             {grid_max:.2e} codes; the snapped vertices' planes: {over} px over 1 code off the true surface, up to {worst}",
            100.0 * exact as f64 / pixels as f64
        );
        assert!(pixels > 100_000);
        // At least 1 - 2 (2^-11.1 + largest grid term) exact: a code is off only within that of a tie.
        assert!(exact as f64 >= pixels as f64 * (1.0 - 2.0 * (2f64.powf(-11.1) + grid_max)));
        assert!(
            over > 100 && worst > 4,
            "the snapped planes miss the true surface"
        );
    }
}
