//! The one error type of the crate.

use core::fmt;

/// Why a triangle, a render state or a buffer was refused. Nothing is written when one of these is returned, except
/// [`Error::Target`] (a colour target that failed part-way: see there).
#[non_exhaustive]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// A NaN or an infinity in a vertex field or a render-state value.
    NonFinite,
    /// `rhw <= 0` (or `-0.0`): the vertex is at or behind the eye, so `W = 1/rhw` is not a valid depth.
    RhwNotPositive,
    /// A vertex x or y outside the guard band `[-GUARD_BAND, GUARD_BAND]` pixels.
    OutOfGuardBand,
    /// `rhw * W_far` of a vertex is at or above [`crate::MAX_T`] (the vertex is `MAX_T` times nearer than the far plane, or more).
    DepthRange,
    /// `W_near <= 0`, `W_far <= W_near`, or `W_far / W_near` above [`crate::MAX_T`].
    InvalidDepthRange,
    /// A buffer whose length does not fit its use: a depth buffer's, packed depth buffer's or colour band's storage
    /// that does not match its width and height (or a zero size), or a mesh frame's vertex scratch or row bins shorter
    /// than the mesh ([`crate::Rasterizer::transform_mesh`], [`crate::Rasterizer::bin_mesh`]).
    BufferSize {
        /// Elements needed: what the width and height make, or the least length the mesh needs.
        expected: usize,
        /// Elements given.
        actual: usize,
    },
    /// The colour target returned an error (its own error value is not kept: this enum has no type parameter).
    /// The draw stops at the failing run, and leaves: every row above it drawn completely (colour and depth); in its
    /// row, the depth codes of the pixels walked before the failing run was written (a prefix of the span) and the
    /// colour of the runs written before it (plus whatever the target wrote of the failing run itself); no pixel of
    /// a later row. A mesh draw stops at the failing triangle; the triangles before it are drawn.
    Target,
    /// Z buffering asked for with a depth format that stores W (see [`crate::DepthMode`]).
    ZWithWFormat,
    /// A camera that cannot be built: `look_at` with the eye on the target or `up` along the view direction, a
    /// field of view outside `(0, pi)` radians (given in degrees, say), or `aspect <= 0`.
    InvalidCamera,
    /// A world-space vertex whose clip-space coordinates (after the matrix) are not finite in f32, or whose
    /// clipping overflows f32: the coordinates or the matrix are too large (about `1e38` after the transform).
    WorldTooLarge,
    /// A mesh index at or beyond the number of vertices, or a per-face colour slice shorter than the faces.
    IndexOutOfRange,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonFinite => f.write_str("NaN or infinity in a vertex or render state"),
            Error::RhwNotPositive => {
                f.write_str("rhw must be > 0 (W = 1/rhw is the eye-space depth)")
            }
            Error::OutOfGuardBand => f.write_str("vertex outside the guard band of +-4096 pixels"),
            Error::DepthRange => {
                f.write_str("rhw * W_far above 2^30: vertex too near the eye for the depth range")
            }
            Error::InvalidDepthRange => {
                f.write_str("depth range needs 0 < W_near < W_far and W_far/W_near <= 2^30")
            }
            Error::BufferSize { expected, actual } => {
                write!(f, "buffer has {actual} elements, {expected} needed")
            }
            Error::Target => f.write_str("the draw target returned an error"),
            Error::ZWithWFormat => {
                f.write_str("Z buffering asked for with a depth format that stores W")
            }
            Error::InvalidCamera => f.write_str(
                "camera: eye on target, up along the view, fov outside (0, pi) radians or aspect <= 0",
            ),
            Error::WorldTooLarge => {
                f.write_str("world vertex too large: clip-space coordinates overflow f32")
            }
            Error::IndexOutOfRange => {
                f.write_str("mesh index beyond the vertices, or too few face colours")
            }
        }
    }
}

impl core::error::Error for Error {}
