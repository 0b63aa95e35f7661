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
