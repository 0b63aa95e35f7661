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
