//! World-space triangles: transform to clip space, clip, map through the viewport, draw.
//!
//! Clipping is homogeneous (Sutherland-Hodgman in clip coordinates, before the divide), against the near W plane
//! `w >= W_near` of the render state, so every vertex that reaches the rasterizer has a finite, positive RHW no
//! larger than `1 / W_near`: a triangle crossing the near plane, or lying partly behind the eye, draws exactly its
//! part in front of the near plane instead of wrapping around through infinity (the "flashing" triangles of naive
//! rasterizers). x and y are clipped to the guard band (4000 px, inside the rasterizer's 4096), so any triangle in
//! front of the eye draws. The far plane needs no clip: pixels beyond `W_far` fail the depth range per pixel.
//! The projection must give `w` = eye depth (Dunlop's "Using W-Buffers" W-friendly matrix; [`crate::projection::is_w_friendly`]).

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;

use crate::projection::Mat4;
use crate::recip::{SpanRecip, WSpan};
use crate::{Codec, DepthBuffer, Error, Packed, Rasterizer, Stats, Vertex};

/// The viewport, like D3DVIEWPORT2: the pixel rectangle (`x`, `y`, `width`, `height`; y down) that the clip
/// rectangle of projected space (`clip_x`, `clip_y`, `clip_width`, `clip_height`; y up, D3D's default
/// `-1, 1, 2, 2`) maps to, and the range `[min_z, max_z]` projected z maps to. A vertex at projected `(x/w, y/w, z/w)`
/// lands at pixel `x + (x/w - clip_x) / clip_width * width`, `y + (clip_y - y/w) / clip_height * height`, with
/// `z = min_z + z/w (max_z - min_z)`. (Depth itself comes from RHW; `z` is passed on in the vertex.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge, pixels (D3DVIEWPORT2's dwX).
    pub x: f32,
    /// Top edge, pixels (dwY).
    pub y: f32,
    /// Width, pixels (dwWidth).
    pub width: f32,
    /// Height, pixels (dwHeight).
    pub height: f32,
    /// Projected x of the left edge (dvClipX).
    pub clip_x: f32,
    /// Projected y of the top edge (dvClipY).
    pub clip_y: f32,
    /// Projected width (dvClipWidth).
    pub clip_width: f32,
    /// Projected height (dvClipHeight).
    pub clip_height: f32,
    /// z of the near plane (dvMinZ).
    pub min_z: f32,
    /// z of the far plane (dvMaxZ).
    pub max_z: f32,
}

impl Viewport {
    /// The pixel rectangle with D3D's default clip rectangle (`-1, 1, 2, 2`) and z range `[0, 1]`.
    pub fn new(x: f32, y: f32, width: f32, height: f32) -> Self {
        Viewport {
            x,
            y,
            width,
            height,
            clip_x: -1.0,
            clip_y: 1.0,
            clip_width: 2.0,
            clip_height: 2.0,
            min_z: 0.0,
            max_z: 1.0,
        }
    }
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

impl<R: WSpan> Rasterizer<R> {
    /// Transforms, clips and maps a world-space triangle: the clipped polygon's vertices (a fan) and their count,
    /// 0 when nothing is left. Every fan triangle is checked, so a later draw of them cannot fail on x or y.
    fn clip_world<C: Copy>(
        &self,
        m: &Mat4,
        vp: &Viewport,
        p: &[[f32; 3]; 3],
        color: C,
    ) -> Result<([Vertex<C>; MAX_VERTS], usize), Error> {
        let vpf = [
            vp.x,
            vp.y,
            vp.width,
            vp.height,
            vp.clip_x,
            vp.clip_y,
            vp.clip_width,
            vp.clip_height,
            vp.min_z,
            vp.max_z,
        ];
        if p.iter()
            .flatten()
            .chain(m.0.iter().flatten())
            .chain(vpf.iter())
            .any(|v| !v.is_finite())
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
        // screen x = X + (x/w - cx) sx, screen y = Y + (cy - y/w) sy
        let (sx, sy) = (
            vp.width as f64 / vp.clip_width as f64,
            vp.height as f64 / vp.clip_height as f64,
        );
        let (cx, cy) = (vp.clip_x as f64, vp.clip_y as f64);
        if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
            return Err(Error::NonFinite);
        }
        // the guard band in projected units: x/w in [kx_lo, kx_hi], y/w in [ky_lo, ky_hi]
        let kx_hi = cx + (CLIP_BAND - vp.x as f64) / sx;
        let kx_lo = cx + (-CLIP_BAND - vp.x as f64) / sx;
        let ky_lo = cy - (CLIP_BAND - vp.y as f64) / sy;
        let ky_hi = cy - (-CLIP_BAND - vp.y as f64) / sy;
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
                return Ok(([Vertex::new(0.0, 0.0, 1.0, color); MAX_VERTS], 0));
            }
        }
        let verts: [Vertex<C>; MAX_VERTS] = core::array::from_fn(|k| {
            let [x, y, z, w] = poly.0[k];
            Vertex {
                x: (vp.x as f64 + (x / w - cx) * sx) as f32,
                y: (vp.y as f64 + (cy - y / w) * sy) as f32,
                z: (vp.min_z as f64 + z / w * (vp.max_z as f64 - vp.min_z as f64)) as f32,
                rhw: (1.0 / w) as f32,
                color,
            }
        });
        // Check every fan triangle before drawing any, so an error writes nothing.
        for k in 1..poly.1 - 1 {
            crate::row_range(&[verts[0], verts[k], verts[k + 1]])?;
        }
        Ok((verts, poly.1))
    }

    /// [`Rasterizer::draw_world`] into a depth buffer of any format (or none), with this rasterizer's W strategy.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_world_format<F: Codec, D>(
        &mut self,
        target: &mut D,
        mut depth: Option<&mut Packed<'_, F>>,
        m: &Mat4,
        vp: &Viewport,
        p: &[[f32; 3]; 3],
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let (verts, n) = self.clip_world(m, vp, p, color)?;
        let mut stats = Stats::default();
        for k in 1..n.saturating_sub(1) {
            stats += self.draw_format(
                target,
                depth.as_deref_mut(),
                &[verts[0], verts[k], verts[k + 1]],
            )?;
        }
        Ok(stats)
    }
}

impl<R: SpanRecip> Rasterizer<R> {
    /// Draws a world-space triangle (`p` as `[x, y, z]`, transformed as row vectors `[x, y, z, 1] * m`, `m` the
    /// world-to-clip matrix) with flat colour `color`, clipped as the module says, into a W16 buffer (the lean path).
    /// On an error nothing is written.
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
        let (verts, n) = self.clip_world(m, vp, p, color)?;
        let mut stats = Stats::default();
        for k in 1..n.saturating_sub(1) {
            stats += self.draw(target, depth, &[verts[0], verts[k], verts[k + 1]])?;
        }
        Ok(stats)
    }
}
