//! Empty: the package exists for its test binary, `tests/judge` (see judge.rs).
