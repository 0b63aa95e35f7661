//! The main job: renders the terrain demo (W_near 10, W_far 10000), writes a PNG, measures the stored depth against
//! the f64 reference and the host time per frame, and ends with one line scripts read:
//! `demo scene=terrain pixels=<drawn> max_err_lsb=<..> mean_err_lsb=<..> frame_ms=<median> png=<path>`

use std::time::Instant;

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{reference_frame, reference_tri, render, Frame};
use wraster::format::{DepthFormat, W16, W16F, Z16};
use wraster::recip::{DefaultRecip, PerPixel};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::RenderState;

/// The winning triangle per pixel when the scene's depths are stored in format `F` and compared with Less, on the
/// f64 reference's coverage and exact per-pixel depth: the storage format is the only thing that differs.
/// (The rasterizer itself writes W16 only so far; this isolates what each format can resolve.)
fn winners<F: DepthFormat>(
    tris: &[[wraster::Vertex<Rgb565>; 3]],
    near: f32,
    far: f32,
) -> Vec<Option<usize>> {
    let n = WIDTH as usize * HEIGHT as usize;
    let (mut code, mut win) = (
        vec![F::encode(far as f64, near as f64, far as f64); n],
        vec![None; n],
    );
    let exact = F::NAME == "exact";
    let mut best = vec![f64::INFINITY; n];
    for (k, tri) in tris.iter().enumerate() {
        let v = tri.map(|q| (q.x, q.y, q.rhw));
        for p in reference_tri(&v, near, far, WIDTH as i32, 0..HEIGHT as i32).unwrap_or_default() {
            if !p.in_range {
                continue;
            }
            let i = p.y as usize * WIDTH as usize + p.x as usize;
            let d = far as f64 / p.t;
            let c = F::encode(d, near as f64, far as f64);
            let pass = if exact { d < best[i] } else { c < code[i] };
            if pass {
                code[i] = c;
                best[i] = d;
                win[i] = Some(k);
            }
        }
    }
    win
}

/// Exact f64 visibility (the nearest surface at each pixel), as a "format" for [`winners`].
struct Exact;
impl DepthFormat for Exact {
    const NAME: &'static str = "exact";
    const BYTES: usize = 4;
    const MAX_CODE: u32 = u32::MAX;
    fn encode(_d: f64, _n: f64, _f: f64) -> u32 {
        0
    }
    fn decode(_c: u32, _n: f64, f: f64) -> f64 {
        f
    }
    fn fraction(_c: u32, _n: f64, _f: f64) -> f64 {
        0.0
    }
}

/// The side-by-side: Z16, W16 and W16F panels, pixels whose visible surface differs from the f64 reference in
/// magenta; prints one `formats` line per format and returns the PNG path.
fn side_by_side(tris: &[[wraster::Vertex<Rgb565>; 3]], near: f32, far: f32) -> std::path::PathBuf {
    let truth = winners::<Exact>(tris, near, far);
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let mut out = Frame::new(3 * WIDTH as u32 + 8, HEIGHT as u32);
    let panels = [
        (Z16::NAME, winners::<Z16>(tris, near, far)),
        (W16::NAME, winners::<W16>(tris, near, far)),
        (W16F::NAME, winners::<W16F>(tris, near, far)),
    ];
    for (k, (name, win)) in panels.iter().enumerate() {
        let mut differ = 0;
        for i in 0..w * h {
            let c = if win[i] != truth[i] {
                differ += 1;
                Rgb565::MAGENTA
            } else {
                win[i].map_or(Rgb565::BLACK, |t| tris[t][0].color)
            };
            out.px[(i / w) * out.w as usize + k * (w + 4) + i % w] = c;
        }
        println!(
            "formats scene=terrain format={name} near={near} far={far} visibility_differs={differ}"
        );
    }
    let png = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/demo/formats.png");
    out.save_png(&png);
    png.canonicalize().unwrap_or(png)
}

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
    let formats_png = side_by_side(&tris, near, far);
    println!("formats png={}", formats_png.display());
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
