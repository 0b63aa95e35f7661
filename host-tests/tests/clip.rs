//! World-space triangles through the projection, near-plane clipping and the viewport, checked against an
//! independent f64 ray caster: for every pixel whose centre is unambiguously inside or outside (the same answer
//! 0.75 px around it, so the 1/512 px vertex snap and f32 clip vertices cannot change it) coverage must agree, and
//! the stored W16 code must be within 1 LSB plus what the depth grid (`2^-18` px or finer: the depth planes go through
//! the vertices as given) and the f32 clip and map (`|x| 2^-21` px) can move the depth there (bounded by the
//! reference's code gradient over 0.75 px, divided by 2048 to reach `3.7e-4` px, a 2x margin).
//! Triangles crossing the near plane and lying partly behind the eye are the peers' most reported bug
//! ("flashing" or deforming near the camera): a sequence of frames moves one through the near plane and past the eye.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::Frame;
use wraster::clip::Viewport;
use wraster::mesh::{Colors, Mesh, Projected};
use wraster::projection::{is_w_friendly, Mat4};
use wraster::{DepthBuffer, Rasterizer, RenderState, W16_FAR};

const W: u16 = 96;
const H: u16 = 72;
const NEAR: f64 = 1.0;
const FAR: f64 = 400.0;
/// cot(fov/2) for a 90 degree field of view.
const S: f64 = 1.0;
const ASPECT: f64 = W as f64 / H as f64;

/// A W-friendly projection (fourth column [0, 0, 1, 0]: w = eye z).
fn projection() -> Mat4 {
    projection_near(NEAR)
}

/// [`projection`] with its near plane at `near`.
fn projection_near(near: f64) -> Mat4 {
    let q = FAR / (FAR - near);
    Mat4([
        [(S / ASPECT) as f32, 0.0, 0.0, 0.0],
        [0.0, S as f32, 0.0, 0.0],
        [0.0, 0.0, q as f32, 1.0],
        [0.0, 0.0, (-q * near) as f32, 0.0],
    ])
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The eye depth where the ray through screen point (sx, sy) meets the triangle, if inside it and in [near, FAR].
fn cast(t: &[[f64; 3]; 3], sx: f64, sy: f64, near: f64) -> Option<f64> {
    let xn = sx / (W as f64 / 2.0) - 1.0;
    let yn = 1.0 - sy / (H as f64 / 2.0);
    let dir = [xn * ASPECT / S, yn / S, 1.0];
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let den = dot(n, dir);
    if den == 0.0 {
        return None;
    }
    let z = dot(n, t[0]) / den;
    if !(near..=FAR).contains(&z) {
        return None;
    }
    let p = [dir[0] * z, dir[1] * z, dir[2] * z];
    let s: Vec<f64> = (0..3)
        .map(|k| dot(n, cross(sub(t[(k + 1) % 3], t[k]), sub(p, t[k]))))
        .collect();
    (s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)).then_some(z)
}

/// The distance from screen point (sx, sy) to the triangle projected in f64 (0 inside), for a triangle wholly in front
/// of the near plane (`None` otherwise): a screen-thin sliver can pass between the axis probes.
fn projected_distance(t: &[[f64; 3]; 3], sx: f64, sy: f64, near: f64) -> Option<f64> {
    if t.iter().any(|v| v[2] <= near) {
        return None;
    }
    let p = t.map(|v| {
        (
            W as f64 / 2.0 * (1.0 + v[0] * S / ASPECT / v[2]),
            H as f64 / 2.0 * (1.0 - v[1] * S / v[2]),
        )
    });
    let e = |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) * (sy - a.1) - (b.1 - a.1) * (sx - a.0);
    let s = [e(p[0], p[1]), e(p[1], p[2]), e(p[2], p[0])];
    if s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0) {
        return Some(0.0);
    }
    let seg = |a: (f64, f64), b: (f64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let l = dx * dx + dy * dy;
        let u = if l > 0.0 {
            (((sx - a.0) * dx + (sy - a.1) * dy) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ((a.0 + u * dx - sx).powi(2) + (a.1 + u * dy - sy).powi(2)).sqrt()
    };
    Some(seg(p[0], p[1]).min(seg(p[1], p[2])).min(seg(p[2], p[0])))
}

fn code(z: f64) -> f64 {
    (z / FAR * 65535.0).round()
}

/// Draws `t` and compares it with the ray caster; returns (pixels drawn, pixels compared).
fn check(t: [[f32; 3]; 3]) -> (usize, usize) {
    let (drawn, compared, _, _) = check_near(t, NEAR);
    (drawn, compared)
}

/// [`check`] with the near plane at `near`; also returns how many covered pixels were compared and how many of them
/// hold the correctly rounded code. The triangle is drawn twice, each checked on its own: by `draw_world` (the f32
/// transform and clip), and as a one-triangle mesh by `draw_mesh` with the default strategy, whose vertices in front
/// of the near plane and inside the guard band take the integer transform (`wraster::recip::SpanRecip::
/// INTEGER_TRANSFORM`; its error is inside the f32 path's, so the same bounds apply) and whose others the f32 clip.
fn check_near(t: [[f32; 3]; 3], near: f64) -> (usize, usize, usize, usize) {
    let m = projection_near(near);
    assert!(is_w_friendly(&m));
    let vp = Viewport::new(0.0, 0.0, W as f32, H as f32);
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(near as f32, FAR as f32).unwrap());
    let mut world = (
        Frame::new(W as u32, H as u32),
        vec![0u16; W as usize * H as usize],
    );
    let mut buf = DepthBuffer::new(&mut world.1, W, H).unwrap();
    buf.clear();
    r.draw_world(&mut world.0, &mut buf, &m, &vp, &t, Rgb565::WHITE)
        .unwrap();
    let mut mesh = (
        Frame::new(W as u32, H as u32),
        vec![0u16; W as usize * H as usize],
    );
    let mut buf = DepthBuffer::new(&mut mesh.1, W, H).unwrap();
    buf.clear();
    let one = Mesh {
        positions: &t,
        indices: &[[0, 1, 2]],
        colors: Colors::Uniform(Rgb565::WHITE),
    };
    let mut scratch = [Projected::default(); 3];
    r.draw_mesh(&mut mesh.0, &mut buf, &one, &m, &vp, &mut scratch)
        .unwrap();
    let a = compare(t, near, &world.0, &world.1);
    let b = compare(t, near, &mesh.0, &mesh.1);
    (a.0 + b.0, a.1 + b.1, a.2 + b.2, a.3 + b.3)
}

/// One drawn frame of `t` against the ray caster: (pixels drawn, compared, covered and compared, exact).
fn compare(
    t: [[f32; 3]; 3],
    near: f64,
    frame: &Frame,
    depth: &[u16],
) -> (usize, usize, usize, usize) {
    let tf = t.map(|v| v.map(|c| c as f64));
    let (mut drawn, mut compared, mut exact, mut covered) = (0, 0, 0, 0);
    for py in 0..H as usize {
        for px in 0..W as usize {
            let (cx, cy) = (px as f64 + 0.5, py as f64 + 0.5);
            let probes: Vec<Option<f64>> = [
                (0.0, 0.0),
                (0.75, 0.0),
                (-0.75, 0.0),
                (0.0, 0.75),
                (0.0, -0.75),
            ]
            .iter()
            .map(|(dx, dy)| cast(&tf, cx + dx, cy + dy, near))
            .collect();
            let stored = depth[py * W as usize + px];
            drawn += usize::from(stored != W16_FAR || frame.writes[py * W as usize + px] > 0);
            if probes.iter().all(|p| p.is_some()) {
                let z = probes[0].unwrap();
                let grad = probes
                    .iter()
                    .map(|p| (code(p.unwrap()) - code(z)).abs())
                    .fold(0.0, f64::max);
                let bound = 1.0 + grad / 2048.0;
                assert!(
                    frame.writes[py * W as usize + px] == 1,
                    "pixel ({px},{py}) should be covered: {t:?}"
                );
                assert!(
                    (stored as f64 - code(z)).abs() <= bound,
                    "({px},{py}): {stored} vs {} (bound {bound}) {t:?}",
                    code(z)
                );
                // Off the correctly rounded code only where the exact value is within the fast tier's error
                // (2^-11.1 codes) plus the same world term of a rounding tie.
                let e = z / FAR * 65535.0;
                assert!(
                    stored as f64 == code(z)
                        || (e - e.floor() - 0.5).abs() <= 2f64.powf(-11.1) + grad / 2048.0,
                    "({px},{py}): {stored} vs exact {e} {t:?}"
                );
                exact += usize::from(stored as f64 == code(z));
                covered += 1;
                compared += 1;
            } else if probes.iter().all(|p| p.is_none())
                && [(0.01, 0.0), (-0.01, 0.0), (0.0, 0.01), (0.0, -0.01)]
                    .iter()
                    .all(|(dx, dy)| cast(&tf, cx + dx, cy + dy, near).is_none())
                && projected_distance(&tf, cx, cy, near).is_none_or(|d| d > 0.01)
            {
                // Empty only if the centre is also more than 0.01 px from the triangle on each axis: the f32 path
                // places an edge within 2e-3 px (at the guard band; `Planes`' error note), so a centre closer than
                // that to an edge (a sliver's vertex, where the other probes all miss) may go either way.
                assert_eq!(
                    frame.writes[py * W as usize + px],
                    0,
                    "pixel ({px},{py}) should be empty: {t:?}"
                );
                compared += 1;
            }
        }
    }
    (drawn, compared, covered, exact)
}

#[test]
fn a_triangle_moving_through_the_near_plane_and_past_the_eye() {
    let mut crossing_frames = 0;
    for k in 0..120 {
        let z = 6.0 - k as f32 * 0.1; // from 6 in front to 6 behind the eye
        let t = [[-4.0, -1.5, z], [4.0, -1.0, z + 3.0], [0.5, 3.0, z + 1.5]];
        let (drawn, compared) = check(t);
        assert!(
            compared > (W as usize * H as usize) / 2,
            "frame {k}: too few unambiguous pixels"
        );
        let crosses =
            t.iter().any(|v| (v[2] as f64) < NEAR) && t.iter().any(|v| (v[2] as f64) > NEAR);
        if crosses && drawn > 0 {
            crossing_frames += 1;
        }
    }
    assert!(
        crossing_frames >= 10,
        "{crossing_frames} frames exercised the near-plane clip"
    );
}

#[test]
fn a_ground_plane_from_behind_the_eye_to_beyond_the_far_plane() {
    for (k, y) in [-2.0f32, -0.5, -0.05].into_iter().enumerate() {
        let t = [[-300.0, y, -50.0], [300.0, y, -50.0], [0.0, y, 800.0]];
        let (drawn, _) = check(t);
        assert!(drawn > 100, "case {k}: {drawn}");
    }
}

/// Random world triangles as a scene hands them over: ground and wall planes seen at grazing angles, triangles
/// crossing the near plane or reaching behind the eye, some beyond the far plane; 1,200 of them, each drawn alone
/// through `draw_world` and held to the ray caster by [`check_near`]'s derived bounds (the depth grid's and the f32
/// transform's term, `grad / 2048`, on top of 1 LSB, and off the correctly rounded code only that close to a tie).
/// Prints the share of compared pixels holding the correctly rounded code of the true surface.
#[test]
fn random_world_triangles_against_the_true_surface() {
    let mut rng = host_tests::Rng(1150);
    let (mut covered, mut exact, mut drawn) = (0usize, 0usize, 0usize);
    for k in 0..1200 {
        let c = |rng: &mut host_tests::Rng, lo: f64, hi: f64| rng.f(lo, hi) as f32;
        let t = match k % 3 {
            // A grazing ground or ceiling patch from near the eye to beyond the far plane.
            0 => {
                let y = c(&mut rng, -3.0, 3.0);
                let (z0, z1) = (c(&mut rng, -2.0, 20.0), c(&mut rng, 20.0, 600.0));
                [
                    [c(&mut rng, -40.0, 40.0), y, z0],
                    [c(&mut rng, -40.0, 40.0), y + c(&mut rng, -0.2, 0.2), z1],
                    [
                        c(&mut rng, -40.0, 40.0),
                        y,
                        c(&mut rng, z0 as f64, z1 as f64),
                    ],
                ]
            }
            // A wall at a grazing angle.
            1 => {
                let x = c(&mut rng, -3.0, 3.0);
                let (z0, z1) = (c(&mut rng, 0.5, 10.0), c(&mut rng, 10.0, 450.0));
                [
                    [x, c(&mut rng, -20.0, 20.0), z0],
                    [x + c(&mut rng, -0.5, 0.5), c(&mut rng, -20.0, 20.0), z1],
                    [
                        x,
                        c(&mut rng, -20.0, 20.0),
                        c(&mut rng, z0 as f64, z1 as f64),
                    ],
                ]
            }
            // Anything in and around the frustum, behind the eye included.
            _ => [0, 1, 2].map(|_| {
                let z = c(&mut rng, -5.0, 60.0);
                [
                    c(&mut rng, -1.5, 1.5) * z.abs().max(1.0),
                    c(&mut rng, -1.2, 1.2) * z.abs().max(1.0),
                    z,
                ]
            }),
        };
        let (d, _, n, e) = check_near(t, NEAR);
        drawn += d;
        covered += n;
        exact += e;
    }
    println!(
        "random world triangles: {drawn} px drawn, {covered} compared, {exact} equal to the correctly rounded code \
         of the true surface ({:.4}%)",
        100.0 * exact as f64 / covered as f64
    );
    assert!(covered > 100_000);
}

/// One vertex far beyond each guard-band plane in turn (and beyond two at a corner), in front of the near plane, so
/// only that plane clips it. At eye depth `w` a point maps to `(48 + 36 x / w, 36 - 36 y / w)` px; at `w = 2`,
/// `(-3000, 150)` maps to `(-53952, -2664)`, 13 times beyond the 4000 px band on one axis and inside it on the other,
/// so a missing plane would leave the vertex to the rasterizer's clamp and turn the edges towards it (slope 0.66
/// instead of 0.05 here). The same scene a tenth the size (near plane 0.1, `w = 0.2`) puts the planes' `k w` far
/// from any `k + w`. Each clipped wedge must cover the frame as the ray caster's triangle does.
#[test]
fn triangles_beyond_each_guard_band_plane_are_clipped_there() {
    let far = [
        (-3000.0f32, 150.0f32),
        (3000.0, -150.0),
        (150.0, 3000.0),
        (-150.0, -3000.0),
        (-3000.0, 3000.0),
        (3000.0, -3000.0),
    ];
    for scale in [1.0f32, 0.1] {
        for (k, (x, y)) in far.into_iter().enumerate() {
            // One vertex beyond the plane, then two (the second as far, across the frame from the first); each
            // in every position of the triangle, so the plane must be found from any vertex's outcode and from two
            // vertices sharing it.
            let one = [[x, y, 2.0], [1.0, -1.0, 2.5], [-0.5, 1.5, 3.0]];
            let two = [[x, y, 2.0], [-y, x, 2.2], [-0.5, 1.5, 3.0]];
            for (n, t) in [one, two].into_iter().enumerate() {
                for rot in 0..3 {
                    let t =
                        [t[rot], t[(rot + 1) % 3], t[(rot + 2) % 3]].map(|v| v.map(|c| c * scale));
                    let (drawn, compared, _, _) = check_near(t, NEAR * scale as f64);
                    assert!(
                        drawn > 100 && compared > W as usize * H as usize / 2,
                        "case {k}, {} beyond, rotated {rot}, at scale {scale}: {drawn} drawn, {compared} compared",
                        n + 1
                    );
                }
            }
        }
    }
}

#[test]
fn bad_world_input_is_an_error_and_writes_nothing() {
    let m = projection();
    let vp = Viewport::new(0.0, 0.0, W as f32, H as f32);
    let mut frame = Frame::new(W as u32, H as u32);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
    buf.clear();
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(1.0, 100.0).unwrap());
    for bad in [f32::NAN, f32::INFINITY] {
        let t = [[0.0, 0.0, 5.0], [1.0, bad, 5.0], [0.0, 1.0, 5.0]];
        assert_eq!(
            r.draw_world(&mut frame, &mut buf, &m, &vp, &t, Rgb565::RED),
            Err(wraster::Error::NonFinite)
        );
    }
    assert!(frame.writes.iter().all(|&n| n == 0));
}

/// World space into any format: a W16 buffer given directly or as an `Option` draws the same pixels and codes, for
/// triangles crossing the near plane and lying partly behind the eye, and the Z formats get the same coverage.
#[test]
fn world_triangles_into_any_format() {
    use wraster::format::{W16, Z16};
    use wraster::recip::{DefaultRecip, PerPixel};
    use wraster::DepthBuffer;
    let m = projection();
    let vp = Viewport::new(0.0, 0.0, W as f32, H as f32);
    let tris = [
        [[-3.0, -1.0, 0.3], [3.0, -1.0, 0.3], [0.0, 2.0, 80.0]],
        [
            [-30.0, -2.0, -20.0],
            [30.0, -2.0, -20.0],
            [0.0, -2.0, 300.0],
        ],
        [[-2.0, 1.0, 5.0], [2.5, -1.5, 20.0], [1.0, 3.0, 10.0]],
    ];
    for t in tris {
        let state = RenderState::new(NEAR as f32, FAR as f32).unwrap();
        let mut lean_frame = Frame::new(W as u32, H as u32);
        let mut depth = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        let mut r: Rasterizer<PerPixel<DefaultRecip>> = Rasterizer::new(state);
        let a = r
            .draw_world(&mut lean_frame, &mut buf, &m, &vp, &t, Rgb565::WHITE)
            .unwrap();
        // The same buffer type given as an `Option` takes the same loop.
        let mut frame = Frame::new(W as u32, H as u32);
        let mut words = vec![0u16; W as usize * H as usize];
        let mut pbuf = DepthBuffer::<W16>::new_format(&mut words, W, H).unwrap();
        pbuf.clear_for(&state.range);
        let b = r
            .draw_world(&mut frame, Some(&mut pbuf), &m, &vp, &t, Rgb565::WHITE)
            .unwrap();
        assert_eq!(a, b);
        assert!(a.written > 100);
        assert!(frame == lean_frame);
        assert!(depth == words);
        let mut zstate = state;
        zstate.mode = wraster::DepthMode::Z;
        let mut rz: Rasterizer<PerPixel<DefaultRecip>> = Rasterizer::new(zstate);
        let mut zframe = Frame::new(W as u32, H as u32);
        let mut zwords = vec![0u16; W as usize * H as usize];
        let mut zbuf = DepthBuffer::<Z16>::new_format(&mut zwords, W, H).unwrap();
        zbuf.clear_for(&state.range);
        let c = rz
            .draw_world(&mut zframe, Some(&mut zbuf), &m, &vp, &t, Rgb565::WHITE)
            .unwrap();
        assert_eq!(c.written, a.written);
    }
}

/// D3DVIEWPORT2's clip rectangle: with the clip rectangle `(-0.5, 0.5, 1, 1)` (the middle half of the projected
/// square) a vertex lands at `X + W/2 + W x/w`, exactly where the default viewport puts the vertex with x and y doubled
/// (`X + (2x/w + 1) W/2`): the two frames are equal pixel for pixel. A zero-sized clip rectangle is refused.
#[test]
fn viewport_clip_rectangle_magnifies() {
    let m = projection();
    let full = Viewport::new(0.0, 0.0, W as f32, H as f32);
    let zoom = Viewport {
        clip_x: -0.5,
        clip_y: 0.5,
        clip_width: 1.0,
        clip_height: 1.0,
        ..full
    };
    let t = [[-2.5, -1.25, 10.0], [2.5, -1.25, 10.0], [0.0, 1.75, 10.0]];
    let doubled = t.map(|[x, y, z]| [2.0 * x, 2.0 * y, z]);
    let draw = |vp: &Viewport, t: &[[f32; 3]; 3]| {
        let mut frame = Frame::new(W as u32, H as u32);
        let mut depth = vec![0u16; W as usize * H as usize];
        let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
        buf.clear();
        let mut r: Rasterizer = Rasterizer::new(RenderState::new(NEAR as f32, FAR as f32).unwrap());
        r.draw_world(&mut frame, &mut buf, &m, vp, t, Rgb565::WHITE)
            .unwrap();
        (frame, depth)
    };
    let (a, b) = (draw(&zoom, &t), draw(&full, &doubled));
    let n = a.0.writes.iter().filter(|&&w| w > 0).count();
    println!(
        "clip rectangle: {n} px, same as the doubled triangle: {}",
        a == b
    );
    assert!(n > 300 && a == b);
    let bad = Viewport {
        clip_width: 0.0,
        ..full
    };
    let mut frame = Frame::new(W as u32, H as u32);
    let mut depth = vec![0u16; W as usize * H as usize];
    let mut buf = DepthBuffer::new(&mut depth, W, H).unwrap();
    let mut r: Rasterizer = Rasterizer::new(RenderState::new(NEAR as f32, FAR as f32).unwrap());
    assert!(r
        .draw_world(&mut frame, &mut buf, &m, &bad, &t, Rgb565::WHITE)
        .is_err());
}
