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

    /// Every bad input is an error and writes nothing: a non-finite or zero light direction, a non-finite ambient or
    /// diffuse term ([`Error::NonFinite`]); an index past the positions (the last valid one is `len - 1`) or an
    /// output shorter than the faces or normals ([`Error::IndexOutOfRange`]). Outputs exactly as long are fine.
    #[test]
    fn bad_input_is_an_error_and_writes_nothing() {
        let good = Light {
            direction: [0.0, 0.0, 1.0],
            ambient: 0.25,
            diffuse: 0.5,
        };
        let pos = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let blue = |_| Rgb888::new(0, 0, 200);
        let bad = [
            Light {
                direction: [f32::NAN, 0.0, 1.0],
                ..good
            },
            Light {
                direction: [0.0, f32::INFINITY, 1.0],
                ..good
            },
            Light {
                direction: [0.0; 3],
                ..good
            },
            Light {
                ambient: f32::NAN,
                ..good
            },
            Light {
                ambient: f32::INFINITY,
                ..good
            },
            Light {
                diffuse: f32::NAN,
                ..good
            },
            Light {
                diffuse: f32::NEG_INFINITY,
                ..good
            },
        ];
        for light in bad {
            let mut out = [Rgb888::WHITE; 3];
            let faces = shade_faces(&pos, &[[0, 1, 2]], &Mat4::IDENTITY, &light, blue, &mut out);
            let verts = shade_vertices(&pos, &Mat4::IDENTITY, &light, blue, &mut out);
            assert_eq!(
                (faces, verts),
                (Err(Error::NonFinite), Err(Error::NonFinite)),
                "{light:?}"
            );
            assert_eq!(out, [Rgb888::WHITE; 3]);
        }
        let mut out = [Rgb888::WHITE; 3];
        for idx in [[0, 1, 3], [3, 0, 1], [0, 9, 2]] {
            let r = shade_faces(
                &pos,
                &[[0, 1, 2], idx],
                &Mat4::IDENTITY,
                &good,
                blue,
                &mut out,
            );
            assert_eq!(r, Err(Error::IndexOutOfRange), "{idx:?}");
            assert_eq!(out, [Rgb888::WHITE; 3]);
        }
        let r = shade_vertices(&pos, &Mat4::IDENTITY, &good, blue, &mut out[..2]);
        assert_eq!(r, Err(Error::IndexOutOfRange));
        assert_eq!(out, [Rgb888::WHITE; 3]);
        // Exactly as long: every face and vertex written (the face towards the light: 0.75 of 200).
        shade_faces(
            &pos,
            &[[0, 1, 2]],
            &Mat4::IDENTITY,
            &good,
            blue,
            &mut out[..1],
        )
        .unwrap();
        assert_eq!(out[0], Rgb888::new(0, 0, 150));
        shade_vertices(&pos[..1], &Mat4::IDENTITY, &good, blue, &mut out[1..2]).unwrap();
        // A zero normal: the ambient term alone (0.25 of 200).
        assert_eq!(out[1], Rgb888::new(0, 0, 50));
    }

    /// The intensity in f64 from the same f32 inputs: `clamp(ambient + diffuse max(0, n' . l), 0, 1)` with `n'` the
    /// unit normal after the model's upper 3x3 (row vectors) and `l` the unit light direction; `ambient` alone for a
    /// zero normal.
    fn intensity_f64(model: &Mat4, n: [f64; 3], light: &Light) -> f64 {
        let unit = |v: [f64; 3]| {
            let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            (len > 0.0).then(|| v.map(|c| c / len))
        };
        let r: [f64; 3] =
            core::array::from_fn(|c| (0..3).map(|k| n[k] * model.0[k][c] as f64).sum());
        let l = unit(light.direction.map(|v| v as f64)).unwrap();
        let i = match unit(r) {
            Some(u) => {
                light.ambient as f64
                    + light.diffuse as f64 * (u[0] * l[0] + u[1] * l[1] + u[2] * l[2]).max(0.0)
            }
            None => light.ambient as f64,
        };
        i.clamp(0.0, 1.0)
    }

    /// Flat and Gouraud shading against [`intensity_f64`] for random models (rotations about all three axes with a
    /// uniform scale from 0.1 to 10), normals, faces, lights and colours, ambient terms from -0.2 to 1.2 (the clamp
    /// at both ends) and diffuse ones to 1: each channel is `round(c I)`, ties up.
    ///
    /// Bound: the f32 intensity is within `2^-16` of the f64 one (under 64 roundings of `2^-24` of unit-sized terms:
    /// the rotation 5, the normalisation 6 with the square root's two, the dot product 5, the intensity 2; a face's
    /// cross product 2 amplified by `1 / sin` of its smallest angle, at most 8 for the faces kept here), so `c I`
    /// moves by at most `255 2^-16 < 0.004`: the channel must equal `round(c I_f64)` wherever that is farther than
    /// 0.004 from a tie, and be within one of it everywhere.
    #[test]
    fn shading_matches_the_f64_intensity() {
        let mut rnd = crate::xorshift(0x116E_7000_0000_0001);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let (mut exact, mut near_tie, mut clamped) = (0u32, 0u32, [0u32; 2]);
        let mut check = |got: Rgb888, base: Rgb888, i: f64| {
            for (g, c) in [
                (got.r(), base.r()),
                (got.g(), base.g()),
                (got.b(), base.b()),
            ] {
                let v = c as f64 * i;
                let want = (v + 0.5).floor();
                if ((v + 0.5).fract() - 0.5).abs() < 0.5 - 0.004 {
                    assert_eq!(g as f64, want, "{c} x {i}");
                    exact += 1;
                } else {
                    assert!((g as f64 - v).abs() <= 1.0, "{c} x {i}");
                    near_tie += 1;
                }
            }
        };
        for _ in 0..2000 {
            let sc = 0.1 + unit() * 9.9;
            let model = Mat4::rotation_x(unit() * 6.3)
                * Mat4::rotation_y(unit() * 6.3)
                * Mat4::rotation_z(unit() * 6.3)
                * Mat4::scale([sc; 3]);
            let light = Light {
                direction: [0, 1, 2].map(|_| unit() * 2.0 - 1.0),
                ambient: unit() * 1.4 - 0.2,
                diffuse: unit(),
            };
            let mut v3 = || [0, 1, 2].map(|_| unit() * 2.0 - 1.0);
            let pos = [v3(), v3(), v3()];
            let normal = v3();
            let base = Rgb888::new((unit() * 255.0) as u8, (unit() * 255.0) as u8, 255);
            // Gouraud: the vertex normal as given.
            let mut out = [Rgb888::BLACK; 1];
            shade_vertices(&[normal], &model, &light, |_| base, &mut out).unwrap();
            let i = intensity_f64(&model, normal.map(|v| v as f64), &light);
            check(out[0], base, i);
            clamped[0] += u32::from(i == 0.0);
            clamped[1] += u32::from(i == 1.0);
            // Flat: the face's geometric normal, for faces whose smallest angle's sine is at least 1/8.
            let d = |a: [f32; 3], b: [f32; 3]| [0, 1, 2].map(|k| b[k] as f64 - a[k] as f64);
            let cross = |a: [f64; 3], b: [f64; 3]| {
                [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ]
            };
            let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let n = cross(d(pos[0], pos[1]), d(pos[0], pos[2]));
            let sin_min = [0, 1, 2]
                .map(|k| {
                    let (a, b, c) = (pos[k], pos[(k + 1) % 3], pos[(k + 2) % 3]);
                    len(n) / (len(d(a, b)) * len(d(a, c)))
                })
                .into_iter()
                .fold(1.0, f64::min);
            if sin_min < 0.125 {
                continue;
            }
            shade_faces(&pos, &[[0, 1, 2]], &model, &light, |_| base, &mut out).unwrap();
            check(out[0], base, intensity_f64(&model, n, &light));
        }
        assert!(
            exact > 10_000 && clamped.iter().all(|&n| n > 50),
            "{exact} {near_tie} {clamped:?}"
        );
    }

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
