//! Points, lines and wireframe triangles (src/packed.rs): their pixel rules against an independent f64 reading of
//! the rules, their depth through the same RHW path, and depth bias on wireframe but never on points or lines.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{snap, Frame, Rng};
use wraster::format::{DepthFormat, W16, Z24};
use wraster::recip::{DefaultRecip, PerPixel};
use wraster::{Codec, Compare, Cull, DepthBuffer, Rasterizer, RenderState, Vertex};

const W: u16 = 96;
const H: u16 = 64;
const FAR: f32 = 1000.0;

type R = Rasterizer<PerPixel<DefaultRecip>>;

fn buffer<'a, F: Codec>(bytes: &'a mut Vec<F::Word>, state: &RenderState) -> DepthBuffer<'a, F> {
    *bytes = vec![F::Word::default(); W as usize * H as usize];
    let mut b = DepthBuffer::<F>::new_format(bytes, W, H).unwrap();
    b.clear_for(&state.range);
    b
}

/// The line rule read independently in f64 from the snapped endpoints: for each major-axis pixel centre in
/// `[start, end)`, the pixel containing the line's point there, and the exact `t = W_far * rhw` at that point.
fn reference_line(a: &Vertex<Rgb565>, b: &Vertex<Rgb565>) -> Vec<(i32, i32, f64)> {
    let (ax, ay, bx, by) = (
        snap(a.x) as f64,
        snap(a.y) as f64,
        snap(b.x) as f64,
        snap(b.y) as f64,
    );
    let (ta, tb) = (a.rhw as f64 * FAR as f64, b.rhw as f64 * FAR as f64);
    let x_major = (bx - ax).abs() >= (by - ay).abs();
    let (ua, va, ub, vb, ta, tb) = if x_major {
        (ax, ay, bx, by, ta, tb)
    } else {
        (ay, ax, by, bx, ta, tb)
    };
    let (ua, va, ub, vb, ta, tb) = if ua <= ub {
        (ua, va, ub, vb, ta, tb)
    } else {
        (ub, vb, ua, va, tb, ta)
    };
    let mut out = Vec::new();
    let mut i = ((ua - 128.0) / 256.0).ceil() as i64;
    while 256.0 * i as f64 + 128.0 < ub {
        let u = 256.0 * i as f64 + 128.0;
        let s = (u - ua) / (ub - ua);
        let v = va + s * (vb - va);
        let j = (v / 256.0).floor() as i64;
        let t = ta + s * (tb - ta);
        let (x, y) = if x_major { (i, j) } else { (j, i) };
        out.push((x as i32, y as i32, t));
        i += 1;
    }
    out
}

/// Random lines (any direction, partly outside the frame, depths 2 to 900): exactly the reference's pixels inside the
/// frame, and each pixel's W16 code within 1 of `round(65535 / t)` (the depth bound of the core: reciprocal below
/// 2^-28, `T` at `k` steps within `(1 + k) / 2` units of `2^-F`, F >= 51 here, so far below half a code).
#[test]
fn lines_follow_the_rule_and_carry_exact_depth() {
    let mut rng = Rng(0x11AE5);
    let state = RenderState {
        compare: Compare::Always,
        ..RenderState::new(1.0, FAR).unwrap()
    };
    let mut r = R::new(state);
    let (mut pixels, mut exact) = (0, 0);
    for _ in 0..2000 {
        let v = |rng: &mut Rng| {
            Vertex::new(
                rng.f(-40.0, 136.0) as f32,
                rng.f(-30.0, 94.0) as f32,
                rng.log(2.0, 900.0) as f32,
                Rgb565::WHITE,
            )
        };
        let line = [v(&mut rng), v(&mut rng)];
        let mut frame = Frame::new(W as u32, H as u32);
        let mut bytes = Vec::new();
        let mut buf = buffer::<W16>(&mut bytes, &state);
        let stats = r.draw_line(&mut frame, Some(&mut buf), &line).unwrap();
        let want: Vec<_> = reference_line(&line[0], &line[1])
            .into_iter()
            .filter(|&(x, y, _)| x >= 0 && x < W as i32 && y >= 0 && y < H as i32)
            .collect();
        assert_eq!(stats.written as usize, want.len(), "{line:?}");
        for &(x, y, t) in &want {
            assert_eq!(
                frame.writes[(y * W as i32 + x) as usize],
                1,
                "({x}, {y}) of {line:?}"
            );
            let code = buf.get(x, y).unwrap() as i64;
            let exact_code = (65535.0 / t).round() as i64;
            assert!(
                (code - exact_code).abs() <= 1,
                "({x}, {y}): {code} vs {exact_code}"
            );
            exact += (code == exact_code) as u32;
            pixels += 1;
        }
        assert_eq!(frame.writes.iter().sum::<u32>() as usize, want.len());
    }
    println!("lines: {pixels} px, {exact} with the exact code");
    assert!(pixels > 20_000);
}

/// A polyline monotone along its segments' shared major axis draws each pixel once: each segment excludes its upper
/// endpoint's column, which the next one starts with. (Where the major axis changes at a join, both segments may
/// take the join's pixel: D3D 10's diamond-exit rule is not implemented.)
#[test]
fn connected_lines_share_no_pixel() {
    let state = RenderState {
        compare: Compare::Always,
        ..RenderState::new(1.0, FAR).unwrap()
    };
    let mut r = R::new(state);
    let pts = [
        (3.3, 4.1),
        (30.7, 19.9),
        (50.2, 5.5),
        (80.6, 30.4),
        (94.3, 34.1),
    ];
    let mut frame = Frame::new(W as u32, H as u32);
    let mut bytes = Vec::new();
    let mut buf = buffer::<Z24>(&mut bytes, &state);
    let mut total = 0;
    for s in pts.windows(2) {
        let v = |(x, y): (f32, f32)| Vertex::new(x, y, 50.0, Rgb565::GREEN);
        total += r
            .draw_line(&mut frame, Some(&mut buf), &[v(s[0]), v(s[1])])
            .unwrap()
            .written;
    }
    assert!(frame.writes.iter().all(|&w| w <= 1), "a pixel drawn twice");
    assert_eq!(frame.writes.iter().sum::<u32>(), total);
    assert_eq!(total, 91, "one pixel per column from 3 to 93");
}

/// A point covers the pixel containing it, at its own depth, and is hidden by a nearer surface; outside the frame or
/// the depth range it draws nothing; bad input is refused with nothing written.
#[test]
fn points_cover_their_pixel_at_their_depth() {
    let state = RenderState::new(1.0, FAR).unwrap();
    let mut r = R::new(state);
    let mut frame = Frame::new(W as u32, H as u32);
    let mut bytes = Vec::new();
    let mut buf = buffer::<W16>(&mut bytes, &state);
    let p = Vertex::new(10.99, 20.01, 250.0, Rgb565::RED);
    let s = r.draw_point(&mut frame, Some(&mut buf), &p).unwrap();
    assert_eq!((s.fragments, s.written), (1, 1));
    assert_eq!(frame.writes[(20 * W as usize) + 10], 1);
    assert_eq!(buf.code(10, 20), Some(W16::encode(250.0, 1.0, FAR as f64)));
    // a nearer triangle hides a farther point drawn after it
    let tri = [
        Vertex::new(30.0, 30.0, 100.0, Rgb565::BLUE),
        Vertex::new(60.0, 30.0, 100.0, Rgb565::BLUE),
        Vertex::new(30.0, 60.0, 100.0, Rgb565::BLUE),
    ];
    r.draw(&mut frame, Some(&mut buf), &tri).unwrap();
    let behind = Vertex::new(35.5, 35.5, 200.0, Rgb565::RED);
    assert_eq!(
        r.draw_point(&mut frame, Some(&mut buf), &behind)
            .unwrap()
            .written,
        0
    );
    let before = Vertex::new(36.5, 35.5, 50.0, Rgb565::RED);
    assert_eq!(
        r.draw_point(&mut frame, Some(&mut buf), &before)
            .unwrap()
            .written,
        1
    );
    // outside the frame, beyond the far plane
    for q in [
        Vertex::new(-0.5, 3.0, 10.0, Rgb565::RED),
        Vertex::new(96.0, 3.0, 10.0, Rgb565::RED),
        Vertex::new(5.0, 5.0, 2000.0, Rgb565::RED),
    ] {
        assert_eq!(
            r.draw_point(&mut frame, Some(&mut buf), &q)
                .unwrap()
                .written,
            0,
            "{q:?}"
        );
    }
    let writes = frame.writes.iter().sum::<u32>();
    let bad = [
        Vertex { rhw: f32::NAN, ..p },
        Vertex { rhw: -1.0, ..p },
        Vertex {
            x: f32::INFINITY,
            ..p
        },
    ];
    for q in bad {
        assert!(r.draw_point(&mut frame, Some(&mut buf), &q).is_err());
        assert!(r.draw_line(&mut frame, Some(&mut buf), &[p, q]).is_err());
        assert!(r
            .draw_wireframe(&mut frame, Some(&mut buf), &[p, q, p])
            .is_err());
    }
    assert_eq!(
        frame.writes.iter().sum::<u32>(),
        writes,
        "an error wrote something"
    );
    assert_eq!(
        r.draw_line(&mut frame, Some(&mut buf), &[p, p])
            .unwrap()
            .culled,
        1
    );
}

/// Seed 001: depth bias applies to solid and wireframe triangles, never to points or lines. A triangle's edges drawn
/// over it take their depth at the edge's point of each major-axis centre, up to one pixel off the pixel centre where
/// the solid triangle took its depth, so they differ by up to the local code slope (at most `r m`, `r = t_max/t_min` of
/// the triangle, as in grazing.rs) plus 3 codes of rounding; with `Less` they fight. An offset of `-(3 + r m)`
/// (depth_bias -4, slope scale -r) puts the wireframe on top everywhere the solid covers; the same state on plain
/// lines changes nothing, because lines take no bias.
#[test]
fn bias_lifts_wireframe_but_not_lines() {
    let tri = [
        Vertex::new(5.3, 4.7, 100.0, Rgb565::BLUE),
        Vertex::new(90.1, 12.2, 130.0, Rgb565::BLUE),
        Vertex::new(20.4, 60.3, 115.0, Rgb565::BLUE),
    ];
    let r_ratio = 130.0f32 / 100.0;
    let run = |bias: bool, wire: bool| -> (usize, usize) {
        let base = RenderState::new(1.0, FAR).unwrap();
        let mut frame = Frame::new(W as u32, H as u32);
        let mut bytes = Vec::new();
        let mut buf = buffer::<W16>(&mut bytes, &base);
        R::new(base).draw(&mut frame, Some(&mut buf), &tri).unwrap();
        let solid = frame.writes.clone();
        let state = RenderState {
            depth_bias: if bias { -4.0 } else { 0.0 },
            slope_scale_depth_bias: if bias { -r_ratio } else { 0.0 },
            ..base
        };
        let mut r = R::new(state);
        let red = tri.map(|v| Vertex {
            color: Rgb565::RED,
            ..v
        });
        let mut drawn = Frame::new(W as u32, H as u32);
        let mut b2 = Vec::new();
        let mut any = buffer::<W16>(&mut b2, &base);
        let mut always = R::new(RenderState {
            compare: Compare::Always,
            ..base
        });
        if wire {
            r.draw_wireframe(&mut frame, Some(&mut buf), &red).unwrap();
            always
                .draw_wireframe(&mut drawn, Some(&mut any), &red)
                .unwrap();
        } else {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                r.draw_line(&mut frame, Some(&mut buf), &[red[a], red[b]])
                    .unwrap();
                always
                    .draw_line(&mut drawn, Some(&mut any), &[red[a], red[b]])
                    .unwrap();
            }
        }
        let over: Vec<usize> = (0..solid.len())
            .filter(|&k| solid[k] > 0 && drawn.writes[k] > 0)
            .collect();
        let shown = over.iter().filter(|&&k| frame.px[k] == Rgb565::RED).count();
        (over.len(), shown)
    };
    let (n, shown) = run(false, true);
    println!("wireframe over its triangle, no bias: {shown} of {n}");
    assert!(
        n > 100 && shown < n,
        "without bias the edges fight their triangle"
    );
    let (n, shown) = run(true, true);
    println!("wireframe, bias: {shown} of {n}");
    assert_eq!(shown, n, "with bias the wireframe shows everywhere");
    let (n_lines, shown_lines) = run(true, false);
    let (n_plain, shown_plain) = run(false, false);
    println!("lines, bias state: {shown_lines} of {n_lines}; no bias: {shown_plain} of {n_plain}");
    assert_eq!(
        (n_lines, shown_lines),
        (n_plain, shown_plain),
        "lines take no bias"
    );
    assert!(shown_lines < n_lines);
}

/// Wireframe triangles are culled like solid ones (zero area, winding).
#[test]
fn wireframe_culls_like_solid() {
    let mut state = RenderState::new(1.0, FAR).unwrap();
    let v = |x, y| Vertex::new(x, y, 50.0, Rgb565::WHITE);
    let cw = [v(5.0, 5.0), v(50.0, 5.0), v(5.0, 50.0)]; // y down: clockwise on screen
    let flat = [v(5.0, 5.0), v(50.0, 5.0), v(95.0, 5.0)];
    let mut frame = Frame::new(W as u32, H as u32);
    let mut bytes = Vec::new();
    let mut buf = buffer::<W16>(&mut bytes, &state);
    assert_eq!(
        R::new(state)
            .draw_wireframe(&mut frame, Some(&mut buf), &flat)
            .unwrap()
            .culled,
        1
    );
    state.cull = Cull::Cw;
    let solid = R::new(state)
        .draw(&mut frame, Some(&mut buf), &cw)
        .unwrap()
        .culled;
    let wire = R::new(state)
        .draw_wireframe(&mut frame, Some(&mut buf), &cw)
        .unwrap()
        .culled;
    assert_eq!((solid, wire), (1, 1));
    state.cull = Cull::Ccw;
    assert!(
        R::new(state)
            .draw_wireframe(&mut frame, Some(&mut buf), &cw)
            .unwrap()
            .written
            > 100
    );
}
