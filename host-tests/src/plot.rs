//! Plots drawn with embedded-graphics into the simulator's PNG output: step against distance per format (the
//! precision command and the report), error against run time with the Pareto front, and depth-error heat maps.

use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor, WebColors};
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle};
use embedded_graphics::text::Text;
use embedded_graphics_simulator::{OutputSettingsBuilder, SimulatorDisplay};
use wraster::format::*;

/// One format's measurement and its analytic step (the precision notes in ARCHITECTURE.md).
pub struct Row {
    /// Format name.
    pub name: &'static str,
    /// The stored fraction at `d`.
    pub stored: fn(f64, f64, f64) -> f64,
    /// The measured step at `d`.
    pub step: fn(f64, f64, f64) -> f64,
    /// the analytic step (ARCHITECTURE.md) at `d`.
    pub analytic: fn(f64, f64, f64) -> f64,
    /// Plot colour.
    pub color: Rgb888,
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

/// The formats and the analytic steps of ARCHITECTURE.md's precision notes: unorm Z `2^-k d^2 (f-n)/(f n)`, unorm W `2^-k f`,
/// float W with m mantissa bits `d 2^-m` (upper bound), float Z `2^-23 z d^2 (f-n)/(f n)`.
pub fn rows() -> Vec<Row> {
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

/// The log-log plot of step against distance, measured points over the analytic lines.
pub fn step_plot(rows: &[Row], n: f64, f: f64, path: &std::path::Path) {
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
    // Every analytic line first, then every format's measured dots over them, so no line hides a format's dots;
    // each format's dots sit at its own phase of the sampled distances (W16's and LZ16's steps, `f / 65535` and
    // `(f - n) / 65535`, nearly coincide: at one phase their dots would cover each other), W16's drawn last and ringed.
    for r in rows {
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
    }
    let phases = 4;
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by_key(|&k| rows[k].name == "W16");
    for &k in &order {
        let r = &rows[k];
        for &d in ds.iter().skip(k % phases).step_by(phases) {
            let s = (r.step)(d, n, f);
            if s > 0.0 {
                let c = Point::new(x(d), y(s));
                if r.name == "W16" {
                    Circle::with_center(c, 8)
                        .into_styled(PrimitiveStyle::with_stroke(Rgb888::BLACK, 1))
                        .draw(&mut disp)
                        .unwrap();
                }
                Circle::with_center(c, 5)
                    .into_styled(PrimitiveStyle::with_fill(r.color))
                    .draw(&mut disp)
                    .unwrap();
            }
        }
    }
    for (k, r) in rows.iter().enumerate() {
        let ly = top + 20 + 16 * k as i32;
        Circle::with_center(Point::new(w - right + 15, ly - 3), 6)
            .into_styled(PrimitiveStyle::with_fill(r.color))
            .draw(&mut disp)
            .unwrap();
        if r.name == "W16" {
            Circle::with_center(Point::new(w - right + 15, ly - 3), 9)
                .into_styled(PrimitiveStyle::with_stroke(Rgb888::BLACK, 1))
                .draw(&mut disp)
                .unwrap();
        }
        Text::new(r.name, Point::new(w - right + 25, ly), text)
            .draw(&mut disp)
            .unwrap();
    }
    save(&disp, path);
}

/// A point of the error-against-time plot.
pub struct Point2 {
    /// Run time (x, log).
    pub x: f64,
    /// Error (y, log; values below `floor` are drawn at `floor`).
    pub y: f64,
    /// Label drawn next to Pareto points.
    pub label: String,
    /// On the Pareto front.
    pub pareto: bool,
    /// Marked with a blue ring and this label (the scene planner's choice).
    pub mark: Option<String>,
}

fn save(disp: &SimulatorDisplay<Rgb888>, path: &std::path::Path) {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).unwrap();
    }
    disp.to_rgb_output_image(
        &OutputSettingsBuilder::new()
            .scale(1)
            .pixel_spacing(0)
            .build(),
    )
    .save_png(path)
    .unwrap();
}

/// Log-log scatter of error against run time; Pareto points filled red, joined, and labelled; the others grey.
pub fn pareto_plot(
    points: &[Point2],
    floor: f64,
    xlabel: &str,
    ylabel: &str,
    path: &std::path::Path,
) {
    let (w, h, left, top, right, bottom) = (1000i32, 640i32, 70i32, 30i32, 30i32, 50i32);
    let mut disp = SimulatorDisplay::<Rgb888>::new(Size::new(w as u32, h as u32));
    disp.clear(Rgb888::WHITE).unwrap();
    let ys = |p: &Point2| p.y.max(floor);
    let (xlo, xhi) = points
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
    let (ylo, yhi) = points.iter().fold((f64::MAX, f64::MIN), |(a, b), p| {
        (a.min(ys(p)), b.max(ys(p)))
    });
    let (xlo, xhi) = ((xlo * 0.8).log10(), (xhi * 1.25).log10());
    let (ylo, yhi) = (
        ylo.log10().floor(),
        yhi.log10().ceil().max(ylo.log10().floor() + 1.0),
    );
    let x = |v: f64| left + ((v.log10() - xlo) / (xhi - xlo) * (w - left - right) as f64) as i32;
    let y = |v: f64| {
        h - bottom - ((v.max(floor).log10() - ylo) / (yhi - ylo) * (h - top - bottom) as f64) as i32
    };
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let grey = PrimitiveStyle::with_stroke(Rgb888::CSS_LIGHT_GRAY, 1);
    for e in ylo as i32..=yhi as i32 {
        let yy = y(10f64.powi(e));
        Line::new(Point::new(left, yy), Point::new(w - right, yy))
            .into_styled(grey)
            .draw(&mut disp)
            .unwrap();
        Text::new(&format!("1e{e}"), Point::new(10, yy + 3), text)
            .draw(&mut disp)
            .unwrap();
    }
    let mut v = 10f64.powf(xlo.floor());
    while v.log10() <= xhi {
        for m in [1.0, 2.0, 5.0] {
            let xv = v * m;
            if xv.log10() >= xlo && xv.log10() <= xhi {
                let xx = x(xv);
                Line::new(Point::new(xx, top), Point::new(xx, h - bottom))
                    .into_styled(grey)
                    .draw(&mut disp)
                    .unwrap();
                Text::new(&format!("{xv}"), Point::new(xx - 6, h - bottom + 14), text)
                    .draw(&mut disp)
                    .unwrap();
            }
        }
        v *= 10.0;
    }
    Text::new(xlabel, Point::new(w / 2 - 80, h - 10), text)
        .draw(&mut disp)
        .unwrap();
    Text::new(ylabel, Point::new(left, 14), text)
        .draw(&mut disp)
        .unwrap();
    let mut front: Vec<&Point2> = points.iter().filter(|p| p.pareto).collect();
    front.sort_by(|a, b| a.x.total_cmp(&b.x));
    for pair in front.windows(2) {
        Line::new(
            Point::new(x(pair[0].x), y(pair[0].y)),
            Point::new(x(pair[1].x), y(pair[1].y)),
        )
        .into_styled(PrimitiveStyle::with_stroke(Rgb888::CSS_RED, 1))
        .draw(&mut disp)
        .unwrap();
    }
    for p in points {
        let (c, d) = if p.pareto {
            (Rgb888::CSS_RED, 7)
        } else {
            (Rgb888::CSS_GRAY, 5)
        };
        Circle::with_center(Point::new(x(p.x), y(p.y)), d)
            .into_styled(PrimitiveStyle::with_fill(c))
            .draw(&mut disp)
            .unwrap();
    }
    let blue = MonoTextStyle::new(&FONT_6X10, Rgb888::CSS_BLUE);
    for p in points {
        if let Some(m) = &p.mark {
            Circle::with_center(Point::new(x(p.x), y(p.y)), 15)
                .into_styled(PrimitiveStyle::with_stroke(Rgb888::CSS_BLUE, 2))
                .draw(&mut disp)
                .unwrap();
            Text::new(m, Point::new(x(p.x) - 20, y(p.y) + 22), blue)
                .draw(&mut disp)
                .unwrap();
        }
    }
    for (k, p) in front.iter().enumerate() {
        let dy = if k % 2 == 0 { -6 } else { 12 };
        Text::new(&p.label, Point::new(x(p.x) + 6, y(p.y) + dy), text)
            .draw(&mut disp)
            .unwrap();
    }
    save(&disp, path);
}

/// A heat map of per-pixel values (`None`: nothing drawn, black) on a log colour scale from `lo` to `hi` (blue to
/// red; at or below `lo`: dark blue), scaled up `zoom` times, with the scale drawn underneath.
#[allow(clippy::too_many_arguments)]
pub fn heat_map(
    values: &[Option<f64>],
    w: u32,
    h: u32,
    lo: f64,
    hi: f64,
    zoom: u32,
    title: &str,
    path: &std::path::Path,
) {
    let bar = 40;
    let mut disp = SimulatorDisplay::<Rgb888>::new(Size::new(w * zoom, h * zoom + bar));
    disp.clear(Rgb888::WHITE).unwrap();
    let color = |v: f64| {
        let s = ((v.max(lo).log10() - lo.log10()) / (hi.log10() - lo.log10())).clamp(0.0, 1.0);
        // blue -> cyan -> yellow -> red
        let (r, g, b) = if s < 0.33 {
            let k = s / 0.33;
            (0.0, k, 0.5 + 0.5 * k)
        } else if s < 0.66 {
            let k = (s - 0.33) / 0.33;
            (k, 1.0, 1.0 - k)
        } else {
            let k = (s - 0.66) / 0.34;
            (1.0, 1.0 - k, 0.0)
        };
        Rgb888::new((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
    };
    for (k, v) in values.iter().enumerate() {
        let c = v.map(color).unwrap_or(Rgb888::BLACK);
        let (px, py) = ((k as u32 % w) * zoom, (k as u32 / w) * zoom);
        for dy in 0..zoom {
            for dx in 0..zoom {
                Pixel(Point::new((px + dx) as i32, (py + dy) as i32), c)
                    .draw(&mut disp)
                    .unwrap();
            }
        }
    }
    let y0 = (h * zoom) as i32 + 4;
    let width = (w * zoom) as i32 - 160;
    for i in 0..width {
        let v = 10f64.powf(lo.log10() + (hi.log10() - lo.log10()) * i as f64 / width as f64);
        Line::new(Point::new(80 + i, y0), Point::new(80 + i, y0 + 12))
            .into_styled(PrimitiveStyle::with_stroke(color(v), 1))
            .draw(&mut disp)
            .unwrap();
    }
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    Text::new(&format!("{lo:.0e}"), Point::new(40, y0 + 10), text)
        .draw(&mut disp)
        .unwrap();
    Text::new(
        &format!("{hi:.0e}"),
        Point::new(80 + width + 4, y0 + 10),
        text,
    )
    .draw(&mut disp)
    .unwrap();
    Text::new(title, Point::new(10, y0 + 30), text)
        .draw(&mut disp)
        .unwrap();
    save(&disp, path);
}
