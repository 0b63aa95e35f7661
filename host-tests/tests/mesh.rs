//! Meshes from world space (`wraster::mesh`), checked against an independent f64 ray caster on W4's eight frames
//! (the rotating torus): the reference rotates the given f32 positions by the given f32 model matrix in f64, takes the
//! workloads' camera (eye depth `W = 3 - z`, 60 degree field of view, 4:3) with an f64 tangent, and casts the ray
//! through each pixel centre against every triangle, nearest hit first.
//!
//! Bounds, derived: a pixel whose centre and four probes 0.75 px around it hit the same nearest triangle must be
//! covered, with that triangle's colour (the depth test picked the visible surface), and its W16 code within
//! `1 + grad / 2048` of the reference's correctly rounded code: 1 LSB for the tiers' contract, plus what the depth
//! planes' positions can be off the true vertices by: half a step of the depth grid (`2^-18` px or less; the planes
//! go through the vertices as given, not the snapped ones) and `|x| * 2^-21` px (the f32 transform and map,
//! `1.5e-4` px at 320 px; see `wraster::clip`), bounded by the reference's code change over 0.75 px (`grad`) divided
//! by 2048 (`3.7e-4` px against the `1.6e-4` px needed: a 2x margin). A code off the correctly rounded one only where
//! the exact value is within the tier's error plus that term of a rounding tie (with the snapped vertices' planes,
//! as before this term existed, the test fails there). A pixel none of whose probes hits must stay empty.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{hash_frame, in_bands, render_torus, with_torus, Frame};
use wraster::clip::Viewport;
use wraster::mesh::{Colors, Mesh, Projected};
use wraster::projection::{Camera, Mat4};
use wraster::recip::{Exact, Fast, FastDiv, FastDivInt, SpanRecip};
use wraster::scenes::{torus, HEIGHT, WIDTH};
use wraster::{DepthBuffer, Error, Rasterizer, RenderState, W16_FAR};

type V3 = [f64; 3];
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Eye depth where the ray with direction `dir` (eye space, `z = 1`) meets triangle `t` (eye space), if inside.
fn cast(t: &[V3; 3], dir: V3) -> Option<f64> {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let den = dot(n, dir);
    if den == 0.0 {
        return None;
    }
    let z = dot(n, t[0]) / den;
    let p = dir.map(|d| d * z);
    let s: Vec<f64> = (0..3)
        .map(|k| dot(n, cross(sub(t[(k + 1) % 3], t[k]), sub(p, t[k]))))
        .collect();
    (s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)).then_some(z)
}

struct Reference {
    /// Eye-space triangles (x right, y up, z = W).
    tris: Vec<[V3; 3]>,
    /// Per pixel: the triangles whose screen box (1 px wider each side) holds it.
    bins: Vec<Vec<u32>>,
    tan: f64,
}

impl Reference {
    fn new(k: usize) -> Reference {
        let m = torus::model(k);
        let pos = torus::positions();
        let eye: Vec<V3> = pos
            .iter()
            .map(|p| {
                let q: Vec<f64> = (0..3)
                    .map(|c| {
                        (0..3).map(|r| p[r] as f64 * m.0[r][c] as f64).sum::<f64>()
                            + m.0[3][c] as f64
                    })
                    .collect();
                [q[0], q[1], 3.0 - q[2]]
            })
            .collect();
        let tan = (std::f64::consts::PI / 6.0).tan();
        let tris: Vec<[V3; 3]> = torus::indices()
            .iter()
            .map(|t| t.map(|i| eye[i as usize]))
            .collect();
        let (w, h) = (WIDTH as usize, HEIGHT as usize);
        let mut bins = vec![Vec::new(); w * h];
        for (id, t) in tris.iter().enumerate() {
            let sx = t.map(|v| 160.0 + 160.0 * v[0] / (v[2] * tan * 4.0 / 3.0));
            let sy = t.map(|v| 120.0 - 120.0 * v[1] / (v[2] * tan));
            let x0 = (sx.iter().cloned().fold(f64::MAX, f64::min) - 1.5)
                .floor()
                .max(0.0) as usize;
            let x1 = (sx.iter().cloned().fold(f64::MIN, f64::max) + 1.5)
                .ceil()
                .min(w as f64) as usize;
            let y0 = (sy.iter().cloned().fold(f64::MAX, f64::min) - 1.5)
                .floor()
                .max(0.0) as usize;
            let y1 = (sy.iter().cloned().fold(f64::MIN, f64::max) + 1.5)
                .ceil()
                .min(h as f64) as usize;
            for y in y0..y1 {
                for x in x0..x1 {
                    bins[y * w + x].push(id as u32);
                }
            }
        }
        Reference { tris, bins, tan }
    }

    /// The nearest triangle and its eye depth at screen point `(sx, sy)`, looked up in pixel `pix`'s bin.
    fn nearest(&self, pix: usize, sx: f64, sy: f64) -> Option<(u32, f64)> {
        let dir = [
            (sx - 160.0) / 160.0 * self.tan * 4.0 / 3.0,
            (120.0 - sy) / 120.0 * self.tan,
            1.0,
        ];
        self.bins[pix]
            .iter()
            .filter_map(|&id| cast(&self.tris[id as usize], dir).map(|z| (id, z)))
            .filter(|&(_, z)| (torus::DEPTH.0 as f64..=torus::DEPTH.1 as f64).contains(&z))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

fn code(z: f64) -> f64 {
    (z / torus::DEPTH.1 as f64 * 65535.0).round()
}

/// Every W4 frame, drawn through the mesh path in 30 bands of 8 rows, against the ray caster.
fn check_frames<R: SpanRecip>() {
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let colors = torus::colors();
    let (mut compared, mut empty, mut over1, mut exact) = (0usize, 0usize, 0usize, 0usize);
    for k in 0..torus::FRAMES {
        let (frame, depth, stats) = render_torus::<R>(k, 8).unwrap();
        let rf = Reference::new(k);
        for py in 0..h {
            for px in 0..w {
                let pix = py * w + px;
                let (cx, cy) = (px as f64 + 0.5, py as f64 + 0.5);
                let probes: Vec<Option<(u32, f64)>> = [
                    (0.0, 0.0),
                    (0.75, 0.0),
                    (-0.75, 0.0),
                    (0.0, 0.75),
                    (0.0, -0.75),
                ]
                .iter()
                .map(|(dx, dy)| rf.nearest(pix, cx + dx, cy + dy))
                .collect();
                if probes.iter().all(|p| p.is_none()) {
                    assert_eq!(
                        frame.writes[pix], 0,
                        "frame {k} ({px},{py}) should be empty"
                    );
                    assert_eq!(depth[pix], W16_FAR);
                    empty += 1;
                    continue;
                }
                let Some((id, z)) = probes[0] else { continue };
                if probes.iter().any(|p| p.map(|q| q.0) != Some(id)) {
                    continue;
                }
                let grad = probes
                    .iter()
                    .map(|p| (code(p.unwrap().1) - code(z)).abs())
                    .fold(0.0, f64::max);
                let bound = 1.0 + grad / 2048.0;
                assert!(
                    frame.writes[pix] > 0,
                    "frame {k} ({px},{py}) should be covered"
                );
                assert_eq!(
                    frame.px[pix], colors[id as usize],
                    "frame {k} ({px},{py}): the visible triangle is {id}"
                );
                let err = (depth[pix] as f64 - code(z)).abs();
                assert!(
                    err <= bound,
                    "frame {k} ({px},{py}): {} vs {} (bound {bound})",
                    depth[pix],
                    code(z)
                );
                // Off the correctly rounded code only where the exact value is within the tier's error
                // (2^-11.1 codes at most) plus the same world term of a rounding tie.
                let e = z / torus::DEPTH.1 as f64 * 65535.0;
                let from_tie = (e - e.floor() - 0.5).abs();
                assert!(
                    err == 0.0 || from_tie <= 2f64.powf(-11.1) + grad / 2048.0,
                    "frame {k} ({px},{py}): {} vs exact {e}, {from_tie} from a tie",
                    depth[pix]
                );
                over1 += usize::from(err > 1.0);
                exact += usize::from(err == 0.0);
                compared += 1;
            }
        }
        assert!(
            stats.culled > 400,
            "frame {k}: about half the torus faces away: {stats:?}"
        );
    }
    println!(
        "{}: {compared} covered pixels compared, {exact} equal to the correctly rounded code ({:.3}%), {over1} over 1 \
         code (within the depth grid's and the f32 transform's term), {empty} empty",
        R::NAME,
        100.0 * exact as f64 / compared as f64
    );
    assert!(compared > 8 * 10_000 && empty > 8 * 40_000);
}

#[test]
fn torus_frames_match_the_f64_ray_caster_fast() {
    check_frames::<Fast>();
}

#[test]
fn torus_frames_match_the_f64_ray_caster_exact() {
    check_frames::<Exact>();
}

#[test]
fn torus_frames_match_the_f64_ray_caster_fast_div_int() {
    check_frames::<FastDivInt>();
}

/// `FastDivInt` (for cores with a divider and no FPU) transforms as `Fast` (the integer transform: the same vertices,
/// bit for bit) and draws as `FastDiv` (the same frame from the same vertices): W4's eight frames, in bands of 8 rows.
/// Its vertices differ from `FastDiv`'s f32 transform somewhere (otherwise this would not tell the two apart).
#[test]
fn fast_div_int_transforms_as_fast_and_draws_as_fast_div() {
    with_torus(fast_div_int_frames);
}

fn fast_div_int_frames(mesh: &Mesh<'_, Rgb565>, cam: &Camera, state: RenderState) {
    let n = mesh.positions.len();
    let vp = Viewport::new(0.0, 0.0, WIDTH as f32, HEIGHT as f32);
    let bits = |v: &[Projected]| -> Vec<[u32; 3]> {
        v.iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.rhw.to_bits()])
            .collect()
    };
    let mut f32_differs = 0;
    for k in 0..torus::FRAMES {
        let m = cam.model_matrix(&torus::model(k));
        let (mut int_div, mut int_fast, mut f32_div) = (
            vec![Projected::default(); n],
            vec![Projected::default(); n],
            vec![Projected::default(); n],
        );
        let mut r = Rasterizer::<FastDivInt>::new(state);
        let mut by_div = Rasterizer::<FastDiv>::new(state);
        Rasterizer::<Fast>::new(state)
            .transform_mesh(mesh, &m, &vp, &mut int_fast)
            .unwrap();
        by_div.transform_mesh(mesh, &m, &vp, &mut f32_div).unwrap();
        let mf = r.transform_mesh(mesh, &m, &vp, &mut int_div).unwrap();
        let draw = |draw: &mut dyn FnMut(
            &mut Frame,
            &mut DepthBuffer<'_>,
        ) -> Result<wraster::Stats, Error>| {
            let mut frame = Frame::new(WIDTH as u32, HEIGHT as u32);
            let mut depth = vec![0u16; WIDTH as usize * HEIGHT as usize];
            let stats =
                in_bands(&mut depth, WIDTH, HEIGHT, 8, |buf| draw(&mut frame, buf)).unwrap();
            (frame, depth, stats.written)
        };
        let a = draw(&mut |f, buf| r.draw_mesh_frame(f, buf, &mf));
        let b = draw(&mut |f, buf| by_div.draw_mesh_frame(f, buf, &mf));
        assert!(a.0 == b.0 && a.1 == b.1 && a.2 == b.2, "frame {k}");
        assert!(a.2 > 10_000, "frame {k}: {} pixels written", a.2);
        assert_eq!(bits(&int_div), bits(&int_fast), "frame {k}");
        f32_differs += bits(&int_div)
            .iter()
            .zip(bits(&f32_div))
            .filter(|(a, b)| **a != *b)
            .count();
    }
    assert!(
        f32_differs > 0,
        "the integer and f32 transforms gave the same vertices"
    );
}

/// A frame drawn in bands (transformed once, binned by rows) equals the frame drawn whole, bit for bit.
#[test]
fn bands_equal_the_whole_frame() {
    for k in [0, 3, 7] {
        let whole = render_torus::<Fast>(k, HEIGHT).unwrap();
        for band in [1, 7, 8, 64] {
            let banded = render_torus::<Fast>(k, band).unwrap();
            assert!(
                whole.0 == banded.0 && whole.1 == banded.1,
                "frame {k}, bands of {band}"
            );
            assert_eq!(whole.2.written, banded.2.written);
        }
        let (mut a, mut b) = (0u64, 0u64);
        hash_frame(&mut a, &whole.0, &whole.1);
        let banded = render_torus::<Fast>(k, 8).unwrap();
        hash_frame(&mut b, &banded.0, &banded.1);
        assert_eq!(a, b);
    }
}

/// Bad mesh input is refused before anything is written: an index beyond the vertices, too few face colours, a
/// short scratch, a NaN position, a NaN in the matrix.
#[test]
fn bad_meshes_are_errors_and_write_nothing() {
    let (pos, idx) = host_tests::cube();
    let cam = host_tests::cube_camera();
    let vp = Viewport::new(0.0, 0.0, 48.0, 48.0);
    let mut frame = Frame::new(48, 48);
    let mut depth = vec![0u16; 48 * 48];
    let mut buf = DepthBuffer::new(&mut depth, 48, 48).unwrap();
    buf.clear();
    let mut r: Rasterizer = Rasterizer::new(cam.render_state().unwrap());
    let mut scratch = [Projected::default(); 8];
    let mut bad_idx = idx;
    bad_idx[5][1] = 8;
    let mut nan_pos = pos;
    nan_pos[3][2] = f32::NAN;
    let faces = [Rgb565::RED; 11];
    let cases: [(Mesh<Rgb565>, Mat4, Error); 4] = [
        (
            Mesh {
                positions: &pos,
                indices: &bad_idx,
                colors: Colors::Uniform(Rgb565::RED),
            },
            cam.matrix(),
            Error::IndexOutOfRange,
        ),
        (
            Mesh {
                positions: &pos,
                indices: &idx,
                colors: Colors::PerFace(&faces),
            },
            cam.matrix(),
            Error::IndexOutOfRange,
        ),
        (
            Mesh {
                positions: &nan_pos,
                indices: &idx,
                colors: Colors::Uniform(Rgb565::RED),
            },
            cam.matrix(),
            Error::NonFinite,
        ),
        (
            Mesh {
                positions: &pos,
                indices: &idx,
                colors: Colors::Uniform(Rgb565::RED),
            },
            Mat4([[f32::NAN; 4]; 4]),
            Error::NonFinite,
        ),
    ];
    for (mesh, m, e) in cases {
        assert_eq!(
            r.draw_mesh(&mut frame, &mut buf, &mesh, &m, &vp, &mut scratch),
            Err(e)
        );
    }
    let ok = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::Uniform(Rgb565::RED),
    };
    assert_eq!(
        r.draw_mesh(
            &mut frame,
            &mut buf,
            &ok,
            &cam.matrix(),
            &vp,
            &mut scratch[..7]
        ),
        Err(Error::BufferSize {
            expected: 8,
            actual: 7
        })
    );
    assert!(frame.writes.iter().all(|&n| n == 0));
    assert!(depth.iter().all(|&d| d == W16_FAR));
}

/// A closed cube with back faces culled covers each pixel at most once, with depth testing off: culling and the
/// shared-edge fill rule leave neither gaps nor double writes. From inside the cube every face is a back face; with
/// culling off, and with the front faces culled (there are none), the walls around the eye (those beside and behind
/// it crossing the eye plane, clipped, whose winding the clip decides before it clips) cover every pixel exactly once.
#[test]
fn a_closed_cube_writes_each_pixel_once_and_draws_from_inside() {
    let (pos, idx) = host_tests::cube();
    let vp = Viewport::new(0.0, 0.0, 64.0, 48.0);
    let eyes = [
        [3.0, 2.0, 5.0],
        [-4.0, -3.0, 2.5],
        [0.2, 0.1, 0.3],
        [-0.6, 0.4, -0.2],
        [0.7, -0.8, 0.5],
    ];
    let inside_culls = [wraster::Cull::None, wraster::Cull::Ccw];
    for (eye, inside_cull) in eyes.iter().flat_map(|e| inside_culls.map(|c| (*e, c))) {
        let cam = Camera::look_at(
            eye,
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            1.2,
            64.0 / 48.0,
            0.1,
            50.0,
        )
        .unwrap();
        let inside = eye.iter().all(|c| c.abs() < 1.0);
        let mut state = cam.render_state().unwrap();
        state.mode = wraster::DepthMode::Off;
        if inside {
            state.cull = inside_cull;
        }
        let mut r: Rasterizer = Rasterizer::new(state);
        let mut frame = Frame::new(64, 48);
        let mut depth = vec![0u16; 64 * 48];
        let mut buf = DepthBuffer::new(&mut depth, 64, 48).unwrap();
        buf.clear();
        let mut scratch = [Projected::default(); 8];
        let mesh = Mesh {
            positions: &pos,
            indices: &idx,
            colors: Colors::Uniform(Rgb565::WHITE),
        };
        let stats = r
            .draw_mesh(
                &mut frame,
                &mut buf,
                &mesh,
                &cam.matrix(),
                &vp,
                &mut scratch,
            )
            .unwrap();
        assert!(
            frame.writes.iter().all(|&n| n <= 1),
            "eye {eye:?}: a pixel written twice"
        );
        let covered = frame.writes.iter().filter(|&&n| n == 1).count();
        if inside {
            assert_eq!(covered, 64 * 48, "eye {eye:?}, {inside_cull:?}: {stats:?}");
        } else {
            assert!(covered > 150 && stats.culled >= 6, "eye {eye:?}: {stats:?}");
        }
    }
}

/// Extreme but finite world coordinates: a ground triangle reaching 1e16 and 1e30 units away draws its visible
/// part (the clip keeps every drawn vertex in the guard band and in front of the near plane); a matrix that takes a
/// vertex beyond f32 is `WorldTooLarge`, with nothing written.
#[test]
fn huge_world_triangles_draw_or_say_what_was_too_large() {
    let cam = Camera::look_at(
        [0.0, 1.0, 0.0],
        [0.0, 1.0, -1.0],
        [0.0, 1.0, 0.0],
        1.2,
        1.0,
        0.5,
        1000.0,
    )
    .unwrap();
    let vp = Viewport::new(0.0, 0.0, 48.0, 48.0);
    for far in [1e3f32, 1e16, 1e30] {
        let t = [[-far, 0.0, 0.5], [far, 0.0, 0.5], [0.0, 0.0, -far]];
        let mut frame = Frame::new(48, 48);
        let mut depth = vec![0u16; 48 * 48];
        let mut buf = DepthBuffer::new(&mut depth, 48, 48).unwrap();
        buf.clear();
        let mut r: Rasterizer = Rasterizer::new(RenderState::new(0.5, 1000.0).unwrap());
        let stats = r
            .draw_world(&mut frame, &mut buf, &cam.matrix(), &vp, &t, Rgb565::GREEN)
            .unwrap_or_else(|e| panic!("{far}: {e}"));
        // the ground fills the lower half of the view (below the horizon at row 24), up to the far plane
        let lower: usize = frame.writes[25 * 48..].iter().filter(|&&n| n > 0).count();
        assert!(
            lower > 20 * 48,
            "{far}: {lower} pixels below the horizon, {stats:?}"
        );
        assert!(
            frame.writes[..23 * 48].iter().all(|&n| n == 0),
            "{far}: nothing above the horizon"
        );
    }
    let t = [[-1.0, 0.0, -5.0], [1.0, 0.0, -5.0], [0.0, 3e38, -5.0]];
    let mut frame = Frame::new(48, 48);
    let mut depth = vec![0u16; 48 * 48];
    let mut buf = DepthBuffer::new(&mut depth, 48, 48).unwrap();
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(0.5, 1000.0).unwrap());
    let m = cam.matrix() * Mat4::scale([10.0; 3]);
    assert_eq!(
        r.draw_world(&mut frame, &mut buf, &m, &vp, &t, Rgb565::GREEN),
        Err(Error::WorldTooLarge)
    );
    assert!(frame.writes.iter().all(|&n| n == 0));
}
