//! Snapshot tests of tiny deterministic scenes live in `tests/`.
