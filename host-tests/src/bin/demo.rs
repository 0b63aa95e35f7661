//! The main job: renders the terrain demo (W_near 10, W_far 10000), writes a PNG, measures the stored depth against
//! the f64 reference and the host time per frame, and ends with one line scripts read:
//! `demo scene=terrain pixels=<drawn> max_err_lsb=<..> mean_err_lsb=<..> frame_ms=<median> png=<path>`

use std::time::Instant;

use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{PrimitiveStyle, Rectangle};
use embedded_graphics::text::{Baseline, Text};
use host_tests::{reference_frame, render, render_format, Frame};
use wraster::format::{DepthFormat, W16, W16F, Z16};
use wraster::recip::{DefaultRecip, PerPixel};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::Codec;
use wraster::RenderState;

/// A distinct colour per triangle index, to tell which triangle a pixel shows.
fn id_color(k: usize) -> Rgb565 {
    let k = k as u16 + 1;
    Rgb565::new((k >> 11) as u8, ((k >> 5) & 63) as u8, (k & 31) as u8)
}

fn id_of(c: Rgb565) -> Option<usize> {
    let v = ((c.r() as u16) << 11) | ((c.g() as u16) << 5) | c.b() as u16;
    (v > 0).then(|| v as usize - 1)
}

/// The visible triangle per pixel when the rasterizer draws the scene into a buffer of format `F` (Less, the default
/// reciprocal; triangles coloured by index).
fn winners<F: Codec>(
    ids: &[[wraster::Vertex<Rgb565>; 3]],
    state: RenderState,
) -> Vec<Option<usize>> {
    let (frame, _, _) =
        render_format::<F, PerPixel<DefaultRecip>>(ids, state, WIDTH, HEIGHT).expect("scene draws");
    frame.px.iter().map(|&c| id_of(c)).collect()
}

/// The far scene: twelve billboards between W = 1500 and 9000, each with a second one 0.3% farther behind it,
/// offset so both show, the farther drawn first (so a format that cannot tell them apart shows the wrong one);
/// the terrain's range (near 10, far 10000). Z16 cannot separate them (its step at 5000 is about
/// 38 units), W16 can (0.15 units everywhere).
fn far_scene() -> Vec<[wraster::Vertex<Rgb565>; 3]> {
    let colors = [Rgb565::RED, Rgb565::BLUE, Rgb565::YELLOW, Rgb565::CYAN];
    let mut tris = Vec::new();
    for k in 0..12 {
        let (col, row) = ((k % 4) as f32, (k / 4) as f32);
        let w = 1500.0 + 650.0 * k as f32;
        let (x, y) = (10.0 + 78.0 * col, 12.0 + 76.0 * row);
        for (layer, (dx, dy, scale)) in [(14.0f32, 10.0f32, 1.003f32), (0.0, 0.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            let c = colors[(k + layer) % 4];
            let v = |px: f32, py: f32, dw: f32| {
                wraster::Vertex::new(x + dx + px, y + dy + py, (w + dw) * scale, c)
            };
            tris.push([v(0.0, 0.0, 0.0), v(52.0, 0.0, 40.0), v(52.0, 50.0, 60.0)]);
            tris.push([v(0.0, 0.0, 0.0), v(52.0, 50.0, 60.0), v(0.0, 50.0, 20.0)]);
        }
    }
    tris
}

/// One row of the side-by-side: Z16, W16 and W16F panels drawn by the rasterizer, pixels whose visible surface
/// differs from the f64 reference in magenta; prints one `formats` line per format.
fn side_by_side(
    name: &str,
    tris: &[[wraster::Vertex<Rgb565>; 3]],
    state: RenderState,
    out: &mut Frame,
    row: usize,
) {
    let (near, far) = (state.range.near(), state.range.far());
    let ids: Vec<_> = tris
        .iter()
        .enumerate()
        .map(|(k, t)| {
            t.map(|v| wraster::Vertex {
                color: id_color(k),
                ..v
            })
        })
        .collect();
    let truth: Vec<Option<usize>> = reference_frame(&ids, near, far, WIDTH as u32, HEIGHT as u32)
        .px
        .iter()
        .map(|&c| id_of(c))
        .collect();
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    let panels = [
        (Z16::NAME, winners::<Z16>(&ids, state)),
        (W16::NAME, winners::<W16>(&ids, state)),
        (W16F::NAME, winners::<W16F>(&ids, state)),
    ];
    for (k, (format, win)) in panels.iter().enumerate() {
        let mut differ = 0;
        for i in 0..w * h {
            let c = if win[i] != truth[i] {
                differ += 1;
                Rgb565::MAGENTA
            } else {
                win[i].map_or(Rgb565::BLACK, |t| tris[t][0].color)
            };
            out.px[(row * (h + 4) + i / w) * out.w as usize + k * (w + 4) + i % w] = c;
        }
        // The panel's label, white on black in its top-left corner: the format, the scene, the differing pixels.
        let label = format!("{format} ({name}): {differ} px differ");
        let at = Point::new((k * (w + 4)) as i32, (row * (h + 4)) as i32);
        Rectangle::new(at, Size::new(6 * label.len() as u32 + 4, 12))
            .into_styled(PrimitiveStyle::with_fill(Rgb565::BLACK))
            .draw(out)
            .expect("the frame takes any pixel");
        Text::with_baseline(
            &label,
            at + Point::new(2, 1),
            MonoTextStyle::new(&FONT_6X10, Rgb565::WHITE),
            Baseline::Top,
        )
        .draw(out)
        .expect("the frame takes any pixel");
        println!(
            "formats scene={name} format={format} near={near} far={far} visibility_differs={differ} source=rasterizer"
        );
    }
}

fn main() {
    let scene = Scene::Terrain;
    let tris: Vec<_> = scene.tris().collect();
    let (near, far) = scene.depth_range();
    let state = RenderState::new(near, far).expect("valid range");
    // The default strategy (the fast tier), as a firmware gets it.
    let (frame, depth, stats) =
        render::<wraster::recip::Fast>(&tris, state, WIDTH, HEIGHT, HEIGHT).expect("scene draws");

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
            let r = render::<wraster::recip::Fast>(&tris, state, WIDTH, HEIGHT, HEIGHT)
                .expect("scene draws");
            std::hint::black_box(&r);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);

    let png = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/demo/terrain.png");
    frame.save_png(&png);
    let png = png.canonicalize().unwrap_or(png);
    // The side-by-side: the terrain (near the eye) and the far scene, with Z16, W16 and W16F.
    let mut out = Frame::new(3 * WIDTH as u32 + 8, 2 * HEIGHT as u32 + 4);
    side_by_side("terrain", &tris, state, &mut out, 0);
    side_by_side("far", &far_scene(), state, &mut out, 1);
    let formats_png =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/demo/formats.png");
    out.save_png(&formats_png);
    let formats_png = formats_png.canonicalize().unwrap_or(formats_png);
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
