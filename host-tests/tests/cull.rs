//! The bounding-sphere cull (`wraster::mesh::Sphere`): the sphere holds its mesh, and a mesh the cull rejects draws
//! nothing, while one far enough outside a plane is rejected (the test is not `true` everywhere).

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use embedded_graphics::prelude::Size;
use host_tests::Frame;
use wraster::clip::Viewport;
use wraster::mesh::{Colors, Mesh, Projected, Sphere};
use wraster::projection::{Camera, Mat4};
use wraster::scenes::torus;
use wraster::{DepthBuffer, Error, Rasterizer};

fn xorshift(mut s: u64) -> impl FnMut() -> f64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Every position lies inside its sphere, in f64 (the radius is rounded up: `Sphere::enclosing`), for the torus,
/// the cube and random clouds of every scale from 1e-20 to 1e30; bad input is an error.
#[test]
fn the_sphere_holds_every_position() {
    let mut rnd = xorshift(0x5EED_0001);
    let mut clouds = vec![torus::positions().to_vec(), host_tests::cube().0.to_vec()];
    for k in 0..200 {
        let scale = 10f64.powf(-20.0 + 50.0 * (k as f64 / 199.0));
        let off = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5].map(|v| v * scale * 4.0);
        let n = 1 + (rnd() * 60.0) as usize;
        clouds.push(
            (0..n)
                .map(|_| [0, 1, 2].map(|i| (off[i] + (rnd() - 0.5) * scale) as f32))
                .collect(),
        );
    }
    for pos in &clouds {
        let s = Sphere::enclosing(pos).unwrap();
        let c = s.center.map(|v| v as f64);
        for p in pos {
            let d2: f64 = (0..3).map(|i| (p[i] as f64 - c[i]).powi(2)).sum();
            assert!(
                d2.sqrt() <= s.radius as f64,
                "{p:?} outside {s:?} by {}",
                d2.sqrt() - s.radius as f64
            );
        }
    }
    assert_eq!(
        Sphere::enclosing(&[[0.0, f32::NAN, 0.0]]),
        Err(Error::NonFinite)
    );
    assert_eq!(
        Sphere::enclosing(&[]).unwrap(),
        Sphere {
            center: [0.0; 3],
            radius: 0.0
        }
    );
}

/// The torus moved to random places around the view (beside each screen edge, behind the eye, in front of the
/// near plane, beyond the far plane, and through all of them), drawn whole with the mesh path: wherever the cull
/// says it cannot be seen, the draw writes no pixel. And wherever the exact (f64) sphere lies outside a plane by more
/// than 1e-3 of its radius, the cull says so: the cull has a margin of `2^-16` of its terms (see `Sphere::visible`),
/// far below that. Also with a viewport smaller than the target (the draw writes outside the viewport through the
/// guard band, so the cull must allow for the whole target).
#[test]
fn a_culled_mesh_draws_nothing_and_a_far_outside_one_is_culled() {
    let (pos, idx) = (torus::positions(), torus::indices());
    let mesh = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::Uniform(Rgb565::WHITE),
    };
    let sphere = Sphere::enclosing(&pos).unwrap();
    let mut rnd = xorshift(0x5EED_0002);
    let (w, h) = (80u32, 60u32);
    let (mut culled, mut drawn, mut must) = (0, 0, 0);
    for k in 0..1500 {
        let cam = Camera::look_at(
            [0.0, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.0, 1.0, 0.0],
            1.0,
            w as f32 / h as f32,
            0.5,
            20.0,
        )
        .unwrap();
        // Eye at the origin looking down -z: place the torus anywhere in a box around the frustum.
        let t = [
            (rnd() - 0.5) * 40.0,
            (rnd() - 0.5) * 30.0,
            -(rnd() * 30.0 - 4.0),
        ];
        let a = (rnd() * 6.0) as f32;
        let model = Mat4::rotation_x(a) * Mat4::translation(t.map(|v| v as f32));
        let m = cam.model_matrix(&model);
        let vp = if k % 3 == 0 {
            Viewport::new(20.0, 15.0, 40.0, 30.0)
        } else {
            Viewport::new(0.0, 0.0, w as f32, h as f32)
        };
        let mut state = cam.render_state().unwrap();
        state.cull = wraster::Cull::None;
        // The depth test on and off, with three comparisons: the cull holds for each.
        state.mode = [wraster::DepthMode::W, wraster::DepthMode::Off][k % 2];
        state.compare = [
            wraster::Compare::Less,
            wraster::Compare::Always,
            wraster::Compare::Greater,
        ][(k / 3) % 3];
        let visible = sphere.visible(&m, &vp, Size::new(w, h), &state.range);
        let mut r: Rasterizer = Rasterizer::new(state);
        let mut frame = Frame::new(w, h);
        let mut depth = vec![0u16; (w * h) as usize];
        let mut buf = DepthBuffer::new(&mut depth, w as u16, h as u16).unwrap();
        buf.clear();
        let mut scratch = vec![Projected::default(); pos.len()];
        let stats = r
            .draw_mesh(&mut frame, &mut buf, &mesh, &m, &vp, &mut scratch)
            .unwrap();
        if !visible {
            culled += 1;
            assert_eq!(stats.written, 0, "culled at {t:?} but drew {stats:?}");
        } else if stats.written > 0 {
            drawn += 1;
        }
        // The exact test in f64: the sphere's centre in eye space (model then view; the camera sits at the origin
        // looking down -z, so eye depth is -z), against the frustum's planes.
        let c = sphere.center.map(|v| v as f64);
        let (ca, sa) = ((a as f64).cos(), (a as f64).sin());
        // Mat4 uses row vectors: p * rotation_x(a) * translation(t).
        let rc = [c[0], c[1] * ca - c[2] * sa, c[1] * sa + c[2] * ca];
        let e = [rc[0] + t[0], rc[1] + t[1], rc[2] + t[2]];
        let depth_eye = -e[2];
        let r0 = sphere.radius as f64 * (1.0 + 1e-3);
        let (sx, sy, ox, oy) = if k % 3 == 0 {
            (20.0, 15.0, 40.0, 30.0)
        } else {
            (
                w as f64 / 2.0,
                h as f64 / 2.0,
                w as f64 / 2.0,
                h as f64 / 2.0,
            )
        };
        // Screen x = ox + sx * cot * x / (aspect W): each edge plane through the eye, unit normals.
        let cot = 1.0 / (0.5f64).tan();
        let aspect = w as f64 / h as f64;
        let (fx, fy) = (sx * cot / aspect, sy * cot);
        let plane = |nx: f64, ny: f64, nz: f64| {
            let n = (nx * nx + ny * ny + nz * nz).sqrt();
            (nx * e[0] + ny * e[1] + nz * depth_eye) / n
        };
        let outside = [
            plane(fx, 0.0, ox),             // screen x >= 0
            plane(-fx, 0.0, w as f64 - ox), // screen x <= w
            plane(0.0, -fy, oy),            // screen y >= 0 (y up in eye space is down on screen)
            plane(0.0, fy, h as f64 - oy),  // screen y <= h
            depth_eye - 0.5,
            20.0 - depth_eye,
        ]
        .iter()
        .any(|&d| d < -r0);
        if outside {
            must += 1;
            assert!(
                !visible,
                "{t:?}: the exact sphere is outside, the cull kept it"
            );
        }
    }
    // The placements reach every case.
    println!("culled {culled}, drawn {drawn}, must {must}");
    assert!(
        culled > 300 && drawn > 300 && must > 300,
        "culled {culled}, drawn {drawn}, must {must}"
    );
}

/// The sphere is the one its doc describes, not merely one holding the points: the centre is the bounding box's
/// centre rounded once to f32 (`lo / 2 + hi / 2`: both halves exact for normal numbers, one rounding in the sum),
/// and the radius is the largest distance from it widened by no more than the doc's budget: the scaling, squares,
/// sum and square root carry under `2^-21` relative, the widening is `2^-18` and the last product rounds by `2^-24`,
/// so `radius <= d_max (1 + 2^-21)(1 + 2^-18)(1 + 2^-24) < d_max (1 + 2^-17)`. A cloud of one point (or of equal
/// points) has radius 0 at that point.
#[test]
fn the_sphere_is_the_box_centre_and_the_farthest_point() {
    let mut rnd = xorshift(0x5EED_0003);
    let mut checked = 0;
    for k in 0..400 {
        let scale = 10f64.powf(-20.0 + 50.0 * (k as f64 / 399.0));
        let off = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5].map(|v| v * scale * 4.0);
        let n = 1 + (rnd() * 40.0) as usize;
        let pos: Vec<[f32; 3]> = (0..n)
            .map(|_| [0, 1, 2].map(|i| (off[i] + (rnd() - 0.5) * scale) as f32))
            .collect();
        let s = Sphere::enclosing(&pos).unwrap();
        for i in 0..3 {
            let lo = pos
                .iter()
                .map(|p| p[i] as f64)
                .fold(f64::INFINITY, f64::min);
            let hi = pos
                .iter()
                .map(|p| p[i] as f64)
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(s.center[i], ((lo + hi) / 2.0) as f32, "cloud {k} axis {i}");
        }
        let c = s.center.map(|v| v as f64);
        let d_max = pos
            .iter()
            .map(|p| {
                (0..3)
                    .map(|i| (p[i] as f64 - c[i]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max);
        let r = s.radius as f64;
        assert!(r >= d_max, "cloud {k}: {r} < {d_max}");
        assert!(
            r <= d_max * (1.0 + 2f64.powi(-17)),
            "cloud {k}: radius {r} is {} of the farthest point's {d_max}",
            r / d_max
        );
        checked += usize::from(d_max > 0.0);
    }
    assert!(checked > 350, "{checked}");
    let one = Sphere::enclosing(&[[1.5, -2.0, 3.0], [1.5, -2.0, 3.0]]).unwrap();
    assert_eq!(
        one,
        Sphere {
            center: [1.5, -2.0, 3.0],
            radius: 0.0
        }
    );
}

/// `Sphere::visible` against the exact test, on spheres placed at random around each of the six planes, within
/// `2^-4` to `2^-26` of touching it (radii `|L(c)| / |a| (1 + delta)`): the planes in object space
/// formed in f64 from the same f32 matrix, viewport and range (`L(c)` and `|a|` as the doc defines them; products of
/// f32 values are exact in f64 and the sums err by some `2^-52`, far below what is asserted). The model matrices are
/// general (rotations, a non-uniform scale, a shear), and the viewports of several kinds, one with its clip corner at
/// the origin (screen planes without a `w` term).
/// - Where the exact sphere reaches inside every plane (`L(c) >= -r |a|` for all six), the cull keeps it: the doc's
///   promise, "culled only when the exact test would cull it".
/// - Where it lies outside one plane by more than the cull's margins (`-L(c) > r sqrt(|a|^2 + 2^-18 B) + (2^-16 +
///   2^-19) T`, with `T` the sum of `L`'s terms' magnitudes and `B >= ` that of `|a|^2`), the cull rejects it: its
///   `d = -l - t 2^-16` has `l` within `2^-20 T` of `L` (the doc), `t` (`T` summed in f32) within `2^-21` of `T`
///   and the subtraction's rounding `2^-24 |L| <= 2^-24 T`, so `d >= -L - (2^-16 + 2^-20 + 2^-23) T`; its
///   `a2 + 2^-20 b` is within `2^-19 B` of `|a|^2 + 2^-20 B`, and the f32 squares and products within `2^-21`, so
///   `d^2 > r^2 (a2 + 2^-20 b)` holds there. (The margin's own `2^-16 T` is thus asserted to within `2^-19 T`: a cull
///   whose margin's terms were an eighth larger would keep some of these spheres.)
#[test]
fn the_sphere_cull_is_the_exact_test_within_its_margins() {
    let mut rnd = xorshift(0x5EED_0004);
    let (mut kept_touching, mut culled_near, mut cases) = (0, 0, 0);
    for k in 0..15_000 {
        let (w, h) = (16 + (rnd() * 300.0) as u32, 16 + (rnd() * 300.0) as u32);
        let near = 0.1 + rnd() * 2.0;
        let far = near * (2.0 + rnd() * 500.0);
        let cam = Camera::look_at(
            [0.0, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.0, 1.0, 0.0],
            0.3 + rnd() as f32 * 2.0,
            w as f32 / h as f32,
            near as f32,
            far as f32,
        )
        .unwrap();
        // A general linear part (rotations, a non-uniform scale and a shear: the planes' normals then have all their
        // Gram products, the cross terms of `|a|^2` too), then a translation in front of the eye.
        let mut shear = Mat4::IDENTITY;
        (shear.0[0][1], shear.0[1][2], shear.0[2][0]) = (
            ((rnd() - 0.5) * 1.5) as f32,
            ((rnd() - 0.5) * 1.5) as f32,
            ((rnd() - 0.5) * 1.5) as f32,
        );
        let model = Mat4::rotation_x((rnd() * 6.0) as f32)
            * Mat4::rotation_y((rnd() * 6.0) as f32)
            * Mat4::scale([0.5 + rnd() as f32, 0.5 + rnd() as f32, 0.5 + rnd() as f32])
            * shear
            * Mat4::translation([
                ((rnd() - 0.5) * 4.0) as f32,
                ((rnd() - 0.5) * 4.0) as f32,
                -(near + rnd() * (far - near)) as f32,
            ]);
        let m = cam.model_matrix(&model);
        // The whole target, a viewport inside it, or one with another clip rectangle; some with its corner at the
        // clip origin.
        let mut vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
        if k % 3 == 1 {
            vp = Viewport::new(3.0, 5.0, w as f32 * 0.75, h as f32 * 0.5);
        } else if k % 3 == 2 {
            (vp.clip_x, vp.clip_y, vp.clip_width, vp.clip_height) = (-0.8, 0.7, 1.7, 1.3);
        }
        if k % 4 == 3 {
            // The clip rectangle's corner at the origin: the planes `x >= 0` and `y >= 0` have no `w` term, so their
            // margin is all `|sx| g` (or `|sy| g`).
            (vp.x, vp.y, vp.clip_x, vp.clip_y) = (0.0, 0.0, 0.0, 0.0);
        }
        let range = cam.render_state().unwrap().range;
        // The six planes `ka (x or y) + kw w + kc >= 0` in clip space, exactly.
        let (sx, sy) = (
            vp.width as f64 / vp.clip_width as f64,
            vp.height as f64 / vp.clip_height as f64,
        );
        let (ox, oy) = (
            vp.x as f64 - vp.clip_x as f64 * sx,
            vp.y as f64 + vp.clip_y as f64 * sy,
        );
        let (wd, ht) = (w as f64, h as f64);
        let planes: [(usize, f64, f64, f64); 6] = [
            (0, sx, ox, 0.0),
            (0, -sx, wd - ox, 0.0),
            (1, -sy, oy, 0.0),
            (1, sy, ht - oy, 0.0),
            (0, 0.0, 1.0, -range.near() as f64),
            (0, 0.0, -1.0, range.far() as f64),
        ];
        let mm = m.0.map(|row| row.map(|v| v as f64));
        // For centre `c`: per plane `(L(c), |a|, T, B)`.
        let terms = |c: [f64; 3]| {
            planes.map(|(axis, ka, kw, kc)| {
                let a = [0, 1, 2].map(|i| ka * mm[i][axis] + kw * mm[i][3]);
                let l = (0..3).map(|i| c[i] * a[i]).sum::<f64>()
                    + ka * mm[3][axis]
                    + kw * mm[3][3]
                    + kc;
                let t = (0..3)
                    .map(|i| (ka * c[i] * mm[i][axis]).abs() + (kw * c[i] * mm[i][3]).abs())
                    .sum::<f64>()
                    + (ka * mm[3][axis]).abs()
                    + (kw * mm[3][3]).abs()
                    + kc.abs();
                let b = (0..3)
                    .map(|i| ((ka * mm[i][axis]).abs() + (kw * mm[i][3]).abs()).powi(2))
                    .sum::<f64>();
                (l, a.iter().map(|v| v * v).sum::<f64>().sqrt(), t, b)
            })
        };
        // A centre anywhere in a box around the view, in object space: outside at least one plane most of the time.
        let center = [0, 1, 2].map(|_| ((rnd() - 0.5) * 40.0) as f32);
        let p = terms(center.map(|v| v as f64));
        // Radius: touching one plane the centre is outside of, within `2^-26` to `2^-4`, either side.
        let outside: Vec<usize> = (0..6).filter(|&j| p[j].0 < 0.0).collect();
        if outside.is_empty() {
            continue;
        }
        let j = outside[(rnd() * outside.len() as f64) as usize];
        let delta = 2f64.powf(-4.0 - rnd() * 22.0) * if k % 2 == 0 { 1.0 } else { -1.0 };
        let radius = (-p[j].0 / p[j].1 * (1.0 + delta)) as f32;
        let sphere = Sphere { center, radius };
        let r = radius as f64;
        let visible = sphere.visible(&m, &vp, Size::new(w, h), &range);
        cases += 1;
        if p.iter().all(|&(l, a, _, _)| l >= -r * a) {
            kept_touching += 1;
            assert!(
                visible,
                "case {k}: the exact sphere reaches inside, the cull rejects it ({sphere:?})"
            );
        }
        if p.iter().any(|&(l, a, t, b)| {
            -l > r * (a * a + b * 2f64.powi(-18)).sqrt() + t * (2f64.powi(-16) + 2f64.powi(-19))
        }) {
            culled_near += 1;
            assert!(
                !visible,
                "case {k}: outside beyond the margins, the cull keeps it ({sphere:?})"
            );
        }
    }
    // Both promises are put to the test near the planes, many times.
    println!("cases {cases}, kept touching {kept_touching}, culled near {culled_near}");
    assert!(
        kept_touching > 1000 && culled_near > 1000,
        "cases {cases}, kept touching {kept_touching}, culled near {culled_near}"
    );
}
