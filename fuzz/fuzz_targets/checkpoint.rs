//! Checkpoint bytes → the decoder (header, checksum, payload) for a coupled and a DEM state: must refuse
//! damaged input with an error, never panic or allocate without bound.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lbdem::run::checkpoint::Checkpoint;

const SCENE: &str = "[scene]\nkind = \"coupled_demo\"\n";

fuzz_target!(|data: &[u8]| {
    let _ = Checkpoint::from_bytes::<lbdem::kinds::coupled_demo::DemoState>(data, SCENE, "coupled_demo");
    let _ = Checkpoint::from_bytes::<lbdem::engine::dem::DemWorld<f64>>(data, SCENE, "coupled_demo");
});
