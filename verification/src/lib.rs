//! Property tests and Kani harnesses live in `tests/` and `src/harness.rs`.
