//! Loads a mesh from an OBJ file (with the `tobj` crate), lights it (Gouraud, from its normals) and renders it
//! from a camera through wraster's mesh path into a 320 x 240 frame, saved as a PNG through
//! embedded-graphics-simulator.
//!
//! `cargo run --release -p host-tests --example obj [-- file.obj [out.png]]` (default: host-tests/assets/torus.obj,
//! target/obj.png). A board bakes an OBJ into flash the same way `boards/common/build.rs` bakes W4's torus: load it
//! in build.rs and write the positions as `f32::from_bits` constants.

use embedded_graphics::pixelcolor::Rgb565;
use host_tests::Frame;
use wraster::clip::Viewport;
use wraster::lighting::{shade_vertices, Light};
use wraster::mesh::{Colors, Mesh, Projected};
use wraster::projection::{Camera, Mat4};
use wraster::{DepthBuffer, Rasterizer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .map_or_else(|| dir.join("assets/torus.obj"), Into::into);
    let out = args
        .next()
        .map_or_else(|| dir.join("../target/obj.png"), Into::into);
    let (models, _) = tobj::load_obj(&path, &tobj::GPU_LOAD_OPTIONS)?;
    let m = &models.first().ok_or("no model in the file")?.mesh;
    let positions: Vec<[f32; 3]> = m
        .positions
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let indices: Vec<[u16; 3]> = m
        .indices
        .chunks_exact(3)
        .map(|t| {
            t.iter()
                .map(|&i| u16::try_from(i))
                .collect::<Result<Vec<_>, _>>()
        })
        .map(|t| t.map(|t| [t[0], t[1], t[2]]))
        .collect::<Result<_, _>>()?;
    let normals: Vec<[f32; 3]> = m
        .normals
        .chunks_exact(3)
        .map(|n| [n[0], n[1], n[2]])
        .collect();
    if normals.len() != positions.len() {
        return Err("the example needs one normal per vertex (vn)".into());
    }

    let camera = Camera::look_at(
        [0.0, -2.2, 2.0],
        [0.0; 3],
        [0.0, 0.0, 1.0],
        1.0,
        4.0 / 3.0,
        0.5,
        20.0,
    )?;
    let model = Mat4::rotation_x(0.4) * Mat4::rotation_z(0.3);
    let light = Light {
        direction: [-1.0, -2.0, 3.0],
        ambient: 0.15,
        diffuse: 0.85,
    };
    let mut colors = vec![Rgb565::new(0, 0, 0); positions.len()];
    shade_vertices(
        &normals,
        &model,
        &light,
        |_| Rgb565::new(31, 40, 8),
        &mut colors,
    )?;
    let mesh = Mesh {
        positions: &positions,
        indices: &indices,
        colors: Colors::PerVertex(&colors),
    };

    let mut frame = Frame::new(320, 240);
    let mut depth = vec![0u16; 320 * 240];
    let mut buf = DepthBuffer::new(&mut depth, 320, 240)?;
    buf.clear();
    let mut r: Rasterizer = Rasterizer::new(camera.render_state()?);
    let mut scratch = vec![Projected::default(); positions.len()];
    let vp = Viewport::new(0.0, 0.0, 320.0, 240.0);
    let mf = r.transform_mesh(&mesh, &camera.model_matrix(&model), &vp, &mut scratch)?;
    let stats = r.draw_mesh_frame_gouraud(&mut frame, &mut buf, &mf)?;
    frame.save_png(&out);
    println!(
        "obj file={} vertices={} triangles={} written={} culled={} png={}",
        path.display(),
        positions.len(),
        indices.len(),
        stats.written,
        stats.culled,
        out.display()
    );
    Ok(())
}
