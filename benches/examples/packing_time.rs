//! Time `generate_packing` alone for a fracture scene (default `scenes/fracture/base.toml`: 1560 ellipses of
//! aspect 0.5, fill, growth, radius adjustment, final relaxation, point bonds), the slow part of the fracture
//! test's preparation. Uses only API that predates the packing speed-ups (`FractureScene::from_toml`,
//! `kinds::fracture::pack`), so the same file measures an older commit for an A/B comparison.
//!
//! `cargo run --release -p lbdem-benches --example packing_time -- [scene.toml] [threads] [repeats]`
//! (defaults base.toml, 1, 1). Prints per repeat the wall time and the process CPU time (user + system from
//! /proc/self/stat, 10 ms ticks; less disturbed by other processes on a shared machine), the steps, whether the
//! isotropic stress converged, the size factor, the wall stresses, the unbalanced-force ratio, the bonds, and a
//! checksum of every particle's position, angle and semi-axes bits and every bond's pair (equal checksums:
//! bitwise-identical packings).
use lbdem_benches::cpu_seconds;
use std::time::Instant;

use lbdem::kinds::fracture::{pack, FractureScene};
use lbdem_kernels::dem::shape::Shape;

/// FNV-1a over 64-bit words.
fn fnv(h: &mut u64, w: u64) {
    for b in w.to_le_bytes() {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "scenes/fracture/base.toml".into());
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let text = std::fs::read_to_string(&path).expect("scene file readable");
    let scene = FractureScene::from_toml(&text, &path).expect("valid fracture scene");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    for r in 0..repeats {
        let (w0, c0) = (Instant::now(), cpu_seconds());
        let packing = pool.install(|| pack(&scene)).expect("packing");
        let (wall, cpu) = (w0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        let world = &packing.world;
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for p in &world.particles {
            fnv(&mut h, p.position[0].to_bits());
            fnv(&mut h, p.position[1].to_bits());
            fnv(&mut h, p.angle.to_bits());
            match p.shape {
                Shape::Disc { radius } => fnv(&mut h, radius.to_bits()),
                Shape::Ellipse {
                    semi_major,
                    semi_minor,
                } => {
                    fnv(&mut h, semi_major.to_bits());
                    fnv(&mut h, semi_minor.to_bits());
                }
            }
        }
        for b in &world.bonds {
            fnv(&mut h, b.pair[0] as u64);
            fnv(&mut h, b.pair[1] as u64);
        }
        println!(
            "repeat {r} threads {threads}: wall {wall:.2} s, cpu {cpu:.2} s, {} particles, {} steps, converged {}, \
             size factor {:.6}, wall stresses {:.3?}, unbalanced {:.4}, bonds {}, checksum {h:016x}",
            world.particles.len(),
            packing.steps,
            packing.converged,
            packing.size_factor,
            packing.wall_stresses,
            packing.unbalanced_force_ratio,
            world.bonds.len(),
        );
    }
}
