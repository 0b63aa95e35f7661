//! wraster: a `no_std` fixed-point triangle rasterizer with a W-buffer, for microcontrollers.
//!
//! It edge-walks triangles exactly (8 sub-pixel bits, top-left rule), interpolates `1/W` (RHW) in fixed point,
//! recovers `W` per pixel with a Newton-Raphson reciprocal, and keeps depth in a packed 16-bit W-buffer
//! (`round(W / W_far * 65535)`), whose precision is spread evenly over the depth range. Pixel centres are at
//! `(i + 0.5, j + 0.5)`, as in Direct3D 10 and later and OpenGL.
//!
//! Strategies are type parameters. The default, [`recip::Fast`] (the fast tier), walks W16 spans in 32-bit arithmetic
//! with a reciprocal carried along the span and the depth test ahead of it: every stored code within 1 LSB of the
//! correctly rounded one, at least 99.9% exact (derived in the crate's `fast` module). [`recip::Exact`] (the exact tier)
//! solves each triangle's depth plane exactly and takes a 28-bit reciprocal at every pixel.
//!
//! ```
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! use embedded_graphics_core::prelude::*;
//! use wraster::{ColorBand, DepthStore, Rasterizer, RenderState, Vertex};
//!
//! let mut px = [0u16; 32 * 16]; // RGB565, what the display takes
//! let mut screen = ColorBand::<Rgb565>::new(&mut px, 32, 16)?;
//! let mut depth = DepthStore::<32, 16>::new();
//! let mut r: Rasterizer = Rasterizer::new(RenderState::new(10.0, 1000.0)?);
//! let tri = [
//!     Vertex::new(1.5, 1.5, 20.0, Rgb565::RED),
//!     Vertex::new(30.5, 4.5, 900.0, Rgb565::RED),
//!     Vertex::new(6.5, 14.5, 100.0, Rgb565::RED),
//! ];
//! let stats = r.draw(&mut screen, &mut depth.view(), &tri)?;
//! assert!(stats.written > 100);
//! assert_eq!(px[2 * 32 + 2], 0xF800); // a pixel inside, red
//! # Ok::<(), wraster::Error>(())
//! ```
//!
//! Every depth format of the seeds ([`format`]) renders through the same [`DepthBuffer`] type (W16 when none is
//! named) and the same draw methods, with Z or W buffering ([`DepthMode`]), and points, lines and wireframe triangles
//! too; [`NoDepth`] draws with depth off:
//!
//! ```
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! use embedded_graphics_core::prelude::*;
//! use wraster::format::RZ32F;
//! use wraster::{DepthBuffer, DepthMode, NoDepth, Rasterizer, RenderState, Vertex};
//!
//! # struct Screen;
//! # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(32, 16) } }
//! # impl DrawTarget for Screen {
//! #     type Color = Rgb565; type Error = core::convert::Infallible;
//! #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
//! # }
//! let mut state = RenderState::new(10.0, 1000.0)?;
//! state.mode = DepthMode::Z;
//! let mut words = [0u32; 32 * 16];
//! let mut depth = DepthBuffer::<RZ32F>::new_format(&mut words, 32, 16)?; // reversed float Z, 4 bytes a pixel
//! depth.clear_for(&state.range);
//! let mut r: Rasterizer = Rasterizer::new(state);
//! let a = Vertex::new(1.5, 1.5, 20.0, Rgb565::RED);
//! let b = Vertex::new(30.5, 4.5, 900.0, Rgb565::RED);
//! let c = Vertex::new(6.5, 14.5, 100.0, Rgb565::RED);
//! assert!(r.draw(&mut Screen, &mut depth, &[a, b, c])?.written > 100);
//! assert!(r.draw_line(&mut Screen, &mut depth, &[a, b])?.fragments > 20);
//! assert!(r.draw_point(&mut Screen, NoDepth, &c)?.written == 1);
//! # Ok::<(), wraster::Error>(())
//! ```
//!
//! From world space: a [`projection::Camera`] (a W-friendly perspective, so its depth planes are the render state's),
//! and an indexed [`mesh::Mesh`] drawn with one call, each vertex transformed once, back faces culled, clipped
//! against the near plane in f32 (no f64 anywhere the firmware links):
//!
//! ```
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! use embedded_graphics_core::prelude::*;
//! use wraster::clip::Viewport;
//! use wraster::mesh::{Colors, Mesh, Projected};
//! use wraster::projection::{Camera, Mat4};
//! use wraster::{ColorBand, DepthStore, Rasterizer};
//!
//! // A tetrahedron, counter-clockwise seen from outside, one colour per face.
//! let positions = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
//! let indices = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
//! let faces = [Rgb565::RED, Rgb565::GREEN, Rgb565::BLUE, Rgb565::YELLOW];
//! let mesh = Mesh { positions: &positions, indices: &indices, colors: Colors::PerFace(&faces) };
//!
//! // Eye at (0, 0, 4) looking at the origin; 60 degree field of view, aspect = width / height.
//! let camera = Camera::look_at([0.0, 0.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0],
//!                              core::f32::consts::FRAC_PI_3, 64.0 / 48.0, 0.5, 100.0)?;
//! let mut r: Rasterizer = Rasterizer::new(camera.render_state()?); // depth range 0.5..100, back faces culled
//! let mut px = [0u16; 64 * 48];
//! let mut screen = ColorBand::<Rgb565>::new(&mut px, 64, 48)?;
//! let mut depth = DepthStore::<64, 48>::new();
//! let mut scratch = [Projected::default(); 4]; // one per vertex, caller-owned: no allocation
//! let vp = Viewport::new(0.0, 0.0, 64.0, 48.0);
//! for frame in 0..3 {
//!     depth.view().clear();
//!     let model = Mat4::rotation_y(0.5 * frame as f32) * Mat4::translation([0.0, 0.0, -1.0]);
//!     let m = camera.model_matrix(&model);
//!     let stats = r.draw_mesh(&mut screen, &mut depth.view(), &mesh, &m, &vp, &mut scratch)?;
//!     assert!(stats.written > 100 && stats.culled >= 1);
//! }
//! # Ok::<(), wraster::Error>(())
//! ```
#![no_std]
// `unsafe` in one module only, `sentinel` (its cursor), where a measured figure showed it pays (the README).
#![deny(unsafe_code)]
#![warn(missing_docs)]

// Unit tests print their measurements and use f64 functions: std for tests only.
#[cfg(test)]
extern crate std;

pub mod clip;
mod depth;
mod draw;
mod edge;
mod error;
mod fast;
mod fixed;
pub mod format;
pub mod input;
#[cfg(feature = "lighting")]
pub mod lighting;
pub mod mesh;
pub mod packed;
pub mod projection;
mod raster;
pub mod recip;
mod runs;
#[cfg(feature = "scenes")]
pub mod scenes;
mod sentinel;
mod setup;
mod small;
mod state;
pub mod target;
mod transform;

/// A xorshift64 generator for the unit tests. The closure is `Copy`: a copy goes on from the same state, so a view
/// made from a copy repeats the sequence rather than sharing it.
#[cfg(test)]
pub(crate) fn xorshift(mut s: u64) -> impl FnMut() -> u64 + Copy {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

#[cfg(feature = "coarse")]
pub use depth::bound_len;
pub use depth::{DepthBuffer, DepthStore, W16_FAR};
pub use draw::{IntoDepth, NoDepth};
pub use error::Error;
pub use input::row_range;
pub use input::{FixedVertex, VertexInput};
pub use packed::{Codec, Resolved};
pub use raster::Rasterizer;
pub use setup::{depth_grid_bits, Stats, Vertex, GUARD_BAND, SUBPIXEL_BITS};
pub use state::{Compare, Cull, DepthMode, DepthRange, RenderState, MAX_T};
pub use target::ColorBand;
