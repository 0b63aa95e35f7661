//! What every wraster firmware shares: the standard scenes baked into flash (from `wraster::scenes`, by build.rs),
//! rendering them band by band with triangles binned by rows, W4's torus through the mesh path, the frame hash, and
//! the `bench` line.
//!
//! Hash: FNV-1a 64 over the frame's rows in order; for each row the colour of every pixel (RGB565, u16 little-endian)
//! then the depth of every pixel (W16, u16 little-endian). The host computes the same (host-tests/tests/firmware.rs).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]

use core::fmt::Write;

use embedded_graphics_core::pixelcolor::raw::RawU16;
use embedded_graphics_core::pixelcolor::Rgb565;
use wraster::clip::Viewport;

use wraster::mesh::{Colors, Mesh, MeshFrame, Projected};
use wraster::recip::SpanRecip;
use wraster::{
    Codec, ColorBand, DepthBuffer, Error, NoDepth, Rasterizer, RenderState, Stats, Vertex,
};

/// A baked triangle: `(x, y, rhw)` bit patterns per vertex, the RGB565 colour, the rows it can cover.
pub struct Tri {
    /// Vertices as f32 bit patterns.
    pub v: [[u32; 3]; 3],
    /// RGB565.
    pub color: u16,
    /// First and last row (inclusive) from `wraster::row_range`: the standard scenes lie in the frame, so `u16` (the
    /// M0's flash: 44 bytes a triangle, 48 with `i32`: 11.6 KB less over the standard scenes' 2,904 triangles; `u16`
    /// rather than `i16`, whose load on the M0 takes no immediate offset).
    pub rows: (u16, u16),
}

/// A baked scene.
pub struct SceneData {
    /// Name, as printed.
    pub name: &'static str,
    /// `W_near`.
    pub near: f32,
    /// `W_far`.
    pub far: f32,
    /// Triangles in drawing order.
    pub tris: &'static [Tri],
    /// Its colours, for a band of half a byte a pixel ([`Nibbles`]).
    pub palette: NibblePalette,
}

include!(concat!(env!("OUT_DIR"), "/scenes.rs"));

/// A plan of host-tests' scene planner (`cargo run --release -p host-tests --bin plan -- <scene>`), baked by build.rs
/// from the files named in `PLAN` (comma-separated) into modules `plans::p0`, `p1`, ... with the chosen format and
/// strategy as the type aliases `PlanFormat` and `PlanStrategy` beside this.
#[derive(Clone, Copy, Debug)]
pub struct PlanData {
    /// The scene (a standard scene's name, or `torus`).
    pub scene: &'static str,
    /// The format's name (`none`: no depth buffer).
    pub format: &'static str,
    /// `W_near` of the plan's render state.
    pub near: f32,
    /// `W_far`.
    pub far: f32,
    /// Rows per depth band.
    pub band_rows: u16,
    /// Bytes of depth buffer the plan needs.
    pub depth_ram: usize,
    /// Visibility errors the host measured for the plan.
    pub visibility_errors: u32,
    /// Whether the W16 buffer keeps a coarse bound (feature `coarse`), stored after the band in the depth RAM.
    pub coarse: bool,
}

/// A plan's depth path (its `PLAN_KIND`, a const generic of [`run_plan`], so a firmware links only its own): no
/// depth buffer.
pub const NO_DEPTH: u8 = 0;
/// The lean W16 path (`Rasterizer::draw`, the fast tier).
pub const LEAN_W16: u8 = 1;
/// A packed format through `Rasterizer::draw_format`.
pub const PACKED: u8 = 2;
/// A plan's scene (its `PLAN_SCENE`, a const generic of [`run_plan`], so a firmware links only the path its scene
/// takes): W4's torus; a standard scene is its index in [`SCENES`].
pub const TORUS_SCENE: usize = usize::MAX;

/// The strategy a `--features size-probe` build runs, named by the build-time `RECIP` (one strategy a firmware, for
/// `boards/tools/cycles.py`'s estimated cycles of each; the report shows them): unset, the core's default
/// ([`PROBE_DEFAULT`]); else [`PROBE_FAST`] (`fast`), [`PROBE_FAST_DIV`] (`fast-div`), [`PROBE_EXACT`] (`lerp64`, the
/// exact tier), [`PROBE_PREV_PIXEL`] (`prev-pixel`) or [`PROBE_F32_DIV`] (`f32-div`), the names of the `bench` lines'
/// `recip=`. Any other name fails the build. A constant, so a firmware links only the strategy it names.
pub const PROBE_RECIP: u8 = probe_recip(option_env!("RECIP"));
/// [`PROBE_RECIP`] unset: the core's default strategy.
pub const PROBE_DEFAULT: u8 = 0;
/// [`PROBE_RECIP`]: `fast`.
pub const PROBE_FAST: u8 = 1;
/// [`PROBE_RECIP`]: `fast-div`.
pub const PROBE_FAST_DIV: u8 = 2;
/// [`PROBE_RECIP`]: `lerp64` (the exact tier).
pub const PROBE_EXACT: u8 = 3;
/// [`PROBE_RECIP`]: `prev-pixel`.
pub const PROBE_PREV_PIXEL: u8 = 4;
/// [`PROBE_RECIP`]: `f32-div`.
pub const PROBE_F32_DIV: u8 = 5;

/// [`PROBE_RECIP`] from the name (a `const fn`: an unknown name is a build error).
const fn probe_recip(name: Option<&str>) -> u8 {
    const fn is(a: &str, b: &str) -> bool {
        let (a, b) = (a.as_bytes(), b.as_bytes());
        if a.len() != b.len() {
            return false;
        }
        let mut i = 0;
        while i < a.len() {
            if a[i] != b[i] {
                return false;
            }
            i += 1;
        }
        true
    }
    match name {
        None => PROBE_DEFAULT,
        Some(n) if is(n, "fast") => PROBE_FAST,
        Some(n) if is(n, "fast-div") => PROBE_FAST_DIV,
        Some(n) if is(n, "lerp64") => PROBE_EXACT,
        Some(n) if is(n, "prev-pixel") => PROBE_PREV_PIXEL,
        Some(n) if is(n, "f32-div") => PROBE_F32_DIV,
        Some(_) => panic!("RECIP: one of fast, fast-div, lerp64, prev-pixel, f32-div"),
    }
}

/// The plans named by `PLAN` at build time (none without it).
pub mod plans {
    include!(concat!(env!("OUT_DIR"), "/plans.rs"));
}

/// Frame size of the standard scenes.
pub const WIDTH: u16 = 320;
/// Frame size of the standard scenes.
pub const HEIGHT: u16 = 240;

impl Tri {
    /// The vertices.
    #[inline]
    pub fn vertices(&self) -> [Vertex<Rgb565>; 3] {
        let c = Rgb565::from(RawU16::new(self.color));
        self.v.map(|[x, y, rhw]| Vertex {
            x: f32::from_bits(x),
            y: f32::from_bits(y),
            z: 0.0,
            rhw: f32::from_bits(rhw),
            color: c,
        })
    }
}

/// FNV-1a 64.
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Hashes `bytes`.
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// Hashes the little-endian bytes of `words`.
    pub fn words(&mut self, words: &[u16]) {
        for w in words {
            for b in w.to_le_bytes() {
                self.0 ^= b as u64;
                self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
}

/// A counter that counts nothing (for boards that only draw).
pub struct NoCounter;

impl Counter for NoCounter {
    fn start(&mut self) {}
    fn stop(&mut self) -> u64 {
        0
    }
}

/// Counts instructions (never cycles) between `start` and `stop`.
pub trait Counter {
    /// Starts or resumes.
    fn start(&mut self);
    /// Instructions since the matching `start`.
    fn stop(&mut self) -> u64;
}

/// Instructions counted with SysTick on the core clock, under QEMU's `-icount shift=0` (one instruction per virtual
/// nanosecond): `ticks * num / den` instructions (25 MHz mps2: 40/1; 16 MHz microbit: 125/2). Resolution: one tick
/// per `start`/`stop` pair. A wrap of the 24-bit counter between them is refused (a panic, so a non-zero exit).
#[cfg(feature = "systick")]
pub struct SysTick {
    syst: cortex_m::peripheral::SYST,
    num: u64,
    den: u64,
}

#[cfg(feature = "systick")]
impl SysTick {
    /// Takes the SysTick peripheral; `num / den` instructions per tick.
    pub fn new(mut syst: cortex_m::peripheral::SYST, num: u64, den: u64) -> Self {
        syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
        syst.set_reload(0x00ff_ffff);
        SysTick { syst, num, den }
    }
}

#[cfg(feature = "systick")]
impl Counter for SysTick {
    fn start(&mut self) {
        self.syst.clear_current();
        let _ = self.syst.has_wrapped(); // reading COUNTFLAG clears it
        self.syst.enable_counter();
    }
    fn stop(&mut self) -> u64 {
        let now = cortex_m::peripheral::SYST::get_current();
        self.syst.disable_counter();
        assert!(
            !self.syst.has_wrapped(),
            "SysTick wrapped between start and stop"
        );
        // After the clear the counter reads 0 until the first tick reloads it with 0xff_ffff.
        let ticks = if now == 0 {
            0
        } else {
            0x0100_0000 - now as u64
        };
        ticks * self.num / self.den
    }
}

/// What one scene run measured.
pub struct Run {
    /// Scene name.
    pub scene: &'static str,
    /// Reciprocal strategy (`SpanRecip::NAME`).
    pub recip: &'static str,
    /// Summed draw statistics.
    pub stats: Stats,
    /// Bands drawn.
    pub bands: u32,
    /// Triangles in the scene.
    pub triangles: u32,
    /// Instructions spent in draw calls (not clears, hashing or printing).
    pub instructions: u64,
    /// Frame hash.
    pub hash: u64,
    /// Whether the depth buffer kept a coarse bound (feature `coarse`).
    pub bound: bool,
}

/// `v` as twice as many `u16`s (the plans' depth storage: `u32`s, so that a 4-byte format's words are aligned).
pub fn u16_words(v: &mut [u32]) -> &mut [u16] {
    bytemuck::cast_slice_mut(v)
}

/// Renders `scene` band by band with the given buffers (`color.len() == depth.len() == WIDTH * band rows`).
/// Each band clears its buffers, then draws only the triangles whose row range meets it (binning).
/// `R` is the reciprocal strategy (`wraster::recip`).
pub fn run_scene<R: SpanRecip, C: Counter>(
    scene: &SceneData,
    color: &mut [u16],
    depth: &mut [u16],
    counter: &mut C,
) -> Result<Run, Error> {
    run_scene_with::<R, C>(scene, color, depth, counter, |_, _| {})
}

/// [`run_scene_with`], each band's depth buffer keeping a coarse bound in `bound` (feature `coarse`; at least
/// `wraster::bound_len(WIDTH, band rows)` long; empty: no bound).
pub fn run_scene_bounded<R: SpanRecip, C: Counter>(
    scene: &SceneData,
    color: &mut [u16],
    depth: &mut [u16],
    bound: &mut [u16],
    counter: &mut C,
    on_band: impl FnMut(u16, &[u16]),
) -> Result<Run, Error> {
    run_scene_cached::<R, C>(scene, color, depth, bound, &mut (), counter, on_band)
}

impl wraster::mesh::Triangle for Tri {
    type Vertex = Vertex<Rgb565>;
    #[inline]
    fn vertices(&self) -> [Vertex<Rgb565>; 3] {
        Tri::vertices(self)
    }
}

/// How a board's standard-scene run draws its triangles: each on its own (`()`, for a frame in one band: nothing
/// to remember) or as a list frame with a plane cache ([`SceneCache`]: a triangle reaching several bands is set up
/// once a frame where the cache has room). A type, not a value: a board links only the draw it uses.
pub trait SceneFrames {
    /// The frame of a scene's triangles.
    type Frame<'a>: DrawTris
    where
        Self: 'a;
    /// The frame of `tris`, for one pass over the bands.
    fn frame<'a>(&'a mut self, tris: &'a [Tri]) -> Self::Frame<'a>;
}

/// One triangle of a [`SceneFrames::Frame`] drawn into a band.
pub trait DrawTris {
    /// Triangle `k` (`t`) into the band.
    fn draw<R: SpanRecip, D: embedded_graphics_core::draw_target::DrawTarget<Color = Rgb565>>(
        &self,
        r: &mut Rasterizer<R>,
        band: &mut D,
        buf: &mut DepthBuffer<'_>,
        k: usize,
        t: &Tri,
    ) -> Result<Stats, Error>;
}

impl SceneFrames for () {
    type Frame<'a> = ();
    fn frame<'a>(&'a mut self, _: &'a [Tri]) {}
}

impl DrawTris for () {
    #[inline(always)]
    fn draw<R: SpanRecip, D: embedded_graphics_core::draw_target::DrawTarget<Color = Rgb565>>(
        &self,
        r: &mut Rasterizer<R>,
        band: &mut D,
        buf: &mut DepthBuffer<'_>,
        _: usize,
        t: &Tri,
    ) -> Result<Stats, Error> {
        r.draw(band, buf, &t.vertices())
    }
}

impl<const N: usize> SceneFrames for wraster::mesh::PlaneCache<N> {
    type Frame<'a> = wraster::mesh::ListFrame<'a, Tri>;
    fn frame<'a>(&'a mut self, tris: &'a [Tri]) -> Self::Frame<'a> {
        self.list(tris)
    }
}

impl DrawTris for wraster::mesh::ListFrame<'_, Tri> {
    #[inline(always)]
    fn draw<R: SpanRecip, D: embedded_graphics_core::draw_target::DrawTarget<Color = Rgb565>>(
        &self,
        r: &mut Rasterizer<R>,
        band: &mut D,
        buf: &mut DepthBuffer<'_>,
        k: usize,
        _: &Tri,
    ) -> Result<Stats, Error> {
        r.draw_listed(band, buf, self, k)
    }
}

/// Triangles a board's standard-scene plane cache holds ([`SceneCache`]): every triangle of W1 and W2 that reaches
/// the next band, and some of the terrain's (its small triangles' depth-grid values, off the grid; W3's lie on it).
pub const SCENE_CACHE: usize = 64;
/// A board's standard-scene plane cache (for scenes drawn in more than one band).
pub type SceneCache = wraster::mesh::PlaneCache<SCENE_CACHE>;

/// [`run_scene_bounded`], the triangles drawn as `cache` says ([`SceneFrames`]).
pub fn run_scene_cached<R: SpanRecip, C: Counter>(
    scene: &SceneData,
    color: &mut [u16],
    depth: &mut [u16],
    bound: &mut [u16],
    cache: &mut impl SceneFrames,
    counter: &mut C,
    on_band: impl FnMut(u16, &[u16]),
) -> Result<Run, Error> {
    run_scene_banded::<R, Rgb565, C>(scene, color, depth, bound, cache, counter, on_band)
}

/// [`run_scene_cached`] with any [`BandKind`]: `color` holds its band's storage (half a byte a pixel for
/// [`Nibbles`]); the band's height is `depth`'s rows.
pub fn run_scene_banded<R: SpanRecip, B: BandKind, C: Counter>(
    scene: &SceneData,
    color: &mut [B::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    cache: &mut impl SceneFrames,
    counter: &mut C,
    on_band: impl FnMut(u16, &[B::Store]),
) -> Result<Run, Error> {
    let state = RenderState::new(scene.near, scene.far)?;
    run_scene_in::<R, B, C>(scene, state, color, depth, bound, cache, counter, on_band)
}

/// [`run_scene_cached`] with the render state `state` (a plan's depth range), in bands of `depth.len() / WIDTH`
/// rows. Out of line: inlined into the boards' scene loop (generic over the band since commit ef8dc3d), LLVM placed
/// the strategies' draws so that the M4's exact tier took 51.5 instructions a pixel on W1 and 51.4 a fragment on W2
/// (46.6 and 45.8 before); out of line 50.5 and 49.7, every other figure of the M4 and RV32 boards the same or lower
/// (M4 W1 23.7 -> 23.6, RV32 W3 2,581.1 -> 2,564.1 a triangle), the M0's the same, and its deepest stack 176 bytes
/// shallower.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn run_scene_in<R: SpanRecip, B: BandKind, C: Counter>(
    scene: &SceneData,
    state: RenderState,
    color: &mut [B::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    cache: &mut impl SceneFrames,
    counter: &mut C,
    mut on_band: impl FnMut(u16, &[B::Store]),
) -> Result<Run, Error> {
    let band_h = (depth.len() / WIDTH as usize) as u16;
    let mut r = Rasterizer::<R>::new(state);
    let frame = cache.frame(scene.tris);
    let mut stats = Stats::default();
    let (mut instructions, mut hash, mut bands) = (0u64, Fnv::default(), 0u32);
    let mut y0 = 0u16;
    while y0 < HEIGHT {
        let h = band_h.min(HEIGHT - y0);
        let n = WIDTH as usize * h as usize;
        let depth = &mut depth[..n];
        let buf = DepthBuffer::band(depth, WIDTH, y0 as i32, h)?;
        let mut buf = with_bound(buf, &mut *bound, h)?;
        buf.clear();
        let mut band = B::band(color, y0 as i32, h, &scene.palette)?;
        let (b0, b1) = (y0 as i32, (y0 + h) as i32 - 1);
        counter.start();
        for (k, t) in scene.tris.iter().enumerate() {
            if i32::from(t.rows.0) <= b1 && i32::from(t.rows.1) >= b0 {
                stats += frame.draw(&mut r, &mut band, &mut buf, k, t)?;
            }
        }
        instructions += counter.stop();
        drop(band);
        let w = WIDTH as usize;
        let color = &color[..B::len(h)];
        for row in 0..h as usize {
            B::hash_row(&mut hash, color, row, &scene.palette);
            hash.words(&buf.data()[row * w..(row + 1) * w]);
        }
        on_band(y0, color);
        bands += 1;
        y0 += h;
    }
    Ok(Run {
        scene: scene.name,
        recip: R::NAME,
        stats,
        bands,
        triangles: scene.tris.len() as u32,
        instructions,
        hash: hash.0,
        bound: cfg!(feature = "coarse") && !bound.is_empty(),
    })
}

/// The first `n` words of a plan's depth storage (the W16 band) and the rest (a coarse bound's room).
fn split_depth(depth: &mut [u16], n: usize) -> Result<(&mut [u16], &mut [u16]), Error> {
    let actual = depth.len();
    depth.split_at_mut_checked(n).ok_or(Error::BufferSize {
        expected: n,
        actual,
    })
}

/// `buf` keeping a coarse bound in the front of `bound` (none when `bound` is empty).
#[cfg_attr(not(feature = "coarse"), allow(clippy::unnecessary_wraps))]
fn with_bound<'a>(
    buf: DepthBuffer<'a>,
    bound: &'a mut [u16],
    rows: u16,
) -> Result<DepthBuffer<'a>, Error> {
    #[cfg(feature = "coarse")]
    if !bound.is_empty() {
        let n = wraster::bound_len(WIDTH as usize, rows as usize);
        let len = bound.len();
        let seg = bound.get_mut(..n).ok_or(Error::BufferSize {
            expected: n,
            actual: len,
        })?;
        return buf.with_bound(seg);
    }
    let _ = (bound, rows);
    Ok(buf)
}

/// [`run_scene`], handing each finished band (first row, RGB565 pixels, `WIDTH` per row) to `on_band`: a display
/// driver pushes it out there.
pub fn run_scene_with<R: SpanRecip, C: Counter>(
    scene: &SceneData,
    color: &mut [u16],
    depth: &mut [u16],
    counter: &mut C,
    on_band: impl FnMut(u16, &[u16]),
) -> Result<Run, Error> {
    run_scene_bounded::<R, C>(scene, color, depth, &mut [], counter, on_band)
}

/// Hands every triangle of a frame whose rows meet the band's `(first, last)` rows to the draw it is given, checking
/// the rows before it makes the vertices (a dynamic call per triangle and band otherwise: the M0's W3 plan cost 15%
/// more than the default build when the draw checked them).
type ForEachTri<'a> = dyn FnMut(
        (i32, i32),
        &mut dyn FnMut(&[Vertex<Rgb565>; 3]) -> Result<(), Error>,
    ) -> Result<(), Error>
    + 'a;

/// Draws `scene` with `state` into colour bands of `rows` rows (`color.len() >= WIDTH * rows`), each band with the
/// depth buffer `F` (or none) in `depth` (bytes; only a packed format uses them) or, for W16, in `depth16`: the
/// lean W16 path. Hash and counts as [`run_scene`]: each row's colours, then its stored depth bytes (none without
/// a buffer).
#[allow(clippy::too_many_arguments)]
fn run_planned_tris<F: Codec<Word: bytemuck::Pod>, R: SpanRecip, C: Counter, const KIND: u8>(
    tris: &mut ForEachTri<'_>,
    plan: &PlanData,
    state: RenderState,
    color: &mut [u16],
    depth: &mut [u16],
    counter: &mut C,
    stats: &mut Stats,
    hash: &mut Fnv,
) -> Result<(u64, u32), Error> {
    let rows = if KIND == NO_DEPTH {
        (color.len() / WIDTH as usize) as u16
    } else {
        plan.band_rows
    };
    let mut r = Rasterizer::<R>::new(state);
    let (mut instructions, mut bands) = (0u64, 0u32);
    let mut y0 = 0u16;
    let w = WIDTH as usize;
    while y0 < HEIGHT {
        let h = rows.min(HEIGHT - y0);
        let n = w * h as usize;
        let color = &mut color[..n];
        color.fill(0);
        let mut band = ColorBand::<Rgb565>::band(color, WIDTH, y0 as i32, h)?;
        let (b0, b1) = (y0 as i32, (y0 + h) as i32 - 1);
        if KIND == NO_DEPTH {
            counter.start();
            let res = tris((b0, b1), &mut |v| {
                *stats += r.draw(&mut band, NoDepth, v)?;
                Ok(())
            });
            instructions += counter.stop();
            res?;
            for row in 0..h as usize {
                hash.words(&band.pixels()[row * w..(row + 1) * w]);
            }
        } else if KIND == LEAN_W16 {
            let (depth, rest) = split_depth(depth, n)?;
            let buf = DepthBuffer::band(depth, WIDTH, y0 as i32, h)?;
            let mut buf = with_bound(buf, if plan.coarse { rest } else { &mut [] }, h)?;
            buf.clear();
            counter.start();
            let res = tris((b0, b1), &mut |v| {
                *stats += r.draw(&mut band, &mut buf, v)?;
                Ok(())
            });
            instructions += counter.stop();
            res?;
            for row in 0..h as usize {
                hash.words(&band.pixels()[row * w..(row + 1) * w]);
                hash.words(&buf.data()[row * w..(row + 1) * w]);
            }
        } else {
            // The format's words in the plan's storage (`u32`-aligned: [`u16_words`]), so a 4-byte format's buffer
            // starts on a 4-byte boundary and the cast's error is not reached.
            let bytes: &mut [u8] = bytemuck::cast_slice_mut(depth);
            let words: &mut [F::Word] = bytemuck::try_cast_slice_mut(&mut bytes[..n * F::BYTES])
                .map_err(|_| Error::BufferSize {
                    expected: n * F::BYTES,
                    actual: 0,
                })?;
            let mut buf = DepthBuffer::<F>::band_format(words, WIDTH, y0 as i32, h)?;
            buf.clear_for(&state.range);
            counter.start();
            let res = tris((b0, b1), &mut |v| {
                *stats += r.draw(&mut band, &mut buf, v)?;
                Ok(())
            });
            instructions += counter.stop();
            res?;
            let rb = w * F::BYTES;
            let bytes: &[u8] = bytemuck::cast_slice(&*depth);
            for row in 0..h as usize {
                hash.words(&band.pixels()[row * w..(row + 1) * w]);
                hash.bytes(&bytes[row * rb..(row + 1) * rb]);
            }
        }
        bands += 1;
        y0 += h;
    }
    Ok((instructions, bands))
}

/// Renders the scene of `plan` as it says: its format (or none), strategy `R`, depth range and band rows; W4's
/// torus is transformed by the mesh path each frame and its triangles drawn from the transformed vertices (the
/// mesh path's own draw takes a W16 buffer only). `depth` must hold the plan's bands (`PlanData::depth_ram` bytes)
/// and `color` at least one colour band.
pub fn run_plan<
    F: Codec<Word: bytemuck::Pod>,
    R: SpanRecip,
    C: Counter,
    const KIND: u8,
    const SCENE: usize,
>(
    plan: &PlanData,
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut (impl SceneFrames + TorusFrames),
    counter: &mut C,
) -> Result<Run, Error> {
    let mut stats = Stats::default();
    let mut hash = Fnv::default();
    // W16 in more than one band: the mesh or list frame with the board's plane cache, as the default build draws.
    let banded = KIND == LEAN_W16 && plan.band_rows < HEIGHT;
    if SCENE == TORUS_SCENE {
        use wraster::scenes::torus;
        let cam = torus::camera()?;
        let mut state = cam.render_state()?;
        state.range = wraster::DepthRange::new(plan.near, plan.far)?;
        let mut r = Rasterizer::<R>::new(state);
        let mesh = Mesh {
            positions: &TORUS_POSITIONS,
            indices: &TORUS_INDICES,
            colors: Colors::PerFace(&TORUS_COLORS),
        };
        let vp = Viewport::new(0.0, 0.0, WIDTH as f32, HEIGHT as f32);
        let (mut instructions, mut bands) = (0, 0);
        for k in 0..torus::FRAMES {
            let m = cam.model_matrix(&torus::model(k));
            counter.start();
            // W16 in more than one band: binned by rows as `run_torus` does, when the board gives the bins.
            let binned = banded && !bins.is_empty();
            let frame = r.transform_mesh(&mesh, &m, &vp, verts).and_then(|f| {
                if binned {
                    r.bin_mesh(f, &mut *bins)
                } else {
                    Ok(f)
                }
            });
            instructions += counter.stop();
            let frame = frame?;
            let (i, b) = if KIND == LEAN_W16 {
                // W16: the mesh path itself (binning by rows, its own cull), as `run_torus` draws; the coarse bound,
                // if the plan keeps one, after the band.
                let n = WIDTH as usize * plan.band_rows as usize;
                let (depth, rest) = split_depth(depth, n)?;
                let bound = if plan.coarse { rest } else { &mut [] };
                // The frame cached or as it is: two types, one call each.
                macro_rules! in_bands {
                    ($frame:expr) => {
                        mesh_frame_in_bands::<_, Rgb565, _>(
                            &mut r,
                            $frame,
                            plan.band_rows,
                            color,
                            depth,
                            bound,
                            counter,
                            &mut stats,
                            &mut hash,
                            &mut |_, _| {},
                        )?
                    };
                }
                if banded {
                    in_bands!(&cache.attach(frame))
                } else {
                    in_bands!(&frame)
                }
            } else {
                let v = frame.vertices();
                run_planned_tris::<F, R, C, KIND>(
                    &mut |(b0, b1), draw| {
                        for (t, c) in TORUS_INDICES.iter().zip(TORUS_COLORS.iter()) {
                            let q = t.map(|i| v[i as usize]);
                            if q.iter().any(|p| p.rhw.is_nan() || p.rhw <= 0.0) {
                                // Needs the clipper: the planner refuses such meshes.
                                return Err(Error::NonFinite);
                            }
                            let tri = q.map(|p| Vertex {
                                x: p.x,
                                y: p.y,
                                z: 0.0,
                                rhw: p.rhw,
                                color: *c,
                            });
                            let rows = wraster::row_range(&tri).unwrap_or((i32::MAX, i32::MIN));
                            if rows.0 <= b1 && rows.1 >= b0 {
                                draw(&tri)?;
                            }
                        }
                        Ok(())
                    },
                    plan,
                    state,
                    color,
                    depth,
                    counter,
                    &mut stats,
                    &mut hash,
                )?
            };
            instructions += i;
            bands = b;
        }
        return Ok(Run {
            scene: "torus",
            recip: R::NAME,
            stats,
            bands,
            triangles: (torus::TRIANGLES * torus::FRAMES) as u32,
            instructions,
            hash: hash.0,
            bound: cfg!(feature = "coarse") && plan.coarse && KIND == LEAN_W16,
        });
    }
    let scene = SCENES.get(SCENE).ok_or(Error::IndexOutOfRange)?;
    let mut state = RenderState::new(scene.near, scene.far)?;
    state.range = wraster::DepthRange::new(plan.near, plan.far)?;
    if banded {
        // The list frame with the plane cache, as the default build (the same pixels, codes and hash as the
        // triangles drawn one by one below).
        let (depth, rest) = split_depth(depth, WIDTH as usize * plan.band_rows as usize)?;
        let bound = if plan.coarse { rest } else { &mut [] };
        return run_scene_in::<R, Rgb565, C>(
            scene,
            state,
            color,
            depth,
            bound,
            cache,
            counter,
            |_, _| {},
        );
    }
    let (instructions, bands) = run_planned_tris::<F, R, C, KIND>(
        // Only the triangles whose rows meet the band's, checked before their vertices are made (as `run_scene`
        // does).
        &mut |(b0, b1), draw| {
            for t in scene.tris {
                if i32::from(t.rows.0) <= b1 && i32::from(t.rows.1) >= b0 {
                    draw(&t.vertices())?;
                }
            }
            Ok(())
        },
        plan,
        state,
        color,
        depth,
        counter,
        &mut stats,
        &mut hash,
    )?;
    Ok(Run {
        scene: scene.name,
        recip: R::NAME,
        stats,
        bands,
        triangles: scene.tris.len() as u32,
        instructions,
        hash: hash.0,
        bound: cfg!(feature = "coarse") && plan.coarse && KIND == LEAN_W16,
    })
}

/// [`run_plan`] and its `bench` line, with `format=` the plan's and the added keys `plan=1 depth_ram=..
/// visibility_errors=..` (and `frames=8 instr_per_frame=` for the torus), or an `error` line; `false` on an error.
/// Out of line: one plan's run at a time on the stack (a firmware of several plans overflowed the Cortex-M0's stack
/// into its statics when they were inlined into one frame).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub fn run_plan_line<
    F: Codec<Word: bytemuck::Pod>,
    R: SpanRecip,
    C: Counter,
    const KIND: u8,
    const SCENE: usize,
>(
    board: &str,
    core: &str,
    plan: &PlanData,
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut (impl SceneFrames + TorusFrames),
    counter: &mut C,
    mut print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    match run_plan::<F, R, C, KIND, SCENE>(plan, color, depth, verts, bins, cache, counter) {
        Ok(run) => {
            // The bench line with the plan's format.
            let mut line = bench_line_of(board, core, plan.format, &run);
            let _ = write!(
                line,
                " plan=1 depth_ram={} visibility_errors={}",
                plan.depth_ram, plan.visibility_errors
            );
            if SCENE == TORUS_SCENE {
                torus_keys(&mut line, &run);
            }
            print(format_args!("{line}"));
            true
        }
        Err(e) => {
            print(format_args!(
                "error board={board} scene={} plan {e}",
                plan.scene
            ));
            false
        }
    }
}

/// Runs every standard scene (or only the one named by the build-time environment variable `ONLY`, for profiles:
/// `ONLY=small cargo run --release`) with reciprocal `R` and prints its `bench` line (or an `error` line) through `print`;
/// `false` when any scene failed.
pub fn run_all<R: SpanRecip, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [u16],
    depth: &mut [u16],
    counter: &mut C,
    print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    run_all_bounded::<R, C>(board, core, color, depth, &mut [], counter, print)
}

/// [`run_all`] with a coarse bound in `bound` ([`run_scene_bounded`]; empty: none).
pub fn run_all_bounded<R: SpanRecip, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [u16],
    depth: &mut [u16],
    bound: &mut [u16],
    counter: &mut C,
    print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    run_all_cached::<R, C>(board, core, color, depth, bound, &mut (), counter, print)
}

/// [`run_all_bounded`], the triangles drawn as `cache` says ([`run_scene_cached`]).
#[allow(clippy::too_many_arguments)]
pub fn run_all_cached<R: SpanRecip, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [u16],
    depth: &mut [u16],
    bound: &mut [u16],
    cache: &mut impl SceneFrames,
    counter: &mut C,
    print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    run_all_banded::<R, Rgb565, C>(board, core, color, depth, bound, cache, counter, print)
}

/// [`run_all_cached`] with any [`BandKind`] ([`run_scene_banded`]).
#[allow(clippy::too_many_arguments)]
pub fn run_all_banded<R: SpanRecip, B: BandKind, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [B::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    cache: &mut impl SceneFrames,
    counter: &mut C,
    mut print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    let mut ok = true;
    for scene in SCENES
        .iter()
        .filter(|s| option_env!("ONLY").is_none_or(|o| o == s.name))
    {
        match run_scene_banded::<R, B, C>(
            scene,
            color,
            depth,
            &mut *bound,
            &mut *cache,
            counter,
            |_, _| {},
        ) {
            Ok(run) => scene_line(board, core, &run, &mut print),
            Err(e) => {
                print(format_args!("error board={board} scene={} {e}", scene.name));
                ok = false;
            }
        }
    }
    ok
}

/// Prints the `bench` line of a standard scene's run. Out of line, as [`torus_line`]: its string (360 bytes) is then
/// on the stack only while the line is written, not under the scenes' draws (on the Cortex-M0 the stack left over
/// sizes the plane cache).
#[inline(never)]
fn scene_line(
    board: &str,
    core: &str,
    run: &Run,
    print: &mut impl FnMut(core::fmt::Arguments<'_>),
) {
    print(format_args!("{}", bench_line(board, core, run)));
}

/// Triangles a board's W4 plane cache holds ([`wraster::mesh::PlaneCache`]): those that reach the next band, and the
/// previous band's until the walk meets them; a full cache only computes values again. 50 is what the M0's 16 KiB
/// leave beside its 6-row bands of half a byte a pixel (its deepest stack then keeps 284 bytes free in the torus build
/// and 268 in the `cull` build, over CI's 256), since the frame loop keeps its transform, its camera and its lines out
/// of line (`torus_frame`, `torus_view`, `torus_line`). Measured on the M0's W4 (default `Fast` alone, commit
/// 2124873's draw code, its firmware given more RAM: `memory.x` at 4M, run in QEMU's mps2-an386, the same
/// instructions): 5-row bands, 7,907,768 instructions a frame with 38, 7,747,448 with 49, 7,678,228 with 64,
/// 7,643,562 with 100; 4-row bands (RGB565), 8,396,060 with 38 and 8,131,556 with 64.
pub const TORUS_CACHE: usize = 50;
/// The W4 plane cache of a plan's firmware (`--features plan`): the plans' runner is deeper on the stack than the
/// default build's W4 run, and on the Cortex-M0 22 triangles keep its 256 bytes free (25 left 204).
pub const PLAN_TORUS_CACHE: usize = 22;
/// A board's W4 plane cache.
pub type TorusCache = wraster::mesh::PlaneCache<TORUS_CACHE>;

/// How a board's W4 run keeps its frames: as they are (`()`, for a frame in one band: nothing to cache) or with a
/// plane cache ([`TorusCache`]). A type, not a value: a board links only the draw it uses.
pub trait TorusFrames {
    /// The frame drawn.
    type Frame<'a>: wraster::mesh::DrawFrame<'a, Rgb565>
    where
        Self: 'a;
    /// Frame `f` as drawn.
    fn attach<'a>(&'a mut self, f: MeshFrame<'a, Rgb565>) -> Self::Frame<'a>;
}

impl TorusFrames for () {
    type Frame<'a> = MeshFrame<'a, Rgb565>;
    fn attach<'a>(&'a mut self, f: MeshFrame<'a, Rgb565>) -> MeshFrame<'a, Rgb565> {
        f
    }
}

impl<const N: usize> TorusFrames for wraster::mesh::PlaneCache<N> {
    type Frame<'a> = wraster::mesh::CachedFrame<'a, Rgb565>;
    fn attach<'a>(&'a mut self, f: MeshFrame<'a, Rgb565>) -> Self::Frame<'a> {
        f.with_plane_cache(self)
    }
}

/// Up to 16 RGB565 colours (the background, 0, at slot 0) and the multiplier that puts colour `c` at slot
/// `(c k) >> 28`, for a band of half a byte a pixel ([`NibbleBand`]): baked per scene by build.rs, which checks that
/// no two of the scene's colours share a slot.
#[derive(Clone, Copy, Debug)]
pub struct NibblePalette {
    /// Slot `i`'s colour.
    pub colors: [u16; 16],
    /// The multiplier.
    pub k: u32,
}

impl NibblePalette {
    /// Colour `c`'s slot (a colour the palette does not hold lands on some other colour's slot).
    #[inline(always)]
    pub fn slot(&self, c: u16) -> u8 {
        ((c as u32).wrapping_mul(self.k) >> 28) as u8
    }
}

/// An RGB565 colour band of half a byte a pixel: each pixel the slot of its colour in a [`NibblePalette`] (pixel `x`
/// of a row in byte `x / 2`, the low nibble for even `x`), turned back into RGB565 as the band leaves (for the
/// display; here, for the hash). A scene of at most 15 colours (every standard scene, W4's eight) then keeps 2.5
/// bytes a pixel with W16 depth rather than 4, which on the Cortex-M0's 16 KiB buys taller bands. Rows `y0..y0 +
/// height` of the frame; writes outside them, or outside the columns, are dropped.
pub struct NibbleBand<'a> {
    px: &'a mut [u8],
    width: usize,
    height: usize,
    y0: i32,
    palette: &'a NibblePalette,
}

impl<'a> NibbleBand<'a> {
    /// A band of `height` rows of `width` (even) pixels from frame row `y0` in `palette`: `px.len()` must be
    /// `width * height / 2` (else [`Error::BufferSize`], as for an odd or zero size).
    pub fn band(
        px: &'a mut [u8],
        width: u16,
        y0: i32,
        height: u16,
        palette: &'a NibblePalette,
    ) -> Result<Self, Error> {
        let expected = width as usize * height as usize / 2;
        if px.len() != expected || width == 0 || height == 0 || !width.is_multiple_of(2) {
            return Err(Error::BufferSize {
                expected,
                actual: px.len(),
            });
        }
        Ok(NibbleBand {
            px,
            width: width as usize,
            height: height as usize,
            y0,
            palette,
        })
    }

    /// The band's bytes, row by row (`width / 2` a row).
    pub fn bytes(&self) -> &[u8] {
        self.px
    }

    /// Row `y` of the frame as the band's bytes (`None` outside the band).
    #[inline(always)]
    fn row_mut(&mut self, y: i32) -> Option<&mut [u8]> {
        let r = y.wrapping_sub(self.y0) as u32 as usize; // below y0: wraps above `height`
        let stride = self.width / 2;
        if r < self.height {
            self.px.get_mut(r * stride..(r + 1) * stride)
        } else {
            None
        }
    }

    /// Columns `x0..x1` (inside the row) of `row` set to the slot `v` (below 16).
    #[inline(always)]
    fn fill_row(row: &mut [u8], x0: usize, x1: usize, v: u8) {
        let mut x = x0;
        if x & 1 == 1 && x < x1 {
            if let Some(b) = row.get_mut(x / 2) {
                *b = (*b & 0x0f) | v << 4;
            }
            x += 1;
        }
        let pairs_end = x1 & !1;
        if x < pairs_end {
            if let Some(bytes) = row.get_mut(x / 2..pairs_end / 2) {
                let vv = v | v << 4;
                // A rasterizer's short run: up to four bytes stored one by one (a loop of stores LLVM makes a
                // `memset` call, on the M0 some 20 instructions more than the stores), longer ones by `fill`.
                match bytes {
                    [] => {}
                    [a] => *a = vv,
                    [a, b] => (*a, *b) = (vv, vv),
                    [a, b, c] => (*a, *b, *c) = (vv, vv, vv),
                    [a, b, c, d] => (*a, *b, *c, *d) = (vv, vv, vv, vv),
                    _ => bytes.fill(vv),
                }
            }
            x = pairs_end;
        }
        if x < x1 {
            if let Some(b) = row.get_mut(x / 2) {
                *b = (*b & 0xf0) | v;
            }
        }
    }
}

impl embedded_graphics_core::geometry::Dimensions for NibbleBand<'_> {
    /// The band's own rows.
    fn bounding_box(&self) -> embedded_graphics_core::primitives::Rectangle {
        embedded_graphics_core::primitives::Rectangle::new(
            embedded_graphics_core::geometry::Point::new(0, self.y0),
            embedded_graphics_core::geometry::Size::new(self.width as u32, self.height as u32),
        )
    }
}

impl embedded_graphics_core::draw_target::DrawTarget for NibbleBand<'_> {
    type Color = Rgb565;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = embedded_graphics_core::Pixel<Rgb565>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        use embedded_graphics_core::pixelcolor::IntoStorage;
        let (width, palette) = (self.width, self.palette);
        for embedded_graphics_core::Pixel(p, c) in pixels {
            if let (Some(row), Ok(x)) = (self.row_mut(p.y), usize::try_from(p.x)) {
                if x < width {
                    Self::fill_row(row, x, x + 1, palette.slot(c.into_storage()));
                }
            }
        }
        Ok(())
    }

    /// Each row of the rectangle clipped to the band: a lone first or last nibble, the bytes between filled whole.
    #[inline(always)]
    fn fill_solid(
        &mut self,
        area: &embedded_graphics_core::primitives::Rectangle,
        color: Rgb565,
    ) -> Result<(), Self::Error> {
        use embedded_graphics_core::pixelcolor::IntoStorage;
        let v = self.palette.slot(color.into_storage());
        let (p, size) = (area.top_left, area.size);
        // A rasterizer's run (one row, inside the columns): no clipping, the row found once.
        let (x, w, r) = (
            p.x as u32 as usize,
            size.width as usize,
            p.y.wrapping_sub(self.y0) as u32 as usize,
        );
        if size.height == 1 && r < self.height && x <= self.width && w <= self.width - x {
            let at = r * self.width + x; // in nibbles
            Self::fill_row(self.px, at, at + w, v);
            return Ok(());
        }
        let x0 = p.x.max(0) as usize;
        let x1 = (p.x.saturating_add_unsigned(size.width).max(0) as usize).min(self.width);
        if x0 < x1 {
            for y in p.y..p.y.saturating_add_unsigned(size.height) {
                if let Some(row) = self.row_mut(y) {
                    Self::fill_row(row, x0, x1, v);
                }
            }
        }
        Ok(())
    }

    fn clear(&mut self, color: Rgb565) -> Result<(), Self::Error> {
        use embedded_graphics_core::pixelcolor::IntoStorage;
        let v = self.palette.slot(color.into_storage());
        self.px.fill(v | v << 4);
        Ok(())
    }
}

/// How a board keeps its colour band: RGB565 in a [`ColorBand`] (`Rgb565`, two bytes a pixel), or half a byte a
/// pixel in a [`NibbleBand`] ([`Nibbles`], with the scene's [`NibblePalette`]). Either way a band hashes as its
/// RGB565 pixels, so the frames' hashes are the same. A type, not a value: a board links only the band it uses.
pub trait BandKind {
    /// The band's storage element.
    type Store: bytemuck::Pod;
    /// The band as a draw target.
    type Band<'a>: embedded_graphics_core::draw_target::DrawTarget<Color = Rgb565>;
    /// Storage elements of a band of `rows` rows.
    fn len(rows: u16) -> usize;
    /// The band of frame rows `y0..y0 + rows` at the front of `px`, cleared to the background (`palette`: the
    /// scene's colours, for a band that needs them).
    fn band<'a>(
        px: &'a mut [Self::Store],
        y0: i32,
        rows: u16,
        palette: &'a NibblePalette,
    ) -> Result<Self::Band<'a>, Error>;
    /// Hashes the band's row `r` (`WIDTH` pixels) as its RGB565 words.
    fn hash_row(hash: &mut Fnv, px: &[Self::Store], r: usize, palette: &NibblePalette);
}

impl BandKind for Rgb565 {
    type Store = u16;
    type Band<'a> = ColorBand<'a, Rgb565>;
    fn len(rows: u16) -> usize {
        WIDTH as usize * rows as usize
    }
    fn band<'a>(
        px: &'a mut [u16],
        y0: i32,
        rows: u16,
        _: &'a NibblePalette,
    ) -> Result<ColorBand<'a, Rgb565>, Error> {
        ColorBand::band(cleared_front(px, Self::len(rows))?, WIDTH, y0, rows)
    }
    fn hash_row(hash: &mut Fnv, px: &[u16], r: usize, _: &NibblePalette) {
        let w = WIDTH as usize;
        hash.words(px.get(r * w..(r + 1) * w).unwrap_or(&[]));
    }
}

/// The first `n` elements of a band's storage, zeroed (the background), or [`Error::BufferSize`].
fn cleared_front<T: bytemuck::Pod>(px: &mut [T], n: usize) -> Result<&mut [T], Error> {
    let actual = px.len();
    let px = px.get_mut(..n).ok_or(Error::BufferSize {
        expected: n,
        actual,
    })?;
    px.fill(bytemuck::Zeroable::zeroed());
    Ok(px)
}

/// [`BandKind`]'s band of half a byte a pixel ([`NibbleBand`]).
pub struct Nibbles;

impl BandKind for Nibbles {
    type Store = u8;
    type Band<'a> = NibbleBand<'a>;
    fn len(rows: u16) -> usize {
        WIDTH as usize * rows as usize / 2
    }
    fn band<'a>(
        px: &'a mut [u8],
        y0: i32,
        rows: u16,
        palette: &'a NibblePalette,
    ) -> Result<NibbleBand<'a>, Error> {
        NibbleBand::band(
            cleared_front(px, Self::len(rows))?,
            WIDTH,
            y0,
            rows,
            palette,
        )
    }
    fn hash_row(hash: &mut Fnv, px: &[u8], r: usize, palette: &NibblePalette) {
        let stride = WIDTH as usize / 2;
        for &b in px.get(r * stride..(r + 1) * stride).unwrap_or(&[]) {
            for i in [b & 15, b >> 4] {
                hash.words(&[palette.colors[i as usize]]);
            }
        }
    }
}

/// W4 "torus" (`wraster::scenes::torus`): 8 frames of the rotating mesh, each transformed once
/// ([`Rasterizer::transform_mesh`] into `verts`, at least 512) and drawn band by band
/// ([`Rasterizer::draw_mesh_frame`]) with the given buffers, depth cleared per band; binned by rows
/// ([`Rasterizer::bin_mesh`]) into `bins` (a byte per triangle) when `bins` is not empty, which pays when the frame
/// is drawn in more than one band (the pixels are the same either way). Counts the transform, the binning and the
/// draws (not the clears or the hash); the hash runs over the 8 frames in order.
#[allow(clippy::too_many_arguments)]
pub fn run_torus<R: SpanRecip, C: Counter>(
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
) -> Result<Run, Error> {
    run_torus_with::<R, C>(
        color,
        depth,
        verts,
        bins,
        cache,
        counter,
        0..wraster::scenes::torus::FRAMES,
        |_, _| {},
    )
}

/// One transformed mesh frame drawn band by band (`band_h` rows, the W16 depth cleared per band) through
/// `Rasterizer::draw_mesh_frame`: each band hashed (its colours, then its depths, row by row) and handed to
/// `on_band` (first row, pixels). Returns the draws' instructions (not the clears or the hash) and the bands.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn mesh_frame_in_bands<'a, R: SpanRecip, T: BandKind, C: Counter>(
    r: &mut Rasterizer<R>,
    frame: &impl wraster::mesh::DrawFrame<'a, Rgb565>,
    band_h: u16,
    color: &mut [T::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    counter: &mut C,
    stats: &mut Stats,
    hash: &mut Fnv,
    on_band: &mut impl FnMut(u16, &[T::Store]),
) -> Result<(u64, u32), Error> {
    let (mut instructions, mut bands) = (0u64, 0u32);
    let w = WIDTH as usize;
    let mut y0 = 0u16;
    while y0 < HEIGHT {
        let h = band_h.min(HEIGHT - y0);
        let depth = &mut depth[..w * h as usize];
        let buf = DepthBuffer::band(depth, WIDTH, y0 as i32, h)?;
        let mut buf = with_bound(buf, &mut *bound, h)?;
        buf.clear();
        let mut band = T::band(color, y0 as i32, h, &TORUS_NIBBLES)?;
        counter.start();
        let s = r.draw_mesh_frame(&mut band, &mut buf, frame);
        instructions += counter.stop();
        drop(band);
        *stats += s?;
        let color = &color[..T::len(h)];
        hash_band::<T>(hash, color, buf.data(), h);
        on_band(y0, color);
        bands += 1;
        y0 += h;
    }
    Ok((instructions, bands))
}

/// Hashes a band's rows (`w` pixels each): each row's colours, then its depths. Out of line: its loop's registers
/// are then not spilled to the stack under the frame's draws (the Cortex-M0's plane cache is sized by that stack).
#[inline(never)]
fn hash_band<T: BandKind>(hash: &mut Fnv, colors: &[T::Store], depths: &[u16], rows: u16) {
    for (r, d) in depths
        .chunks_exact(WIDTH as usize)
        .take(rows as usize)
        .enumerate()
    {
        T::hash_row(hash, colors, r, &TORUS_NIBBLES);
        hash.words(d);
    }
}

/// [`run_torus`] for frames `frames` (frame `k` rotates by `k` steps; any `k`), handing each finished band (first
/// row, RGB565 pixels) to `on_band`, as a display driver wants it.
#[allow(clippy::too_many_arguments)]
pub fn run_torus_with<R: SpanRecip, C: Counter>(
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
    frames: core::ops::Range<usize>,
    on_band: impl FnMut(u16, &[u16]),
) -> Result<Run, Error> {
    run_torus_bounded::<R, Rgb565, C>(
        color,
        depth,
        &mut [],
        verts,
        bins,
        cache,
        counter,
        frames,
        on_band,
    )
}

/// [`run_torus_with`], each band's depth buffer keeping a coarse bound in `bound` (feature `coarse`; empty: none).
#[allow(clippy::too_many_arguments)]
pub fn run_torus_bounded<R: SpanRecip, T: BandKind, C: Counter>(
    color: &mut [T::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
    frames: core::ops::Range<usize>,
    mut on_band: impl FnMut(u16, &[T::Store]),
) -> Result<Run, Error> {
    use wraster::scenes::torus;
    let band_h = (depth.len() / WIDTH as usize) as u16;
    let (state, to_clip) = torus_view()?;
    let mut r = Rasterizer::<R>::new(state);
    let mesh = Mesh {
        positions: &TORUS_POSITIONS,
        indices: &TORUS_INDICES,
        colors: Colors::PerFace(&TORUS_COLORS),
    };
    let vp = Viewport::new(0.0, 0.0, WIDTH as f32, HEIGHT as f32);
    let mut stats = Stats::default();
    let (mut instructions, mut hash, mut bands) = (0u64, Fnv::default(), 0u32);
    let n_frames = frames.len() as u32;
    for k in frames {
        // Borrowed in place (moved out, the frame would take a second slot of the stack).
        let prepared = torus_frame(&r, &to_clip, k, &mesh, &vp, verts, bins, cache, counter);
        let frame = match &prepared {
            Ok((f, i)) => {
                instructions += i;
                f
            }
            Err(e) => return Err(*e),
        };
        let (i, b) = mesh_frame_in_bands::<_, T, _>(
            &mut r,
            frame,
            band_h,
            color,
            depth,
            &mut *bound,
            counter,
            &mut stats,
            &mut hash,
            &mut on_band,
        )?;
        instructions += i;
        bands += b;
    }
    Ok(Run {
        scene: "torus",
        recip: R::NAME,
        stats,
        bands: bands / n_frames.max(1),
        triangles: torus::TRIANGLES as u32 * n_frames,
        instructions,
        hash: hash.0,
        bound: cfg!(feature = "coarse") && !bound.is_empty(),
    })
}

/// W4's camera as its render state and its matrix (`Camera::matrix`), which the frames keep instead of the camera.
/// Out of line, with the camera on its stack: the frames' draws then run under a smaller frame.
#[inline(never)]
fn torus_view() -> Result<(wraster::RenderState, wraster::projection::Mat4), Error> {
    let cam = wraster::scenes::torus::camera()?;
    Ok((cam.render_state()?, cam.matrix()))
}

/// Frame `k` of W4 transformed ([`Rasterizer::transform_mesh`]), binned by rows where `bins` is not empty
/// ([`Rasterizer::bin_mesh`]) and given `cache`, with the instructions that took. Out of line: the model matrix and
/// the transform's result (a frame returned through memory) then take stack only while the frame is prepared, not
/// under its draws, which on the Cortex-M0 set how many triangles its plane cache can hold.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn torus_frame<'a, R: SpanRecip, C: Counter, T: TorusFrames>(
    r: &Rasterizer<R>,
    to_clip: &wraster::projection::Mat4,
    k: usize,
    mesh: &Mesh<'a, Rgb565>,
    vp: &Viewport,
    verts: &'a mut [Projected],
    bins: &'a mut [u8],
    cache: &'a mut T,
    counter: &mut C,
) -> Result<(T::Frame<'a>, u64), Error> {
    // `Camera::model_matrix` with the camera's matrix computed once: the same operations, the same bits.
    let m = wraster::scenes::torus::model(k) * *to_clip;
    counter.start();
    let frame = r.transform_mesh(mesh, &m, vp, verts).and_then(|f| {
        if bins.is_empty() {
            Ok(f)
        } else {
            r.bin_mesh(f, bins)
        }
    });
    let frame = match frame {
        Ok(f) => cache.attach(f),
        Err(e) => return Err(e),
    };
    Ok((frame, counter.stop()))
}

/// [`run_torus`] and its `bench` line (with `frames=8 instr_per_frame=`) or an `error` line; `false` on an error.
/// Skipped (true) when the build-time `ONLY` names another scene.
#[allow(clippy::too_many_arguments)]
pub fn run_torus_line<R: SpanRecip, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
    print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    run_torus_line_bounded::<R, C>(
        board,
        core,
        color,
        depth,
        &mut [],
        verts,
        bins,
        cache,
        counter,
        print,
    )
}

/// [`run_torus_line`] with a coarse bound in `bound` ([`run_torus_bounded`]; empty: none).
#[allow(clippy::too_many_arguments)]
pub fn run_torus_line_bounded<R: SpanRecip, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [u16],
    depth: &mut [u16],
    bound: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
    print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    run_torus_line_in::<R, Rgb565, C>(
        board, core, color, depth, bound, verts, bins, cache, counter, print,
    )
}

/// [`run_torus_line_bounded`] with any [`BandKind`]: `color` holds its band's storage (half a byte a pixel for
/// [`Nibbles`]); the band's height is `depth`'s rows.
#[allow(clippy::too_many_arguments)]
pub fn run_torus_line_in<R: SpanRecip, T: BandKind, C: Counter>(
    board: &str,
    core: &str,
    color: &mut [T::Store],
    depth: &mut [u16],
    bound: &mut [u16],
    verts: &mut [Projected],
    bins: &mut [u8],
    cache: &mut impl TorusFrames,
    counter: &mut C,
    mut print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    if option_env!("ONLY").is_some_and(|o| o != "torus") {
        return true;
    }
    match run_torus_bounded::<R, T, C>(
        color,
        depth,
        bound,
        verts,
        bins,
        cache,
        counter,
        0..wraster::scenes::torus::FRAMES,
        |_, _| {},
    ) {
        Ok(run) => {
            torus_line(board, core, &run, &mut print);
            true
        }
        Err(e) => {
            print(format_args!("error board={board} scene=torus {e}"));
            false
        }
    }
}

/// The `bench` line of a torus run. Out of line: its string (360 bytes) is then on the stack only while the line is
/// written, not under the frame's draws (the Cortex-M0's 16 KiB hold the bands, the vertices and the stack).
#[inline(never)]
fn torus_line(
    board: &str,
    core: &str,
    run: &Run,
    print: &mut impl FnMut(core::fmt::Arguments<'_>),
) {
    let mut line = bench_line(board, core, run);
    torus_keys(&mut line, run);
    print(format_args!("{line}"));
}

/// W4's added keys of a `bench` line: `frames=8 instr_per_frame=`.
fn torus_keys(line: &mut heapless::String<360>, run: &Run) {
    let frames = wraster::scenes::torus::FRAMES as u64;
    let _ = write!(
        line,
        " frames={frames} instr_per_frame={}",
        Ratio(run.instructions, frames)
    );
}

/// What the bounding-sphere cull costs and saves on W4 (`wraster::mesh::Sphere`): the instructions of
/// `Sphere::visible` for frame 0's matrix (the torus in view: the cull passes it) and for the torus moved behind the
/// eye (culled), each the mean of 64 calls (one SysTick tick is 40 or 62.5 instructions), against one
/// `transform_mesh` of frame 0 (what a culled mesh does not pay). Prints
/// `cull board=.. core=.. scene=torus in_view=.. outside=.. transform=.. culled_outside=..`; `false` on an error or
/// when the cull gets either case wrong.
pub fn cull_line<C: Counter>(
    board: &str,
    core: &str,
    verts: &mut [Projected],
    counter: &mut C,
    mut print: impl FnMut(core::fmt::Arguments<'_>),
) -> bool {
    use wraster::mesh::Sphere;
    use wraster::scenes::torus;
    let run =
        |verts: &mut [Projected], counter: &mut C| -> Result<(u64, u64, u64, bool, bool), Error> {
            let cam = torus::camera()?;
            let state = cam.render_state()?;
            let r = Rasterizer::<wraster::recip::Fast>::new(state);
            let mesh = Mesh {
                positions: &TORUS_POSITIONS,
                indices: &TORUS_INDICES,
                colors: Colors::PerFace(&TORUS_COLORS),
            };
            let vp = Viewport::new(0.0, 0.0, WIDTH as f32, HEIGHT as f32);
            let size = embedded_graphics_core::geometry::Size::new(WIDTH as u32, HEIGHT as u32);
            let sphere = Sphere::enclosing(&TORUS_POSITIONS)?;
            let m_in = cam.model_matrix(&torus::model(0));
            // The eye is at z = 3 looking at the origin: z = 10 is behind it.
            let m_out = cam.model_matrix(
                &(torus::model(0) * wraster::projection::Mat4::translation([0.0, 0.0, 10.0])),
            );
            let mut mean = |m: &wraster::projection::Mat4| {
                let mut v = true;
                counter.start();
                for _ in 0..64 {
                    v &= core::hint::black_box(&sphere).visible(
                        core::hint::black_box(m),
                        &vp,
                        size,
                        &state.range,
                    );
                }
                (counter.stop() / 64, v)
            };
            let (i_in, v_in) = mean(&m_in);
            let (i_out, v_out) = mean(&m_out);
            counter.start();
            let f = r.transform_mesh(&mesh, &m_in, &vp, verts);
            let t = counter.stop();
            f?;
            Ok((i_in, i_out, t, v_in, !v_out))
        };
    match run(verts, counter) {
        Ok((i_in, i_out, t, kept, culled)) => {
            print(format_args!(
                "cull board={board} core={core} scene=torus in_view={i_in} outside={i_out} transform={t} culled_outside={culled}"
            ));
            kept && culled
        }
        Err(e) => {
            print(format_args!("error board={board} scene=torus cull {e}"));
            false
        }
    }
}

/// `num / den` with one decimal, by integers.
struct Ratio(u64, u64);

impl core::fmt::Display for Ratio {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let tenths = (self.0 * 10 + self.1 / 2) / self.1.max(1);
        write!(f, "{}.{}", tenths / 10, tenths % 10)
    }
}

/// The bench line of a run (the format; keys are stable).
pub fn bench_line(board: &str, core: &str, run: &Run) -> heapless::String<360> {
    bench_line_of(board, core, "W16", run)
}

/// [`bench_line`] with another depth format's name (a plan's).
pub fn bench_line_of(board: &str, core: &str, format: &str, run: &Run) -> heapless::String<360> {
    let mut s = heapless::String::new();
    let (px, fr) = (run.stats.written as u64, run.stats.fragments as u64);
    let _ = write!(
        s,
        "bench board={board} core={core} scene={} format={format} bands={} pixels={px} fragments={fr} triangles={} instructions={} instr_per_px={} instr_per_fragment={} instr_per_tri={} hash={:016x} recip={} bound={}",
        run.scene,
        run.bands,
        run.triangles,
        run.instructions,
        Ratio(run.instructions, px),
        Ratio(run.instructions, fr),
        Ratio(run.instructions, run.triangles as u64),
        run.hash,
        run.recip,
        if run.bound { "coarse" } else { "none" }
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics_core::draw_target::DrawTarget;
    use embedded_graphics_core::geometry::{Point, Size};
    use embedded_graphics_core::primitives::Rectangle;

    fn rgb(c: u16) -> Rgb565 {
        Rgb565::from(RawU16::new(c))
    }

    /// `RECIP` names the strategies by the `bench` lines' `recip=`; unset is the core's default; a prefix or a longer
    /// name is no name (an unknown one fails the build: a `const` panic).
    #[test]
    fn probe_recip_reads_the_bench_names() {
        assert_eq!(probe_recip(None), PROBE_DEFAULT);
        for (name, want) in [
            ("fast", PROBE_FAST),
            ("fast-div", PROBE_FAST_DIV),
            ("lerp64", PROBE_EXACT),
            ("prev-pixel", PROBE_PREV_PIXEL),
            ("f32-div", PROBE_F32_DIV),
        ] {
            assert_eq!(probe_recip(Some(name)), want, "{name}");
        }
        for bad in ["fas", "fast-di", "fast-divx", "exact", ""] {
            assert!(
                std::panic::catch_unwind(|| probe_recip(Some(bad))).is_err(),
                "{bad}"
            );
        }
    }

    /// Every rectangle (inside, across every side, empty, far outside, from every column's parity) fills exactly its
    /// pixels inside the band and keeps the rest, and `draw_iter` writes exactly the pixels inside: checked against a
    /// model of one colour a pixel, on a band 10 pixels wide and 5 rows high at frame row 7, in W4's palette.
    #[test]
    fn a_nibble_band_fills_exactly_the_pixels_inside() {
        let (w, h, y0) = (10usize, 5usize, 7i32);
        let pal = &TORUS_NIBBLES;
        let colors: Vec<u16> = pal.colors.iter().copied().filter(|&c| c != 0).collect();
        assert_eq!(colors.len(), 8);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move |n: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as i32
        };
        let (mut px, mut model) = ([0u8; 25], [0u16; 50]);
        for k in 0..5000 {
            let c = colors[rnd(8) as usize];
            let mut band = NibbleBand::band(&mut px, w as u16, y0, h as u16, pal).unwrap();
            let (x, y) = (rnd(16) - 3, rnd(11) + y0 - 3);
            if k % 2 == 0 {
                let (rw, rh) = (rnd(14) as u32, rnd(4) as u32);
                band.fill_solid(&Rectangle::new(Point::new(x, y), Size::new(rw, rh)), rgb(c))
                    .unwrap();
                for j in y..y + rh as i32 {
                    for i in x..x + rw as i32 {
                        if (0..w as i32).contains(&i) && (y0..y0 + h as i32).contains(&j) {
                            model[(j - y0) as usize * w + i as usize] = c;
                        }
                    }
                }
            } else {
                band.draw_iter([embedded_graphics_core::Pixel(Point::new(x, y), rgb(c))])
                    .unwrap();
                if (0..w as i32).contains(&x) && (y0..y0 + h as i32).contains(&y) {
                    model[(y - y0) as usize * w + x as usize] = c;
                }
            }
            let unpacked: Vec<u16> = px
                .iter()
                .flat_map(|b| [b & 15, b >> 4])
                .map(|i| pal.colors[i as usize])
                .collect();
            assert_eq!(unpacked, model, "after step {k}");
        }
    }

    /// Every scene's palette (baked by build.rs) holds each of its triangles' colours in a slot of its own, and the
    /// background 0 in slot 0: so a band of half a byte a pixel keeps every colour it is given.
    #[test]
    fn every_scene_palette_holds_its_colours() {
        for scene in &SCENES {
            let pal = &scene.palette;
            assert_eq!((pal.slot(0), pal.colors[0]), (0, 0));
            for t in scene.tris {
                assert_eq!(
                    pal.colors[pal.slot(t.color) as usize],
                    t.color,
                    "{}",
                    scene.name
                );
            }
        }
        for &c in TORUS_COLORS.iter() {
            use embedded_graphics_core::pixelcolor::IntoStorage;
            let c = c.into_storage();
            assert_eq!(TORUS_NIBBLES.colors[TORUS_NIBBLES.slot(c) as usize], c);
        }
    }

    /// A band of half a byte a pixel hashes as the RGB565 band of the same draws (`Nibbles` against `Rgb565`): so a
    /// frame's hash is the same whichever band a board keeps.
    #[test]
    fn a_nibble_band_hashes_as_its_rgb565_colours() {
        let rows = 3u16;
        let pal = &SCENES[3].palette;
        let (mut nib, mut rgb565) = (vec![0u8; Nibbles::len(rows)], vec![0u16; Rgb565::len(rows)]);
        let mut b = Nibbles::band(&mut nib, 20, rows, pal).unwrap();
        let mut c = Rgb565::band(&mut rgb565, 20, rows, pal).unwrap();
        for (k, x) in (0..WIDTH as i32).step_by(7).enumerate() {
            let t = &SCENES[3].tris[k * 13 % SCENES[3].tris.len()];
            let r = Rectangle::new(Point::new(x, 20 + (k % 3) as i32), Size::new(5, 1));
            b.fill_solid(&r, rgb(t.color)).unwrap();
            c.fill_solid(&r, rgb(t.color)).unwrap();
        }
        let (mut hn, mut hr) = (Fnv::default(), Fnv::default());
        for r in 0..rows as usize {
            Nibbles::hash_row(&mut hn, &nib, r, pal);
            Rgb565::hash_row(&mut hr, &rgb565, r, pal);
        }
        assert_eq!(hn.0, hr.0);
        assert_ne!(hr.0, Fnv::default().0);
    }

    /// A band of the wrong size is an error, not a panic.
    #[test]
    fn a_nibble_band_of_the_wrong_size_is_an_error() {
        let pal = &TORUS_NIBBLES;
        assert!(NibbleBand::band(&mut [0u8; 24], 10, 0, 5, pal).is_err());
        assert!(NibbleBand::band(&mut [0u8; 25], 9, 0, 5, pal).is_err());
        assert!(Nibbles::band(&mut [0u8; 10], 0, 1, pal).is_err());
    }
}
