//! What a coarse depth bound could save, at best: `cargo run --release -p host-tests --bin coarse -- <overdraw|torus|...>`.
//!
//! A coarse bound keeps the largest stored code per region (the whole band, a row, an 8x8 tile) and rejects a
//! triangle, or the part of a span in a region, whose nearest code is at or behind it (`Less` fails for every one of
//! its pixels) before any per-pixel work. This measures the best any such bound could do: it draws the scene with
//! the W16 lean path (fast tier, `Less`) and, before each triangle, takes the *exact* largest stored code of each
//! region (an oracle: a real bound kept as the buffer is written can only be larger, as a write that lowers the
//! region's largest code cannot lower the bound without reading the region again) and the triangle's own codes
//! (drawn alone), and counts the fragments each granularity would have rejected. Prints one line per granularity,
//! and `tile8-kept`: the bound a rasterizer can keep, lowered to a triangle's largest code in a tile it covers whole;
//! then, last, `coarse scene=.. fragments=.. failing=.. band_rejects=.. row_rejects=.. tile8_rejects=.. tile8_kept_rejects=..`.
use host_tests::plan::workload;
use host_tests::Frame;
use wraster::recip::Fast;
use wraster::{Compare, DepthBuffer, Rasterizer, RenderState};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = std::env::args()
        .nth(1)
        .ok_or("usage: coarse <big|overdraw|small|terrain|torus>")?;
    let wl = workload(&scene)?;
    let (w, h) = (wl.w as usize, wl.h as usize);
    let (mut fragments, mut failing, mut band, mut row, mut tile) = (0u64, 0u64, 0u64, 0u64, 0u64);
    // The kept bound: per 8x8 tile, lowered to a triangle's largest code in the tile when the triangle covers the
    // whole tile (every pixel then holds at most that code), never read back from the buffer.
    let mut kept = 0u64;
    let (tw, th) = (w.div_ceil(8), h.div_ceil(8));
    for tris in &wl.frames {
        let mut depth = vec![0u16; w * h];
        let mut buf = DepthBuffer::new(&mut depth, wl.w, wl.h)?;
        buf.clear();
        let mut frame = Frame::new(w as u32, h as u32);
        let mut r = Rasterizer::<Fast>::new(wl.state);
        let mut alone_state: RenderState = wl.state;
        alone_state.compare = Compare::Always;
        let mut alone = Rasterizer::<Fast>::new(alone_state);
        let mut tbound = vec![u16::MAX; tw * th];
        for t in tris {
            // The triangle's codes, drawn alone into a cleared buffer.
            let mut own = vec![0u16; w * h];
            let mut obuf = DepthBuffer::new(&mut own, wl.w, wl.h)?;
            obuf.clear();
            let mut of = Frame::new(w as u32, h as u32);
            alone.draw(&mut of, &mut obuf, t)?;
            let stored = buf.data();
            let covered: Vec<usize> = (0..w * h).filter(|&k| of.writes[k] > 0).collect();
            let fails = covered.iter().filter(|&&k| own[k] >= stored[k]).count() as u64;
            fragments += covered.len() as u64;
            failing += fails;
            // Band (the whole frame: the M4's one band): the triangle's nearest code against the largest stored.
            let max_all = stored.iter().copied().max().unwrap_or(0);
            let nearest = covered.iter().map(|&k| own[k]).min().unwrap_or(u16::MAX);
            if nearest >= max_all {
                band += covered.len() as u64;
            }
            // Rows: each span (the covered pixels of a row) against its row's largest stored code.
            for y in 0..h {
                let span: Vec<usize> = (y * w..(y + 1) * w).filter(|&k| of.writes[k] > 0).collect();
                if span.is_empty() {
                    continue;
                }
                let rmax = stored[y * w..(y + 1) * w]
                    .iter()
                    .copied()
                    .max()
                    .unwrap_or(0);
                if span.iter().all(|&k| own[k] >= rmax) {
                    row += span.len() as u64;
                }
                // 8x8 tiles: each span's part in a tile against the tile's largest stored code.
                for tx in 0..w.div_ceil(8) {
                    let part: Vec<usize> = span
                        .iter()
                        .copied()
                        .filter(|&k| (k % w) / 8 == tx)
                        .collect();
                    if part.is_empty() {
                        continue;
                    }
                    let (ty, x0) = (y / 8 * 8, tx * 8);
                    let tmax = (ty..(ty + 8).min(h))
                        .flat_map(|yy| {
                            stored[yy * w + x0..yy * w + (x0 + 8).min(w)]
                                .iter()
                                .copied()
                        })
                        .max()
                        .unwrap_or(0);
                    if part.iter().all(|&k| own[k] >= tmax) {
                        tile += part.len() as u64;
                    }
                    if part.iter().all(|&k| own[k] >= tbound[(y / 8) * tw + tx]) {
                        kept += part.len() as u64;
                    }
                }
            }
            r.draw(&mut frame, &mut buf, t)?;
            for ty in 0..th {
                for tx in 0..tw {
                    let px: Vec<usize> = (ty * 8..(ty * 8 + 8).min(h))
                        .flat_map(|yy| (tx * 8..(tx * 8 + 8).min(w)).map(move |xx| yy * w + xx))
                        .collect();
                    if px.iter().all(|&k| of.writes[k] > 0) {
                        let m = px.iter().map(|&k| own[k]).max().unwrap_or(u16::MAX);
                        let b = &mut tbound[ty * tw + tx];
                        *b = (*b).min(m);
                    }
                }
            }
        }
    }
    let pct = |n: u64| 100.0 * n as f64 / fragments.max(1) as f64;
    println!("scene {scene}: {} frame(s), {fragments} fragments, {failing} failing the depth test ({:.1}%)", wl.frames.len(), pct(failing));
    for (name, n) in [
        ("band", band),
        ("row", row),
        ("tile8", tile),
        ("tile8-kept", kept),
    ] {
        println!("granularity={name} rejected_fragments={n} ({:.1}% of fragments, {:.1}% of the failing ones)", pct(n), 100.0 * n as f64 / failing.max(1) as f64);
    }
    println!("coarse scene={} fragments={fragments} failing={failing} band_rejects={band} row_rejects={row} tile8_rejects={tile} tile8_kept_rejects={kept}", wl.name);
    Ok(())
}
