//! Host-side tools for wraster: a checked framebuffer, the independent f64 reference rasterizer, render helpers.
//!
//! The reference shares with the core only the rules: snapping for coverage (round to nearest, ties to even, 8 bits),
//! the top-left rule and the W16 encoding `round(W / W_far * 65535)`. Its arithmetic is its own: coverage by
//! evaluating the three edge functions of the snapped vertices at every pixel centre in i64, and W at each covered
//! centre by barycentric interpolation of `1/W` over the vertices **as given** (f64, the true surface, extrapolated
//! at a covered centre just outside the given triangle). It also reports how far the core's depth grid (vertices
//! rounded to `2^-17` to `2^-29` px by the box's size, `wraster::depth_grid_bits`) may move the depth at each pixel,
//! so that tests can add that derived term to their bounds.

pub mod plan;
pub mod plot;

use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;
use wraster::format::{DepthFormat, Storage};
use wraster::packed::Input;
use wraster::recip::{SpanRecip, WSpan};
use wraster::{Codec, DepthBuffer, Error, Rasterizer, RenderState, Stats, Vertex};

/// A colour framebuffer that counts writes per pixel and panics on any write outside it.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
    /// Colours, row-major.
    pub px: Vec<Rgb565>,
    /// Writes per pixel.
    pub writes: Vec<u32>,
}

impl Frame {
    /// A black frame.
    pub fn new(w: u32, h: u32) -> Self {
        Frame {
            w,
            h,
            px: vec![Rgb565::BLACK; (w * h) as usize],
            writes: vec![0; (w * h) as usize],
        }
    }
    fn put(&mut self, p: Point, c: Rgb565) {
        assert!(
            p.x >= 0 && p.y >= 0 && (p.x as u32) < self.w && (p.y as u32) < self.h,
            "write outside the frame at {p:?}"
        );
        let k = (p.y as u32 * self.w + p.x as u32) as usize;
        self.px[k] = c;
        self.writes[k] += 1;
    }
    /// Saves as a PNG through embedded-graphics-simulator.
    pub fn save_png(&self, path: &std::path::Path) {
        use embedded_graphics_simulator::{OutputSettingsBuilder, SimulatorDisplay};
        let mut d = SimulatorDisplay::<Rgb565>::new(Size::new(self.w, self.h));
        for (k, c) in self.px.iter().enumerate() {
            let p = Point::new((k as u32 % self.w) as i32, (k as u32 / self.w) as i32);
            Pixel(p, *c).draw(&mut d).unwrap();
        }
        let img = d.to_rgb_output_image(
            &OutputSettingsBuilder::new()
                .scale(1)
                .pixel_spacing(0)
                .build(),
        );
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).unwrap();
        }
        img.save_png(path).unwrap();
    }
}

impl OriginDimensions for Frame {
    fn size(&self) -> Size {
        Size::new(self.w, self.h)
    }
}

impl DrawTarget for Frame {
    type Color = Rgb565;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            self.put(p, c);
        }
        Ok(())
    }
    fn fill_solid(&mut self, area: &Rectangle, c: Rgb565) -> Result<(), Self::Error> {
        for p in area.points() {
            self.put(p, c);
        }
        Ok(())
    }
}

/// Snaps a coordinate to 1/256 pixel, round to nearest, ties to even (the shared rule).
pub fn snap(v: f32) -> i64 {
    (v as f64 * 256.0).round_ties_even() as i64
}

/// A covered pixel of the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefPixel {
    /// Column.
    pub x: i32,
    /// Row.
    pub y: i32,
    /// `t = W_far / W` at the pixel centre.
    pub t: f64,
    /// Whether `W_near <= W <= W_far`.
    pub in_range: bool,
    /// `round(65535 / t)`, the W16 code (meaningful when in range).
    pub code: u16,
    /// A bound, in W16 codes, on what rounding the vertices to the core's depth grid can change the code's exact
    /// value `65535 / t` by at this pixel: the planes of `t` through the grid positions `q_k` and through the given
    /// `v_k` differ by an affine function worth `grad t . (q_k - v_k)` at `q_k`, so by at most
    /// `sum |lambda_k| |grad t . (q_k - v_k)|` at the pixel (`lambda_k` its barycentrics in the `q` triangle); times
    /// `65535 / (t (t - delta))`. Zero when the vertices lie on the grid.
    pub grid_lsb: f64,
    /// The same bound in units of `t` (what it is before the conversion to codes), for other formats.
    pub grid_t: f64,
}

/// Barycentrics of `(px, py)` in the triangle `g` (f64, any orientation), unnormalised (the three edge functions)
/// with their sum, the doubled signed area; `None` for a degenerate triangle. (Dividing once keeps a constant plane
/// exact: the edge functions of small grid positions are exact in f64.)
fn barycentrics(g: &[(f64, f64); 3], px: f64, py: f64) -> Option<([f64; 3], f64)> {
    let e = |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0);
    let area = (g[1].0 - g[0].0) * (g[2].1 - g[0].1) - (g[1].1 - g[0].1) * (g[2].0 - g[0].0);
    if area == 0.0 {
        return None;
    }
    Some(([e(g[1], g[2]), e(g[2], g[0]), e(g[0], g[1])], area))
}

/// The gradient of the plane through `(g_k, t_k)`.
fn gradient(g: &[(f64, f64); 3], t: [f64; 3]) -> Option<(f64, f64)> {
    let area = (g[1].0 - g[0].0) * (g[2].1 - g[0].1) - (g[1].1 - g[0].1) * (g[2].0 - g[0].0);
    if area == 0.0 {
        return None;
    }
    let tx =
        -((g[2].1 - g[1].1) * t[0] + (g[0].1 - g[2].1) * t[1] + (g[1].1 - g[0].1) * t[2]) / area;
    let ty =
        ((g[2].0 - g[1].0) * t[0] + (g[0].0 - g[2].0) * t[1] + (g[1].0 - g[0].0) * t[2]) / area;
    Some((tx, ty))
}

/// The reference's pixels of one triangle inside columns `[0, width)` and rows `rows`, in row-major order.
/// `None` when the triangle has zero snapped area.
pub fn reference_tri(
    v: &[(f32, f32, f32); 3],
    near: f32,
    far: f32,
    width: i32,
    rows: std::ops::Range<i32>,
) -> Option<Vec<RefPixel>> {
    // v: (x, y, rhw)
    let mut p: Vec<(i64, i64, f64)> = v
        .iter()
        .map(|&(x, y, rhw)| (snap(x), snap(y), rhw as f64 * far as f64))
        .collect();
    let e = |a: (i64, i64, f64), b: (i64, i64, f64), px: i64, py: i64| {
        (b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0)
    };
    let area = e(p[0], p[1], p[2].0, p[2].1);
    if area == 0 {
        return None;
    }
    // Depth: the given positions (orientation does not matter to a plane), and the depth grid's positions.
    let given = v.map(|(x, y, _)| (x as f64, y as f64));
    let tk = v.map(|(_, _, rhw)| rhw as f64 * far as f64);
    // The core's depth grid for this box (the shared rule: `wraster::depth_grid_bits` of the snapped box's larger
    // side in whole pixels); rounding relative to the box's first pixel is rounding the coordinate itself.
    let px_of = |c: f32| snap(c) >> 8;
    let extent = |f: fn(&(f32, f32, f32)) -> f32| {
        let c: Vec<i64> = v.iter().map(|q| px_of(f(q))).collect();
        c.iter().max().unwrap() - c.iter().min().unwrap()
    };
    let bits = wraster::depth_grid_bits(extent(|q| q.0).max(extent(|q| q.1)) as i32);
    let scale = (1u64 << bits) as f64;
    let grid_of = |c: f64| (c * scale).round_ties_even() / scale;
    let on_grid = given.map(|(x, y)| (grid_of(x), grid_of(y)));
    let grad = gradient(&given, tk);
    let shift = match grad {
        Some((tx, ty)) => {
            let d = |k: usize| tx * (on_grid[k].0 - given[k].0) + ty * (on_grid[k].1 - given[k].1);
            [d(0), d(1), d(2)]
        }
        None => [0.0; 3],
    };
    if area < 0 {
        p.swap(1, 2);
    }
    let area = area.abs() as f64;
    // top-left: a left edge runs upwards (a.y > b.y); a top edge is horizontal and runs rightwards.
    let tl = |a: (i64, i64, f64), b: (i64, i64, f64)| a.1 > b.1 || (a.1 == b.1 && b.0 > a.0);
    let edges = [(p[1], p[2], 0usize), (p[2], p[0], 1), (p[0], p[1], 2)];
    let x0 = (p.iter().map(|q| q.0).min().unwrap() >> 8).max(0);
    let x1 = ((p.iter().map(|q| q.0).max().unwrap() >> 8) + 1).min(width as i64 - 1);
    let y0 = (p.iter().map(|q| q.1).min().unwrap() >> 8).max(rows.start as i64);
    let y1 = ((p.iter().map(|q| q.1).max().unwrap() >> 8) + 1).min(rows.end as i64 - 1);
    let mut out = Vec::new();
    for j in y0..=y1 {
        for i in x0..=x1 {
            let (px, py) = (256 * i + 128, 256 * j + 128);
            let mut w = [0f64; 3];
            let mut inside = true;
            for &(a, b, k) in &edges {
                let ev = e(a, b, px, py);
                if ev < 0 || (ev == 0 && !tl(a, b)) {
                    inside = false;
                    break;
                }
                w[k] = ev as f64;
            }
            if !inside {
                continue;
            }
            let (cx, cy) = (i as f64 + 0.5, j as f64 + 0.5);
            // The true surface through the given vertices; a degenerate given triangle (whose snapped one is not) has
            // none, and takes the snapped vertices' plane, as the core does.
            let (t, grid) = match barycentrics(&given, cx, cy) {
                Some((e, a)) if grad.is_some() => {
                    let (eq, aq) = barycentrics(&on_grid, cx, cy).unwrap_or((e, a));
                    let g: f64 = (0..3).map(|k| (eq[k] / aq).abs() * shift[k].abs()).sum();
                    ((e[0] * tk[0] + e[1] * tk[1] + e[2] * tk[2]) / a, g)
                }
                _ => ((w[0] * p[0].2 + w[1] * p[1].2 + w[2] * p[2].2) / area, 0.0),
            };
            let in_range = t >= 1.0 && t * near as f64 <= far as f64;
            let code = (65535.0 / t).round().clamp(0.0, 65535.0) as u16;
            // 65535 |1/t - 1/(t + delta)| <= 65535 delta / (t (t - delta)), with a relative 1e-9 for f64 rounding.
            let grid_lsb = if grid == 0.0 {
                0.0
            } else {
                65535.0 * grid * (1.0 + 1e-9) / (t * (t - grid)).abs() + 1e-12
            };
            out.push(RefPixel {
                x: i as i32,
                y: j as i32,
                t,
                in_range,
                code,
                grid_lsb,
                grid_t: if grid == 0.0 {
                    0.0
                } else {
                    grid * (1.0 + 1e-9) + 1e-300
                },
            });
        }
    }
    Some(out)
}

/// The reference's coverage of one triangle drawn alone with writes on and no depth rejection: 1 where a pixel is
/// covered and in range in a `w x h` frame, else 0 (the shape of [`Frame::writes`]), and how many pixels that is.
pub fn reference_writes(
    v: &[Vertex<Rgb565>; 3],
    near: f32,
    far: f32,
    w: u32,
    h: u32,
) -> (Vec<u32>, usize) {
    let px = reference_tri(
        &v.map(|q| (q.x, q.y, q.rhw)),
        near,
        far,
        w as i32,
        0..h as i32,
    )
    .unwrap_or_default();
    let mut writes = vec![0u32; (w * h) as usize];
    for p in px.iter().filter(|p| p.in_range) {
        writes[(p.y as u32 * w + p.x as u32) as usize] = 1;
    }
    (writes, px.len())
}

/// The reference's final frame for a list of triangles with a `Less` test on exact W: colour, the exact `1/t` of the
/// nearest surface, and its W16 code (65535 and 1.0 where nothing was drawn).
pub struct RefFrame {
    /// Colours.
    pub px: Vec<Rgb565>,
    /// `W / W_far` of the visible surface.
    pub depth: Vec<f64>,
    /// The W16 code of the visible surface.
    pub code: Vec<u16>,
    /// The exact depth of the second-nearest surface drawn at each pixel (`f64::INFINITY` if none): where it is within
    /// 2 LSB of the nearest, either may win in a W16 buffer.
    pub runner_up: Vec<f64>,
    /// Whether any triangle covers the pixel in range.
    pub covered: Vec<bool>,
}

/// Renders `tris` with the reference.
pub fn reference_frame(
    tris: &[[Vertex<Rgb565>; 3]],
    near: f32,
    far: f32,
    w: u32,
    h: u32,
) -> RefFrame {
    let n = (w * h) as usize;
    let mut f = RefFrame {
        px: vec![Rgb565::BLACK; n],
        depth: vec![1.0; n],
        code: vec![65535; n],
        runner_up: vec![f64::INFINITY; n],
        covered: vec![false; n],
    };
    let mut best = vec![f64::INFINITY; n];
    for tri in tris {
        let v = tri.map(|q| (q.x, q.y, q.rhw));
        for p in reference_tri(&v, near, far, w as i32, 0..h as i32).unwrap_or_default() {
            if !p.in_range {
                continue;
            }
            let k = (p.y as u32 * w + p.x as u32) as usize;
            f.covered[k] = true;
            let d = 1.0 / p.t;
            if d < best[k] {
                f.runner_up[k] = best[k];
                best[k] = d;
                f.px[k] = tri[0].color;
                f.depth[k] = d;
                f.code[k] = p.code;
            } else if d < f.runner_up[k] {
                f.runner_up[k] = d;
            }
        }
    }
    f
}

/// Renders `tris` into a `w x h` frame with `bands` depth bands of `band_h` rows (the last may be shorter), each
/// cleared before its pass; returns the frame, the whole-frame depth and the summed stats.
pub fn render<R: SpanRecip>(
    tris: &[[Vertex<Rgb565>; 3]],
    state: RenderState,
    w: u16,
    h: u16,
    band_h: u16,
) -> Result<(Frame, Vec<u16>, Stats), Error> {
    let mut frame = Frame::new(w as u32, h as u32);
    let mut depth = vec![0u16; w as usize * h as usize];
    let mut r = Rasterizer::<R>::new(state);
    let stats = in_bands(&mut depth, w, h, band_h, |buf| {
        let mut stats = Stats::default();
        for t in tris {
            stats += r.draw(&mut frame, &mut *buf, t)?;
        }
        Ok(stats)
    })?;
    Ok((frame, depth, stats))
}

/// Splits `depth` (`w x h`) into bands of `band_h` rows (the last may be shorter), clears each and draws it with
/// `draw`; the summed stats.
pub fn in_bands(
    depth: &mut [u16],
    w: u16,
    h: u16,
    band_h: u16,
    draw: impl FnMut(&mut DepthBuffer<'_>) -> Result<Stats, Error>,
) -> Result<Stats, Error> {
    in_bands_bounded(depth, w, h, band_h, &mut [], draw)
}

/// [`in_bands`], each band's buffer keeping a coarse bound in the front of `bound` (`wraster::bound_len(w, band_h)`
/// long; empty: none).
pub fn in_bands_bounded(
    depth: &mut [u16],
    w: u16,
    h: u16,
    band_h: u16,
    bound: &mut [u16],
    mut draw: impl FnMut(&mut DepthBuffer<'_>) -> Result<Stats, Error>,
) -> Result<Stats, Error> {
    let mut stats = Stats::default();
    let mut y0 = 0u16;
    while y0 < h {
        let bh = band_h.min(h - y0);
        let slice = &mut depth[y0 as usize * w as usize..(y0 + bh) as usize * w as usize];
        let mut buf = DepthBuffer::band(slice, w, y0 as i32, bh)?;
        if !bound.is_empty() {
            let n = wraster::bound_len(w as usize, bh as usize);
            let len = bound.len();
            let seg = bound.get_mut(..n).ok_or(Error::BufferSize {
                expected: n,
                actual: len,
            })?;
            buf = buf.with_bound(seg)?;
        }
        buf.clear();
        stats += draw(&mut buf)?;
        y0 += bh;
    }
    Ok(stats)
}

/// A random coordinate: mostly anywhere in and around the frame, sometimes on a pixel centre, sometimes on a
/// sub-pixel tie (half-way between two 1/256 steps, which rounds to even).
pub fn coord(rng: &mut Rng, extent: f64) -> f32 {
    let v = rng.f(-0.3 * extent, 1.3 * extent);
    match rng.bits() % 4 {
        0 => (v.floor() + 0.5) as f32,
        1 => ((v * 256.0).floor() / 256.0 + 1.0 / 512.0) as f32,
        _ => v as f32,
    }
}

/// A random triangle around a `W x H` frame (the tests' 96 x 64): sizes from sub-pixel slivers to much larger than
/// the frame, both windings, depths log-uniform in `[wmin, wmax)`.
pub fn random_tri(rng: &mut Rng, wmin: f64, wmax: f64) -> [Vertex<Rgb565>; 3] {
    let c = Rgb565::new(
        (rng.bits() % 32) as u8,
        (rng.bits() % 64) as u8,
        (rng.bits() % 32) as u8,
    );
    let kind = rng.bits() % 4;
    let (x, y) = (coord(rng, 96.0), coord(rng, 64.0));
    let spread = match kind {
        0 => 0.5,
        1 => 4.0,
        2 => 30.0,
        _ => 200.0,
    };
    let mut v = [Vertex::new(x, y, rng.log(wmin, wmax) as f32, c); 3];
    for q in v.iter_mut().skip(1) {
        q.x = x + rng.f(-spread, spread) as f32;
        q.y = y + rng.f(-spread, spread) as f32;
        q.rhw = 1.0 / rng.log(wmin, wmax) as f32;
    }
    if kind == 0 && rng.bits().is_multiple_of(2) {
        // a sliver: the third vertex nearly on the line of the first two
        let s = rng.f(0.0, 1.0) as f32;
        v[2].x = v[0].x + s * (v[1].x - v[0].x) + 1.0 / 512.0;
        v[2].y = v[0].y + s * (v[1].y - v[0].y);
    }
    v
}

/// `words`' codes as the little-endian bytes of their format's storage, `F::BYTES` each.
pub fn le_bytes<F: DepthFormat>(words: &[F::Word]) -> Vec<u8> {
    words
        .iter()
        .flat_map(|w| w.code().to_le_bytes()[..F::BYTES].to_vec())
        .collect()
}

/// Renders `tris` into a `w x h` frame and a whole-frame buffer of format `F` (cleared to the far plane) with
/// strategy `R`, through the span loop generic over the format (W16's too: `Rasterizer::draw_generic`); returns the
/// frame, every pixel's code and the summed stats.
pub fn render_format<F: Codec, R: WSpan>(
    tris: &[[Vertex<Rgb565>; 3]],
    state: RenderState,
    w: u16,
    h: u16,
) -> Result<(Frame, Vec<u32>, Stats), Error> {
    let mut frame = Frame::new(w as u32, h as u32);
    let mut words = vec![F::Word::default(); w as usize * h as usize];
    let mut buf = DepthBuffer::<F>::new_format(&mut words, w, h)?;
    buf.clear_for(&state.range);
    let mut r = Rasterizer::<R>::new(state);
    let mut stats = Stats::default();
    for t in tris {
        // The span loop generic over the format, W16's too (`draw` gives W16 to the tiers' own loops).
        stats += r.draw_generic(&mut frame, &mut buf, t)?;
    }
    let codes = words.iter().map(|w| w.code()).collect();
    Ok((frame, codes, stats))
}

/// The exact value format `F` stores for eye depth `d` (what [`DepthFormat::fraction`] decodes a code to): `d / f`
/// for W formats, D3D Z, reversed Z, or the linear-Z trick's `(d - n) / (f - n)`. Computed here, in f64, from the
/// formulas, not from the format's code.
pub fn exact_fraction<F: Codec>(d: f64, n: f64, f: f64) -> f64 {
    match (F::INPUT, F::REVERSED) {
        (Input::W, _) => d / f,
        // D3D's Z, f/(f-n) (1 - n/d), and reversed Z, n (f/d - 1) / (f - n): written out here rather than taken from
        // the crate's `format::z_of` / `rz_of`, so the test does not check the crate against itself.
        (Input::Z, false) => f / (f - n) * (1.0 - n / d),
        (Input::Z, true) => n * (f / d - 1.0) / (f - n),
        (Input::LinearZ, _) => (d - n) / (f - n),
    }
}

/// Half the larger distance from `code`'s value to its neighbours' (the rounding a correct encoder can add).
pub fn half_step<F: DepthFormat>(code: u32, n: f64, f: f64) -> f64 {
    let v = F::fraction(code, n, f);
    let up = if code < F::MAX_CODE {
        (F::fraction(code + 1, n, f) - v).abs()
    } else {
        0.0
    };
    let down = if code > 0 {
        (v - F::fraction(code - 1, n, f)).abs()
    } else {
        0.0
    };
    up.max(down) / 2.0
}

/// Whether `cmd --version` runs.
pub fn have(cmd: &str) -> bool {
    std::process::Command::new(cmd)
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// Builds and runs firmware board `board` (a directory of boards/) under QEMU with cargo `features`, from the
/// board's directory so its target and runner (.cargo/config.toml) apply; its stdout, or why it failed.
pub fn run_board(board: &str, features: &[&str]) -> Result<String, String> {
    run_board_env(board, features, &[])
}

/// [`run_board`] with environment variables for its build (`PLAN=...`, say).
pub fn run_board_env(
    board: &str,
    features: &[&str],
    env: &[(&str, &str)],
) -> Result<String, String> {
    let boards = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../boards");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = std::process::Command::new(&cargo);
    cmd.args(["run", "--release", "--quiet"]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    cmd.envs(env.iter().copied());
    let out = cmd
        .current_dir(boards.join(board))
        .env_remove("CARGO_TARGET_DIR")
        .output()
        .map_err(|e| format!("cargo: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if out.status.success() {
        Ok(stdout)
    } else {
        Err(format!(
            "{board} failed: {}\n{stdout}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ))
    }
}

/// The value of `key=` in a `bench ...` line.
pub fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(' ')
        .find_map(|kv| kv.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
}

/// A small xorshift64 generator for reproducible tests.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn bits(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in `[lo, hi)`.
    pub fn f(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.bits() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Log-uniform in `[lo, hi)`.
    pub fn log(&mut self, lo: f64, hi: f64) -> f64 {
        (self.f(lo.ln(), hi.ln())).exp()
    }
}

/// FNV-1a 64 of a frame, continuing `hash`, as the boards compute it (boards/common): for each row, its RGB565
/// colours then its W16 depths, u16 little-endian.
pub fn hash_frame(hash: &mut u64, frame: &Frame, depth: &[u16]) {
    use embedded_graphics::pixelcolor::IntoStorage;
    let mut words = |ws: &mut dyn Iterator<Item = u16>| {
        for w in ws {
            for b in w.to_le_bytes() {
                *hash ^= b as u64;
                *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    };
    let w = frame.w as usize;
    for row in 0..frame.h as usize {
        words(
            &mut frame.px[row * w..(row + 1) * w]
                .iter()
                .map(|c| c.into_storage()),
        );
        words(&mut depth[row * w..(row + 1) * w].iter().copied());
    }
}

/// W4's mesh (`wraster::scenes::torus`), camera and render state, handed to `f` (the tests' way to the torus).
pub fn with_torus<T>(
    f: impl FnOnce(&wraster::mesh::Mesh<'_, Rgb565>, &wraster::projection::Camera, RenderState) -> T,
) -> T {
    use wraster::mesh::{Colors, Mesh};
    use wraster::scenes::torus;
    let (pos, idx, col) = (torus::positions(), torus::indices(), torus::colors());
    let mesh = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::PerFace(&col),
    };
    let cam = torus::camera().expect("W4's camera");
    let state = cam.render_state().expect("W4's render state");
    f(&mesh, &cam, state)
}

/// W4 frame `k` (`wraster::scenes::torus`) through the mesh path, transformed once and drawn in bands of `band_h`
/// rows (the last may be shorter), each band's depth cleared first: the frame, its depth, the summed stats.
pub fn render_torus<R: SpanRecip>(
    k: usize,
    band_h: u16,
) -> Result<(Frame, Vec<u16>, Stats), Error> {
    render_torus_with::<R>(k, band_h, wraster::scenes::torus::camera()?.render_state()?)
}

/// [`render_torus`] with render state `state` (a plan's depth range, say).
pub fn render_torus_with<R: SpanRecip>(
    k: usize,
    band_h: u16,
    state: RenderState,
) -> Result<(Frame, Vec<u16>, Stats), Error> {
    use wraster::clip::Viewport;
    use wraster::mesh::{Colors, Mesh, Projected};
    use wraster::scenes::{torus, HEIGHT, WIDTH};
    let (pos, idx, col) = (torus::positions(), torus::indices(), torus::colors());
    let mesh = Mesh {
        positions: &pos,
        indices: &idx,
        colors: Colors::PerFace(&col),
    };
    let cam = torus::camera()?;
    let (w, h) = (WIDTH, HEIGHT);
    let mut frame = Frame::new(w as u32, h as u32);
    let mut depth = vec![0u16; w as usize * h as usize];
    let mut r = Rasterizer::<R>::new(state);
    let mut scratch = vec![Projected::default(); pos.len()];
    let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
    let mf = r.transform_mesh(
        &mesh,
        &cam.model_matrix(&torus::model(k)),
        &vp,
        &mut scratch,
    )?;
    let stats = in_bands(&mut depth, w, h, band_h, |buf| {
        r.draw_mesh_frame(&mut frame, buf, &mf)
    })?;
    Ok((frame, depth, stats))
}

/// The camera the mesh tests view [`cube`] with: from `(3, 2, 5)` towards the origin, a field of view of 1 radian,
/// square, depth planes 0.5 and 50.
pub fn cube_camera() -> wraster::projection::Camera {
    wraster::projection::Camera::look_at(
        [3.0, 2.0, 5.0],
        [0.0; 3],
        [0.0, 1.0, 0.0],
        1.0,
        1.0,
        0.5,
        50.0,
    )
    .expect("a valid camera")
}

/// A cube from -1 to 1, twelve triangles, every face wound counter-clockwise seen from outside: a closed convex mesh.
pub fn cube() -> ([[f32; 3]; 8], [[u16; 3]; 12]) {
    (
        [
            [-1.0, -1.0, -1.0],
            [1.0, -1.0, -1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
        ],
        [
            [0, 3, 2],
            [0, 2, 1],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [2, 3, 7],
            [2, 7, 6],
            [1, 2, 6],
            [1, 6, 5],
            [0, 4, 7],
            [0, 7, 3],
        ],
    )
}

/// Every depth comparison.
pub const COMPARES: [wraster::Compare; 8] = [
    wraster::Compare::Never,
    wraster::Compare::Less,
    wraster::Compare::Equal,
    wraster::Compare::LessEqual,
    wraster::Compare::Greater,
    wraster::Compare::NotEqual,
    wraster::Compare::GreaterEqual,
    wraster::Compare::Always,
];

/// Every standard scene and W4 rendered whole-frame with the strategy `R`, each frame hashed as the boards hash it
/// ([`hash_frame`]; W4's 8 frames in one hash): `(scene, R::NAME) -> (hash, written, fragments)` into `out`.
pub fn scene_hashes<R: SpanRecip>(
    out: &mut std::collections::HashMap<(String, String), (u64, u32, u32)>,
) {
    use wraster::scenes::{torus, Scene, HEIGHT, WIDTH};
    for scene in Scene::ALL {
        let (near, far) = scene.depth_range();
        let tris: Vec<_> = scene.tris().collect();
        let (frame, depth, stats) = render::<R>(
            &tris,
            RenderState::new(near, far).unwrap(),
            WIDTH,
            HEIGHT,
            HEIGHT,
        )
        .unwrap();
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        hash_frame(&mut h, &frame, &depth);
        out.insert(
            (scene.name().into(), R::NAME.into()),
            (h, stats.written, stats.fragments),
        );
    }
    // W4: the 8 torus frames through the mesh path, one hash over all of them in order.
    let (mut h, mut written, mut fragments) = (0xcbf2_9ce4_8422_2325u64, 0, 0);
    for k in 0..torus::FRAMES {
        let (frame, depth, stats) = render_torus::<R>(k, HEIGHT).unwrap();
        hash_frame(&mut h, &frame, &depth);
        written += stats.written;
        fragments += stats.fragments;
    }
    out.insert(("torus".into(), R::NAME.into()), (h, written, fragments));
}
