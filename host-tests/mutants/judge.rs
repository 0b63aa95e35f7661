//! The mutation run's judge (`host-tests/mutants.py`): the suites that judge the core's arithmetic against the f64
//! reference (every test file of host-tests/tests but the property tests, the commands and the firmware runs),
//! compiled into one test binary, so a mutant costs one crate's build instead of sixteen.
//! A package of its own (so a mutant does not rebuild host-tests' binaries too), with `test = false`: `cargo test`
//! does not run it, as the same tests run there as host-tests' own test binaries.

#[path = "../tests/bad_input.rs"]
mod bad_input;
#[path = "../tests/bias.rs"]
mod bias;
#[path = "../tests/bins.rs"]
mod bins;
#[path = "../tests/boundaries.rs"]
mod boundaries;
#[path = "../tests/clip.rs"]
mod clip;
#[path = "../tests/coarse.rs"]
mod coarse;
#[path = "../tests/compare.rs"]
mod compare;
#[path = "../tests/cull.rs"]
mod cull;
#[path = "../tests/fixed_input.rs"]
mod fixed_input;
#[path = "../tests/formats.rs"]
mod formats;
#[path = "../tests/fuzz_regressions.rs"]
mod fuzz_regressions;
#[path = "../tests/golden.rs"]
mod golden;
#[path = "../tests/gouraud.rs"]
mod gouraud;
#[path = "../tests/grazing.rs"]
mod grazing;
#[path = "../tests/long_edges.rs"]
mod long_edges;
#[path = "../tests/mesh.rs"]
mod mesh;
#[path = "../tests/mock_display.rs"]
mod mock_display;
#[path = "../tests/primitives.rs"]
mod primitives;
#[path = "../tests/reference.rs"]
mod reference;
#[path = "../tests/seed_numbers.rs"]
mod seed_numbers;
#[path = "../tests/stiff.rs"]
mod stiff;
