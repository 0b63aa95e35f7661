//! Golden frames: every strategy's frames of the standard scenes and W4, pinned by their hashes.
//!
//! The accuracy suites judge each strategy against the f64 reference within its derived bound, so an arithmetic
//! change that stays inside the bound (a rounding step moved by one unit, a seed one cell off) passes them; but each
//! strategy is a fixed function of its input, bit for bit the same on every core (the firmware test), and these are
//! its frames (tiny-skia's golden images, as hashes: FNV-1a 64 of the colour and W16 rows, [`hash_frame`]). They are
//! the hashes the QEMU boards print in their `bench` lines. A change that moves any bit of any frame fails here;
//! a deliberate one updates this table with the boards' new hashes, and says why in its commit. `fast-div-int`
//! (`FastDivInt`) draws as `fast-div` and transforms meshes as `fast`: its standard scenes (no transform) are
//! `fast-div`'s frames, and its W4 frames those of `fast` (whose draws round as `fast-div`'s on W4).
//!
//! [`hash_frame`]: host_tests::hash_frame

use std::collections::HashMap;

use host_tests::scene_hashes;
use wraster::recip::{Exact, Fast, FastDiv, FastDivInt, PrevPixel};

/// `(scene, strategy, hash, written, fragments)`.
const GOLDEN: &[(&str, &str, u64, u32, u32)] = &[
    ("big", "fast", 0x074855cf9c8ad5e0, 32235, 32235),
    ("big", "fast-div", 0x074855cf9c8ad5e0, 32235, 32235),
    ("big", "fast-div-int", 0x074855cf9c8ad5e0, 32235, 32235),
    ("big", "lerp64", 0x074855cf9c8ad5e0, 32235, 32235),
    ("big", "prev-pixel", 0x074855cf9c8ad5e0, 32235, 32235),
    ("overdraw", "fast", 0xf4a3302847958469, 83797, 248347),
    ("overdraw", "fast-div", 0xa32fb48357ec691e, 83797, 248347),
    (
        "overdraw",
        "fast-div-int",
        0xa32fb48357ec691e,
        83797,
        248347,
    ),
    ("overdraw", "lerp64", 0xf4a3302847958469, 83797, 248347),
    ("overdraw", "prev-pixel", 0x43359444c691b0c6, 83797, 248347),
    ("small", "fast", 0xc5a04b751a830aea, 36000, 36000),
    ("small", "fast-div", 0xcf6ead3fc2f33b11, 36000, 36000),
    ("small", "fast-div-int", 0xcf6ead3fc2f33b11, 36000, 36000),
    ("small", "lerp64", 0x9e32ee9a0f7f0a51, 36000, 36000),
    ("small", "prev-pixel", 0x9e32ee9a0f7f0a51, 36000, 36000),
    ("terrain", "fast", 0xb775bf05e2881a11, 56244, 70838),
    ("terrain", "fast-div", 0xb775bf05e2881a11, 56244, 70838),
    ("terrain", "fast-div-int", 0xb775bf05e2881a11, 56244, 70838),
    ("terrain", "lerp64", 0xb775bf05e2881a11, 56244, 70838),
    ("terrain", "prev-pixel", 0xb775bf05e2881a11, 56244, 70838),
    ("torus", "fast", 0xcf6cdd0d1dc65495, 147323, 152060),
    ("torus", "fast-div", 0x5dd7a2400c38913e, 147323, 152060),
    ("torus", "fast-div-int", 0xcf6cdd0d1dc65495, 147323, 152060),
    ("torus", "lerp64", 0xfa9f95e2bd2419c9, 147323, 152060),
    ("torus", "prev-pixel", 0x0794973605377561, 147323, 152060),
];

#[test]
fn every_strategy_renders_its_golden_frames() {
    let mut host = HashMap::new();
    scene_hashes::<Fast>(&mut host);
    scene_hashes::<FastDiv>(&mut host);
    scene_hashes::<Exact>(&mut host);
    scene_hashes::<PrevPixel>(&mut host);
    scene_hashes::<FastDivInt>(&mut host);
    let mut keys: Vec<_> = host.keys().cloned().collect();
    keys.sort();
    // The table's lines, for a deliberate update (`cargo test -p host-tests --test golden -- --nocapture`).
    for k in &keys {
        let (h, w, f) = host[k];
        println!("    (\"{}\", \"{}\", 0x{h:016x}, {w}, {f}),", k.0, k.1);
    }
    assert_eq!(GOLDEN.len(), host.len(), "every scene and strategy pinned");
    for &(scene, recip, hash, written, fragments) in GOLDEN {
        let got = host[&(scene.to_string(), recip.to_string())];
        assert_eq!(
            got,
            (hash, written, fragments),
            "{scene} {recip}: hash {:016x}, written {}, fragments {}",
            got.0,
            got.1,
            got.2
        );
    }
}
