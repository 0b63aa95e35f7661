//! wraster on QEMU `microbit` (nRF51, Cortex-M0, 16 KiB RAM, thumbv6m-none-eabi), memory map in `memory.x`.
//!
//! The frame does not fit in RAM: every standard scene is rendered in 16 bands of 15 rows (a 320x15 colour band of
//! half a byte a pixel, `wraster_board::NibbleBand`, and a 320x15 W16 band: 12,000 bytes), triangles binned by rows (see `wraster-board`), with this core's default (`Fast`), then
//! the other strategies; one `bench` line per run over semihosting, exit 0; any error or panic exits non-zero.
//! `--features torus` builds W4 instead (the rotating torus through the mesh path, 40 bands of 6 rows whose colour is
//! a palette index a pixel, two to a byte: its 512 transformed vertices take 6 KiB of the 16, its row bins 1 KiB,
//! its plane cache 1,424 bytes, and the deepest stack of the run, 2.6 KiB, leaves 284 bytes free: `boards/tools/stackdepth.c`, which
//! CI runs on this build and fails under 256); `--features cull` adds the bounding-sphere cull's line and RV32's default strategy (`FastDivInt`).
//! Run: `cd boards/qemu-m0 && cargo run --release` (the runner in `.cargo/config.toml` adds `-icount shift=0`).
//!
//! Instructions are counted with SysTick on the 16 MHz core clock: one tick is exactly 62.5 instructions under
//! `-icount shift=0`, read around the draw calls only (not the clears, the hash or the printing).
//! These are instructions, not cycles: QEMU is not cycle-accurate.
#![no_std]
#![no_main]
// A plan build runs only its plans: the scene runners stay compiled but unused.
#![cfg_attr(feature = "plan", allow(dead_code, unused_imports))]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;
use wraster::recip::Fast;
#[cfg(not(feature = "torus"))]
use wraster::recip::SpanRecip;
#[cfg(not(any(feature = "size-probe", feature = "plan")))]
use wraster::recip::{Exact, FastDiv, PrevPixel};
#[cfg(not(feature = "torus"))]
use wraster_board::run_all_banded;
#[cfg(not(feature = "torus"))]
use wraster_board::Nibbles;
#[cfg(not(any(feature = "size-probe", feature = "torus")))]
use wraster_board::{run_scene_banded, SCENES};
use wraster_board::{SysTick, HEIGHT, WIDTH};
#[cfg(feature = "torus")]
use {
    wraster::mesh::Projected,
    wraster::scenes::torus::{TRIANGLES, VERTICES},
};

/// Rows per band of the standard scenes: 15 (16 bands; 30 of 8 rows before), their colour band holding each pixel's
/// slot in the scene's palette, two to a byte (`wraster_board::NibbleBand`; every standard scene has at most 13
/// colours): 12,000 bytes with the W16 band, where 8 rows of RGB565 took 10,240, the plane cache giving up the rest
/// (`SceneCache`). Measured (`--features size-probe`, default `Fast`), instructions for W1, W2, W3, terrain: 8 rows
/// of RGB565 and 86 cached triangles 1,774,619, 8,899,428, 13,448,682, 13,121,805 (commit 2124873); 12 rows of half
/// a byte and 86, 1,719,181, 8,335,556, 12,745,622, 12,582,244; 15 rows and 48, 1,703,433, 8,154,870, 12,370,936,
/// 12,602,683 (commit 406cbb0's draw code); 15 rows and 55, 1,703,183, 8,153,811, 12,334,061, 12,532,372. 12 rows with `--features coarse`, whose bound (one code per 8 pixels of
/// each row) takes the room 15 would need.
#[cfg(not(feature = "torus"))]
const BAND_ROWS: usize = if cfg!(feature = "coarse") { 12 } else { 15 };
/// With `--features torus` the 512 transformed vertices take 6 KiB, so the bands are 6 rows (40 bands, 4,800 bytes):
/// W4's colours are eight palette entries, so its colour band holds a palette index a pixel, two to a byte
/// (`wraster_board::NibbleBand`), not RGB565 (two bytes a pixel: 4 rows, 60 bands, 5,120 bytes). Taller bands set
/// up fewer triangles again, and the plane cache took the bytes left (`wraster_board::TORUS_CACHE`): W4's frame
/// (default `Fast`, commit 2124873's draw code, the same hash) 8,461,874 instructions with RGB565 in 4 rows and 38
/// cached triangles; 7,839,211 with a byte a pixel in 5 rows and 50; 7,597,535 with half a byte in 6 rows and 50
/// (7,564,325 with the later changes to the fills and the fast tier's runs, commit 22035f6).
/// The same firmware given more RAM (`memory.x` at 4M, run in QEMU's mps2-an386: the same instructions), 38 cached
/// triangles, `Fast` alone: 4 rows 8,396,060 a frame, 5 rows 7,907,768, 6 rows 7,576,783, 8 rows 7,145,757.
/// Again on commit a1d1c39 (`ONLY=torus`, all four strategies, `Fast`'s line), rows and cached triangles against
/// today's 6 and 50: 6 and 0 +25.9%, 6 and 70 -1.0%, 6 and 90 -1.2%; 8 and 0 +13.3%, 8 and 20 +1.8%, 8 and 50 -5.8%,
/// 8 and 70 -6.5%; 10 and 0 +6.0%. The cache is worth more than taller bands: 8 rows pay only with some 30 or more
/// triangles cached, and their 5.8% with 50 needs 1,600 bytes more than this RAM has (the deepest stack, 2,692 bytes,
/// is mostly the torus run's frame, 888, and the mesh draw's, 1,216, whose locals LLVM already overlaps).
#[cfg(feature = "torus")]
const BAND_ROWS: usize = 6;
const PIXELS: usize = WIDTH as usize * BAND_ROWS;
const _: () = assert!((HEIGHT as usize).is_multiple_of(BAND_ROWS));

/// The standard scenes' plane cache on this board: 55 triangles (1,540 bytes), what the 15-row bands leave with the
/// deepest stack 256 bytes from the statics (CI fails under 256: 260 free; with the band loop inline, 48 left 276).
/// With 8-row bands it held 86, which kept W3's triangles across the bands' edges (64, the other boards'
/// `SCENE_CACHE`, cost W3 0.9% and the terrain 1.9% more instructions there). In 15-row bands 55 against 48: W3
/// -0.3%, the terrain -0.6%. 64 with `--features coarse`, in 12-row bands beside its bound's 960 bytes (CI checks
/// that build's stack too).
#[cfg(not(feature = "torus"))]
type SceneCache = wraster::mesh::PlaneCache<
    {
        if cfg!(feature = "coarse") {
            64
        } else {
            55
        }
    },
>;

#[cfg(not(feature = "torus"))]
fn all<R: SpanRecip>(
    color: &mut [u8],
    depth: &mut [u16],
    cache: &mut SceneCache,
    counter: &mut SysTick,
) -> bool {
    run_all_banded::<R, Nibbles, _>(
        "qemu-m0",
        "m0",
        color,
        depth,
        &mut [],
        cache,
        counter,
        |line| hprintln!("{}", line),
    )
}

/// The cost of banding, measured on this core: every scene drawn again in bands of half the height (35 of 7 rows,
/// the last of 2); the extra instructions over the run in 16 bands, divided by the 19 extra bands, are what one band
/// costs (triangle setup repeated for triangles spanning both halves, the span walk restarted, the binning test).
#[cfg(not(any(feature = "size-probe", feature = "torus")))]
fn band_overhead(
    color: &mut [u8],
    depth: &mut [u16],
    cache: &mut SceneCache,
    counter: &mut SysTick,
) -> bool {
    let half = WIDTH as usize * BAND_ROWS / 2;
    fn run(
        scene: &wraster_board::SceneData,
        color: &mut [u8],
        depth: &mut [u16],
        cache: &mut SceneCache,
        counter: &mut SysTick,
    ) -> Result<wraster_board::Run, wraster::Error> {
        run_scene_banded::<Fast, Nibbles, _>(
            scene,
            color,
            depth,
            &mut [],
            cache,
            counter,
            |_, _| {},
        )
    }
    for scene in &SCENES {
        let r30 = run(scene, color, depth, cache, counter);
        let r60 = run(
            scene,
            &mut color[..half / 2],
            &mut depth[..half],
            cache,
            counter,
        );
        match (r30, r60) {
            (Ok(a), Ok(b)) if a.hash == b.hash => hprintln!(
                "band-overhead board=qemu-m0 scene={} bands={}/{} instructions={}/{} instr_per_extra_band={}",
                scene.name,
                a.bands,
                b.bands,
                a.instructions,
                b.instructions,
                (b.instructions as i64 - a.instructions as i64) / (b.bands - a.bands) as i64
            ),
            _ => {
                hprintln!("error board=qemu-m0 scene={} band-overhead run failed or differed", scene.name);
                return false;
            }
        }
    }
    true
}

/// W4's plane cache on this board (see `main`).
#[cfg(feature = "torus")]
type Cache = wraster::mesh::PlaneCache<{ wraster_board::TORUS_CACHE }>;

/// `--features torus`: W4 only (the rotating torus through the mesh path), with each strategy.
#[cfg(all(feature = "torus", not(feature = "plan")))]
#[entry]
fn main() -> ! {
    // Each pixel's slot in W4's palette, two to a byte (`wraster_board::TORUS_NIBBLES`): it hashes as its RGB565 colour.
    static mut COLOR: [u8; PIXELS / 2] = [0; PIXELS / 2];
    static mut DEPTH: [u16; PIXELS] = [0; PIXELS];
    static mut VERTS: [Projected; VERTICES] = [Projected {
        x: 0.0,
        y: 0.0,
        rhw: 0.0,
    }; VERTICES];
    // The row bins (`Rasterizer::bin_mesh`, a byte per triangle): each of the 40 bands sets up only the triangles
    // that can reach it.
    static mut BINS: [u8; TRIANGLES] = [0; TRIANGLES];
    // The plane cache (`wraster::mesh::PlaneCache`, 50 triangles, 1,424 bytes): a triangle reaching several bands
    // has its depth-grid values computed once a frame, not in each band. The same in the `cull` build: the stack
    // keeps 256 bytes free in both (`wraster_board::TORUS_CACHE`).
    static mut CACHE: Cache = Cache::new();
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut counter = SysTick::new(cp.SYST, 125, 2);
    // Out of line: one strategy's run at a time on the stack (measured by CI's `stack` line).
    #[inline(never)]
    fn torus<R: wraster::recip::SpanRecip>(
        color: &mut [u8],
        depth: &mut [u16],
        verts: &mut [Projected],
        bins: &mut [u8],
        cache: &mut Cache,
        counter: &mut SysTick,
    ) -> bool {
        wraster_board::run_torus_line_in::<R, wraster_board::Nibbles, _>(
            "qemu-m0",
            "m0",
            color,
            depth,
            &mut [],
            verts,
            bins,
            cache,
            counter,
            |line| hprintln!("{}", line),
        )
    }
    let ok = torus::<Fast>(COLOR, DEPTH, VERTS, BINS, CACHE, &mut counter);
    // `--features size-probe`: the default strategy only (profiles).
    #[cfg(not(feature = "size-probe"))]
    let ok = ok
        & torus::<FastDiv>(COLOR, DEPTH, VERTS, BINS, CACHE, &mut counter)
        & torus::<Exact>(COLOR, DEPTH, VERTS, BINS, CACHE, &mut counter)
        & torus::<PrevPixel>(COLOR, DEPTH, VERTS, BINS, CACHE, &mut counter);
    // RV32's default (`FastDivInt`: `FastDiv` with the integer mesh transform), for the hash test, in the `cull`
    // build: one more strategy in the torus build moved the other strategies' figures (this core's default +0.4%).
    #[cfg(feature = "cull")]
    let ok =
        ok & torus::<wraster::recip::FastDivInt>(COLOR, DEPTH, VERTS, BINS, CACHE, &mut counter);
    // `--features cull`: W4's build also measures the bounding-sphere cull (README: leaving work out at run time).
    // Out of line too: its frame is not under the torus runs' (the stack is as deep as in the build without it).
    #[cfg(feature = "cull")]
    #[inline(never)]
    fn cull(verts: &mut [Projected], counter: &mut SysTick) -> bool {
        wraster_board::cull_line("qemu-m0", "m0", verts, counter, |line| {
            hprintln!("{}", line)
        })
    }
    #[cfg(feature = "cull")]
    let ok = ok & cull(VERTS, &mut counter);
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[cfg(not(any(feature = "torus", feature = "plan")))]
#[entry]
fn main() -> ! {
    // Each pixel's slot in its scene's palette, two to a byte (`wraster_board::NibbleBand`).
    static mut COLOR: [u8; PIXELS / 2] = [0; PIXELS / 2];
    static mut DEPTH: [u16; PIXELS] = [0; PIXELS];
    // The plane cache of the standard scenes (`wraster::mesh::PlaneCache`, `SceneCache` above): a triangle reaching
    // several bands is set up once a frame where it has room.
    static mut CACHE: SceneCache = SceneCache::new();
    // The coarse bound of `--features coarse`: one code per 8 pixels of each band row (640 bytes).
    #[cfg(feature = "coarse")]
    static mut BOUND: [u16; wraster::bound_len(WIDTH as usize, BAND_ROWS)] =
        [0; wraster::bound_len(WIDTH as usize, BAND_ROWS)];
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut counter = SysTick::new(cp.SYST, 125, 2);
    #[cfg(not(feature = "size-probe"))]
    let ok = all::<Fast>(COLOR, DEPTH, CACHE, &mut counter);
    // `--features size-probe`: one strategy, the default unless the build-time `RECIP` names another
    // (`wraster_board::PROBE_RECIP`: boards/tools/cycles.py estimates each strategy's cycles so; not `f32-div`, which
    // this core would run in soft float). A constant: the firmware links only the strategy it runs.
    #[cfg(feature = "size-probe")]
    let ok = {
        use wraster::recip::{Exact, FastDiv, PrevPixel};
        use wraster_board::{
            PROBE_EXACT, PROBE_F32_DIV, PROBE_FAST_DIV, PROBE_PREV_PIXEL, PROBE_RECIP,
        };
        const _: () = assert!(
            PROBE_RECIP != PROBE_F32_DIV,
            "RECIP=f32-div: the M4 board only"
        );
        match PROBE_RECIP {
            PROBE_FAST_DIV => all::<FastDiv>(COLOR, DEPTH, CACHE, &mut counter),
            PROBE_EXACT => all::<Exact>(COLOR, DEPTH, CACHE, &mut counter),
            PROBE_PREV_PIXEL => all::<PrevPixel>(COLOR, DEPTH, CACHE, &mut counter),
            _ => all::<Fast>(COLOR, DEPTH, CACHE, &mut counter),
        }
    };
    // `--features coarse`: the default again with a coarse depth bound (`bound=coarse` lines), same hashes; drawn
    // the same way (list frames with the plane cache), so the two lines differ by the bound alone.
    #[cfg(feature = "coarse")]
    let ok = ok
        & run_all_banded::<Fast, Nibbles, _>(
            "qemu-m0",
            "m0",
            COLOR,
            DEPTH,
            BOUND,
            CACHE,
            &mut counter,
            |line| hprintln!("{}", line),
        );
    // `--features size-probe` runs the default strategy only (profiles, cycle estimates: boards/tools/cycles.py).
    #[cfg(not(feature = "size-probe"))]
    // The other strategies for the hash test (`FastDiv`, the M4's and RV32's default: its division is a library
    // call on this core, which has no divide instruction).
    let ok = ok
        & all::<FastDiv>(COLOR, DEPTH, CACHE, &mut counter)
        & all::<Exact>(COLOR, DEPTH, CACHE, &mut counter)
        & all::<PrevPixel>(COLOR, DEPTH, CACHE, &mut counter)
        & band_overhead(COLOR, DEPTH, CACHE, &mut counter);
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

/// `--features plan` (with `PLAN=<plan files>`): the planner's plans, each with only what it chose; the buffers are
/// sized from the plans (colour bands as tall as the tallest depth band, 8 rows when no plan keeps depth; the torus's
/// vertex store only when a plan draws it).
#[cfg(feature = "plan")]
mod plan_buffers {
    use wraster_board::{plans, WIDTH};
    const ROWS: usize = if plans::MAX_BAND_ROWS == 0 {
        8
    } else {
        plans::MAX_BAND_ROWS
    };
    pub const COLOR_LEN: usize = WIDTH as usize * ROWS;
    const _: () = assert!(
        plans::COUNT > 0,
        "--features plan needs PLAN=<file>,... (host-tests' plan binary writes them)"
    );
}
#[cfg(feature = "plan")]
use {
    plan_buffers::COLOR_LEN,
    wraster::mesh::Projected,
    wraster_board::plans::{self, BINS_LEN, DEPTH_LEN, VERTS_LEN},
};

#[cfg(feature = "plan")]
#[entry]
fn main() -> ! {
    static mut COLOR: [u16; COLOR_LEN] = [0; COLOR_LEN];
    static mut DEPTH: [u32; DEPTH_LEN] = [0; DEPTH_LEN];
    static mut VERTS: [Projected; VERTS_LEN] = [Projected {
        x: 0.0,
        y: 0.0,
        rhw: 0.0,
    }; VERTS_LEN];
    static mut BINS: [u8; BINS_LEN] = [0; BINS_LEN];
    // The plane cache of plans drawn in bands (as the default build's; empty where none is).
    static mut CACHE: wraster_board::plans::PlanCache = wraster_board::plans::PlanCache::new();
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut counter = SysTick::new(cp.SYST, 125, 2);
    let ok = plans::run_all_plans(
        "qemu-m0",
        "m0",
        COLOR,
        wraster_board::u16_words(DEPTH),
        VERTS,
        BINS,
        CACHE,
        &mut counter,
        &mut |a| hprintln!("{}", a),
    );
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}
