//! Indexed triangle meshes drawn from world (or object) space with one call.
//!
//! [`Rasterizer::transform_mesh`] transforms each vertex once per frame into caller-provided storage (no
//! allocation): screen `x`, `y` and `rhw` for a vertex in front of the near plane and inside the guard band, a mark
//! for the others. [`Rasterizer::draw_mesh_frame`] then draws the triangles into a buffer or a band of one, as often
//! as there are bands: a triangle whose three vertices are marked inside is tested against the band's rows (a band
//! it cannot touch costs a compare), culled by the sign of its snapped screen area (the rasterizer's own test, so the
//! mesh drops exactly the triangles a draw of them would; a float or integer filter decides without snapping unless
//! the area is near zero), and drawn; the few others are transformed
//! again from their positions, rejected when all three vertices lie outside one plane, culled by the sign of
//! `det[x y w]` (the homogeneous back-face test, right for vertices behind the eye too) and clipped
//! ([`crate::clip`]). [`Rasterizer::bin_mesh`], once per frame, culls the triangles on screen and records each one's
//! row bucket in a byte of caller storage: each band then tests a byte per triangle and sets up only those that can
//! reach it (on the Cortex-M0's W4, then in 60 bands, a quarter of the frame's instructions saved).
//! [`Rasterizer::draw_mesh`] does the transform and the draw for a whole frame. Everything is f32; all checks happen
//! in `transform_mesh`, before anything is drawn. [`Sphere::visible`] tells, for the price of one point's transform,
//! whether a mesh can reach the screen at all, so a mesh out of view need not be transformed.
//!
//! ```
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! use embedded_graphics_core::prelude::*;
//! use wraster::clip::Viewport;
//! use wraster::mesh::{Colors, Mesh, Projected, Sphere};
//! use wraster::projection::{Camera, Mat4};
//! use wraster::{DepthBuffer, DepthStore, Rasterizer};
//!
//! # struct Screen;
//! # impl OriginDimensions for Screen { fn size(&self) -> Size { Size::new(64, 48) } }
//! # impl DrawTarget for Screen {
//! #     type Color = Rgb565; type Error = core::convert::Infallible;
//! #     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, _: I) -> Result<(), Self::Error> { Ok(()) }
//! # }
//! // A unit cube, counter-clockwise seen from outside.
//! let positions = [
//!     [-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0],
//!     [-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0],
//! ];
//! let indices = [
//!     [0, 3, 2], [0, 2, 1], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
//!     [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [0, 4, 7], [0, 7, 3],
//! ];
//! let faces = [Rgb565::RED, Rgb565::RED, Rgb565::GREEN, Rgb565::GREEN, Rgb565::BLUE, Rgb565::BLUE,
//!              Rgb565::CYAN, Rgb565::CYAN, Rgb565::WHITE, Rgb565::WHITE, Rgb565::YELLOW, Rgb565::YELLOW];
//! let cube = Mesh { positions: &positions, indices: &indices, colors: Colors::PerFace(&faces) };
//!
//! let camera = Camera::look_at([3.0, 2.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 1.0, 64.0 / 48.0, 0.5, 50.0)?;
//! let mut r: Rasterizer = Rasterizer::new(camera.render_state()?);
//! let mut depth = DepthStore::<64, 48>::new();
//! let mut scratch = [Projected::default(); 8];
//! let model = Mat4::rotation_y(0.3);
//! let vp = Viewport::new(0.0, 0.0, 64.0, 48.0);
//! let stats = r.draw_mesh(&mut Screen, &mut depth.view(), &cube, &camera.model_matrix(&model), &vp, &mut scratch)?;
//! assert_eq!(stats.culled, 6); // the six back-facing triangles
//! assert!(stats.written > 200); // about a tenth of the 64 x 48 screen
//!
//! // In bands of 8 rows, as a small core draws (one band's depth in RAM): transform and bin once per frame, then
//! // each band sets up only the triangles that can reach it. The same pixels as the whole frame's.
//! let frame = r.transform_mesh(&cube, &camera.model_matrix(&model), &vp, &mut scratch)?;
//! let mut bins = [0u8; 12]; // a byte per triangle
//! let frame = r.bin_mesh(frame, &mut bins)?;
//! let mut band = [0u16; 64 * 8];
//! let mut written = 0;
//! for y0 in (0..48).step_by(8) {
//!     let mut buf = DepthBuffer::band(&mut band, 64, y0, 8)?;
//!     buf.clear();
//!     written += r.draw_mesh_frame(&mut Screen, &mut buf, &frame)?.written;
//! }
//! assert_eq!(written, stats.written);
//!
//! // A mesh out of view costs a sphere test, not a transform: test before drawing.
//! let sphere = Sphere::enclosing(&positions)?;
//! let range = camera.render_state()?.range;
//! assert!(sphere.visible(&camera.model_matrix(&model), &vp, Size::new(64, 48), &range));
//! let behind = model * Mat4::translation([0.0, 0.0, 20.0]); // the eye looks from z = 5 towards the origin
//! assert!(!sphere.visible(&camera.model_matrix(&behind), &vp, Size::new(64, 48), &range));
//! # Ok::<(), wraster::Error>(())
//! ```

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::pixelcolor::PixelColor;

use crate::clip::{check_matrix, fan, to_clip, Planes, Viewport};
use crate::projection::Mat4;
use crate::recip::{SpanRecip, WSpan};
use crate::setup::{Plane, Remember, Solved};
use crate::small::Kept;
use crate::transform::IntTransform;
use crate::{Cull, DepthBuffer, Error, Rasterizer, Stats, Vertex, VertexInput};
use core::cell::Cell;

/// The colours of a mesh.
#[derive(Clone, Copy, Debug)]
pub enum Colors<'a, C> {
    /// One colour for every triangle.
    Uniform(C),
    /// One colour per triangle (at least as many as `indices`).
    PerFace(&'a [C]),
    /// One colour per vertex (at least as many as `positions`): interpolated by
    /// `Rasterizer::draw_mesh_frame_gouraud` (feature `gouraud`); the flat draws take a triangle's first vertex's
    /// colour, as Direct3D's flat shading does.
    PerVertex(&'a [C]),
}

/// An indexed triangle mesh: each triangle is three indices into `positions` (`u16`: up to 65,536 vertices).
#[derive(Clone, Copy, Debug)]
pub struct Mesh<'a, C> {
    /// Vertex positions, object space.
    pub positions: &'a [[f32; 3]],
    /// Triangles, three indices each.
    pub indices: &'a [[u16; 3]],
    /// Colours.
    pub colors: Colors<'a, C>,
}

pub use crate::transform::Projected;

/// A mesh transformed for one frame ([`Rasterizer::transform_mesh`]): draw it into each band with
/// [`Rasterizer::draw_mesh_frame`].
#[derive(Clone, Copy, Debug)]
pub struct MeshFrame<'a, C> {
    mesh: Mesh<'a, C>,
    m: Mat4,
    planes: Planes,
    verts: &'a [Projected],
    bins: Option<Bins<'a>>,
}

/// Row buckets of a frame's triangles ([`Rasterizer::bin_mesh`]): one byte per triangle, the bucket of its top row
/// for a front-facing triangle whose three vertices are on screen, [`CLIP`] for one to clip, [`CULLED`] for the
/// others.
#[derive(Clone, Copy, Debug)]
struct Bins<'a> {
    of: &'a [u8],
    /// Bucket of top row `t`: `clamp((t - origin) >> shift, 0, BUCKETS - 1)`.
    origin: i32,
    shift: u32,
    /// The largest `bottom - top` of a binned triangle (rows, with the margins of [`Bins::rows`]).
    reach: i32,
    cull: Cull,
    culled: u32,
    /// Whether any triangle is marked [`CLIP`] (visited by every band).
    clips: bool,
}

/// Storage for a frame's plane cache ([`MeshFrame::with_plane_cache`]), `N` triangles (28 bytes each, plus 24 on
/// 32-bit targets).
///
/// A frame drawn in bands sets a triangle up again in every band it reaches; on the fast tier the costliest part of
/// that set-up for vertices off the 1/256 px grid is the depth-grid correction (the plane through the vertices as
/// given, evaluated at the snapped ones: about 1,580 instructions a triangle on the Cortex-M0, where without a cache
/// it would be about a fifth of W4's frame). The cache keeps those values for the triangles that reach the next
/// band, so each is computed once a frame; for a triangle too large for the small-triangle path it keeps the solved
/// plane of `T` instead (the exact solve, three 128-bit divisions), and for a small triangle that path drew, its
/// depth constants (the next band skips the range tests, the products of its depth sum and their leading zeros).
/// All are functions of the triangle alone, so the frames are the same with and without the cache; a full cache
/// just computes the values again. Triangle lists use it too ([`PlaneCache::list`]). Bands must come in order, top to bottom, for it to help:
/// a band that does not start where the previous one ended, a change of the depth range or of the strategy empties
/// it. Triangles from index 2^20 on are not cached.
///
/// A frame in bands of 8 rows, transformed once, binned by rows and cached (all in caller storage):
/// ```
/// use embedded_graphics_core::pixelcolor::Rgb565;
/// use embedded_graphics_core::prelude::*;
/// use wraster::clip::Viewport;
/// use wraster::mesh::{Colors, Mesh, PlaneCache, Projected};
/// use wraster::projection::{Camera, Mat4};
/// use wraster::{ColorBand, DepthBuffer, Rasterizer};
///
/// let positions = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
/// let indices = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
/// let mesh = Mesh { positions: &positions, indices: &indices, colors: Colors::Uniform(Rgb565::GREEN) };
/// let camera = Camera::look_at([0.0, 0.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0],
///                              core::f32::consts::FRAC_PI_3, 64.0 / 48.0, 0.5, 100.0)?;
/// let mut r: Rasterizer = Rasterizer::new(camera.render_state()?);
/// let (mut scratch, mut bins) = ([Projected::default(); 4], [0u8; 4]);
/// let mut cache = PlaneCache::<8>::new();
/// let m = camera.model_matrix(&Mat4::rotation_y(0.3));
/// let frame = r.transform_mesh(&mesh, &m, &Viewport::new(0.0, 0.0, 64.0, 48.0), &mut scratch)?;
/// let frame = r.bin_mesh(frame, &mut bins)?.with_plane_cache(&mut cache);
/// let (mut px, mut z) = ([0u16; 64 * 8], [0u16; 64 * 8]);
/// let mut written = 0;
/// for y0 in (0..48).step_by(8) {
///     let mut band = ColorBand::<Rgb565>::band(&mut px, 64, y0, 8)?;
///     let mut depth = DepthBuffer::band(&mut z, 64, y0, 8)?;
///     depth.clear();
///     written += r.draw_mesh_frame(&mut band, &mut depth, &frame)?.written;
///     // ... send `band.pixels()` to the display's rows y0..y0 + 8 ...
/// }
/// assert!(written > 100);
/// # Ok::<(), wraster::Error>(())
/// ```
#[derive(Debug)]
pub struct PlaneCache<const N: usize> {
    state: CacheState,
    slots: [Cell<Slot>; N],
}

impl<const N: usize> PlaneCache<N> {
    /// An empty cache (it is emptied again by [`MeshFrame::with_plane_cache`]).
    pub const fn new() -> Self {
        PlaneCache {
            state: CacheState {
                head: Cell::new(0),
                len: Cell::new(0),
                prev: Cell::new(0),
                // All zero (a static of it is `.bss`); `with_plane_cache` and `list` mark it empty.
                band_end: Cell::new(0),
                tag: Cell::new(0),
            },
            slots: [const { Cell::new(Slot { key: 0, t: [0; 6] }) }; N],
        }
    }
}

impl<const N: usize> PlaneCache<N> {
    /// The cache, emptied, as a frame's view of it.
    fn emptied(&mut self) -> Cache<'_> {
        let cache = Cache {
            state: &self.state,
            slots: &self.slots,
        };
        cache.reset();
        cache
    }

    /// The triangles `tris` as one frame drawn band by band, top to bottom, with [`Rasterizer::draw_listed`]
    /// (the cache is emptied here). A triangle that reaches the next band is set up there from what this one
    /// remembered: its depth-grid values on the fast tier (as a [`CachedFrame`]'s), or, for a triangle too large for
    /// the small-triangle path, its solved plane of `T` (the exact solve: on the Cortex-M0 some 4,000 instructions,
    /// with its divisions), or, for a small triangle that path drew, its depth constants. The frame borrows the list,
    /// so triangle `k` is the same in every band.
    ///
    /// ```
    /// use embedded_graphics_core::pixelcolor::Rgb565;
    /// use embedded_graphics_core::prelude::*;
    /// use wraster::mesh::PlaneCache;
    /// use wraster::{ColorBand, DepthBuffer, Rasterizer, RenderState, Vertex};
    ///
    /// let tris = [
    ///     [Vertex::new(2.0, 1.0, 10.0, Rgb565::RED), Vertex::new(60.0, 9.0, 40.0, Rgb565::RED),
    ///      Vertex::new(9.0, 46.0, 20.0, Rgb565::RED)],
    ///     [Vertex::new(30.0, 2.0, 5.0, Rgb565::BLUE), Vertex::new(62.0, 47.0, 60.0, Rgb565::BLUE),
    ///      Vertex::new(1.0, 40.0, 30.0, Rgb565::BLUE)],
    /// ];
    /// let mut r: Rasterizer = Rasterizer::new(RenderState::new(1.0, 100.0)?);
    /// let mut cache = PlaneCache::<2>::new();
    /// let frame = cache.list(&tris);
    /// let (mut px, mut z) = ([0u16; 64 * 8], [0u16; 64 * 8]);
    /// let mut written = 0;
    /// for y0 in (0..48).step_by(8) {
    ///     let mut band = ColorBand::<Rgb565>::band(&mut px, 64, y0, 8)?;
    ///     let mut depth = DepthBuffer::band(&mut z, 64, y0, 8)?;
    ///     depth.clear();
    ///     for k in 0..tris.len() {
    ///         written += r.draw_listed(&mut band, &mut depth, &frame, k)?.written;
    ///     }
    ///     // ... send `band.pixels()` to the display's rows y0..y0 + 8 ...
    /// }
    /// assert!(written > 1000);
    /// # Ok::<(), wraster::Error>(())
    /// ```
    pub fn list<'a, T: Triangle>(&'a mut self, tris: &'a [T]) -> ListFrame<'a, T> {
        ListFrame {
            tris,
            cache: self.emptied(),
        }
    }
}

/// A triangle of a list drawn band by band with a [`PlaneCache`] ([`PlaneCache::list`]): its three vertices, the
/// same each time they are asked for (what the cache remembers of triangle `k` is a function of them).
pub trait Triangle {
    /// The vertices' type ([`Vertex`], [`crate::FixedVertex`]).
    type Vertex: VertexInput;
    /// The three vertices, in drawing order.
    fn vertices(&self) -> [Self::Vertex; 3];
}

impl<V: VertexInput + Copy> Triangle for [V; 3] {
    type Vertex = V;
    #[inline(always)]
    fn vertices(&self) -> [V; 3] {
        *self
    }
}

/// A list of triangles drawn as one frame, band by band, with a [`PlaneCache`] ([`PlaneCache::list`],
/// [`Rasterizer::draw_listed`]).
pub struct ListFrame<'a, T> {
    tris: &'a [T],
    cache: Cache<'a>,
}

impl<T> ListFrame<'_, T> {
    /// The triangles.
    pub fn triangles(&self) -> &[T] {
        self.tris
    }
}

impl<T> core::fmt::Debug for ListFrame<'_, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ListFrame")
            .field("triangles", &self.tris.len())
            .finish_non_exhaustive()
    }
}

impl<const N: usize> Default for PlaneCache<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// A [`MeshFrame`] with a [`PlaneCache`] ([`MeshFrame::with_plane_cache`]), drawn with
/// [`Rasterizer::draw_mesh_frame`] like the frame itself.
#[derive(Clone, Copy, Debug)]
pub struct CachedFrame<'a, C> {
    frame: MeshFrame<'a, C>,
    cache: Cache<'a>,
}

impl<'a, C> CachedFrame<'a, C> {
    /// The frame.
    pub fn frame(&self) -> &MeshFrame<'a, C> {
        &self.frame
    }
}

/// What [`Rasterizer::draw_mesh_frame`] draws: a [`MeshFrame`] or a [`CachedFrame`] (sealed). Each is its own
/// instance of the draw: a firmware that draws only one of them links only that one.
pub trait DrawFrame<'a, C>: sealed::Frame<'a, C> {}
impl<'a, C: Copy> DrawFrame<'a, C> for MeshFrame<'a, C> {}
impl<'a, C: Copy> DrawFrame<'a, C> for CachedFrame<'a, C> {}

mod sealed {
    use super::{Cache, CachedFrame, MeshFrame, INDEX};
    use crate::setup::{Culled, NoMemo, Remember, TMemo};

    /// Triangle `k`'s memo in a band whose last row is `last`: values from the cache, and kept for a triangle that
    /// reaches further down. No early cull ([`TMemo::early_cull`]), for a mesh's triangles (culled first) and a
    /// list's alike: one instance of the draw for both (with the test a list's, without it a mesh's, they were two, and
    /// a firmware drawing both held 9,316 more bytes of `.text`; and as a value, the M0's W4 frame took 0.15% more
    /// instructions). A list frame's culled triangle computes its values once a frame, kept for its later bands.
    pub struct Remembered<'a> {
        pub(super) cache: Cache<'a>,
        pub(super) k: u32,
        pub(super) last: i32,
    }

    impl TMemo for Remembered<'_> {
        #[inline(always)]
        fn early_cull(&self) -> bool {
            false
        }
        #[inline]
        fn take(&mut self) -> Option<Remember> {
            self.cache.take(self.k)
        }
        #[inline]
        fn keep(&mut self, r: Remember, last_row: i32) {
            if last_row > self.last {
                self.cache.keep(self.k, r);
            }
        }
    }

    /// The frame, and a triangle's memo ([`crate::setup::TMemo`]) in a band.
    pub trait Frame<'a, C> {
        type Memo<'m>: TMemo
        where
            Self: 'm;
        fn frame(&self) -> &MeshFrame<'a, C>;
        /// A band of rows `[y0, y0 + h)` begins, drawn with `tag`.
        fn begin(&self, y0: i32, h: u16, tag: u64);
        /// Triangle `k`'s memo (`None`: a clipped triangle's fan) in a band whose last row is `last`.
        fn memo(&self, k: Option<usize>, last: i32) -> Self::Memo<'_>;
    }

    impl<'a, C> Frame<'a, C> for MeshFrame<'a, C> {
        type Memo<'m>
            = Culled
        where
            Self: 'm;
        #[inline(always)]
        fn frame(&self) -> &MeshFrame<'a, C> {
            self
        }
        #[inline(always)]
        fn begin(&self, _: i32, _: u16, _: u64) {}
        #[inline(always)]
        fn memo(&self, _: Option<usize>, _: i32) -> Culled {
            NoMemo
        }
    }

    impl<'a, C> Frame<'a, C> for CachedFrame<'a, C> {
        type Memo<'m>
            = Option<Remembered<'m>>
        where
            Self: 'm;
        #[inline(always)]
        fn frame(&self) -> &MeshFrame<'a, C> {
            &self.frame
        }
        #[inline]
        fn begin(&self, y0: i32, h: u16, tag: u64) {
            self.cache.begin(y0, h, tag);
        }
        #[inline(always)]
        fn memo(&self, k: Option<usize>, last: i32) -> Option<Remembered<'_>> {
            // Keys are 20 bits (`INDEX`): a triangle beyond is not cached.
            let k = u32::try_from(k?).ok().filter(|&k| k <= INDEX)?;
            Some(Remembered {
                cache: self.cache,
                k,
                last,
            })
        }
    }
}

/// A remembered triangle: its key (the triangle's index in bits 0 to 19, what is kept in the bits above: [`DECLINED`],
/// [`PLANE`], [`SMALL`], the plane's fraction bits or the small triangle's shifts) and its values, each `i64` as two
/// `u32` halves (so a slot is aligned to 4 bytes and takes 28, not 32): the depth-grid values, the plane's reference
/// value and steps, or the small triangle's `S` and steps.
#[derive(Clone, Copy, Debug)]
struct Slot {
    key: u32,
    t: [u32; 6],
}

/// The index bits of [`Slot::key`] (triangles beyond are not cached).
const INDEX: u32 = (1 << 20) - 1;
/// Bit 31 of [`Slot::key`] alone: no depth-grid values (declined).
const DECLINED: u32 = 1 << 31;
/// Bit 30 of [`Slot::key`] alone: a solved plane ([`Remember::Plane`]), its fraction bits (at most 61) in bits 24 to
/// 29.
const PLANE: u32 = 1 << 30;
/// Bits 30 and 31 of [`Slot::key`]: a small triangle's constants ([`Remember::Small`]), its code's shift `s0` (at
/// most 32) in bits 24 to 29 and, in bits 20 to 23, 1 more than its leading zeros where they are the same at every
/// pixel (at most 8), else 0.
const SMALL: u32 = DECLINED | PLANE;

/// The cache's ring: `len` slots from `head`, of which the first `prev` were left by the previous band (in
/// increasing triangle order, the order [`MeshFrame::for_each`] visits), the rest by the current one.
#[derive(Debug)]
struct CacheState {
    head: Cell<usize>,
    len: Cell<usize>,
    prev: Cell<usize>,
    /// The row after the current band's last, and what the values depend on besides the triangle (strategy, far
    /// plane).
    band_end: Cell<i32>,
    tag: Cell<u64>,
}

/// A frame's view of a [`PlaneCache`].
#[derive(Clone, Copy, Debug)]
struct Cache<'a> {
    state: &'a CacheState,
    slots: &'a [Cell<Slot>],
}

impl Cache<'_> {
    /// A band of rows `[y0, y0 + h)`: the previous band's entries become the ones to look up when it is the next
    /// band of the same frame drawn the same way (`tag`); otherwise the cache is emptied.
    fn begin(&self, y0: i32, h: u16, tag: u64) {
        let st = self.state;
        if st.band_end.get() == y0 && st.tag.get() == tag && !self.slots.is_empty() {
            // Entries the previous band left unread: their triangles did not come back.
            let p = st.prev.get();
            st.head.set(wrap(st.head.get() + p, self.slots.len()));
            st.len.set(st.len.get() - p);
        } else {
            st.head.set(0);
            st.len.set(0);
        }
        st.prev.set(st.len.get());
        st.band_end.set(y0.saturating_add(h as i32));
        st.tag.set(tag);
    }

    /// [`Cache::begin`], unless a band ending where rows `[y0, y0 + h)` end, drawn with `tag`, is the current one (a
    /// list's draws come one triangle at a time: the first of a band begins it). A band missed here (another band
    /// with the same end) only finds less: an entry is a function of its triangle and the tag alone.
    fn enter(&self, y0: i32, h: u16, tag: u64) {
        let st = self.state;
        if st.band_end.get() != y0.saturating_add(h as i32) || st.tag.get() != tag {
            self.begin(y0, h, tag);
        }
    }

    /// Emptied, for a new frame.
    fn reset(&self) {
        self.state.band_end.set(i32::MIN);
        self.state.len.set(0);
        self.state.prev.set(0);
    }

    /// Triangle `k`'s values from the previous band, if it left them (entries of smaller triangles are dropped:
    /// they did not come back).
    fn take(&self, k: u32) -> Option<Remember> {
        let st = self.state;
        while st.prev.get() > 0 {
            let head = st.head.get();
            let e = self.slots[head].get();
            let key = e.key & INDEX;
            if key > k {
                return None;
            }
            st.head.set(if head + 1 == self.slots.len() {
                0
            } else {
                head + 1
            });
            st.len.set(st.len.get() - 1);
            st.prev.set(st.prev.get() - 1);
            if key == k {
                let t = &e.t;
                let join = |lo: u32, hi: u32| ((hi as u64) << 32 | lo as u64) as i64;
                let v = [join(t[0], t[1]), join(t[2], t[3]), join(t[4], t[5])];
                return Some(if e.key & SMALL == SMALL {
                    // Not zero: it was kept from a `Kept` (`s0 >= 1`).
                    let shifts = ((e.key >> 24) & 63) | ((e.key >> 20) & 15) << 8;
                    match core::num::NonZeroU16::new(shifts as u16) {
                        Some(shifts) => Remember::Small(Kept {
                            s_o: v[0] as u64,
                            sx: v[1] as u64,
                            sy: v[2] as u64,
                            shifts,
                        }),
                        None => return None,
                    }
                } else if e.key & PLANE != 0 {
                    Remember::Plane(Solved {
                        plane: Plane {
                            row: v[0],
                            sx: v[1],
                            sy: v[2],
                        },
                        frac: (e.key >> 24) & 63,
                    })
                } else {
                    Remember::T((e.key & DECLINED == 0).then_some(v))
                });
            }
        }
        None
    }

    /// Keeps triangle `k`'s values for the next band (dropped when the cache is full).
    fn keep(&self, k: u32, r: Remember) {
        let (st, n) = (self.state, self.slots.len());
        let len = st.len.get();
        if len < n {
            let at = wrap(st.head.get() + len, n);
            let (key, t) = match r {
                // `s0 <= 32` and `lz <= 8` (`crate::small`'s module doc); a value beyond the key's bits is not kept.
                Remember::Small(Kept { shifts, .. })
                    if shifts.get() & 0xff > 63 || shifts.get() >> 8 > 15 =>
                {
                    return
                }
                Remember::Small(Kept {
                    s_o,
                    sx,
                    sy,
                    shifts,
                }) => {
                    let z = shifts.get() as u32;
                    (
                        k | SMALL | (z & 0xff) << 24 | (z >> 8) << 20,
                        [s_o as i64, sx as i64, sy as i64],
                    )
                }
                Remember::T(Some(t)) => (k, t),
                Remember::T(None) => (k | DECLINED, [0; 3]),
                Remember::Plane(Solved { plane, frac }) => (
                    k | PLANE | (frac & 63) << 24,
                    [plane.row, plane.sx, plane.sy],
                ),
            };
            self.slots[at].set(Slot {
                key,
                t: [
                    t[0] as u32,
                    (t[0] >> 32) as u32,
                    t[1] as u32,
                    (t[1] >> 32) as u32,
                    t[2] as u32,
                    (t[2] >> 32) as u32,
                ],
            });
            st.len.set(len + 1);
        }
    }
}

/// Row buckets: 0 to 253. A frame whose top rows span under 254 rows has a bucket per row.
const BUCKETS: i32 = 254;
/// A triangle's byte when it needs clipping (visited by every band), and when it was culled (by none).
const CLIP: u8 = 254;
const CULLED: u8 = 255;

impl Bins<'_> {
    /// A screen triangle's rows `(top, bottom)`, such that a band of rows `[y0, y0 + h)` whose test in
    /// [`MeshFrame::triangle`] admits the triangle has `top <= y0 + h - 1` and `bottom >= y0` (the test admits it when
    /// `ymin <= y0 + h - 0.49` and `ymax >= y0 + 0.49`). `as i32` truncates toward zero: `top = (ymin as i32) - 1`
    /// is below `ymin` (truncation adds less than 1), so at most `y0 + h - 1`; `bottom = ymax as i32` is at least
    /// `y0`, as truncation rounds a positive `ymax` down to an integer no smaller than `y0` and a negative one up.
    /// (Without the `- 1`, a negative `ymin` rounded up misses bands above row 0.)
    #[inline]
    fn rows(ymin: f32, ymax: f32) -> (i32, i32) {
        (trunc(ymin) - 1, trunc(ymax))
    }
    #[inline]
    fn bucket(&self, row: i32) -> u8 {
        ((row.max(self.origin) - self.origin) >> self.shift).min(BUCKETS - 1) as u8
    }
}

impl<'a, C: Copy> MeshFrame<'a, C> {
    /// The mesh.
    pub fn mesh(&self) -> &Mesh<'a, C> {
        &self.mesh
    }
    /// The transformed vertices.
    pub fn vertices(&self) -> &'a [Projected] {
        self.verts
    }
    /// This frame with a plane cache (`cache`, emptied here): drawn band by band, top to bottom, with
    /// [`Rasterizer::draw_mesh_frame`], a triangle that reaches several bands has its depth-grid values computed once
    /// instead of in each (see [`PlaneCache`]). The same pixels and codes as without it. A type of its own, so a
    /// firmware that never caches links no cache code.
    pub fn with_plane_cache<const N: usize>(
        self,
        cache: &'a mut PlaneCache<N>,
    ) -> CachedFrame<'a, C> {
        CachedFrame {
            frame: self,
            cache: cache.emptied(),
        }
    }

    /// The triangles [`Rasterizer::bin_mesh`] culled (`None` for a frame not binned).
    pub fn binned_culled(&self) -> Option<u32> {
        self.bins.map(|b| b.culled)
    }

    /// Triangle `k`'s per-vertex colours (the face colour three times for flat colours).
    #[inline]
    fn colors(&self, k: usize, idx: [usize; 3]) -> [C; 3] {
        match self.mesh.colors {
            Colors::Uniform(c) => [c; 3],
            Colors::PerFace(f) => [f[k]; 3],
            Colors::PerVertex(v) => idx.map(|i| v[i]),
        }
    }

    /// Visits the triangles that can touch rows `[y0, y0 + h)`, culled and clipped, as screen-space triangles
    /// (`f(k, vertices)`: `k` the triangle's index, `None` for the fan of a clipped one; the vertices' colours with
    /// the barycentric weights already applied by `mix`), in increasing triangle order. A binned frame ([`Rasterizer::bin_mesh`], with the same cull mode) tests a byte per
    /// triangle and looks further only at those in the buckets the band can reach and those to clip, so it draws
    /// exactly the triangles, in the same order, as the walk over all of them; its screen triangles were culled
    /// once by the binning.
    fn for_each<E>(
        &self,
        cull: Cull,
        y0: i32,
        h: u16,
        stats: &mut Stats,
        mix: &impl Fn([C; 3], [f32; 3]) -> C,
        mut f: impl FnMut(Option<usize>, [Vertex<C>; 3]) -> Result<Stats, E>,
    ) -> Result<(), E> {
        // Rows whose centre can be covered: y in [y0 + 0.5, y0 + h - 0.5], less 0.01 px of slack for the snap (which
        // moves y by at most 1/512 px) and the bounds' own rounding (below 2^-11 px for |y| < 2^12). Compared as
        // ordered integers (`key`): a float compare is a library call on a core without an FPU.
        let rows = (
            key(y0 as f32 + 0.49),
            key(y0.saturating_add(h as i32) as f32 - 0.49),
        );
        // A binned frame: the buckets of the top rows in [y0 - reach, y0 + h - 1], which hold every binned triangle
        // that can touch the band (its bottom is at least y0 and at most `reach` below its top); and the triangles to
        // clip. (One loop with one call of `triangle` for both kinds of frame: a second call site keeps LLVM from
        // inlining the draw into it, which costs the walk over all triangles 1% on the Cortex-M4's W4.)
        let (of, lo, span, clips) = match self.bins.filter(|b| b.cull == cull) {
            Some(b) => {
                let lo = b.bucket(y0.saturating_sub(b.reach));
                (
                    b.of,
                    lo,
                    b.bucket(y0.saturating_add(h as i32 - 1)) - lo,
                    b.clips,
                )
            }
            None => (&[][..], 0, 0, false),
        };
        let (binned, indices) = (!of.is_empty(), self.mesh.indices);
        let mut k = 0;
        loop {
            if binned {
                k = next_in_reach(of, k, lo, span, clips);
            }
            let Some(tri) = indices.get(k) else {
                return Ok(());
            };
            self.triangle(k, tri, cull, binned, rows, stats, mix, &mut f)?;
            k += 1;
        }
    }

    /// Triangle `k` for [`MeshFrame::for_each`]: skipped when it cannot touch the band's `rows` (`key`s of its
    /// first and last admitted centre) or is culled as `cull` says (a screen triangle only when not `binned`: the
    /// binning kept it), else clipped if it needs it and handed to `f`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn triangle<E>(
        &self,
        k: usize,
        tri: &[u16; 3],
        cull: Cull,
        binned: bool,
        (top, bottom): (i32, i32),
        stats: &mut Stats,
        mix: &impl Fn([C; 3], [f32; 3]) -> C,
        f: &mut impl FnMut(Option<usize>, [Vertex<C>; 3]) -> Result<Stats, E>,
    ) -> Result<(), E> {
        let idx = tri.map(|i| i as usize);
        let [a, b, c] = idx.map(|i| self.verts[i]);
        if on_screen(&[a, b, c]) {
            let (ka, kb, kc) = (key(a.y), key(b.y), key(c.y));
            if ka.max(kb).max(kc) < top || ka.min(kb).min(kc) > bottom {
                return Ok(());
            }
            let vc = self.colors(k, idx);
            if !binned && culled_on_screen(cull, &[a, b, c]) {
                stats.culled += 1;
                return Ok(());
            }
            let v = [a, b, c];
            *stats += f(
                Some(k),
                core::array::from_fn(|i| Vertex {
                    x: v[i].x,
                    y: v[i].y,
                    z: 0.0,
                    rhw: v[i].rhw,
                    color: vc[i],
                }),
            )?;
            return Ok(());
        }
        self.clipped(k, idx, cull, stats, mix, f)
    }

    /// The clipping half of [`MeshFrame::triangle`]: out of line, so the polygons' stack (two of
    /// [`crate::clip`]'s `Poly`) is taken only by a triangle that crosses a plane, not by every screen triangle's draw
    /// (on the Cortex-M0's 16 KiB, the stack's depth decides how tall the bands can be).
    #[inline(never)]
    fn clipped<E>(
        &self,
        k: usize,
        idx: [usize; 3],
        cull: Cull,
        stats: &mut Stats,
        mix: &impl Fn([C; 3], [f32; 3]) -> C,
        f: &mut impl FnMut(Option<usize>, [Vertex<C>; 3]) -> Result<Stats, E>,
    ) -> Result<(), E> {
        let vc = self.colors(k, idx);
        // Needs clipping: the positions were checked by transform_mesh, so these cannot fail.
        let cl = idx.map(|i| to_clip(&self.m, &self.mesh.positions[i]).unwrap_or([0.0; 4]));
        let codes = cl.map(|v| self.planes.outcode(&v));
        if codes[0] & codes[1] & codes[2] != 0 {
            return Ok(());
        }
        // det [x y w]: its sign is the winding seen from the eye; on screen (y down) the area has the other sign.
        let det = cl[0][0] * (cl[1][1] * cl[2][3] - cl[2][1] * cl[1][3])
            - cl[1][0] * (cl[0][1] * cl[2][3] - cl[2][1] * cl[0][3])
            + cl[2][0] * (cl[0][1] * cl[1][3] - cl[1][1] * cl[0][3]);
        if culled(cull, -det) {
            stats.culled += 1;
            return Ok(());
        }
        // A triangle whose clipping overflows f32 is skipped here (draw_world reports it as WorldTooLarge):
        // the draws of a transformed frame do not fail on input.
        let Ok(poly) = self.planes.clip(&cl, codes[0] | codes[1] | codes[2]) else {
            return Ok(());
        };
        for j in 1..poly.len().saturating_sub(1) {
            *stats += f(None, fan(&self.planes, &poly, j, &|w| mix(vc, w)))?;
        }
        Ok(())
    }
}

/// The first triangle from `k` on whose byte in `of` is a bucket in `[lo, lo + span]` (mod 256) or [`CLIP`]; `of.len()`
/// when none: one compare a byte, and the [`CLIP`] test only where the binning marked a triangle to clip (`clips`).
/// Every band tests every byte, and most are out of reach: on the M0's W4 (then 60 bands) this scan was about 4% of the
/// frame's instructions (3.6 million over the 8 frames of 89.7 million), so where no triangle is to clip and the
/// reach is under 128 buckets (W4's is a few) it tests four bytes at a time ([`Reach`], [`skip_words`]) over the
/// aligned words (measured: the M0's W4 frame 1.8% fewer instructions). Fewer would take a coarser index (a bucket
/// range per group of triangles) or the triangles sorted by bucket (two bytes each).
#[inline]
fn next_in_reach(of: &[u8], mut k: usize, lo: u8, span: u8, clips: bool) -> usize {
    if !clips {
        // The next triangle is often in reach too (its neighbour in the mesh): then no call.
        if span < 128 && k < of.len() && of[k].wrapping_sub(lo) > span {
            k = skip_words(of, k, lo, span);
        }
        while k < of.len() && of[k].wrapping_sub(lo) > span {
            k += 1;
        }
        return k;
    }
    while k < of.len() && of[k].wrapping_sub(lo) > span && of[k] != CLIP {
        k += 1;
    }
    k
}

/// [`next_in_reach`] from `k` without [`CLIP`]s, for `span < 128`: the bytes before the first aligned word one at a
/// time, then whole words; the first byte in reach before the words, or the start of the word that holds one, or of
/// the tail. Out of line: its values are then not on the stack under the draws (the Cortex-M0's W4 stack).
#[inline(never)]
fn skip_words(of: &[u8], mut k: usize, lo: u8, span: u8) -> usize {
    let (head, words, _) = bytemuck::pod_align_to::<u8, u32>(of);
    let base = head.len();
    while k < of.len() && (k < base || !(k - base).is_multiple_of(4)) {
        if of[k].wrapping_sub(lo) <= span {
            return k;
        }
        k += 1;
    }
    if k < of.len() {
        let reach = Reach::new(lo, span);
        let mut i = (k - base) / 4;
        while i < words.len() && !reach.any(words[i]) {
            i += 1;
        }
        k = base + 4 * i;
    }
    k
}

/// The test of four buckets at a time (SWAR, in one `u32`): whether any byte `b` of a word has `(b - lo) mod 256 <=
/// span`, for `span < 128`. Each byte's difference modulo 256 without borrows between bytes, `d = ((w | H) - (L &
/// !H)) ^ ((w ^ !L) & H)` (`H` the bytes' top bits, `L` = `lo` in every byte: the low seven bits subtract with the top
/// bit set, so no borrow leaves a byte, and the top bit is then corrected), then whether any byte of `d` is below `n =
/// span + 1 <= 128`: `(d - N) & !d & H` is nonzero exactly then (`N` = `n` in every byte: the lowest such byte borrows
/// and keeps its top bit clear in `d`; no byte at or above `n` with a clear top bit borrows unless one below it did).
#[derive(Clone, Copy)]
struct Reach {
    low: u32,
    top: u32,
    n: u32,
}

impl Reach {
    const H: u32 = 0x8080_8080;
    #[inline(always)]
    fn new(lo: u8, span: u8) -> Reach {
        let l = u32::from(lo) * 0x0101_0101;
        Reach {
            low: l & !Self::H,
            top: !l & Self::H,
            n: (u32::from(span) + 1) * 0x0101_0101,
        }
    }
    /// Whether a byte of `w` is in reach (see [`next_in_reach`]).
    #[inline(always)]
    fn any(self, w: u32) -> bool {
        let d = ((w | Self::H).wrapping_sub(self.low)) ^ ((w & Self::H) ^ self.top);
        d.wrapping_sub(self.n) & !d & Self::H != 0
    }
}

/// Whether all three vertices were mapped to the screen by `transform_mesh` (`rhw > 0`, compared as integers:
/// positive floats have positive bit patterns, and 0 marks a vertex to clip).
#[inline]
fn on_screen(v: &[Projected; 3]) -> bool {
    v.iter().all(|p| (p.rhw.to_bits() as i32) > 0)
}

/// A screen triangle's vertices `k` of `frame`.
#[inline]
fn screen_tri<C>(frame: &MeshFrame<'_, C>, k: usize) -> [Projected; 3] {
    frame.mesh.indices[k].map(|i| frame.verts[i as usize])
}

/// The screen area of a triangle (doubled; y down: positive is clockwise on the display), in f32.
#[cfg(test)]
fn screen_area(a: &Projected, b: &Projected, c: &Projected) -> f32 {
    (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)
}

/// Whether a triangle on screen is culled as `cull` says: by the sign of the doubled area of its snapped vertices
/// ([`crate::input::snapped_area`]), the test the rasterizer applies to every triangle it is given, so that culling
/// here (once a frame, before the set-up) drops exactly the triangles the draws would drop (a zero area among them:
/// it covers no pixel). Where the core has an FPU the float area decides first when it is far enough from zero
/// ([`clear_area`]); otherwise, and on cores without an FPU (where each float operation is a library call of some 60
/// to 90 instructions), the snapped area itself. The same triangles either way, on every core.
#[inline]
fn culled_on_screen(cull: Cull, v: &[Projected; 3]) -> bool {
    let area = if crate::input::HARD_FLOAT {
        if let Some(area) = clear_area(v) {
            return culled(cull, area);
        }
        None
    } else {
        clear_area_fixed(v)
    };
    let [a, b, c] = v;
    match area.or_else(|| crate::input::snapped_area([(a.x, a.y), (b.x, b.y), (c.x, c.y)])) {
        Some(area) => match cull {
            _ if area == 0 => true,
            Cull::Cw => area > 0,
            Cull::Ccw => area < 0,
            Cull::None => false,
        },
        // Not reached for vertices `transform_mesh` put on screen (finite, inside the clip band, which is inside the
        // guard band): the draw reports it.
        None => false,
    }
}

/// [`culled_on_screen`]'s float test: the f32 doubled area where it is far enough from zero that the snapped area
/// has its sign (nonzero), else `None`. With `u = b - a`, `v = c - a` and `S = |ux| + |uy| + |vx| + |vy|`:
/// snapping moves each coordinate by at most `2^-9` px, each difference by `2^-8`, so the snapped area is within
/// `2^-8 S + 2^-15` of the exact area of the vertices as given (the cross terms, and the product of two moves twice).
/// The f32 evaluation (three roundings on each product's path, one on the difference) is within
/// `4.01 2^-24 (|ux vy| + |vx uy|)` of that, and on screen every coordinate is within the clip band (`|x| <= 4000`),
/// so each difference is at most 8000 and `|ux vy| + |vx uy| <= 8000 S`: within `2^-8.9 S`. Both together are below
/// `2^-7 S + 2^-14`, with room for the rounding of `S` itself (relative `2^-22`) and any underflow (`2^-149`).
#[inline]
fn clear_area([a, b, c]: &[Projected; 3]) -> Option<f32> {
    let (ux, uy, vx, vy) = (b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y);
    let area = ux * vy - vx * uy;
    (area.abs() > (ux.abs() + uy.abs() + vx.abs() + vy.abs()) * (1.0 / 128.0) + 1.0 / 16384.0)
        .then_some(area)
}

/// [`clear_area`] for cores without an FPU, in integers: the doubled area `At` of the vertices truncated to the
/// snap grid ([`crate::input::fixed_trunc`], units of `2^-8` px, within one unit of `256 x`), where its sign is the
/// snapped area's, else `None`. With `S` the sum of the four differences' magnitudes (real, in units) and
/// `St` the truncated ones' (within 8 of `S`): the snapped area is within `S + 2` units² of the exact area times
/// `2^16` ([`clear_area`]'s argument in units), and `At` within `2 S + 8` (each difference is off by below 2 units).
/// So where `|At| > 3 St + 34 >= 3 S + 10`, the snapped area has `At`'s sign and is not zero.
#[inline]
fn clear_area_fixed([a, b, c]: &[Projected; 3]) -> Option<i64> {
    use crate::input::fixed_trunc as t;
    let (ux, uy) = (t(b.x) - t(a.x), t(b.y) - t(a.y));
    let (vx, vy) = (t(c.x) - t(a.x), t(c.y) - t(a.y));
    // Coordinates within the clip band (below 2^20 units): differences below 2^21, products below 2^42.
    let area = crate::fast::smul_wide(ux, vy) - crate::fast::smul_wide(vx, uy);
    let st = ux.unsigned_abs() + uy.unsigned_abs() + vx.unsigned_abs() + vy.unsigned_abs();
    // `st` below 2^23: `3 st + 34` fits a u32 (a u64 product would be a library call on the Cortex-M0).
    (area.unsigned_abs() > (3 * st + 34) as u64).then_some(area)
}

/// `v as i32` (toward zero, saturating, NaN to 0): the FPU's conversion where the core has one, else from the bits
/// (where `as i32` is four library calls: the NaN test, two range tests and the conversion).
#[inline]
fn trunc(v: f32) -> i32 {
    if crate::input::HARD_FLOAT {
        v as i32
    } else {
        trunc_bits(v)
    }
}

/// [`trunc`] from the bits.
#[inline]
fn trunc_bits(v: f32) -> i32 {
    let b = v.to_bits();
    let mag = b & 0x7fff_ffff;
    let exp = (mag >> 23) as i32;
    let r = if mag > 0x7f80_0000 || exp < 127 {
        0 // NaN, or below 1 in magnitude
    } else if exp >= 127 + 31 {
        return if b >> 31 != 0 { i32::MIN } else { i32::MAX };
    } else {
        let m = (mag & 0x7f_ffff) | 0x80_0000;
        (if exp >= 150 {
            m << (exp - 150)
        } else {
            m >> (150 - exp)
        }) as i32 // below 2^31
    };
    if b >> 31 != 0 {
        -r
    } else {
        r
    }
}

/// An integer with the order of the (non-NaN) f32 `y`: the bits, with the magnitude flipped for negative values.
#[inline]
fn key(y: f32) -> i32 {
    let b = y.to_bits() as i32;
    b ^ (((b >> 31) as u32) >> 1) as i32
}

/// Whether a triangle with screen area `area` (y down; positive = clockwise on the display) is culled. A zero or NaN
/// area is culled whatever the mode: it covers no pixel.
#[inline]
fn culled(cull: Cull, area: f32) -> bool {
    match cull {
        _ if !(area != 0.0) => true,
        Cull::Cw => area > 0.0,
        Cull::Ccw => area < 0.0,
        Cull::None => false,
    }
}

impl<R: WSpan> Rasterizer<R> {
    /// Transforms `mesh` by `m` (object to clip space, row vectors; a camera's `model_matrix`) and maps it through
    /// `vp` into `scratch` (at least one [`Projected`] per position), once per frame. Checks everything the draws
    /// need, so a draw of the frame cannot fail on its input: [`Error::BufferSize`] for a short `scratch`,
    /// [`Error::IndexOutOfRange`] for an index beyond `positions` or too few colours, [`Error::NonFinite`] for a
    /// NaN or infinity in a position, `m` or `vp`, [`Error::WorldTooLarge`] for a vertex whose clip coordinates
    /// overflow f32.
    pub fn transform_mesh<'a, C: Copy>(
        &self,
        mesh: &Mesh<'a, C>,
        m: &Mat4,
        vp: &Viewport,
        scratch: &'a mut [Projected],
    ) -> Result<MeshFrame<'a, C>, Error> {
        let n = mesh.positions.len();
        if scratch.len() < n {
            return Err(Error::BufferSize {
                expected: n,
                actual: scratch.len(),
            });
        }
        let colors_ok = match mesh.colors {
            Colors::Uniform(_) => true,
            Colors::PerFace(f) => f.len() >= mesh.indices.len(),
            Colors::PerVertex(v) => v.len() >= n,
        };
        if !colors_ok || mesh.indices.iter().flatten().any(|&i| i as usize >= n) {
            return Err(Error::IndexOutOfRange);
        }
        check_matrix(m)?;
        let planes = Planes::new(self.state.range.near(), vp)?;
        if R::INTEGER_TRANSFORM {
            let it = IntTransform::new(m, &planes, mesh.positions)?;
            for (p, s) in mesh.positions.iter().zip(scratch.iter_mut()) {
                *s = it.project(p)?.unwrap_or_default();
            }
        } else {
            for (p, s) in mesh.positions.iter().zip(scratch.iter_mut()) {
                let c = to_clip(m, p)?;
                *s = if planes.outcode(&c) == 0 {
                    let [x, y, _, rhw] = planes.map_checked(&c)?;
                    Projected { x, y, rhw }
                } else {
                    Projected::default()
                };
            }
        }
        Ok(MeshFrame {
            mesh: *mesh,
            m: *m,
            planes,
            verts: &scratch[..n],
            bins: None,
        })
    }

    /// Bins a transformed frame's triangles by rows, once per frame, for drawing it in bands: each band's
    /// [`Rasterizer::draw_mesh_frame`] then sets up only the triangles whose top row lies within reach of its rows
    /// (and those to clip), after a one-byte test per triangle instead of a test of its vertices, and the triangles on
    /// screen are culled here once instead of in every band they reach. `bins` (caller storage, one byte per
    /// triangle) holds each triangle's row bucket.
    ///
    /// The draws of a binned frame give the same pixels and codes and count the same fragments as the unbinned
    /// frame's: they draw the same triangles in the same (index) order. Their [`Stats::culled`] leaves out the
    /// triangles culled here ([`MeshFrame::binned_culled`]). A draw whose render state culls otherwise than this
    /// rasterizer's walks every triangle, as an unbinned frame does. Error: [`Error::BufferSize`] for `bins` shorter
    /// than the triangles.
    ///
    /// The bins are a slice the caller sizes to its mesh, not a `heapless` collection: a byte per triangle, indexed
    /// by triangle, with no count to keep, and a capacity that is the mesh's, known where the mesh is (a firmware's
    /// `static` beside its vertices), not fixed in the crate.
    pub fn bin_mesh<'a, C: Copy>(
        &self,
        frame: MeshFrame<'a, C>,
        bins: &'a mut [u8],
    ) -> Result<MeshFrame<'a, C>, Error> {
        let n = frame.mesh.indices.len();
        if bins.len() < n {
            return Err(Error::BufferSize {
                expected: n,
                actual: bins.len(),
            });
        }
        let of = &mut bins[..n];
        let cull = self.state.cull;
        // The rows of a screen triangle (its vertices' least and greatest y picked by `key`: no float compare).
        let rows = |[a, b, c]: [Projected; 3]| {
            let (ka, kb, kc) = (key(a.y), key(b.y), key(c.y));
            let ymin = if ka <= kb && ka <= kc {
                a.y
            } else if kb <= kc {
                b.y
            } else {
                c.y
            };
            let ymax = if ka >= kb && ka >= kc {
                a.y
            } else if kb >= kc {
                b.y
            } else {
                c.y
            };
            Bins::rows(ymin, ymax)
        };
        // First pass: cull, and the top rows' range and the reach of the triangles kept on screen (marked 0).
        let (mut lo, mut hi, mut reach, mut culled_n) = (i32::MAX, i32::MIN, 0, 0u32);
        let mut clips = false;
        for (k, b) in of.iter_mut().enumerate() {
            let v = screen_tri(&frame, k);
            *b = if on_screen(&v) {
                if culled_on_screen(cull, &v) {
                    culled_n += 1;
                    CULLED
                } else {
                    let (top, bottom) = rows(v);
                    (lo, hi, reach) = (lo.min(top), hi.max(top), reach.max(bottom - top));
                    0
                }
            } else {
                clips = true;
                CLIP
            };
        }
        if lo > hi {
            (lo, hi) = (0, 0); // nothing on screen
        }
        // Rows within the guard band: `hi - lo` is below 2^14, so the shift stops below 7.
        let mut shift = 0;
        while (hi - lo) >> shift >= BUCKETS {
            shift += 1;
        }
        let mut bins = Bins {
            of: &[],
            origin: lo,
            shift,
            reach,
            cull,
            culled: culled_n,
            clips,
        };
        // Second pass: the bucket of each kept triangle's top row.
        for (k, b) in of.iter_mut().enumerate() {
            if *b == 0 {
                *b = bins.bucket(rows(screen_tri(&frame, k)).0);
            }
        }
        bins.of = of;
        Ok(MeshFrame {
            bins: Some(bins),
            ..frame
        })
    }
}

impl<R: SpanRecip> Rasterizer<R> {
    /// Draws a transformed mesh into `depth` (a whole frame or a band: only the triangles that can touch its rows
    /// are set up), flat-shaded, back faces dropped as the render state's [`Cull`] says. With the render state the
    /// frame was transformed with, it fails only when `target` fails (then as [`Rasterizer::draw`] says).
    pub fn draw_mesh_frame<'a, D, F>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        frame: &F,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor + 'a,
        F: DrawFrame<'a, D::Color>,
    {
        let mut stats = Stats::default();
        let (y0, h, cull) = (depth.y0(), depth.height(), self.state.cull);
        frame.begin(y0, h, self.memo_tag());
        let last = y0.saturating_add(h as i32 - 1);
        frame
            .frame()
            .for_each(cull, y0, h, &mut stats, &|c, _| c[0], |k, v| {
                self.draw_memo(target, depth, &v, &mut frame.memo(k, last))
            })?;
        Ok(stats)
    }

    /// Draws triangle `k` of `frame` into a W16 buffer: the same pixels, codes and statistics as
    /// [`Rasterizer::draw`] of its vertices, with what [`PlaneCache::list`] describes remembered from the previous
    /// band for the next. A band begins with the first draw whose buffer ends at another row than the last one's; the
    /// cache helps where the bands come top to bottom and, within a band, the triangles in increasing `k` (any other
    /// order draws the same, computing more). `k` beyond the list: [`Error::IndexOutOfRange`].
    pub fn draw_listed<D, T>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        frame: &ListFrame<'_, T>,
        k: usize,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        T: Triangle,
        T::Vertex: VertexInput<Color = D::Color>,
    {
        let t = frame.tris.get(k).ok_or(Error::IndexOutOfRange)?;
        let (y0, h) = (depth.y0(), depth.height());
        frame.cache.enter(y0, h, self.memo_tag());
        let last = y0.saturating_add(h as i32 - 1);
        let mut memo = u32::try_from(k)
            .ok()
            .filter(|&k| k <= INDEX)
            .map(|k| sealed::Remembered {
                cache: frame.cache,
                k,
                last,
            });
        self.draw_remembered(target, depth, t, &mut memo)
    }

    /// [`Rasterizer::draw_memo`] of `t` out of line: one copy, outside the caller's loop, which reads the vertices
    /// itself (measured on the Cortex-M0's W3: 1.9% fewer instructions than inline).
    #[inline(never)]
    fn draw_remembered<D, T>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        t: &T,
        memo: &mut Option<sealed::Remembered<'_>>,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
        T: Triangle,
        T::Vertex: VertexInput<Color = D::Color>,
    {
        self.draw_memo(target, depth, &t.vertices(), memo)
    }

    /// [`Rasterizer::transform_mesh`] then [`Rasterizer::draw_mesh_frame`]: a whole frame in one call.
    pub fn draw_mesh<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        mesh: &Mesh<'_, D::Color>,
        m: &Mat4,
        vp: &Viewport,
        scratch: &mut [Projected],
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor,
    {
        let frame = self.transform_mesh(mesh, m, vp, scratch)?;
        self.draw_mesh_frame(target, depth, &frame)
    }

    /// [`Rasterizer::draw_mesh_frame`] with per-vertex colours interpolated perspective-correctly
    /// ([`Rasterizer::draw_gouraud`], feature `gouraud`); a clipped vertex's colour is the mix of the triangle's
    /// three by its barycentric weights in clip space.
    #[cfg(feature = "gouraud")]
    pub fn draw_mesh_frame_gouraud<D>(
        &mut self,
        target: &mut D,
        depth: &mut DepthBuffer<'_>,
        frame: &MeshFrame<'_, D::Color>,
    ) -> Result<Stats, Error>
    where
        D: DrawTarget,
        D::Color: PixelColor
            + From<embedded_graphics_core::pixelcolor::Rgb888>
            + Into<embedded_graphics_core::pixelcolor::Rgb888>,
    {
        use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};
        let mix = |c: [D::Color; 3], w: [f32; 3]| {
            let rgb = c.map(|c| {
                let c: Rgb888 = c.into();
                [c.r() as f32, c.g() as f32, c.b() as f32]
            });
            let ch = |i: usize| {
                let v = w[0] * rgb[0][i] + w[1] * rgb[1][i] + w[2] * rgb[2][i] + 0.5;
                v.clamp(0.0, 255.0) as u8
            };
            D::Color::from(Rgb888::new(ch(0), ch(1), ch(2)))
        };
        let mut stats = Stats::default();
        let (y0, h, cull) = (depth.y0(), depth.height(), self.state.cull);
        frame.for_each(cull, y0, h, &mut stats, &mix, |_, v| {
            self.draw_gouraud(target, depth, &v)
        })?;
        Ok(stats)
    }
}

/// A sphere enclosing a mesh, in its object space: the cheap test before a frame's transform
/// ([`Sphere::visible`]): a mesh wholly outside the view costs one point's transform and six plane tests, not a
/// transform of every vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, object space.
    pub center: [f32; 3],
    /// Radius, object units.
    pub radius: f32,
}

impl Sphere {
    /// A sphere holding every point of `positions`: the centre of their bounding box and the largest distance from
    /// it, rounded up (distances scaled by the largest coordinate difference, so no square overflows; the scaling,
    /// squares, sum and square root carry under `2^-21` relative, and the radius is widened by `2^-18`, so every
    /// position lies inside in exact arithmetic). Not the smallest sphere (within `sqrt(3)` of it), but one
    /// pass and no iteration. [`Error::NonFinite`] for a NaN or infinite coordinate; an empty slice gives radius 0
    /// at the origin. A box whose size overflows f32 gives an infinite radius, which [`Sphere::visible`] never culls.
    pub fn enclosing(positions: &[[f32; 3]]) -> Result<Sphere, Error> {
        if positions.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite);
        }
        let Some(first) = positions.first() else {
            return Ok(Sphere {
                center: [0.0; 3],
                radius: 0.0,
            });
        };
        let (mut lo, mut hi) = (*first, *first);
        for p in positions {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        // Halves first: `lo + hi` may overflow where the centre does not.
        let center = [0, 1, 2].map(|i| lo[i] * 0.5 + hi[i] * 0.5);
        // Distances scaled by the largest coordinate difference `s`, so their squares cannot overflow or underflow.
        let s = positions.iter().fold(0.0f32, |m, p| {
            (0..3).fold(m, |m, i| m.max((p[i] - center[i]).abs()))
        });
        if s == 0.0 {
            return Ok(Sphere {
                center,
                radius: 0.0,
            });
        }
        let r2 = positions.iter().fold(0.0f32, |m, p| {
            let d = [0, 1, 2].map(|i| (p[i] - center[i]) / s);
            m.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        });
        let radius = s * crate::projection::sqrt(r2) * (1.0 + 1.0 / 262_144.0);
        Ok(Sphere {
            center,
            radius: if radius.is_finite() {
                radius
            } else {
                f32::INFINITY
            },
        })
    }

    /// Whether any of the sphere can reach the screen: `false` only when it lies wholly outside one of the six
    /// planes bounding what a draw can write: the screen rectangle `[0, size.width] x [0, size.height]` mapped back
    /// through `vp` (so a target larger than the viewport, drawn into through the guard band, is allowed for), the
    /// near plane `W = W_near` and the far plane `W = W_far` of `range` (the range test writes nothing beyond it).
    /// `m` takes the sphere's object space to clip space, as for [`Rasterizer::transform_mesh`] (a camera's
    /// `model_matrix`).
    ///
    /// Each plane is `k . c + k_c >= 0` in clip space (for `w > 0`, where a point can be drawn at all; screen
    /// `x >= 0` is `sx x + ox w >= 0`, ...), so in object space `L(p) = a . p + a_3` with `a = M k`; the sphere is
    /// outside when `L(centre) < -radius |a|`. The centre is transformed once (its clip `x`, `y`, `w`), `|a|^2` comes
    /// from the Gram products of `M`'s `x`, `y` and `w` columns, and the test is compared squared (no square root).
    /// Rounding: `L` errs by under `2^-20` of `T`, the sum of its terms' magnitudes, and `|a|^2` by under `2^-20` of
    /// `B`, its terms' magnitudes; the test subtracts `2^-16 T` from `-L` and adds `2^-20 B` to `|a|^2`, so a mesh is
    /// culled only when the exact test would cull it. A NaN or overflow anywhere gives `true`. A viewport the draws
    /// refuse (a clip width or height that is not positive: `transform_mesh` returns [`Error::NonFinite`]) may give
    /// either answer.
    pub fn visible(
        &self,
        m: &Mat4,
        vp: &Viewport,
        size: embedded_graphics_core::geometry::Size,
        range: &crate::DepthRange,
    ) -> bool {
        // The screen mapping (as `clip::Planes`): x = ox + (x/w) sx, y = oy - (y/w) sy.
        let (sx, sy) = (vp.width / vp.clip_width, vp.height / vp.clip_height);
        let (ox, oy) = (vp.x - vp.clip_x * sx, vp.y + vp.clip_y * sy);
        if !(sx.is_finite() && sy.is_finite() && ox.is_finite() && oy.is_finite()) {
            return true;
        }
        let (c, r, m) = (self.center, self.radius, &m.0);
        // The centre's clip x, y, w and their terms' magnitudes; the Gram products of the columns.
        let col = |j: usize| {
            let v = c[0] * m[0][j] + c[1] * m[1][j] + c[2] * m[2][j] + m[3][j];
            let g = (c[0] * m[0][j]).abs()
                + (c[1] * m[1][j]).abs()
                + (c[2] * m[2][j]).abs()
                + m[3][j].abs();
            (v, g)
        };
        let dot = |i: usize, j: usize| m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j];
        let ((x, gx), (y, gy), (w, gw)) = (col(0), col(1), col(3));
        let (xx, yy, ww, xw, yw) = (dot(0, 0), dot(1, 1), dot(3, 3), dot(0, 3), dot(1, 3));
        // Outside plane `ka * (x or y) + kw * w + kc >= 0`, column Gram products `aa`, `aw` for its axis.
        let outside = |ka: f32, v: f32, g: f32, aa: f32, aw: f32, kw: f32, kc: f32| {
            let l = ka * v + kw * w + kc;
            let t = ka.abs() * g + kw.abs() * gw + kc.abs();
            let d = -l - t * (1.0 / 65_536.0);
            let a2 = ka * ka * aa + 2.0 * ka * kw * aw + kw * kw * ww;
            let b = ka * ka * aa + (2.0 * ka * kw * aw).abs() + kw * kw * ww;
            // NaN (an overflow) fails every comparison: not outside.
            d > 0.0 && t.is_finite() && d * d > r * r * (a2 + b * (1.0 / 1_048_576.0))
        };
        let (wd, ht) = (size.width as f32, size.height as f32);
        !(outside(sx, x, gx, xx, xw, ox, 0.0) // screen x >= 0
            || outside(-sx, x, gx, xx, xw, wd - ox, 0.0) // screen x <= width
            || outside(-sy, y, gy, yy, yw, oy, 0.0) // screen y >= 0
            || outside(sy, y, gy, yy, yw, ht - oy, 0.0) // screen y <= height
            || outside(0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -range.near()) // W >= W_near
            || outside(0.0, 0.0, 0.0, 0.0, 0.0, -1.0, range.far())) // W <= W_far
    }
}

/// `i % n` for `i < 2 n` (a ring index: the head and a length, each below `n`), without the division (a library
/// call on the Cortex-M0, where a band's cache keeps its triangles in the ring).
#[inline(always)]
fn wrap(i: usize, n: usize) -> usize {
    debug_assert!(i < 2 * n.max(1));
    if i >= n {
        i - n
    } else {
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recip::Fast;
    use crate::RenderState;
    use std::vec;
    use std::vec::Vec;

    /// Draws `tris` into a frame of `w` x `h` pixels in bands of `rows` (bottom to top when `up`), each triangle `k`
    /// with `draw(band, depth, k)` into a cleared band: the frame's RGB565 colours and W16 codes, and the statistics.
    fn draw_in_bands(
        (w, h): (usize, usize),
        rows: usize,
        up: bool,
        n: usize,
        mut draw: impl FnMut(
            &mut crate::ColorBand<'_, embedded_graphics_core::pixelcolor::Rgb565>,
            &mut DepthBuffer<'_>,
            usize,
        ) -> Stats,
    ) -> (Vec<u16>, Vec<u16>, Stats) {
        let (mut px, mut z) = (vec![0u16; w * h], vec![0u16; w * h]);
        let mut stats = Stats::default();
        let mut bands: Vec<usize> = (0..h).step_by(rows).collect();
        if up {
            bands.reverse();
        }
        for y0 in bands {
            let bh = rows.min(h - y0);
            let (mut cp, mut zp) = (vec![0u16; w * bh], vec![0u16; w * bh]);
            let (width, top) = (w as u16, y0 as i32);
            let mut band = crate::ColorBand::band(&mut cp, width, top, bh as u16).unwrap();
            let mut depth = DepthBuffer::band(&mut zp, width, top, bh as u16).unwrap();
            depth.clear();
            for k in 0..n {
                stats += draw(&mut band, &mut depth, k);
            }
            px[y0 * w..(y0 + bh) * w].copy_from_slice(band.pixels());
            z[y0 * w..(y0 + bh) * w].copy_from_slice(depth.data());
        }
        (px, z, stats)
    }

    /// A frame of screen vertices given as they are (as `transform_mesh` would leave them), in a 64 x 64 viewport.
    fn screen_frame<'a, C: Copy>(mesh: Mesh<'a, C>, verts: &'a [Projected]) -> MeshFrame<'a, C> {
        let vp = Viewport::new(0.0, 0.0, 64.0, 64.0);
        MeshFrame {
            mesh,
            m: Mat4::translation([0.0; 3]),
            planes: Planes::new(1.0, &vp).unwrap(),
            verts,
            bins: None,
        }
    }

    /// W4's torus (its positions, indices and per-face colours), for the tests that draw it as a mesh.
    #[cfg(feature = "scenes")]
    struct TorusParts {
        positions: [[f32; 3]; crate::scenes::torus::VERTICES],
        indices: [[u16; 3]; crate::scenes::torus::TRIANGLES],
        colors: [embedded_graphics_core::pixelcolor::Rgb565; crate::scenes::torus::TRIANGLES],
    }

    #[cfg(feature = "scenes")]
    impl TorusParts {
        fn new() -> Self {
            use crate::scenes::torus;
            TorusParts {
                positions: torus::positions(),
                indices: torus::indices(),
                colors: torus::colors(),
            }
        }
        fn mesh(&self) -> Mesh<'_, embedded_graphics_core::pixelcolor::Rgb565> {
            Mesh {
                positions: &self.positions,
                indices: &self.indices,
                colors: Colors::PerFace(&self.colors),
            }
        }
    }

    #[test]
    fn the_word_scan_finds_what_the_byte_scan_finds() {
        // Every `lo`, reaches up to 127 (the words' limit) and past it, from starts at every alignment of the word
        // (slices of a longer array at several offsets), over random bytes and bytes placed around the reach's edges:
        // the first byte in reach found four at a time is the byte loop's.
        let mut rnd = crate::xorshift(0x5EED_B175);
        let buf: Vec<u8> = (0..300).map(|_| (rnd() >> 24) as u8).collect();
        let slow = |of: &[u8], mut k: usize, lo: u8, span: u8| {
            while k < of.len() && of[k].wrapping_sub(lo) > span {
                k += 1;
            }
            k
        };
        let mut found = 0;
        for lo in 0..=253u8 {
            for span in [0u8, 1, 2, 5, 17, 64, 126, 127, 128, 200] {
                // Bytes just outside the reach on both sides, and one inside now and then.
                let edge: Vec<u8> = (0..64)
                    .map(|i| match (rnd() >> 28) % 4 {
                        0 => lo.wrapping_sub(1),
                        1 => lo.wrapping_add(span).wrapping_add(1),
                        2 if i % 9 == 0 => lo.wrapping_add(span / 2),
                        _ => 255,
                    })
                    .collect();
                for data in [&buf[(lo % 7) as usize..], &edge[(lo % 5) as usize..]] {
                    for k in [0, 1, 2, 3, 5, 17, data.len() - 1, data.len()] {
                        let want = slow(data, k, lo, span);
                        assert_eq!(
                            next_in_reach(data, k, lo, span, false),
                            want,
                            "{lo} {span} {k}"
                        );
                        found += usize::from(want < data.len());
                    }
                }
            }
        }
        assert!(found > 10_000, "{found}");
    }

    /// [`Reach::any`] says whether a byte of the word is in reach (`b - lo <= span` modulo 256), for every `lo` and
    /// every span the words take (under 128): random words, and words of bytes at the reach's edges.
    #[test]
    fn reach_finds_a_byte_in_reach_in_a_word() {
        let mut rnd = crate::xorshift(0x4EAC_4000_0000_0001);
        let (mut yes, mut no) = (0u32, 0u32);
        for lo in 0..=255u8 {
            for span in 0..128u8 {
                let reach = Reach::new(lo, span);
                for i in 0..40 {
                    let w = if i % 2 == 0 {
                        rnd() as u32
                    } else {
                        u32::from_le_bytes([0; 4].map(|_| match rnd() % 4 {
                            0 => lo.wrapping_sub(1),
                            1 => lo.wrapping_add(span).wrapping_add(1),
                            2 => lo.wrapping_add(span),
                            _ => lo,
                        }))
                    };
                    let want = w.to_le_bytes().iter().any(|b| b.wrapping_sub(lo) <= span);
                    assert_eq!(reach.any(w), want, "{lo} {span} {w:08x}");
                    if want {
                        yes += 1;
                    } else {
                        no += 1;
                    }
                }
            }
        }
        assert!(yes > 100_000 && no > 100_000, "{yes} {no}");
    }

    /// The bins of strips of small triangles whose tops run down 1.3 rows apart, every fifth one back-facing, every
    /// seventh one with a vertex to clip: 300 from row -20 (a range of 390 rows: buckets of 2 rows), 150 from row 100
    /// (193 rows: a bucket per row) and one alone. Each kept triangle's byte is the bucket of its top row
    /// `(trunc(ymin) - 1 - origin) >> shift`, with `origin` the least top row and `shift` the least that brings the
    /// range under 254 buckets; the culled and clipped ones carry their marks; rows beyond the range clamp to the first
    /// and the last bucket.
    #[test]
    fn buckets_follow_the_top_rows() {
        for (start, n, want_shift) in [(-20.0f32, 300usize, 1u32), (100.0, 150, 0), (37.2, 1, 0)] {
            let mut verts = Vec::new();
            let culls = |k: usize| k % 5 == 4;
            let clips = |k: usize| k % 7 == 3;
            for k in 0..n {
                let y = start + 1.3 * k as f32;
                let (a, b) = ((10.0, y), (20.0, y + 0.5));
                let c = (12.0, y + 3.5);
                // Clockwise on the display (y down) is a positive area: `b` and `c` swapped for the back faces.
                let (b, c) = if culls(k) { (c, b) } else { (b, c) };
                let rhw = if clips(k) { 0.0 } else { 0.5 };
                for (x, y) in [a, b, c] {
                    verts.push(Projected { x, y, rhw });
                }
            }
            let indices: Vec<[u16; 3]> = (0..n)
                .map(|k| [3 * k as u16, 3 * k as u16 + 1, 3 * k as u16 + 2])
                .collect();
            let positions = [[0.0f32; 3]; 1];
            let mesh = Mesh {
                positions: &positions,
                indices: &indices,
                colors: Colors::Uniform(0u8),
            };
            let mut state = RenderState::new(1.0, 10.0).unwrap();
            state.cull = Cull::Ccw;
            let r = Rasterizer::<Fast>::new(state);
            let frame = screen_frame(mesh, &verts);
            let mut bytes = vec![0u8; n];
            let binned = r.bin_mesh(frame, &mut bytes).unwrap();
            let b = binned.bins.unwrap();
            let kept = |k: &usize| !culls(*k) && !clips(*k);
            let top = |k: usize| (start + 1.3 * k as f32) as i32 - 1;
            let origin = (0..n).filter(kept).map(top).min().unwrap();
            let range = (0..n).filter(kept).map(top).max().unwrap() - origin;
            let shift = (0..).find(|&s| range >> s < 254).unwrap();
            assert_eq!(
                (b.origin, b.shift, shift),
                (origin, want_shift, want_shift),
                "from {start}"
            );
            // The reach: the tallest kept triangle's rows, 3.5 rows of y and the margin.
            let reach = (0..n)
                .filter(kept)
                .map(|k| (start + 1.3 * k as f32 + 3.5) as i32 - top(k))
                .max()
                .unwrap();
            assert_eq!(b.reach, reach);
            let mut spread = std::collections::BTreeSet::new();
            for k in 0..n {
                let want = if clips(k) {
                    CLIP
                } else if culls(k) {
                    CULLED
                } else {
                    ((top(k) - origin) >> shift) as u8
                };
                assert_eq!(b.of[k], want, "from {start}: triangle {k}");
                spread.insert(b.of[k]);
            }
            assert!(spread.len() >= n / 2, "from {start}");
            let culled = (0..n).filter(|&k| culls(k) && !clips(k)).count() as u32;
            assert_eq!(binned.binned_culled(), Some(culled));
            assert_eq!(b.bucket(origin - 100), 0);
            assert_eq!(b.bucket(origin + 5), (5 >> shift) as u8);
            assert_eq!(b.bucket(origin + 10_000), (BUCKETS - 1) as u8);
        }
    }

    /// A target that takes any pixel.
    struct Null;
    impl embedded_graphics_core::geometry::OriginDimensions for Null {
        fn size(&self) -> embedded_graphics_core::geometry::Size {
            embedded_graphics_core::geometry::Size::new(64, 64)
        }
    }
    impl DrawTarget for Null {
        type Color = embedded_graphics_core::pixelcolor::BinaryColor;
        type Error = core::convert::Infallible;
        fn draw_iter<I>(&mut self, _: I) -> Result<(), Self::Error>
        where
            I: IntoIterator<Item = embedded_graphics_core::Pixel<Self::Color>>,
        {
            Ok(())
        }
    }

    /// A band's walk looks only at triangles whose rows can hold a covered centre of the band: a back face just above
    /// the band (its lowest vertex 0.3 px above the band's first row, whose centres are 0.5 px below it) and one just
    /// below are not counted as culled there, while one reaching into the band is.
    #[test]
    fn a_band_counts_only_the_triangles_it_can_reach() {
        use embedded_graphics_core::pixelcolor::BinaryColor;
        // Three triangles wound alike, and the cull mode that drops that winding.
        let tri = |y0: f32, y1: f32| {
            [(10.0, y0), (12.0, y1), (20.0, y0)].map(|(x, y)| Projected { x, y, rhw: 0.5 })
        };
        let verts: Vec<Projected> = [tri(5.0, 9.7), tri(14.3, 18.0), tri(8.0, 11.0)].concat();
        let indices = [[0u16, 1, 2], [3, 4, 5], [6, 7, 8]];
        let positions = [[0.0f32; 3]; 1];
        let mesh = Mesh {
            positions: &positions,
            indices: &indices,
            colors: Colors::Uniform(BinaryColor::On),
        };
        let area = screen_area(&verts[0], &verts[1], &verts[2]);
        let mut state = RenderState::new(1.0, 10.0).unwrap();
        state.cull = if area > 0.0 { Cull::Cw } else { Cull::Ccw };
        let mut r = Rasterizer::<Fast>::new(state);
        let frame = screen_frame(mesh, &verts);
        let mut data = vec![0u16; 64 * 4];
        let mut band = crate::DepthBuffer::band(&mut data, 64, 10, 4).unwrap();
        let s = r.draw_mesh_frame(&mut Null, &mut band, &frame).unwrap();
        assert_eq!(s.culled, 1, "{s:?}");
    }

    /// W4's frame `k` drawn in bands of `rows` rows (in `order`: top to bottom, or the reverse), binned or not, with a
    /// plane cache of `N` slots or none: the frame's colours and depths, the calls of `t_at_snapped`, the triangles
    /// (by their snapped vertices) it was called for, and every triangle's values as the draws used them (once each).
    #[cfg(feature = "scenes")]
    #[allow(clippy::type_complexity)]
    type Drawn = (
        Vec<u16>,
        Vec<u16>,
        usize,
        usize,
        Vec<([(i32, i32); 3], Option<[i64; 3]>)>,
    );

    #[cfg(feature = "scenes")]
    fn torus_in_bands<R: SpanRecip, const N: usize>(
        k: usize,
        rows: u16,
        binned: bool,
        cache: Option<&mut PlaneCache<N>>,
        reverse: bool,
        alternate: bool,
    ) -> Drawn {
        use crate::scenes::torus;
        use embedded_graphics_core::pixelcolor::Rgb565;
        let (w, h) = (320u16, 240u16);
        let torus_parts = TorusParts::new();
        let mesh = torus_parts.mesh();
        let cam = torus::camera().unwrap();
        let mut r = Rasterizer::<R>::new(cam.render_state().unwrap());
        let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
        let (mut verts, mut bins) = (
            vec![Projected::default(); torus::VERTICES],
            vec![0u8; torus::TRIANGLES],
        );
        let m = cam.model_matrix(&torus::model(k));
        let mut frame = r.transform_mesh(&mesh, &m, &vp, &mut verts).unwrap();
        if binned {
            frame = r.bin_mesh(frame, &mut bins).unwrap();
        }
        // `alternate`: every second and third band of three by another strategy, with the far plane further out
        // (the cache must not hand one's values to the other).
        let mut other = cam.render_state().unwrap();
        other.range = crate::DepthRange::new(torus::DEPTH.0, torus::DEPTH.1 * 1.5).unwrap();
        let (mut r2, mut r3) = (
            Rasterizer::<crate::recip::FastDiv>::new(other),
            Rasterizer::<crate::recip::Fast>::new(other),
        );
        let (mut color, mut depth) = (
            vec![0u16; w as usize * h as usize],
            vec![0u16; w as usize * h as usize],
        );
        crate::setup::T_AT_SNAPPED_CALLS.with(|c| c.borrow_mut().clear());
        crate::setup::FAST_T_USED.with(|c| c.borrow_mut().clear());
        let mut y0s: Vec<u16> = (0..h).step_by(rows as usize).collect();
        if reverse {
            y0s.reverse();
        }
        let mut bands =
            |f: &mut dyn FnMut(&mut crate::ColorBand<'_, Rgb565>, &mut DepthBuffer<'_>, u16)| {
                for &y0 in &y0s {
                    let n = rows.min(h - y0);
                    let at = y0 as usize * w as usize..(y0 + n) as usize * w as usize;
                    let mut band =
                        crate::ColorBand::<Rgb565>::band(&mut color[at.clone()], w, y0 as i32, n)
                            .unwrap();
                    let mut buf =
                        crate::DepthBuffer::band(&mut depth[at], w, y0 as i32, n).unwrap();
                    buf.clear();
                    f(&mut band, &mut buf, y0 / rows % 3);
                }
            };
        // Draws band `turn` of three of `frame` (`alternate`: the second and third by the other rasterizers).
        type Rs<'r, R> = (
            &'r mut Rasterizer<R>,
            &'r mut Rasterizer<crate::recip::FastDiv>,
            &'r mut Rasterizer<crate::recip::Fast>,
        );
        fn drawer<'a, 'r, F: DrawFrame<'a, Rgb565>, R: SpanRecip>(
            frame: &'r F,
            rs: Rs<'r, R>,
            alternate: bool,
        ) -> impl FnMut(&mut crate::ColorBand<'_, Rgb565>, &mut DepthBuffer<'_>, u16) + 'r {
            move |band, buf, turn| {
                match (alternate, turn) {
                    (true, 1) => rs.1.draw_mesh_frame(band, buf, frame),
                    (true, 2) => rs.2.draw_mesh_frame(band, buf, frame),
                    _ => rs.0.draw_mesh_frame(band, buf, frame),
                }
                .unwrap();
            }
        }
        let rs = (&mut r, &mut r2, &mut r3);
        match cache {
            Some(c) => bands(&mut drawer(&frame.with_plane_cache(c), rs, alternate)),
            None => bands(&mut drawer(&frame, rs, alternate)),
        }
        let mut calls = crate::setup::T_AT_SNAPPED_CALLS.with(|c| c.take());
        let n = calls.len();
        calls.sort_unstable();
        calls.dedup();
        let mut used = crate::setup::FAST_T_USED.with(|c| c.take());
        used.sort_unstable();
        used.dedup();
        (color, depth, n, calls.len(), used)
    }

    /// The plane cache draws exactly what the frame draws without it (W4's frames, both fast strategies, binned and
    /// not, bands of 1 to 8 rows, caches of 1 to 200 slots), computes the depth-grid values no more often, and, with
    /// room for every triangle that crosses a band's edge, exactly as often as one band of the whole frame does
    /// (once per triangle). Bands drawn bottom to top (not the next band each time) empty it: the same count as
    /// without a cache. A cache left from another frame or strategy is emptied by `with_plane_cache`.
    #[test]
    #[cfg(feature = "scenes")]
    fn the_plane_cache_draws_the_same_and_computes_each_triangle_once() {
        fn check<R: SpanRecip>() {
            let (mut small, mut mid, mut big) = (
                PlaneCache::<1>::new(),
                PlaneCache::<26>::new(),
                PlaneCache::<200>::new(),
            );
            for k in [0, 3, 6] {
                let (c1, d1, ..) = torus_in_bands::<R, 0>(k, 240, false, None, false, false);
                for (rows, binned) in [(4, true), (1, false), (8, true), (7, false)] {
                    // Without a cache: each triangle in every band it reaches.
                    let (c, d, plain, distinct, used) =
                        torus_in_bands::<R, 0>(k, rows, binned, None, false, false);
                    assert!(c == c1 && d == d1);
                    assert!(
                        distinct > 300 && plain > distinct + distinct / 2,
                        "{plain} {distinct}"
                    );
                    // Each triangle's values exactly as computed (a remembered value is the computed one).
                    assert_eq!(used.len(), distinct);
                    let (c, d, n, m, u) =
                        torus_in_bands::<R, 1>(k, rows, binned, Some(&mut small), false, false);
                    assert!(
                        c == c1
                            && d == d1
                            && u == used
                            && n <= plain
                            && n > distinct
                            && m == distinct,
                        "{n}"
                    );
                    let (c, d, n, m, u) =
                        torus_in_bands::<R, 26>(k, rows, binned, Some(&mut mid), false, false);
                    assert!(
                        c == c1
                            && d == d1
                            && u == used
                            && n < plain
                            && n >= distinct
                            && m == distinct,
                        "{n}"
                    );
                    // Room for every crossing triangle: each computed once.
                    let (c, d, n, m, u) =
                        torus_in_bands::<R, 200>(k, rows, binned, Some(&mut big), false, false);
                    assert!(c == c1 && d == d1 && u == used, "rows {rows}");
                    assert!(
                        n == distinct && m == distinct,
                        "rows {rows}: {n} {m} {distinct}"
                    );
                    // Bottom to top: no band follows the previous one, so nothing is reused.
                    let (c, d, n, _, u) =
                        torus_in_bands::<R, 200>(k, rows, binned, Some(&mut big), true, false);
                    assert!(c == c1 && d == d1 && u == used && n == plain, "{n} {plain}");
                    // Bands by turns with other strategies and far planes: what they would draw without a cache, and
                    // nothing reused (no band is drawn as the previous one was).
                    let (c2, d2, plain, _, used) =
                        torus_in_bands::<R, 0>(k, rows, binned, None, false, true);
                    let (c, d, n, _, u) =
                        torus_in_bands::<R, 200>(k, rows, binned, Some(&mut big), false, true);
                    assert!(c == c2 && d == d2 && u == used && n == plain, "{n} {plain}");
                }
            }
        }
        check::<crate::recip::Fast>();
        check::<crate::recip::FastDiv>();
    }

    /// A cache handed to a new frame by `with_plane_cache` starts empty: a frame whose first band starts where the
    /// last frame's last band ended, drawn the same way (so the band would otherwise follow it), draws what it draws
    /// with a fresh cache, though the two frames' triangles share their indices (W4's frame 0, then the same with
    /// the world scaled about the eye: the same triangles cross the split at row 128, at other depths; the middle
    /// row, 120, is a row of vertices that no triangle crosses).
    #[test]
    #[cfg(feature = "scenes")]
    fn a_new_frame_takes_nothing_from_the_last() {
        use crate::scenes::torus;
        use embedded_graphics_core::pixelcolor::Rgb565;
        let (w, h, rows) = (320u16, 240u16, 8u16);
        let torus_parts = TorusParts::new();
        let mesh = torus_parts.mesh();
        let cam = torus::camera().unwrap();
        let mut r = Rasterizer::<Fast>::new(cam.render_state().unwrap());
        let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
        let mut verts = vec![Projected::default(); torus::VERTICES];
        // Frame 0 with the world scaled by `s` about the eye (0, 0, 3): the same screen positions (to f32 rounding),
        // every `W` times `s`. Its bands from row `from` to `to` with `cache`: colour and depth.
        let mut draw = |s: f32, (from, to): (u16, u16), cache: &mut PlaneCache<200>| {
            let about_eye = Mat4::translation([0.0, 0.0, -3.0])
                * Mat4::scale([s; 3])
                * Mat4::translation([0.0, 0.0, 3.0]);
            let m = cam.model_matrix(&(torus::model(0) * about_eye));
            let frame = r.transform_mesh(&mesh, &m, &vp, &mut verts).unwrap();
            let frame = frame.with_plane_cache(cache);
            let (mut color, mut z) = (
                vec![0u16; w as usize * h as usize],
                vec![0u16; w as usize * h as usize],
            );
            for y0 in (from..to).step_by(rows as usize) {
                let at = y0 as usize * w as usize..(y0 + rows) as usize * w as usize;
                let mut band =
                    crate::ColorBand::<Rgb565>::band(&mut color[at.clone()], w, y0 as i32, rows)
                        .unwrap();
                let mut depth = DepthBuffer::band(&mut z[at], w, y0 as i32, rows).unwrap();
                depth.clear();
                r.draw_mesh_frame(&mut band, &mut depth, &frame).unwrap();
            }
            (color, z)
        };
        let mut cache = PlaneCache::<200>::new();
        draw(1.0, (0, 128), &mut cache);
        let reused = draw(1.25, (128, h), &mut cache);
        let fresh = draw(1.25, (128, h), &mut PlaneCache::new());
        assert!(reused == fresh);
        // The same pixels, other depths.
        let first = draw(1.0, (128, h), &mut PlaneCache::new());
        assert!(first.1 != fresh.1);
    }

    /// A band drawn another way than the band before it takes nothing that band kept: the cache's tag holds what its
    /// entries depend on besides the triangle (`Rasterizer::memo_tag`). The torus's frame 0 in 8-row bands, rows 0
    /// to 127 drawn one way and rows 128 on another with the same cache, against those rows drawn the second way with
    /// a fresh one:
    /// another near plane (a small triangle's remembered constants skip the range test's near side): `W_near` from the
    /// camera's to 3.0, inside the depths of the torus's lower rows (from about 2.65), the frame transformed with the
    /// camera's. The second way is seen to matter: its rows differ from the first way's. The strategies (whose entries
    /// differ: the depth-grid values by another way, a small triangle's seed, planes for the exact tier) and another
    /// far plane have tags of their own too.
    #[test]
    #[cfg(feature = "scenes")]
    fn a_band_drawn_another_way_takes_nothing_from_the_last() {
        use crate::recip::{Exact, FastDiv};
        use crate::scenes::torus;
        use embedded_graphics_core::pixelcolor::Rgb565;
        type Rows = (Vec<u16>, Vec<u16>);
        let (w, h) = (320u16, 240u16);
        let torus_parts = TorusParts::new();
        let mesh = torus_parts.mesh();
        let cam = torus::camera().unwrap();
        let state = cam.render_state().unwrap();
        let m = cam.model_matrix(&torus::model(0));
        let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
        // Bands from row `from` to `to` of `frame` into `out` (colour and depth).
        fn bands<R: SpanRecip>(
            r: &mut Rasterizer<R>,
            frame: &CachedFrame<'_, Rgb565>,
            (from, to): (u16, u16),
            out: &mut Rows,
        ) {
            let (w, rows) = (320u16, 8u16);
            for y0 in (from..to).step_by(rows as usize) {
                let at = y0 as usize * w as usize..(y0 + rows) as usize * w as usize;
                let mut band =
                    crate::ColorBand::<Rgb565>::band(&mut out.0[at.clone()], w, y0 as i32, rows)
                        .unwrap();
                let mut depth = DepthBuffer::band(&mut out.1[at], w, y0 as i32, rows).unwrap();
                depth.clear();
                r.draw_mesh_frame(&mut band, &mut depth, frame).unwrap();
            }
        }
        let blank = || -> Rows {
            (
                vec![0; w as usize * h as usize],
                vec![0; w as usize * h as usize],
            )
        };
        // Rows 128 on of `b` after rows 0 to 127 of `a` with one cache, and of `b` alone with a fresh one; and those
        // rows of `a` alone.
        fn check<A: SpanRecip, B: SpanRecip>(
            a: &mut Rasterizer<A>,
            b: &mut Rasterizer<B>,
            frame: MeshFrame<'_, Rgb565>,
            blank: &dyn Fn() -> Rows,
            what: &str,
        ) {
            let (mut shared, mut fresh, mut first) = (blank(), blank(), blank());
            let mut cache = PlaneCache::<200>::new();
            let cached = frame.with_plane_cache(&mut cache);
            bands(a, &cached, (0, 128), &mut shared);
            bands(b, &cached, (128, 240), &mut shared);
            let mut cache = PlaneCache::<200>::new();
            bands(
                b,
                &frame.with_plane_cache(&mut cache),
                (128, 240),
                &mut fresh,
            );
            let mut cache = PlaneCache::<200>::new();
            bands(
                a,
                &frame.with_plane_cache(&mut cache),
                (128, 240),
                &mut first,
            );
            let lower = 128 * 320..;
            assert!(
                shared.0[lower.clone()] == fresh.0[lower.clone()],
                "{what}: colour"
            );
            assert!(
                shared.1[lower.clone()] == fresh.1[lower.clone()],
                "{what}: depth"
            );
            assert!(
                first.1[lower.clone()] != fresh.1[lower],
                "{what}: the two ways draw alike"
            );
        }
        let mut verts = vec![Projected::default(); torus::VERTICES];
        let mut near = state;
        near.range = crate::DepthRange::new(3.0, state.range.far()).unwrap();
        let (mut fast, mut fast_near) = (
            Rasterizer::<Fast>::new(state),
            Rasterizer::<Fast>::new(near),
        );
        let frame = fast.transform_mesh(&mesh, &m, &vp, &mut verts).unwrap();
        check(&mut fast, &mut fast_near, frame, &blank, "near plane");
        let (div, exact) = (
            Rasterizer::<FastDiv>::new(state),
            Rasterizer::<Exact>::new(state),
        );
        // The strategies draw these rows alike (the fast tiers' codes agree with the exact tier's here), so that the tag
        // tells them apart is seen in the tags themselves: every pair of these ways has its own.
        let tags = [
            fast.memo_tag(),
            fast_near.memo_tag(),
            div.memo_tag(),
            exact.memo_tag(),
            Rasterizer::<Fast>::new(RenderState::new(0.5, 90.0).unwrap()).memo_tag(),
        ];
        for i in 0..tags.len() {
            for j in 0..i {
                assert_ne!(tags[i], tags[j], "ways {j} and {i}");
            }
        }
    }

    /// The cache's ring against a model, a queue with a capacity: a band that follows the previous one (it begins
    /// where that one ended, with the same tag) finds what that band kept, in triangle order, and drops what it skips;
    /// any other band, and a reset, empty it; a full ring keeps nothing more. Every kind of value comes back as it was
    /// kept (the depth-grid values or none, a plane and its fraction bits, a small triangle's constants and shifts),
    /// a small triangle's shifts beyond the key's bits are not kept, and a triangle is kept only where it reaches
    /// below the band (`Remembered`'s rule). Rings of 1 to 7 slots, random bands, triangles and values.
    #[test]
    fn the_cache_ring_follows_its_model() {
        use std::collections::VecDeque;
        let mut rnd = crate::xorshift(0xCAC4_E000_0000_0001);
        for cap in [1usize, 2, 3, 7] {
            let state = PlaneCache::<0>::new().state;
            let slots = vec![Cell::new(Slot { key: 0, t: [0; 6] }); cap];
            let cache = Cache {
                state: &state,
                slots: &slots,
            };
            cache.reset();
            let (mut queue, mut prev) = (VecDeque::<(u32, Remember)>::new(), 0usize);
            let (mut band_end, mut tag, mut next_k) = (i32::MIN, 0u64, 0u32);
            for step in 0..40_000 {
                match rnd() % 10 {
                    0 | 1 => {
                        // A band: mostly the next one, drawn the same way.
                        let y0 = if !rnd().is_multiple_of(4) {
                            band_end
                        } else {
                            (rnd() % 300) as i32
                        };
                        let (h, t) = (
                            1 + (rnd() % 8) as u16,
                            if rnd().is_multiple_of(8) {
                                rnd() % 3
                            } else {
                                tag
                            },
                        );
                        cache.begin(y0, h, t);
                        if band_end == y0 && tag == t {
                            queue.drain(..prev);
                        } else {
                            queue.clear();
                        }
                        (prev, band_end, tag, next_k) = (queue.len(), y0 + h as i32, t, 0);
                    }
                    2 if rnd().is_multiple_of(8) => {
                        cache.reset();
                        (queue, prev, band_end) = (VecDeque::new(), 0, i32::MIN);
                    }
                    // Keeps come within a band.
                    _ if band_end == i32::MIN => {}
                    2..=5 => {
                        // The band's next triangle, at or after the last one.
                        let k = (next_k + (rnd() % 3) as u32).min(INDEX);
                        next_k = k + 1;
                        let mut want = None;
                        while prev > 0 && queue[0].0 <= k {
                            let (key, r) = queue.pop_front().unwrap();
                            prev -= 1;
                            if key == k {
                                want = Some(r);
                                break;
                            }
                        }
                        assert_eq!(cache.take(k), want, "cap {cap}, step {step}");
                    }
                    _ => {
                        let k = next_k.saturating_sub(1);
                        let v = [0; 3].map(|_| rnd() as i64);
                        let r = match rnd() % 4 {
                            0 => Remember::T(Some(v)),
                            1 => Remember::T(None),
                            2 => Remember::Plane(Solved {
                                plane: Plane {
                                    row: v[0],
                                    sx: v[1],
                                    sy: v[2],
                                },
                                frac: (rnd() % 64) as u32,
                            }),
                            _ => {
                                // `s0` below 64 and 1 more than the leading zeros below 16 fit the key; now and
                                // then one beyond either.
                                let (s0, lz) = (1 + rnd() % 70, rnd() % 18);
                                Remember::Small(crate::small::Kept {
                                    s_o: v[0] as u64,
                                    sx: v[1] as u64,
                                    sy: v[2] as u64,
                                    shifts: core::num::NonZeroU16::new((s0 | lz << 8) as u16)
                                        .unwrap(),
                                })
                            }
                        };
                        let fits = match r {
                            Remember::Small(kept) => {
                                kept.shifts.get() & 0xff <= 63 && kept.shifts.get() >> 8 <= 15
                            }
                            _ => true,
                        };
                        // Through `Remembered` (the draws' memo): kept only below the band's last row.
                        let last = band_end - 1;
                        let below = rnd().is_multiple_of(2);
                        let mut memo = sealed::Remembered { cache, k, last };
                        crate::setup::TMemo::keep(
                            &mut memo,
                            r,
                            if below { last + 1 } else { last },
                        );
                        if below && fits && queue.len() < cap {
                            queue.push_back((k, r));
                        }
                    }
                }
                assert_eq!(state.len.get(), queue.len(), "cap {cap}, step {step}");
            }
        }
    }

    /// A list frame's draw (the memo draw, which snaps every vertex before it checks any `1/W`) reports the error
    /// [`Rasterizer::draw`] reports (its checks vertex by vertex: `z` and `1/W`, then the position, then `T`'s
    /// range), whatever mix of bad vertices a triangle has, and writes nothing: every vertex in each of seven kinds
    /// (good, `z` NaN, `1/W` NaN, `1/W <= 0`, `x` NaN, `y` beyond the guard band, `T` beyond its range) at each of the
    /// three places (343 triangles), for both fast-tier seeds and the exact tier.
    #[test]
    fn a_list_frame_reports_the_error_draw_reports() {
        use crate::{ColorBand, Vertex};
        use embedded_graphics_core::pixelcolor::{Rgb565, RgbColor};
        let kind = |k: usize, at: (f32, f32)| {
            let mut v = Vertex::new(at.0, at.1, 20.0, Rgb565::RED);
            match k {
                1 => v.z = f32::NAN,
                2 => v.rhw = f32::NAN,
                3 => v.rhw = -0.5,
                4 => v.x = f32::NAN,
                5 => v.y = 1.0e5,
                6 => v.rhw = 1.0e12, // T = rhw W_far far beyond 2^30
                _ => {}
            }
            v
        };
        fn check<R: SpanRecip>(tris: &[[Vertex<Rgb565>; 3]]) -> usize {
            let mut r = Rasterizer::<R>::new(RenderState::new(1.0, 500.0).unwrap());
            let mut cache = PlaneCache::<8>::new();
            let frame = cache.list(tris);
            let (mut cp, mut zp) = (vec![0u16; 32 * 32], vec![0u16; 32 * 32]);
            let mut errors = 0;
            for (k, t) in tris.iter().enumerate() {
                let mut band = ColorBand::<Rgb565>::band(&mut cp, 32, 0, 32).unwrap();
                let mut depth = DepthBuffer::band(&mut zp, 32, 0, 32).unwrap();
                depth.clear();
                let plain = r.draw(&mut band, &mut depth, t).err();
                let listed = r.draw_listed(&mut band, &mut depth, &frame, k).err();
                assert_eq!(plain, listed, "triangle {k}");
                assert!(plain.is_none() || depth.data().iter().all(|&c| c == u16::MAX));
                errors += usize::from(plain.is_some());
            }
            errors
        }
        let at = [(2.0, 2.0), (20.0, 4.0), (6.0, 25.0)];
        let tris: Vec<_> = (0..343)
            .map(|n| [0, 1, 2].map(|i| kind(n / 7usize.pow(i as u32) % 7, at[i])))
            .collect();
        // Every triangle but the all-good one is an error.
        assert_eq!(check::<crate::recip::Fast>(&tris), 342);
        assert_eq!(check::<crate::recip::FastDiv>(&tris), 342);
        assert_eq!(check::<crate::recip::Exact>(&tris), 342);
    }

    /// A list frame ([`PlaneCache::list`], [`Rasterizer::draw_listed`]) draws exactly what [`Rasterizer::draw`]
    /// draws (colours, codes, statistics), band by band, on random lists of large, medium and small triangles, on
    /// the snap grid and off it, for the fast tier (both seeds) and the exact tier; with room for every triangle,
    /// each plane is solved and each triangle's depth-grid values computed once a frame (what one band of the whole
    /// frame does), and a full or small cache only computes more. The same for a frame drawn bottom to top (no
    /// band follows the previous one: nothing reused) and for a state change between bands.
    #[test]
    fn a_list_frame_draws_what_draw_draws_and_solves_each_plane_once() {
        use crate::setup::{PLANE_SOLVES, T_AT_SNAPPED_CALLS};
        use crate::small::SMALL_CONSTANTS;
        use crate::Vertex;
        use embedded_graphics_core::pixelcolor::{raw::RawU16, Rgb565};
        const W: usize = 96;
        const H: usize = 80;
        type Snapped = Vec<[(i32, i32); 3]>;
        type Frame = (Vec<u16>, Vec<u16>, Stats, Snapped, Snapped, Snapped);
        // Whether no triangle appears twice (the lists' triangles are distinct).
        fn once(v: &Snapped) -> bool {
            let mut v = v.clone();
            v.sort_unstable();
            v.windows(2).all(|w| w[0] != w[1])
        }
        // Draws `tris` in bands of `rows` (`up`: bottom to top), through the list frame when `cache` is given.
        fn run<R: SpanRecip>(
            tris: &[[Vertex<Rgb565>; 3]],
            rows: usize,
            cache: Option<&mut PlaneCache<64>>,
            up: bool,
        ) -> Frame {
            let mut r = Rasterizer::<R>::new(RenderState::new(1.0, 500.0).unwrap());
            PLANE_SOLVES.with(|c| c.borrow_mut().clear());
            T_AT_SNAPPED_CALLS.with(|c| c.borrow_mut().clear());
            SMALL_CONSTANTS.with(|c| c.borrow_mut().clear());
            let mut frame = cache.map(|c| c.list(tris));
            let (px, z, stats) =
                draw_in_bands(
                    (W, H),
                    rows,
                    up,
                    tris.len(),
                    |band, depth, k| match &mut frame {
                        Some(f) => r.draw_listed(band, depth, f, k).unwrap(),
                        None => r.draw(band, depth, &tris[k]).unwrap(),
                    },
                );
            (
                px,
                z,
                stats,
                PLANE_SOLVES.with(|c| c.take()),
                T_AT_SNAPPED_CALLS.with(|c| c.take()),
                SMALL_CONSTANTS.with(|c| c.take()),
            )
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // (planes solved again in some band without the cache, small triangles' constants computed again)
        let mut again = (false, false);
        for trial in 0..12 {
            let tris: Vec<[Vertex<Rgb565>; 3]> = (0..40)
                .map(|k| {
                    let size = [110.0, 60.0, 20.0, 6.0][k % 4];
                    let (cx, cy) = (rnd() * W as f64, rnd() * H as f64);
                    let on_grid = (k / 4 + trial) % 2 == 0;
                    let c = Rgb565::from(RawU16::new((rnd() * 65535.0) as u16));
                    core::array::from_fn(|_| {
                        let mut x = cx + (rnd() - 0.5) * size;
                        let mut y = cy + (rnd() - 0.5) * size;
                        if on_grid {
                            (x, y) = ((x * 256.0).round() / 256.0, (y * 256.0).round() / 256.0);
                        }
                        Vertex::new(x as f32, y as f32, (1.5 + rnd() * 400.0) as f32, c)
                    })
                })
                .collect();
            fn check<R: SpanRecip>(tris: &[[Vertex<Rgb565>; 3]], again: &mut (bool, bool)) {
                let mut cache = PlaneCache::<64>::new();
                let whole = run::<R>(tris, H, None, false);
                for rows in [1, 3, 8, 80] {
                    let plain = run::<R>(tris, rows, None, false);
                    assert!(
                        plain.0 == whole.0 && plain.1 == whole.1,
                        "banding changed the frame"
                    );
                    let listed = run::<R>(tris, rows, Some(&mut cache), false);
                    assert!(
                        listed.0 == plain.0 && listed.1 == plain.1,
                        "{} rows {rows}",
                        R::NAME
                    );
                    assert_eq!(listed.2, plain.2);
                    // Room for every triangle: each triangle's values computed once, and each plane solved once
                    // where the list has no triangle the small-triangle path may take (on the fast tier, one it
                    // declines is solved again in each band: whether it declines may depend on the band).
                    assert!(once(&listed.4), "{} rows {rows}", R::NAME);
                    // And each small triangle the small-triangle path draws has its depth constants computed once.
                    assert!(once(&listed.5), "{} rows {rows}", R::NAME);
                    if !R::FAST_W16 || tris.iter().all(|t| !small_box(t)) {
                        assert!(once(&listed.3), "{} rows {rows}", R::NAME);
                    }
                    assert!(plain.3.len() >= listed.3.len() && plain.4.len() >= listed.4.len());
                    assert!(plain.5.len() >= listed.5.len());
                    again.0 |= !once(&plain.3);
                    again.1 |= !once(&plain.5);
                    // Bottom to top: what the plain draw does, computed as often.
                    let up = run::<R>(tris, rows, Some(&mut cache), true);
                    let plain_up = run::<R>(tris, rows, None, true);
                    assert!(up.0 == plain.0 && up.1 == plain.1 && up.2 == plain.2);
                    assert!(up.3.len() == plain_up.3.len() && up.4.len() == plain_up.4.len());
                    assert!(up.5.len() == plain_up.5.len());
                }
            }
            // The small-triangle path's box: under 32 px wide and 126 px high, snapped.
            fn small_box(t: &[Vertex<Rgb565>; 3]) -> bool {
                let snap = |v: f32| (v * 256.0).round() as i32;
                let (xs, ys) = (t.map(|v| snap(v.x)), t.map(|v| snap(v.y)));
                let span = |a: [i32; 3]| a.iter().max().unwrap() - a.iter().min().unwrap();
                span(xs) < 32 << 8 && span(ys) < 126 << 8
            }
            let large: Vec<_> = tris.iter().copied().filter(|t| !small_box(t)).collect();
            for list in [&tris[..], &large[..]] {
                check::<crate::recip::Fast>(list, &mut again);
                check::<crate::recip::FastDiv>(list, &mut again);
                check::<crate::recip::Exact>(list, &mut again);
            }
        }
        // The lists have triangles the exact solve sets up, and small ones the small-triangle path draws, in more
        // than one band.
        assert!(again.0 && again.1);
    }

    /// A list's triangle off the snap grid that the render state culls is culled before the fast tier's depth-grid
    /// values when drawn alone ([`t_at_snapped`](crate::setup::t_at_snapped) is never called for it; a list frame's
    /// draws, which share the mesh's memo, compute them), in bands, for both fast seeds and both windings culled; and
    /// culling it there draws what the draws drew before, alone and through a list frame in bands: the frame, codes
    /// and statistics of the same list drawn without culling less the triangles whose
    /// snapped doubled area (here from the f32 vertices in f64, rounded to 1/256 px ties to even) is zero or has the
    /// culled sign. Random triangles of 1 to 110 px (the small path and the general set-up), a fifth of them
    /// degenerate (the third vertex on the line through the first two, before rounding to f32).
    #[test]
    fn a_culled_triangle_off_the_grid_is_culled_before_its_depth_values() {
        use crate::setup::T_AT_SNAPPED_CALLS;
        use crate::{Cull, Vertex};
        use embedded_graphics_core::pixelcolor::{raw::RawU16, Rgb565};
        const W: usize = 96;
        const H: usize = 80;
        type Tri = [Vertex<Rgb565>; 3];
        // A frame's colours and codes, its statistics and the snapped vertices of each `t_at_snapped` call.
        type Frame = (Vec<u16>, Vec<u16>, Stats, Vec<[(i32, i32); 3]>);
        let snap = |v: f32| (v as f64 * 256.0).round_ties_even() as i64;
        let area = |t: &Tri| {
            let p = t.map(|v| (snap(v.x), snap(v.y)));
            (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1)
        };
        let snapped = |t: &Tri| t.map(|v| (snap(v.x) as i32, snap(v.y) as i32));
        let dropped = |cull: Cull, a: i64| match cull {
            Cull::None => false,
            Cull::Cw => a >= 0,
            Cull::Ccw => a <= 0,
        };
        // Draws `tris` with `cull` in bands of `rows` (through a list frame when `listed`).
        fn run<R: SpanRecip>(tris: &[Tri], cull: Cull, rows: usize, listed: bool) -> Frame {
            let mut state = RenderState::new(1.0, 500.0).unwrap();
            state.cull = cull;
            let mut r = Rasterizer::<R>::new(state);
            let mut cache = PlaneCache::<64>::new();
            let frame = cache.list(tris);
            T_AT_SNAPPED_CALLS.with(|c| c.borrow_mut().clear());
            let (px, z, stats) = draw_in_bands(
                (W, H),
                rows,
                false,
                tris.len(),
                |band, depth, k| match listed {
                    true => r.draw_listed(band, depth, &frame, k).unwrap(),
                    false => r.draw(band, depth, &tris[k]).unwrap(),
                },
            );
            (px, z, stats, T_AT_SNAPPED_CALLS.with(|c| c.take()))
        }
        let mut rnd = crate::xorshift(0x0C0F_FEE5_CA11_ED00);
        let mut unit = move || (rnd() >> 11) as f64 / (1u64 << 53) as f64;
        let (mut culled_seen, mut kept_seen) = (0u32, 0u32);
        for trial in 0..10 {
            let tris: Vec<Tri> = (0..40)
                .map(|k| {
                    let size = [110.0, 40.0, 12.0, 3.0][k % 4];
                    let (cx, cy) = (unit() * W as f64, unit() * H as f64);
                    let c = Rgb565::from(RawU16::new((unit() * 65535.0) as u16));
                    let mut p: [(f64, f64); 3] = core::array::from_fn(|_| {
                        (cx + (unit() - 0.5) * size, cy + (unit() - 0.5) * size)
                    });
                    if (k + trial) % 5 == 0 {
                        let f = unit();
                        p[2] = (
                            p[0].0 + (p[1].0 - p[0].0) * f,
                            p[0].1 + (p[1].1 - p[0].1) * f,
                        );
                    }
                    p.map(|(x, y)| {
                        Vertex::new(x as f32, y as f32, (1.5 + unit() * 400.0) as f32, c)
                    })
                })
                .collect();
            fn check<R: SpanRecip>(
                tris: &[Tri],
                area: &impl Fn(&Tri) -> i64,
                snapped: &impl Fn(&Tri) -> [(i32, i32); 3],
                dropped: &impl Fn(Cull, i64) -> bool,
                seen: (&mut u32, &mut u32),
            ) {
                for cull in [Cull::Cw, Cull::Ccw] {
                    let kept: Vec<Tri> = tris
                        .iter()
                        .copied()
                        .filter(|t| !dropped(cull, area(t)))
                        .collect();
                    let culled: Vec<[(i32, i32); 3]> = tris
                        .iter()
                        .filter(|t| dropped(cull, area(t)))
                        .map(snapped)
                        .collect();
                    let expect = run::<R>(&kept, Cull::None, H, false);
                    // The reference's areas are the draws': none of the kept triangles is degenerate to them.
                    assert_eq!(expect.2.culled, 0);
                    for (rows, listed) in [(H, false), (8, false), (8, true), (3, true)] {
                        let got = run::<R>(tris, cull, rows, listed);
                        assert!(
                            got.0 == expect.0 && got.1 == expect.1,
                            "{cull:?} {rows} {listed}: frame"
                        );
                        // Each band's draw of a culled triangle counts it (whether or not it has rows there).
                        let bands = H.div_ceil(rows) as u32;
                        assert_eq!(
                            got.2.culled,
                            culled.len() as u32 * bands,
                            "{cull:?} {rows} {listed}"
                        );
                        assert_eq!(
                            (got.2.fragments, got.2.written),
                            (expect.2.fragments, expect.2.written),
                            "{cull:?} {rows} {listed}"
                        );
                        if !listed {
                            assert!(
                                got.3.iter().all(|p| !culled.contains(p)),
                                "{cull:?} {rows}: the depth-grid values of a culled triangle"
                            );
                            *seen.0 += culled.len() as u32;
                            *seen.1 += got.3.len() as u32;
                        }
                    }
                }
            }
            let seen = (&mut culled_seen, &mut kept_seen);
            check::<crate::recip::Fast>(&tris, &area, &snapped, &dropped, seen);
            let seen = (&mut culled_seen, &mut kept_seen);
            check::<crate::recip::FastDiv>(&tris, &area, &snapped, &dropped, seen);
        }
        // The kept triangles' values were computed (the path is taken), and there were culled ones to skip.
        assert!(
            culled_seen > 1000 && kept_seen > 1000,
            "{culled_seen} {kept_seen}"
        );
    }

    /// `trunc_bits` (the cores without an FPU) is `as i32` (the FPU's conversion) on every class of f32: a stride
    /// through all bit patterns, every integer boundary near the guard band, and the specials.
    #[test]
    fn trunc_from_the_bits_is_as_i32() {
        let check = |v: f32| assert_eq!(trunc_bits(v), v as i32, "{v:e} ({:#x})", v.to_bits());
        for b in (0..=u32::MAX).step_by(997) {
            check(f32::from_bits(b));
        }
        for k in -5000..5000 {
            let t = k as f32 * 0.5;
            for d in [0, 1, 2] {
                check(f32::from_bits(t.to_bits() + d));
                check(f32::from_bits(t.to_bits().wrapping_sub(d)));
            }
        }
        for v in [
            0.0,
            -0.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            2147483520.0,
            2147483648.0,
            -2147483648.0,
            -2147483904.0,
            f32::MIN_POSITIVE,
        ] {
            check(v);
        }
    }

    /// A mesh with per-vertex colours through [`Rasterizer::draw_mesh_frame_gouraud`]: a triangle on screen draws
    /// exactly what [`Rasterizer::draw_gouraud`] draws of its projected vertices with their own colours; a triangle
    /// that crosses the near plane, with one colour at all three vertices, draws that colour at every pixel (the clip's
    /// mix of three equal colours by weights that sum to 1 is that colour: each channel `c (1 + e) + 0.5` with
    /// `|e| <= 3 2^-24`, under `2^-10` from `c + 0.5`, rounds down to `c`), over the pixels the flat draw covers.
    #[cfg(feature = "gouraud")]
    #[test]
    fn per_vertex_colours_reach_the_gouraud_draw() {
        use embedded_graphics_core::pixelcolor::{Rgb888, RgbColor};
        let cam = crate::projection::Camera::look_at(
            [0.0, 0.0, 3.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            1.2,
            1.0,
            0.5,
            50.0,
        )
        .unwrap();
        let vp = Viewport::new(0.0, 0.0, 64.0, 64.0);
        let mut r = Rasterizer::<Fast>::new(cam.render_state().unwrap());
        r.state.cull = Cull::None;
        let draw =
            |r: &mut Rasterizer<Fast>, positions: &[[f32; 3]], colors: &[Rgb888], gouraud: bool| {
                let mesh = Mesh {
                    positions,
                    indices: &[[0, 1, 2]],
                    colors: if gouraud {
                        Colors::PerVertex(colors)
                    } else {
                        Colors::Uniform(colors[0])
                    },
                };
                let mut verts = [Projected::default(); 3];
                let frame = r
                    .transform_mesh(&mesh, &cam.matrix(), &vp, &mut verts)
                    .unwrap();
                let (mut px, mut z) = (vec![0u32; 64 * 64], vec![0u16; 64 * 64]);
                let mut band = crate::ColorBand::<Rgb888>::new(&mut px, 64, 64).unwrap();
                let mut depth = DepthBuffer::new(&mut z, 64, 64).unwrap();
                depth.clear();
                if gouraud {
                    r.draw_mesh_frame_gouraud(&mut band, &mut depth, &frame)
                        .unwrap();
                } else {
                    r.draw_mesh_frame(&mut band, &mut depth, &frame).unwrap();
                }
                (px, z, verts)
            };
        let colors = [Rgb888::RED, Rgb888::GREEN, Rgb888::BLUE];
        let on_screen = [[-1.0, -0.8, 0.2], [1.1, -0.5, -0.4], [0.1, 1.0, 0.3]];
        let (px, z, verts) = draw(&mut r, &on_screen, &colors, true);
        let v: [crate::Vertex<Rgb888>; 3] = core::array::from_fn(|i| crate::Vertex {
            x: verts[i].x,
            y: verts[i].y,
            z: 0.0,
            rhw: verts[i].rhw,
            color: colors[i],
        });
        let (mut px2, mut z2) = (vec![0u32; 64 * 64], vec![0u16; 64 * 64]);
        let mut band = crate::ColorBand::<Rgb888>::new(&mut px2, 64, 64).unwrap();
        let mut depth = DepthBuffer::new(&mut z2, 64, 64).unwrap();
        depth.clear();
        r.draw_gouraud(&mut band, &mut depth, &v).unwrap();
        assert!(px == px2 && z == z2);
        assert!(px.iter().filter(|&&c| c != 0).count() > 200);
        // Crossing the near plane (the eye is at z = 3, the plane at 2.5).
        let crossing = [[-1.0, -0.8, 0.0], [1.0, -0.6, 2.9], [0.2, 0.9, 0.5]];
        let one = Rgb888::new(200, 121, 40);
        let (px, _, _) = draw(&mut r, &crossing, &[one; 3], true);
        let (flat, _, _) = draw(&mut r, &crossing, &[one; 3], false);
        let raw = embedded_graphics_core::prelude::RawData::into_inner(
            embedded_graphics_core::pixelcolor::raw::RawU24::from(one),
        );
        assert!(px
            .iter()
            .zip(&flat)
            .all(|(&g, &f)| (g == 0) == (f == 0) && (g == 0 || g == raw)));
        assert!(px.iter().filter(|&&c| c == raw).count() > 200);
    }

    /// A triangle that crosses a plane is culled before it is clipped by its winding seen from the eye (the sign of
    /// `det [x y w]` of its clip coordinates): exactly where what it would draw has the culled winding on screen.
    /// Random triangles around the eye, each drawn with no culling (its fan triangles' screen areas, formed here) and
    /// with each culling mode: a triangle whose every fan triangle of nonzero area runs clockwise is culled by `Cw`
    /// and drawn whole by `Ccw`, and the other way round; a culled one counts once.
    #[test]
    fn a_clipped_triangle_is_culled_by_the_winding_it_would_draw() {
        let cam = crate::projection::Camera::look_at(
            [0.0; 3],
            [0.3, -0.2, -1.0],
            [0.0, 1.0, 0.0],
            1.2,
            1.0,
            0.1,
            50.0,
        )
        .unwrap();
        let (m, vp) = (cam.matrix(), Viewport::new(0.0, 0.0, 64.0, 64.0));
        let r = Rasterizer::<Fast>::new(cam.render_state().unwrap());
        let mut rnd = crate::xorshift(0xC11F_C011_0000_0001);
        let mut unit = move || (rnd() >> 40) as f32 / (1u64 << 24) as f32;
        let (mut cw, mut ccw) = (0, 0);
        for k in 0..20_000 {
            let positions: [[f32; 3]; 3] =
                core::array::from_fn(|_| core::array::from_fn(|_| unit() * 4.0 - 2.0));
            let mesh = Mesh {
                positions: &positions,
                indices: &[[0, 1, 2]],
                colors: Colors::Uniform(0u8),
            };
            let mut verts = [Projected::default(); 3];
            let frame = r.transform_mesh(&mesh, &m, &vp, &mut verts).unwrap();
            // The fan triangles `f` receives under `cull` (`None` for a clipped triangle), and the stats.
            let draw = |cull: Cull| {
                let (mut fans, mut stats) = (Vec::new(), Stats::default());
                frame
                    .for_each(cull, 0, 64, &mut stats, &|c, _| c[0], |k, v| {
                        fans.push((k, v.map(|v| (v.x as f64, v.y as f64))));
                        Ok::<_, ()>(Stats::default())
                    })
                    .unwrap();
                (fans, stats.culled)
            };
            let (fans, _) = draw(Cull::None);
            if fans.is_empty() || fans.iter().any(|(k, _)| k.is_some()) {
                continue; // not clipped, or outside the view
            }
            // y down: a positive area runs clockwise on the display.
            let areas: Vec<f64> = fans
                .iter()
                .map(|(_, [a, b, c])| (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1))
                .filter(|&a| a.abs() > 1e-6)
                .collect();
            let clockwise = if areas.iter().all(|&a| a > 0.0) {
                cw += 1;
                true
            } else if areas.iter().all(|&a| a < 0.0) {
                ccw += 1;
                false
            } else {
                continue;
            };
            let (culls, keeps) = if clockwise {
                (Cull::Cw, Cull::Ccw)
            } else {
                (Cull::Ccw, Cull::Cw)
            };
            assert_eq!(draw(culls), (Vec::new(), 1), "{k}: {positions:?}");
            assert_eq!(draw(keeps), (fans, 0), "{k}: {positions:?}");
        }
        assert!(cw > 1000 && ccw > 1000, "{cw} {ccw}");
        // Edge-on: a triangle in a plane through the eye (here `y = 0`, seen along `-z`: its clip `y` is 0 and so is
        // `det`) covers no pixel, and is culled whatever the mode, counted once.
        let cam = crate::projection::Camera::look_at(
            [0.0; 3],
            [0.0, 0.0, -1.0],
            [0.0, 1.0, 0.0],
            1.2,
            1.0,
            0.1,
            50.0,
        )
        .unwrap();
        let positions = [[1.0, 0.0, -2.0], [-1.0, 0.0, -0.05], [0.5, 0.0, 1.0]];
        let mesh = Mesh {
            positions: &positions,
            indices: &[[0, 1, 2]],
            colors: Colors::Uniform(0u8),
        };
        let mut verts = [Projected::default(); 3];
        let frame = r
            .transform_mesh(&mesh, &cam.matrix(), &vp, &mut verts)
            .unwrap();
        for cull in [Cull::None, Cull::Cw, Cull::Ccw] {
            let mut stats = Stats::default();
            frame
                .for_each(
                    cull,
                    0,
                    64,
                    &mut stats,
                    &|c, _| c[0],
                    |k, v| -> Result<Stats, ()> {
                        panic!("{cull:?}: drew {k:?} {:?}", v.map(|v| (v.x, v.y)))
                    },
                )
                .unwrap();
            assert_eq!(stats.culled, 1, "{cull:?}");
        }
    }

    /// Where the float test decides ([`clear_area`]), or the integer one ([`clear_area_fixed`]), the snapped area has its sign: on random triangles and on
    /// near-degenerate ones (a third vertex a few ulps off the line through two others, and tiny triangles), whose
    /// float and snapped areas often disagree, so the fallback is needed (asserted) and the bound is what decides.
    #[test]
    fn the_float_cull_has_the_snapped_areas_sign() {
        let mut rnd = crate::xorshift(0x5EED_CAFE_0001);
        let mut unit = move || (rnd() >> 40) as f32 / (1u64 << 24) as f32;
        let (mut decided, mut fallback, mut disagree, mut fixed) = (0, 0, 0, 0);
        for n in 0..400_000 {
            let mut pt = |scale: f32| (unit() * scale - scale / 2.0, unit() * scale - scale / 2.0);
            let scale = [4000.0, 200.0, 4.0, 0.05][n % 4]; // c stays below 4000 (the clip band)
            let (a, b) = (pt(scale), pt(scale));
            let c = if n % 3 == 0 {
                // On the line through a and b, then a few ulps off it.
                let t = unit() * 2.0 - 0.5;
                let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
                let k = (unit() * 8.0) as u32;
                (f32::from_bits(x.to_bits() + k), y)
            } else {
                pt(scale)
            };
            let v = [a, b, c].map(|(x, y)| Projected { x, y, rhw: 1.0 });
            let snapped = crate::input::snapped_area([a, b, c]).unwrap();
            if let Some(area) = clear_area_fixed(&v) {
                fixed += 1;
                assert!(
                    area != 0 && (area > 0) == (snapped > 0),
                    "{a:?} {b:?} {c:?}: {area} {snapped}"
                );
            }
            let float = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            match clear_area(&v) {
                Some(area) => {
                    decided += 1;
                    assert!(
                        (area > 0.0 && snapped > 0) || (area < 0.0 && snapped < 0),
                        "{a:?} {b:?} {c:?}: float {area:e}, snapped {snapped}"
                    );
                }
                None => {
                    fallback += 1;
                    if (float > 0.0) != (snapped > 0) || (float == 0.0) != (snapped == 0) {
                        disagree += 1;
                    }
                }
            }
        }
        assert!(
            decided > 200_000 && fallback > 10_000 && disagree > 1_000,
            "{decided} {fallback} {disagree}"
        );
        assert!(fixed > 150_000, "{fixed}");
    }

    /// Where no filter decides, the cull is the snapped area's sign under every mode: near-zero triangles whose
    /// snapped area is negative, positive and zero (the adversarial ones below, their mirror images, and triangles
    /// whose vertices snap onto one line), each against the rule the rasterizer applies.
    #[test]
    fn the_cull_of_near_zero_areas_is_the_snapped_areas() {
        let mut rnd = crate::xorshift(0x0C11_5A1E_0003);
        let mut unit = move || (rnd() >> 40) as f32 / (1u64 << 24) as f32;
        let rule = |cull: Cull, area: i64| match cull {
            _ if area == 0 => true,
            Cull::Cw => area > 0,
            Cull::Ccw => area < 0,
            Cull::None => false,
        };
        let mut seen = [0; 3]; // snapped areas below, at and above zero, decided by the snapped area
        for n in 0..100_000 {
            let (a, b) = (
                (unit() * 64.0, unit() * 64.0),
                (unit() * 64.0, unit() * 64.0),
            );
            let t = unit();
            // On the line through a and b, then moved by under a sub-pixel.
            let d = (unit() - 0.5) / 128.0;
            let c = (a.0 + t * (b.0 - a.0) + d, a.1 + t * (b.1 - a.1) - d);
            let mut tri = if n % 2 == 0 { [a, b, c] } else { [a, c, b] };
            if n % 3 == 0 {
                // All three within 2^-11 px of one row of the snap grid: they snap onto it (area 0).
                let y = (unit() * 64.0 * 256.0).floor() / 256.0;
                for p in tri.iter_mut() {
                    p.1 = y + (unit() - 0.5) / 1024.0;
                }
            }
            let v = tri.map(|(x, y)| Projected { x, y, rhw: 1.0 });
            let snapped = crate::input::snapped_area(tri).unwrap();
            if clear_area(&v).is_some() {
                continue;
            }
            seen[(snapped.signum() + 1) as usize] += 1;
            for cull in [Cull::Cw, Cull::Ccw, Cull::None] {
                assert_eq!(
                    culled_on_screen(cull, &v),
                    rule(cull, snapped),
                    "{tri:?} {cull:?}: snapped {snapped}"
                );
            }
        }
        assert!(seen.iter().all(|&k| k > 1_000), "{seen:?}");
    }

    /// The filters' bounds are what decides: triangles built so that snapping shrinks the area as far as it can
    /// (every coordinate just beside a half-sub-pixel tie, on the side that rounds against the area) have a positive
    /// area up to about `2^-8 S` whose snapped area is negative. Both filters leave every one of them to the snapped
    /// area; with either bound at a quarter of its derived size, many would be culled by the wrong sign (counted here,
    /// so a filter too loose for these triangles fails the test).
    #[test]
    fn adversarial_snaps_stay_with_the_snapped_area() {
        let mut rnd = crate::xorshift(0xAD5E_5A1E_0002);
        let mut unit = move || (rnd() >> 40) as f32 / (1u64 << 24) as f32;
        let (mut wrong_sign, mut quarter_float, mut quarter_fixed) = (0, 0, 0);
        for _ in 0..200_000 {
            // Within 64 px, where the f32 spacing (2^-18 px) resolves a point 2^-16 px beside a tie.
            let tie = |v: f32| ((v * 256.0).floor() + 0.5) / 256.0;
            let (a, b) = (
                (unit() * 64.0, unit() * 64.0),
                (unit() * 64.0, unit() * 64.0),
            );
            let (ux, uy) = (b.0 - a.0, b.1 - a.1);
            let len = (ux * ux + uy * uy).sqrt();
            if len < 1.0 {
                continue;
            }
            // c beside the line through a and b, by a fraction of a sub-pixel.
            let (t, d) = (unit(), (unit() - 0.25) / 256.0);
            let c = (a.0 + t * ux - d * uy / len, a.1 + t * uy + d * ux / len);
            let [a, b, c] = [a, b, c].map(|(x, y)| (tie(x), tie(y)));
            // dA/d(coordinate), then each coordinate 2^-16 px to the side that snaps against the area.
            let g = [
                b.1 - c.1,
                c.0 - b.0,
                c.1 - a.1,
                a.0 - c.0,
                a.1 - b.1,
                b.0 - a.0,
            ];
            let mut q = [a.0, a.1, b.0, b.1, c.0, c.1];
            for (v, g) in q.iter_mut().zip(g) {
                *v += if g > 0.0 { -1.0 } else { 1.0 } / 65536.0;
            }
            let [a, b, c] = [(q[0], q[1]), (q[2], q[3]), (q[4], q[5])];
            let area =
                (b.0 - a.0) as f64 * (c.1 - a.1) as f64 - (c.0 - a.0) as f64 * (b.1 - a.1) as f64;
            let snapped = crate::input::snapped_area([a, b, c]).unwrap();
            if area <= 0.0 || snapped > 0 {
                continue;
            }
            wrong_sign += 1;
            let v = [a, b, c].map(|(x, y)| Projected { x, y, rhw: 1.0 });
            assert_eq!(
                clear_area(&v),
                None,
                "{a:?} {b:?} {c:?}: {area:e}, snapped {snapped}"
            );
            assert_eq!(
                clear_area_fixed(&v),
                None,
                "{a:?} {b:?} {c:?}: {area:e}, snapped {snapped}"
            );
            // What a quarter of each bound would have decided (by the wrong sign).
            let s = (b.0 - a.0).abs() + (b.1 - a.1).abs() + (c.0 - a.0).abs() + (c.1 - a.1).abs();
            if area > s as f64 / 512.0 + 1.0 / 65536.0 {
                quarter_float += 1;
            }
            let t = |v: f32| crate::input::fixed_trunc(v) as i64;
            let at = (t(b.0) - t(a.0)) * (t(c.1) - t(a.1)) - (t(c.0) - t(a.0)) * (t(b.1) - t(a.1));
            let st = (t(b.0) - t(a.0)).abs()
                + (t(b.1) - t(a.1)).abs()
                + (t(c.0) - t(a.0)).abs()
                + (t(c.1) - t(a.1)).abs();
            if at.abs() > (3 * st + 34) / 4 {
                quarter_fixed += 1;
            }
        }
        assert!(
            wrong_sign > 50_000 && quarter_float > 1_000 && quarter_fixed > 1_000,
            "{wrong_sign} {quarter_float} {quarter_fixed}"
        );
    }
}
