//! The eight comparison functions of Microsoft, "Depth Buffering (Windows CE 5.0)" (D3DMCMPFUNC), with depth write on and off, in
//! rendering: a second triangle drawn over a first passes exactly where the function holds between its own code and
//! the stored one, and only then writes colour (and depth, if writing); the test runs before any colour work.
//! The expected results come from this file's own reading of the comparison, applied to the codes each triangle
//! stores when drawn alone (`Always`), not from `Compare::test`.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::Frame;
use wraster::{Compare, DepthBuffer, Rasterizer, RenderState, Vertex};

const W: u16 = 64;
const H: u16 = 48;

fn tri(p: [(f32, f32, f32); 3], c: Rgb565) -> [Vertex<Rgb565>; 3] {
    p.map(|(x, y, w)| Vertex::new(x, y, w, c))
}

/// Colours and depths after drawing `tris` in order with `state`, on a cleared buffer.
fn draw(tris: &[([Vertex<Rgb565>; 3], Compare)], write: bool) -> (Vec<Rgb565>, Vec<u16>, Vec<u32>) {
    let mut frame = Frame::new(W as u32, H as u32);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
    buf.clear();
    for (k, (t, cmp)) in tris.iter().enumerate() {
        let mut state = RenderState::new(10.0, 1000.0).unwrap();
        state.compare = *cmp;
        state.depth_write = k == 0 || write;
        Rasterizer::<wraster::recip::PerPixel<wraster::recip::DefaultRecip>>::new(state)
            .draw(&mut frame, &mut buf, t)
            .unwrap();
    }
    (frame.px, depth, frame.writes)
}

fn holds(cmp: Compare, new: u16, stored: u16) -> bool {
    match cmp {
        Compare::Never => false,
        Compare::Less => new < stored,
        Compare::Equal => new == stored,
        Compare::LessEqual => new <= stored,
        Compare::Greater => new > stored,
        Compare::NotEqual => new != stored,
        Compare::GreaterEqual => new >= stored,
        Compare::Always => true,
    }
}

#[test]
fn all_eight_comparisons_with_write_on_and_off() {
    // A tilted first triangle, a second crossing it (so it is in front on one side and behind on the other),
    // partly beyond the far plane (W 1500 > 1000, so those spans take the checked loop), and the first again
    // (equal codes everywhere).
    let first = tri(
        [(2.0, 3.0, 40.0), (60.0, 6.0, 400.0), (8.0, 45.0, 120.0)],
        Rgb565::RED,
    );
    let crossing = tri(
        [(4.0, 40.0, 60.0), (62.0, 30.0, 1500.0), (30.0, 1.0, 200.0)],
        Rgb565::BLUE,
    );
    let same = tri(
        [(2.0, 3.0, 40.0), (60.0, 6.0, 400.0), (8.0, 45.0, 120.0)],
        Rgb565::GREEN,
    );
    let all = host_tests::COMPARES;
    let (c0, d0, _) = draw(&[(first, Compare::Always)], true);
    let mut passes = [0usize; 8];
    for second in [crossing, same] {
        let (_, d1, w1) = draw(&[(second, Compare::Always)], true); // the second's own codes and coverage
        for (k, &cmp) in all.iter().enumerate() {
            for write in [true, false] {
                let (c, d, _) = draw(&[(first, Compare::Always), (second, cmp)], write);
                for p in 0..c.len() {
                    let pass = w1[p] > 0 && holds(cmp, d1[p], d0[p]);
                    passes[k] += usize::from(pass);
                    let (want_c, want_d) = match (pass, write) {
                        (true, true) => (second[0].color, d1[p]),
                        (true, false) => (second[0].color, d0[p]),
                        (false, _) => (c0[p], d0[p]),
                    };
                    assert_eq!(c[p], want_c, "{cmp:?} write={write} pixel {p}");
                    assert_eq!(d[p], want_d, "{cmp:?} write={write} pixel {p}");
                }
            }
        }
    }
    // The scene exercises each function both ways: every one but Never passes somewhere, and every one but Always
    // fails somewhere the second triangle covers; and the counts add up as the definitions say.
    for (k, cmp) in all.iter().enumerate() {
        println!("{cmp:?}: {} passing pixels", passes[k]);
        if *cmp != Compare::Never {
            assert!(passes[k] > 0, "{cmp:?} never passed");
        }
        if *cmp != Compare::Always {
            assert!(passes[k] < passes[7], "{cmp:?} never failed");
        }
    }
    let [_, less, equal, less_equal, greater, not_equal, greater_equal, always] = passes;
    assert_eq!(less + equal, less_equal);
    assert_eq!(greater + equal, greater_equal);
    assert_eq!(less + greater, not_equal);
    assert_eq!(less_equal + greater, always);
}

/// The fast tier's span loop (W16, `Less`, depth write: the default) over a stored depth that changes every pixel,
/// so its passing runs open and close all along each span, on a steep and a shallow triangle: a pixel whose
/// reference code `r` is at least 2 below the stored code is drawn once, with a code within 1 of `r` (the tier's
/// bound: within 1 LSB of the correctly rounded code); one whose stored code is at most `r - 1` is not drawn and
/// keeps it; the codes `r` and `r + 1`, which the 1-LSB bound leaves either way, are not judged. Uncovered pixels are
/// untouched.
#[test]
fn fast_tier_runs_break_and_resume_where_the_stored_depth_says() {
    let mut rng = host_tests::Rng(0x05EE_D0FF_A57A);
    let mut rnd = move || rng.bits();
    for p in [
        [(2.0, 3.0, 12.0), (61.0, 9.0, 900.0), (20.0, 46.0, 300.0)],
        [(1.0, 1.0, 400.0), (63.0, 20.0, 420.0), (5.0, 47.0, 410.0)],
    ] {
        let t = tri(p, Rgb565::RED);
        let (near, far) = (10.0, 1000.0);
        let reference = host_tests::reference_tri(
            &t.map(|q| (q.x, q.y, q.rhw)),
            near,
            far,
            W as i32,
            0..H as i32,
        )
        .unwrap();
        let mut stored: Vec<u16> = (0..W as usize * H as usize).map(|_| rnd() as u16).collect();
        for r in &reference {
            let off = (rnd() % 9) as i32 - 4;
            stored[(r.y * W as i32 + r.x) as usize] = (r.code as i32 + off).clamp(0, 65535) as u16;
        }
        let mut depth = stored.clone();
        let mut frame = Frame::new(W as u32, H as u32);
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        Rasterizer::<wraster::recip::Fast>::new(RenderState::new(near, far).unwrap())
            .draw(&mut frame, &mut buf, &t)
            .unwrap();
        let mut covered = vec![false; stored.len()];
        let (mut drawn, mut kept) = (0, 0);
        for r in reference.iter().filter(|r| r.in_range) {
            let i = (r.y * W as i32 + r.x) as usize;
            covered[i] = true;
            let (s, rc) = (stored[i] as i32, r.code as i32);
            if s >= rc + 2 {
                assert_eq!(frame.writes[i], 1, "pixel {} {}", r.x, r.y);
                assert!(
                    (depth[i] as i32 - rc).abs() <= 1,
                    "pixel {} {}: {} vs {rc}",
                    r.x,
                    r.y,
                    depth[i]
                );
                drawn += 1;
            } else if s < rc {
                assert_eq!(
                    (frame.writes[i], depth[i]),
                    (0, stored[i]),
                    "pixel {} {}",
                    r.x,
                    r.y
                );
                kept += 1;
            }
        }
        for i in (0..stored.len()).filter(|&i| !covered[i]) {
            assert_eq!((frame.writes[i], depth[i]), (0, stored[i]));
        }
        assert!(drawn > 200 && kept > 200, "{drawn} {kept}");
    }
}

/// `Less` is strict in the fast tier's loop too: the same triangle drawn a second time over its own depth writes
/// nothing. The second draw takes the fresh reciprocal at pixels the first reached by chaining; the tier's contract
/// alone lets the two differ by one code, and on these two triangles they agree at every pixel (so any pixel the
/// second draw writes is an equal code passing `Less`).
#[test]
fn fast_tier_less_is_strict_on_a_second_identical_draw() {
    for p in [
        [(2.0, 3.0, 12.0), (61.0, 9.0, 900.0), (20.0, 46.0, 300.0)],
        [(1.0, 1.0, 400.0), (63.0, 20.0, 420.0), (5.0, 47.0, 410.0)],
    ] {
        let t = tri(p, Rgb565::RED);
        let mut depth = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        let mut r =
            Rasterizer::<wraster::recip::Fast>::new(RenderState::new(10.0, 1000.0).unwrap());
        let mut frame = Frame::new(W as u32, H as u32);
        let first = r.draw(&mut frame, &mut buf, &t).unwrap();
        let second = r.draw(&mut frame, &mut buf, &t).unwrap();
        assert!(first.written > 500);
        assert_eq!((second.fragments, second.written), (first.fragments, 0));
    }
}
