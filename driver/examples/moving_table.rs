//! The moving-solid table: every solid operator (Ω₁, Ω₂, Ω₃, Ω₁ₗ with BGK and NT's weighting;
//! ΩΛ with TRT, Λ = 3/16, B = ε) on four cases at τ ∈ {0.55, 0.8, 1.2, 2.0}:
//!
//! * Couette under a slab whose surface lies on a cell face: effective surface minus geometric (nodes);
//! * Stokes' first problem (slab started impulsively): largest deviation from U erfc(d/(2√(νt))) over U;
//! * slab sliding on a wall at rest: effective surface (nodes) and fluid momentum over its Couette value;
//! * the free disc of `scenes/terminal_velocity.toml` (grain/fluid density 2.65, and 1.0 with `--light`): drag
//!   error against S&A.
//!
//! "diverged" marks a run that left the bounded band (|u| ≤ 2U, density in [0.5, 1.5], finite).
//!
//! ```text
//! cargo run --release -p lbdem --example moving_table [-- --light]
//! cargo run --release -p lbdem --example moving_table -- --stability 1,1.25,1.5,2
//! ```
//!
//! `--stability` runs only the free disc with ΩΛ, one row per grain/fluid density ratio in the list (the
//! light-grain limit the scenes refuse or warn about, `lbdem::scene::check_free_grain_operator`).
#[path = "../tests/common/moving_cases.rs"]
mod moving_cases;

use moving_cases::{couette, free_disc, stokes_first_problem, touching_wall, Method, Outcome};

const TAUS: [f64; 4] = [0.55, 0.8, 1.2, 2.0];

fn cell(o: Outcome, f: impl Fn(&Outcome) -> String) -> String {
    if o.bounded {
        f(&o)
    } else {
        "diverged".into()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--stability") {
        let list: Vec<f64> = args
            .get(i + 1)
            .expect("--stability 1,1.25,...")
            .split(',')
            .map(|x| x.parse().expect("a density ratio"))
            .collect();
        let m = Method::LAMBDA;
        print!("| ΩΛ free disc: ρs/ρf |");
        for tau in TAUS {
            print!(" τ = {tau} |");
        }
        println!();
        print!("|---|");
        for _ in TAUS {
            print!("---|");
        }
        println!();
        for density in list {
            print!("| {density} |");
            for tau in TAUS {
                let s = cell(free_disc(m, tau, density), |o| {
                    format!("{:+.2} %", 100.0 * o.error)
                });
                eprintln!("ΩΛ free disc ρs/ρf = {density} τ={tau}: {s}");
                print!(" {s} |");
            }
            println!();
        }
        return;
    }
    let light = args.iter().any(|a| a == "--light");
    let density = if light { 1.0 } else { 2.65 };
    print!("| operator | case |");
    for tau in TAUS {
        print!(" τ = {tau} |");
    }
    println!();
    print!("|---|---|");
    for _ in TAUS {
        print!("---|");
    }
    println!();
    for m in Method::table() {
        let name = m.name();
        let row = |case: &str, f: &dyn Fn(f64) -> String| {
            print!("| {name} | {case} |");
            for tau in TAUS {
                let s = f(tau);
                eprintln!("{name} {case} τ={tau}: {s}");
                print!(" {s} |");
            }
            println!();
        };
        row("Couette, surface on a face: offset (nodes)", &|tau| {
            cell(couette(m, tau, 0.0), |o| format!("{:+.3}", o.error))
        });
        row("Couette, surface mid-cell (φ = ½): offset", &|tau| {
            cell(couette(m, tau, 0.5), |o| format!("{:+.3}", o.error))
        });
        row("Stokes' first problem: max error / U", &|tau| {
            cell(stokes_first_problem(m, tau), |o| {
                format!("{:.3} (fit {:+.2})", o.error, o.other)
            })
        });
        row(
            "slab on a wall: surface; fluid momentum / Couette",
            &|tau| {
                cell(touching_wall(m, tau), |o| {
                    format!("{:+.3}; {:.4}", o.error, o.other)
                })
            },
        );
        row(
            &format!("free disc (ρs/ρf = {density}): drag error"),
            &|tau| {
                cell(free_disc(m, tau, density), |o| {
                    format!("{:+.2} %", 100.0 * o.error)
                })
            },
        );
    }
}
