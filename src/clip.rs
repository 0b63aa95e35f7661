//! World-space triangles: transform to clip space, clip, map through the viewport, draw.
//!
//! All in f32 (no f64, so no soft-float doubles on a microcontroller). Clipping is homogeneous (Sutherland-Hodgman in
//! clip coordinates, before the divide), against the near W plane
//! `w >= W_near` of the render state, so every vertex that reaches the rasterizer has a finite, positive RHW no
//! larger than `1 / W_near`: a triangle crossing the near plane, or lying partly behind the eye, draws exactly its
//! part in front of the near plane instead of wrapping around through infinity (the "flashing" triangles of naive
//! rasterizers). x and y are clipped to the guard band (4000 px, inside the rasterizer's 4096), so any triangle in
//! front of the eye draws. The far plane needs no clip: pixels beyond `W_far` fail the depth range per pixel.
//! The projection must give `w` = eye depth (Dunlop's "Using W-Buffers" W-friendly matrix; [`crate::projection::is_w_friendly`]).

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;

use crate::projection::Mat4;
use crate::recip::WSpan;
use crate::{Error, IntoDepth, Rasterizer, Stats, Vertex};

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
pub(crate) const CLIP_BAND: f32 = 4000.0;
/// Up to 3 + one vertex per plane (5 planes).
const MAX_VERTS: usize = 8;

/// A polygon vertex: clip-space `x, y, z, w`, then the barycentric weights of the source triangle's three vertices
/// (for per-vertex colours).
type PolyVertex = [f32; 7];
/// The clipped polygon (`heapless`: a fixed capacity, no allocation).
type Poly = heapless::Vec<PolyVertex, MAX_VERTS>;

/// The clip planes and the viewport map, in f32, for one depth range and viewport.
///
/// Error of the f32 path against exact arithmetic: the transform is 3 products and 3 sums per coordinate (a
/// relative error of about `4 * 2^-24` of the largest term), the map `x / w`, `- cx`, `* sx`, `+ X` adds 4 roundings:
/// a screen position within about `|x_px| * 2^-21` px (`2e-3` px at the 4000 px guard band, `1e-4` px on a 320 px
/// screen) and `rhw` within `2^-22` relative (`0.016` W16 code), far below the 1/512 px of the vertex snap.
/// (`host-tests/tests/clip.rs` checks the drawn frames against an f64 ray caster.)
#[derive(Clone, Copy, Debug)]
pub(crate) struct Planes {
    near: f32,
    /// `x/w` in `[kx_lo, kx_hi]`, `y/w` in `[ky_lo, ky_hi]`: the guard band in projected units.
    k: [f32; 4],
    /// Screen `x = ox + (x/w) sx`, `y = oy - (y/w) sy`.
    sx: f32,
    sy: f32,
    ox: f32,
    oy: f32,
    zmin: f32,
    zscale: f32,
}

impl Planes {
    pub(crate) fn new(near: f32, vp: &Viewport) -> Result<Planes, Error> {
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
        if vpf.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite);
        }
        let (sx, sy) = (vp.width / vp.clip_width, vp.height / vp.clip_height);
        if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
            return Err(Error::NonFinite);
        }
        let (cx, cy) = (vp.clip_x, vp.clip_y);
        let k = [
            cx + (-CLIP_BAND - vp.x) / sx,
            cx + (CLIP_BAND - vp.x) / sx,
            cy - (CLIP_BAND - vp.y) / sy,
            cy - (-CLIP_BAND - vp.y) / sy,
        ];
        let (ox, oy) = (vp.x - cx * sx, vp.y + cy * sy);
        if !(k.iter().all(|v| v.is_finite()) && ox.is_finite() && oy.is_finite()) {
            return Err(Error::NonFinite);
        }
        Ok(Planes {
            near,
            k,
            sx,
            sy,
            ox,
            oy,
            zmin: vp.min_z,
            zscale: vp.max_z - vp.min_z,
        })
    }

    /// The viewport map's constants `(sx, sy, ox, oy)`: screen `x = ox + (x/w) sx`, `y = oy - (y/w) sy`.
    pub(crate) fn map_constants(&self) -> (f32, f32, f32, f32) {
        (self.sx, self.sy, self.ox, self.oy)
    }

    /// `W_near`.
    pub(crate) fn near(&self) -> f32 {
        self.near
    }

    /// Signed distance of `c` to plane `p` (inside when `>= 0`): the near W plane, then the guard band's four.
    #[inline]
    fn dist(&self, p: usize, c: &[f32]) -> f32 {
        match p {
            0 => c[3] - self.near,
            1 => c[0] - self.k[0] * c[3],
            2 => self.k[1] * c[3] - c[0],
            3 => c[1] - self.k[2] * c[3],
            _ => self.k[3] * c[3] - c[1],
        }
    }

    /// Bit `p` set when `c` is outside plane `p`. A NaN distance (an overflow) counts as outside.
    #[inline]
    pub(crate) fn outcode(&self, c: &[f32; 4]) -> u8 {
        (0..5).fold(0, |o, p| {
            let d = self.dist(p, c);
            o | (u8::from(d.is_nan() || d < 0.0) << p)
        })
    }

    /// Screen `x, y`, the viewport's `z`, and `rhw` of a clip-space point inside every plane. The clip keeps the
    /// point in the guard band and in front of the near plane mathematically; the clamps only absorb f32 rounding
    /// (a point computed a rounding outside), so that no clipped vertex is refused by the rasterizer.
    #[inline]
    pub(crate) fn map(&self, c: &[f32]) -> [f32; 4] {
        let w = c[3].max(self.near);
        let rhw = 1.0 / w;
        let x = (self.ox + c[0] * rhw * self.sx).clamp(-CLIP_BAND, CLIP_BAND);
        let y = (self.oy - c[1] * rhw * self.sy).clamp(-CLIP_BAND, CLIP_BAND);
        // z is only checked downstream (depth comes from rhw): an overflow there must not refuse the vertex.
        let z = self.zmin + c[2] * rhw * self.zscale;
        [x, y, if z.is_finite() { z } else { 0.0 }, rhw]
    }

    /// [`Planes::map`], refused with [`Error::WorldTooLarge`] when the result is not a drawable vertex: a NaN `x` or
    /// `y` (both are clamped, so NaN is their only bad value), `w` not finite, or `rhw` infinite (`1 / W_near`
    /// overflows for a `W_near` below about `3e-39`). `rhw = 1 / max(w, W_near)` with `W_near > 0` is never negative,
    /// and zero only for `w = +inf`, so these four tests are all it needs. (A fuzz finding: a clipped vertex's
    /// interpolated coordinates could overflow after the last plane, and reach the draw as a non-finite vertex after
    /// earlier triangles of the mesh had been drawn.)
    #[inline]
    pub(crate) fn map_checked(&self, c: &[f32]) -> Result<[f32; 4], Error> {
        let v = self.map(c);
        if v[0].is_nan() || v[1].is_nan() || !v[3].is_finite() || !c[3].is_finite() {
            return Err(Error::WorldTooLarge);
        }
        Ok(v)
    }

    /// Clips triangle `c` (clip space) against the five planes (Sutherland-Hodgman), `out` the triangle's outcodes
    /// or'ed. [`Error::WorldTooLarge`] when a distance overflows f32.
    pub(crate) fn clip(&self, c: &[[f32; 4]; 3], out: u8) -> Result<Poly, Error> {
        let mut poly = Poly::new();
        for (k, v) in c.iter().enumerate() {
            let mut pv = [0.0; 7];
            pv[..4].copy_from_slice(v);
            pv[4 + k] = 1.0;
            let _ = poly.push(pv);
        }
        for p in 0..5 {
            if out & (1 << p) == 0 {
                continue;
            }
            let mut next = Poly::new();
            let n = poly.len();
            for k in 0..n {
                let (a, b) = (&poly[k], &poly[(k + 1) % n]);
                let (da, db) = (self.dist(p, a), self.dist(p, b));
                if !(da.is_finite() && db.is_finite()) {
                    return Err(Error::WorldTooLarge);
                }
                if da >= 0.0 {
                    let _ = next.push(*a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    let t = da / (da - db);
                    let _ = next.push(core::array::from_fn(|i| a[i] + t * (b[i] - a[i])));
                }
            }
            if next.len() < 3 {
                return Ok(Poly::new());
            }
            poly = next;
        }
        // Every vertex must map to a drawable one (an interpolation after the last plane can overflow).
        for v in poly.iter() {
            self.map_checked(v)?;
        }
        Ok(poly)
    }
}

/// `[x, y, z, 1] * m`; `Err(NonFinite)` for a non-finite input, `Err(WorldTooLarge)` when the product overflows.
#[inline]
pub(crate) fn to_clip(m: &Mat4, q: &[f32; 3]) -> Result<[f32; 4], Error> {
    if !q.iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite);
    }
    let c: [f32; 4] = core::array::from_fn(|i| {
        q[0] * m.0[0][i] + q[1] * m.0[1][i] + q[2] * m.0[2][i] + m.0[3][i]
    });
    if c.iter().all(|v| v.is_finite()) {
        Ok(c)
    } else {
        Err(Error::WorldTooLarge)
    }
}

/// Checks a matrix.
pub(crate) fn check_matrix(m: &Mat4) -> Result<(), Error> {
    if m.0.iter().flatten().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite)
    }
}

/// The fan triangle `(0, k, k + 1)` of a clipped polygon as vertices, their colours from `color` (given the
/// barycentric weights of the source triangle's vertices).
pub(crate) fn fan<C>(
    planes: &Planes,
    poly: &Poly,
    k: usize,
    color: &impl Fn([f32; 3]) -> C,
) -> [Vertex<C>; 3] {
    [0, k, k + 1].map(|i| {
        let pv = &poly[i];
        let [x, y, z, rhw] = planes.map(pv);
        Vertex {
            x,
            y,
            z,
            rhw,
            color: color([pv[4], pv[5], pv[6]]),
        }
    })
}

impl<R: WSpan> Rasterizer<R> {
    /// Transforms, clips and maps a world-space triangle: the clipped polygon, empty when nothing is left.
    fn clip_world(
        &self,
        m: &Mat4,
        vp: &Viewport,
        p: &[[f32; 3]; 3],
    ) -> Result<(Planes, Poly), Error> {
        check_matrix(m)?;
        let planes = Planes::new(self.state.range.near(), vp)?;
        let c = [to_clip(m, &p[0])?, to_clip(m, &p[1])?, to_clip(m, &p[2])?];
        let codes = c.map(|v| planes.outcode(&v));
        if codes[0] & codes[1] & codes[2] != 0 {
            return Ok((planes, Poly::new()));
        }
        Ok((planes, planes.clip(&c, codes[0] | codes[1] | codes[2])?))
    }

    /// Draws a world-space triangle (`p` as `[x, y, z]`, transformed as row vectors `[x, y, z, 1] * m`, `m` the
    /// world-to-clip matrix) with flat colour `color`, clipped as the module says, into `depth` (a buffer of any
    /// format, an `Option` of one, or [`NoDepth`](crate::NoDepth): as [`Rasterizer::draw`]), all in f32. Errors
    /// before anything is written: [`Error::NonFinite`] for a NaN or an infinity in `p`, `m` or `vp`,
    /// [`Error::WorldTooLarge`] when a transformed coordinate overflows f32 (any finite triangle whose clip
    /// coordinates stay below about `1e37` draws its visible part). A failing `target` is as [`Rasterizer::draw`]'s.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_world<'b, 'a: 'b, B: IntoDepth<'b, 'a>, D>(
        &mut self,
        target: &mut D,
        mut depth: B,
        m: &Mat4,
        vp: &Viewport,
        p: &[[f32; 3]; 3],
        color: D::Color,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let (planes, poly) = self.clip_world(m, vp, p)?;
        let mut stats = Stats::default();
        for k in 1..poly.len().saturating_sub(1) {
            let v = fan(&planes, &poly, k, &|_| color);
            stats += depth.draw_triangle(self, target, &v)?;
        }
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planes(near: f32) -> Planes {
        Planes::new(near, &Viewport::new(0.0, 0.0, 240.0, 240.0)).unwrap()
    }

    /// Each of `map_checked`'s four refusals on its own (the other three components drawable), and a drawable
    /// vertex accepted with `map`'s values.
    #[test]
    fn map_checked_refuses_each_undrawable_component_alone() {
        let p = planes(1.0);
        let good = [1.0, 2.0, 0.5, 4.0];
        assert_eq!(p.map_checked(&good), Ok(p.map(&good)));
        let bad = |c: [f32; 4], p: &Planes| {
            assert_eq!(p.map_checked(&c), Err(Error::WorldTooLarge), "{c:?}")
        };
        // x NaN only (y, w and rhw fine).
        bad([f32::NAN, 2.0, 0.5, 4.0], &p);
        // y NaN only.
        bad([1.0, f32::NAN, 0.5, 4.0], &p);
        // w NaN or -inf: map takes max(w, W_near) = W_near, so x, y and rhw are finite; only w tells.
        bad([1.0, 2.0, 0.5, f32::NAN], &p);
        bad([1.0, 2.0, 0.5, f32::NEG_INFINITY], &p);
        // w = +inf: rhw = 0 and x, y = 0 * x: finite, so again only w tells.
        bad([1.0, 2.0, 0.5, f32::INFINITY], &p);
        // rhw infinite only: W_near = 1e-40 (a subnormal), 1 / 1e-40 overflows; w is finite and x = y = 0.
        bad([0.0, 0.0, 0.5, 1e-40], &planes(1e-40));
        // A huge but finite w is drawable (rhw is a tiny positive normal number).
        let far = [0.0, 0.0, 0.5, 1e38];
        assert!(p.map_checked(&far).is_ok());
    }

    /// A distance that overflows at one vertex only refuses the triangle, even where the rest of the clip could go
    /// on: `a` has `w = 1e38`, inside every guard-band plane by an infinite distance (`k w` overflows); `c` is behind
    /// the eye and outside the near plane and three guard-band planes, so the polygon is clipped against them.
    #[test]
    fn a_distance_overflowing_at_one_vertex_is_world_too_large() {
        let p = planes(1.0);
        let c = [
            [0.0, 0.0, 0.0, 1e38],
            [1.0, 0.0, 0.0, 2.0],
            [-300.0, 0.0, 0.0, -1.0],
        ];
        let codes = c.map(|v| p.outcode(&v));
        assert_eq!(codes, [0, 0, 0b11011]);
        assert!((1..5).all(|k| p.dist(k, &c[0]) == f32::INFINITY));
        assert_eq!(
            p.clip(&c, codes[0] | codes[1] | codes[2]).err(),
            Some(Error::WorldTooLarge)
        );
        // The same triangle with a finite far vertex clips to a drawable polygon.
        let c = [[0.0, 0.0, 0.0, 1e3], c[1], c[2]];
        let poly = p
            .clip(&c, c.iter().fold(0, |o, v| o | p.outcode(v)))
            .unwrap();
        assert!(poly.len() >= 3 && poly.iter().all(|v| p.map_checked(v).is_ok()));
    }
}
