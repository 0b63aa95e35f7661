//! The demo and report commands: their script lines and what they claim.

use std::process::Command;

use host_tests::field;

/// The demo's side-by-side is drawn by the rasterizer into Z16, W16 and W16F. In the far scene two billboards 0.3%
/// apart (4.5 units at W = 1500, 27 at 9000, range 10..10000) must be told apart: W16's step is 10000 / 65535 = 0.15
/// units everywhere, and each code is within 1 LSB, so W16 shows no difference from the reference; Z16's step,
/// `d^2 (f - n) / (f n) / 65535`, is 3.4 units at 1500 and 38 at 5000, so it must show the wrong billboard somewhere.
/// The `demo ...` line comes last.
#[test]
fn demo_prints_the_side_by_side_and_its_line_last() {
    let out = Command::new(env!("CARGO_BIN_EXE_demo")).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let last = text.lines().last().unwrap();
    assert!(last.starts_with("demo scene=terrain pixels="), "{last}");
    assert_eq!(field(last, "max_err_lsb"), Some("0"), "{last}");
    let differs = |scene: &str, format: &str| -> u64 {
        let line = text
            .lines()
            .find(|l| {
                l.starts_with("formats ")
                    && field(l, "scene") == Some(scene)
                    && field(l, "format") == Some(format)
            })
            .unwrap_or_else(|| panic!("no formats line for {scene} {format}"));
        assert_eq!(field(line, "source"), Some("rasterizer"));
        field(line, "visibility_differs").unwrap().parse().unwrap()
    };
    assert_eq!(differs("far", "W16"), 0);
    assert!(differs("far", "Z16") > 1000);
    for f in ["Z16", "W16", "W16F"] {
        differs("terrain", f);
    }
}

/// The report measures 54 combinations (5 W formats x 9 strategies, the 4 lean W16 rows, 5 Z formats), writes its
/// files, and ends with its line. Its claims that follow from derived bounds: the fast tier (`2^-27.2`, 2^-11 of a
/// code), the exact tier and the table strategies (2 or 3 Newton steps from the 64-entry table: error below 2^-27, far under half a W16 code) store every scene
/// pixel within 1 code of the f64 encode, and the Pareto front is not empty.
#[test]
fn report_writes_its_tables_and_its_line_last() {
    let out = Command::new(env!("CARGO_BIN_EXE_report"))
        .arg("--no-boards")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let last = text.lines().last().unwrap();
    assert!(last.starts_with("report "), "{last}");
    assert_eq!(field(last, "combos"), Some("54"));
    assert_eq!(field(last, "out"), Some("report/report.md"));
    let pareto: usize = field(last, "pareto").unwrap().parse().unwrap();
    assert!(pareto >= 1);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../report");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for png in ["pareto.png", "step_10_10000.png", "terrain_error.png"] {
        assert!(dir.join(png).exists(), "{png}");
    }
    // Estimated cycles beside the instructions (issue 10), in both tables (here without boards: no figures).
    assert_eq!(
        md.matches("| M4 instr/px | M4 est. cycles/px | M0 instr/px | M0 est. cycles/px |")
            .count(),
        2
    );
    let row = |format: &str, strategy: &str| -> Vec<String> {
        md.lines()
            .find(|l| {
                l.starts_with(&format!("| {format} | {strategy} |")) && l.matches('|').count() > 12
            })
            .unwrap_or_else(|| panic!("no row {format} {strategy}"))
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    for s in [
        "fast tier (default), lean W16 path",
        "lerp64+1nr (exact tier), lean W16 path",
        "table64+2nr",
        "table64+3nr",
    ] {
        let r = row("W16", s);
        let max_lsb: u64 = r[4].split('/').next().unwrap().trim().parse().unwrap();
        assert!(max_lsb <= 1, "{s}: {max_lsb}");
    }
}

/// The coarse-bound measurement (`coarse`): its line comes last; what a bound rejects is a subset of what fails the
/// depth test (each rejected fragment is at or behind everything stored in its region, so `Less` fails it), the
/// kept bound rejects no more than the exact one, and the whole band no more than rows. On W2 (16 large
/// triangles over each other) the whole frame and every row always hold some far pixel, so only tiles reject.
#[test]
fn coarse_counts_what_a_bound_could_reject() {
    let out = Command::new(env!("CARGO_BIN_EXE_coarse"))
        .arg("overdraw")
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let last = text.lines().last().unwrap();
    assert!(last.starts_with("coarse scene=overdraw "), "{last}");
    let n = |k: &str| -> u64 { field(last, k).unwrap().parse().unwrap() };
    // W2's fragments and failing fragments, as the boards count them (README: 248,347, of which 83,797 pass).
    assert_eq!((n("fragments"), n("failing")), (248_347, 248_347 - 83_797));
    assert!(n("tile8_kept_rejects") <= n("tile8_rejects") && n("tile8_rejects") <= n("failing"));
    // A triangle behind the frame's largest code is behind every row's.
    assert!(n("band_rejects") <= n("row_rejects"));
    assert_eq!((n("band_rejects"), n("row_rejects")), (0, 0));
    assert!(n("tile8_kept_rejects") > n("failing") / 2, "{last}");
}
