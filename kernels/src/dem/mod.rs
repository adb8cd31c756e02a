//! Discrete-element kernels (issue 3): shapes, contact detection, contact and bond laws, integration.
