//! Fluid index-arithmetic harness bodies.
