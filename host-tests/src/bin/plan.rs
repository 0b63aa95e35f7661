//! The scene planner: `cargo run --release -p host-tests --bin plan -- <scene> [--max-visibility-errors N]
//! [--depth-ram BYTES] [--core m0|m4|rv32] [--out FILE] [--measure]` for `big`, `overdraw`, `small`, `terrain`,
//! `torus` (W4's 8 frames) and `obj:<file.obj>` (a mesh along a camera path: `host_tests::plan::obj_workload`).
//! Measures the scene against the f64 reference, picks the cheapest build within the budget (default: 0
//! visibility errors; the core's board's depth RAM; `m4`), writes it as Rust source for a board's build.rs
//! (default `target/plans/<scene>-<core>.rs`; `PLAN=<file> cargo run --release --features plan` in a board) and
//! prints, last, `plan scene=.. format=.. strategy=.. near=.. far=.. bands=.. depth_ram=.. features=.. visibility_errors=..`.
//! `--measure` ranks by cost on the core instead of by RAM: the first candidate within the budget of each of the
//! first three formats that have one (no depth buffer, W16, LZ16, ...) is built into a firmware of its own for the
//! core's QEMU board and run,
//! and the plan is the one with the fewest instructions per frame (needs the board's target and QEMU).
//! See `host_tests::plan` for the candidates and what a visibility error is.
use host_tests::plan::{
    candidates, measure_on_board, rank_measured, workload, Budget, Core, Reference,
};
use wraster::format::{LZ16, W16, W16F, W24F, Z16, Z24};

/// How far code placement alone moves a board's instruction count between builds of the same code (measured: the
/// single-scene builds against the full firmware, and the full M0 firmware between two stops whose default path
/// compiled to the same instructions, differ by up to 3%). A run-time feature that saves less is not kept.
const PLACEMENT_NOISE: f64 = 0.03;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut scene, mut max, mut ram, mut core, mut out) = (None, 0u32, None, Core::M4, None);
    let mut measure = false;
    while let Some(a) = args.next() {
        let mut val = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--max-visibility-errors" => max = val()?.parse()?,
            "--depth-ram" => ram = Some(val()?.parse()?),
            "--core" => core = Core::parse(&val()?).ok_or("--core is m0, m4 or rv32")?,
            "--out" => out = Some(std::path::PathBuf::from(val()?)),
            "--measure" => measure = true,
            s if !s.starts_with('-') && scene.is_none() => scene = Some(s.to_string()),
            s => return Err(format!("unexpected argument {s:?}").into()),
        }
    }
    let scene = scene.ok_or("usage: plan <big|overdraw|small|terrain|torus|obj:FILE> [--max-visibility-errors N] [--depth-ram BYTES] [--core m0|m4|rv32] [--out FILE] [--measure]")?;
    let wl = workload(&scene)?;
    let budget = Budget {
        max_visibility_errors: max,
        depth_ram: ram.unwrap_or(core.default_depth_ram(&scene)),
        core,
    };
    // What the scene needs: its W range and the closest pair of surfaces, against each format's step there.
    let refs: Vec<Reference> = wl
        .frames
        .iter()
        .map(|t| Reference::new(t, &wl.state, wl.w, wl.h))
        .collect();
    let (n, f) = (wl.state.range.near() as f64, wl.state.range.far() as f64);
    if let Some((lo, hi)) = refs
        .iter()
        .filter_map(Reference::depth_span)
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    {
        println!(
            "scene {scene}: {} frame(s), W drawn from {:.6} to {:.6} (range {n} to {f})",
            wl.frames.len(),
            lo * f,
            hi * f
        );
    }
    let gap = |g: &dyn Fn(&Reference) -> f64| refs.iter().map(g).fold(f64::INFINITY, f64::min);
    println!(
        "closest surfaces, in steps of each format at the nearer one (scene's range; under 1 may swap): W16 {:.3}, LZ16 {:.3}, Z16 {:.3}, W16F {:.3}, W24F {:.3}, Z24 {:.3}",
        gap(&|r| r.min_gap_steps::<W16>(f, n, f)),
        gap(&|r| r.min_gap_steps::<LZ16>(f, n, f)),
        gap(&|r| r.min_gap_steps::<Z16>(f, n, f)),
        gap(&|r| r.min_gap_steps::<W16F>(f, n, f)),
        gap(&|r| r.min_gap_steps::<W24F>(f, n, f)),
        gap(&|r| r.min_gap_steps::<Z24>(f, n, f)),
    );
    let mut cands = candidates(&wl, budget, if measure { 3 } else { 1 })?;
    // The coarse depth bound is a run-time saving: measured beside each fast-tier W16 candidate (`base` pairs it
    // with its candidate without the bound); it takes an eighth more depth RAM, within the same budget (shorter bands).
    let mut base = vec![];
    if measure && cands[0].budget_met {
        let with: Vec<_> = cands
            .iter()
            .enumerate()
            .filter_map(|(k, c)| Some((k, c.with_coarse(wl.w, wl.h, budget.depth_ram)?)))
            .collect();
        for (k, c) in with {
            base.push((cands.len(), k));
            cands.push(c);
        }
    }
    let p = if measure && cands[0].budget_met {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/plans/candidates");
        let mut costs = measure_on_board(&cands, &dir)?;
        for (c, n) in cands.iter().zip(&costs) {
            println!(
                "measured format={} strategy={} features={} bands={} instructions_per_frame={n:.0} visibility_errors={}",
                c.format,
                c.strategy,
                if c.features.is_empty() { "none".to_string() } else { c.features.join(",") },
                c.bands,
                c.visibility_errors
            );
        }
        // Kept only where it saves more than code placement moves a count between builds of the same code.
        for &(c, b) in &base {
            if costs[c] > costs[b] * (1.0 - PLACEMENT_NOISE) {
                println!(
                    "coarse bound left out: {:.0} against {:.0} without it, a saving under {}%",
                    costs[c],
                    costs[b],
                    PLACEMENT_NOISE * 100.0
                );
                costs[c] = f64::INFINITY;
            }
        }
        rank_measured(cands, &costs)
    } else {
        cands
            .into_iter()
            .next()
            .expect("candidates returns at least one plan")
    };
    for (format, strategy, range, e) in &p.tried {
        println!(
            "candidate format={format} strategy={strategy} range={range} visibility_errors={e}"
        );
    }
    let out = out.unwrap_or_else(|| {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!(
            "../target/plans/{}-{}.rs",
            wl.name,
            core.name()
        ))
    });
    if let Some(d) = out.parent() {
        std::fs::create_dir_all(d)?;
    }
    let command: Vec<String> = std::env::args().skip(1).collect();
    std::fs::write(&out, p.rust(&format!("plan {}", command.join(" "))))?;
    println!("wrote {}", out.display());
    if !p.budget_met {
        println!("no candidate meets the budget of {max} visibility errors: the plan is the cheapest with the fewest ({})", p.visibility_errors);
    }
    println!("{}", p.line());
    Ok(())
}
