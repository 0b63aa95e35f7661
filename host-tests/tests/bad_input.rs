//! Bad input gets a clear error, nothing is written, nothing panics.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::Frame;
use wraster::{
    DepthBuffer, DepthRange, DepthStore, Error, Rasterizer, RenderState, Vertex, W16_FAR,
};

fn good() -> [Vertex<Rgb565>; 3] {
    [
        Vertex::new(2.0, 2.0, 20.0, Rgb565::RED),
        Vertex::new(60.0, 5.0, 200.0, Rgb565::RED),
        Vertex::new(10.0, 40.0, 50.0, Rgb565::RED),
    ]
}

/// Draws `tri` and asserts the error and that neither buffer changed.
fn refused(tri: [Vertex<Rgb565>; 3], want: Error) {
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0).unwrap());
    let mut frame = Frame::new(64, 48);
    let mut store = DepthStore::<64, 48>::new();
    let got = r.draw(&mut frame, &mut store.view(), &tri);
    assert_eq!(got, Err(want), "{tri:?}");
    assert!(frame.writes.iter().all(|&n| n == 0));
    assert!(store.view().data().iter().all(|&d| d == W16_FAR));
}

#[test]
fn non_finite_in_every_vertex_field() {
    for k in 0..3 {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for field in 0..4 {
                let mut t = good();
                match field {
                    0 => t[k].x = bad,
                    1 => t[k].y = bad,
                    2 => t[k].z = bad,
                    _ => t[k].rhw = bad,
                }
                refused(t, Error::NonFinite);
            }
        }
    }
}

#[test]
fn rhw_not_positive() {
    for bad in [0.0f32, -0.0, -1.0, -1e-40] {
        let mut t = good();
        t[1].rhw = bad;
        refused(t, Error::RhwNotPositive);
    }
}

#[test]
fn outside_the_guard_band() {
    for bad in [4096.0f32, -4096.0, 1e9, -5000.0] {
        let mut t = good();
        t[2].x = bad;
        refused(t, Error::OutOfGuardBand);
        let mut t = good();
        t[0].y = bad;
        refused(t, Error::OutOfGuardBand);
    }
    // just inside is fine
    let mut t = good();
    t[2].x = 4095.5;
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0).unwrap());
    let mut frame = Frame::new(64, 48);
    let mut store = DepthStore::<64, 48>::new();
    assert!(r.draw(&mut frame, &mut store.view(), &t).is_ok());
}

#[test]
fn vertex_too_near_for_the_range() {
    // rhw * W_far above 2^30: W_far = 1000, W < 1000 / 2^30.
    let mut t = good();
    t[0].rhw = 2.0e6;
    refused(t, Error::DepthRange);
    // denormal rhw is fine (far beyond the far plane: nothing drawn there)
    let mut t = good();
    t[0].rhw = 1e-40;
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0).unwrap());
    let mut frame = Frame::new(64, 48);
    let mut store = DepthStore::<64, 48>::new();
    assert!(r.draw(&mut frame, &mut store.view(), &t).is_ok());
}

#[test]
fn invalid_depth_ranges() {
    assert_eq!(DepthRange::new(10.0, 10.0), Err(Error::InvalidDepthRange));
    assert_eq!(DepthRange::new(10.0, 5.0), Err(Error::InvalidDepthRange));
    assert_eq!(DepthRange::new(0.0, 5.0), Err(Error::InvalidDepthRange));
    assert_eq!(DepthRange::new(-1.0, 5.0), Err(Error::InvalidDepthRange));
    assert_eq!(DepthRange::new(f32::NAN, 5.0), Err(Error::NonFinite));
    assert_eq!(DepthRange::new(1.0, f32::INFINITY), Err(Error::NonFinite));
    // ratio limit 2^30, exact at the boundary
    assert!(DepthRange::new(1.0, (1u64 << 30) as f32).is_ok());
    assert_eq!(
        DepthRange::new(1.0, (1u64 << 30) as f32 * 1.0000001),
        Err(Error::InvalidDepthRange)
    );
    assert!(DepthRange::new(1e-3, 1e5).is_ok());
}

#[test]
fn buffer_of_the_wrong_size() {
    let mut data = vec![0u16; 100];
    assert_eq!(
        DepthBuffer::new(&mut data, 10, 11).unwrap_err(),
        Error::BufferSize {
            expected: 110,
            actual: 100
        }
    );
    assert_eq!(
        DepthBuffer::band(&mut data, 0, 0, 5).unwrap_err(),
        Error::BufferSize {
            expected: 0,
            actual: 100
        }
    );
    assert!(DepthBuffer::new(&mut data, 10, 10).is_ok());
    // An empty buffer is refused whichever side is zero, even though its length (0) then matches.
    let empty: &mut [u16] = &mut [];
    for (w, h) in [(0, 5), (5, 0), (0, 0)] {
        assert_eq!(
            DepthBuffer::new(empty, w, h).unwrap_err(),
            Error::BufferSize {
                expected: 0,
                actual: 0
            },
            "{w} x {h}"
        );
    }
}

/// `DepthBuffer::get` on a band (frame rows 7..10 of a 5-wide frame): every pixel of the band reads its own element,
/// and every pixel around it, in frame coordinates, reads `None`.
#[test]
fn depth_buffer_get_reads_its_band_only() {
    let mut data: Vec<u16> = (100..115).collect();
    let buf = DepthBuffer::band(&mut data, 5, 7, 3).unwrap();
    for y in -2..14 {
        for x in -2..8 {
            let want = ((0..5).contains(&x) && (7..10).contains(&y))
                .then(|| 100 + ((y - 7) * 5 + x) as u16);
            assert_eq!(buf.get(x, y), want, "({x}, {y})");
        }
    }
    assert_eq!(buf.get(0, i32::MIN), None);
    assert_eq!(buf.get(i32::MAX, 7), None);
}

#[test]
fn errors_display() {
    let s = format!(
        "{}",
        Error::BufferSize {
            expected: 110,
            actual: 100
        }
    );
    // The same error for every buffer (depth, colour band, mesh scratch and bins): the message names none of them.
    assert_eq!(s, "buffer has 100 elements, 110 needed");
    let _: &dyn core::error::Error = &Error::NonFinite;
}

/// A band buffer narrower in rows than the triangle: only its rows are touched, and a frame target smaller than
/// the depth buffer's width is never written outside (the Frame panics if it were).
#[test]
fn drawing_is_clipped_to_the_band() {
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0).unwrap());
    let mut frame = Frame::new(64, 48);
    let mut data = vec![W16_FAR; 64 * 5];
    let mut band = DepthBuffer::band(&mut data, 64, 10, 5).unwrap();
    let s = r.draw(&mut frame, &mut band, &good()).unwrap();
    assert!(s.written > 0);
    for (k, &n) in frame.writes.iter().enumerate() {
        let y = k / 64;
        assert!(n == 0 || (10..15).contains(&y));
    }
}

/// A colour target that fails once it has been handed `budget` pixels (before writing the run that exceeds it).
struct Failing {
    inner: host_tests::Frame,
    budget: usize,
}

impl embedded_graphics::prelude::OriginDimensions for Failing {
    fn size(&self) -> embedded_graphics::prelude::Size {
        self.inner.size()
    }
}

impl embedded_graphics::prelude::DrawTarget for Failing {
    type Color = Rgb565;
    type Error = ();
    fn draw_iter<I: IntoIterator<Item = embedded_graphics::Pixel<Rgb565>>>(
        &mut self,
        px: I,
    ) -> Result<(), ()> {
        let px: Vec<_> = px.into_iter().collect();
        if px.len() > self.budget {
            return Err(());
        }
        self.budget -= px.len();
        self.inner.draw_iter(px).map_err(|_| ())
    }
}

/// What a failing colour target leaves behind (the contract `Error::Target` documents): every row above the failing
/// one is drawn completely, colour and depth; in the failing row a prefix of the span has its depth codes (the
/// pixels walked before the failing run was written) and colour only where depth is; no row below is touched.
#[test]
fn a_failing_target_leaves_whole_rows_and_a_prefix() {
    let tri = [
        Vertex::new(3.5, 2.5, 20.0, Rgb565::RED),
        Vertex::new(60.5, 9.5, 900.0, Rgb565::RED),
        Vertex::new(12.5, 40.5, 100.0, Rgb565::RED),
    ];
    let (w, h) = (64u16, 48u16);
    let full = host_tests::render::<wraster::recip::Fast>(
        &[tri],
        RenderState::new(10.0, 1000.0).unwrap(),
        w,
        h,
        h,
    )
    .unwrap();
    for budget in [0, 1, 100, 333, 800] {
        let mut target = Failing {
            inner: host_tests::Frame::new(w as u32, h as u32),
            budget,
        };
        let mut depth = vec![0u16; w as usize * h as usize];
        let mut buf = DepthBuffer::new(&mut depth, w, h).unwrap();
        buf.clear();
        let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0).unwrap());
        assert_eq!(
            r.draw(&mut target, &mut buf, &tri),
            Err(Error::Target),
            "budget {budget}"
        );
        let rows_equal = |j: usize| {
            let s = j * w as usize..(j + 1) * w as usize;
            depth[s.clone()] == full.1[s.clone()] && target.inner.px[s.clone()] == full.0.px[s]
        };
        let jf = (0..h as usize)
            .find(|&j| !rows_equal(j))
            .expect("some row is incomplete");
        for j in jf + 1..h as usize {
            let s = j * w as usize..(j + 1) * w as usize;
            assert!(
                depth[s.clone()].iter().all(|&d| d == W16_FAR),
                "budget {budget}: row {j} touched"
            );
            assert!(target.inner.writes[s].iter().all(|&n| n == 0));
        }
        let row = jf * w as usize;
        let stored: Vec<bool> = (0..w as usize).map(|i| depth[row + i] != W16_FAR).collect();
        let first = stored.iter().position(|&s| s);
        let last = stored.iter().rposition(|&s| s);
        if let (Some(a), Some(b)) = (first, last) {
            assert!(
                stored[a..=b].iter().all(|&s| s),
                "budget {budget}: depth not a prefix"
            );
            for i in a..=b {
                assert_eq!(depth[row + i], full.1[row + i]);
            }
        }
        for (i, &s) in stored.iter().enumerate() {
            if target.inner.writes[row + i] > 0 {
                assert!(s, "budget {budget}: colour without depth at {i}");
            }
        }
        assert_eq!(
            target.inner.writes.iter().sum::<u32>() as usize,
            budget - target.budget,
            "every pixel handed to the target before the failure is in the frame"
        );
    }
}

/// `MAX_T` is the limit the checks apply (a mutation of the constant went unnoticed: nothing compared it with the
/// checks): a far/near ratio of exactly `MAX_T` is accepted and the next f32 above it refused; a vertex's
/// `rhw * W_far` must stay below it (the plane keeps 31 integer bits): just below is accepted, exactly `MAX_T` refused.
#[test]
fn max_t_is_the_limit_the_checks_apply() {
    assert_eq!(wraster::MAX_T, 1073741824.0);
    assert!(DepthRange::new(1.0, wraster::MAX_T).is_ok());
    let above = f32::from_bits(wraster::MAX_T.to_bits() + 1);
    assert_eq!(DepthRange::new(1.0, above), Err(Error::InvalidDepthRange));
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(1.0, 1024.0).unwrap());
    let mut store = DepthStore::<64, 48>::new();
    let v = |rhw: f32| Vertex {
        x: 10.0,
        y: 10.0,
        z: 0.0,
        rhw,
        color: Rgb565::RED,
    };
    let tri = |rhw| {
        [
            v(rhw),
            Vertex { x: 40.0, ..v(0.01) },
            Vertex { y: 40.0, ..v(0.01) },
        ]
    };
    // rhw * W_far just below MAX_T: accepted (that vertex is nearer than W_near, so it is clipped per pixel)
    let below = f32::from_bits(1048576.0f32.to_bits() - 1);
    assert!(r
        .draw(&mut Frame::new(64, 48), &mut store.view(), &tri(below))
        .is_ok());
    assert_eq!(
        r.draw(&mut Frame::new(64, 48), &mut store.view(), &tri(1048576.0)),
        Err(Error::DepthRange)
    );
}

/// A band may start at any row `y0` (`DepthBuffer::band`, `band_format` take any `i32`): bands at the ends of the
/// `i32` range, where `y0 + height` would overflow, draw nothing and do not panic, through the triangle paths (small
/// and general), a packed format's triangles, lines and points, a world triangle and a mesh frame binned and not.
#[test]
fn bands_at_the_ends_of_the_row_range_draw_nothing() {
    use wraster::clip::Viewport;
    use wraster::format::W24F;
    use wraster::mesh::{Colors, Mesh, Projected};
    use wraster::DepthBuffer;
    let cam = host_tests::cube_camera();
    let (pos, idx) = host_tests::cube();
    let mesh = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::Uniform(Rgb565::RED),
    };
    let big = [
        Vertex::new(-500.0, -500.0, 20.0, Rgb565::RED),
        Vertex::new(900.0, -400.0, 200.0, Rgb565::RED),
        Vertex::new(10.0, 900.0, 50.0, Rgb565::RED),
    ];
    for y0 in [
        i32::MIN,
        i32::MIN + 5,
        -(1 << 30),
        1 << 30,
        i32::MAX - 5,
        i32::MAX,
    ] {
        let mut r: Rasterizer = Rasterizer::new(cam.render_state().unwrap());
        let mut frame = Frame::new(64, 48);
        let mut data = vec![W16_FAR; 64 * 8];
        let mut band = DepthBuffer::band(&mut data, 64, y0, 8).unwrap();
        for tri in [good(), big] {
            assert_eq!(
                r.draw(&mut frame, &mut band, &tri).unwrap().written,
                0,
                "y0 {y0}"
            );
        }
        let m = cam.matrix();
        let vp = Viewport::new(0.0, 0.0, 64.0, 48.0);
        let world = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
        assert_eq!(
            r.draw_world(&mut frame, &mut band, &m, &vp, &world, Rgb565::RED)
                .unwrap()
                .written,
            0
        );
        let mut scratch = [Projected::default(); 8];
        let mut bins = [0u8; 12];
        let mf = r.transform_mesh(&mesh, &m, &vp, &mut scratch).unwrap();
        assert_eq!(
            r.draw_mesh_frame(&mut frame, &mut band, &mf)
                .unwrap()
                .written,
            0
        );
        let mf = r.bin_mesh(mf, &mut bins).unwrap();
        assert_eq!(
            r.draw_mesh_frame(&mut frame, &mut band, &mf)
                .unwrap()
                .written,
            0
        );
        let mut bytes = vec![[0u8; 3]; 64 * 8];
        let mut packed = DepthBuffer::<W24F>::band_format(&mut bytes, 64, y0, 8).unwrap();
        for tri in [good(), big] {
            let s = r.draw(&mut frame, Some(&mut packed), &tri).unwrap();
            assert_eq!(s.written, 0, "y0 {y0}");
        }
        let line = [good()[0], good()[2]];
        assert_eq!(
            r.draw_line(&mut frame, Some(&mut packed), &line)
                .unwrap()
                .written,
            0
        );
        assert_eq!(
            r.draw_point(&mut frame, Some(&mut packed), &good()[1])
                .unwrap()
                .written,
            0
        );
        assert!(frame.writes.iter().all(|&n| n == 0));
    }
}
