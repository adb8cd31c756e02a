//! Proof harness bodies, generic over a [`Chooser`](crate::Chooser). Each is run by a `#[kani::proof]` under
//! `cfg(kani)` and by a bounded-exhaustive `#[test]` otherwise (see `tests/proofs.rs`).
pub mod dem;
pub mod fluid;
