//! wraster on QEMU `virt` (RV32IMAC, riscv32imac-unknown-none-elf), memory map in `memory.x`.
//!
//! Renders every standard scene (or, with `--features torus`, W4's torus) whole-frame (320x240 colour and W16 depth in
//! RAM) with this core's default strategy, then the other cores' defaults and the other strategies, prints one `bench`
//! line per run over semihosting and exits 0; any error or panic exits non-zero. Run: `cd boards/qemu-rv32 && cargo run --release`.
//!
//! Instructions are the difference of the `minstret` CSR (instructions retired) around the draw calls only: exact.
#![no_std]
#![no_main]
#![forbid(unsafe_code)]

use riscv_rt::entry;
use riscv_semihosting::{debug, hprintln};
use wraster::mesh::Projected;
#[cfg(feature = "torus")]
use wraster::recip::FastDivInt;
use wraster::recip::{Exact, Fast, FastDiv, PrevPixel, SpanRecip};
use wraster::scenes::torus::VERTICES;
#[cfg(not(feature = "torus"))]
use wraster_board::run_all;
#[cfg(feature = "torus")]
use wraster_board::run_torus_line;
use wraster_board::{Counter, HEIGHT, WIDTH};

const PIXELS: usize = WIDTH as usize * HEIGHT as usize;

struct Minstret(u64);

impl Counter for Minstret {
    fn start(&mut self) {
        self.0 = riscv::register::minstret::read64();
    }
    fn stop(&mut self) -> u64 {
        riscv::register::minstret::read64() - self.0
    }
}

fn all<R: SpanRecip>(color: &mut [u16], depth: &mut [u16], verts: &mut [Projected]) -> bool {
    // `--features torus` builds W4 alone (as on the other boards: one build each keeps the figures comparable).
    #[cfg(not(feature = "torus"))]
    {
        let _ = verts;
        run_all::<R, _>(
            "qemu-rv32",
            "rv32",
            color,
            depth,
            &mut Minstret(0),
            |line| hprintln!("{}", line),
        )
    }
    #[cfg(feature = "torus")]
    run_torus_line::<R, _>(
        "qemu-rv32",
        "rv32",
        color,
        depth,
        verts,
        &mut [], // one band: nothing to bin
        &mut (), // nor to cache
        &mut Minstret(0),
        |line| hprintln!("{}", line),
    )
}

#[entry]
fn main() -> ! {
    // The frame lives on the stack (riscv-rt gives it the top of the 16 MiB RAM): no `static mut`, no unsafe.
    let (mut color, mut depth) = ([0u16; PIXELS], [0u16; PIXELS]);
    let mut verts = [Projected::default(); VERTICES];
    // This core's default first (RV32IM has DIVU and no FPU: the division-seeded fast tier, W4's meshes transformed in
    // integers, `FastDivInt`; the standard scenes are given in screen space, where it is `FastDiv`), then the others
    // for the hash test.
    #[cfg(feature = "torus")]
    let ok = all::<FastDivInt>(&mut color, &mut depth, &mut verts);
    #[cfg(not(feature = "torus"))]
    let ok = true;
    let ok = ok
        & all::<FastDiv>(&mut color, &mut depth, &mut verts)
        & all::<Fast>(&mut color, &mut depth, &mut verts)
        & all::<Exact>(&mut color, &mut depth, &mut verts)
        & all::<PrevPixel>(&mut color, &mut depth, &mut verts);
    // `--features cull`: W4's build also measures the bounding-sphere cull (README: leaving work out at run time).
    #[cfg(feature = "cull")]
    let ok = ok
        & wraster_board::cull_line("qemu-rv32", "rv32", &mut verts, &mut Minstret(0), |line| {
            hprintln!("{}", line)
        });
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        riscv::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        riscv::asm::wfi();
    }
}
