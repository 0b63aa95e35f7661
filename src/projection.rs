//! Projection matrices and the W planes, as in Rogers, "W-Buffering in Direct3D" (NVIDIA) ("W-Buffering in Direct3D").
//! Matrices are row-major and apply to row vectors, `v' = v * M`, as in the seeds: `m[r][c]` is Direct3D's
//! `_rc` with both indices from 0, so `_34` is `m[2][3]`.

use crate::{Error, RenderState};

/// A 4x4 matrix for row vectors (`v * M`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat4(pub [[f32; 4]; 4]);

impl Mat4 {
    /// The identity.
    pub const IDENTITY: Mat4 = Mat4([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]);
    /// Direct3D's `_rc` (1-based, as the seeds write it).
    pub fn at(&self, r: usize, c: usize) -> f32 {
        self.0[r - 1][c - 1]
    }
    /// `v * M`.
    pub fn transform(&self, v: [f32; 4]) -> [f32; 4] {
        let mut out = [0.0; 4];
        for (c, o) in out.iter_mut().enumerate() {
            *o = (0..4).map(|r| v[r] * self.0[r][c]).sum();
        }
        out
    }
    /// `self * rhs` (apply `self` first, then `rhs`).
    pub fn then(&self, rhs: &Mat4) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = (0..4).map(|k| self.0[r][k] * rhs.0[k][c]).sum();
            }
        }
        Mat4(m)
    }
}

/// `sin` and `cos` of `x` in f32, for `|x| <= 6000` (beyond, the argument reduction loses bits and the result is only
/// bounded by 1; NaN for a NaN or an infinity): the argument is reduced by `pi/2` in three parts (Cody and Waite), then Taylor polynomials to `r^9`
/// and `r^10` on `|r| <= pi/4` (truncation below `2e-9`). Error below `4e-7` absolute (five f32 roundings of terms
/// at most 1, `5 * 2^-24 = 3e-7`, plus the truncation), checked against f64 in the tests. micromath's `sin`/`cos`
/// document an error of 0.002: too coarse for a projection's planes or a rotation that a test compares with f64.
pub fn sin_cos(x: f32) -> (f32, f32) {
    // pi/2 = P1 + P2 + P3 (Cody and Waite), P1 and P2 short enough that k * P1 and k * P2 are exact for k < 2^12.
    const P1: f32 = 1.570_312_5; // 0x3fc90000
    const P2: f32 = f32::from_bits(0x39fd_a000); // 4.837513e-4
    const P3: f32 = f32::from_bits(0x33a2_2169); // 7.54979e-8
    let k = {
        let q = x * core::f32::consts::FRAC_2_PI;
        // round half away from zero, without `f32::round` (std)
        let r = if q >= 0.0 { q + 0.5 } else { q - 0.5 };
        if !r.is_finite() {
            return (f32::NAN, f32::NAN);
        }
        r as i32 // saturates beyond 2^31 (x beyond 3e9, where the reduction below no longer reaches pi/4)
    };
    let kf = k as f32;
    // Within |pi/4| plus a rounding wherever the result is accurate; the clamp only bounds the polynomials (and so
    // the result, by 1) where the reduction has lost its bits. (A fuzz finding: sin_cos(f32::MAX) gave inf.)
    let r = (((x - kf * P1) - kf * P2) - kf * P3).clamp(-0.786, 0.786);
    let r2 = r * r;
    let s =
        r * (1.0 + r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 / 362_880.0))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0 - r2 / 3_628_800.0))));
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `sqrt(x)` for `x >= 0` in f32: micromath's estimate (a shift of the bits, documented deviation ~5%) refined by
/// three Newton steps, each of which squares the relative error (`0.05 -> 1.3e-3 -> 7.8e-7 -> 3e-13`), so the
/// result is within an f32 rounding or two. 0 for `x <= 0` or NaN.
pub fn sqrt(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    let mut y = micromath::F32(x).sqrt().0;
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y
}

fn sub3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// `a / |a|`, or `None` for a zero or non-finite length.
pub(crate) fn unit(a: [f32; 3]) -> Option<[f32; 3]> {
    let n = sqrt(dot3(a, a));
    (n > 0.0 && n.is_finite()).then(|| a.map(|c| c / n))
}

impl Mat4 {
    /// Translation by `t`.
    pub fn translation(t: [f32; 3]) -> Mat4 {
        let mut m = Mat4::IDENTITY;
        m.0[3] = [t[0], t[1], t[2], 1.0];
        m
    }
    /// Scale by `s` along each axis.
    pub fn scale(s: [f32; 3]) -> Mat4 {
        let mut m = Mat4::IDENTITY;
        m.0[0][0] = s[0];
        m.0[1][1] = s[1];
        m.0[2][2] = s[2];
        m
    }
    /// Rotation by `a` radians about the x axis, counter-clockwise seen from `+x` (right-handed):
    /// `y' = y cos a - z sin a`, `z' = y sin a + z cos a`. `sin` and `cos` by [`sin_cos`].
    pub fn rotation_x(a: f32) -> Mat4 {
        let (s, c) = sin_cos(a);
        let mut m = Mat4::IDENTITY;
        m.0[1][1] = c;
        m.0[1][2] = s;
        m.0[2][1] = -s;
        m.0[2][2] = c;
        m
    }
    /// Rotation by `a` radians about the y axis (right-handed): `x' = x cos a + z sin a`, `z' = -x sin a + z cos a`.
    pub fn rotation_y(a: f32) -> Mat4 {
        let (s, c) = sin_cos(a);
        let mut m = Mat4::IDENTITY;
        m.0[0][0] = c;
        m.0[0][2] = -s;
        m.0[2][0] = s;
        m.0[2][2] = c;
        m
    }
    /// Rotation by `a` radians about the z axis (right-handed): `x' = x cos a - y sin a`, `y' = x sin a + y cos a`.
    pub fn rotation_z(a: f32) -> Mat4 {
        let (s, c) = sin_cos(a);
        let mut m = Mat4::IDENTITY;
        m.0[0][0] = c;
        m.0[0][1] = s;
        m.0[1][0] = -s;
        m.0[1][1] = c;
        m
    }
    /// The view matrix of an eye at `eye` looking at `target`, `up` giving the screen's up direction: eye space has
    /// x to the right, y up and z (the eye depth, W after [`perspective`]) along the view direction. Works in a
    /// right-handed world (the usual one: a mesh wound counter-clockwise seen from outside shows its front faces
    /// counter-clockwise on screen, and [`Cull::Cw`](crate::Cull::Cw) drops the back faces).
    /// [`Error::InvalidCamera`] when `eye == target` or `up` is parallel to the view direction; [`Error::NonFinite`]
    /// for a NaN or an infinity; [`Error::WorldTooLarge`] when the eye is so far out (near `f32::MAX`) that the
    /// translation overflows f32.
    pub fn look_at(eye: [f32; 3], target: [f32; 3], up: [f32; 3]) -> Result<Mat4, Error> {
        if !eye.iter().chain(&target).chain(&up).all(|v| v.is_finite()) {
            return Err(Error::NonFinite);
        }
        let f = unit(sub3(target, eye)).ok_or(Error::InvalidCamera)?;
        let r = unit(cross3(f, up)).ok_or(Error::InvalidCamera)?;
        let u = cross3(r, f);
        let t = [-dot3(eye, r), -dot3(eye, u), -dot3(eye, f)];
        // (A fuzz finding: an eye at 3e38 gave an infinite translation.)
        if !t.iter().all(|v| v.is_finite()) {
            return Err(Error::WorldTooLarge);
        }
        Ok(Mat4([
            [r[0], u[0], f[0], 0.0],
            [r[1], u[1], f[1], 0.0],
            [r[2], u[2], f[2], 0.0],
            [t[0], t[1], t[2], 1.0],
        ]))
    }
}

/// `a * b`: apply `a`, then `b` (row vectors: `v * (a * b) = (v * a) * b`), as [`Mat4::then`].
impl core::ops::Mul for Mat4 {
    type Output = Mat4;
    fn mul(self, rhs: Mat4) -> Mat4 {
        self.then(&rhs)
    }
}

/// A W-friendly perspective projection and the depth planes it was built with, so a [`RenderState`] taken from it
/// cannot disagree with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perspective {
    /// Eye space to clip space (row vectors): `w` out equals eye depth `z` in.
    pub matrix: Mat4,
    /// `W_near`: the near clip plane, in eye depth.
    pub near: f32,
    /// `W_far`: the far plane, in eye depth.
    pub far: f32,
}

impl Perspective {
    /// The render state for this projection: depth range `[near, far]`, `Less`, depth write, back faces of a
    /// counter-clockwise mesh culled ([`Cull::Cw`](crate::Cull::Cw), see [`Mat4::look_at`]).
    pub fn render_state(&self) -> Result<RenderState, Error> {
        let mut s = RenderState::new(self.near, self.far)?;
        s.cull = crate::Cull::Cw;
        Ok(s)
    }
}

/// A W-friendly perspective (Dunlop, "Using W-Buffers": fourth column `[0, 0, 1, 0]`, so clip `w` is the eye
/// depth): `fov_y` the vertical field of view in radians, in `(0, pi)`; `aspect` = width / height (4/3 for
/// 320 x 240), as OpenGL's `gluPerspective` and most libraries take it; `near` and `far` the eye depths of the
/// planes. `x/w` and `y/w` are in `[-1, 1]` across the field of view and `z/w` in `[0, 1]` from near to far.
/// `cot(fov_y / 2)` by [`sin_cos`] (4e-7), not micromath (0.002). Errors: [`Error::NonFinite`] for NaN or
/// infinity, [`Error::InvalidCamera`] for a field of view outside `(0, pi)` (degrees, say) or `aspect <= 0`,
/// [`Error::InvalidDepthRange`] as [`RenderState::new`].
pub fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Result<Perspective, Error> {
    if !(fov_y.is_finite() && aspect.is_finite() && near.is_finite() && far.is_finite()) {
        return Err(Error::NonFinite);
    }
    if !(fov_y > 0.0 && fov_y < core::f32::consts::PI && aspect > 0.0) {
        return Err(Error::InvalidCamera);
    }
    crate::DepthRange::new(near, far)?;
    let (s, c) = sin_cos(fov_y * 0.5);
    let cot = c / s;
    let q = far / (far - near);
    Ok(Perspective {
        matrix: Mat4([
            [cot / aspect, 0.0, 0.0, 0.0],
            [0.0, cot, 0.0, 0.0],
            [0.0, 0.0, q, 1.0],
            [0.0, 0.0, -q * near, 0.0],
        ]),
        near,
        far,
    })
}

/// A camera: where the eye is and its projection. [`Camera::matrix`] takes world space to clip space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World to eye space ([`Mat4::look_at`]).
    pub view: Mat4,
    /// Eye to clip space.
    pub projection: Perspective,
}

impl Camera {
    /// An eye at `eye` looking at `target` (`up` up) through [`perspective`]`(fov_y, aspect, near, far)`.
    pub fn look_at(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fov_y: f32,
        aspect: f32,
        near: f32,
        far: f32,
    ) -> Result<Camera, Error> {
        Ok(Camera {
            view: Mat4::look_at(eye, target, up)?,
            projection: perspective(fov_y, aspect, near, far)?,
        })
    }
    /// World to clip space: `view * projection`.
    pub fn matrix(&self) -> Mat4 {
        self.view * self.projection.matrix
    }
    /// `model`, then this camera: object space to clip space.
    pub fn model_matrix(&self, model: &Mat4) -> Mat4 {
        *model * self.matrix()
    }
    /// [`Perspective::render_state`].
    pub fn render_state(&self) -> Result<RenderState, Error> {
        self.projection.render_state()
    }
}

/// `D3DUtil_SetProjectionMatrix` (Rogers, "W-Buffering in Direct3D"), kept under its own name: `_11 = cos(fov/2) * aspect`,
/// `_22 = cos(fov/2)`, `_33 = Q = far sin(fov/2) / (far - near)`, `_34 = sin(fov/2)`, `_43 = -Q near`. Its `aspect` is
/// height / width (the seed's convention). Its `E_INVALIDARG` when `far - near < 0.01` is
/// [`Error::InvalidDepthRange`]; a field of view outside `(0, pi)` or a non-finite input is [`Error::NonFinite`].
/// (This matrix has `W = z sin(fov/2)`: its W planes are `near sin`, `far sin`, and it is not W-friendly in Dunlop's
/// "Using W-Buffers" sense: use [`perspective`] with a W-buffer.)
pub fn d3dutil_set_projection_matrix(
    fov: f32,
    aspect: f32,
    near: f32,
    far: f32,
) -> Result<Mat4, Error> {
    if !(fov.is_finite() && aspect.is_finite() && near.is_finite() && far.is_finite()) {
        return Err(Error::NonFinite);
    }
    if far - near < 0.01 {
        return Err(Error::InvalidDepthRange);
    }
    if !(fov > 0.0 && fov < core::f32::consts::PI) {
        return Err(Error::NonFinite);
    }
    let (sin, cos) = sin_cos(fov / 2.0);
    let q = far * sin / (far - near);
    let mut m = [[0.0f32; 4]; 4];
    m[0][0] = cos * aspect;
    m[1][1] = cos;
    m[2][2] = q;
    m[2][3] = sin;
    m[3][2] = -q * near;
    Ok(Mat4(m))
}

/// `W_near` and `W_far` of a projection matrix by Rogers's formulas:
/// `dvWNear = _44 - _43 / _33 * _34`, `dvWFar = (_44 - _43) / (_33 - _34) * _34 + _44`.
/// A matrix for which they are not finite, or do not give `0 < W_near < W_far`, is an error.
pub fn w_planes(m: &Mat4) -> Result<(f32, f32), Error> {
    let (m33, m34, m43, m44) = (m.at(3, 3), m.at(3, 4), m.at(4, 3), m.at(4, 4));
    let near = m44 - m43 / m33 * m34;
    let far = (m44 - m43) / (m33 - m34) * m34 + m44;
    if !(near.is_finite() && far.is_finite()) {
        return Err(Error::NonFinite);
    }
    if near <= 0.0 || far <= near {
        return Err(Error::InvalidDepthRange);
    }
    Ok((near, far))
}

/// The matrix Rogers's `set_wbuffer_planes` builds (identity but `_33 = W_near / (W_far - W_near) + 1`,
/// `_34 = 1`, `_43 = 0`, `_44 = W_near`), whose W planes are `(W_near, W_far)`. Its error when `W_far <= W_near`
/// (the seed returns 1), and, since W-buffering needs it, when `W_near <= 0`.
pub fn wbuffer_planes_matrix(w_near: f32, w_far: f32) -> Result<Mat4, Error> {
    if !(w_near.is_finite() && w_far.is_finite()) {
        return Err(Error::NonFinite);
    }
    if w_far <= w_near || w_near <= 0.0 {
        return Err(Error::InvalidDepthRange);
    }
    let mut m = Mat4::IDENTITY;
    m.0[3][2] = 0.0;
    m.0[2][3] = 1.0;
    m.0[3][3] = w_near;
    m.0[2][2] = w_near / (w_far - w_near) + 1.0;
    Ok(m)
}

/// Seed Dunlop's "Using W-Buffers" W-friendly test: the fourth column is `[0, 0, 1, 0]`, so the output W equals the
/// input z (eye depth). Other matrices give a W that is only proportional to depth (or not at all).
pub fn is_w_friendly(m: &Mat4) -> bool {
    m.at(1, 4) == 0.0 && m.at(2, 4) == 0.0 && m.at(3, 4) == 1.0 && m.at(4, 4) == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, ulps: f32) -> bool {
        (a - b).abs() <= ulps * f32::EPSILON * b.abs().max(1e-30)
    }

    /// `set_wbuffer_planes` then Rogers's formulas give the planes back: `_44 - 0 = W_near` exactly, and
    /// `W_near / (_33 - 1) + W_near = W_far` with `_33` rounded to f32 once and a few f64 operations: within a few
    /// f32 ulps scaled by `W_far / W_near` (the relative error of `_33 - 1` grows with it).
    #[test]
    fn wbuffer_planes_round_trip() {
        for (n, f) in [
            (1.0f32, 10.0f32),
            (10.0, 1000.0),
            (10.0, 10000.0),
            (0.5, 3.0),
            (1e-3, 1.0),
            (100.0, 1e7),
        ] {
            let m = wbuffer_planes_matrix(n, f).unwrap();
            assert!(
                !is_w_friendly(&m),
                "Rogers's matrix keeps _44 = W_near: not [0,0,1,0]"
            );
            let (wn, wf) = w_planes(&m).unwrap();
            assert_eq!(wn, n);
            assert!(close(wf, f, 4.0 * (f / n).max(1.0)), "{n} {f}: {wf}");
        }
    }

    /// D3DUtil_SetProjectionMatrix's W planes are `near sin(fov/2)` and `far sin(fov/2)` (derived in its doc), to a
    /// few f32 roundings scaled by `far / (far - near)` and, for the far plane, `far / near` (`_33 - _34` cancels).
    #[test]
    fn d3dutil_w_planes_and_error() {
        for (fov, n, f) in [
            (1.0f32, 1.0f32, 100.0f32),
            (1.5, 10.0, 1000.0),
            (0.7, 0.1, 50.0),
        ] {
            let m = d3dutil_set_projection_matrix(fov, 4.0 / 3.0, n, f).unwrap();
            let s = (fov as f64 / 2.0).sin() as f32;
            let (wn, wf) = w_planes(&m).unwrap();
            assert!(close(wn, n * s, 8.0 * f / (f - n)), "{wn} vs {}", n * s);
            assert!(
                close(wf, f * s, 8.0 * f / (f - n) * (f / n)),
                "{wf} vs {}",
                f * s
            );
            assert!(!is_w_friendly(&m));
        }
        assert_eq!(
            d3dutil_set_projection_matrix(1.0, 1.0, 1.0, 1.009),
            Err(Error::InvalidDepthRange)
        );
        assert!(d3dutil_set_projection_matrix(1.0, 1.0, 1.0, 1.011).is_ok());
        assert_eq!(
            d3dutil_set_projection_matrix(f32::NAN, 1.0, 1.0, 10.0),
            Err(Error::NonFinite)
        );
    }

    /// The W-friendly perspective: `w` out is eye depth exactly (`_34 = 1`, `_44 = 0`), Rogers's formulas give its
    /// planes back (`W_near = q n / q` to two roundings, `W_far` to a few scaled by `far / near`), its render state
    /// has the same planes, and a field of view in degrees or a bad aspect is refused.
    #[test]
    fn w_friendly_perspective() {
        for (fov, a, n, f) in [
            (core::f32::consts::FRAC_PI_3, 4.0 / 3.0, 0.5f32, 100.0f32),
            (1.5, 1.0, 10.0, 1000.0),
            (0.3, 2.0, 0.1, 50.0),
        ] {
            let p = perspective(fov, a, n, f).unwrap();
            assert!(is_w_friendly(&p.matrix));
            let (wn, wf) = w_planes(&p.matrix).unwrap();
            assert!(close(wn, n, 4.0), "{wn} vs {n}");
            assert!(close(wf, f, 8.0 * f / n), "{wf} vs {f}");
            let st = p.render_state().unwrap();
            assert_eq!((st.range.near(), st.range.far()), (n, f));
            // a point on the top edge of the field of view at depth 7 lands on y/w = 1, on the right edge x/w = 1
            let t = (fov as f64 / 2.0).tan();
            let top = p.matrix.transform([0.0, (7.0 * t) as f32, 7.0, 1.0]);
            let right = p
                .matrix
                .transform([(7.0 * t * a as f64) as f32, 0.0, 7.0, 1.0]);
            assert_eq!(top[3], 7.0);
            assert!(
                (top[1] / top[3] - 1.0).abs() < 2e-6 && (right[0] / right[3] - 1.0).abs() < 2e-6
            );
        }
        assert_eq!(perspective(60.0, 1.0, 1.0, 10.0), Err(Error::InvalidCamera));
        assert_eq!(perspective(1.0, 0.0, 1.0, 10.0), Err(Error::InvalidCamera));
        assert_eq!(
            perspective(1.0, 1.0, 10.0, 1.0),
            Err(Error::InvalidDepthRange)
        );
        assert_eq!(
            perspective(1.0, f32::INFINITY, 1.0, 10.0),
            Err(Error::NonFinite)
        );
    }

    /// look_at: the eye maps to the origin, the target to `(0, 0, distance)`, `up` to `+y`; rotations are
    /// right-handed and orthonormal to f32 rounding; `*` applies left then right.
    #[test]
    fn camera_and_transforms() {
        let v = Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap();
        assert_eq!(v.transform([0.0, 0.0, 3.0, 1.0]), [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(v.transform([0.0, 0.0, 0.0, 1.0]), [0.0, 0.0, 3.0, 1.0]);
        assert_eq!(v.transform([1.0, 1.0, 0.0, 1.0]), [1.0, 1.0, 3.0, 1.0]);
        let v2 = Mat4::look_at([1.0, 2.0, 3.0], [-4.0, 0.5, 2.0], [0.0, 1.0, 0.0]).unwrap();
        let d = v2.transform([-4.0, 0.5, 2.0, 1.0]);
        let dist = (25.0f64 + 2.25 + 1.0).sqrt();
        assert!(d[0].abs() < 1e-6 && d[1].abs() < 1e-6 && (d[2] as f64 - dist).abs() < 1e-5);
        assert_eq!(
            Mat4::look_at([1.0; 3], [1.0; 3], [0.0, 1.0, 0.0]),
            Err(Error::InvalidCamera)
        );
        assert_eq!(
            Mat4::look_at([0.0; 3], [0.0, 5.0, 0.0], [0.0, 1.0, 0.0]),
            Err(Error::InvalidCamera)
        );
        let q = core::f32::consts::FRAC_PI_2;
        let close3 = |a: [f32; 4], b: [f32; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close3(
            Mat4::rotation_z(q).transform([1.0, 0.0, 0.0, 1.0]),
            [0.0, 1.0, 0.0, 1.0]
        ));
        assert!(close3(
            Mat4::rotation_x(q).transform([0.0, 1.0, 0.0, 1.0]),
            [0.0, 0.0, 1.0, 1.0]
        ));
        assert!(close3(
            Mat4::rotation_y(q).transform([0.0, 0.0, 1.0, 1.0]),
            [1.0, 0.0, 0.0, 1.0]
        ));
        let m = Mat4::scale([2.0, 3.0, 4.0]) * Mat4::translation([1.0, 1.0, 1.0]);
        assert_eq!(m.transform([1.0, 1.0, 1.0, 1.0]), [3.0, 4.0, 5.0, 1.0]);
        let c = Camera::look_at(
            [0.0, 0.0, 3.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            1.0,
            1.0,
            0.5,
            100.0,
        )
        .unwrap();
        assert_eq!(c.matrix().transform([0.0, 0.0, 1.0, 1.0])[3], 2.0);
        assert_eq!(c.render_state().unwrap().cull, crate::Cull::Cw);
    }

    /// The rotations move every point as their docs write it, for random angles and points, against f64 with the
    /// angle's `sin` and `cos` (within [`sin_cos`]'s 4e-7, and the f32 products' and sums' roundings: 2e-6 at the
    /// points' magnitude, below 2).
    #[test]
    fn rotations_move_points_as_documented() {
        let mut rnd = crate::xorshift(0x0707_A7E0_0000_0001);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        for _ in 0..2000 {
            let a = (unit() * 20.0 - 10.0) as f32;
            let (s, c) = ((a as f64).sin(), (a as f64).cos());
            let p = [0, 1, 2].map(|_| (unit() * 4.0 - 2.0) as f32);
            let (x, y, z) = (p[0] as f64, p[1] as f64, p[2] as f64);
            let cases = [
                (Mat4::rotation_x(a), [x, y * c - z * s, y * s + z * c]),
                (Mat4::rotation_y(a), [x * c + z * s, y, -x * s + z * c]),
                (Mat4::rotation_z(a), [x * c - y * s, x * s + y * c, z]),
            ];
            for (m, want) in cases {
                let got = m.transform([p[0], p[1], p[2], 1.0]);
                for k in 0..3 {
                    assert!(
                        (got[k] as f64 - want[k]).abs() < 2e-6,
                        "{a} {p:?}: {got:?} {want:?}"
                    );
                }
                assert_eq!(got[3], 1.0);
            }
        }
    }

    /// `look_at` for random eyes, targets and up directions: its rows' `r`, `u`, `f` (the eye's right, up and
    /// forward in world space) are orthonormal within 1e-6, `f` along `target - eye`, `r = f x up` normalised (right
    /// of the view in a right-handed world), `u` in the plane of `up` and `f` on `up`'s side; the eye maps to the
    /// origin, the target to `(0, 0, |target - eye|)`, and a step right of the eye (along `r`) to `x > 0`.
    #[test]
    fn look_at_is_an_orthonormal_right_handed_view() {
        let mut rnd = crate::xorshift(0x1007_A700_0000_0001);
        let mut unit = move || (rnd() >> 11) as f32 / (1u64 << 53) as f32;
        let mut v3 = move |s: f32| [0, 1, 2].map(|_| (unit() * 2.0 - 1.0) * s);
        let f64s = |v: [f32; 3]| v.map(|c| c as f64);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let mut checked = 0;
        for _ in 0..2000 {
            let (eye, target, up) = (v3(10.0), v3(10.0), v3(1.0));
            let d = [0, 1, 2].map(|k| target[k] as f64 - eye[k] as f64);
            let (dn, un) = (dot(d, d).sqrt(), dot(f64s(up), f64s(up)).sqrt());
            // Well away from the refusals (eye at the target, up along the view).
            if dn < 0.1
                || cross(d, f64s(up)).iter().map(|c| c * c).sum::<f64>().sqrt() < 0.1 * dn * un
            {
                continue;
            }
            let m = Mat4::look_at(eye, target, up).unwrap();
            let col = |c: usize| [0, 1, 2].map(|r| m.0[r][c] as f64);
            let (r, u, f) = (col(0), col(1), col(2));
            for (a, b, want) in [
                (r, r, 1.0),
                (u, u, 1.0),
                (f, f, 1.0),
                (r, u, 0.0),
                (r, f, 0.0),
                (u, f, 0.0),
            ] {
                assert!((dot(a, b) - want).abs() < 1e-6, "{eye:?} {target:?} {up:?}");
            }
            assert!((dot(f, d) / dn - 1.0).abs() < 1e-6);
            let fu = cross(f, f64s(up));
            let fu_n = dot(fu, fu).sqrt();
            assert!(
                (dot(r, fu) / fu_n - 1.0).abs() < 1e-6,
                "right = forward x up"
            );
            assert!(dot(u, f64s(up)) > 0.0 && dot(cross(r, u), f) < -1.0 + 1e-6);
            let e = m.transform([eye[0], eye[1], eye[2], 1.0]);
            let t = m.transform([target[0], target[1], target[2], 1.0]);
            assert!(e[..3].iter().all(|v| v.abs() < 1e-5), "{e:?}");
            assert!(t[0].abs() < 1e-5 && t[1].abs() < 1e-5 && (t[2] as f64 - dn).abs() < 1e-5 * dn);
            let right = [0, 1, 2].map(|k| eye[k] + r[k] as f32);
            assert!(m.transform([right[0], right[1], right[2], 1.0])[0] > 0.5);
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
    }

    /// `perspective`'s field of view is open at both ends, `(0, pi)`, and `aspect` must be positive.
    #[test]
    fn perspective_refuses_its_limits() {
        let pi = core::f32::consts::PI;
        for (fov, aspect) in [
            (0.0, 1.0),
            (-0.5, 1.0),
            (pi, 1.0),
            (4.0, 1.0),
            (1.0, 0.0),
            (1.0, -1.0),
        ] {
            assert_eq!(
                perspective(fov, aspect, 1.0, 10.0),
                Err(Error::InvalidCamera),
                "{fov} {aspect}"
            );
        }
        let below_pi = f32::from_bits(pi.to_bits() - 1);
        for (fov, aspect) in [
            (f32::MIN_POSITIVE, 1.0),
            (1e-3, 1.0),
            (below_pi, 1.0),
            (1.0, 1e-30),
        ] {
            let p = perspective(fov, aspect, 1.0, 10.0).unwrap();
            assert!(
                p.matrix.0.iter().flatten().all(|v| v.is_finite()),
                "{fov} {aspect}"
            );
        }
    }

    /// `D3DUtil_SetProjectionMatrix`'s five entries as its doc writes them, against f64 with the half angle's `sin`
    /// and `cos` (within [`sin_cos`]'s 4e-7 and a few f32 roundings: 2e-6 relative); its refusals: any non-finite
    /// argument or a field of view outside `(0, pi)` ([`Error::NonFinite`]), `far - near` below 0.01 (0.01 itself
    /// is accepted, as the seed's `< 0.01` test has it).
    #[test]
    fn d3dutil_entries_and_refusals() {
        let close = |a: f32, b: f64| (a as f64 - b).abs() <= 2e-6 * b.abs();
        for (fov, aspect, n, f) in [
            (1.0f32, 0.75f32, 1.0f32, 100.0f32),
            (2.5, 1.3, 0.5, 7.0),
            (0.2, 0.6, 3.0, 4.0),
        ] {
            let m = d3dutil_set_projection_matrix(fov, aspect, n, f).unwrap();
            let (sn, cs) = ((fov as f64 / 2.0).sin(), (fov as f64 / 2.0).cos());
            let q = f as f64 * sn / (f as f64 - n as f64);
            assert!(close(m.at(1, 1), cs * aspect as f64), "{m:?}");
            assert!(close(m.at(2, 2), cs) && close(m.at(3, 3), q) && close(m.at(3, 4), sn));
            assert!(close(m.at(4, 3), -q * n as f64));
            let zero = [
                (1, 2),
                (1, 3),
                (1, 4),
                (2, 1),
                (2, 3),
                (2, 4),
                (3, 1),
                (3, 2),
                (4, 1),
                (4, 2),
                (4, 4),
            ];
            assert!(zero.iter().all(|&(r, c)| m.at(r, c) == 0.0));
        }
        let ok = (1.0, 1.0, 1.0, 10.0);
        for k in 0..4 {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let mut a = [ok.0, ok.1, ok.2, ok.3];
                a[k] = bad;
                assert_eq!(
                    d3dutil_set_projection_matrix(a[0], a[1], a[2], a[3]),
                    Err(Error::NonFinite),
                    "{a:?}"
                );
            }
        }
        let pi = core::f32::consts::PI;
        for fov in [0.0, -1.0, pi, 3.5] {
            assert_eq!(
                d3dutil_set_projection_matrix(fov, 1.0, 1.0, 10.0),
                Err(Error::NonFinite),
                "{fov}"
            );
        }
        assert!(
            d3dutil_set_projection_matrix(f32::from_bits(pi.to_bits() - 1), 1.0, 1.0, 10.0).is_ok()
        );
        assert!(d3dutil_set_projection_matrix(1.0, 1.0, 0.0, 0.01).is_ok());
        let just_below = f32::from_bits(0.01f32.to_bits() - 1);
        assert_eq!(
            d3dutil_set_projection_matrix(1.0, 1.0, 0.0, just_below),
            Err(Error::InvalidDepthRange)
        );
    }

    /// `w_planes` refuses a matrix for which either plane is not finite, the other being finite: `_33 = 0` (the near
    /// plane infinite) and `_33 = _34` (the far plane infinite).
    #[test]
    fn w_planes_refuse_either_plane_infinite() {
        let mut m = Mat4::IDENTITY;
        (m.0[2][2], m.0[2][3], m.0[3][2], m.0[3][3]) = (0.0, 1.0, 1.0, 0.0); // near -inf, far 1
        assert_eq!(w_planes(&m), Err(Error::NonFinite));
        (m.0[2][2], m.0[2][3], m.0[3][2], m.0[3][3]) = (1.0, 1.0, -1.0, 0.0); // near 1, far inf
        assert_eq!(w_planes(&m), Err(Error::NonFinite));
    }

    /// `sqrt` within two f32 roundings of the true root.
    #[test]
    fn newton_sqrt() {
        for k in 1..2000 {
            let x = k as f32 * 0.37 + 1e-3 * k as f32 * k as f32;
            let e = ((sqrt(x) as f64 - (x as f64).sqrt()) / (x as f64).sqrt()).abs();
            assert!(e <= 2.0 * f32::EPSILON as f64, "{x}: {e}");
        }
        assert_eq!(sqrt(-1.0), 0.0);
        assert_eq!(sqrt(f32::NAN), 0.0);
    }

    #[test]
    fn bad_planes_are_errors() {
        assert_eq!(
            wbuffer_planes_matrix(10.0, 10.0),
            Err(Error::InvalidDepthRange)
        );
        assert_eq!(
            wbuffer_planes_matrix(10.0, 5.0),
            Err(Error::InvalidDepthRange)
        );
        assert_eq!(
            wbuffer_planes_matrix(0.0, 5.0),
            Err(Error::InvalidDepthRange)
        );
        assert_eq!(
            wbuffer_planes_matrix(-1.0, 5.0),
            Err(Error::InvalidDepthRange)
        );
        assert_eq!(wbuffer_planes_matrix(f32::NAN, 5.0), Err(Error::NonFinite));
        assert_eq!(w_planes(&Mat4::IDENTITY), Err(Error::InvalidDepthRange));
    }

    /// `sin_cos` within its documented 4e-7 of f64 over `[-100, 100]` densely and `[-6000, 6000]` sparsely.
    #[test]
    fn f32_sin_cos() {
        let mut worst = 0.0f64;
        for k in 0..=400_000 {
            let x = if k <= 200_000 {
                -100.0f32 + k as f32 * 0.001
            } else {
                -6000.0 + (k - 200_000) as f32 * 0.06
            };
            let (s, c) = sin_cos(x);
            let xd = x as f64;
            worst = worst
                .max((s as f64 - xd.sin()).abs())
                .max((c as f64 - xd.cos()).abs());
        }
        std::println!("sin_cos worst {worst:e} (bound 4e-7)");
        assert!(worst < 4e-7, "{worst}");
    }

    /// Beyond the accurate range every finite argument still gives values bounded by 1, and a non-finite one NaN
    /// (fuzz finding: `sin_cos(f32::MAX)` was `(inf, -inf)`).
    #[test]
    fn sin_cos_is_bounded_everywhere() {
        for x in [
            1.0e7f32,
            -3.3e9,
            1.0e20,
            f32::MAX,
            f32::MIN,
            2.0e38,
            8.0e6,
            -8.0e6,
        ] {
            let (s, c) = sin_cos(x);
            assert!(s.abs() <= 1.0 && c.abs() <= 1.0, "sin_cos({x}) = {s}, {c}");
        }
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan());
        }
    }

    #[test]
    fn row_vectors() {
        let m = wbuffer_planes_matrix(10.0, 1000.0).unwrap();
        // v * M: W out = z * _34 + w * _44
        let out = m.transform([0.0, 0.0, 50.0, 1.0]);
        assert_eq!(out[3], 50.0 + 10.0);
        assert_eq!(Mat4::IDENTITY.then(&m), m);
    }
}
