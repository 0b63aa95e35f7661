//! One function per fuzz target: it decodes the bytes into calls, makes them, and panics when an invariant fails.
//!
//! Invariants, every target: no panic (overflow checks on); no write outside the colour target (it panics) or the
//! depth storage (guard areas on both sides, checked after every call); an error other than [`Error::Target`] leaves
//! both buffers exactly as they were; a frame drawn in bands equals the frame drawn whole (pixels, write counts,
//! codes, fragments and written counts, and the same error for the same call); a failing colour target gives
//! [`Error::Target`] and no other error than the whole draw gives.

use super::{Bytes, Canvas, Guarded};
use embedded_graphics_core::pixelcolor::Rgb565;
use embedded_graphics_core::prelude::Size;
use wraster::clip::Viewport;
use wraster::format::{Storage, W24FScaled, LZ16, RZ32F, W16, W16F, W24F, W32F, Z16, Z24, Z32F};
use wraster::input::{I24F8, U16F16, U1F31, U8F24};
use wraster::mesh::{Colors, Mesh, PlaneCache, Projected};
use wraster::projection::{self, Camera, Mat4};
use wraster::recip::{
    Exact, Fast, FastDiv, Linear, Newton, PerPixel, PrevPixel, Quake, SpanRecip, WSpan,
};
use wraster::{
    Codec, Compare, Cull, DepthBuffer, DepthMode, DepthRange, Error, FixedVertex, Rasterizer,
    RenderState, Stats, Vertex, VertexInput,
};

const COMPARES: [Compare; 8] = [
    Compare::Never,
    Compare::Less,
    Compare::Equal,
    Compare::LessEqual,
    Compare::Greater,
    Compare::NotEqual,
    Compare::GreaterEqual,
    Compare::Always,
];

/// A render state from the bytes; an invalid depth range is checked to be refused, then replaced by a valid one.
fn state(b: &mut Bytes) -> RenderState {
    let (near, far) = (b.f32(), b.f32());
    let mut s = match RenderState::new(near, far) {
        Ok(s) => {
            let (n, f) = (s.range.near(), s.range.far());
            assert!(n > 0.0 && f > n && f.is_finite(), "accepted {near} {far}");
            s
        }
        Err(e) => {
            assert!(
                matches!(e, Error::NonFinite | Error::InvalidDepthRange),
                "{e:?}"
            );
            RenderState::new(1.0, 1000.0).unwrap()
        }
    };
    s.mode = [DepthMode::W, DepthMode::Z, DepthMode::Off][b.u8() as usize % 3];
    s.compare = COMPARES[b.u8() as usize % 8];
    s.depth_write = !b.u8().is_multiple_of(4);
    s.cull = [Cull::None, Cull::Cw, Cull::Ccw][b.u8() as usize % 3];
    if b.u8().is_multiple_of(4) {
        s.depth_bias = b.f32();
        s.slope_scale_depth_bias = b.f32();
    }
    s
}

fn vertex(b: &mut Bytes) -> Vertex<Rgb565> {
    Vertex {
        x: b.f32(),
        y: b.f32(),
        z: if b.u8().is_multiple_of(8) {
            b.f32()
        } else {
            0.0
        },
        rhw: b.f32(),
        color: b.color(),
    }
}

fn dims(b: &mut Bytes) -> (u16, u16, u16) {
    let w = 1 + b.u8() as u16 % 40;
    let h = 1 + b.u8() as u16 % 40;
    let band = 1 + b.u8() as u16 % h;
    (w, h, band)
}

/// Asserts that an error left the canvas and the depth storage as they were.
fn untouched<T: PartialEq + core::fmt::Debug>(
    e: Error,
    canvas: &Canvas,
    before: &Canvas,
    depth: &[T],
    depth_before: &[T],
) {
    assert_ne!(e, Error::Target, "no target failure was asked for");
    assert!(
        canvas.same_picture(before),
        "{e:?}, yet the colour target was written"
    );
    assert!(
        depth == depth_before,
        "{e:?}, yet the depth buffer was written"
    );
}

/// Compares a banded draw's summed results with the whole draw's.
fn same_result(whole: &Result<Stats, Error>, bands: Result<Stats, Error>) {
    match (whole, bands) {
        (Ok(a), Ok(b)) => assert_eq!(
            (a.fragments, a.written),
            (b.fragments, b.written),
            "bands and whole disagree"
        ),
        (Err(a), Err(b)) => assert_eq!(*a, b),
        (a, b) => panic!("whole {a:?}, bands {b:?}"),
    }
}

fn add(sum: &mut Result<Stats, Error>, r: Result<Stats, Error>) {
    match (sum.as_mut(), r) {
        (Ok(s), Ok(t)) => *s += t,
        (Ok(_), Err(e)) => *sum = Err(e),
        (Err(_), _) => {}
    }
}

/// The failing target: the same calls with a pixel budget. Each call gives what the whole draw gave, or
/// `Err(Target)` (after which the run stops, as a firmware would).
fn failing_matches(
    whole: &[Result<Stats, Error>],
    mut call: impl FnMut(usize) -> Result<Stats, Error>,
) {
    for (k, want) in whole.iter().enumerate() {
        match (want, call(k)) {
            (_, Err(Error::Target)) => {
                assert!(want.is_ok(), "{want:?} became a target failure");
                return;
            }
            (Ok(_), Ok(_)) => {}
            (Err(a), Err(b)) => assert_eq!(*a, b),
            (a, b) => panic!("whole {a:?}, failing target {b:?}"),
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// raster: the W16 path (`draw`, `draw_gouraud`) with every span strategy.

pub fn raster(data: &[u8]) {
    let mut b = Bytes(data);
    // The division seed, the only strategy whose passing runs chain (`chain_run`, walked to a sentinel), takes half
    // of `Fast`'s first bytes (4 modulo 8), so that the regression inputs keep the strategies they were found with.
    match b.u8() {
        k if k % 8 == 4 => raster_with::<FastDiv>(&mut b),
        k if k % 4 == 0 => raster_with::<Fast>(&mut b),
        k if k % 4 == 1 => raster_with::<Exact>(&mut b),
        k if k % 4 == 2 => raster_with::<PrevPixel>(&mut b),
        _ => raster_with::<PerPixel<Newton<Linear, 2>>>(&mut b),
    }
}

fn raster_with<R: SpanRecip>(b: &mut Bytes) {
    let (w, h, band) = dims(b);
    let n = (w as usize) * (h as usize);
    let st = state(b);
    let ops: Vec<(bool, [Vertex<Rgb565>; 3])> = (0..1 + b.u8() % 6)
        .map(|_| (b.u8().is_multiple_of(4), [vertex(b), vertex(b), vertex(b)]))
        .collect();
    // A wrong-size buffer is refused.
    let off = b.u8() as usize % 5;
    if off != 2 && n + off >= 2 {
        let mut v = vec![0u16; n + off - 2];
        assert!(matches!(
            DepthBuffer::new(&mut v, w, h),
            Err(Error::BufferSize { .. })
        ));
        assert!(matches!(
            DepthBuffer::band(&mut v, w, 3, h),
            Err(Error::BufferSize { .. })
        ));
    }
    if std::env::var_os("WRASTER_FUZZ_DEBUG").is_some() {
        eprintln!(
            "{} {w}x{h} band {band} {st:?}\n{ops:?}",
            core::any::type_name::<R>()
        );
    }
    let draw = |r: &mut Rasterizer<R>,
                c: &mut Canvas,
                d: &mut DepthBuffer,
                g: bool,
                t: &[Vertex<Rgb565>; 3]| {
        if g {
            r.draw_gouraud(c, d, t)
        } else {
            r.draw(c, d, t)
        }
    };

    let mut r = Rasterizer::<R>::new(st);
    let mut canvas = Canvas::new(w as u32, h as u32);
    let mut depth = Guarded::new(n, 0u16, 0xa5a5);
    DepthBuffer::new(depth.inner(), w, h).unwrap().clear();
    let mut whole = Vec::new();
    // The whole run's colour and depth after each call (index k + 1), for the failing target's documented state.
    let mut states = vec![(canvas.clone(), depth.data().to_vec())];
    for (g, t) in &ops {
        let (c0, d0) = (canvas.clone(), depth.data().to_vec());
        let res = draw(
            &mut r,
            &mut canvas,
            &mut DepthBuffer::new(depth.inner(), w, h).unwrap(),
            *g,
            t,
        );
        depth.check();
        match res {
            Err(e) => untouched(e, &canvas, &c0, depth.data(), &d0),
            Ok(s) => {
                assert!(s.written <= s.fragments && s.fragments as usize <= n && s.culled <= 1)
            }
        }
        whole.push(res);
        states.push((canvas.clone(), depth.data().to_vec()));
    }

    let mut canvas2 = Canvas::new(w as u32, h as u32);
    let mut depth2 = Guarded::new(n, 0u16, 0x5a5a);
    DepthBuffer::new(depth2.inner(), w, h).unwrap().clear();
    for ((g, t), want) in ops.iter().zip(&whole) {
        let mut sum = Ok(Stats::default());
        for y0 in (0..h).step_by(band as usize) {
            let hh = band.min(h - y0);
            let rows =
                &mut depth2.inner()[y0 as usize * w as usize..(y0 + hh) as usize * w as usize];
            let mut buf = DepthBuffer::band(rows, w, y0 as i32, hh).unwrap();
            add(&mut sum, draw(&mut r, &mut canvas2, &mut buf, *g, t));
        }
        depth2.check();
        same_result(want, sum);
    }
    assert!(canvas.same_picture(&canvas2), "bands drew another picture");
    assert!(depth.data() == depth2.data(), "bands stored other codes");

    // The flat triangles as a list frame with a plane cache, band by band (`PlaneCache::list`, `draw_listed`): the
    // same results, pictures and codes as `draw` of each in the same bands and order, with a cache of any size.
    let flat: Vec<[Vertex<Rgb565>; 3]> = ops.iter().filter(|(g, _)| !g).map(|(_, t)| *t).collect();
    let (mut few, mut many) = (PlaneCache::<1>::new(), PlaneCache::<8>::new());
    let lists = [few.list(&flat), many.list(&flat)];
    let mut plain = (
        Canvas::new(w as u32, h as u32),
        Guarded::new(n, 0u16, 0x5a5a),
    );
    let mut listed: Vec<_> = lists
        .iter()
        .map(|_| {
            (
                Canvas::new(w as u32, h as u32),
                Guarded::new(n, 0u16, 0x5a5a),
            )
        })
        .collect();
    for y0 in (0..h).step_by(band as usize) {
        let hh = band.min(h - y0);
        let span = y0 as usize * w as usize..(y0 + hh) as usize * w as usize;
        let mut pd =
            DepthBuffer::band(&mut plain.1.inner()[span.clone()], w, y0 as i32, hh).unwrap();
        pd.clear();
        let mut bufs: Vec<_> = listed
            .iter_mut()
            .map(|(c, d)| {
                let mut buf =
                    DepthBuffer::band(&mut d.inner()[span.clone()], w, y0 as i32, hh).unwrap();
                buf.clear();
                (c, buf)
            })
            .collect();
        for (k, t) in flat.iter().enumerate() {
            let want = r.draw(&mut plain.0, &mut pd, t);
            for ((c, buf), list) in bufs.iter_mut().zip(&lists) {
                same_result(&want, r.draw_listed(*c, buf, list, k));
            }
        }
    }
    plain.1.check();
    for (c, d) in &listed {
        d.check();
        assert!(plain.0.same_picture(c), "a list frame drew another picture");
        assert!(
            plain.1.data() == d.data(),
            "a list frame stored other codes"
        );
    }

    // A coarse bound kept across the calls (whole frame): the same results, pictures and codes as without it, and
    // no write outside the bound's own buffer.
    let mut canvas4 = Canvas::new(w as u32, h as u32);
    let mut depth4 = Guarded::new(n, 0u16, 0x5a5a);
    let mut seg = Guarded::new(wraster::bound_len(w as usize, h as usize), 0u16, 0x3c3c);
    {
        let mut buf = DepthBuffer::new(depth4.inner(), w, h)
            .unwrap()
            .with_bound(seg.inner())
            .unwrap();
        buf.clear();
        for ((g, t), want) in ops.iter().zip(&whole) {
            same_result(want, draw(&mut r, &mut canvas4, &mut buf, *g, t));
        }
    }
    depth4.check();
    seg.check();
    assert!(
        canvas.same_picture(&canvas4),
        "the coarse bound drew another picture"
    );
    assert!(
        depth.data() == depth4.data(),
        "the coarse bound stored other codes"
    );

    let mut canvas3 = Canvas::new(w as u32, h as u32);
    canvas3.budget = Some(b.u16() as u32 % 512);
    let mut depth3 = Guarded::new(n, 0u16, 0x5a5a);
    DepthBuffer::new(depth3.inner(), w, h).unwrap().clear();
    let mut failed_at = None;
    failing_matches(&whole, |k| {
        let (g, t) = &ops[k];
        let res = draw(
            &mut r,
            &mut canvas3,
            &mut DepthBuffer::new(depth3.inner(), w, h).unwrap(),
            *g,
            t,
        );
        if res == Err(Error::Target) {
            failed_at = Some(k);
        }
        res
    });
    depth3.check();
    if let Some(k) = failed_at {
        // Error::Target's documented state: every row above the failing one as the whole draw left it (colour and
        // depth), the failing row partly, every later row as it was before the call.
        let (before, after) = (&states[k], &states[k + 1]);
        let cols = |j: usize| j * w as usize..(j + 1) * w as usize;
        let same_as = |st: &(Canvas, Vec<u16>), j: usize| {
            canvas3.px[cols(j)] == st.0.px[cols(j)] && depth3.data()[cols(j)] == st.1[cols(j)]
        };
        let jf = (0..h as usize)
            .find(|&j| !same_as(after, j))
            .unwrap_or(h as usize);
        for j in jf + 1..h as usize {
            assert!(
                same_as(before, j),
                "row {j}, after the failing row {jf}, was touched"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// packed: every format, mode and primitive through `DepthBuffer`s of every format (or none).

pub fn packed(data: &[u8]) {
    let mut b = Bytes(data);
    let strategy = b.u8() % 3;
    macro_rules! with {
        ($f:ty) => {
            match strategy {
                0 => packed_with::<$f, Fast>(&mut b),
                1 => packed_with::<$f, Exact>(&mut b),
                _ => packed_with::<$f, Quake<4>>(&mut b),
            }
        };
    }
    match b.u8() % 10 {
        0 => with!(W16),
        1 => with!(W16F),
        2 => with!(W24F),
        3 => with!(W24FScaled),
        4 => with!(W32F),
        5 => with!(Z16),
        6 => with!(Z24),
        7 => with!(Z32F),
        8 => with!(RZ32F),
        _ => with!(LZ16),
    }
}

#[derive(Clone, Copy, Debug)]
enum Prim {
    Tri,
    Line,
    Point,
    Wire,
}

fn packed_with<F: Codec, R: WSpan>(b: &mut Bytes) {
    let (w, h, band) = dims(b);
    let n = (w as usize) * (h as usize);
    let st = state(b);
    let no_depth = b.u8().is_multiple_of(8);
    let ops: Vec<(Prim, [Vertex<Rgb565>; 3])> = (0..1 + b.u8() % 6)
        .map(|_| {
            let p = [Prim::Tri, Prim::Line, Prim::Point, Prim::Wire][b.u8() as usize % 4];
            (p, [vertex(b), vertex(b), vertex(b)])
        })
        .collect();
    let off = b.u8() as usize % 5;
    if off != 2 && n + off >= 2 {
        let mut v = vec![F::Word::default(); n + off - 2];
        assert!(matches!(
            DepthBuffer::<F>::new_format(&mut v, w, h),
            Err(Error::BufferSize { .. })
        ));
    }
    let draw = |r: &mut Rasterizer<R>,
                c: &mut Canvas,
                d: Option<&mut DepthBuffer<F>>,
                p: Prim,
                t: &[Vertex<Rgb565>; 3]| match p {
        Prim::Tri => r.draw(c, d, t),
        Prim::Line => r.draw_line(c, d, &[t[0], t[1]]),
        Prim::Point => r.draw_point(c, d, &t[0]),
        Prim::Wire => r.draw_wireframe(c, d, t),
    };
    let (fill, s1, s2) = (
        F::Word::default(),
        F::Word::from_code(0xa5a5_a5a5),
        F::Word::from_code(0x5a5a_5a5a),
    );
    let mut r = Rasterizer::<R>::new(st);
    let mut canvas = Canvas::new(w as u32, h as u32);
    let mut depth = Guarded::new(n, fill, s1);
    DepthBuffer::<F>::new_format(depth.inner(), w, h)
        .unwrap()
        .clear_for(&st.range);
    let mut whole = Vec::new();
    for (p, t) in &ops {
        let (c0, d0) = (canvas.clone(), depth.data().to_vec());
        let res = if no_depth {
            draw(&mut r, &mut canvas, None, *p, t)
        } else {
            draw(
                &mut r,
                &mut canvas,
                Some(&mut DepthBuffer::<F>::new_format(depth.inner(), w, h).unwrap()),
                *p,
                t,
            )
        };
        depth.check();
        if let Err(e) = res {
            untouched(e, &canvas, &c0, depth.data(), &d0);
        }
        whole.push(res);
    }
    if !no_depth {
        let mut canvas2 = Canvas::new(w as u32, h as u32);
        let mut depth2 = Guarded::new(n, fill, s2);
        DepthBuffer::<F>::new_format(depth2.inner(), w, h)
            .unwrap()
            .clear_for(&st.range);
        for ((p, t), want) in ops.iter().zip(&whole) {
            let mut sum = Ok(Stats::default());
            for y0 in (0..h).step_by(band as usize) {
                let hh = band.min(h - y0);
                let row = w as usize;
                let rows = &mut depth2.inner()[y0 as usize * row..(y0 + hh) as usize * row];
                let mut buf = DepthBuffer::<F>::band_format(rows, w, y0 as i32, hh).unwrap();
                add(&mut sum, draw(&mut r, &mut canvas2, Some(&mut buf), *p, t));
            }
            depth2.check();
            same_result(want, sum);
        }
        assert!(canvas.same_picture(&canvas2), "bands drew another picture");
        assert!(depth.data() == depth2.data(), "bands stored other codes");
    }
    let mut canvas3 = Canvas::new(w as u32, h as u32);
    canvas3.budget = Some(b.u16() as u32 % 512);
    let mut depth3 = Guarded::new(n, fill, s2);
    DepthBuffer::<F>::new_format(depth3.inner(), w, h)
        .unwrap()
        .clear_for(&st.range);
    failing_matches(&whole, |k| {
        let (p, t) = &ops[k];
        if no_depth {
            draw(&mut r, &mut canvas3, None, *p, t)
        } else {
            draw(
                &mut r,
                &mut canvas3,
                Some(&mut DepthBuffer::<F>::new_format(depth3.inner(), w, h).unwrap()),
                *p,
                t,
            )
        }
    });
    depth3.check();
}

// ---------------------------------------------------------------------------------------------------------------
// world: world-space triangles and meshes, any matrix, viewport, camera, mesh (bad indices, short colour slices,
// short scratch), whole and in bands.

fn mat(b: &mut Bytes) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for row in m.iter_mut() {
        for x in row.iter_mut() {
            *x = b.f32();
        }
    }
    Mat4(m)
}

fn p3(b: &mut Bytes) -> [f32; 3] {
    [b.f32(), b.f32(), b.f32()]
}

pub fn world(data: &[u8]) {
    let mut b = Bytes(data);
    let b = &mut b;
    let (w, h, band) = dims(b);
    let n = (w as usize) * (h as usize);
    let mut st = state(b);
    st.mode = DepthMode::W;
    let m = if b.bool() {
        mat(b)
    } else {
        match Camera::look_at(p3(b), p3(b), p3(b), b.f32(), b.f32(), b.f32(), b.f32()) {
            Ok(cam) => {
                let s = cam
                    .render_state()
                    .expect("a camera that builds gives a render state");
                st.range = s.range;
                st.cull = s.cull;
                let model = Mat4::rotation_y(b.f32()) * Mat4::translation(p3(b));
                cam.model_matrix(&model)
            }
            Err(e) => {
                assert!(
                    matches!(
                        e,
                        Error::InvalidCamera
                            | Error::NonFinite
                            | Error::InvalidDepthRange
                            | Error::WorldTooLarge
                    ),
                    "{e:?}"
                );
                mat(b)
            }
        }
    };
    let vp = if b.bool() {
        Viewport::new(0.0, 0.0, w as f32, h as f32)
    } else {
        Viewport::new(b.f32(), b.f32(), b.f32(), b.f32())
    };
    let nv = 1 + b.u8() as usize % 10;
    let positions: Vec<[f32; 3]> = (0..nv).map(|_| p3(b)).collect();
    let nf = b.u8() % 12;
    let indices: Vec<[u16; 3]> = (0..nf)
        .map(|_| {
            let mut i = || {
                let x = b.u8();
                // Mostly in range; sometimes one past it, or anything.
                match x % 16 {
                    0 => b.u16(),
                    1 => nv as u16,
                    _ => (x as usize % nv) as u16,
                }
            };
            [i(), i(), i()]
        })
        .collect();
    let nc = b.u8() % 12;
    let colours: Vec<Rgb565> = (0..nc).map(|_| b.color()).collect();
    let colors = match b.u8() % 3 {
        0 => Colors::Uniform(b.color()),
        1 => Colors::PerFace(&colours),
        _ => Colors::PerVertex(&colours),
    };
    let mesh = Mesh {
        positions: &positions,
        indices: &indices,
        colors,
    };
    let scratch_len = if b.u8() % 8 == 0 {
        b.u8() as usize % 12
    } else {
        nv
    };
    let tri = [p3(b), p3(b), p3(b)];
    let wcolor = b.color();
    let gouraud = b.bool();

    let mut r: Rasterizer = Rasterizer::new(st);
    let blank = Canvas::new(w as u32, h as u32);
    let mut cleared = vec![0u16; n];
    DepthBuffer::new(&mut cleared, w, h).unwrap().clear();

    // draw_world, whole.
    let mut canvas = Canvas::new(w as u32, h as u32);
    let mut depth = Guarded::new(n, 0u16, 0xa5a5);
    depth.inner().copy_from_slice(&cleared);
    let whole = r.draw_world(
        &mut canvas,
        &mut DepthBuffer::new(depth.inner(), w, h).unwrap(),
        &m,
        &vp,
        &tri,
        wcolor,
    );
    depth.check();
    if let Err(e) = whole {
        untouched(e, &canvas, &blank, depth.data(), &cleared);
    }
    // The mesh, whole.
    let draw_frame =
        |r: &mut Rasterizer,
         c: &mut Canvas,
         d: &mut DepthBuffer,
         f: &Result<wraster::mesh::MeshFrame<Rgb565>, Error>| match f {
            Ok(f) if gouraud => r.draw_mesh_frame_gouraud(c, d, f),
            Ok(f) => r.draw_mesh_frame(c, d, f),
            Err(e) => Err(*e),
        };
    let mut scratch = vec![Projected::default(); scratch_len];
    let frame = r.transform_mesh(&mesh, &m, &vp, &mut scratch);
    if std::env::var_os("WRASTER_FUZZ_DEBUG").is_some() {
        eprintln!(
            "{w}x{h} {st:?}\n{m:?}\n{vp:?}\n{positions:?}\n{indices:?}\n{:?}",
            frame.as_ref().map(|f| f.vertices().to_vec())
        );
    }
    let mut mcanvas = Canvas::new(w as u32, h as u32);
    let mut mdepth = Guarded::new(n, 0u16, 0xa5a5);
    mdepth.inner().copy_from_slice(&cleared);
    let mwhole = draw_frame(
        &mut r,
        &mut mcanvas,
        &mut DepthBuffer::new(mdepth.inner(), w, h).unwrap(),
        &frame,
    );
    mdepth.check();
    if let Err(e) = mwhole {
        untouched(e, &mcanvas, &blank, mdepth.data(), &cleared);
    }
    // The bounding-sphere cull: a mesh it rejects draws nothing (the sphere holds every position, used or not).
    if let Ok(sphere) = wraster::mesh::Sphere::enclosing(&positions) {
        if !sphere.visible(&m, &vp, Size::new(w as u32, h as u32), &st.range) {
            if let Ok(s) = &mwhole {
                assert_eq!(s.written, 0, "culled by its sphere {sphere:?}, yet drawn");
            }
            assert!(mcanvas.same_picture(&blank) && mdepth.data() == &cleared[..]);
        }
    }
    if !gouraud {
        // draw_mesh is transform_mesh then draw_mesh_frame.
        let mut c = Canvas::new(w as u32, h as u32);
        let mut d = Guarded::new(n, 0u16, 0xa5a5);
        d.inner().copy_from_slice(&cleared);
        let mut s2 = vec![Projected::default(); scratch_len];
        let res = r.draw_mesh(
            &mut c,
            &mut DepthBuffer::new(d.inner(), w, h).unwrap(),
            &mesh,
            &m,
            &vp,
            &mut s2,
        );
        d.check();
        assert_eq!(res, mwhole);
        assert!(c.same_picture(&mcanvas) && d.data() == mdepth.data());
    }
    // In bands: draw_world per band, and the mesh frame (transformed once, above) per band.
    let mut canvas2 = Canvas::new(w as u32, h as u32);
    let mut depth2 = Guarded::new(n, 0u16, 0x5a5a);
    depth2.inner().copy_from_slice(&cleared);
    let mut mcanvas2 = Canvas::new(w as u32, h as u32);
    let mut mdepth2 = Guarded::new(n, 0u16, 0x5a5a);
    mdepth2.inner().copy_from_slice(&cleared);
    let (mut sum, mut msum) = (Ok(Stats::default()), Ok(Stats::default()));
    for y0 in (0..h).step_by(band as usize) {
        let hh = band.min(h - y0);
        let rows = y0 as usize * w as usize..(y0 + hh) as usize * w as usize;
        let mut buf =
            DepthBuffer::band(&mut depth2.inner()[rows.clone()], w, y0 as i32, hh).unwrap();
        add(
            &mut sum,
            r.draw_world(&mut canvas2, &mut buf, &m, &vp, &tri, wcolor),
        );
        let mut mbuf = DepthBuffer::band(&mut mdepth2.inner()[rows], w, y0 as i32, hh).unwrap();
        add(
            &mut msum,
            draw_frame(&mut r, &mut mcanvas2, &mut mbuf, &frame),
        );
    }
    depth2.check();
    mdepth2.check();
    same_result(&whole, sum);
    same_result(&mwhole, msum);
    assert!(
        canvas.same_picture(&canvas2) && depth.data() == depth2.data(),
        "draw_world: bands differ"
    );
    assert!(
        mcanvas.same_picture(&mcanvas2) && mdepth.data() == mdepth2.data(),
        "mesh: bands differ"
    );
    // The same triangle in a packed Z format (draw_world), and a failing target.
    let mut zst = st;
    zst.mode = DepthMode::Z;
    let mut rz: Rasterizer<Exact> = Rasterizer::new(zst);
    let mut zc = Canvas::new(w as u32, h as u32);
    let mut zd = Guarded::new(n, [0u8; 3], [0xa5; 3]);
    DepthBuffer::<Z24>::new_format(zd.inner(), w, h)
        .unwrap()
        .clear_for(&zst.range);
    let z0 = zd.data().to_vec();
    let zres = rz.draw_world(
        &mut zc,
        Some(&mut DepthBuffer::<Z24>::new_format(zd.inner(), w, h).unwrap()),
        &m,
        &vp,
        &tri,
        wcolor,
    );
    zd.check();
    match (zres, whole) {
        (Err(e), Err(f)) => {
            assert_eq!(e, f);
            untouched(e, &zc, &blank, zd.data(), &z0);
        }
        (Ok(_), Ok(_)) => {}
        (a, b) => panic!("Z24 {a:?}, W16 {b:?}"),
    }
    let mut fc = Canvas::new(w as u32, h as u32);
    fc.budget = Some(b.u16() as u32 % 512);
    let mut fd = Guarded::new(n, 0u16, 0x5a5a);
    fd.inner().copy_from_slice(&cleared);
    let mut scratch3 = vec![Projected::default(); scratch_len];
    let fres = r.draw_mesh(
        &mut fc,
        &mut DepthBuffer::new(fd.inner(), w, h).unwrap(),
        &mesh,
        &m,
        &vp,
        &mut scratch3,
    );
    fd.check();
    let mut once = Some(fres);
    failing_matches(&[mwhole], |_| once.take().expect("one call"));
    // The frame binned by rows (bin_mesh), in the same bands: the same picture, codes, fragments and writes; bins
    // shorter than the triangles are an error.
    if let Ok(f) = &frame {
        let nb = if b.u8() % 8 == 0 {
            b.u8() as usize % 12
        } else {
            indices.len()
        };
        let mut bins = vec![0u8; nb];
        match r.bin_mesh(*f, &mut bins) {
            Err(e) => {
                assert!(nb < indices.len(), "{e:?}");
                assert_eq!(
                    e,
                    Error::BufferSize {
                        expected: indices.len(),
                        actual: nb
                    }
                );
            }
            Ok(binned) => {
                assert!(binned.binned_culled().is_some());
                // The frame drawn band by band (`draw` one band): the same picture, codes, fragments and writes as
                // the unbinned frame.
                let mut same_in_bands = |what: &str,
                                         draw: &mut dyn FnMut(
                    &mut Rasterizer,
                    &mut Canvas,
                    &mut DepthBuffer,
                )
                    -> Result<Stats, Error>| {
                    let mut bcanvas = Canvas::new(w as u32, h as u32);
                    let mut bdepth = Guarded::new(n, 0u16, 0x5a5a);
                    bdepth.inner().copy_from_slice(&cleared);
                    let mut bsum = Ok(Stats::default());
                    for y0 in (0..h).step_by(band as usize) {
                        let hh = band.min(h - y0);
                        let rows = y0 as usize * w as usize..(y0 + hh) as usize * w as usize;
                        let mut buf =
                            DepthBuffer::band(&mut bdepth.inner()[rows], w, y0 as i32, hh).unwrap();
                        add(&mut bsum, draw(&mut r, &mut bcanvas, &mut buf));
                    }
                    bdepth.check();
                    same_result(&mwhole, bsum);
                    assert!(
                        mcanvas.same_picture(&bcanvas) && mdepth.data() == bdepth.data(),
                        "mesh: the {what} frame differs"
                    );
                };
                same_in_bands("binned", &mut |r, c, d| draw_frame(r, c, d, &Ok(binned)));
                // With a plane cache (3 slots, or 64; the flat draw: Gouraud's has no cache).
                if !gouraud {
                    let (mut few, mut many) = (PlaneCache::<3>::new(), PlaneCache::<64>::new());
                    let cached = if b.u8() % 2 == 0 {
                        binned.with_plane_cache(&mut few)
                    } else {
                        binned.with_plane_cache(&mut many)
                    };
                    same_in_bands("cached", &mut |r, c, d| r.draw_mesh_frame(c, d, &cached));
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// state: the constructors (depth range, render state, viewport, projection, camera, matrices) and buffers of any
// size; f32 helpers on any input.

pub fn state_target(data: &[u8]) {
    let mut b = Bytes(data);
    let b = &mut b;
    let (near, far) = (b.f32(), b.f32());
    match DepthRange::new(near, far) {
        Ok(r) => {
            assert!(r.near() > 0.0 && r.far() > r.near() && r.far().is_finite());
            assert!((r.far() / r.near()) <= wraster::MAX_T * 1.0001);
            assert_eq!(RenderState::new(near, far).map(|s| s.range), Ok(r));
        }
        Err(e) => {
            assert!(matches!(e, Error::NonFinite | Error::InvalidDepthRange));
            assert_eq!(RenderState::new(near, far).err(), Some(e));
        }
    }
    let (fov, aspect) = (b.f32(), b.f32());
    if let Ok(p) = projection::perspective(fov, aspect, near, far) {
        assert!(fov > 0.0 && fov < core::f32::consts::PI && aspect > 0.0);
        let s = p
            .render_state()
            .expect("a perspective that builds gives its render state");
        assert!(projection::is_w_friendly(&p.matrix));
        let _ = projection::w_planes(&p.matrix);
        let _ = s;
    }
    let _ = projection::d3dutil_set_projection_matrix(b.f32(), b.f32(), b.f32(), b.f32());
    let m = mat(b);
    let _ = projection::w_planes(&m);
    let _ = projection::is_w_friendly(&m);
    let _ = projection::wbuffer_planes_matrix(b.f32(), b.f32());
    let (eye, target, up) = (p3(b), p3(b), p3(b));
    if let Ok(v) = Mat4::look_at(eye, target, up) {
        assert!(
            v.0.iter().flatten().all(|x| x.is_finite()),
            "look_at gave {v:?}"
        );
    }
    let _ = Camera::look_at(eye, target, up, fov, aspect, near, far).map(|c| c.render_state());
    let a = b.f32();
    let (s, c) = projection::sin_cos(a);
    if a.is_finite() {
        assert!(
            s.abs() <= 1.0 + 1e-6 && c.abs() <= 1.0 + 1e-6,
            "sin_cos({a}) = {s}, {c}"
        );
    }
    let q = projection::sqrt(a);
    if a >= 0.0 && a.is_finite() {
        assert!(q >= 0.0 && q.is_finite());
    }
    let _ = Mat4::rotation_x(a) * Mat4::rotation_z(b.f32()) * Mat4::scale(p3(b)) * m;
    let _ = Viewport::new(b.f32(), b.f32(), b.f32(), b.f32());
    // Buffers of any size and any band origin: refused unless the storage matches.
    let (w, h) = (b.u16() % 600, b.u16() % 600);
    let len = b.u16() as usize * 4;
    let y0 = b.u32() as i32;
    let mut v = vec![0u16; len];
    let ok = len == w as usize * h as usize;
    for res in [
        DepthBuffer::new(&mut v, w, h).map(|_| ()),
        DepthBuffer::band(&mut v, w, y0, h).map(|_| ()),
    ] {
        match res {
            Ok(()) => assert!(ok),
            Err(e) => assert!(!ok || w == 0 || h == 0, "{e:?}"),
        }
    }
    let mut bytes = vec![[0u8; 3]; len];
    let ok3 = len == w as usize * h as usize;
    match DepthBuffer::<W24F>::band_format(&mut bytes, w, y0, h) {
        Ok(_) => assert!(ok3),
        Err(e) => assert!(!ok3 || w == 0 || h == 0, "{e:?}"),
    }
    // Lighting with any light and any normals.
    let light = wraster::lighting::Light {
        direction: p3(b),
        ambient: b.f32(),
        diffuse: b.f32(),
    };
    let positions: Vec<[f32; 3]> = (0..1 + b.u8() % 6).map(|_| p3(b)).collect();
    let np = positions.len() as u16;
    let indices: Vec<[u16; 3]> = (0..b.u8() % 6)
        .map(|_| [b.u16() % (np + 1), b.u16() % np, b.u16() % np])
        .collect();
    let mut out = vec![Rgb565::new(0, 0, 0); indices.len()];
    let _ = wraster::lighting::shade_faces(
        &positions,
        &indices,
        &m,
        &light,
        |_| Rgb565::new(31, 63, 31),
        &mut out,
    );
    let mut outv = vec![Rgb565::new(0, 0, 0); positions.len()];
    let normals: Vec<[f32; 3]> = positions.iter().map(|_| p3(b)).collect();
    let _ = wraster::lighting::shade_vertices(
        &normals,
        &m,
        &light,
        |_| Rgb565::new(31, 63, 31),
        &mut outv,
    );
    // `row_range` (binning triangles into bands): no panic; an error only where the draw of the same vertices errs
    // too (it checks x and y as the draw does); otherwise every row the draw writes lies in the range.
    let tri: [Vertex<Rgb565>; 3] = core::array::from_fn(|_| {
        Vertex::new(b.f32(), b.f32(), 1.0 + b.u8() as f32, Rgb565::new(31, 0, 0))
    });
    let mut canvas = Canvas::new(64, 64);
    let mut d = vec![u16::MAX; 64 * 64];
    let drawn = Rasterizer::<Fast>::new(RenderState::new(1.0, 300.0).unwrap()).draw(
        &mut canvas,
        &mut DepthBuffer::new(&mut d, 64, 64).unwrap(),
        &tri,
    );
    match wraster::row_range(&tri) {
        Err(e) => assert!(drawn.is_err(), "row_range {e:?}, draw {drawn:?}"),
        Ok((first, last)) => {
            for j in 0..64 {
                if d[j * 64..(j + 1) * 64].iter().any(|&c| c != u16::MAX) {
                    assert!(
                        first <= j as i32 && j as i32 <= last,
                        "row {j} outside {first}..={last}"
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// fixed_input: FixedVertex with any bits (no panic, errors as documented), and equal to the f32 Vertex where the
// values are equal.

fn fixed_twin<R: wraster::input::Fixed<Bits = u32>>(
    b: &mut Bytes,
) -> (FixedVertex<Rgb565, R>, Vertex<Rgb565>) {
    // x, y: any 16.8 value within the guard band, or any bits at all.
    let mut xy = || {
        let v = b.u32() as i32;
        if b.u8().is_multiple_of(8) {
            v
        } else {
            v % (4096 << 8)
        }
    };
    let (x, y) = (I24F8::from_bits(xy()), I24F8::from_bits(xy()));
    let mut bits = b.u32();
    let full = b.u8().is_multiple_of(4);
    if !full {
        // at most 24 significant bits, so the value is an f32 too
        let sig = 32 - bits.leading_zeros();
        if sig > 24 {
            bits &= !((1u32 << (sig - 24)) - 1);
        }
    }
    let rhw = R::from_bits(bits);
    let c = b.color();
    let f = Vertex {
        x: x.to_bits() as f32 / 256.0,
        y: y.to_bits() as f32 / 256.0,
        z: 0.0,
        rhw: if full {
            f32::NAN
        } else {
            bits as f32 / (2f32).powi(R::FRAC_NBITS as i32)
        },
        color: c,
    };
    (
        FixedVertex {
            x,
            y,
            rhw,
            color: c,
        },
        f,
    )
}

pub fn fixed_input(data: &[u8]) {
    let mut b = Bytes(data);
    match b.u8() % 3 {
        0 => fixed_with::<U1F31>(&mut b),
        1 => fixed_with::<U8F24>(&mut b),
        _ => fixed_with::<U16F16>(&mut b),
    }
}

fn fixed_with<R: wraster::input::Fixed<Bits = u32>>(b: &mut Bytes) {
    let (w, h, _) = dims(b);
    let n = (w as usize) * (h as usize);
    let st = state(b);
    let mut r: Rasterizer = Rasterizer::new(st);
    for _ in 0..1 + b.u8() % 4 {
        let t: [(FixedVertex<Rgb565, R>, Vertex<Rgb565>); 3] =
            [fixed_twin(b), fixed_twin(b), fixed_twin(b)];
        let fx = t.map(|p| p.0);
        let fl = t.map(|p| p.1);
        // Exactness of the twin: x, y below 2^20 in magnitude after the guard check, rhw with <= 24 bits.
        let twin = fl.iter().all(|v| v.rhw.is_finite())
            && fx.iter().all(|v| {
                v.x.to_bits().unsigned_abs() < 1 << 24 && v.y.to_bits().unsigned_abs() < 1 << 24
            });
        let mut ca = Canvas::new(w as u32, h as u32);
        let mut da = Guarded::new(n, 0u16, 0xa5a5);
        DepthBuffer::new(da.inner(), w, h).unwrap().clear();
        let ra = r.draw(
            &mut ca,
            &mut DepthBuffer::new(da.inner(), w, h).unwrap(),
            &fx,
        );
        da.check();
        if let Err(e) = ra {
            assert!(
                matches!(
                    e,
                    Error::OutOfGuardBand
                        | Error::RhwNotPositive
                        | Error::DepthRange
                        | Error::ZWithWFormat
                ),
                "{e:?}"
            );
        }
        let mut pa = Guarded::new(n, 0u16, 0xa5a5);
        DepthBuffer::<Z16>::new_format(pa.inner(), w, h)
            .unwrap()
            .clear_for(&st.range);
        let pra = r.draw(
            &mut ca,
            Some(&mut DepthBuffer::<Z16>::new_format(pa.inner(), w, h).unwrap()),
            &fx,
        );
        pa.check();
        if twin {
            let mut cb = Canvas::new(w as u32, h as u32);
            let mut db = Guarded::new(n, 0u16, 0xa5a5);
            DepthBuffer::new(db.inner(), w, h).unwrap().clear();
            let rb = r.draw(
                &mut cb,
                &mut DepthBuffer::new(db.inner(), w, h).unwrap(),
                &fl,
            );
            assert_eq!(ra, rb, "{fx:?} / {fl:?}");
            let mut pb = Guarded::new(n, 0u16, 0xa5a5);
            DepthBuffer::<Z16>::new_format(pb.inner(), w, h)
                .unwrap()
                .clear_for(&st.range);
            let prb = r.draw(
                &mut cb,
                Some(&mut DepthBuffer::<Z16>::new_format(pb.inner(), w, h).unwrap()),
                &fl,
            );
            assert_eq!(pra, prb);
            assert!(
                ca.same_picture(&cb) && da.data() == db.data() && pa.data() == pb.data(),
                "fixed and f32 differ: {fx:?} / {fl:?}"
            );
        }
    }
}

#[allow(dead_code)]
fn _input_is_sealed<V: VertexInput>() {}
