//! Row bins of a transformed mesh frame (`Rasterizer::bin_mesh`): a binned frame drawn in bands of any height gives
//! the pixels, the codes, the fragments and the writes of the same frame unbinned (the bins only leave out triangles
//! a band cannot reach, and keep the triangle order), on W4's eight frames and on random meshes that need clipping,
//! in every cull mode. No tolerance: the frames are compared bit for bit.

use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::{DrawTargetExt, Point};
use host_tests::{in_bands, with_torus, Frame};
use wraster::clip::Viewport;
use wraster::mesh::{Colors, Mesh, Projected};
use wraster::projection::{Camera, Mat4};
use wraster::recip::Fast;
use wraster::scenes::torus;
use wraster::{Cull, DepthBuffer, Error, Rasterizer, RenderState, Stats};

/// What one frame drawn in bands of `band` rows gives: the colours, the codes, the draws' stats, and the binning's
/// cull count (`None` unbinned). Bins with a rasterizer of state `state`, draws with `draw_state`.
struct Drawn {
    frame: Frame,
    depth: Vec<u16>,
    stats: Stats,
    binned_culled: Option<u32>,
}

#[allow(clippy::too_many_arguments)]
fn draw(
    mesh: &Mesh<'_, Rgb565>,
    m: &Mat4,
    state: RenderState,
    draw_state: RenderState,
    (w, h): (u16, u16),
    band: u16,
    binned: bool,
) -> Result<Drawn, Error> {
    let r = Rasterizer::<Fast>::new(state);
    let mut d = Rasterizer::<Fast>::new(draw_state);
    let mut scratch = vec![Projected::default(); mesh.positions.len()];
    let mut bins = vec![0u8; mesh.indices.len()];
    let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
    let mut mf = r.transform_mesh(mesh, m, &vp, &mut scratch)?;
    if binned {
        mf = r.bin_mesh(mf, &mut bins)?;
    }
    let mut frame = Frame::new(w as u32, h as u32);
    let mut depth = vec![0u16; w as usize * h as usize];
    let stats = in_bands(&mut depth, w, h, band, |buf| {
        d.draw_mesh_frame(&mut frame, buf, &mf)
    })?;
    Ok(Drawn {
        frame,
        depth,
        stats,
        binned_culled: mf.binned_culled(),
    })
}

/// Binned and unbinned draws of one frame agree bit for bit in bands of `bands` rows, and in one band the culls add
/// up: the binning's plus the binned draw's (triangles to clip, culled by their clip-space winding) are the unbinned
/// draw's, plus the back faces wholly above or below the frame (the binning culls every triangle on the guard band's
/// screen; a draw tests a triangle's rows first): none when the mesh is `in_view`. Returns the written pixels of the
/// whole-frame draw.
fn same_either_way(
    mesh: &Mesh<'_, Rgb565>,
    m: &Mat4,
    state: RenderState,
    size: (u16, u16),
    bands: &[u16],
    in_view: bool,
) -> u32 {
    let whole = draw(mesh, m, state, state, size, size.1, false).unwrap();
    let whole_binned = draw(mesh, m, state, state, size, size.1, true).unwrap();
    let binned_culls = whole_binned.binned_culled.unwrap() + whole_binned.stats.culled;
    if in_view {
        assert_eq!(whole.stats.culled, binned_culls);
    } else {
        assert!(whole.stats.culled <= binned_culls);
    }
    assert_eq!(whole.binned_culled, None);
    for &band in bands {
        let plain = draw(mesh, m, state, state, size, band, false).unwrap();
        let binned = draw(mesh, m, state, state, size, band, true).unwrap();
        assert!(
            plain.frame == binned.frame && plain.depth == binned.depth,
            "bands of {band}: the binned frame differs"
        );
        assert_eq!(
            (plain.stats.fragments, plain.stats.written),
            (binned.stats.fragments, binned.stats.written),
            "bands of {band}"
        );
        // Banding itself changes nothing either (the existing property, on these meshes too).
        assert!(plain.frame == whole.frame && plain.depth == whole.depth);
    }
    whole.stats.written
}

/// W4's eight frames, in bands of 1, 3, 4 (the Cortex-M0's), 7, 16 (the RP2040's) and 240 rows.
#[test]
fn binned_torus_frames_equal_the_unbinned() {
    with_torus(|mesh, cam, state| {
        for k in 0..torus::FRAMES {
            let m = cam.model_matrix(&torus::model(k));
            let written =
                same_either_way(mesh, &m, state, (320, 240), &[1, 3, 4, 7, 16, 240], true);
            assert!(written > 10_000, "frame {k}: {written} pixels");
        }
    });
}

/// A xorshift64 generator.
fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// Random triangle soups seen from inside and near them, so that some triangles cross the near plane or leave the
/// guard band (the clip path, visited by every band), some lie wholly above or below the screen, and some span it
/// (a large reach); in each cull mode, in bands of 1, 2, 5, 8 and 13 rows.
#[test]
fn binned_soups_with_clipping_equal_the_unbinned() {
    let mut rnd = xorshift(0x853C_49E6_748F_EA9B);
    let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
    let mut clipped_somewhere = false;
    for case in 0..12 {
        let spread = [0.5, 2.0, 8.0][case % 3];
        let pos: Vec<[f32; 3]> = (0..90)
            .map(|_| [0.0; 3].map(|_: f32| (unit() * 2.0 - 1.0) * spread))
            .collect();
        let idx: Vec<[u16; 3]> = (0..120)
            .map(|_| [0; 3].map(|_: u16| (unit() * 90.0) as u16 % 90))
            .collect();
        let col: Vec<Rgb565> = (0..120)
            .map(|i| Rgb565::new((i % 32) as u8, (i * 7 % 64) as u8, (i * 3 % 32) as u8))
            .collect();
        let mesh = Mesh {
            positions: &pos,
            indices: &idx,
            colors: Colors::PerFace(&col),
        };
        let eye = [unit() * 2.0 - 1.0, unit() * 2.0 - 1.0, 1.5 + unit() * 2.0];
        let cam =
            Camera::look_at(eye, [0.0; 3], [0.0, 1.0, 0.0], 1.3, 4.0 / 3.0, 0.3, 40.0).unwrap();
        for cull in [Cull::Cw, Cull::Ccw, Cull::None] {
            let mut state = cam.render_state().unwrap();
            state.cull = cull;
            // A binned draw culls only triangles to clip (by their clip-space winding): some culls there show that
            // the clip path ran.
            let binned = draw(&mesh, &cam.matrix(), state, state, (64, 48), 48, true).unwrap();
            clipped_somewhere |= binned.stats.culled > 0;
            let written = same_either_way(
                &mesh,
                &cam.matrix(),
                state,
                (64, 48),
                &[1, 2, 5, 8, 13],
                false,
            );
            assert!(written > 0, "case {case}: nothing drawn");
        }
    }
    assert!(
        clipped_somewhere,
        "no soup needed the clipper: the test lost its clip path"
    );
}

/// A frame binned for one cull mode and drawn with another walks every triangle as unbinned: the same frame as an
/// unbinned draw in the drawing mode.
#[test]
fn a_draw_that_culls_otherwise_ignores_the_bins() {
    with_torus(|mesh, cam, state| {
        let mut none = state;
        none.cull = Cull::None;
        let m = cam.model_matrix(&torus::model(2));
        for band in [4, 240] {
            let binned_cw = draw(mesh, &m, state, none, (320, 240), band, true).unwrap();
            let plain_none = draw(mesh, &m, none, none, (320, 240), band, false).unwrap();
            assert!(binned_cw.frame == plain_none.frame && binned_cw.depth == plain_none.depth);
            assert_eq!(binned_cw.stats.fragments, plain_none.stats.fragments);
            // Drawing the back faces too changes the frame's fragments (else this test could not tell).
            let plain_cw = draw(mesh, &m, state, state, (320, 240), band, false).unwrap();
            assert!(plain_cw.stats.fragments < plain_none.stats.fragments);
        }
    });
}

/// Bins shorter than the triangles are refused; a mesh wholly off screen bins and draws nothing.
#[test]
fn short_bins_are_an_error_and_an_empty_view_draws_nothing() {
    let (pos, idx) = host_tests::cube();
    let mesh = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::Uniform(Rgb565::new(31, 0, 0)),
    };
    let cam = host_tests::cube_camera();
    let r = Rasterizer::<Fast>::new(cam.render_state().unwrap());
    let vp = Viewport::new(0.0, 0.0, 48.0, 48.0);
    let mut scratch = [Projected::default(); 8];
    let mf = r
        .transform_mesh(&mesh, &cam.matrix(), &vp, &mut scratch)
        .unwrap();
    let mut bins = [0u8; 11];
    assert_eq!(
        r.bin_mesh(mf, &mut bins).err(),
        Some(Error::BufferSize {
            expected: 12,
            actual: 11
        })
    );
    // The cube moved 40 units to the side: outside the view.
    let aside = cam.model_matrix(&Mat4::translation([40.0, 0.0, 0.0]));
    let state = cam.render_state().unwrap();
    for binned in [false, true] {
        let d = draw(&mesh, &aside, state, state, (48, 48), 5, binned).unwrap();
        assert_eq!((d.stats.fragments, d.stats.written), (0, 0));
    }
}

/// A frame whose rows start above row 0 (a viewport and depth bands from row -24), where `as i32` truncation rounds
/// the rows of a triangle up rather than down: binned and unbinned bands of 1 to 5 rows agree on the torus.
#[test]
fn bands_above_row_zero_keep_every_triangle() {
    with_torus(|mesh, cam, state| {
        let (w, h, top) = (160u16, 120u16, -60i32);
        let vp = Viewport::new(0.0, top as f32, w as f32, h as f32);
        for k in [1, 5] {
            let m = cam.model_matrix(&torus::model(k));
            let mut out = Vec::new();
            for binned in [false, true] {
                for band in [1u16, 2, 5] {
                    let r = Rasterizer::<Fast>::new(state);
                    let mut scratch = vec![Projected::default(); mesh.positions.len()];
                    let mut bins = vec![0u8; mesh.indices.len()];
                    let mut mf = r.transform_mesh(mesh, &m, &vp, &mut scratch).unwrap();
                    if binned {
                        mf = r.bin_mesh(mf, &mut bins).unwrap();
                    }
                    let mut d = Rasterizer::<Fast>::new(state);
                    let mut frame = Frame::new(w as u32, h as u32);
                    let mut depth = vec![0u16; w as usize * h as usize];
                    let mut stats = Stats::default();
                    for (i, rows) in depth.chunks_mut(w as usize * band as usize).enumerate() {
                        let bh = (rows.len() / w as usize) as u16;
                        let mut buf =
                            DepthBuffer::band(rows, w, top + (i * band as usize) as i32, bh)
                                .unwrap();
                        buf.clear();
                        let mut target = frame.translated(Point::new(0, -top));
                        stats += d.draw_mesh_frame(&mut target, &mut buf, &mf).unwrap();
                    }
                    out.push((frame, depth, stats.fragments, stats.written));
                }
            }
            assert!(out[0].3 > 1000, "frame {k}: the torus is not in this view");
            for o in &out[1..] {
                assert!(
                    o.0 == out[0].0 && o.1 == out[0].1 && (o.2, o.3) == (out[0].2, out[0].3),
                    "frame {k}"
                );
            }
        }
    });
}
