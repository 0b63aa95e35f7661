//! The scene planner: what a given scene needs, measured against the f64 reference, and the cheapest build that
//! draws it with at most a given number of visibility errors (`cargo run --release -p host-tests --bin plan`).
//!
//! A **visibility error** is a pixel whose visible surface differs from the reference's: the reference covers it and
//! the candidate shows nothing, or shows a triangle the reference does not cover there, or shows one whose exact
//! depth at that pixel is farther than the nearest surface's (two surfaces at exactly the same depth are a tie:
//! either is right). Triangles are told apart by drawing each with its own colour (its index plus one as a raw
//! RGB565 value). The reference is [`crate::reference_tri`]: the shared coverage rules on the snapped vertices, depth
//! from the vertices as given, in f64, with the scene's own depth range.
//!
//! The candidates, cheapest first:
//! - **no depth buffer**: culling and drawing order alone (`draw` with `NoDepth`);
//! - the 16-bit formats (2 bytes a pixel): W16 through the lean path (`Rasterizer::draw`, the fast tier), then
//!   LZ16, Z16 and W16F through the generic span loop; then the 24-bit (W24F, W24FScaled, Z24) and 32-bit (W32F, Z32F,
//!   RZ32F) ones;
//! - for each format the W strategies in the order of their measured cost on the core (the boards' `bench` lines in
//!   the README: on the M4 `fast-div`, `fast`, `exact`, `prev-pixel`; on RV32 the same with `fast-div-int` (meshes
//!   transformed in integers: no FPU) for `fast-div`; on the M0, whose division is a library call, `fast` first);
//! - for each, the depth range tightened to the W the scene really draws (the smallest and largest reference W over
//!   its covered pixels and frames, widened by `2^-8` of itself so that no pixel the scene draws falls outside),
//!   then the scene's own.
//!
//! The first candidate within the budget is the plan: every candidate is measured by rendering, so a plan's stated
//! error count is what its build draws. RAM is not run time (W3 without a depth buffer costs twice its W16 build on
//! the boards: the colour-only draw has no small-triangle path), so `--measure` ([`candidates`],
//! [`measure_on_board`], [`rank_measured`]) runs the first candidate of each of the first three formats within the
//! budget on the core's board and takes the fewest instructions per frame. The band height is the most rows whose depth buffer fits the RAM budget.
use std::fmt::Write as _;

use embedded_graphics::pixelcolor::raw::RawU16;
use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::*;
use wraster::format::{
    DepthFormat, W24FScaled, LZ16, RZ32F, W16, W16F, W24F, W32F, Z16, Z24, Z32F,
};
use wraster::recip::{Exact, Fast, FastDiv, FastDivInt, PrevPixel, SpanRecip};
use wraster::{Codec, Cull, DepthBuffer, Error, NoDepth, Rasterizer, RenderState, Vertex};

use crate::{in_bands, reference_tri, snap, Frame};

/// A core the plan is for: it orders the strategies by their cost there and sets the default depth RAM.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Core {
    /// Cortex-M0/M0+ (no divide instruction).
    M0,
    /// Cortex-M4F.
    M4,
    /// RV32IMAC.
    Rv32,
}

impl Core {
    /// From `m0`, `m4` or `rv32`.
    pub fn parse(s: &str) -> Option<Core> {
        match s {
            "m0" => Some(Core::M0),
            "m4" => Some(Core::M4),
            "rv32" => Some(Core::Rv32),
            _ => None,
        }
    }
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Core::M0 => "m0",
            Core::M4 => "m4",
            Core::Rv32 => "rv32",
        }
    }
    /// The W strategies, cheapest first on this core (the README's measured `bench` figures: every scene and W4).
    /// RV32 (no FPU) takes `fast-div-int` where the M4 takes `fast-div`: the same draws, meshes transformed in
    /// integers (27% fewer instructions on its W4 frame; the standard scenes have no transform, and the same frames).
    pub fn strategies(self) -> &'static [&'static str] {
        match self {
            Core::M0 => &["fast", "fast-div", "exact", "prev-pixel"],
            Core::M4 => &["fast-div", "fast", "exact", "prev-pixel"],
            Core::Rv32 => &["fast-div-int", "fast", "exact", "prev-pixel"],
        }
    }
    /// The depth RAM a plan may take for scene `scene`: the M0 board's 16 KiB holds 8-row W16 bands (5,120 bytes)
    /// beside an RGB565 colour band, 4-row ones (2,560) for the torus, whose 512 transformed vertices take 6 KiB (a
    /// plan's firmware keeps RGB565 colour; the default builds keep half a byte a pixel beside 15-row bands, 6 for
    /// the torus); the M4 and RV32 boards hold a whole W16 frame (153,600 bytes).
    pub fn default_depth_ram(self, scene: &str) -> usize {
        match self {
            Core::M0 if scene == "torus" => 320 * 4 * 2,
            Core::M0 => 320 * 8 * 2,
            Core::M4 | Core::Rv32 => 320 * 240 * 2,
        }
    }
}

/// The depth formats a plan may choose, cheapest first ("none": no depth buffer).
pub const FORMATS: [&str; 11] = [
    "none",
    "W16",
    "LZ16",
    "Z16",
    "W16F",
    "W24F",
    "W24FScaled",
    "Z24",
    "W32F",
    "Z32F",
    "RZ32F",
];

/// Bytes a pixel of format `name` stores.
pub fn format_bytes(name: &str) -> usize {
    match name {
        "none" => 0,
        "W16" => W16::BYTES,
        "LZ16" => LZ16::BYTES,
        "Z16" => Z16::BYTES,
        "W16F" => W16F::BYTES,
        "W24F" => W24F::BYTES,
        "W24FScaled" => W24FScaled::BYTES,
        "Z24" => Z24::BYTES,
        "W32F" => W32F::BYTES,
        "Z32F" => Z32F::BYTES,
        "RZ32F" => RZ32F::BYTES,
        _ => panic!("unknown format {name}"),
    }
}

/// A scene to plan: its frames (each a list of screen-space triangles in drawing order), the render state it is
/// drawn with (depth range, compare, culling) and the frame size.
pub struct Workload {
    /// Its name (`big`, `overdraw`, `small`, `terrain`, `torus`).
    pub name: String,
    /// The triangles of each frame, in drawing order.
    pub frames: Vec<Vec<[Vertex<Rgb565>; 3]>>,
    /// The scene's own render state.
    pub state: RenderState,
    /// Frame width.
    pub w: u16,
    /// Frame height.
    pub h: u16,
}

/// The workload of a standard scene or of W4 (`torus`: its 8 frames through the core's f32 transform, as the
/// boards draw them; the screen-space vertices are the same for every candidate, so its visibility errors count
/// depth decisions only).
pub fn workload(name: &str) -> Result<Workload, String> {
    use wraster::scenes::{torus, Scene, HEIGHT, WIDTH};
    if let Some(scene) = Scene::ALL.into_iter().find(|s| s.name() == name) {
        let (near, far) = scene.depth_range();
        return Ok(Workload {
            name: name.into(),
            frames: vec![scene.tris().collect()],
            state: RenderState::new(near, far).map_err(|e| format!("{e:?}"))?,
            w: WIDTH,
            h: HEIGHT,
        });
    }
    if let Some(path) = name.strip_prefix("obj:") {
        return obj_workload(std::path::Path::new(path), OBJ_FRAMES);
    }
    if name != "torus" {
        return Err(format!(
            "unknown scene {name:?} (big, overdraw, small, terrain, torus, obj:<file.obj>)"
        ));
    }
    let cam = torus::camera().map_err(|e| format!("{e:?}"))?;
    let (pos, idx) = (torus::positions(), torus::indices());
    let state = cam.render_state().map_err(|e| format!("{e:?}"))?;
    let frames = (0..torus::FRAMES)
        .map(|k| {
            screen_tris(
                &pos,
                &idx,
                &cam.model_matrix(&torus::model(k)),
                state,
                WIDTH,
                HEIGHT,
            )
        })
        .collect::<Result<_, _>>()?;
    Ok(Workload {
        name: name.into(),
        frames,
        state,
        w: WIDTH,
        h: HEIGHT,
    })
}

/// Frames of an OBJ scene's camera path.
pub const OBJ_FRAMES: usize = 8;

/// An OBJ mesh (loaded with `tobj`, every model of the file as one mesh) seen along a camera path: `frames` views
/// from an eye circling the mesh's bounding sphere (`wraster::mesh::Sphere`: centre `c`, radius `r`) at distance
/// `3r`, 0.4 rad above the plane `y = c_y`, looking at `c` with `y` up; 60 degrees vertical field of view, aspect
/// 4:3, `W_near = r` and `W_far = 4.5 r` (every vertex lies between `2r` and `4r` from the eye, and the sphere's
/// 19.5 degrees fit the 30-degree half field: no triangle needs clipping). Back faces culled: the mesh must be wound
/// counter-clockwise seen from outside. Its name is `obj-<file stem>`.
pub fn obj_workload(path: &std::path::Path, frames: usize) -> Result<Workload, String> {
    use wraster::projection::Camera;
    use wraster::scenes::{HEIGHT, WIDTH};
    let (models, _) = tobj::load_obj(path, &tobj::GPU_LOAD_OPTIONS)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let (mut pos, mut idx) = (Vec::<[f32; 3]>::new(), Vec::<[u16; 3]>::new());
    for model in &models {
        let base = pos.len();
        pos.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]]),
        );
        for t in model.mesh.indices.chunks_exact(3) {
            let k = |i: u32| {
                u16::try_from(base + i as usize)
                    .map_err(|_| "more than 65,536 vertices".to_string())
            };
            idx.push([k(t[0])?, k(t[1])?, k(t[2])?]);
        }
    }
    let sphere = wraster::mesh::Sphere::enclosing(&pos).map_err(|e| format!("{e:?}"))?;
    let (c, r) = (sphere.center, sphere.radius);
    if !(r > 0.0 && r.is_finite()) {
        return Err(format!("{}: an empty or degenerate mesh", path.display()));
    }
    let (d, e) = (3.0 * r, 0.4f32);
    let mut out = vec![];
    let mut state = None;
    for k in 0..frames {
        let a = 2.0 * core::f32::consts::PI * k as f32 / frames as f32;
        let eye = [
            c[0] + d * e.cos() * a.cos(),
            c[1] + d * e.sin(),
            c[2] + d * e.cos() * a.sin(),
        ];
        let cam = Camera::look_at(
            eye,
            c,
            [0.0, 1.0, 0.0],
            core::f32::consts::FRAC_PI_3,
            4.0 / 3.0,
            r,
            4.5 * r,
        )
        .map_err(|e| format!("{e:?}"))?;
        let st = cam.render_state().map_err(|e| format!("{e:?}"))?;
        out.push(screen_tris(&pos, &idx, &cam.matrix(), st, WIDTH, HEIGHT)?);
        state = Some(st);
    }
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh");
    Ok(Workload {
        name: format!("obj-{stem}"),
        frames: out,
        state: state.ok_or("no frames")?,
        w: WIDTH,
        h: HEIGHT,
    })
}

/// A mesh's triangles in screen space through the core's own transform (`transform_mesh`), every face, in index
/// order (culling is the render state's, in the draw). A triangle with a vertex outside the view volume would need
/// the clipper, which a plan does not model yet: an error.
pub fn screen_tris(
    pos: &[[f32; 3]],
    idx: &[[u16; 3]],
    m: &wraster::projection::Mat4,
    state: RenderState,
    w: u16,
    h: u16,
) -> Result<Vec<[Vertex<Rgb565>; 3]>, String> {
    use wraster::clip::Viewport;
    use wraster::mesh::{Colors, Mesh, Projected};
    let mesh = Mesh {
        positions: pos,
        indices: idx,
        colors: Colors::Uniform(Rgb565::WHITE),
    };
    let mut scratch = vec![Projected::default(); pos.len()];
    let r = Rasterizer::<Fast>::new(state);
    let vp = Viewport::new(0.0, 0.0, w as f32, h as f32);
    let mf = r
        .transform_mesh(&mesh, m, &vp, &mut scratch)
        .map_err(|e| format!("{e:?}"))?;
    let v = mf.vertices();
    idx.iter()
        .map(|t| {
            let q = t.map(|i| v[i as usize]);
            if q.iter().any(|p| p.rhw.is_nan() || p.rhw <= 0.0) {
                return Err(
                    "a triangle crosses the view volume: planning clipped meshes is not built yet"
                        .into(),
                );
            }
            Ok(q.map(|p| Vertex {
                x: p.x,
                y: p.y,
                z: 0.0,
                rhw: p.rhw,
                color: Rgb565::WHITE,
            }))
        })
        .collect()
}

/// Triangle `k`'s colour in an id frame.
fn id_color(k: usize) -> Rgb565 {
    RawU16::new(k as u16 + 1).into()
}

/// What the reference says of every pixel of one frame: the covering triangles (id, exact `W / W_far` of the
/// scene's range) in range.
pub struct Reference {
    per_px: Vec<Vec<(u32, f64)>>,
}

impl Reference {
    /// The reference of `tris` drawn with `state`'s depth range and culling in a `w x h` frame.
    pub fn new(tris: &[[Vertex<Rgb565>; 3]], state: &RenderState, w: u16, h: u16) -> Reference {
        let (near, far) = (state.range.near(), state.range.far());
        let mut per_px = vec![Vec::new(); w as usize * h as usize];
        for (k, t) in tris.iter().enumerate() {
            // The shared culling rule, on the snapped vertices: the doubled signed area (y down).
            let p = t.map(|q| (snap(q.x), snap(q.y)));
            let area =
                (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
            let culled = match state.cull {
                Cull::Cw => area > 0,
                Cull::Ccw => area < 0,
                Cull::None => false,
            };
            if culled {
                continue;
            }
            let v = t.map(|q| (q.x, q.y, q.rhw));
            for px in reference_tri(&v, near, far, w as i32, 0..h as i32).unwrap_or_default() {
                if px.in_range {
                    per_px[(px.y as usize) * w as usize + px.x as usize]
                        .push((k as u32, 1.0 / px.t));
                }
            }
        }
        Reference { per_px }
    }

    /// The smallest and largest `W / W_far` of a covered pixel (`None` when nothing is covered).
    pub fn depth_span(&self) -> Option<(f64, f64)> {
        let mut it = self.per_px.iter().flatten().map(|&(_, d)| d);
        let first = it.next()?;
        Some(it.fold((first, first), |(a, b), d| (a.min(d), b.max(d))))
    }

    /// The visibility errors of an id frame (each pixel: 0 for nothing, else the triangle's index plus one).
    pub fn errors(&self, ids: &[u32]) -> u32 {
        let mut n = 0;
        for (list, &id) in self.per_px.iter().zip(ids) {
            let nearest = list.iter().map(|&(_, d)| d).fold(f64::INFINITY, f64::min);
            let ok = if id == 0 {
                list.is_empty()
            } else {
                list.iter().any(|&(k, d)| k + 1 == id && d <= nearest)
            };
            n += u32::from(!ok);
        }
        n
    }

    /// The smallest gap between the nearest and the second-nearest surface at a pixel, in steps of format `F` at the
    /// nearest surface's depth (`F::step`), with depth range `[near, far]` (`f64::INFINITY` when no pixel has two).
    pub fn min_gap_steps<F: DepthFormat>(&self, far_of_ref: f64, near: f64, far: f64) -> f64 {
        let mut best = f64::INFINITY;
        for list in &self.per_px {
            if list.len() < 2 {
                continue;
            }
            let mut d: Vec<f64> = list.iter().map(|&(_, d)| d * far_of_ref).collect();
            d.sort_by(f64::total_cmp);
            if d[1] > d[0] {
                best = best.min((d[1] - d[0]) / F::step(d[0], near, far));
            }
        }
        best
    }
}

/// Renders `tris` (each in its id colour) with format `format` (or none), strategy `strategy` and `state`, in bands
/// of `band_h` rows: the id frame.
pub fn render_ids(
    tris: &[[Vertex<Rgb565>; 3]],
    format: &str,
    strategy: &str,
    state: RenderState,
    w: u16,
    h: u16,
    band_h: u16,
) -> Result<Vec<u32>, Error> {
    let tris: Vec<_> = tris
        .iter()
        .enumerate()
        .map(|(k, t)| {
            t.map(|mut v| {
                v.color = id_color(k);
                v
            })
        })
        .collect();
    let frame = match strategy {
        "fast" => draw_as::<Fast>(&tris, format, state, w, h, band_h)?,
        "fast-div" => draw_as::<FastDiv>(&tris, format, state, w, h, band_h)?,
        "fast-div-int" => draw_as::<FastDivInt>(&tris, format, state, w, h, band_h)?,
        "exact" => draw_as::<Exact>(&tris, format, state, w, h, band_h)?,
        "prev-pixel" => draw_as::<PrevPixel>(&tris, format, state, w, h, band_h)?,
        _ => panic!("unknown strategy {strategy}"),
    };
    Ok(frame.px.iter().map(|c| c.into_storage() as u32).collect())
}

fn draw_as<R: SpanRecip>(
    tris: &[[Vertex<Rgb565>; 3]],
    format: &str,
    state: RenderState,
    w: u16,
    h: u16,
    band_h: u16,
) -> Result<Frame, Error> {
    match format {
        "none" => {
            let mut frame = Frame::new(w as u32, h as u32);
            let mut r = Rasterizer::<R>::new(state);
            for t in tris {
                r.draw(&mut frame, NoDepth, t)?;
            }
            Ok(frame)
        }
        "W16" => {
            let mut frame = Frame::new(w as u32, h as u32);
            let mut depth = vec![0u16; w as usize * h as usize];
            let mut r = Rasterizer::<R>::new(state);
            in_bands(&mut depth, w, h, band_h, |buf| {
                let mut s = wraster::Stats::default();
                for t in tris {
                    s += r.draw(&mut frame, &mut *buf, t)?;
                }
                Ok(s)
            })?;
            Ok(frame)
        }
        f => Ok(packed_rows::<R>(f, tris, state, w, h, band_h)?.0),
    }
}

/// What the planner is asked for.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    /// The most visibility errors allowed, over every frame.
    pub max_visibility_errors: u32,
    /// Bytes the depth buffer may take.
    pub depth_ram: usize,
    /// The core.
    pub core: Core,
}

/// A plan: what to build for a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The scene.
    pub scene: String,
    /// The core it is for.
    pub core: Core,
    /// The depth format (`none`: no depth buffer).
    pub format: String,
    /// The W strategy.
    pub strategy: String,
    /// `W_near` of the plan's render state.
    pub near: f32,
    /// `W_far`.
    pub far: f32,
    /// Rows per band (the frame's height: one band).
    pub band_rows: u16,
    /// Bands per frame.
    pub bands: u16,
    /// Bytes of depth buffer.
    pub depth_ram: usize,
    /// The crate features the scene needs (none of the standard scenes uses Gouraud colour, depth bias or lighting).
    pub features: Vec<&'static str>,
    /// Visibility errors over every frame, measured.
    pub visibility_errors: u32,
    /// Candidates measured before this one was taken: `(format, strategy, range, errors)`.
    pub tried: Vec<(String, String, &'static str, u32)>,
    /// Visibility errors of the general default build on this core, measured the same way: W16, the core's first
    /// strategy, the scene's own depth range, the board's default bands (the figure the plan is compared with).
    pub default_visibility_errors: u32,
    /// How it was chosen: `ram` (the first candidate within the budget, by depth RAM, then the strategies' order)
    /// or `measured` (the fewest instructions per frame on the core's QEMU board among [`candidates`]).
    pub ranked_by: &'static str,
    /// Its instructions per frame on the core's board, when measured.
    pub instructions_per_frame: Option<f64>,
    /// Whether the plan meets the error budget (when no candidate does, the plan is the cheapest of those with the
    /// fewest errors: a scene whose surfaces intersect has pixels where they are closer than any format's step).
    pub budget_met: bool,
}

impl Plan {
    /// The line scripts read.
    pub fn line(&self) -> String {
        let features = if self.features.is_empty() {
            "none".to_string()
        } else {
            self.features.join(",")
        };
        format!(
            "plan scene={} format={} strategy={} near={} far={} bands={} depth_ram={} features={} visibility_errors={} core={} band_rows={} budget_met={} default_visibility_errors={} ranked_by={} instructions_per_frame={}",
            self.scene,
            self.format,
            self.strategy,
            self.near,
            self.far,
            self.bands,
            self.depth_ram,
            features,
            self.visibility_errors,
            self.core.name(),
            self.band_rows,
            self.budget_met,
            self.default_visibility_errors,
            self.ranked_by,
            self.instructions_per_frame
                .map_or("-".to_string(), |n| format!("{n:.0}"))
        )
    }

    /// The plan as Rust source, for a board's build.rs to include (`PLAN=<file>,...`; see boards/common): the
    /// chosen format and strategy as type aliases, the depth path as a constant, the rest as a `PlanData`, so the
    /// firmware names only what the plan chose.
    pub fn rust(&self, command: &str) -> String {
        let strategy = match self.strategy.as_str() {
            "fast" => "Fast",
            "fast-div" => "FastDiv",
            "fast-div-int" => "FastDivInt",
            "exact" => "Exact",
            "prev-pixel" => "PrevPixel",
            s => panic!("unknown strategy {s}"),
        };
        let (format, kind) = match self.format.as_str() {
            "none" => ("W16", "NO_DEPTH"),
            "W16" => ("W16", "LEAN_W16"),
            f => (f, "PACKED"),
        };
        let mut s = String::new();
        writeln!(
            s,
            "// The plan for scene `{}` on {}, written by `{command}`: generated, do not edit.",
            self.scene,
            self.core.name()
        )
        .unwrap();
        writeln!(s, "// {}", self.line()).unwrap();
        writeln!(s, "/// Its depth format (with `NO_DEPTH`, only named).\npub type PlanFormat = wraster::format::{format};").unwrap();
        writeln!(
            s,
            "/// Its W strategy.\npub type PlanStrategy = wraster::recip::{strategy};"
        )
        .unwrap();
        writeln!(
            s,
            "/// Its depth path.\npub const PLAN_KIND: u8 = crate::{kind};"
        )
        .unwrap();
        // The boards bake the standard scenes and W4 only: another scene's plan names no scene they can draw.
        let scene = match wraster::scenes::Scene::ALL
            .iter()
            .position(|x| x.name() == self.scene)
        {
            Some(k) => k.to_string(),
            None if self.scene == "torus" => "crate::TORUS_SCENE".to_string(),
            None => format!(
                "panic!(\"the boards bake the standard scenes and W4's torus, not {}\")",
                self.scene
            ),
        };
        writeln!(
            s,
            "/// Its scene: the index in `SCENES`, or `TORUS_SCENE`.\npub const PLAN_SCENE: usize = {scene};"
        )
        .unwrap();
        writeln!(
            s,
            "/// The plan.\npub const PLAN: crate::PlanData = crate::PlanData {{ scene: {:?}, format: {:?}, near: f32::from_bits({:#010x}), far: f32::from_bits({:#010x}), band_rows: {}, depth_ram: {}, visibility_errors: {}, coarse: {} }};",
            self.scene, self.format, self.near.to_bits(), self.far.to_bits(), self.band_rows, self.depth_ram, self.visibility_errors, self.coarse()
        )
        .unwrap();
        if self.coarse() {
            writeln!(
                s,
                "const _: () = assert!(cfg!(feature = \"coarse\"), \"this plan keeps a coarse depth bound: build with --features plan,coarse\");"
            )
            .unwrap();
        }
        s
    }

    /// Whether the plan keeps a coarse depth bound (feature `coarse`).
    pub fn coarse(&self) -> bool {
        self.features.contains(&"coarse")
    }

    /// The board features its firmware is built with (`plan`, and `coarse` when it keeps the bound).
    pub fn board_features(&self) -> Vec<&'static str> {
        if self.coarse() {
            vec!["plan", "coarse"]
        } else {
            vec!["plan"]
        }
    }

    /// This W16 fast-tier plan with a coarse depth bound beside its buffer (feature `coarse`): one `u16` per 8 pixels
    /// of each band row, so the bands shrink to keep depth and bound within `depth_ram` bytes. `None` for another
    /// format or strategy (only the fast tier's span loop uses the bound). The pictures are the same as without it.
    pub fn with_coarse(&self, w: u16, h: u16, depth_ram: usize) -> Option<Plan> {
        if self.format != "W16"
            || !matches!(self.strategy.as_str(), "fast" | "fast-div" | "fast-div-int")
            || self.coarse()
        {
            return None;
        }
        let row = w as usize * 2 + wraster::bound_len(w as usize, 1) * 2;
        let rows = (depth_ram / row).min(h as usize) as u16;
        if rows == 0 {
            return None;
        }
        let mut features = self.features.clone();
        features.push("coarse");
        Some(Plan {
            band_rows: rows,
            bands: h.div_ceil(rows),
            depth_ram: row * rows as usize,
            features,
            ..self.clone()
        })
    }
}

/// The depth range `[near, far]` tightened to the W a scene draws (`span`: the smallest and largest `W / W_far` of
/// its covered pixels), widened by `2^-8` of itself, never beyond the scene's own range.
pub fn tightened(state: &RenderState, span: (f64, f64)) -> (f32, f32) {
    let (n, f) = (state.range.near(), state.range.far());
    let lo = (span.0 * f as f64 * (1.0 - 1.0 / 256.0)) as f32;
    let hi = (span.1 * f as f64 * (1.0 + 1.0 / 256.0)) as f32;
    (lo.max(n), hi.min(f))
}

/// The visibility errors of one candidate over every frame of `wl`.
pub fn errors_of(
    wl: &Workload,
    refs: &[Reference],
    format: &str,
    strategy: &str,
    state: RenderState,
    band_rows: u16,
) -> Result<u32, Error> {
    let mut n = 0;
    for (tris, r) in wl.frames.iter().zip(refs) {
        n += r.errors(&render_ids(
            tris, format, strategy, state, wl.w, wl.h, band_rows,
        )?);
    }
    Ok(n)
}

/// The cheapest plan within `budget` (see the module's docs); when no candidate meets it, the cheapest of those
/// with the fewest errors, with `budget_met: false` (with too little depth RAM for any format, that is "none").
pub fn plan(wl: &Workload, budget: Budget) -> Result<Plan, Error> {
    Ok(candidates(wl, budget, 1)?.swap_remove(0))
}

/// Up to `formats` plans within `budget`, each the first candidate of its format that meets it (cheapest RAM
/// first): what [`rank_measured`] compares on the core. When none meets it, the one plan [`plan`] falls back to.
/// Every plan carries the candidates tried up to the last one returned.
pub fn candidates(wl: &Workload, budget: Budget, formats: usize) -> Result<Vec<Plan>, Error> {
    let formats = formats.max(1);
    let mut meeting: Vec<Plan> = vec![];
    let refs: Vec<Reference> = wl
        .frames
        .iter()
        .map(|t| Reference::new(t, &wl.state, wl.w, wl.h))
        .collect();
    let span = refs
        .iter()
        .filter_map(Reference::depth_span)
        .fold(None, |acc: Option<(f64, f64)>, (a, b)| {
            Some(acc.map_or((a, b), |(x, y)| (x.min(a), y.max(b))))
        });
    let own = (wl.state.range.near(), wl.state.range.far());
    let mut ranges = vec![];
    if let Some(s) = span {
        let t = tightened(&wl.state, s);
        if t.0 < t.1 && t != own {
            ranges.push(("tight", t));
        }
    }
    ranges.push(("scene", own));
    let default_rows =
        (budget.core.default_depth_ram(&wl.name) / (wl.w as usize * 2)).min(wl.h as usize) as u16;
    let default_errors = errors_of(
        wl,
        &refs,
        "W16",
        budget.core.strategies()[0],
        wl.state,
        default_rows,
    )?;
    let mut tried = vec![];
    let mut best: Option<Plan> = None;
    for format in FORMATS {
        if meeting.len() >= formats {
            break;
        }
        let bytes = format_bytes(format);
        let row_bytes = wl.w as usize * bytes;
        let band_rows = if bytes == 0 {
            wl.h
        } else {
            (budget.depth_ram / row_bytes).min(wl.h as usize) as u16
        };
        if band_rows == 0 {
            continue;
        }
        let bands = wl.h.div_ceil(band_rows);
        let strategies: Vec<&str> = if bytes == 0 {
            vec![budget.core.strategies()[0]]
        } else {
            budget.core.strategies().to_vec()
        };
        'format: for strategy in strategies {
            for &(kind, (near, far)) in &ranges {
                if bytes == 0 && kind == "tight" {
                    // Without a depth buffer the range only culls: keep the scene's.
                    continue;
                }
                let mut state = wl.state;
                state.range = wraster::DepthRange::new(near, far)?;
                let e = errors_of(wl, &refs, format, strategy, state, band_rows)?;
                tried.push((format.to_string(), strategy.to_string(), kind, e));
                let p = Plan {
                    scene: wl.name.clone(),
                    core: budget.core,
                    format: format.into(),
                    strategy: strategy.into(),
                    near,
                    far,
                    band_rows,
                    bands,
                    depth_ram: row_bytes * band_rows as usize,
                    features: vec![],
                    visibility_errors: e,
                    default_visibility_errors: default_errors,
                    ranked_by: "ram",
                    instructions_per_frame: None,
                    tried: vec![],
                    budget_met: e <= budget.max_visibility_errors,
                };
                if p.budget_met {
                    meeting.push(p);
                    break 'format;
                }
                if best.as_ref().is_none_or(|b| e < b.visibility_errors) {
                    best = Some(p);
                }
            }
        }
    }
    if !meeting.is_empty() {
        return Ok(meeting
            .into_iter()
            .map(|p| Plan {
                tried: tried.clone(),
                ..p
            })
            .collect());
    }
    let best = best.ok_or(Error::BufferSize {
        expected: wl.w as usize * 2,
        actual: budget.depth_ram,
    })?;
    Ok(vec![Plan { tried, ..best }])
}

/// The QEMU board a core's plans run on (`qemu-m0`, `qemu-m4`; the RV32 board has no `plan` feature yet).
pub fn board_of(core: Core) -> Option<&'static str> {
    match core {
        Core::M0 => Some("qemu-m0"),
        Core::M4 => Some("qemu-m4"),
        Core::Rv32 => None,
    }
}

/// Each candidate's instructions per frame on its core's board: each written as a plan into `dir`, built into a
/// firmware of its own (`PLAN=<file> cargo run --release --features plan`: what would ship; in one firmware with the
/// others, LLVM inlines differently and a plan's count moved by up to 50%) and run under QEMU; read from its
/// `bench` line (`instr_per_frame` for the torus's frames, else `instructions`).
pub fn measure_on_board(cands: &[Plan], dir: &std::path::Path) -> Result<Vec<f64>, String> {
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    if let Some(p) = cands.iter().find(|p| {
        p.scene != "torus"
            && !wraster::scenes::Scene::ALL
                .iter()
                .any(|s| s.name() == p.scene)
    }) {
        return Err(format!(
            "--measure runs plans on the boards, which bake the standard scenes and W4's torus, not {}",
            p.scene
        ));
    }
    cands
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let board = board_of(p.core).ok_or("--measure needs the M0 or M4 board")?;
            let f = dir.join(format!("{}-{}-{k}.rs", p.scene, p.core.name()));
            std::fs::write(&f, p.rust("plan --measure (a candidate)"))
                .map_err(|e| e.to_string())?;
            let file = f.canonicalize().map_err(|e| e.to_string())?;
            let out = crate::run_board_env(
                board,
                &p.board_features(),
                &[("PLAN", &file.display().to_string())],
            )?;
            let line = out
                .lines()
                .find(|l| {
                    l.starts_with("bench ")
                        && crate::field(l, "scene") == Some(p.scene.as_str())
                        && crate::field(l, "format") == Some(p.format.as_str())
                })
                .ok_or_else(|| format!("no bench line for {} {}:\n{out}", p.scene, p.format))?;
            crate::field(line, "instr_per_frame")
                .or_else(|| crate::field(line, "instructions"))
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| format!("no instruction count in {line}"))
        })
        .collect()
}

/// The candidate with the fewest instructions per frame (the first, the least RAM, on a tie), marked as measured.
pub fn rank_measured(cands: Vec<Plan>, costs: &[f64]) -> Plan {
    let (k, _) =
        costs.iter().enumerate().fold(
            (0, f64::INFINITY),
            |(bk, bc), (k, &c)| if c < bc { (k, c) } else { (bk, bc) },
        );
    let mut p = cands.into_iter().nth(k).expect("one cost per candidate");
    p.ranked_by = "measured";
    p.instructions_per_frame = Some(costs[k]);
    p
}

/// FNV-1a 64 over bytes (the boards' `Fnv`).
fn fnv(h: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// What a board built from `plan` prints for it (`hash`, `pixels`, `fragments`), computed here: the plan's scene in
/// its own colours, drawn as the board draws it (its format or none, strategy, range, bands; the torus's W16
/// frames through the mesh path), hashed as the boards hash: each row's RGB565 colours, then its stored depth
/// bytes (none without a buffer).
pub fn plan_hash(plan: &Plan) -> Result<(u64, u32, u32), Error> {
    match plan.strategy.as_str() {
        "fast" => plan_hash_as::<Fast>(plan),
        "fast-div" => plan_hash_as::<FastDiv>(plan),
        "fast-div-int" => plan_hash_as::<FastDivInt>(plan),
        "exact" => plan_hash_as::<Exact>(plan),
        "prev-pixel" => plan_hash_as::<PrevPixel>(plan),
        s => panic!("unknown strategy {s}"),
    }
}

fn plan_hash_as<R: SpanRecip>(plan: &Plan) -> Result<(u64, u32, u32), Error> {
    use wraster::scenes::{torus, Scene};
    let wl = workload(&plan.scene).map_err(|_| Error::IndexOutOfRange)?;
    let mut state = wl.state;
    state.range = wraster::DepthRange::new(plan.near, plan.far)?;
    let (w, h) = (wl.w as usize, wl.h as usize);
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut stats = wraster::Stats::default();
    let frames: Vec<Vec<[Vertex<Rgb565>; 3]>> =
        match Scene::ALL.into_iter().find(|s| s.name() == plan.scene) {
            Some(s) => vec![s.tris().collect()],
            None => {
                // The torus in its own face colours.
                let col = torus::colors();
                wl.frames
                    .iter()
                    .map(|f| {
                        f.iter()
                            .zip(col.iter())
                            .map(|(t, c)| {
                                t.map(|mut v| {
                                    v.color = *c;
                                    v
                                })
                            })
                            .collect()
                    })
                    .collect()
            }
        };
    for (k, tris) in frames.iter().enumerate() {
        let mut frame = Frame::new(w as u32, h as u32);
        let mut r = Rasterizer::<R>::new(state);
        let depth_rows: Vec<Vec<u8>> = match plan.format.as_str() {
            "none" => {
                for t in tris {
                    stats += r.draw(&mut frame, NoDepth, t)?;
                }
                vec![vec![]; h]
            }
            "W16" => {
                let mut depth = vec![0u16; w * h];
                if plan.scene == "torus" {
                    let (f, d, s) = crate::render_torus_with::<R>(k, plan.band_rows, state)?;
                    frame = f;
                    depth = d;
                    stats += s;
                } else {
                    // With the plan's coarse bound, as its firmware keeps it (the same frames either way).
                    let mut seg = match plan.coarse() {
                        true => vec![0u16; wraster::bound_len(w, plan.band_rows as usize)],
                        false => vec![],
                    };
                    let (ww, hh, rows) = (wl.w, wl.h, plan.band_rows);
                    stats += crate::in_bands_bounded(&mut depth, ww, hh, rows, &mut seg, |buf| {
                        let mut s = wraster::Stats::default();
                        for t in tris {
                            s += r.draw(&mut frame, &mut *buf, t)?;
                        }
                        Ok(s)
                    })?;
                }
                depth
                    .chunks(w)
                    .map(|row| row.iter().flat_map(|c| c.to_le_bytes()).collect())
                    .collect()
            }
            f => {
                let (fr, rows, s) = packed_rows::<R>(f, tris, state, wl.w, wl.h, plan.band_rows)?;
                frame = fr;
                stats += s;
                rows
            }
        };
        for (y, d) in depth_rows.iter().enumerate() {
            let row: Vec<u8> = frame.px[y * w..(y + 1) * w]
                .iter()
                .flat_map(|c| c.into_storage().to_le_bytes())
                .collect();
            fnv(&mut hash, &row);
            fnv(&mut hash, d);
        }
    }
    Ok((hash, stats.written, stats.fragments))
}

/// A packed format's draw in bands of `band_h` rows, each cleared to the far plane first: the frame, every row's
/// stored bytes, the stats.
fn packed_rows<R: SpanRecip>(
    format: &str,
    tris: &[[Vertex<Rgb565>; 3]],
    state: RenderState,
    w: u16,
    h: u16,
    band_h: u16,
) -> Result<(Frame, Vec<Vec<u8>>, wraster::Stats), Error> {
    fn go<F: Codec, R: SpanRecip>(
        tris: &[[Vertex<Rgb565>; 3]],
        state: RenderState,
        w: u16,
        h: u16,
        band_h: u16,
    ) -> Result<(Frame, Vec<Vec<u8>>, wraster::Stats), Error> {
        let mut frame = Frame::new(w as u32, h as u32);
        let mut r = Rasterizer::<R>::new(state);
        let mut rows = vec![];
        let mut stats = wraster::Stats::default();
        let mut y0 = 0u16;
        while y0 < h {
            let bh = band_h.min(h - y0);
            let mut words = vec![F::Word::default(); w as usize * bh as usize];
            let mut buf = DepthBuffer::<F>::band_format(&mut words, w, y0 as i32, bh)?;
            buf.clear_for(&state.range);
            for t in tris {
                stats += r.draw(&mut frame, &mut buf, t)?;
            }
            rows.extend(words.chunks(w as usize).map(crate::le_bytes::<F>));
            y0 += bh;
        }
        Ok((frame, rows, stats))
    }
    match format {
        "LZ16" => go::<LZ16, R>(tris, state, w, h, band_h),
        "Z16" => go::<Z16, R>(tris, state, w, h, band_h),
        "W16F" => go::<W16F, R>(tris, state, w, h, band_h),
        "W24F" => go::<W24F, R>(tris, state, w, h, band_h),
        "W24FScaled" => go::<W24FScaled, R>(tris, state, w, h, band_h),
        "Z24" => go::<Z24, R>(tris, state, w, h, band_h),
        "W32F" => go::<W32F, R>(tris, state, w, h, band_h),
        "Z32F" => go::<Z32F, R>(tris, state, w, h, band_h),
        "RZ32F" => go::<RZ32F, R>(tris, state, w, h, band_h),
        _ => panic!("unknown format {format}"),
    }
}
