//! Perspective-correct vertex colours against the f64 reference.

use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use embedded_graphics::prelude::*;
use host_tests::{reference_tri, Rng};
use wraster::{Compare, DepthBuffer, Rasterizer, RenderState, Vertex};

const W: u16 = 96;
const H: u16 = 64;

struct Frame888 {
    px: Vec<Option<Rgb888>>,
}

impl OriginDimensions for Frame888 {
    fn size(&self) -> Size {
        Size::new(W as u32, H as u32)
    }
}

impl DrawTarget for Frame888 {
    type Color = Rgb888;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            assert!(
                p.x >= 0 && p.y >= 0 && p.x < W as i32 && p.y < H as i32,
                "write outside at {p:?}"
            );
            let k = p.y as usize * W as usize + p.x as usize;
            assert!(self.px[k].is_none(), "pixel written twice");
            self.px[k] = Some(c);
        }
        Ok(())
    }
}

/// Each channel equals `round(sum w_i c_i / W_i / sum w_i / W_i)` (the perspective-correct value) within 1, and
/// exactly for at least 99.9% of channels. Bound: the colour is `256 Q / T` with the default reciprocal (relative
/// error below 2^-28.1) and planes solved exactly and rounded at 2^-F (F >= 47 here): the error is below
/// 255 * 2^-28 < 2^-20, so a channel is off only within 2^-20 of a rounding tie, and then by 1.
#[test]
fn gouraud_is_perspective_correct() {
    let mut rng = Rng(77);
    let state = RenderState {
        compare: Compare::Always,
        ..RenderState::new(1.0, 1000.0).unwrap()
    };
    let mut r: Rasterizer = Rasterizer::new(state);
    let mut depth = vec![0u16; W as usize * H as usize];
    let (mut channels, mut exact) = (0u64, 0u64);
    for _ in 0..3000 {
        let mut v = [Vertex::new(0.0, 0.0, 1.0, Rgb888::BLACK); 3];
        for q in &mut v {
            *q = Vertex::new(
                rng.f(-30.0, 126.0) as f32,
                rng.f(-30.0, 94.0) as f32,
                // vertices in and out of the depth range [1, 1000], so the range test decides some pixels
                rng.log(0.6, 1600.0) as f32,
                Rgb888::new(
                    (rng.bits() % 256) as u8,
                    (rng.bits() % 256) as u8,
                    (rng.bits() % 256) as u8,
                ),
            );
        }
        let mut frame = Frame888 {
            px: vec![None; W as usize * H as usize],
        };
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        r.draw_gouraud(&mut frame, &mut buf, &v).unwrap();
        let pts = v.map(|q| (q.x, q.y, q.rhw));
        let Some(pixels) = reference_tri(&pts, 1.0, 1000.0, W as i32, 0..H as i32) else {
            continue;
        };
        // Two-sided: exactly the reference's in-range pixels are drawn (each covered pixel checked below, and
        // nothing else: the counts agree), so a lost range test or extra coverage fails.
        let drawn = frame.px.iter().filter(|p| p.is_some()).count();
        assert_eq!(drawn, pixels.iter().filter(|p| p.in_range).count(), "{v:?}");
        for p in pixels.iter().filter(|p| p.in_range) {
            let got =
                frame.px[p.y as usize * W as usize + p.x as usize].expect("covered pixel drawn");
            let want = reference_color(&v, p.x, p.y);
            for (g, w) in [(got.r(), want[0]), (got.g(), want[1]), (got.b(), want[2])] {
                let d = (g as f64 - w).abs();
                assert!(
                    d < 1.0 + 1e-9 && (g as f64 - w.round()).abs() <= 1.0,
                    "pixel ({}, {}): {g} vs {w}",
                    p.x,
                    p.y
                );
                channels += 1;
                exact += u64::from(g as f64 == w.round());
            }
        }
    }
    let frac = exact as f64 / channels as f64;
    println!(
        "gouraud: {channels} channels, {exact} exact ({:.5}%)",
        100.0 * frac
    );
    assert!(channels > 1_000_000);
    assert!(frac >= 0.999);
}

/// The exact perspective-correct colour at a pixel centre (f64, barycentric on the snapped vertices).
fn reference_color(v: &[Vertex<Rgb888>; 3], i: i32, j: i32) -> [f64; 3] {
    // The vertices as given: the colour planes, like the depth plane, go through them (not the snapped ones).
    let p: Vec<(f64, f64)> = v.iter().map(|q| (q.x as f64, q.y as f64)).collect();
    let (px, py) = (i as f64 + 0.5, j as f64 + 0.5);
    let e = |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0);
    let w = [e(p[1], p[2]), e(p[2], p[0]), e(p[0], p[1])];
    let den: f64 = (0..3).map(|k| w[k] * v[k].rhw as f64).sum();
    let ch = |k: usize, c: u8| w[k] * v[k].rhw as f64 * c as f64;
    [
        (0..3).map(|k| ch(k, v[k].color.r())).sum::<f64>() / den,
        (0..3).map(|k| ch(k, v[k].color.g())).sum::<f64>() / den,
        (0..3).map(|k| ch(k, v[k].color.b())).sum::<f64>() / den,
    ]
}
