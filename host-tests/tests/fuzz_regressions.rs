//! Every input that ever failed a fuzz target (`fuzz/regressions/<target>/<what it found>`), replayed through the
//! same checks the targets run (`fuzz/src/checks.rs`), as an ordinary test. A new finding: copy its artifact there
//! under a name that says what it was.

#[allow(dead_code)]
#[path = "../../fuzz/src/lib.rs"]
mod wraster_fuzz;

use std::path::Path;

fn replay(target: &str, check: fn(&[u8])) -> usize {
    // The repository's fuzz/ (this file is also built into host-tests/mutants/, one level deeper).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .find(|d| d.join("fuzz/regressions").is_dir())
        .expect("fuzz/regressions above the manifest");
    let dir = root.join("fuzz/regressions").join(target);
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = e.unwrap().path();
        if path.file_name().is_some_and(|f| f == ".keep") {
            continue;
        }
        let data = std::fs::read(&path).unwrap();
        println!("{target}: {}", path.file_name().unwrap().to_string_lossy());
        check(&data);
        n += 1;
    }
    n
}

#[test]
fn raster_findings() {
    assert!(replay("raster", wraster_fuzz::checks::raster) >= 1);
}

#[test]
fn state_findings() {
    assert!(replay("state", wraster_fuzz::checks::state_target) >= 2);
}

#[test]
fn other_targets_findings() {
    // No finding yet on these targets; their directories exist so a new one lands here.
    replay("packed", wraster_fuzz::checks::packed);
    replay("world", wraster_fuzz::checks::world);
    replay("fixed_input", wraster_fuzz::checks::fixed_input);
}
