//! Fixed-point vertex input (`FixedVertex`: x, y as `I24F8`, `1/W` as a 32-bit unsigned `fixed` type) against the
//! f32 `Vertex` with the same values: the same pixels, colours and codes, for every primitive, format and strategy.

use embedded_graphics::pixelcolor::Rgb565;
use host_tests::{random_tri, Frame, Rng};
use wraster::format::{W24F, Z16};
use wraster::input::{I24F8, U1F31, U8F24};
use wraster::recip::{Exact, Fast, SpanRecip};
use wraster::{DepthBuffer, DepthMode, Error, FixedVertex, Rasterizer, RenderState, Vertex};

/// The f32 vertex moved onto values both types hold exactly: x, y on the 1/256 grid, and `rhw` a multiple of 2^-31
/// (U1F31's step) with at most 24 significant bits (an f32 mantissa). Returns the pair.
fn twins(v: Vertex<Rgb565>) -> (Vertex<Rgb565>, FixedVertex<Rgb565>) {
    let x = I24F8::from_num(v.x); // rounds to the grid (the snap itself)
    let y = I24F8::from_num(v.y);
    let mut bits = (v.rhw as f64 * 2f64.powi(31)).round() as u64;
    assert!(bits > 0 && bits < 1 << 32, "rhw {} outside U1F31", v.rhw);
    let sig = 64 - bits.leading_zeros();
    if sig > 24 {
        bits &= !((1u64 << (sig - 24)) - 1);
    }
    let rhw = U1F31::from_bits(bits as u32);
    let f = Vertex {
        x: x.to_num::<f32>(),
        y: y.to_num::<f32>(),
        z: 0.0,
        rhw: rhw.to_num::<f32>(),
        color: v.color,
    };
    assert_eq!(
        f.rhw as f64,
        bits as f64 / 2f64.powi(31),
        "rhw not exact in f32"
    );
    (
        f,
        FixedVertex {
            x,
            y,
            rhw,
            color: v.color,
        },
    )
}

/// A triangle as f32 vertices and as their fixed-point twins.
type Pair = ([Vertex<Rgb565>; 3], [FixedVertex<Rgb565>; 3]);

const W: u16 = 96;
const H: u16 = 64;

/// Each pair drawn alone into cleared buffers (so no later triangle hides a difference), flat and Gouraud.
fn w16_pair<R: SpanRecip>(tris: &[Pair], state: RenderState) {
    let mut r = Rasterizer::<R>::new(state);
    let n = W as usize * H as usize;
    let (mut da, mut db) = (vec![0u16; n], vec![0u16; n]);
    let mut written = 0;
    for (a, b) in tris {
        for gouraud in [false, true] {
            let (mut fa, mut fb) = (
                Frame::new(W as u32, H as u32),
                Frame::new(W as u32, H as u32),
            );
            let mut ba = DepthBuffer::new(&mut da, W, H).unwrap();
            let mut bb = DepthBuffer::new(&mut db, W, H).unwrap();
            ba.clear();
            bb.clear();
            let (sa, sb) = if gouraud {
                (
                    r.draw_gouraud(&mut fa, &mut ba, a),
                    r.draw_gouraud(&mut fb, &mut bb, b),
                )
            } else {
                (r.draw(&mut fa, &mut ba, a), r.draw(&mut fb, &mut bb, b))
            };
            assert_eq!(sa, sb, "{a:?} / {b:?}");
            written += sa.map(|s| s.written).unwrap_or(0);
            assert!(
                fa == fb && da == db,
                "frames or codes differ: {a:?} / {b:?}"
            );
        }
    }
    assert!(written > 100_000, "the suite must draw: {written}");
}

fn suite() -> Vec<Pair> {
    let mut rng = Rng(77);
    (0..3000)
        .map(|_| {
            let t = random_tri(&mut rng, 1.5, 9000.0).map(twins);
            (t.map(|p| p.0), t.map(|p| p.1))
        })
        .collect()
}

/// W16 (flat and Gouraud), both tiers, far/near 1e4 with vertices in and out of range: identical frames and codes.
#[test]
fn fixed_input_draws_like_f32_in_w16() {
    let tris = suite();
    let state = RenderState::new(1.0, 1.0e4).unwrap();
    w16_pair::<Fast>(&tris, state);
    w16_pair::<Exact>(&tris, state);
}

/// Other formats (a W and a Z format), points, lines and wireframes: identical frames, codes and stats.
#[test]
fn fixed_input_draws_like_f32_in_packed_formats_and_primitives() {
    let tris = suite();
    let mut state = RenderState::new(1.0, 1.0e4).unwrap();
    for mode in [DepthMode::W, DepthMode::Z] {
        state.mode = mode;
        let mut r: Rasterizer = Rasterizer::new(state);
        let (mut fa, mut fb) = (
            Frame::new(W as u32, H as u32),
            Frame::new(W as u32, H as u32),
        );
        let n = W as usize * H as usize;
        let (mut ba, mut bb) = (vec![[0u8; 3]; n], vec![[0u8; 3]; n]); // W24F: 3 bytes a pixel
        let mut total = 0;
        for (a, b) in &tris {
            // Each triangle alone into cleared buffers, so no later triangle hides a difference.
            let mut pa = DepthBuffer::<W24F>::new_format(&mut ba, W, H).unwrap();
            let mut pb = DepthBuffer::<W24F>::new_format(&mut bb, W, H).unwrap();
            pa.clear_for(&state.range);
            pb.clear_for(&state.range);
            if mode == DepthMode::Z {
                // Z formats through their own buffer type; W24F refuses Z (checked below).
                let mut za = vec![0u16; n];
                let mut zb = vec![0u16; n];
                let mut qa = DepthBuffer::<Z16>::new_format(&mut za, W, H).unwrap();
                let mut qb = DepthBuffer::<Z16>::new_format(&mut zb, W, H).unwrap();
                qa.clear_for(&state.range);
                qb.clear_for(&state.range);
                let x = r.draw(&mut fa, Some(&mut qa), a);
                let y = r.draw(&mut fb, Some(&mut qb), b);
                assert_eq!(x, y);
                let _ = (qa, qb);
                let diff = za.iter().zip(&zb).filter(|(p, q)| p != q).count();
                assert!(diff == 0, "{diff} codes differ: {a:?} / {b:?} {x:?}");
                total += x.map(|s| s.written).unwrap_or(0);
                assert_eq!(
                    r.draw(&mut fa, Some(&mut pa), a),
                    r.draw(&mut fb, Some(&mut pb), b)
                );
                continue;
            }
            let x = r.draw(&mut fa, Some(&mut pa), a);
            let y = r.draw(&mut fb, Some(&mut pb), b);
            assert_eq!(x, y);
            total += x.map(|s| s.written).unwrap_or(0);
            assert_eq!(
                r.draw_line(&mut fa, Some(&mut pa), &[a[0], a[1]]),
                r.draw_line(&mut fb, Some(&mut pb), &[b[0], b[1]])
            );
            assert_eq!(
                r.draw_point(&mut fa, Some(&mut pa), &a[2]),
                r.draw_point(&mut fb, Some(&mut pb), &b[2])
            );
            assert_eq!(
                r.draw_wireframe(&mut fa, Some(&mut pa), a),
                r.draw_wireframe(&mut fb, Some(&mut pb), b)
            );
            let _ = (pa, pb);
            assert!(ba == bb, "codes differ: {a:?} / {b:?}");
        }
        assert!(total > 20_000, "{mode:?}: {total}");
        assert_eq!(fa, fb);
        assert_eq!(ba, bb);
    }
}

/// A wider `1/W` type: U8F24 holds `1/W` up to 256 (W > 1/256); the same codes as the f32 vertex with that value.
#[test]
fn other_rhw_widths_draw_like_f32() {
    let state = RenderState::new(0.01, 100.0).unwrap();
    let mut r: Rasterizer = Rasterizer::new(state);
    let rhw = U8F24::from_bits(50 << 24 | 0x12_3456); // 50.07..., 30 significant bits: exact in neither f32 nor U1F31
    let rhw_f = U8F24::from_bits(50 << 24 | 0x12_3400); // 22 significant bits: exact in f32
    let mk = |x: f32, y: f32, rhw| FixedVertex {
        x: I24F8::from_num(x),
        y: I24F8::from_num(y),
        rhw,
        color: Rgb565::new(1, 2, 3),
    };
    let fixed = [
        mk(2.0, 2.0, rhw_f),
        mk(60.0, 5.0, rhw_f),
        mk(10.0, 40.0, rhw_f),
    ];
    let float = fixed.map(|v| Vertex {
        x: v.x.to_num(),
        y: v.y.to_num(),
        z: 0.0,
        rhw: v.rhw.to_num(),
        color: v.color,
    });
    assert_eq!(float[0].rhw as f64, rhw_f.to_num::<f64>());
    let (mut fa, mut fb) = (Frame::new(64, 48), Frame::new(64, 48));
    let (mut da, mut db) = (vec![u16::MAX; 64 * 48], vec![u16::MAX; 64 * 48]);
    let a = r
        .draw(
            &mut fa,
            &mut DepthBuffer::new(&mut da, 64, 48).unwrap(),
            &float,
        )
        .unwrap();
    let b = r
        .draw(
            &mut fb,
            &mut DepthBuffer::new(&mut db, 64, 48).unwrap(),
            &fixed,
        )
        .unwrap();
    assert_eq!((a, &fa, &da), (b, &fb, &db));
    assert!(a.written > 500, "{a:?}");
    // The full 30-bit value draws too, at the code of W = 1/rhw: 65535 * W / W_far rounded, within the fast tier's
    // 1 LSB contract (W = 0.01997..., code about 13; the 2^-22 relative difference between the two rhw moves it by
    // far less than a code).
    let full = fixed.map(|v| FixedVertex { rhw, ..v });
    let mut dc = vec![u16::MAX; 64 * 48];
    r.draw(
        &mut Frame::new(64, 48),
        &mut DepthBuffer::new(&mut dc, 64, 48).unwrap(),
        &full,
    )
    .unwrap();
    let want = (65535.0 / (rhw.to_num::<f64>() * 100.0)).round() as i32;
    let k = 10 * 64 + 20;
    assert!((dc[k] as i32 - want).abs() <= 1, "{} vs {want}", dc[k]);
}

/// Out-of-range fixed input gives the f32 path's errors: `rhw = 0`, a vertex at the guard band.
#[test]
fn fixed_input_errors() {
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(1.0, 100.0).unwrap());
    let ok = FixedVertex {
        x: I24F8::from_num(1),
        y: I24F8::from_num(1),
        rhw: U1F31::from_num(0.5),
        color: Rgb565::new(1, 1, 1),
    };
    let mut d = vec![0u16; 16];
    let mut run = |t: [FixedVertex<Rgb565>; 3]| {
        r.draw(
            &mut Frame::new(4, 4),
            &mut DepthBuffer::new(&mut d, 4, 4).unwrap(),
            &t,
        )
    };
    assert_eq!(
        run([
            FixedVertex {
                rhw: U1F31::ZERO,
                ..ok
            },
            ok,
            ok
        ]),
        Err(Error::RhwNotPositive)
    );
    let edge = I24F8::from_num(wraster::GUARD_BAND);
    assert_eq!(
        run([ok, FixedVertex { x: edge, ..ok }, ok]),
        Err(Error::OutOfGuardBand)
    );
    assert_eq!(
        run([ok, ok, FixedVertex { y: -edge, ..ok }]),
        Err(Error::OutOfGuardBand)
    );
    let inside = I24F8::from_num(wraster::GUARD_BAND) - I24F8::DELTA;
    assert!(run([
        ok,
        FixedVertex { x: inside, ..ok },
        FixedVertex { y: -inside, ..ok }
    ])
    .is_ok());
    // t = rhw * W_far above MAX_T (2^30): W_far 1e9 with rhw 1.5.
    let mut far: Rasterizer = Rasterizer::new(RenderState::new(1.0, 1.0e9).unwrap());
    let big = FixedVertex {
        rhw: U1F31::from_num(1.5),
        ..ok
    };
    assert_eq!(
        far.draw(
            &mut Frame::new(4, 4),
            &mut DepthBuffer::new(&mut d, 4, 4).unwrap(),
            &[big, ok, ok]
        ),
        Err(Error::DepthRange)
    );
}
