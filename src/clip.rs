//! World-space triangles: transform to clip space, clip, map through the viewport, draw.
//!
//! Clipping is homogeneous (Sutherland-Hodgman in clip coordinates, before the divide), against the near W plane
//! `w >= W_near` of the render state, so every vertex that reaches the rasterizer has a finite, positive RHW no
//! larger than `1 / W_near`: a triangle crossing the near plane, or lying partly behind the eye, draws exactly its
//! part in front of the near plane instead of wrapping around through infinity (the "flashing" triangles of naive
//! rasterizers). x and y are clipped to the guard band (4000 px, inside the rasterizer's 4096), so any triangle in
//! front of the eye draws. The far plane needs no clip: pixels beyond `W_far` fail the depth range per pixel.
//! The projection must give `w` = eye depth (seed 002's W-friendly matrix; [`crate::projection::is_w_friendly`]).

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;

use crate::projection::Mat4;
use crate::recip::SpanRecip;
use crate::{DepthBuffer, Error, Rasterizer, Stats, Vertex};

/// The viewport, like D3DVIEWPORT2: the pixel rectangle clip space maps to (x right, y down; clip-space y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge, pixels.
    pub x: f32,
    /// Top edge, pixels.
    pub y: f32,
    /// Width, pixels.
    pub width: f32,
    /// Height, pixels.
    pub height: f32,
}

/// Guard band used for clipping, pixels (inside [`crate::GUARD_BAND`]).
const CLIP_BAND: f64 = 4000.0;
/// Up to 3 + one vertex per plane (5 planes).
const MAX_VERTS: usize = 8;

type Poly = ([[f64; 4]; MAX_VERTS], usize);

/// Keeps the part of `poly` where `dot(plane, v) + offset >= 0`.
fn clip_plane(poly: &Poly, plane: [f64; 4], offset: f64) -> Poly {
    let (vs, n) = poly;
    let mut out = ([[0.0; 4]; MAX_VERTS], 0usize);
    let dist = |v: &[f64; 4]| v.iter().zip(plane).map(|(a, b)| a * b).sum::<f64>() + offset;
    for k in 0..*n {
        let (a, b) = (vs[k], vs[(k + 1) % n]);
        let (da, db) = (dist(&a), dist(&b));
        if da >= 0.0 && out.1 < MAX_VERTS {
            out.0[out.1] = a;
            out.1 += 1;
        }
        if (da >= 0.0) != (db >= 0.0) && out.1 < MAX_VERTS {
            let t = da / (da - db);
            out.0[out.1] = core::array::from_fn(|i| a[i] + t * (b[i] - a[i]));
            out.1 += 1;
        }
    }
    out
}

impl<R: SpanRecip> Rasterizer<R> {
    /// Draws a world-space triangle (`p` as `[x, y, z]`, transformed as row vectors `[x, y, z, 1] * m`, `m` the
    /// world-to-clip matrix) with flat colour `color`, clipped as the module says. On an error nothing is written.
    pub fn draw_world<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        m: &Mat4,
        vp: &Viewport,
        p: &[[f32; 3]; 3],
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        if p.iter()
            .flatten()
            .chain(m.0.iter().flatten())
            .any(|v| !v.is_finite())
            || ![vp.x, vp.y, vp.width, vp.height]
                .iter()
                .all(|v| v.is_finite())
        {
            return Err(Error::NonFinite);
        }
        let mut poly: Poly = ([[0.0; 4]; MAX_VERTS], 3);
        for (k, q) in p.iter().enumerate() {
            for c in 0..4 {
                poly.0[k][c] =
                    (0..3).map(|r| q[r] as f64 * m.0[r][c] as f64).sum::<f64>() + m.0[3][c] as f64;
            }
        }
        let near = self.state.range.near() as f64;
        let (w2, h2) = (vp.width as f64 / 2.0, vp.height as f64 / 2.0);
        // screen x = vp.x + (x/w + 1) w2 within +-CLIP_BAND, screen y = vp.y + (1 - y/w) h2 likewise
        let kx_hi = (CLIP_BAND - vp.x as f64) / w2 - 1.0;
        let kx_lo = (-CLIP_BAND - vp.x as f64) / w2 - 1.0;
        let ky_lo = 1.0 - (CLIP_BAND - vp.y as f64) / h2;
        let ky_hi = 1.0 - (-CLIP_BAND - vp.y as f64) / h2;
        // the near W plane (w - W_near >= 0), then the guard band's four planes
        for (plane, offset) in [
            ([0.0, 0.0, 0.0, 1.0], -near),
            ([-1.0, 0.0, 0.0, kx_hi], 0.0),
            ([1.0, 0.0, 0.0, -kx_lo], 0.0),
            ([0.0, -1.0, 0.0, ky_hi], 0.0),
            ([0.0, 1.0, 0.0, -ky_lo], 0.0),
        ] {
            poly = clip_plane(&poly, plane, offset);
            if poly.1 < 3 {
                return Ok(Stats::default());
            }
        }
        let verts: [Vertex<D::Color>; MAX_VERTS] = core::array::from_fn(|k| {
            let [x, y, z, w] = poly.0[k];
            Vertex {
                x: (vp.x as f64 + (x / w + 1.0) * w2) as f32,
                y: (vp.y as f64 + (1.0 - y / w) * h2) as f32,
                z: (z / w) as f32,
                rhw: (1.0 / w) as f32,
                color,
            }
        });
        // Check every fan triangle before drawing any, so an error writes nothing.
        for k in 1..poly.1 - 1 {
            crate::row_range(&[verts[0], verts[k], verts[k + 1]])?;
        }
        let mut stats = Stats::default();
        for k in 1..poly.1 - 1 {
            stats += self.draw(target, depth, &[verts[0], verts[k], verts[k + 1]])?;
        }
        Ok(stats)
    }
}
