//! The same frames, bit for bit, on x86-64 and on the emulated Cortex-M4, Cortex-M0 and RV32 boards.
//!
//! Each QEMU board (boards/qemu-*) prints one `bench` line per scene and reciprocal strategy with a hash of its final
//! frame: FNV-1a 64 over the rows in order, each row's RGB565 colours (u16 little-endian) then its W16 depths (u16
//! little-endian). This test renders the same scenes here, whole-frame (the M0 board renders in 16 bands), hashes
//! them with its own FNV-1a, and asserts every board's hash and pixel counts equal the host's. W4 (the torus, 8
//! frames through the mesh path) has one hash over its 8 frames; each board runs it in a build of its own
//! (`--features torus`), and RV32's default for it (`FastDivInt`) also in the M4's and M0's `--features cull` builds.
//!
//! The boards run under QEMU (`.ci/run` installs it). Without QEMU the test fails, unless `WRASTER_SKIP_FIRMWARE=1`
//! says to skip it: a test that cannot run never reports "ok" by itself.

use std::collections::HashMap;

use host_tests::{have, run_board, scene_hashes};
use wraster::recip::{Exact, Fast, FastDiv, FastDivInt, PrevPixel, SpanRecip};

#[test]
fn boards_render_the_hosts_frames_bit_for_bit() {
    let field = |line: &str, key: &str| -> String {
        host_tests::field(line, key)
            .unwrap_or_else(|| panic!("no {key}= in {line}"))
            .to_string()
    };
    // A test that cannot run fails, unless told to skip: WRASTER_SKIP_FIRMWARE=1 (a machine without QEMU, knowingly).
    if !(have("qemu-system-arm") && have("qemu-system-riscv32")) {
        let skip = std::env::var("WRASTER_SKIP_FIRMWARE").is_ok_and(|v| v == "1");
        assert!(
            skip,
            "QEMU (qemu-system-arm, qemu-system-riscv32) is missing: install it (.ci/run shows how) or set \
             WRASTER_SKIP_FIRMWARE=1 to skip the firmware runs"
        );
        eprintln!("skipped (WRASTER_SKIP_FIRMWARE=1): QEMU not installed");
        return;
    }
    let mut host = HashMap::new();
    scene_hashes::<Fast>(&mut host);
    scene_hashes::<FastDiv>(&mut host);
    scene_hashes::<Exact>(&mut host);
    scene_hashes::<PrevPixel>(&mut host);
    // RV32's default: `FastDiv` with the integer mesh transform. The standard scenes are given in screen space (no
    // transform): the boards run it on W4 only.
    scene_hashes::<FastDivInt>(&mut host);

    // Each board builds the standard scenes (four strategies), and W4 with `--features torus` (on the M0, 40 bands of
    // palette indices, hashed as their RGB565 colours: its vertex store takes 6 KiB of the 16): the four, and on RV32 its default `FastDivInt` too, which the M4 and
    // M0 run in their `cull` builds.
    let std_lines = host
        .keys()
        .filter(|(s, r)| s != "torus" && r != FastDivInt::NAME)
        .count();
    for (board, features, bands, lines) in [
        ("qemu-m4", &[][..], 1, std_lines),
        ("qemu-m4", &["torus"][..], 1, 4),
        ("qemu-m4", &["cull"][..], 1, 5),
        ("qemu-m0", &[][..], 16, std_lines),
        ("qemu-m0", &["torus"][..], 40, 4),
        ("qemu-m0", &["cull"][..], 40, 5),
        ("qemu-rv32", &[][..], 1, std_lines),
        ("qemu-rv32", &["torus"][..], 1, 5),
    ] {
        let stdout = run_board(board, features).unwrap_or_else(|e| panic!("{e}"));
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
            seen, lines,
            "{board} {features:?} printed {seen} bench lines:\n{stdout}"
        );
    }
}
