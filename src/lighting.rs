//! Lighting (feature `lighting`): a directional light and an ambient term, shading a mesh's colours once per frame
//! into caller storage, which the mesh draws then use ([`crate::mesh::Colors::PerFace`] for flat shading,
//! [`crate::mesh::Colors::PerVertex`] with [`crate::Rasterizer::draw_mesh_frame_gouraud`] for Gouraud shading, through
//! the perspective-correct colour path).
//!
//! Intensity `I = ambient + diffuse * max(0, n . l)`, clamped to `[0, 1]`, with `n` the unit normal after the model
//! matrix's upper 3x3 (a rotation, or a rotation with a uniform scale: normalised again after it) and `l` the unit
//! direction towards the light, in the same (world) space. Each 8-bit channel becomes `round(c * I)`. Normals are
//! normalised with [`crate::projection::sqrt`] (micromath's estimate refined by Newton steps to an f32 rounding or
//! two: micromath's own `sqrt` deviates by ~5%, which would show as banding on a smooth surface).

use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};

use crate::projection::{unit, Mat4};
use crate::Error;

/// A directional light with an ambient term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Direction towards the light (need not be unit length; not zero).
    pub direction: [f32; 3],
    /// Ambient intensity, `[0, 1]`.
    pub ambient: f32,
    /// Diffuse intensity, `[0, 1]`.
    pub diffuse: f32,
}

/// `v` through the upper 3x3 of `m` (row vectors).
fn rotate(m: &Mat4, v: [f32; 3]) -> [f32; 3] {
    core::array::from_fn(|c| v[0] * m.0[0][c] + v[1] * m.0[1][c] + v[2] * m.0[2][c])
}

impl Light {
    fn checked(&self) -> Result<[f32; 3], Error> {
        if !(self.direction.iter().all(|v| v.is_finite())
            && self.ambient.is_finite()
            && self.diffuse.is_finite())
        {
            return Err(Error::NonFinite);
        }
        unit(self.direction).ok_or(Error::NonFinite)
    }

    /// `base` lit by intensity `I` for object-space normal `n` under `model`.
    fn shade<C: From<Rgb888> + Into<Rgb888>>(
        &self,
        l: [f32; 3],
        model: &Mat4,
        n: [f32; 3],
        base: C,
    ) -> C {
        let i = match unit(rotate(model, n)) {
            Some(n) => {
                let d = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
                self.ambient + self.diffuse * d.max(0.0)
            }
            None => self.ambient,
        }
        .clamp(0.0, 1.0);
        let c: Rgb888 = base.into();
        let ch = |v: u8| (v as f32 * i + 0.5) as u8;
        C::from(Rgb888::new(ch(c.r()), ch(c.g()), ch(c.b())))
    }
}

/// Flat shading: face `k`'s colour `base(k)` lit by its geometric normal (`(p1 - p0) x (p2 - p0)`, outwards for a
/// mesh wound counter-clockwise seen from outside), written to `out[k]`. Errors: [`Error::IndexOutOfRange`] for an
/// index beyond `positions` or a short `out`, [`Error::NonFinite`] for a non-finite or zero light direction.
pub fn shade_faces<C: Copy + From<Rgb888> + Into<Rgb888>>(
    positions: &[[f32; 3]],
    indices: &[[u16; 3]],
    model: &Mat4,
    light: &Light,
    base: impl Fn(usize) -> C,
    out: &mut [C],
) -> Result<(), Error> {
    let l = light.checked()?;
    if out.len() < indices.len()
        || indices
            .iter()
            .flatten()
            .any(|&i| i as usize >= positions.len())
    {
        return Err(Error::IndexOutOfRange);
    }
    for (k, (t, o)) in indices.iter().zip(out.iter_mut()).enumerate() {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let (e1, e2) = (
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        );
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        *o = light.shade(l, model, n, base(k));
    }
    Ok(())
}

/// Gouraud shading: vertex `k`'s colour `base(k)` lit by its normal `normals[k]` (object space), written to `out[k]`
/// (draw with [`crate::mesh::Colors::PerVertex`] and [`crate::Rasterizer::draw_mesh_frame_gouraud`]). Errors:
/// [`Error::IndexOutOfRange`] for a short `out`, [`Error::NonFinite`] for a non-finite or zero light direction.
pub fn shade_vertices<C: Copy + From<Rgb888> + Into<Rgb888>>(
    normals: &[[f32; 3]],
    model: &Mat4,
    light: &Light,
    base: impl Fn(usize) -> C,
    out: &mut [C],
) -> Result<(), Error> {
    let l = light.checked()?;
    if out.len() < normals.len() {
        return Err(Error::IndexOutOfRange);
    }
    for (k, (n, o)) in normals.iter().zip(out.iter_mut()).enumerate() {
        *o = light.shade(l, model, *n, base(k));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics_core::pixelcolor::Rgb565;

    /// A face towards the light gets `ambient + diffuse`, one at 60 degrees `ambient + diffuse / 2`, one facing away
    /// only the ambient term; each channel `round(c * I)` of its 8-bit value (Rgb888 of the Rgb565 colour, then back).
    #[test]
    fn flat_intensities() {
        let light = Light {
            direction: [0.0, 0.0, 2.0],
            ambient: 0.2,
            diffuse: 0.8,
        };
        // three triangles in the z = 0 plane: counter-clockwise seen from +z (normal +z), clockwise (normal -z),
        // and one tilted to a normal at 60 degrees from +z
        let (s, c) = crate::projection::sin_cos(core::f32::consts::FRAC_PI_3);
        let pos = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, c, -s],
        ];
        let idx = [[0, 1, 2], [0, 2, 1], [0, 1, 3]];
        let mut out = [Rgb888::BLACK; 3];
        let white = |_| Rgb888::new(200, 100, 50);
        shade_faces(&pos, &idx, &Mat4::IDENTITY, &light, white, &mut out).unwrap();
        assert_eq!(out[0], Rgb888::new(200, 100, 50));
        assert_eq!(out[1], Rgb888::new(40, 20, 10));
        assert_eq!(out[2], Rgb888::new(120, 60, 30));
        // the model's rotation turns the normals: rotated by pi about x, face 0 faces away
        shade_faces(
            &pos,
            &idx,
            &Mat4::rotation_x(core::f32::consts::PI),
            &light,
            white,
            &mut out,
        )
        .unwrap();
        assert_eq!(out[0], Rgb888::new(40, 20, 10));
        let mut short = [Rgb565::BLACK; 2];
        assert_eq!(
            shade_faces(
                &pos,
                &idx,
                &Mat4::IDENTITY,
                &light,
                |_| Rgb565::RED,
                &mut short
            ),
            Err(Error::IndexOutOfRange)
        );
        let dark = Light {
            direction: [0.0; 3],
            ..light
        };
        assert_eq!(
            shade_vertices(
                &[[0.0, 0.0, 1.0]],
                &Mat4::IDENTITY,
                &dark,
                |_| Rgb565::RED,
                &mut short
            ),
            Err(Error::NonFinite)
        );
        let mut v = [Rgb888::BLACK; 1];
        shade_vertices(&[[0.0, 0.0, 5.0]], &Mat4::IDENTITY, &light, white, &mut v).unwrap();
        assert_eq!(v[0], Rgb888::new(200, 100, 50));
    }
}
