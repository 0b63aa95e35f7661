//! What every depth format can resolve: `cargo run --release -p host-tests --bin precision -- --near 10 --far 10000
//! [--at d1,d2,...]`. For each format and distance (default: near, 100, 500, 1000, 5000, far) one line
//! `format=<NAME> near=<n> far=<f> d=<d> stored=<fraction> step=<eye units>`, the step measured by decoding the
//! neighbouring code (wraster::format). It also writes a log-log PNG of step against distance for every format,
//! the analytic limits of the precision notes in ARCHITECTURE.md drawn as lines under the measured points.

use std::path::PathBuf;

use host_tests::plot::{rows, step_plot};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let get = |key: &str| {
        args.iter()
            .position(|a| a == key)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let n: f64 = get("--near")
        .map(|s| s.parse().expect("--near"))
        .unwrap_or(10.0);
    let f: f64 = get("--far")
        .map(|s| s.parse().expect("--far"))
        .unwrap_or(10000.0);
    if !(n > 0.0 && f > n && f.is_finite()) {
        eprintln!("precision: need 0 < --near < --far, finite");
        std::process::exit(2);
    }
    let at: Vec<f64> = match get("--at") {
        Some(s) => s
            .split(',')
            .map(|v| v.trim().parse().expect("--at d1,d2,..."))
            .collect(),
        None => [n, 100.0, 500.0, 1000.0, 5000.0, f]
            .into_iter()
            .filter(|&d| d >= n && d <= f)
            .collect(),
    };
    let rows = rows();
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/precision");
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join(format!("step_{n}_{f}.png"));
    step_plot(&rows, n, f, &png);
    println!("plot={}", png.canonicalize().unwrap_or(png).display());
    for r in &rows {
        for &d in &at {
            println!(
                "format={} near={n} far={f} d={d} stored={:.6} step={:.6e}",
                r.name,
                (r.stored)(d, n, f),
                (r.step)(d, n, f)
            );
        }
    }
}
