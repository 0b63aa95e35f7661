//! The main job: renders the terrain demo (W_near 10, W_far 10000), writes a PNG, measures the stored depth against
//! the f64 reference and the host time per frame, and ends with one line scripts read:
//! `demo scene=terrain pixels=<drawn> max_err_lsb=<..> mean_err_lsb=<..> frame_ms=<median> png=<path>`

use std::time::Instant;

use host_tests::{reference_frame, render};
use wraster::recip::{DefaultRecip, PerPixel};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::RenderState;

fn main() {
    let scene = Scene::Terrain;
    let tris: Vec<_> = scene.tris().collect();
    let (near, far) = scene.depth_range();
    let state = RenderState::new(near, far).expect("valid range");
    let (frame, depth, stats) =
        render::<PerPixel<DefaultRecip>>(&tris, state, WIDTH, HEIGHT, HEIGHT).expect("scene draws");

    // Error: the final stored code against the reference's code of the visible surface, at every drawn pixel.
    let reference = reference_frame(&tris, near, far, WIDTH as u32, HEIGHT as u32);
    let (mut drawn, mut max_err, mut sum_err) = (0u64, 0i64, 0i64);
    for ((&d, &writes), &want) in depth.iter().zip(&frame.writes).zip(&reference.code) {
        if writes > 0 {
            drawn += 1;
            let e = (d as i64 - want as i64).abs();
            max_err = max_err.max(e);
            sum_err += e;
        }
    }

    // Cost: median of 31 whole frames (clear + draw), host time.
    let mut times: Vec<f64> = (0..31)
        .map(|_| {
            let t = Instant::now();
            let r = render::<PerPixel<DefaultRecip>>(&tris, state, WIDTH, HEIGHT, HEIGHT)
                .expect("scene draws");
            std::hint::black_box(&r);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);

    let png = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/demo/terrain.png");
    frame.save_png(&png);
    let png = png.canonicalize().unwrap_or(png);
    println!(
        "triangles={} fragments={} written={} culled={}",
        tris.len(),
        stats.fragments,
        stats.written,
        stats.culled
    );
    println!(
        "demo scene={} pixels={drawn} max_err_lsb={max_err} mean_err_lsb={:.6} frame_ms={:.3} png={}",
        scene.name(),
        sum_err as f64 / drawn.max(1) as f64,
        times[times.len() / 2],
        png.display()
    );
}
