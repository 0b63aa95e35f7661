//! Pixels exactly at `W_near` and `W_far`, where the range test decides alone. Depths are powers of two (near 4, far
//! 1024), so `rhw`, `t = W_far * rhw` and the constant plane are exact and the reference's range test is exact too:
//! a triangle lying at `W_far` (t = 1) or at `W_near` (t = 256) is drawn, one an f32 step beyond either is not.
//! Flat and Gouraud, W16 and every packed W format.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{render_format, Frame};
use wraster::format::{W16, W16F, W24F, W32F};
use wraster::recip::{Exact, Fast, PrevPixel, SpanRecip};
use wraster::{Codec, Compare, DepthBuffer, Rasterizer, RenderState, Vertex, W16_FAR};

const NEAR: f32 = 4.0;
const FAR: f32 = 1024.0;

fn flat(rhw: f32) -> [Vertex<Rgb565>; 3] {
    let v = |x, y| Vertex {
        x,
        y,
        z: 0.0,
        rhw,
        color: Rgb565::GREEN,
    };
    [v(2.0, 2.0), v(60.0, 5.0), v(10.0, 40.0)]
}

/// The reference's covered pixels, and how many it finds in range (its range test is exact on these values).
fn reference(rhw: f32) -> (u32, u32) {
    let px = host_tests::reference_tri(&flat(rhw).map(|q| (q.x, q.y, q.rhw)), NEAR, FAR, 64, 0..48)
        .unwrap();
    (
        px.len() as u32,
        px.iter().filter(|p| p.in_range).count() as u32,
    )
}

fn state() -> RenderState {
    let mut s = RenderState::new(NEAR, FAR).unwrap();
    s.compare = Compare::Always;
    s
}

/// (written, the code at a covered pixel) for `R`, flat and Gouraud.
fn w16<R: SpanRecip>(rhw: f32, gouraud: bool) -> (u32, u16) {
    let mut depth = vec![0u16; 64 * 48];
    let mut buf = DepthBuffer::new(&mut depth, 64, 48).unwrap();
    buf.clear();
    let mut r = Rasterizer::<R>::new(state());
    let mut frame = Frame::new(64, 48);
    let s = if gouraud {
        r.draw_gouraud(&mut frame, &mut buf, &flat(rhw)).unwrap()
    } else {
        r.draw(&mut frame, &mut buf, &flat(rhw)).unwrap()
    };
    assert_eq!(
        s.fragments,
        reference(rhw).0,
        "the reference's covered pixels"
    );
    (s.written, depth[10 * 64 + 12])
}

fn each<R: SpanRecip>() {
    let beyond_far = f32::from_bits((1.0 / FAR).to_bits() - 1); // W a hair beyond W_far
    let inside_near = f32::from_bits((1.0 / NEAR).to_bits() + 1); // W a hair nearer than W_near
    let (all, _) = reference(1.0 / FAR);
    assert!(all > 1000);
    assert_eq!(
        reference(1.0 / FAR),
        (all, all),
        "the reference: at W_far in range"
    );
    assert_eq!(
        reference(1.0 / NEAR),
        (all, all),
        "the reference: at W_near in range"
    );
    assert_eq!(reference(beyond_far), (all, 0));
    assert_eq!(reference(inside_near), (all, 0));
    for g in [false, true] {
        // At W_far: t = 1, the code is 65535 exactly.
        assert_eq!(
            w16::<R>(1.0 / FAR, g),
            (all, W16_FAR),
            "at W_far, gouraud {g}"
        );
        // At W_near: t = 256, the code is round(65535 / 256) = 256.
        assert_eq!(
            w16::<R>(1.0 / NEAR, g),
            (all, 256),
            "at W_near, gouraud {g}"
        );
        assert_eq!(w16::<R>(beyond_far, g).0, 0, "beyond W_far, gouraud {g}");
        assert_eq!(
            w16::<R>(inside_near, g).0,
            0,
            "nearer than W_near, gouraud {g}"
        );
    }
}

#[test]
fn w16_range_is_inclusive_at_both_planes_and_exact() {
    each::<Fast>();
    each::<Exact>();
    each::<PrevPixel>();
}

fn packed<F: Codec>() {
    let beyond_far = f32::from_bits((1.0 / FAR).to_bits() - 1);
    let inside_near = f32::from_bits((1.0 / NEAR).to_bits() + 1);
    let run = |rhw: f32| render_format::<F, Exact>(&[flat(rhw)], state(), 64, 48).unwrap();
    let (all, _) = reference(1.0 / FAR);
    let (_, codes, s) = run(1.0 / FAR);
    assert_eq!((s.fragments, s.written), (all, all), "{} at W_far", F::NAME);
    assert_eq!(
        F::fraction(codes[10 * 64 + 12], NEAR as f64, FAR as f64),
        1.0,
        "{}",
        F::NAME
    );
    let (_, codes, s) = run(1.0 / NEAR);
    assert_eq!(s.written, all, "{} at W_near", F::NAME);
    let v = F::fraction(codes[10 * 64 + 12], NEAR as f64, FAR as f64);
    assert!(
        (v - 1.0 / 256.0).abs() <= 0.5 / F::MAX_CODE as f64 + 1e-12,
        "{}: {v}",
        F::NAME
    );
    assert_eq!(run(beyond_far).2.written, 0, "{} beyond W_far", F::NAME);
    assert_eq!(
        run(inside_near).2.written,
        0,
        "{} nearer than W_near",
        F::NAME
    );
}

#[test]
fn packed_w_formats_range_is_inclusive_at_both_planes() {
    packed::<W16>();
    packed::<W16F>();
    packed::<W24F>();
    packed::<W32F>();
}

/// A strategy of a user's own that overshoots `1/t` by `2^-13` (its stated bound): at `W_far` its code rounds to
/// `65535 (1 + 2^-13) = 65543`, past the format. A strategy whose bound reaches half a code (`2^-17` relative) gets
/// the encoder's clamp, so the pixel stores 65535, the far code (not a wrapped 7, nor a debug-build panic).
#[derive(Default)]
struct Overshoot;

impl SpanRecip for Overshoot {
    const NAME: &'static str = "overshoot";
    const MAX_REL_ERROR: f64 = 1.0 / 8192.0 + 1e-9;
    fn recip(&mut self, m: u32) -> u32 {
        let x = (1u64 << 62) / m as u64; // 2^62 / m <= 2^31 for m >= 2^31
        (x + (x >> 13)) as u32 // <= 2^31 + 2^18: fits
    }
}

#[test]
fn an_overshooting_strategy_is_clamped_at_the_far_code() {
    let rhw = 1.0 / FAR;
    for gouraud in [false, true] {
        let (written, code) = w16::<Overshoot>(rhw, gouraud);
        assert_eq!(written, reference(rhw).1, "gouraud {gouraud}");
        assert_eq!(code, W16_FAR, "gouraud {gouraud}");
    }
}
