//! Snapshot tests of tiny deterministic scenes, one module per file of this directory, compiled into one test
//! binary. The snapshots are named `golden__<file>__<test>.snap` after the module path.
mod coupled_scene;
mod dem_beam;
mod fluid_scenes;
