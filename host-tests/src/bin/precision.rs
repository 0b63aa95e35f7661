//! What every depth format can resolve: `cargo run --release -p host-tests --bin precision -- --near 10 --far 10000
//! [--at d1,d2,...]`. For each format and distance (default: near, 100, 500, 1000, 5000, far) one line
//! `format=<NAME> near=<n> far=<f> d=<d> stored=<fraction> step=<eye units>`, the step measured by decoding the
//! neighbouring code (wraster::format). It also writes a log-log PNG of step against distance for every format,
//! the analytic limits of shared/notes/precision.md drawn as lines under the measured points.

use std::path::PathBuf;

use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor, WebColors};
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle};
use embedded_graphics::text::Text;
use embedded_graphics_simulator::{OutputSettingsBuilder, SimulatorDisplay};
use wraster::format::*;

/// One format's measurement and its analytic step (precision.md).
struct Row {
    name: &'static str,
    stored: fn(f64, f64, f64) -> f64,
    step: fn(f64, f64, f64) -> f64,
    analytic: fn(f64, f64, f64) -> f64,
    color: Rgb888,
}

fn row<F: DepthFormat>(analytic: fn(f64, f64, f64) -> f64, color: Rgb888) -> Row {
    Row {
        name: F::NAME,
        stored: |d, n, f| F::fraction(F::encode(d, n, f), n, f),
        step: F::step,
        analytic,
        color,
    }
}

fn p2(e: i32) -> f64 {
    2f64.powi(e)
}

/// The formats and precision.md's analytic steps: unorm Z `2^-k d^2 (f-n)/(f n)`, unorm W `2^-k f`,
/// float W with m mantissa bits `d 2^-m` (upper bound), float Z `2^-23 z d^2 (f-n)/(f n)`.
fn rows() -> Vec<Row> {
    vec![
        row::<W16>(|_, _, f| f / 65535.0, Rgb888::CSS_DODGER_BLUE),
        row::<W16F>(|d, _, _| d * p2(-12), Rgb888::CSS_LIME_GREEN),
        row::<W24F>(|d, _, _| d * p2(-15), Rgb888::CSS_DARK_GREEN),
        row::<W24FScaled>(|d, _, _| d * p2(-15), Rgb888::CSS_OLIVE),
        row::<W32F>(|d, _, _| d * p2(-23), Rgb888::CSS_TEAL),
        row::<Z16>(
            |d, n, f| p2(-16) * d * d * (f - n) / (f * n),
            Rgb888::CSS_RED,
        ),
        row::<Z24>(
            |d, n, f| p2(-24) * d * d * (f - n) / (f * n),
            Rgb888::CSS_ORANGE,
        ),
        row::<Z32F>(
            |d, n, f| p2(-23) * z_of(d, n, f) * d * d * (f - n) / (f * n),
            Rgb888::CSS_MAGENTA,
        ),
        row::<RZ32F>(
            |d, n, f| p2(-23) * rz_of(d, n, f) * d * d * (f - n) / (f * n),
            Rgb888::CSS_PURPLE,
        ),
        row::<LZ16>(|_, n, f| (f - n) / 65535.0, Rgb888::CSS_SADDLE_BROWN),
    ]
}

fn plot(rows: &[Row], n: f64, f: f64, path: &std::path::Path) {
    let (w, h, left, top, right, bottom) = (900i32, 560i32, 70i32, 20i32, 170i32, 50i32);
    let mut disp = SimulatorDisplay::<Rgb888>::new(Size::new(w as u32, h as u32));
    disp.clear(Rgb888::WHITE).unwrap();
    let ds: Vec<f64> = (0..=120)
        .map(|k| n * (f / n).powf(k as f64 / 120.0))
        .collect();
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for r in rows {
        for &d in &ds {
            for s in [(r.step)(d, n, f), (r.analytic)(d, n, f)] {
                if s > 0.0 && s.is_finite() {
                    lo = lo.min(s);
                    hi = hi.max(s);
                }
            }
        }
    }
    let (lo, hi) = (lo.log10().floor(), hi.log10().ceil());
    let x = |d: f64| left + ((d / n).log10() / (f / n).log10() * (w - left - right) as f64) as i32;
    let y = |s: f64| h - bottom - ((s.log10() - lo) / (hi - lo) * (h - top - bottom) as f64) as i32;
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let grey = PrimitiveStyle::with_stroke(Rgb888::CSS_LIGHT_GRAY, 1);
    for e in lo as i32..=hi as i32 {
        let yy = y(10f64.powi(e));
        Line::new(Point::new(left, yy), Point::new(w - right, yy))
            .into_styled(grey)
            .draw(&mut disp)
            .unwrap();
        Text::new(&format!("1e{e}"), Point::new(10, yy + 3), text)
            .draw(&mut disp)
            .unwrap();
    }
    let mut dec = n.log10().ceil() as i32;
    while 10f64.powi(dec) <= f {
        let xx = x(10f64.powi(dec));
        Line::new(Point::new(xx, top), Point::new(xx, h - bottom))
            .into_styled(grey)
            .draw(&mut disp)
            .unwrap();
        Text::new(
            &format!("1e{dec}"),
            Point::new(xx - 10, h - bottom + 14),
            text,
        )
        .draw(&mut disp)
        .unwrap();
        dec += 1;
    }
    Text::new("eye depth d (log)", Point::new(w / 2 - 60, h - 10), text)
        .draw(&mut disp)
        .unwrap();
    Text::new(
        "step, eye units (log): lines = analytic limit, dots = measured",
        Point::new(left, 12),
        text,
    )
    .draw(&mut disp)
    .unwrap();
    for (k, r) in rows.iter().enumerate() {
        let line = PrimitiveStyle::with_stroke(r.color, 1);
        for pair in ds.windows(2) {
            let (a, b) = ((r.analytic)(pair[0], n, f), (r.analytic)(pair[1], n, f));
            if a > 0.0 && b > 0.0 {
                Line::new(Point::new(x(pair[0]), y(a)), Point::new(x(pair[1]), y(b)))
                    .into_styled(line)
                    .draw(&mut disp)
                    .unwrap();
            }
        }
        for &d in ds.iter().step_by(3) {
            let s = (r.step)(d, n, f);
            if s > 0.0 {
                Circle::with_center(Point::new(x(d), y(s)), 4)
                    .into_styled(PrimitiveStyle::with_fill(r.color))
                    .draw(&mut disp)
                    .unwrap();
            }
        }
        let ly = top + 20 + 16 * k as i32;
        Circle::with_center(Point::new(w - right + 15, ly - 3), 6)
            .into_styled(PrimitiveStyle::with_fill(r.color))
            .draw(&mut disp)
            .unwrap();
        Text::new(r.name, Point::new(w - right + 25, ly), text)
            .draw(&mut disp)
            .unwrap();
    }
    let img = disp.to_rgb_output_image(
        &OutputSettingsBuilder::new()
            .scale(1)
            .pixel_spacing(0)
            .build(),
    );
    img.save_png(path).unwrap();
}

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
    plot(&rows, n, f, &png);
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
