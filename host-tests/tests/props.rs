//! Property tests (proptest) of the invariants every draw keeps, over random scenes: no panic, no write outside the
//! buffers (the test `Frame` panics on one), a refused triangle writes nothing, and banded rendering equals
//! whole-frame rendering bit for bit. The case count is CI-sized; a long run:
//! `PROPTEST_CASES=100000 cargo test --release -p host-tests --test props`.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{render, Frame};
use proptest::prelude::*;
use wraster::recip::{DefaultRecip, PerPixel, PrevPixel};
use wraster::{DepthBuffer, RenderState, Vertex, W16_FAR};

const W: u16 = 48;
const H: u16 = 40;

/// Any f32 at all: every bit pattern (NaN, infinities, denormals, huge and negative values).
fn any_bits() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits)
}

/// Mostly sane values with a chance of the extreme.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![8 => -20.0f32..70.0, 1 => any_bits(), 1 => -5000.0f32..5000.0]
}

fn rhw() -> impl Strategy<Value = f32> {
    prop_oneof![8 => 1e-4f32..1.0, 1 => any_bits(), 1 => 1e-9f32..1e3]
}

fn tri() -> impl Strategy<Value = [Vertex<Rgb565>; 3]> {
    prop::array::uniform3((coord(), coord(), rhw(), any::<u16>())).prop_map(|v| {
        v.map(|(x, y, r, c)| Vertex {
            x,
            y,
            z: 0.5,
            rhw: r,
            color: Rgb565::from(embedded_graphics::pixelcolor::raw::RawU16::new(c)),
        })
    })
}

proptest! {
    // 400 cases unless PROPTEST_CASES says otherwise (an explicit `cases` would override the environment).
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(400),
        .. ProptestConfig::default()
    })]

    /// Every triangle either draws inside the buffers or is refused with nothing written; never a panic.
    #[test]
    fn any_triangle_draws_inside_or_is_refused_untouched(t in tri(), near in 0.01f32..10.0, ratio in 1.001f32..1e5) {
        let state = match RenderState::new(near, near * ratio) {
            Ok(s) => s,
            Err(_) => return Ok(()),
        };
        let mut r: wraster::Rasterizer = wraster::Rasterizer::new(state);
        let mut frame = Frame::new(W as u32, H as u32);
        let mut depth = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        match r.draw(&mut frame, &mut buf, &t) {
            Ok(stats) => {
                prop_assert!(stats.written <= stats.fragments);
                prop_assert_eq!(frame.writes.iter().map(|&n| n as u64).sum::<u64>(), stats.written as u64);
            }
            Err(_) => {
                prop_assert!(frame.writes.iter().all(|&n| n == 0));
                prop_assert!(depth.iter().all(|&d| d == W16_FAR));
            }
        }
    }

    /// A random scene of valid triangles drawn in bands of any height equals it drawn whole, for both reciprocals.
    #[test]
    fn bands_equal_the_whole_frame(
        tris in prop::collection::vec(
            prop::array::uniform3((-20.0f32..70.0, -20.0f32..60.0, 1e-3f32..1.0)).prop_map(|v| {
                v.map(|(x, y, r)| Vertex { x, y, z: 0.5, rhw: r, color: Rgb565::GREEN })
            }),
            1..12,
        ),
        band in 1u16..H,
    ) {
        let state = RenderState::new(1.0, 1000.0).unwrap();
        let whole = render::<PerPixel<DefaultRecip>>(&tris, state, W, H, H).unwrap();
        let banded = render::<PerPixel<DefaultRecip>>(&tris, state, W, H, band).unwrap();
        prop_assert_eq!(&whole.0.px, &banded.0.px);
        prop_assert_eq!(&whole.1, &banded.1);
        let whole = render::<PrevPixel>(&tris, state, W, H, H).unwrap();
        let banded = render::<PrevPixel>(&tris, state, W, H, band).unwrap();
        prop_assert_eq!(&whole.0.px, &banded.0.px);
        prop_assert_eq!(&whole.1, &banded.1);
    }

    /// The packed path keeps the same invariants for every kind of format and primitive: any triangle, line, point or
    /// wireframe into W16F, Z24 (3 bytes) or reversed Z, with the Quake strategy too, draws inside or is refused with
    /// nothing written.
    #[test]
    fn any_primitive_into_any_format_draws_inside_or_is_refused(t in tri(), near in 0.01f32..10.0, ratio in 1.001f32..1e5, kind in 0u8..4) {
        fn one<F: wraster::Codec, R: wraster::recip::WSpan>(t: &[Vertex<Rgb565>; 3], state: RenderState, kind: u8) -> Result<(), TestCaseError> {
            let mut r = wraster::Rasterizer::<R>::new(state);
            let mut frame = Frame::new(W as u32, H as u32);
            let mut bytes = vec![<F as wraster::format::DepthFormat>::Word::default(); W as usize * H as usize];
            let mut buf = wraster::DepthBuffer::<F>::new_format(&mut bytes, W, H).unwrap();
            buf.clear_for(&state.range);
            let cleared = bytes.clone();
            let mut buf = wraster::DepthBuffer::<F>::new_format(&mut bytes, W, H).unwrap();
            let out = match kind {
                0 => r.draw(&mut frame, Some(&mut buf), t),
                1 => r.draw_line(&mut frame, Some(&mut buf), &[t[0], t[1]]),
                2 => r.draw_point(&mut frame, Some(&mut buf), &t[2]),
                _ => r.draw_wireframe(&mut frame, Some(&mut buf), t),
            };
            match out {
                Ok(stats) => {
                    prop_assert!(stats.written <= stats.fragments);
                    prop_assert_eq!(frame.writes.iter().map(|&n| n as u64).sum::<u64>(), stats.written as u64);
                }
                Err(_) => {
                    prop_assert!(frame.writes.iter().all(|&n| n == 0));
                    prop_assert!(bytes == cleared);
                }
            }
            Ok(())
        }
        let state = match RenderState::new(near, near * ratio) {
            Ok(s) => s,
            Err(_) => return Ok(()),
        };
        one::<wraster::format::W16F, PerPixel<DefaultRecip>>(&t, state, kind)?;
        one::<wraster::format::Z24, PerPixel<DefaultRecip>>(&t, state, kind)?;
        one::<wraster::format::RZ32F, PerPixel<DefaultRecip>>(&t, state, kind)?;
        one::<wraster::format::W32F, wraster::recip::Quake<8>>(&t, state, kind)?;
    }
}
