//! embedded-graphics' `MockDisplay`, which panics on a pixel drawn outside it or drawn twice: with depth testing off,
//! a closed convex mesh (back faces culled) and a grid of adjoining triangles must write every pixel at most once,
//! and the grid must write each pixel of its rectangle exactly once (no gap, no overlap: the top-left rule).

use embedded_graphics::mock_display::MockDisplay;
use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use embedded_graphics::prelude::*;
use host_tests::Rng;
use wraster::clip::Viewport;
use wraster::mesh::{Colors, Mesh, Projected};
use wraster::projection::{Camera, Mat4};
use wraster::{Cull, DepthMode, DepthStore, Rasterizer, RenderState, Vertex};

#[test]
fn closed_cube_with_depth_off_writes_no_pixel_twice() {
    let camera = Camera::look_at(
        [3.0, 2.5, 4.0],
        [0.0; 3],
        [0.0, 1.0, 0.0],
        0.9,
        1.0,
        0.5,
        50.0,
    )
    .unwrap();
    let mut state = camera.render_state().unwrap();
    assert_eq!(state.cull, Cull::Cw, "the camera culls back faces");
    state.mode = DepthMode::Off;
    let mut r: Rasterizer = Rasterizer::new(state);
    let faces: Vec<Rgb565> = (0..12)
        .map(|k| Rgb565::new(k as u8 * 2, 63 - k as u8 * 4, 31))
        .collect();
    let (positions, indices) = host_tests::cube();
    let mesh = Mesh {
        positions: &positions,
        indices: &indices,
        colors: Colors::PerFace(&faces),
    };
    let vp = Viewport::new(0.0, 0.0, 64.0, 64.0);
    let mut depth = DepthStore::<64, 64>::new();
    let mut scratch = [Projected::default(); 8];
    for k in 0..24 {
        let mut display = MockDisplay::<Rgb565>::new(); // panics on overdraw and out of bounds
        let model = Mat4::rotation_y(k as f32 * 0.26) * Mat4::rotation_x(k as f32 * 0.11);
        let m = camera.model_matrix(&model);
        let stats = r
            .draw_mesh(
                &mut display,
                &mut depth.view(),
                &mesh,
                &m,
                &vp,
                &mut scratch,
            )
            .unwrap();
        // Three faces at most are in front: 6 of the 12 triangles culled at least, and the picture is solid.
        assert!(stats.culled >= 6, "frame {k}: {stats:?}");
        let drawn = display.affected_area().size;
        assert!(
            drawn.width > 10 && drawn.height > 10,
            "frame {k}: {drawn:?}"
        );
        assert_eq!(stats.written, stats.fragments);
        let mut count = 0;
        for y in 0..64 {
            for x in 0..64 {
                count += u32::from(display.get_pixel(Point::new(x, y)).is_some());
            }
        }
        assert_eq!(count, stats.written, "frame {k}: each written pixel once");
    }
}

#[test]
fn grid_of_adjoining_triangles_covers_each_pixel_once() {
    let mut rng = Rng(5);
    // A 6 x 5 grid of cells over [2, 62) x [3, 58), inner vertices jittered off the pixel grid (shared by the cells
    // around them), each cell split along a random diagonal: 60 triangles that tile the rectangle exactly.
    let (nx, ny) = (6usize, 5usize);
    let (x0, x1, y0, y1) = (2.0f32, 62.0f32, 3.0f32, 58.0f32);
    let mut grid = vec![[0.0f32; 2]; (nx + 1) * (ny + 1)];
    for j in 0..=ny {
        for i in 0..=nx {
            let mut x = x0 + (x1 - x0) * i as f32 / nx as f32;
            let mut y = y0 + (y1 - y0) * j as f32 / ny as f32;
            if i > 0 && i < nx {
                x += rng.f(-3.0, 3.0) as f32;
            }
            if j > 0 && j < ny {
                y += rng.f(-3.0, 3.0) as f32;
            }
            grid[j * (nx + 1) + i] = [x, y];
        }
    }
    let mut state = RenderState::new(1.0, 100.0).unwrap();
    state.mode = DepthMode::Off;
    let mut r: Rasterizer = Rasterizer::new(state);
    let mut depth = DepthStore::<64, 64>::new();
    let mut display = MockDisplay::<Rgb565>::new();
    let v = |i: usize, j: usize| {
        let [x, y] = grid[j * (nx + 1) + i];
        Vertex::new(
            x,
            y,
            2.0 + (i + j) as f32,
            Rgb565::new((i * 5) as u8, (j * 12) as u8, 9),
        )
    };
    let mut written = 0;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            let tris = if rng.bits().is_multiple_of(2) {
                [[a, b, c], [a, c, d]]
            } else {
                [[a, b, d], [b, c, d]]
            };
            for t in tris {
                written += r.draw(&mut display, &mut depth.view(), &t).unwrap().written;
            }
        }
    }
    // The rectangle's outer edges are straight: pixel centres (x + 0.5, y + 0.5) with 2 <= x + 0.5 < 62 and
    // 3 <= y + 0.5 < 58 (top-left rule: the left and top edges in, the right and bottom edges out).
    let mut inside = 0;
    for y in 0..64 {
        for x in 0..64 {
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let want = (x0..x1).contains(&cx) && (y0..y1).contains(&cy);
            inside += u32::from(want);
            assert_eq!(
                display.get_pixel(Point::new(x, y)).is_some(),
                want,
                "pixel ({x}, {y})"
            );
        }
    }
    assert_eq!(written, inside);
    assert_eq!(inside, 60 * 55);
}

#[test]
fn mock_display_catches_a_double_write() {
    // The check itself: drawing the same triangle twice with depth off must panic in MockDisplay.
    let result = std::panic::catch_unwind(|| {
        let mut state = RenderState::new(1.0, 100.0).unwrap();
        state.mode = DepthMode::Off;
        let mut r: Rasterizer = Rasterizer::new(state);
        let mut depth = DepthStore::<64, 64>::new();
        let mut display = MockDisplay::<Rgb565>::new();
        let t = [
            Vertex::new(2.0, 2.0, 5.0, Rgb565::RED),
            Vertex::new(30.0, 4.0, 5.0, Rgb565::RED),
            Vertex::new(6.0, 30.0, 5.0, Rgb565::RED),
        ];
        r.draw(&mut display, &mut depth.view(), &t).unwrap();
        r.draw(&mut display, &mut depth.view(), &t).unwrap();
    });
    assert!(result.is_err());
}
