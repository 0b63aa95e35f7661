//! Host time of the standard scenes (W1-W3 of the README's standard scenes and the terrain demo): a depth clear and
//! the draw calls, into a host framebuffer that checks every write. Throughput is per written pixel for
//! big/overdraw/terrain and per triangle for small.
//! `cargo bench -p host-tests --bench raster`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use host_tests::Frame;
use wraster::recip::{Exact, Fast, PrevPixel, SpanRecip};
use wraster::scenes::{Scene, HEIGHT, WIDTH};
use wraster::{DepthStore, Rasterizer, RenderState};

fn draw_scene<R: SpanRecip>(
    scene: Scene,
    frame: &mut Frame,
    depth: &mut DepthStore<320, 240>,
) -> u32 {
    let (n, f) = scene.depth_range();
    let mut r = Rasterizer::<R>::new(RenderState::new(n, f).unwrap());
    let mut view = depth.view();
    view.clear();
    let mut written = 0;
    for t in scene.tris() {
        written += r.draw(frame, &mut view, &t).unwrap().written;
    }
    written
}

fn scenes(c: &mut Criterion) {
    let mut frame = Frame::new(WIDTH as u32, HEIGHT as u32);
    let mut depth = Box::new(DepthStore::<320, 240>::new());
    let mut g = c.benchmark_group("scene");
    for scene in Scene::ALL {
        let written = draw_scene::<Fast>(scene, &mut frame, &mut depth);
        println!(
            "scene={} triangles={} written={written}",
            scene.name(),
            scene.len()
        );
        g.throughput(Throughput::Elements(if scene == Scene::Small {
            scene.len() as u64
        } else {
            written as u64
        }));
        g.bench_with_input(BenchmarkId::new("fast", scene.name()), &scene, |b, &s| {
            b.iter(|| draw_scene::<Fast>(s, &mut frame, &mut depth))
        });
        g.bench_with_input(BenchmarkId::new("exact", scene.name()), &scene, |b, &s| {
            b.iter(|| draw_scene::<Exact>(s, &mut frame, &mut depth))
        });
        g.bench_with_input(
            BenchmarkId::new("prev-pixel", scene.name()),
            &scene,
            |b, &s| b.iter(|| draw_scene::<PrevPixel>(s, &mut frame, &mut depth)),
        );
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = scenes
}
criterion_main!(benches);
