//! wraster on QEMU `mps2-an386` (Cortex-M4F, thumbv7em-none-eabihf), memory map from the top-level `memory.x`.
//!
//! Renders every standard scene (or, with `--features torus`, W4's torus) (`wraster::scenes`, baked by `wraster-board`) whole-frame (320x240 colour and W16
//! depth in RAM, one band), with this core's default (`FastDiv`: the fast tier seeded by `UDIV`), then the table-seeded fast tier, the exact
//! tier and the previous-pixel seed (and, in W4's `cull` build, RV32's default `FastDivInt`), prints one `bench` line per
//! run over semihosting and exits 0; any error or panic exits non-zero.
//! Run: `cd boards/qemu-m4 && cargo run --release` (the runner in `.cargo/config.toml` adds `-icount shift=0`).
//!
//! Instructions are counted with SysTick on the 25 MHz core clock: one tick is exactly 40 instructions under
//! `-icount shift=0`, read around the draw calls only (not the clears, the hash or the printing).
//! These are instructions, not cycles: QEMU is not cycle-accurate.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;
use wraster::mesh::Projected;
#[cfg(not(any(feature = "size-probe", feature = "plan")))]
use wraster::recip::{Exact, Fast, PrevPixel};
#[cfg(not(feature = "plan"))]
use wraster::recip::{FastDiv, SpanRecip};
#[cfg(not(feature = "plan"))]
use wraster::scenes::torus::VERTICES;
#[cfg(not(any(feature = "torus", feature = "plan")))]
use wraster_board::run_all;
#[cfg(all(feature = "torus", not(feature = "plan")))]
use wraster_board::run_torus_line;
use wraster_board::{SysTick, HEIGHT, WIDTH};

const PIXELS: usize = WIDTH as usize * HEIGHT as usize;

#[cfg(not(feature = "plan"))]
fn all<R: SpanRecip>(
    color: &mut [u16],
    depth: &mut [u16],
    verts: &mut [Projected],
    counter: &mut SysTick,
) -> bool {
    // `--features torus` builds W4 alone: in one build with the standard scenes, the mesh path changes how LLVM
    // inlines the triangle path, and the standard scenes' figures with it.
    #[cfg(not(feature = "torus"))]
    {
        let _ = verts;
        run_all::<R, _>("qemu-m4", "m4", color, depth, counter, |line| {
            hprintln!("{}", line)
        })
    }
    #[cfg(feature = "torus")]
    // One band: nothing to bin (`&mut []`).
    run_torus_line::<R, _>(
        "qemu-m4",
        "m4",
        color,
        depth,
        verts,
        &mut [],
        &mut (), // one band: nothing to cache
        counter,
        |line| hprintln!("{}", line),
    )
}

#[cfg(not(feature = "plan"))]
#[entry]
fn main() -> ! {
    static mut COLOR: [u16; PIXELS] = [0; PIXELS];
    static mut DEPTH: [u16; PIXELS] = [0; PIXELS];
    // The coarse bound of `--features coarse`: one code per 8 pixels of each row.
    #[cfg(feature = "coarse")]
    static mut BOUND: [u16; wraster::bound_len(WIDTH as usize, HEIGHT as usize)] =
        [0; wraster::bound_len(WIDTH as usize, HEIGHT as usize)];
    static mut VERTS: [Projected; VERTICES] = [Projected {
        x: 0.0,
        y: 0.0,
        rhw: 0.0,
    }; VERTICES];
    let cp = cortex_m::Peripherals::take().unwrap();
    let mut counter = SysTick::new(cp.SYST, 40, 1);
    // This core's default: the fast tier seeded by its divide instruction.
    #[cfg(not(feature = "size-probe"))]
    let ok = all::<FastDiv>(COLOR, DEPTH, VERTS, &mut counter);
    // `--features size-probe`: one strategy, the default unless the build-time `RECIP` names another
    // (`wraster_board::PROBE_RECIP`: boards/tools/cycles.py estimates each strategy's cycles so). A constant: the
    // firmware links only the strategy it runs.
    #[cfg(feature = "size-probe")]
    let ok = {
        use wraster::recip::{Exact, F32Div, Fast, PerPixel, PrevPixel};
        use wraster_board::{
            PROBE_EXACT, PROBE_F32_DIV, PROBE_FAST, PROBE_PREV_PIXEL, PROBE_RECIP,
        };
        match PROBE_RECIP {
            PROBE_FAST => all::<Fast>(COLOR, DEPTH, VERTS, &mut counter),
            PROBE_EXACT => all::<Exact>(COLOR, DEPTH, VERTS, &mut counter),
            PROBE_PREV_PIXEL => all::<PrevPixel>(COLOR, DEPTH, VERTS, &mut counter),
            PROBE_F32_DIV => all::<PerPixel<F32Div>>(COLOR, DEPTH, VERTS, &mut counter),
            _ => all::<FastDiv>(COLOR, DEPTH, VERTS, &mut counter),
        }
    };
    // `--features size-probe` links the default path only, to measure the library's share of .text (README).
    // The other strategies run for the hash test: each strategy's frames agree across cores.
    #[cfg(not(feature = "size-probe"))]
    let ok = ok
        & all::<Fast>(COLOR, DEPTH, VERTS, &mut counter)
        & all::<Exact>(COLOR, DEPTH, VERTS, &mut counter)
        & all::<PrevPixel>(COLOR, DEPTH, VERTS, &mut counter);
    // W4's `cull` build also runs RV32's default (`FastDivInt`: `FastDiv` with the integer mesh transform) for the hash
    // test (in the torus build, one more strategy moved the others' figures: this core's default +0.3%); the standard
    // scenes are given in screen space, where it is `FastDiv`.
    #[cfg(all(feature = "cull", not(feature = "size-probe")))]
    let ok = ok & all::<wraster::recip::FastDivInt>(COLOR, DEPTH, VERTS, &mut counter);
    // `--features cull`: W4's build also measures the bounding-sphere cull (README: leaving work out at run time).
    #[cfg(feature = "cull")]
    let ok = ok
        & wraster_board::cull_line("qemu-m4", "m4", VERTS, &mut counter, |line| {
            hprintln!("{}", line)
        });
    // `--features coarse`: the default again with a coarse depth bound (`bound=coarse` lines), same hashes.
    #[cfg(all(feature = "coarse", feature = "torus"))]
    let ok = ok
        & wraster_board::run_torus_line_bounded::<FastDiv, _>(
            "qemu-m4",
            "m4",
            COLOR,
            DEPTH,
            BOUND,
            VERTS,
            &mut [],
            &mut (),
            &mut counter,
            |line| hprintln!("{}", line),
        );
    #[cfg(all(feature = "coarse", not(feature = "torus")))]
    let ok = ok
        & wraster_board::run_all_bounded::<FastDiv, _>(
            "qemu-m4",
            "m4",
            COLOR,
            DEPTH,
            BOUND,
            &mut counter,
            |line| hprintln!("{}", line),
        );
    // `--features f32-div` adds the f32-division reciprocal (one VDIV on this core), for comparison (README).
    #[cfg(feature = "f32-div")]
    let ok = ok
        & all::<wraster::recip::PerPixel<wraster::recip::F32Div>>(
            COLOR,
            DEPTH,
            VERTS,
            &mut counter,
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

/// `--features plan` (with `PLAN=<plan files>`): the planner's plans instead, each with only what it chose; the depth
/// buffer is sized from the plans (none when no plan keeps depth) and the torus's vertex store is there only when a
/// plan draws it, so `.bss` shows what a plan saves.
#[cfg(feature = "plan")]
use wraster_board::plans::{BINS_LEN, DEPTH_LEN, VERTS_LEN};
#[cfg(feature = "plan")]
const _: () = assert!(
    wraster_board::plans::COUNT > 0,
    "--features plan needs PLAN=<file>,... (host-tests' plan binary writes them)"
);

#[cfg(feature = "plan")]
#[entry]
fn main() -> ! {
    static mut COLOR: [u16; PIXELS] = [0; PIXELS];
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
    let mut counter = SysTick::new(cp.SYST, 40, 1);
    let ok = wraster_board::plans::run_all_plans(
        "qemu-m4",
        "m4",
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
