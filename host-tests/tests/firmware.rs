//! The same frames, bit for bit, on x86-64 and on the emulated Cortex-M4, Cortex-M0 and RV32 boards.
//!
//! Each QEMU board (boards/qemu-*) prints one `bench` line per scene and reciprocal strategy with a hash of its final
//! frame: FNV-1a 64 over the rows in order, each row's RGB565 colours (u16 little-endian) then its W16 depths (u16
//! little-endian). This test renders the same scenes here, whole-frame (the M0 board renders in 30 bands), hashes
//! them with its own FNV-1a, and asserts every board's hash and pixel counts equal the host's.
//!
//! The boards run under QEMU when it is installed; `.ci/run` installs it and sets `CI=true`, which makes QEMU
//! required (a missing emulator fails the test instead of skipping it).

use std::collections::HashMap;

use embedded_graphics::pixelcolor::IntoStorage;
use host_tests::{have, render, run_board};
use wraster::recip::{Exact, Fast, PrevPixel, SpanRecip};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::RenderState;

fn fnv1a(hash: &mut u64, words: impl IntoIterator<Item = u16>) {
    for w in words {
        for b in w.to_le_bytes() {
            *hash ^= b as u64;
            *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// `(scene, recip) -> (hash, written, fragments)` on the host.
fn host_runs<R: SpanRecip>(out: &mut HashMap<(String, String), (u64, u32, u32)>) {
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
        let w = WIDTH as usize;
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for row in 0..HEIGHT as usize {
            fnv1a(
                &mut h,
                frame.px[row * w..(row + 1) * w]
                    .iter()
                    .map(|c| c.into_storage()),
            );
            fnv1a(&mut h, depth[row * w..(row + 1) * w].iter().copied());
        }
        out.insert(
            (scene.name().into(), R::NAME.into()),
            (h, stats.written, stats.fragments),
        );
    }
}

#[test]
fn boards_render_the_hosts_frames_bit_for_bit() {
    let field = |line: &str, key: &str| -> String {
        host_tests::field(line, key)
            .unwrap_or_else(|| panic!("no {key}= in {line}"))
            .to_string()
    };
    let required = std::env::var("CI").is_ok_and(|v| v == "true");
    if !(have("qemu-system-arm") && have("qemu-system-riscv32")) {
        assert!(
            !required,
            "CI=true but QEMU is missing: .ci/run installs it"
        );
        eprintln!("skipped: qemu-system-arm / qemu-system-riscv32 not installed (see .ci/run)");
        return;
    }
    let mut host = HashMap::new();
    host_runs::<Fast>(&mut host);
    host_runs::<Exact>(&mut host);
    host_runs::<PrevPixel>(&mut host);

    for (board, bands) in [("qemu-m4", 1), ("qemu-m0", 30), ("qemu-rv32", 1)] {
        let stdout = run_board(board, &[]).unwrap_or_else(|e| panic!("{e}"));
        let mut seen = 0;
        for line in stdout.lines().filter(|l| l.starts_with("bench ")) {
            let key = (
                field(line, "scene").to_string(),
                field(line, "recip").to_string(),
            );
            let (hash, written, fragments) = host[&key];
            assert_eq!(field(line, "board"), board);
            assert_eq!(
                field(line, "hash"),
                format!("{hash:016x}"),
                "{board} {key:?}"
            );
            assert_eq!(
                field(line, "pixels").parse::<u32>().unwrap(),
                written,
                "{board} {key:?}"
            );
            assert_eq!(
                field(line, "fragments").parse::<u32>().unwrap(),
                fragments,
                "{board} {key:?}"
            );
            assert_eq!(
                field(line, "bands").parse::<u32>().unwrap(),
                bands,
                "{board} {key:?}"
            );
            println!("{line}");
            seen += 1;
        }
        assert_eq!(
            seen,
            host.len(),
            "{board} printed {seen} bench lines:\n{stdout}"
        );
    }
}
