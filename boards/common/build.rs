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
        writeln!(s, "static {name}: [Tri; {}] = [", scene.len()).unwrap();
        for t in scene.tris() {
            let (r0, r1) =
                wraster::row_range(&t).expect("standard scenes are inside the guard band");
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
            "    SceneData {{ name: {:?}, near: f32::from_bits({:#x}), far: f32::from_bits({:#x}), tris: &{name} }},",
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
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("scenes.rs");
    std::fs::write(out, s).unwrap();
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../src");
}
