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
    assert!(s.contains("110") && s.contains("100"));
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
