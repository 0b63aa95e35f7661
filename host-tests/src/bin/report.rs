//! Error against run time: `cargo run --release -p host-tests --bin report [-- --no-boards]`.
//!
//! Every depth format x every W strategy (the reciprocal only matters to the W formats; the Z formats need none and
//! appear once) over the standard scenes and the stiff suite, each measured against the f64 reference:
//! depth error in LSBs of the format and relative to depth, visibility and coverage differences, host ns per drawn
//! pixel (median of 15 runs), and the boards' instructions per pixel where the firmware runs that combination, with
//! estimated cycles beside them ([`board_cpis`]).
//! Writes report/report.md and report/*.png; the last line is `report combos=<n> pareto=<k> out=report/report.md`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::RgbColor;
use host_tests::plot::{heat_map, pareto_plot, rows, step_plot, Point2};
use host_tests::{field, have, random_tri, reference_frame, run_board, Frame, RefFrame, Rng};
use wraster::format::{
    DepthFormat, Storage, W24FScaled, LZ16, RZ32F, W16, W16F, W24F, W32F, Z16, Z24, Z32F,
};
use wraster::recip::{
    DefaultRecip, F32Div, Newton, PerPixel, PrevPixel, Quake, SpanRecip, Table64, WSpan,
};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::{Codec, Compare, DepthBuffer, Rasterizer, RenderState, Vertex};

type Tri = [Vertex<Rgb565>; 3];

/// One frame of a measured workload: triangles, depth range, frame size, comparison.
struct Case {
    name: String,
    tris: Vec<Tri>,
    near: f32,
    far: f32,
    w: u16,
    h: u16,
    /// Each triangle alone into a cleared buffer with `Always` (pure depth error), or the whole list with `Less`.
    alone: bool,
    reference: Vec<RefFrame>,
}

impl Case {
    fn new(
        name: &str,
        tris: Vec<Tri>,
        (near, far): (f32, f32),
        (w, h): (u16, u16),
        alone: bool,
    ) -> Self {
        let reference = if alone {
            tris.iter()
                .map(|t| reference_frame(std::slice::from_ref(t), near, far, w as u32, h as u32))
                .collect()
        } else {
            vec![reference_frame(&tris, near, far, w as u32, h as u32)]
        };
        Case {
            name: name.into(),
            tris,
            near,
            far,
            w,
            h,
            alone,
            reference,
        }
    }
}

/// Error tallies over a set of cases.
#[derive(Default, Clone)]
struct Err {
    pixels: u64,
    max_lsb: u64,
    sum_lsb: f64,
    max_rel: f64,
    sum_rel: f64,
    visibility: u64,
    coverage: u64,
}

impl Err {
    fn mean_lsb(&self) -> f64 {
        self.sum_lsb / self.pixels.max(1) as f64
    }
    fn mean_rel(&self) -> f64 {
        self.sum_rel / self.pixels.max(1) as f64
    }
}

struct Combo {
    format: &'static str,
    strategy: &'static str,
    scenes: Err,
    stiff: Err,
    /// Host ns per written pixel over the four standard scenes, median of 15.
    ns_px: f64,
    /// Board key (for the instruction columns), when a board runs this combination.
    board_key: Option<&'static str>,
    pareto: bool,
}

/// Draws `tris` into a frame and a cleared buffer: the frame, every pixel's code, the written pixels and the time of
/// the draw calls alone (ns; not the allocation or the clear).
type RenderFn = fn(&Case, &[Tri], Compare) -> (Frame, Vec<u32>, u32, f64);

/// A black frame whose memory has been written, so no page fault lands in a timed draw.
fn touched_frame(case: &Case) -> Frame {
    let mut frame = Frame::new(case.w as u32, case.h as u32);
    frame.px.fill(Rgb565::BLACK);
    frame.writes.fill(1);
    frame.writes.fill(0);
    frame
}

/// The W16 buffer's lean path (`Rasterizer::draw`), the one the boards run.
fn render_lean<R: SpanRecip>(
    case: &Case,
    tris: &[Tri],
    compare: Compare,
) -> (Frame, Vec<u32>, u32, f64) {
    let mut state = RenderState::new(case.near, case.far).unwrap();
    state.compare = compare;
    let mut frame = touched_frame(case);
    let mut depth = vec![0u16; case.w as usize * case.h as usize];
    let mut buf = DepthBuffer::new(&mut depth, case.w, case.h).unwrap();
    buf.clear();
    let mut r = Rasterizer::<R>::new(state);
    let t0 = Instant::now();
    let mut written = 0;
    for t in tris {
        written += r.draw(&mut frame, &mut buf, t).unwrap().written;
    }
    let ns = t0.elapsed().as_nanos() as f64;
    (
        frame,
        depth.into_iter().map(u32::from).collect(),
        written,
        ns,
    )
}

/// Any format through the span loop generic over the format and the strategy (`Rasterizer::draw_generic`; W16's
/// too, which `Rasterizer::draw` gives to the tiers' own loops: those are the "lean W16 path" rows).
fn render_case<F: Codec, R: WSpan>(
    case: &Case,
    tris: &[Tri],
    compare: Compare,
) -> (Frame, Vec<u32>, u32, f64) {
    let mut state = RenderState::new(case.near, case.far).unwrap();
    state.compare = compare;
    let mut frame = touched_frame(case);
    let mut bytes = vec![<F as DepthFormat>::Word::default(); case.w as usize * case.h as usize];
    let mut buf = DepthBuffer::<F>::new_format(&mut bytes, case.w, case.h).unwrap();
    buf.clear_for(&state.range);
    let mut r = Rasterizer::<R>::new(state);
    let t0 = Instant::now();
    let mut written = 0;
    for t in tris {
        written += r.draw_generic(&mut frame, &mut buf, t).unwrap().written;
    }
    let ns = t0.elapsed().as_nanos() as f64;
    (frame, bytes.iter().map(|w| w.code()).collect(), written, ns)
}

/// Compares a rendered frame with the reference's.
fn tally<F: Codec>(e: &mut Err, frame: &Frame, codes: &[u32], rf: &RefFrame, near: f32, far: f32) {
    let (n, f) = (near as f64, far as f64);
    for (k, &code) in codes.iter().enumerate() {
        let drawn = frame.writes[k] > 0;
        if drawn != rf.covered[k] {
            e.coverage += 1;
            continue;
        }
        if !drawn {
            continue;
        }
        if frame.px[k] != rf.px[k] {
            e.visibility += 1;
            continue;
        }
        let d = rf.depth[k] * f;
        let want = F::encode(d, n, f);
        let lsb = (code as i64 - want as i64).unsigned_abs();
        let rel = (F::decode(code, n, f) - d).abs() / d;
        e.pixels += 1;
        e.max_lsb = e.max_lsb.max(lsb);
        e.sum_lsb += lsb as f64;
        e.max_rel = e.max_rel.max(rel);
        e.sum_rel += rel;
    }
}

fn errors<F: Codec>(cases: &[Case], draw: RenderFn) -> Err {
    let mut e = Err::default();
    for case in cases {
        if case.alone {
            for (t, rf) in case.tris.iter().zip(&case.reference) {
                let (frame, codes, _, _) = draw(case, std::slice::from_ref(t), Compare::Always);
                tally::<F>(&mut e, &frame, &codes, rf, case.near, case.far);
            }
        } else {
            let (frame, codes, _, _) = draw(case, &case.tris, Compare::Less);
            tally::<F>(
                &mut e,
                &frame,
                &codes,
                &case.reference[0],
                case.near,
                case.far,
            );
        }
    }
    e
}

/// Median over 15 runs of (all scenes' draw time) / (all scenes' written pixels), in ns.
fn host_time(scenes: &[Case], draw: RenderFn) -> f64 {
    let mut runs: Vec<f64> = (0..16)
        .map(|_| {
            let (mut ns, mut px) = (0f64, 0u64);
            for case in scenes {
                let (_, _, written, t) = draw(case, &case.tris, Compare::Less);
                ns += t;
                px += written as u64;
            }
            ns / px as f64
        })
        .collect();
    runs.remove(0); // the first run warms caches and branch predictors
    runs.sort_by(f64::total_cmp);
    runs[runs.len() / 2]
}

fn measure<F: Codec, R: WSpan>(
    strategy: &'static str,
    board_key: Option<&'static str>,
    scenes: &[Case],
    stiff: &[Case],
) -> Combo {
    measure_with::<F>(strategy, board_key, scenes, stiff, render_case::<F, R>)
}

fn measure_with<F: Codec>(
    strategy: &'static str,
    board_key: Option<&'static str>,
    scenes: &[Case],
    stiff: &[Case],
    draw: RenderFn,
) -> Combo {
    Combo {
        format: F::NAME,
        strategy,
        scenes: errors::<F>(scenes, draw),
        stiff: errors::<F>(stiff, draw),
        ns_px: host_time(scenes, draw),
        board_key,
        pareto: false,
    }
}

/// Every W strategy for a W format.
fn w_format<F: Codec>(out: &mut Vec<Combo>, scenes: &[Case], stiff: &[Case]) {
    out.push(measure::<F, PerPixel<Newton<Table64, 0>>>(
        "table64+0nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, PerPixel<Newton<Table64, 1>>>(
        "table64+1nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, PerPixel<Newton<Table64, 2>>>(
        "table64+2nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, PerPixel<Newton<Table64, 3>>>(
        "table64+3nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, PerPixel<DefaultRecip>>(
        "lerp64+1nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, PrevPixel>(
        "prev-pixel+1nr",
        None,
        scenes,
        stiff,
    ));
    out.push(measure::<F, Quake<8>>("quake-8", None, scenes, stiff));
    out.push(measure::<F, Quake<16>>("quake-16", None, scenes, stiff));
    out.push(measure::<F, PerPixel<F32Div>>(
        "f32-div", None, scenes, stiff,
    ));
}

/// The stiff suite: random triangles (slivers to larger than the frame) at far/near 10 to 1e6 and with W_near 1e-3 and
/// W_far 1e7; 1000-pixel needles; grazing spans along which RHW changes 1000x; vertices on pixel centres and ties.
fn stiff_suite() -> Vec<Case> {
    let mut rng = Rng(0x0005_71FF_CA5E);
    let mut cases = Vec::new();
    let c = Rgb565::WHITE;
    for (n, f) in [
        (1.0f32, 10.0f32),
        (1.0, 1e2),
        (1.0, 1e3),
        (1.0, 1e4),
        (1.0, 1e5),
        (1.0, 1e6),
        (1e-3, 1e3),
        (10.0, 1e7),
    ] {
        let (nd, fd) = (n as f64, f as f64);
        let tris = (0..40).map(|_| random_tri(&mut rng, nd, fd)).collect();
        cases.push(Case::new(
            &format!("random f/n={}", fd / nd),
            tris,
            (n, f),
            (96, 64),
            true,
        ));
    }
    // needles 1000 px long across a wide frame, W from near to far along them
    let needles = (0..12)
        .map(|k| {
            let y = 2.0 + 5.0 * k as f32;
            [
                Vertex::new(5.3, y, 1.5, c),
                Vertex::new(1005.7, y + 0.7 + 0.1 * k as f32, 900.0, c),
                Vertex::new(5.9, y + 1.6, 1.5, c),
            ]
        })
        .collect();
    cases.push(Case::new(
        "needles 1000 px",
        needles,
        (1.0, 1000.0),
        (1024, 64),
        true,
    ));
    // grazing: RHW changes 1000x along each span, and a floor whose W runs from 1 to 1000 over a few rows
    let grazing = vec![
        [
            Vertex::new(0.0, 0.0, 1.0, c),
            Vertex::new(96.0, 0.0, 1000.0, c),
            Vertex::new(0.0, 64.0, 1.0, c),
        ],
        [
            Vertex::new(0.0, 10.0, 1000.0, c),
            Vertex::new(96.0, 10.0, 1000.0, c),
            Vertex::new(48.0, 14.0, 1.0, c),
        ],
        [
            Vertex::new(96.0, 0.0, 2.0, c),
            Vertex::new(0.0, 32.0, 999.0, c),
            Vertex::new(96.0, 64.0, 2.0, c),
        ],
    ];
    cases.push(Case::new(
        "grazing 1000x",
        grazing,
        (1.0, 1000.0),
        (96, 64),
        true,
    ));
    // vertices on pixel centres and on sub-pixel ties
    let ties = (0..30)
        .map(|_| {
            let mut t = random_tri(&mut rng, 1.0, 1000.0);
            for (k, v) in t.iter_mut().enumerate() {
                v.x = (v.x.floor() + if k == 0 { 0.5 } else { 1.0 / 512.0 }).clamp(-200.0, 300.0);
                v.y = (v.y.floor() + 0.5).clamp(-200.0, 300.0);
            }
            t
        })
        .collect();
    cases.push(Case::new(
        "centres and ties",
        ties,
        (1.0, 1000.0),
        (96, 64),
        true,
    ));
    cases
}

fn board_figures(run: bool) -> (Vec<(String, String, f64)>, String) {
    // (core, recip, instructions per written pixel over the scenes)
    let mut out = Vec::new();
    if !run {
        return (out, "not run (--no-boards)".into());
    }
    if !have("qemu-system-arm") {
        return (
            out,
            "not run: qemu-system-arm is not installed (.ci/run installs it)".into(),
        );
    }
    let mut note = String::from(
        "from the boards' `bench` lines: instructions / written pixels over the four scenes",
    );
    for (board, core, features) in [
        ("qemu-m4", "M4", &[][..]),
        ("qemu-m4", "M4", &["f32-div"][..]),
        ("qemu-m0", "M0", &[][..]),
    ] {
        match run_board(board, features) {
            Ok(stdout) => {
                let mut sums: Vec<(String, f64, f64)> = Vec::new();
                for line in stdout.lines().filter(|l| l.starts_with("bench ")) {
                    let recip = field(line, "recip").unwrap_or("?").to_string();
                    let ins: f64 = field(line, "instructions")
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(0.0);
                    let px: f64 = field(line, "pixels")
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(0.0);
                    match sums.iter_mut().find(|s| s.0 == recip) {
                        Some(s) => {
                            s.1 += ins;
                            s.2 += px;
                        }
                        None => sums.push((recip, ins, px)),
                    }
                }
                for (recip, ins, px) in sums {
                    out.push((core.to_string(), recip, ins / px));
                }
            }
            Err(e) => {
                let _ = write!(
                    note,
                    "; {board} {features:?} failed: {}",
                    e.lines().next().unwrap_or("")
                );
            }
        }
    }
    (out, note)
}

/// Estimated cycles per instruction of each strategy's draw code on the two Cortex-M boards, for the strategies `boards`
/// has figures of: `python3 boards/tools/cycles.py <board> --recip <name> --together` (its `cpi=`), which runs a build
/// of the board with only that strategy (`--features size-probe`, the build-time `RECIP`) under QEMU with the
/// insncount plugin and weights every executed instruction of the draw code by its class in the core's timing table
/// (the Cortex-M4 and Cortex-M0+ Technical Reference Manuals). Estimates: no memory wait states, no pipeline effects
/// beyond the branch penalty. (core, recip, cycles per instruction), and what the note says.
fn board_cpis(boards: &[(String, String, f64)]) -> (Vec<(String, String, f64)>, String) {
    let mut out = Vec::new();
    if boards.is_empty() {
        return (out, "estimated cycles not taken (no board figures)".into());
    }
    if !have("python3") {
        return (
            out,
            "estimated cycles not taken: python3 is not installed".into(),
        );
    }
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../boards/tools/cycles.py");
    let mut note = String::from("estimated cycles: the instructions times the cycles per instruction of the strategy's own single-strategy build (`boards/tools/cycles.py <board> --recip <name> --together`: each executed instruction weighted by its class in the Cortex-M4 and Cortex-M0+ Technical Reference Manuals' timing tables; no wait states, no pipeline effects beyond the branch penalty)");
    for (core, recip, _) in boards {
        let board = if core == "M4" { "qemu-m4" } else { "qemu-m0" };
        // The M4's two firmwares (with and without `f32-div`) both report the other strategies: one estimate each.
        if !["fast", "lerp64", "prev-pixel", "f32-div"].contains(&recip.as_str())
            || (core == "M0" && recip == "f32-div")
            || out.iter().any(|(c, r, _)| c == core && r == recip)
        {
            continue;
        }
        let run = std::process::Command::new("python3")
            .arg(&script)
            .args([board, "--recip", recip, "--together"])
            .output();
        let cpi = run.as_ref().ok().and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .rev()
                .find(|l| l.starts_with("cycles "))
                .and_then(|l| field(l, "cpi").and_then(|v| v.parse::<f64>().ok()))
        });
        match cpi {
            Some(cpi) => out.push((core.clone(), recip.clone(), cpi)),
            None => {
                let why = match &run {
                    Ok(o) => String::from_utf8_lossy(&o.stderr)
                        .lines()
                        .last()
                        .unwrap_or("")
                        .to_string(),
                    Err(e) => e.to_string(),
                };
                let _ = write!(note, "; cycles.py {board} {recip} failed: {why}");
            }
        }
    }
    (out, note)
}

fn main() {
    let run_boards = !std::env::args().any(|a| a == "--no-boards");
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../report");
    std::fs::create_dir_all(&dir).unwrap();

    let scenes: Vec<Case> = Scene::ALL
        .iter()
        .map(|&s| {
            Case::new(
                s.name(),
                s.tris().collect(),
                s.depth_range(),
                (WIDTH, HEIGHT),
                false,
            )
        })
        .collect();
    let stiff = stiff_suite();

    let mut combos = vec![
        measure_with::<W16>(
            "fast tier (default), lean W16 path",
            Some("fast"),
            &scenes,
            &stiff,
            render_lean::<wraster::recip::Fast>,
        ),
        measure_with::<W16>(
            "lerp64+1nr (exact tier), lean W16 path",
            Some("lerp64"),
            &scenes,
            &stiff,
            render_lean::<PerPixel<DefaultRecip>>,
        ),
        measure_with::<W16>(
            "prev-pixel+1nr, lean W16 path",
            Some("prev-pixel"),
            &scenes,
            &stiff,
            render_lean::<PrevPixel>,
        ),
        measure_with::<W16>(
            "f32-div, lean W16 path",
            Some("f32-div"),
            &scenes,
            &stiff,
            render_lean::<PerPixel<F32Div>>,
        ),
    ];
    w_format::<W16>(&mut combos, &scenes, &stiff);
    w_format::<W16F>(&mut combos, &scenes, &stiff);
    w_format::<W24F>(&mut combos, &scenes, &stiff);
    w_format::<W24FScaled>(&mut combos, &scenes, &stiff);
    w_format::<W32F>(&mut combos, &scenes, &stiff);
    for c in [
        measure::<Z16, PerPixel<DefaultRecip>>("none (Z)", None, &scenes, &stiff),
        measure::<Z24, PerPixel<DefaultRecip>>("none (Z)", None, &scenes, &stiff),
        measure::<Z32F, PerPixel<DefaultRecip>>("none (Z)", None, &scenes, &stiff),
        measure::<RZ32F, PerPixel<DefaultRecip>>("none (Z)", None, &scenes, &stiff),
        measure::<LZ16, PerPixel<DefaultRecip>>("none (linear Z)", None, &scenes, &stiff),
    ] {
        combos.push(c);
    }

    // Pareto over (host ns/px, largest relative depth error over scenes and stiff suite): no other combination is
    // both at least as fast and at least as exact, and strictly better in one.
    let err = |c: &Combo| c.scenes.max_rel.max(c.stiff.max_rel);
    for i in 0..combos.len() {
        let (ti, ei) = (combos[i].ns_px, err(&combos[i]));
        combos[i].pareto = !combos.iter().any(|o| {
            let (to, eo) = (o.ns_px, err(o));
            to <= ti && eo <= ei && (to < ti || eo < ei)
        });
    }
    let pareto = combos.iter().filter(|c| c.pareto).count();

    let (boards, board_note) = board_figures(run_boards);
    let (cpis, cycles_note) = board_cpis(&boards);
    let insn = |core: &str, key: Option<&str>| -> String {
        key.and_then(|k| boards.iter().find(|b| b.0 == core && b.1 == k))
            .map(|b| format!("{:.1}", b.2))
            .unwrap_or_else(|| "-".into())
    };
    // Estimated cycles per written pixel: the board's instructions times the strategy's cycles per instruction.
    let cycles = |core: &str, key: Option<&str>| -> String {
        key.and_then(|k| {
            let b = boards.iter().find(|b| b.0 == core && b.1 == k)?;
            let c = cpis.iter().find(|c| c.0 == core && c.1 == k)?;
            Some(format!("{:.1}", b.2 * c.2))
        })
        .unwrap_or_else(|| "-".into())
    };

    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);

    // The scene planner's choices (M4, ranked by RAM: no board needed), marked on the plot: each plan's format with
    // the report's combination of the same strategy (the fast tier for `fast-div`, whose host arithmetic is the same
    // tier's), else the format's first combination.
    let links = format!("obj:{}/assets/links.obj", env!("CARGO_MANIFEST_DIR"));
    let plans: Vec<host_tests::plan::Plan> =
        ["big", "overdraw", "small", "terrain", "torus", &links]
            .iter()
            .map(|s| {
                let wl = host_tests::plan::workload(s).expect("a standard scene");
                let core = host_tests::plan::Core::M4;
                host_tests::plan::plan(
                    &wl,
                    host_tests::plan::Budget {
                        max_visibility_errors: 0,
                        depth_ram: core.default_depth_ram(s),
                        core,
                    },
                )
                .expect("the scene plans")
            })
            .collect();
    let mut marks: Vec<Vec<&str>> = vec![vec![]; combos.len()];
    for p in &plans {
        let key = if p.strategy == "fast-div" {
            "fast"
        } else {
            p.strategy.as_str()
        };
        let same = |c: &&Combo| c.format == p.format;
        if let Some(k) = combos
            .iter()
            .position(|c| same(&c) && c.board_key == Some(key))
            .or_else(|| combos.iter().position(|c| same(&c)))
        {
            marks[k].push(&p.scene);
        }
    }
    // plots
    let points: Vec<Point2> = combos
        .iter()
        .zip(&marks)
        .map(|(c, m)| Point2 {
            x: c.ns_px,
            y: err(c),
            label: format!("{} {}", c.format, c.strategy),
            pareto: c.pareto,
            mark: (!m.is_empty()).then(|| format!("plan: {}", m.join(", "))),
        })
        .collect();
    pareto_plot(
        &points,
        1e-9,
        "host ns per drawn pixel (median of 15; log)",
        "largest relative depth error over scenes and stiff suite (log); red = Pareto front",
        &dir.join("pareto.png"),
    );
    step_plot(&rows(), 10.0, 10000.0, &dir.join("step_10_10000.png"));
    // heat map: the chosen default (W16, lerp64 + 1 step) on the terrain scene, |decoded - exact| / d per pixel
    let terrain = &scenes[3];
    let (frame, codes, _, _) =
        render_lean::<PerPixel<DefaultRecip>>(terrain, &terrain.tris, Compare::Less);
    let rf = &terrain.reference[0];
    let (n, f) = (terrain.near as f64, terrain.far as f64);
    let heat: Vec<Option<f64>> = (0..codes.len())
        .map(|k| {
            (frame.writes[k] > 0 && rf.covered[k] && frame.px[k] == rf.px[k]).then(|| {
                let d = rf.depth[k] * f;
                (W16::decode(codes[k], n, f) - d).abs() / d
            })
        })
        .collect();
    let heat_max = heat.iter().flatten().cloned().fold(0.0, f64::max);
    heat_map(
        &heat,
        WIDTH as u32,
        HEIGHT as u32,
        1e-6,
        1e-1,
        2,
        "terrain, W16 + lerp64/1 NR: |decoded W - exact W| / W",
        &dir.join("terrain_error.png"),
    );

    // report.md
    let mut md = String::new();
    let _ = writeln!(md, "# Error against run time\n");
    let _ = writeln!(md, "Made by `cargo run --release -p host-tests --bin report` on {cpu} ({cores} threads). Host times are medians of 15 runs of the four standard scenes (the draw calls alone, into a checked host framebuffer), in ns per written pixel. Board figures: {board_note}; {cycles_note}. QEMU counts instructions, not cycles: the cycles are estimates.\n");
    let _ = writeln!(md, "Errors are against the f64 reference (same snapped vertices and rules, its own arithmetic). LSB: |code - the format's f64 encode of the exact depth|. Relative: |decoded depth - exact depth| / depth, which includes the format's own quantisation. Only pixels where both agree on the visible surface count towards the depth error; the others are counted as visibility or coverage differences. The stiff suite draws each triangle alone (`Always`), so it has no visibility differences.\n");
    let _ = writeln!(
        md,
        "## Pareto front (host time against largest relative error)\n"
    );
    let _ = writeln!(md, "| format | strategy | host ns/px | max rel. error | max LSB (scenes / stiff) | M4 instr/px | M4 est. cycles/px | M0 instr/px | M0 est. cycles/px |\n|---|---|---|---|---|---|---|---|---|");
    let mut front: Vec<&Combo> = combos.iter().filter(|c| c.pareto).collect();
    front.sort_by(|a, b| a.ns_px.total_cmp(&b.ns_px));
    for c in &front {
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} | {:.2e} | {} / {} | {} | {} | {} | {} |",
            c.format,
            c.strategy,
            c.ns_px,
            err(c),
            c.scenes.max_lsb,
            c.stiff.max_lsb,
            insn("M4", c.board_key),
            cycles("M4", c.board_key),
            insn("M0", c.board_key),
            cycles("M0", c.board_key)
        );
    }
    let _ = writeln!(md, "\n![error against run time](pareto.png)\n");
    let _ = writeln!(md, "## The scene planner's choices\n\nRinged in blue on the plot above: what `cargo run --release -p host-tests --bin plan -- <scene>` (M4, ranked by RAM) takes for each scene (and for `obj:host-tests/assets/links.obj`, two linked rings along a camera path), on the report's combination of the same format and tier (a plan without a depth buffer has no depth error to plot). `--measure` ranks by instructions on the board instead; the savings below use it.\n\n```");
    for p in &plans {
        let _ = writeln!(md, "{}", p.line());
    }
    let _ = writeln!(md, "```\n\n## What a plan saves\n");
    match std::fs::read_to_string(dir.join("savings.md")) {
        Ok(t) => {
            let _ = writeln!(md, "{t}");
        }
        Err(_) => {
            let _ = writeln!(md, "Not measured yet: `python3 boards/tools/savings.py` builds and runs each plan's firmware and the default build on the M4 and M0 boards and writes `report/savings.md`, which this section includes.\n");
        }
    }
    let _ = writeln!(md, "## Every combination\n");
    let _ = writeln!(md, "| format | strategy | host ns/px | scenes: max / mean LSB | scenes: max / mean rel. | visibility diffs | coverage diffs | stiff: max LSB | stiff: max rel. | stiff coverage diffs | M4 instr/px | M4 est. cycles/px | M0 instr/px | M0 est. cycles/px | Pareto |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in &combos {
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} | {} / {:.4} | {:.2e} / {:.2e} | {} | {} | {} | {:.2e} | {} | {} | {} | {} | {} | {} |",
            c.format,
            c.strategy,
            c.ns_px,
            c.scenes.max_lsb,
            c.scenes.mean_lsb(),
            c.scenes.max_rel,
            c.scenes.mean_rel(),
            c.scenes.visibility,
            c.scenes.coverage,
            c.stiff.max_lsb,
            c.stiff.max_rel,
            c.stiff.coverage,
            insn("M4", c.board_key),
            cycles("M4", c.board_key),
            insn("M0", c.board_key),
            cycles("M0", c.board_key),
            if c.pareto { "yes" } else { "" }
        );
    }
    let _ = writeln!(
        md,
        "\nScene pixels compared per combination: {}; stiff-suite pixels: {}.\n",
        combos[0].scenes.pixels, combos[0].stiff.pixels
    );
    let _ = writeln!(md, "## Step against distance (near 10, far 10000)\n\nMeasured steps (dots, from neighbouring codes) over the analytic limits of the precision notes in ARCHITECTURE.md (lines). `cargo run --release -p host-tests --bin precision -- --near 10 --far 10000` prints the numbers.\n\n![step against distance](step_10_10000.png)\n");
    let _ = writeln!(md, "## Terrain depth error of the exact tier (W16, lerp64 seed + 1 Newton-Raphson step)\n\nPer pixel, |decoded W - exact W| / W on a log scale from 1e-6 (blue) to 1e-1 (red); largest {heat_max:.2e}. This is the W16 quantisation itself (half a code is 0.5 / 65535 of W_far, so the relative error grows towards the eye, 0.0076 at W = 10): the reciprocal adds no code error on this scene (every pixel where it shows the reference's surface holds the exact code).\n\n![terrain error](terrain_error.png)\n");
    let _ = writeln!(md, "## Stiff suite\n");
    for c in &stiff {
        let _ = writeln!(
            md,
            "- {}: {} triangles, range [{}, {}], {}x{} frame",
            c.name,
            c.tris.len(),
            c.near,
            c.far,
            c.w,
            c.h
        );
    }
    std::fs::write(dir.join("report.md"), &md).unwrap();

    for c in &front {
        println!(
            "pareto format={} strategy=\"{}\" ns_px={:.2} max_rel={:.2e}",
            c.format,
            c.strategy,
            c.ns_px,
            err(c)
        );
    }
    println!(
        "report combos={} pareto={} out=report/report.md",
        combos.len(),
        pareto
    );
}
