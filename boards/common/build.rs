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
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("scenes.rs");
    std::fs::write(out, s).unwrap();
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../src");
}
