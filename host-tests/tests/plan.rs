//! The scene planner (`host_tests::plan`, the `plan` binary): its error count counts what it claims, its plans are
//! what the scenes need, and the boards built from them draw the host's frames.

use embedded_graphics::pixelcolor::Rgb565;
use host_tests::plan::{
    candidates, errors_of, measure_on_board, plan, plan_hash, rank_measured, render_ids, workload,
    Budget, Core, Reference, Workload,
};
use host_tests::{have, run_board_env};
use wraster::{RenderState, Vertex};

/// Whether QEMU is here to run the boards; without it a test fails unless told to skip (`WRASTER_SKIP_FIRMWARE=1`,
/// as `firmware.rs`).
/// Key `k` of a board's output line (it must be there).
fn key(line: &str, k: &str) -> String {
    host_tests::field(line, k)
        .unwrap_or_else(|| panic!("no {k} in {line}"))
        .to_string()
}

fn qemu() -> bool {
    if have("qemu-system-arm") {
        return true;
    }
    assert!(
        std::env::var("WRASTER_SKIP_FIRMWARE").is_ok_and(|v| v == "1"),
        "QEMU (qemu-system-arm) is missing: install it (.ci/run shows how) or set WRASTER_SKIP_FIRMWARE=1"
    );
    false
}

fn budget(core: Core, scene: &str) -> Budget {
    Budget {
        max_visibility_errors: 0,
        depth_ram: core.default_depth_ram(scene),
        core,
    }
}

/// Two overlapping triangles, the nearer drawn second; the reference's error count of an id frame.
#[test]
fn visibility_errors_count_what_they_claim() {
    let c = Rgb565::new(1, 2, 3);
    let far = [
        Vertex::new(2.0, 2.0, 50.0, c),
        Vertex::new(30.0, 2.0, 50.0, c),
        Vertex::new(2.0, 30.0, 50.0, c),
    ];
    let near = [
        Vertex::new(10.0, 10.0, 20.0, c),
        Vertex::new(30.0, 10.0, 20.0, c),
        Vertex::new(10.0, 30.0, 20.0, c),
    ];
    let wl = Workload {
        name: "two".into(),
        frames: vec![vec![far, near]],
        state: RenderState::new(1.0, 100.0).unwrap(),
        w: 32,
        h: 32,
    };
    let r = Reference::new(&wl.frames[0], &wl.state, wl.w, wl.h);
    // With a depth buffer: the nearer one wins everywhere it covers, 0 errors.
    let good = render_ids(&wl.frames[0], "W16", "exact", wl.state, 32, 32, 32).unwrap();
    assert_eq!(r.errors(&good), 0);
    // Drawn the other way round without depth, every pixel both cover shows the far one: each is an error.
    let swapped = render_ids(&[near, far], "none", "exact", wl.state, 32, 32, 32).unwrap();
    // (ids of the swapped list: 1 = near, 2 = far; map back to the reference's order.)
    let back: Vec<u32> = swapped.iter().map(|&id| [0, 2, 1][id as usize]).collect();
    let overlap = good
        .iter()
        .zip(&back)
        .filter(|&(&g, &b)| g == 2 && b == 1)
        .count() as u32;
    assert!(overlap > 50);
    assert_eq!(r.errors(&back), overlap);
    // Nothing shown where the reference covers, or something where it covers nothing: errors too.
    let mut holes = good.clone();
    holes[10 * 32 + 12] = 0;
    holes[31 * 32 + 31] = 1;
    assert_eq!(r.errors(&holes), 2);
    // The same through errors_of: the depth-less frame in drawing order (far, then near) is right.
    assert_eq!(
        errors_of(&wl, &[r], "none", "fast", wl.state, 32).unwrap(),
        0
    );
}

/// What each standard scene and W4 needs, on each core's default budget (0 visibility errors): W1 (one triangle)
/// and W3 (a grid of quads that never overlap) need no depth buffer, W2 and the torus need one and get W16 with the
/// range tightened to the W they draw, and the terrain's interpenetrating boxes have pixels where two surfaces are
/// closer than any format's step, so no candidate meets 0 and the plan is the first with the fewest errors.
#[test]
fn plans_fit_their_scenes() {
    for core in [Core::M4, Core::M0] {
        for scene in ["big", "overdraw", "small", "terrain", "torus"] {
            let wl = workload(scene).unwrap();
            let p = plan(&wl, budget(core, scene)).unwrap();
            assert_eq!(
                p.strategy,
                core.strategies()[0],
                "{scene}: the core's cheapest strategy"
            );
            let refs: Vec<Reference> = wl
                .frames
                .iter()
                .map(|t| Reference::new(t, &wl.state, wl.w, wl.h))
                .collect();
            let mut state = wl.state;
            state.range = wraster::DepthRange::new(p.near, p.far).unwrap();
            // Its stated error count is what its build draws, in its bands.
            let measured =
                errors_of(&wl, &refs, &p.format, &p.strategy, state, p.band_rows).unwrap();
            assert_eq!(measured, p.visibility_errors, "{scene}");
            assert!(p.depth_ram <= core.default_depth_ram(scene), "{scene}");
            match scene {
                "big" | "small" => {
                    assert_eq!(
                        (p.format.as_str(), p.depth_ram, p.visibility_errors),
                        ("none", 0, 0),
                        "{scene}"
                    );
                }
                "overdraw" | "torus" => {
                    assert!(p.budget_met && p.visibility_errors == 0, "{scene}");
                    assert_eq!(p.format, "W16", "{scene}");
                    // The depth-less candidate was measured first, and fails: the surfaces overlap.
                    assert_eq!(p.tried[0].0, "none");
                    assert!(p.tried[0].3 > 1000, "{scene}: {:?}", p.tried[0]);
                    // The range is the W drawn, within the scene's, and a pixel's W stays inside it.
                    assert!(
                        p.near > wl.state.range.near() && p.far < wl.state.range.far(),
                        "{scene}"
                    );
                    assert_eq!(p.band_rows as usize * 320 * 2, p.depth_ram);
                }
                _ => {
                    assert!(!p.budget_met && p.visibility_errors > 0);
                    let fewest = p.tried.iter().map(|t| t.3).min().unwrap();
                    assert_eq!(p.visibility_errors, fewest);
                    // W16 on the terrain: its far boxes need more than 16 bits of linear W.
                    let w16 = p.tried.iter().find(|t| t.0 == "W16").unwrap().3;
                    assert!(w16 > p.visibility_errors);
                }
            }
        }
    }
    // A larger budget takes a cheaper plan: W16 on the terrain.
    let wl = workload("terrain").unwrap();
    let w16 = plan(&wl, budget(Core::M4, "terrain"))
        .unwrap()
        .tried
        .iter()
        .find(|t| t.0 == "W16")
        .unwrap()
        .3;
    let p = plan(
        &wl,
        Budget {
            max_visibility_errors: w16,
            ..budget(Core::M4, "terrain")
        },
    )
    .unwrap();
    assert!(p.budget_met && p.format == "W16" && p.visibility_errors <= w16);
    // Less RAM, more bands; too little for one row of any format leaves only "none", which misses the budget.
    let wl = workload("overdraw").unwrap();
    let p = plan(
        &wl,
        Budget {
            depth_ram: 320 * 2 * 10,
            ..budget(Core::M0, "overdraw")
        },
    )
    .unwrap();
    assert_eq!((p.band_rows, p.bands, p.visibility_errors), (10, 24, 0));
    let p = plan(
        &wl,
        Budget {
            depth_ram: 100,
            ..budget(Core::M0, "overdraw")
        },
    )
    .unwrap();
    assert!(!p.budget_met && p.format == "none" && p.visibility_errors > 1000);
    let wl = workload("big").unwrap();
    assert_eq!(
        plan(
            &wl,
            Budget {
                depth_ram: 0,
                ..budget(Core::M0, "big")
            }
        )
        .unwrap()
        .format,
        "none"
    );
}

/// The boards built from the plans (`--features plan`, `PLAN=<files>`) print the hash, pixel and fragment counts of
/// the host's rendering of each plan. Needs QEMU, as `firmware.rs` (`WRASTER_SKIP_FIRMWARE=1` skips knowingly).
#[test]
fn boards_built_from_plans_draw_the_hosts_frames() {
    if !qemu() {
        return;
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/plans-test");
    std::fs::create_dir_all(&dir).unwrap();
    // The M0 cannot hold the torus's vertices beside 8-row bands: its torus plan is a build of its own.
    for (board, core, groups) in [
        (
            "qemu-m4",
            Core::M4,
            vec![vec!["big", "overdraw", "small", "terrain", "torus"]],
        ),
        (
            "qemu-m0",
            Core::M0,
            vec![vec!["big", "overdraw", "small", "terrain"], vec!["torus"]],
        ),
    ] {
        for group in groups {
            let mut files = vec![];
            let mut want = std::collections::HashMap::new();
            for scene in &group {
                let p = plan(&workload(scene).unwrap(), budget(core, scene)).unwrap();
                let f = dir.join(format!("{scene}-{}.rs", core.name()));
                std::fs::write(&f, p.rust("the plan test")).unwrap();
                files.push(f.display().to_string());
                want.insert(scene.to_string(), (p.clone(), plan_hash(&p).unwrap()));
            }
            let out = run_board_env(board, &["plan"], &[("PLAN", &files.join(","))])
                .unwrap_or_else(|e| panic!("{e}"));
            let mut seen = 0;
            for line in out.lines().filter(|l| l.starts_with("bench ")) {
                let f = |k: &str| key(line, k);
                let (p, (hash, written, fragments)) = &want[&f("scene")];
                assert_eq!(f("hash"), format!("{hash:016x}"), "{line}");
                assert_eq!(f("pixels"), written.to_string(), "{line}");
                assert_eq!(f("fragments"), fragments.to_string(), "{line}");
                assert_eq!(
                    (f("format"), f("recip")),
                    (p.format.clone(), p.strategy.clone()),
                    "{line}"
                );
                assert_eq!(f("visibility_errors"), p.visibility_errors.to_string());
                seen += 1;
            }
            assert_eq!(seen, group.len(), "{board}: {out}");
        }
    }
}

/// `candidates` returns, in RAM order, the first plan of each format within the budget, each with the errors it
/// states; `plan` is the first of them. On W3 (a grid that never overlaps) no depth buffer, W16 and LZ16 all draw it
/// without an error; on W2 (overlapping triangles) no depth buffer cannot.
#[test]
fn candidates_are_the_first_of_each_format_within_the_budget() {
    let wl = workload("small").unwrap();
    let c = candidates(&wl, budget(Core::M4, "small"), 3).unwrap();
    let formats: Vec<&str> = c.iter().map(|p| p.format.as_str()).collect();
    assert_eq!(formats, ["none", "W16", "LZ16"]);
    assert!(c.iter().all(|p| p.budget_met && p.visibility_errors == 0));
    let first = plan(&wl, budget(Core::M4, "small")).unwrap();
    assert_eq!(
        (first.format, first.near, first.far),
        ("none".to_string(), c[0].near, c[0].far)
    );
    let wl = workload("overdraw").unwrap();
    let c = candidates(&wl, budget(Core::M4, "overdraw"), 2).unwrap();
    assert_eq!(c.len(), 2);
    assert!(c.iter().all(|p| p.format != "none" && p.budget_met));
    assert!(c[0].tried.iter().any(|t| t.0 == "none" && t.3 > 0));
}

/// `rank_measured` takes the fewest instructions, the first (least RAM) on a tie.
#[test]
fn measured_ranking_takes_the_fewest_instructions() {
    let wl = workload("small").unwrap();
    let c = candidates(&wl, budget(Core::M4, "small"), 3).unwrap();
    let p = rank_measured(c.clone(), &[3.0, 2.0, 2.0]);
    assert_eq!(
        (p.format.as_str(), p.ranked_by, p.instructions_per_frame),
        ("W16", "measured", Some(2.0))
    );
    assert_eq!(rank_measured(c, &[1.0, 1.0, 5.0]).format, "none");
}

/// `measure_on_board` runs each candidate in a firmware of its own on the core's board and reads its count, and the
/// measured ranking takes the cheapest of those counts: on W1 and W3, whose first two candidates are no depth buffer
/// and W16, on both cores. (Which one wins is a figure, not a result: the README reports it.) Needs QEMU, as
/// `firmware.rs` (`WRASTER_SKIP_FIRMWARE=1` skips knowingly).
#[test]
fn measured_ranking_runs_each_candidate_on_its_board() {
    if !qemu() {
        return;
    }
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/plans-test/measured");
    for core in [Core::M4, Core::M0] {
        for scene in ["small", "big"] {
            let wl = workload(scene).unwrap();
            let c = candidates(&wl, budget(core, scene), 2).unwrap();
            let formats: Vec<String> = c.iter().map(|p| p.format.clone()).collect();
            assert_eq!(formats, ["none", "W16"], "{scene} on {core:?}");
            let costs = measure_on_board(&c, &dir).unwrap();
            assert!(costs.iter().all(|&n| n > 0.0), "{costs:?}");
            let least = costs.iter().cloned().fold(f64::INFINITY, f64::min);
            let p = rank_measured(c, &costs);
            assert_eq!(
                (p.ranked_by, p.instructions_per_frame),
                ("measured", Some(least)),
                "{scene} on {core:?}: {costs:?}"
            );
            assert_eq!(
                p.format,
                formats[costs.iter().position(|&n| n == least).unwrap()]
            );
        }
    }
}

/// An OBJ mesh along a camera path (`obj:<file>`: two linked rings seen from 8 places on a circle): where the rings
/// pass in front of each other, drawing order alone shows the wrong one (the depth-less candidate counts its
/// errors), so the plan keeps W16 over the W the path draws, with no error; its Rust names no scene the boards
/// bake, so a board build from it stops with that message, and `--measure` says so too.
#[test]
fn an_obj_scene_plans_along_its_camera_path() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/links.obj");
    let wl = workload(&format!("obj:{path}")).unwrap();
    assert_eq!((wl.name.as_str(), wl.frames.len()), ("obj-links", 8));
    let p = plan(&wl, budget(Core::M4, "obj-links")).unwrap();
    assert!(
        p.tried.iter().any(|t| t.0 == "none" && t.3 > 100),
        "{:?}",
        p.tried
    );
    assert_eq!(
        (p.format.as_str(), p.visibility_errors, p.budget_met),
        ("W16", 0, true)
    );
    let (n, f) = (wl.state.range.near(), wl.state.range.far());
    assert!(p.near > n && p.far < f && p.near < p.far, "{p:?}");
    assert!(p
        .rust("test")
        .contains("panic!(\"the boards bake the standard scenes"));
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/plans-test/obj");
    assert!(measure_on_board(&[p], &dir)
        .unwrap_err()
        .contains("not obj-links"));
    assert!(workload("obj:/no/such/file.obj").is_err());
}

/// A W16 fast-tier plan with the coarse depth bound (`Plan::with_coarse`, what `--measure` also tries): its depth
/// and bound stay within the budget's RAM (shorter bands), other formats and strategies get none, and the boards
/// built from it (`--features plan,coarse`) print the host's hash, pixels and fragments, which are those of the same
/// plan without the bound. Needs QEMU, as `firmware.rs` (`WRASTER_SKIP_FIRMWARE=1` skips knowingly).
#[test]
fn coarse_plans_draw_the_same_frames() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/plans-test/coarse");
    std::fs::create_dir_all(&dir).unwrap();
    for (board, core, scenes) in [
        ("qemu-m4", Core::M4, vec!["overdraw", "torus"]),
        ("qemu-m0", Core::M0, vec!["overdraw"]),
    ] {
        let mut files = vec![];
        let mut want = std::collections::HashMap::new();
        for scene in scenes {
            let wl = workload(scene).unwrap();
            let b = budget(core, scene);
            let p = plan(&wl, b).unwrap();
            assert_eq!(p.format, "W16", "{scene}");
            let c = p.with_coarse(wl.w, wl.h, b.depth_ram).unwrap();
            assert!(
                c.coarse() && c.depth_ram <= b.depth_ram && c.band_rows < p.band_rows,
                "{c:?}"
            );
            assert_eq!(c.board_features(), ["plan", "coarse"]);
            let mut exact = p.clone();
            exact.strategy = "exact".into();
            assert!(exact.with_coarse(wl.w, wl.h, b.depth_ram).is_none());
            let host = plan_hash(&c).unwrap();
            assert_eq!(
                host,
                plan_hash(&p).unwrap(),
                "{scene}: the bound changed the frames"
            );
            let f = dir.join(format!("{scene}-{}.rs", core.name()));
            std::fs::write(&f, c.rust("the coarse plan test")).unwrap();
            files.push(f.display().to_string());
            want.insert(scene.to_string(), host);
        }
        if !qemu() {
            continue;
        }
        let out = run_board_env(board, &["plan", "coarse"], &[("PLAN", &files.join(","))])
            .unwrap_or_else(|e| panic!("{e}"));
        let mut seen = 0;
        for line in out.lines().filter(|l| l.starts_with("bench ")) {
            let f = |k: &str| key(line, k);
            let (hash, written, fragments) = want[&f("scene")];
            assert_eq!(
                (f("hash"), f("pixels"), f("fragments")),
                (
                    format!("{hash:016x}"),
                    written.to_string(),
                    fragments.to_string()
                ),
                "{line}"
            );
            seen += 1;
        }
        assert_eq!(seen, want.len(), "{board}: {out}");
    }
}
