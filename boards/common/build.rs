//! Bakes wraster's standard scenes into a Rust source of constant data (f32 bit patterns, so the firmware gets the
//! exact vertices the host draws), with each triangle's row range for binning into bands.

use std::fmt::Write as _;

use embedded_graphics_core::pixelcolor::IntoStorage;
use wraster::scenes::Scene;

fn main() {
    let mut s = String::new();
    let mut list = String::new();
    for scene in Scene::ALL {
        let name = scene.name().to_uppercase();
        let (near, far) = scene.depth_range();
        let palette = nibble_palette(scene.tris().map(|t| t[0].color.into_storage()));
        writeln!(s, "static {name}: [Tri; {}] = [", scene.len()).unwrap();
        for t in scene.tris() {
            let (r0, r1) =
                wraster::row_range(&t).expect("standard scenes are inside the guard band");
            // The standard scenes lie in the frame: rows from 0, `u16` (4 bytes a triangle less flash).
            let rows =
                |r: i32| u16::try_from(r).expect("the standard scenes' rows lie in the frame");
            let (r0, r1) = (rows(r0), rows(r1));
            let v: Vec<String> = t
                .iter()
                .map(|q| {
                    format!(
                        "[{:#x}, {:#x}, {:#x}]",
                        q.x.to_bits(),
                        q.y.to_bits(),
                        q.rhw.to_bits()
                    )
                })
                .collect();
            writeln!(
                s,
                "    Tri {{ v: [{}], color: {:#06x}, rows: ({r0}, {r1}) }},",
                v.join(", "),
                t[0].color.into_storage()
            )
            .unwrap();
        }
        writeln!(s, "];").unwrap();
        writeln!(
            list,
            "    SceneData {{ name: {:?}, near: f32::from_bits({:#x}), far: f32::from_bits({:#x}), tris: &{name}, palette: {palette} }},",
            scene.name(),
            near.to_bits(),
            far.to_bits()
        )
        .unwrap();
    }
    writeln!(s, "/// The standard scenes, in wraster::scenes::Scene::ALL order.\npub static SCENES: [SceneData; {}] = [\n{list}];", Scene::ALL.len()).unwrap();
    // W4: the torus mesh (positions as f32 bit patterns, so the firmware draws the host's exact vertices).
    use wraster::scenes::torus;
    let pos: Vec<String> = torus::positions()
        .iter()
        .map(|p| {
            let b = p.map(|c| format!("f32::from_bits({:#x})", c.to_bits()));
            format!("[{}]", b.join(", "))
        })
        .collect();
    let idx: Vec<String> = torus::indices().iter().map(|t| format!("{t:?}")).collect();
    let col: Vec<String> = torus::colors()
        .iter()
        .map(|c| {
            let v = c.into_storage();
            format!("Rgb565::new({}, {}, {})", v >> 11, (v >> 5) & 63, v & 31)
        })
        .collect();
    writeln!(
        s,
        "/// W4's torus positions (wraster::scenes::torus).\npub static TORUS_POSITIONS: [[f32; 3]; {}] = [{}];",
        pos.len(),
        pos.join(", ")
    )
    .unwrap();
    writeln!(
        s,
        "/// W4's torus triangles.\npub static TORUS_INDICES: [[u16; 3]; {}] = [{}];",
        idx.len(),
        idx.join(", ")
    )
    .unwrap();
    writeln!(
        s,
        "/// W4's torus face colours.\npub static TORUS_COLORS: [Rgb565; {}] = [{}];",
        col.len(),
        col.join(", ")
    )
    .unwrap();
    writeln!(
        s,
        "/// W4's colours as a nibble palette ([`NibbleBand`]).\npub static TORUS_NIBBLES: NibblePalette = {};",
        nibble_palette(torus::colors().iter().map(|c| c.into_storage()))
    )
    .unwrap();
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("scenes.rs");
    std::fs::write(out, s).unwrap();
    plans();
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../src");
}

/// A scene's colours (RGB565) as a `NibblePalette`: the background 0 and every colour, each at slot
/// `(c * k) >> 28` for the first multiplier `k` (odd, from a fixed sequence) that puts no two in one slot (0 goes to
/// slot 0 whatever `k`). Panics for a scene of more than 15 colours besides the background, or one that uses 0.
fn nibble_palette(colors: impl Iterator<Item = u16>) -> String {
    let mut distinct: Vec<u16> = colors.collect();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(!distinct.contains(&0), "a scene colour is the background's");
    assert!(
        distinct.len() <= 15,
        "{} colours do not fit a nibble",
        distinct.len()
    );
    let mut k = 0x9e37_79b9u32;
    loop {
        let mut slots = [None::<u16>; 16];
        slots[0] = Some(0);
        let fits = distinct.iter().all(|&c| {
            let i = ((c as u32).wrapping_mul(k) >> 28) as usize;
            slots[i].replace(c).is_none()
        });
        if fits {
            let colors: Vec<String> = slots
                .iter()
                .map(|c| format!("{:#06x}", c.unwrap_or(0)))
                .collect();
            return format!(
                "NibblePalette {{ colors: [{}], k: {k:#x} }}",
                colors.join(", ")
            );
        }
        k = k.wrapping_mul(0x2c1b_3c6d).wrapping_add(0x297a_2d39) | 1;
    }
}

/// The plans named by `PLAN` (comma-separated files written by host-tests' `plan` binary), each in a module `pN`,
/// with `COUNT`, the largest depth RAM and band height among them, whether one draws the torus, and
/// `run_all_plans`, which runs each with its own format, strategy and depth path (nothing else is linked).
fn plans() {
    println!("cargo:rerun-if-env-changed=PLAN");
    let files: Vec<String> = std::env::var("PLAN")
        .map(|v| {
            v.split(',')
                .filter(|f| !f.is_empty())
                .map(String::from)
                .collect()
        })
        .unwrap_or_default();
    let mut s = String::new();
    let mut calls = String::new();
    let (mut ram, mut rows, mut torus, mut banded) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, f) in files.iter().enumerate() {
        let path = std::fs::canonicalize(f).unwrap_or_else(|e| panic!("PLAN file {f}: {e}"));
        println!("cargo:rerun-if-changed={}", path.display());
        writeln!(
            s,
            "/// Plan {k}: `{}`.\npub mod p{k} {{\n    include!({:?});\n}}",
            path.display(),
            path.display()
        )
        .unwrap();
        writeln!(
            calls,
            "    ok &= crate::run_plan_line::<p{k}::PlanFormat, p{k}::PlanStrategy, C, {{ p{k}::PLAN_KIND }}, {{ p{k}::PLAN_SCENE }}>(board, core, &p{k}::PLAN, color, depth, verts, bins, cache, counter, &mut *print);"
        )
        .unwrap();
        ram.push(format!("p{k}::PLAN.depth_ram"));
        rows.push(format!("if p{k}::PLAN_KIND == crate::NO_DEPTH {{ 0 }} else {{ p{k}::PLAN.band_rows as usize }}"));
        torus.push(format!("p{k}::PLAN_SCENE == crate::TORUS_SCENE"));
        banded.push(format!(
            "(p{k}::PLAN_KIND == crate::LEAN_W16 && p{k}::PLAN.band_rows < crate::HEIGHT)"
        ));
    }
    let max = |v: &[String]| {
        v.iter()
            .fold("0".to_string(), |acc, x| format!("max({acc}, {x})"))
    };
    writeln!(
        s,
        "#[allow(dead_code)]\nconst fn max(a: usize, b: usize) -> usize {{ if a > b {{ a }} else {{ b }} }}"
    )
    .unwrap();
    writeln!(
        s,
        "/// Plans baked in.\npub const COUNT: usize = {};",
        files.len()
    )
    .unwrap();
    writeln!(
        s,
        "/// The largest depth RAM a plan needs, in bytes.\npub const MAX_DEPTH_RAM: usize = {};",
        max(&ram)
    )
    .unwrap();
    writeln!(s, "/// The most rows a plan's depth band has (0: no plan keeps a depth buffer).\npub const MAX_BAND_ROWS: usize = {};", max(&rows)).unwrap();
    writeln!(s, "/// Whether a plan draws W4's torus (its vertices need RAM).\npub const HAS_TORUS: bool = false{};", torus.iter().map(|t| format!(" || {t}")).collect::<String>()).unwrap();
    writeln!(
        s,
        "/// The `u32` words of depth storage a board gives the plans (4-byte words, so that a 4-byte format's buffer is\n/// aligned; [`crate::u16_words`] lends them as `u16`s).\npub const DEPTH_LEN: usize = MAX_DEPTH_RAM.div_ceil(4);\n/// The transformed vertices a board stores for the plans (the torus's, or none).\npub const VERTS_LEN: usize = if HAS_TORUS {{ wraster::scenes::torus::VERTICES }} else {{ 0 }};\n/// The row bins a board stores for the plans (a byte per torus triangle, or none).\npub const BINS_LEN: usize = if HAS_TORUS {{ wraster::scenes::torus::TRIANGLES }} else {{ 0 }};"
    )
    .unwrap();
    writeln!(
        s,
        "/// Whether a plan draws W16 in more than one band (with a plane cache, as the default build).\npub const BANDED: bool = false{};\n/// The plans' plane cache: [`crate::PLAN_TORUS_CACHE`] where a plan draws the torus (its vertices take the RAM),\n/// else the standard scenes' [`crate::SCENE_CACHE`]; none where no plan draws in bands.\npub const CACHE_LEN: usize = if !BANDED {{ 0 }} else if HAS_TORUS {{ crate::PLAN_TORUS_CACHE }} else {{ crate::SCENE_CACHE }};\n/// The plans' plane cache.\npub type PlanCache = wraster::mesh::PlaneCache<CACHE_LEN>;",
        banded.iter().map(|t| format!(" || {t}")).collect::<String>()
    )
    .unwrap();
    writeln!(
        s,
        "/// Runs every plan, printing its `bench` line; `false` when one failed.\n#[allow(unused_variables, unused_mut, clippy::let_and_return, clippy::too_many_arguments)]\npub fn run_all_plans<C: crate::Counter>(board: &str, core: &str, color: &mut [u16], depth: &mut [u16], verts: &mut [wraster::mesh::Projected], bins: &mut [u8], cache: &mut PlanCache, counter: &mut C, print: &mut dyn FnMut(core::fmt::Arguments<'_>)) -> bool {{\n    let mut ok = true;\n{calls}    ok\n}}"
    )
    .unwrap();
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("plans.rs");
    std::fs::write(out, s).unwrap();
}
