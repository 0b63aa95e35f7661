//! Nearly horizontal edges walked over hundreds of rows. Such an edge's row quotient (the column where its line
//! crosses the row) starts beyond the guard band and is clamped there at set-up (see `src/edge.rs`); it must stay
//! beyond it, neither overflowing `i32` nor walking back into the frame, which the walk ensures by setting the edges
//! up again every `Edge::rows_exact` rows. An edge rising 1/256 px over 8,000 px moves its crossing by
//! `8000 * 256 = 2^21` px a row (`B / |A|` with `|A| = 1`, `B` about `2^21` sub-pixels: the largest step inside the guard
//! band), so from the clamp at `2^30` a walk that never re-set its edges would overflow after `2^30 / 2^21 = 512`
//! rows (apex below the edge: the crossing moves away) or cross the frame after 512 rows (apex above: it moves
//! back). Each triangle here spans rows 1 to 1090 of a 16 x 1100 frame, so either failure shows: coverage must equal
//! the reference's pixel for pixel, drawn whole and in bands, in both tiers.

use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use host_tests::{reference_writes, render};
use wraster::recip::{Exact, Fast, SpanRecip};
use wraster::{Compare, RenderState, Vertex};

const W: u16 = 16;
const H: u16 = 1100;

fn tris() -> Vec<[Vertex<Rgb565>; 3]> {
    let v = |x, y| Vertex {
        x,
        y,
        z: 0.0,
        rhw: 0.01,
        color: Rgb565::GREEN,
    };
    let mut out = Vec::new();
    for (edge_y, apex_y) in [(1.0, 1090.0), (1090.0, 1.0)] {
        for rise in [1.0 / 256.0, -1.0 / 256.0] {
            let (a, b, c) = (v(-4000.0, edge_y), v(4000.0, edge_y + rise), v(8.0, apex_y));
            out.push([a, b, c]);
            out.push([b, a, c]);
        }
    }
    out
}

fn check<R: SpanRecip>() {
    let mut state = RenderState::new(10.0, 1000.0).unwrap();
    state.compare = Compare::Always;
    for (k, tri) in tris().iter().enumerate() {
        let (want, covered) = reference_writes(tri, 10.0, 1000.0, W as u32, H as u32);
        // Rows 1..1089, all 16 columns but near the apex: enough rows for either failure to show.
        assert!(covered > 16 * 1000, "triangle {k}: {covered} pixels");
        for band_h in [H, 100] {
            let (frame, _, _) =
                render::<R>(core::slice::from_ref(tri), state, W, H, band_h).unwrap();
            assert_eq!(frame.writes, want, "triangle {k}, bands of {band_h} rows");
        }
    }
}

#[test]
fn nearly_horizontal_edges_over_a_thousand_rows_cover_as_the_reference() {
    check::<Fast>();
    check::<Exact>();
}
