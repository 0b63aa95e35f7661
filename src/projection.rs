//! Projection matrices and the W planes, as in Rogers, "W-Buffering in Direct3D" (NVIDIA) ("W-Buffering in Direct3D").
//! Matrices are row-major and apply to row vectors, `v' = v * M`, as in the seeds: `m[r][c]` is Direct3D's
//! `_rc` with both indices from 0, so `_34` is `m[2][3]`.

use crate::Error;

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

/// `sin` and `cos` of `x` in `[-4, 4]` by their Taylor series in f64 (terms to `x^25`: error below `1e-12`), so
/// `core` needs no float library.
fn sin_cos(x: f64) -> (f64, f64) {
    let (mut s, mut c, mut term_s, mut term_c) = (0.0, 0.0, x, 1.0);
    for k in 0..13 {
        s += term_s;
        c += term_c;
        let (a, b) = ((2 * k + 2) as f64, (2 * k + 3) as f64);
        term_s *= -x * x / (a * b);
        term_c *= -x * x / ((2 * k + 1) as f64 * a);
    }
    (s, c)
}

/// `D3DUtil_SetProjectionMatrix` (Rogers): `_11 = cos(fov/2) * aspect`, `_22 = cos(fov/2)`,
/// `_33 = Q = far sin(fov/2) / (far - near)`, `_34 = sin(fov/2)`, `_43 = -Q near`. Its `E_INVALIDARG` when
/// `far - near < 0.01` is [`Error::InvalidDepthRange`]; a field of view outside `(0, pi)` or a non-finite input is
/// [`Error::NonFinite`]. (This matrix has `W = z sin(fov/2)`: its W planes are `near sin`, `far sin`, and it is not
/// W-friendly in Dunlop's "Using W-Buffers" sense.)
pub fn perspective(fov: f32, aspect: f32, near: f32, far: f32) -> Result<Mat4, Error> {
    if !(fov.is_finite() && aspect.is_finite() && near.is_finite() && far.is_finite()) {
        return Err(Error::NonFinite);
    }
    if far - near < 0.01 {
        return Err(Error::InvalidDepthRange);
    }
    if fov <= 0.0 || fov as f64 >= core::f64::consts::PI {
        return Err(Error::NonFinite);
    }
    let (sin, cos) = sin_cos(fov as f64 / 2.0);
    let (sin, cos) = (sin as f32, cos as f32);
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
    let (m33, m34, m43, m44) = (
        m.at(3, 3) as f64,
        m.at(3, 4) as f64,
        m.at(4, 3) as f64,
        m.at(4, 4) as f64,
    );
    let near = m44 - m43 / m33 * m34;
    let far = (m44 - m43) / (m33 - m34) * m34 + m44;
    let (near, far) = (near as f32, far as f32);
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

    /// D3DUtil_SetProjectionMatrix's W planes are `near sin(fov/2)` and `far sin(fov/2)` (derived in `perspective`'s
    /// doc), to a few f32 roundings scaled by `far / (far - near)`.
    #[test]
    fn perspective_w_planes_and_error() {
        for (fov, n, f) in [
            (1.0f32, 1.0f32, 100.0f32),
            (1.5, 10.0, 1000.0),
            (0.7, 0.1, 50.0),
        ] {
            let m = perspective(fov, 4.0 / 3.0, n, f).unwrap();
            let s = sin_cos(fov as f64 / 2.0).0 as f32;
            let (wn, wf) = w_planes(&m).unwrap();
            assert!(close(wn, n * s, 8.0), "{wn} vs {}", n * s);
            assert!(
                close(wf, f * s, 8.0 * f / (f - n) * (f / n)),
                "{wf} vs {}",
                f * s
            );
            assert!(!is_w_friendly(&m));
        }
        assert_eq!(
            perspective(1.0, 1.0, 1.0, 1.009),
            Err(Error::InvalidDepthRange)
        );
        assert!(perspective(1.0, 1.0, 1.0, 1.011).is_ok());
        assert_eq!(perspective(f32::NAN, 1.0, 1.0, 10.0), Err(Error::NonFinite));
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

    #[test]
    fn series_sin_cos() {
        for k in 0..=300 {
            let x = -3.2 + k as f64 * 0.0213;
            let (s, c) = sin_cos(x);
            assert!(
                (s - x.sin()).abs() < 1e-12 && (c - x.cos()).abs() < 1e-12,
                "{x}"
            );
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
