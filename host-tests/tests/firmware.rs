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
use std::path::Path;
use std::process::Command;

use embedded_graphics::pixelcolor::IntoStorage;
use host_tests::render;
use wraster::recip::{DefaultRecip, PerPixel, PrevPixel, SpanRecip};
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

fn field<'a>(line: &'a str, key: &str) -> &'a str {
    line.split(' ')
        .find_map(|kv| kv.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key}= in {line}"))
}

fn have(cmd: &str) -> bool {
    Command::new(cmd)
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

#[test]
fn boards_render_the_hosts_frames_bit_for_bit() {
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
    host_runs::<PerPixel<DefaultRecip>>(&mut host);
    host_runs::<PrevPixel>(&mut host);

    let boards = Path::new(env!("CARGO_MANIFEST_DIR")).join("../boards");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    for (board, bands) in [("qemu-m4", 1), ("qemu-m0", 30), ("qemu-rv32", 1)] {
        // `cargo run` from the board's directory picks up its target and QEMU runner (.cargo/config.toml).
        let out = Command::new(&cargo)
            .args(["run", "--release", "--quiet"])
            .current_dir(boards.join(board))
            .env_remove("CARGO_TARGET_DIR")
            .output()
            .expect("cargo runs");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{board} failed: {}\n{stdout}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
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
