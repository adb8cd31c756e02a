//! Checkpoint payloads behind a valid envelope: the input is the payload (postcard bytes of a state); the
//! target seals it with a correct header and SHA-256 checksum, as a file written by lbdem would carry, so every
//! mutation reaches the decoder instead of failing the checksum (the `checkpoint` target covers the envelope).
//! A coupled-demo state that decodes is then resumed and advanced by one chunk, as `lbdem resume` would: a
//! decoded state must be refused with an error or run, never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lbdem::engine::exec::Exec;
use lbdem::kinds::coupled_demo::{CoupledDemo, DemoState};
use lbdem::run::checkpoint::{scene_hash, Checkpoint, Persist, FORMAT_VERSION, MAGIC};
use lbdem::run::{Case, Kind};
use sha2::{Digest, Sha256};

const SCENE: &str = "[scene]\nkind = \"coupled_demo\"\n[demo]\nnx = 32\nny = 32\ntau = 0.8\ndiscs = 2\nradius = 4.0\nspeed = 0.01\nsteps = 80\nrecord_interval = 10\n";

/// `payload` in a sealed envelope of kind `coupled_demo` and float width `precision`.
fn sealed(payload: &[u8], precision: u8) -> Vec<u8> {
    let kind = CoupledDemo::NAME;
    let mut out = Vec::with_capacity(payload.len() + 128);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.push(precision);
    out.extend_from_slice(&(kind.len() as u32).to_le_bytes());
    out.extend_from_slice(kind.as_bytes());
    out.extend_from_slice(&scene_hash(SCENE));
    out.extend_from_slice(&0u64.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    let mut h = Sha256::new();
    h.update(&out);
    h.update(payload);
    let digest: [u8; 32] = h.finalize().into();
    out.extend_from_slice(&digest);
    out.extend_from_slice(payload);
    out
}

fn decode<S: Persist>(payload: &[u8]) -> Option<S> {
    let precision = if S::PRECISION == 0 { 8 } else { S::PRECISION };
    Checkpoint::from_bytes::<S>(&sealed(payload, precision), SCENE, CoupledDemo::NAME)
        .ok()
        .map(|(_, s)| s)
}

fuzz_target!(|data: &[u8]| {
    let _ = decode::<lbdem::engine::dem::DemWorld<f64>>(data);
    let _ = decode::<lbdem::engine::lattice::FluidLattice<f32>>(data);
    let Some(mut state) = decode::<DemoState>(data) else {
        return;
    };
    let case = Case::<CoupledDemo>::read(SCENE, "fuzz.toml").expect("the fuzz scene is valid");
    if CoupledDemo::resume(&case, &mut state, &Exec::default()).is_err() {
        return;
    }
    if !CoupledDemo::finished(&case, &state) {
        let _ = CoupledDemo::advance(&case, &mut state, None);
    }
});
