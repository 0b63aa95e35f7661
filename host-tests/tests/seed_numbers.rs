//! The source documents' quantitative claims about Z and W depth, recomputed in f64 from the projection's definitions
//! (part of the depth issue). The Z mapping is Direct3D's `[0, 1]` one, `Z(d) = f / (f - n) * (1 - n / d)` for eye
//! depth `d` (Rogers's `D3DUtil_SetProjectionMatrix`: `Q = f / (f - n)`, `z' = Q d - Q n`, `Z = z' / d`).
//! Tolerances are the documents' printed precision (six decimals: half a unit in the last place) plus f64 rounding.

fn z(n: f64, f: f64, d: f64) -> f64 {
    f / (f - n) * (1.0 - n / d)
}

/// Half a unit in the sixth decimal: the seed's tables print six.
const SIX_DECIMALS: f64 = 0.5e-6 + 1e-12;

/// Dunlop, "Linear Depth", near 10 / far 10000: Z at 100, 500, 1000 and far; and the linear-Z trick
/// (`vPos.z = vPos.z * vPos.w / Far`), whose output is `Z * d / f = (d - n) / (f - n)`, at 100, 500, 1000, 5000 and far.
#[test]
fn seed_004_tables() {
    let (n, f) = (10.0, 10000.0);
    for (d, want) in [
        (10.0, 0.0),
        (100.0, 0.900901),
        (500.0, 0.980981),
        (1000.0, 0.990991),
        (10000.0, 1.0),
    ] {
        assert!(
            (z(n, f, d) - want).abs() <= SIX_DECIMALS,
            "Z({d}) = {} vs {want}",
            z(n, f, d)
        );
    }
    for (d, want) in [
        (100.0, 0.009009),
        (500.0, 0.049049),
        (1000.0, 0.099099),
        (5000.0, 0.499499),
        (10000.0, 1.0),
    ] {
        let trick = z(n, f, d) * d / f;
        assert!(
            (trick - want).abs() <= SIX_DECIMALS,
            "linear Z({d}) = {trick} vs {want}"
        );
        assert!(
            (trick - (d - n) / (f - n)).abs() <= 1e-12,
            "the trick is (d - n) / (f - n)"
        );
    }
}

/// Dunlop, "Using W-Buffers", near 10 / far 1000: "half of the number space is used in the first 10 units of
/// distance after the near plane" and "at a distance of 100, over 90% of the range ... has been used".
#[test]
fn seed_002_claims() {
    let (n, f) = (10.0, 1000.0);
    let at20 = z(n, f, n + 10.0);
    assert!(at20 >= 0.5, "{at20}");
    assert!(
        (at20 - 0.505_050_505).abs() < 1e-9,
        "exactly 50/99 = {at20}"
    );
    let at100 = z(n, f, 100.0);
    assert!(at100 > 0.9, "{at100}");
    assert!(
        (at100 - 0.909_090_909).abs() < 1e-9,
        "exactly 10/11 = {at100}"
    );
}

/// Microsoft, "W-Buffering" (Direct3D DDK): far/near 100 uses "90 percent of the depth buffer range on the first 10 percent of the
/// scene depth range" (true: exactly 91.7%), and at 1000 "98 percent of the range is used on the first two percent
/// of the depth". The second is wrong by exact arithmetic: the first 2% of `[n, f]` holds 95.3% of the range.
#[test]
fn seed_003_claims_and_its_error() {
    let share = |r: f64, frac: f64| z(1.0, r, 1.0 + frac * (r - 1.0));
    let at100 = share(100.0, 0.10);
    assert!(at100 >= 0.90, "{at100}");
    assert!((at100 - 0.917_431).abs() < 1e-6, "{at100}");
    let at1000 = share(1000.0, 0.02);
    // Exact: 1000/999 * (1 - 1/20.98) = 0.953289...: the seed's 98% is not what the formula gives.
    assert!((at1000 - 0.953_289).abs() < 1e-6, "{at1000}");
    assert!(
        at1000 < 0.98,
        "the seed says 98%; exact arithmetic gives {at1000}"
    );
}

/// Dunlop's "Linear Depth" trick stores `(d - n) / (f - n)` at the vertices, and the rasterizer interpolates it
/// linearly in screen space, while depth itself is perspective-correct (1/d is what is linear in screen space).
/// Along an edge from `d0` to `d1 = r d0`, at screen fraction `s` the trick gives `(1 - s) d0 + s d1` against the
/// true `1 / ((1 - s)/d0 + s/d1)`: relative error `s (1 - s) (r - 1)^2 / r`, largest at the middle, `(r - 1)^2 / (4r)`
/// (ARCHITECTURE.md, precision notes: 12.5% at r = 2, 56% at r = 4, 203% at r = 10). The documents' table is exact only at vertices.
#[test]
fn linear_z_trick_interior_error() {
    let (n, f) = (10.0, 10000.0);
    for (r, printed) in [(2.0, 0.125), (4.0, 0.5625), (10.0, 2.025)] {
        let d0 = 50.0;
        let d1 = r * d0;
        let (l0, l1) = ((d0 - n) / (f - n), (d1 - n) / (f - n));
        let mut worst = 0.0f64;
        for k in 0..=1000 {
            let s = k as f64 / 1000.0;
            let stored = (1.0 - s) * l0 + s * l1; // what the Z-buffer holds inside the edge
            let implied = n + stored * (f - n);
            let truth = 1.0 / ((1.0 - s) / d0 + s / d1);
            worst = worst.max((implied / truth - 1.0).abs());
        }
        let bound = (r - 1.0) * (r - 1.0) / (4.0 * r);
        // s = 1/2 is on the grid, so the sampled maximum is the exact one up to f64 rounding.
        assert!((worst - bound).abs() < 1e-12, "r = {r}: {worst} vs {bound}");
        assert!(
            (bound - printed).abs() < 1e-3,
            "the precision notes print {printed} for r = {r}"
        );
    }
}
