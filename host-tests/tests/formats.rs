//! Rendering into every depth format (src/packed.rs) against the f64 reference and the formats' definitions;
//! depth modes and Dunlop's "Using W-Buffers" capability check; the linear-Z trick inside triangles.

use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::pixelcolor::RgbColor;
use host_tests::{
    exact_fraction, half_step, random_tri, reference_tri, render, render_format, Frame, Rng,
};
use wraster::format::{
    DepthFormat, W24FScaled, LZ16, RZ32F, W16, W16F, W24F, W32F, Z16, Z24, Z32F,
};
use wraster::packed::{resolve, Input};
use wraster::recip::{DefaultRecip, PerPixel, PrevPixel, Quake, SpanRecip, WSpan};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::{
    Codec, Compare, DepthBuffer, DepthMode, Error, NoDepth, Rasterizer, RenderState, Vertex,
};

const W: u16 = 96;
const H: u16 = 64;

/// The W16 codes and the colours of the packed path equal the lean path's (`Rasterizer::draw`), for every scene, with
/// both per-pixel strategies: the same `T`, reciprocal and rounding, so the same codes, bit for bit.
#[test]
fn packed_w16_equals_the_lean_path() {
    fn check<R: SpanRecip>() {
        for scene in Scene::ALL {
            let (n, f) = scene.depth_range();
            let tris: Vec<_> = scene.tris().collect();
            let state = RenderState::new(n, f).unwrap();
            let (f1, d1, s1) = render::<R>(&tris, state, WIDTH, HEIGHT, HEIGHT).unwrap();
            let (f2, d2, s2) = render_format::<W16, R>(&tris, state, WIDTH, HEIGHT).unwrap();
            assert_eq!(s1, s2, "{} {}", scene.name(), R::NAME);
            assert!(f1 == f2, "{} {}: colours differ", scene.name(), R::NAME);
            assert!(
                d1.iter().zip(&d2).all(|(a, b)| *a as u32 == *b),
                "{} {}: codes differ",
                scene.name(),
                R::NAME
            );
        }
    }
    check::<PerPixel<DefaultRecip>>();
    check::<PrevPixel>();
}

/// Bounds of the value a pixel stores before rounding to a code, relative (times the value) and absolute, for the
/// default reciprocal and depth ranges up to `f/n = 1e6` (the stiff ranges):
/// - `T` (the plane of `t = f/W`) errs by at most `(1 + k + l) / 2` units of `2^-F` at `k` columns and `l` rows from
///   its reference pixel (src/raster.rs), `F = 61 - bits(floor(t_max)) >= 40` for vertex `t <= 1.25e6 < 2^21`
///   (vertices reach `0.8 n`), and `k + l < 2^10` here (vertices stay within 250 px left of the frame), so `T` errs
///   by below `2^-31` of `t >= 1`, relative;
/// - W formats: the reciprocal (`PerPixel<DefaultRecip>::MAX_REL_ERROR`), plus `2^-31` for the top 32 bits of `u`
///   the float formats multiply by `W_far`, plus the `T` error: all relative;
/// - Z formats: `rz = (t - 1) n / (f - n)` with `n / (f - n)` truncated to 32 bits (`2^-31` relative) and `T`'s error
///   `2^-31 t` times `n / (f - n)`, absolute `2^-31 f / (f - n) <= 2^-30` for `f >= 2n`; `Z = 1 - rz` has the same
///   absolute error, reversed Z the same relative and absolute parts.
fn value_bound<F: Codec>(v: f64) -> f64 {
    let t_err = 2f64.powi(-31);
    match F::INPUT {
        // The 24-bit float formats are defined (the DDK's "W-Buffering") as the f32 with its low byte rounded off: a double rounding,
        // which adds up to half an f32 step, 2^-24 relative.
        Input::W if F::BYTES == 3 => {
            v * (PerPixel::<DefaultRecip>::MAX_REL_ERROR + 2f64.powi(-31) + t_err + 2f64.powi(-24))
        }
        Input::W => v * (PerPixel::<DefaultRecip>::MAX_REL_ERROR + 2f64.powi(-31) + t_err),
        // the relative part is of rz: 1 - Z for Z, the value itself for reversed Z
        _ => {
            let rz = if F::REVERSED { v } else { 1.0 - v };
            rz * 2f64.powi(-31) + 2f64.powi(-30)
        }
    }
}

/// Every covered, in-range pixel of random triangles (each drawn alone into a cleared buffer with `Always`) holds a
/// code whose value is within the derived bound of the exact value plus half a step (round to nearest), and the
/// packed path covers exactly the reference's pixels.
fn within_bound<F: Codec>() {
    let mut rng = Rng(0x5EED_F0F0 ^ F::BYTES as u64 ^ (F::MAX_CODE as u64) << 8);
    let (mut pixels, mut exact, mut worst) = (0u64, 0u64, 0f64);
    // The stiff ranges: far/near 10 to 1e6, W_near down to 1e-3, W_far up to 1e7.
    let ranges = [
        (1.0f32, 10.0f32),
        (10.0, 1000.0),
        (1.0, 1e4),
        (0.1, 1e4),
        (1.0, 1e5),
        (1.0, 1e6),
        (1e-3, 1e3),
        (10.0, 1e7),
    ];
    for (n, f) in ranges {
        let (nd, fd) = (n as f64, f as f64);
        let mut state = RenderState::new(n, f).unwrap();
        state.compare = Compare::Always;
        let c = Rgb565::WHITE;
        // 1000-pixel needles and grazing spans along which W goes from near to far, then random triangles
        let fixed = [
            [
                Vertex::new(1.3, 3.2, 1.01 * n, c),
                Vertex::new(1000.7, 3.9, 0.99 * f, c),
                Vertex::new(1.9, 4.8, 1.01 * n, c),
            ],
            [
                Vertex::new(0.0, 0.0, 1.01 * n, c),
                Vertex::new(96.0, 0.0, 0.99 * f, c),
                Vertex::new(0.0, 64.0, 1.01 * n, c),
            ],
            [
                Vertex::new(96.0, 0.0, 1.01 * n, c),
                Vertex::new(0.0, 32.0, 0.99 * f, c),
                Vertex::new(96.0, 64.0, 1.5 * n, c),
            ],
        ];
        for k in 0..160 {
            let tri = match fixed.get(k) {
                Some(t) => *t,
                None => random_tri(&mut rng, nd * 0.8, fd * 1.1),
            };
            let Some(refpx) =
                reference_tri(&tri.map(|q| (q.x, q.y, q.rhw)), n, f, W as i32, 0..H as i32)
            else {
                continue;
            };
            let (_, codes, stats) =
                render_format::<F, PerPixel<DefaultRecip>>(&[tri], state, W, H).unwrap();
            let drawn = refpx.iter().filter(|p| p.in_range).count() as u32;
            assert_eq!(stats.written, drawn, "{} coverage {tri:?}", F::NAME);
            for p in refpx.iter().filter(|p| p.in_range) {
                let d = fd / p.t;
                let code = codes[(p.y as u32 * W as u32 + p.x as u32) as usize];
                let want = exact_fraction::<F>(d, nd, fd);
                let got = F::fraction(code, nd, fd);
                let err = (got - want).abs();
                // Plus what the depth grid can move the exact value (`RefPixel::grid_t`, derived): the format's
                // value at `t` moved by that much either way.
                let gt = p.grid_t.min(p.t / 2.0);
                let grid = (exact_fraction::<F>(fd / (p.t - gt), nd, fd) - want)
                    .abs()
                    .max((exact_fraction::<F>(fd / (p.t + gt), nd, fd) - want).abs());
                let bound = value_bound::<F>(want) + half_step::<F>(code, nd, fd) + grid;
                assert!(
                    err <= bound,
                    "{} n={n} f={f} d={d}: value {got} vs exact {want}, err {err:e} > bound {bound:e}",
                    F::NAME
                );
                pixels += 1;
                // Not the correctly rounded code only where the exact value lies within the value bound of the
                // midpoint between the stored code and the correctly rounded one (a rounding boundary): the share of
                // such pixels is what the bound predicts, asserted per pixel rather than as a tuned percentage.
                let e = F::encode(d, nd, fd);
                if code != e {
                    let mid = (got + F::fraction(e, nd, fd)) / 2.0;
                    assert!(
                        (want - mid).abs() <= value_bound::<F>(want) + grid,
                        "{} n={n} f={f} d={d}: code {code}, correctly rounded {e}, exact {want} is {:e} from their midpoint (bound {:e} + grid {grid:e})",
                        F::NAME,
                        (want - mid).abs(),
                        value_bound::<F>(want)
                    );
                }
                exact += (code == e) as u64;
                worst = worst.max(err / bound);
            }
        }
    }
    println!(
        "{}: {pixels} px, {:.4}% equal to the f64 encode, worst error {:.3} of its bound",
        F::NAME,
        100.0 * exact as f64 / pixels as f64,
        worst
    );
    assert!(pixels > 10_000);
}

#[test]
fn w16_within_bound() {
    within_bound::<W16>();
}
#[test]
fn w16f_within_bound() {
    within_bound::<W16F>();
}
#[test]
fn w24f_within_bound() {
    within_bound::<W24F>();
}
#[test]
fn w24f_scaled_within_bound() {
    within_bound::<W24FScaled>();
}
#[test]
fn w32f_within_bound() {
    within_bound::<W32F>();
}
#[test]
fn z16_within_bound() {
    within_bound::<Z16>();
}
#[test]
fn z24_within_bound() {
    within_bound::<Z24>();
}
#[test]
fn z32f_within_bound() {
    within_bound::<Z32F>();
}
#[test]
fn rz32f_within_bound() {
    within_bound::<RZ32F>();
}

/// Seed 004's linear-Z trick stores `(d - n) / (f - n)` at the vertices and interpolates it linearly in screen space,
/// where `1/d` is what is linear. With screen barycentrics `l_i`, the stored depth is `sum l_i d_i` against the true
/// `1 / sum (l_i / d_i)`, and by Kantorovich's inequality their ratio is at most `(r + 1)^2 / (4r)`, `r = d_max/d_min`:
/// relative error at most `(r - 1)^2 / (4r)` (seed_numbers.rs checks the one-dimensional case against the seed).
/// Every pixel of a slanted quad stays inside that bound (plus the rounding and the `T` error of the bound above),
/// always towards far, and the error is real: above a quarter of the bound somewhere, hundreds of codes.
#[test]
fn linear_z_trick_errs_inside_triangles_within_kantorovich() {
    let (n, f) = (10.0f32, 10000.0f32);
    let (nd, fd) = (n as f64, f as f64);
    let c = Rgb565::GREEN;
    let quad = [
        (2.0, 2.0, 20.0),
        (94.0, 2.0, 20.0),
        (94.0, 62.0, 2000.0),
        (2.0, 62.0, 2000.0),
    ];
    let v = |k: usize| Vertex::new(quad[k].0, quad[k].1, quad[k].2, c);
    let tris = [[v(0), v(1), v(2)], [v(0), v(2), v(3)]];
    let state = RenderState::new(n, f).unwrap();
    let (_, codes, _) = render_format::<LZ16, PerPixel<DefaultRecip>>(&tris, state, W, H).unwrap();
    let (mut max_rel, mut max_codes, mut px) = (0f64, 0i64, 0);
    for tri in &tris {
        let depths = tri.map(|q| 1.0 / q.rhw as f64);
        let r = depths.iter().cloned().fold(0.0, f64::max)
            / depths.iter().cloned().fold(f64::MAX, f64::min);
        let kant = (r - 1.0).powi(2) / (4.0 * r);
        for p in
            reference_tri(&tri.map(|q| (q.x, q.y, q.rhw)), n, f, W as i32, 0..H as i32).unwrap()
        {
            let d = fd / p.t;
            let code = codes[(p.y as u32 * W as u32 + p.x as u32) as usize];
            let stored = LZ16::fraction(code, nd, fd);
            // the stored linear depth's relative error, as a depth: (n + s (f - n)) / d - 1
            let rel = (nd + stored * (fd - nd)) / d - 1.0;
            let slack = (half_step::<LZ16>(code, nd, fd) + 2f64.powi(-33)) * (fd - nd) / d;
            assert!(
                rel <= kant + slack && rel >= -slack,
                "d={d}: rel {rel} vs bound {kant}"
            );
            max_rel = max_rel.max(rel / kant);
            max_codes = max_codes.max(code as i64 - LZ16::encode(d, nd, fd) as i64);
            px += 1;
        }
    }
    println!("linear-Z trick: {px} px, worst {max_rel:.3} of the Kantorovich bound, {max_codes} codes too far");
    assert!(max_rel > 0.25 && max_codes > 100);
}

/// Seed 002's capability check and the Windows CE "Depth Buffering" docs' "no depth buffer, no depth".
#[test]
fn modes_fall_back_and_depth_is_off_without_a_buffer() {
    use DepthMode::{Off, Z};
    const WM: DepthMode = DepthMode::W;
    let r = |m, has| resolve::<Z16>(m, has).map(|r| (r.mode, r.fell_back));
    assert_eq!(
        r(WM, true),
        Ok((Z, true)),
        "W asked, Z format: Z, and it says so"
    );
    assert_eq!(r(Z, true), Ok((Z, false)));
    assert_eq!(r(Off, true), Ok((Off, false)));
    assert_eq!(r(WM, false), Ok((Off, false)), "no buffer: off");
    assert_eq!(r(Z, false), Ok((Off, false)));
    assert_eq!(resolve::<W16F>(WM, true).map(|r| r.mode), Ok(WM));
    assert_eq!(resolve::<W16F>(Z, true), Err(Error::ZWithWFormat));
    assert_eq!(resolve::<LZ16>(WM, true).map(|r| r.fell_back), Ok(true));

    // Without a buffer every covered pixel is written, in drawing order (the later triangle wins), whatever the mode.
    let near = [
        Vertex::new(0.0, 0.0, 20.0, Rgb565::RED),
        Vertex::new(96.0, 0.0, 20.0, Rgb565::RED),
        Vertex::new(0.0, 64.0, 20.0, Rgb565::RED),
    ];
    let far = near.map(|q| Vertex::new(q.x, q.y, 900.0, Rgb565::BLUE));
    for mode in [Off, Z, WM] {
        let mut state = RenderState::new(10.0, 1000.0).unwrap();
        state.mode = mode;
        let mut r = Rasterizer::<PerPixel<DefaultRecip>>::new(state);
        let mut frame = Frame::new(W as u32, H as u32);
        let a = r.draw(&mut frame, NoDepth, &near).unwrap();
        let b = r.draw(&mut frame, NoDepth, &far).unwrap();
        assert_eq!((a.written, b.written), (a.fragments, b.fragments));
        assert!(a.written > 2000);
        assert!(
            frame.px.iter().all(|&c| c != Rgb565::RED),
            "{mode:?}: depth must be off"
        );
        if mode == Z {
            continue; // Z with a W16 buffer is refused: below
        }
        // With a buffer and mode Off, the buffer is untouched and everything passes.
        let mut bytes = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::<W16>::new_format(&mut bytes, W, H).unwrap();
        buf.clear_for(&state.range);
        let s = r.draw(&mut frame, Some(&mut buf), &near).unwrap();
        let t = r.draw(&mut frame, Some(&mut buf), &far).unwrap();
        if mode == Off {
            assert_eq!((s.written, t.written), (s.fragments, t.fragments));
            assert!(
                bytes.iter().all(|&b| b == 0xffff),
                "mode Off must not write depth"
            );
        } else if mode == WM {
            assert_eq!(t.written, 0, "W: the far triangle is hidden");
        }
    }
    // Z asked with a W format is an error, and nothing is drawn.
    let mut state = RenderState::new(10.0, 1000.0).unwrap();
    state.mode = Z;
    let mut r = Rasterizer::<PerPixel<DefaultRecip>>::new(state);
    let mut frame = Frame::new(W as u32, H as u32);
    let mut bytes = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::<W16>::new_format(&mut bytes, W, H).unwrap();
    assert_eq!(
        r.draw(&mut frame, Some(&mut buf), &near),
        Err(Error::ZWithWFormat)
    );
    assert_eq!(frame.writes.iter().sum::<u32>(), 0);
    let mut d16 = vec![0u16; W as usize * H as usize];
    let mut lean = wraster::DepthBuffer::new(&mut d16, W, H).unwrap();
    assert_eq!(
        r.draw(&mut frame, &mut lean, &near),
        Err(Error::ZWithWFormat)
    );
}

/// Two triangles 50 units apart, drawn in both orders: with `Less`, the nearer one is visible in every format,
/// including reversed Z (whose comparison is evaluated reversed) and with every W strategy.
#[test]
fn less_keeps_the_nearest_in_every_format() {
    fn check<F: Codec, R: WSpan>() {
        let mk = |w: f32, c| {
            [
                Vertex::new(4.0, 4.0, w, c),
                Vertex::new(90.0, 8.0, w * 1.5, c),
                Vertex::new(10.0, 60.0, w * 1.2, c),
            ]
        };
        let (a, b) = (mk(100.0, Rgb565::RED), mk(150.0, Rgb565::BLUE));
        let state = RenderState::new(1.0, 1000.0).unwrap();
        for order in [[a, b], [b, a]] {
            let (frame, _, _) = render_format::<F, R>(&order, state, W, H).unwrap();
            let red = frame.px.iter().filter(|&&c| c == Rgb565::RED).count();
            assert!(red > 2000, "{} {}", F::NAME, R::NAME);
            assert!(
                frame.px.iter().all(|&c| c != Rgb565::BLUE),
                "{} {}: the far one shows",
                F::NAME,
                R::NAME
            );
        }
    }
    check::<W16, PerPixel<DefaultRecip>>();
    check::<W16F, PrevPixel>();
    check::<W24F, Quake<8>>();
    check::<W24FScaled, Quake<16>>();
    check::<W32F, PerPixel<DefaultRecip>>();
    check::<Z16, PerPixel<DefaultRecip>>();
    check::<Z24, PerPixel<DefaultRecip>>();
    check::<Z32F, PerPixel<DefaultRecip>>();
    check::<RZ32F, PerPixel<DefaultRecip>>();
    check::<LZ16, PerPixel<DefaultRecip>>();
}

/// A packed buffer of the wrong size is refused; bands of a packed buffer cover exactly their rows.
#[test]
fn packed_buffers_check_their_size() {
    let mut b = vec![[0u8; 3]; 3];
    assert!(matches!(
        DepthBuffer::<Z24>::new_format(&mut b, 2, 2),
        Err(Error::BufferSize {
            expected: 4,
            actual: 3
        })
    ));
    let mut b = vec![[0u8; 3]; 4];
    let buf = DepthBuffer::<Z24>::new_format(&mut b, 2, 2).unwrap();
    assert_eq!(buf.code(1, 1), Some(0));
    assert_eq!(buf.get(2, 1), None);
}

/// Depth bias in the packed path, in each format's codes (the Windows CE "Depth Buffering" docs, "in the units of the buffer in use"), for two
/// triangles in one plane (B inside A, drawn after it with `Less`; the geometry of bias.rs, depths 51 to 238, range
/// 1..1000). Their stored codes disagree by at most `k` codes, so without bias B fights and with a bias of `-(k + 1)`
/// it shows everywhere:
/// - 16-bit formats: each code is within 1 of the exact value's (the bound above is far below half a code) and the
///   exact values differ by the f32 rounding of RHW only (far below a code): `k = 3`;
/// - reversed float Z: each value errs by `rz 2^-31 + 2^-30` (above), one code is `rz 2^-23` or more, and `rz >= 2^-10`
///   for `d <= 500` here, so each is within `2^-6 / rz <= 16` codes plus a half of rounding; the f32 rounding of RHW
///   moves `rz` by `t K 2^-24`, at most one code for `t >= 2`: `k = 2 * 16 + 2 = 34`. A negative bias is nearer in
///   every format (for reversed Z it raises the code).
///
/// (LZ16 is not here: the linear-Z trick's interior error makes the smaller triangle B nearer than A everywhere, so the
/// pair does not fight; it disagrees by far more than any bias should cover.)
#[test]
fn bias_removes_coplanar_fighting_in_every_16_bit_format_and_reversed_z() {
    fn shown<F: Codec>(bias: f32) -> (usize, usize) {
        let rhw = |x: f32, y: f32| (0.05 - 0.0007 * x as f64 - 0.0006 * y as f64) as f32;
        let tri = |p: [(f32, f32); 3], c| {
            p.map(|(x, y)| Vertex {
                x,
                y,
                z: 0.5,
                rhw: rhw(x, y),
                color: c,
            })
        };
        let a = tri([(2.0, 2.0), (62.0, 4.0), (4.0, 46.0)], Rgb565::RED);
        let b = tri([(8.0, 7.0), (50.0, 12.0), (12.0, 38.0)], Rgb565::BLUE);
        let base = RenderState::new(1.0, 1000.0).unwrap();
        let mut frame = Frame::new(W as u32, H as u32);
        let mut bytes = vec![<F as DepthFormat>::Word::default(); W as usize * H as usize];
        let mut buf = DepthBuffer::<F>::new_format(&mut bytes, W, H).unwrap();
        buf.clear_for(&base.range);
        Rasterizer::<PerPixel<DefaultRecip>>::new(base)
            .draw(&mut frame, Some(&mut buf), &a)
            .unwrap();
        let state = RenderState {
            depth_bias: bias,
            ..base
        };
        let s = Rasterizer::<PerPixel<DefaultRecip>>::new(state)
            .draw(&mut frame, Some(&mut buf), &b)
            .unwrap();
        (
            s.fragments as usize,
            frame.px.iter().filter(|&&c| c == Rgb565::BLUE).count(),
        )
    }
    fn check<F: Codec>(k: f32) {
        let (n, s) = shown::<F>(0.0);
        assert!(
            n > 300 && s < n,
            "{}: without bias the pair fights ({s} of {n})",
            F::NAME
        );
        let (n, s) = shown::<F>(-(k + 1.0));
        assert_eq!(
            s,
            n,
            "{}: bias {} must show B everywhere",
            F::NAME,
            -(k + 1.0)
        );
        println!(
            "{}: no bias fights, bias {} shows all {n}",
            F::NAME,
            -(k + 1.0)
        );
    }
    check::<W16>(3.0);
    check::<W16F>(3.0);
    check::<Z16>(3.0);
    check::<RZ32F>(34.0);
}

/// All eight comparisons, with depth write on and off, give the same frame and codes on the packed path as on the lean
/// one (W16, the overdraw scene); on reversed Z they keep their meaning in depth order: `Greater` keeps the farthest
/// surface, as `Greater` does on W16.
#[test]
fn every_comparison_on_the_packed_path() {
    let scene = Scene::Overdraw;
    let (n, f) = scene.depth_range();
    let tris: Vec<_> = scene.tris().collect();
    for cmp in host_tests::COMPARES {
        for write in [true, false] {
            let state = RenderState {
                compare: cmp,
                depth_write: write,
                ..RenderState::new(n, f).unwrap()
            };
            let (f1, d1, s1) =
                render::<PerPixel<DefaultRecip>>(&tris, state, WIDTH, HEIGHT, HEIGHT).unwrap();
            let (f2, d2, s2) =
                render_format::<W16, PerPixel<DefaultRecip>>(&tris, state, WIDTH, HEIGHT).unwrap();
            assert_eq!(s1, s2, "{cmp:?} {write}");
            assert!(
                f1 == f2 && d1.iter().zip(&d2).all(|(a, b)| *a as u32 == *b),
                "{cmp:?} {write}"
            );
        }
    }
    // Reversed Z evaluates every comparison in depth order: after a `Less` pass, a second pass in reverse order with
    // each comparison shows the same surfaces as W16, except where two surfaces' exact depths are within 2 W16 LSB
    // (each W16 code is within 1 of exact, so only there can W16 see a tie that reversed Z does not).
    fn two_pass<F: Codec>(
        tris: &[[Vertex<Rgb565>; 3]],
        state: RenderState,
        cmp: Compare,
    ) -> (Vec<Rgb565>, u32) {
        let mut frame = Frame::new(WIDTH as u32, HEIGHT as u32);
        let mut bytes = vec![<F as DepthFormat>::Word::default(); WIDTH as usize * HEIGHT as usize];
        let mut buf = DepthBuffer::<F>::new_format(&mut bytes, WIDTH, HEIGHT).unwrap();
        buf.clear_for(&state.range);
        let mut r = Rasterizer::<PerPixel<DefaultRecip>>::new(state);
        for t in tris {
            r.draw(&mut frame, Some(&mut buf), t).unwrap();
        }
        r.state.compare = cmp;
        let mut second = 0;
        for t in tris.iter().rev() {
            let c = t.map(|v| Vertex {
                color: Rgb565::MAGENTA,
                ..v
            });
            second += r.draw(&mut frame, Some(&mut buf), &c).unwrap().written;
        }
        (frame.px, second)
    }
    let state = RenderState::new(n, f).unwrap();
    let rf = host_tests::reference_frame(&tris, n, f, WIDTH as u32, HEIGHT as u32);
    let tie = |k: usize| (rf.runner_up[k] - rf.depth[k]) * 65535.0 <= 2.0;
    for cmp in [
        Compare::Greater,
        Compare::GreaterEqual,
        Compare::LessEqual,
        Compare::Equal,
        Compare::NotEqual,
    ] {
        let (w, sw) = two_pass::<W16>(&tris, state, cmp);
        let (rz, _) = two_pass::<RZ32F>(&tris, state, cmp);
        let differ = (0..w.len()).filter(|&k| w[k] != rz[k] && !tie(k)).count();
        assert_eq!(differ, 0, "{cmp:?}");
        if cmp != Compare::Equal {
            assert!(sw > 1000, "{cmp:?}: the second pass draws");
        }
    }
}

/// One draw method for every depth argument: a buffer given as `&mut`, as `Some` or (for the depth-off draw) as
/// `NoDepth` draws the same frame, codes and stats as the span loop generic over the format given the same argument
/// (`draw_generic`): on W16 with the fast tier (whose own loops `draw` takes, the same codes as the generic loop's
/// W16 instance), on W16 with `Quake` (which `draw` gives to the generic loop) and on Z24; with `NoDepth` every
/// fragment in the depth range is written.
#[test]
fn one_draw_method_for_every_depth_argument() {
    use wraster::format::Storage;
    use wraster::recip::Fast;
    use wraster::{DepthBuffer, NoDepth};
    let scene = Scene::Overdraw;
    let (n, f) = scene.depth_range();
    let tris: Vec<_> = scene.tris().collect();
    let state = RenderState::new(n, f).unwrap();
    fn run<F: Codec, R: WSpan>(
        tris: &[[Vertex<Rgb565>; 3]],
        state: RenderState,
        how: u8,
    ) -> (Frame, Vec<u32>, wraster::Stats) {
        let mut frame = Frame::new(WIDTH as u32, HEIGHT as u32);
        let mut words = vec![F::Word::default(); WIDTH as usize * HEIGHT as usize];
        let mut buf = DepthBuffer::<F>::new_format(&mut words, WIDTH, HEIGHT).unwrap();
        buf.clear_for(&state.range);
        let mut r = Rasterizer::<R>::new(state);
        let mut stats = wraster::Stats::default();
        for t in tris {
            stats += match how {
                0 => r.draw(&mut frame, &mut buf, t),
                1 => r.draw(&mut frame, Some(&mut buf), t),
                2 => r.draw_generic(&mut frame, &mut buf, t),
                3 => r.draw(&mut frame, NoDepth, t),
                _ => r.draw_generic(&mut frame, NoDepth, t),
            }
            .unwrap();
        }
        (frame, words.iter().map(|w| w.code()).collect(), stats)
    }
    fn check<F: Codec, R: WSpan>(tris: &[[Vertex<Rgb565>; 3]], state: RenderState) {
        let a = run::<F, R>(tris, state, 0);
        for how in [1, 2] {
            let b = run::<F, R>(tris, state, how);
            assert!(a.0 == b.0 && a.1 == b.1, "{} {} {how}", F::NAME, R::NAME);
            assert_eq!(a.2, b.2, "{} {} {how}", F::NAME, R::NAME);
        }
        assert!(
            a.2.written < a.2.fragments,
            "{}: the depth test hides some",
            F::NAME
        );
    }
    check::<W16, Fast>(&tris, state);
    check::<W16, Quake<8>>(&tris, state);
    check::<Z24, Fast>(&tris, state);
    let (off, gen) = (
        run::<W16, Fast>(&tris, state, 3),
        run::<W16, Fast>(&tris, state, 4),
    );
    assert!(off.0 == gen.0 && off.2 == gen.2);
    assert_eq!(
        off.2.written, off.2.fragments,
        "depth off writes every fragment"
    );
}
