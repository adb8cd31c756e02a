//! The τ table: drag of the periodic square array of cylinders against Sangani & Acrivos (1982)
//! for τ ∈ {0.55, 0.6, 0.8, 1.2, 2.0} and c ∈ {0.2, 0.4, 0.6}, for every solid operator with BGK and with TRT
//! (Λ = 3/16) side by side, and the τ-independent method (TRT + ΩΛ) with both weightings.
//!
//! ```text
//! cargo run --release -p lbdem --example tau_table -- [--cell 40] [--only lambda] [--c 0.2,0.4,0.6]
//! ```
//! `--cell` sets the cell side l in nodes (default 40, the issue's); `--only lambda` runs the ΩΛ rows only,
//! `--only bgk` the BGK rows only. Each entry is the relative error of F/(μU) in percent; the drive is sized for
//! Re = 0.01 at every τ (see `driver/tests/common/psm_cases.rs`). Markdown on stdout, progress on stderr.
#[path = "../tests/common/psm_cases.rs"]
mod psm_cases;

use lbdem_kernels::fluid::collide::{LambdaTerms, SolidOperator, Weighting};
use psm_cases::{square_array, Fluid, Method, TAUS};

/// The operator's symbol, with ΩΛ's constants.
fn operator_name(m: Method) -> String {
    if m.solid != SolidOperator::LambdaConsistent {
        return m.solid.symbol().to_string();
    }
    let LambdaTerms { friction, pressure } = m.lambda;
    if pressure == 0.0 {
        format!("ΩΛ (κ = {friction})")
    } else {
        format!("ΩΛ (κ = {friction}, α = {pressure})")
    }
}

fn weighting_name(w: Weighting) -> &'static str {
    match w {
        Weighting::NobleTorczynski => "B₂ (NT)",
        Weighting::SolidFraction => "B = ε",
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |key: &str| {
        args.iter()
            .position(|a| a == key)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let cell: usize = value("--cell").map_or(40, |v| v.parse().expect("--cell N"));
    let only = value("--only");
    let cs: Vec<f64> = value("--c").map_or(vec![0.2, 0.4, 0.6], |v| {
        v.split(',').map(|x| x.parse().expect("--c list")).collect()
    });
    let mut methods = Vec::new();
    let ops = [
        SolidOperator::NonEquilibriumBounceBack,
        SolidOperator::Superposition,
        SolidOperator::MovingWallBounceBack,
        SolidOperator::LinearizedNonEquilibriumBounceBack,
    ];
    if only.as_deref() != Some("lambda") {
        for op in ops {
            for fluid in [Fluid::Bgk, Fluid::Trt(3.0 / 16.0)] {
                if only.as_deref() == Some("bgk") && fluid != Fluid::Bgk {
                    continue;
                }
                methods.push(Method {
                    fluid,
                    solid: op,
                    weighting: Weighting::NobleTorczynski,
                    lambda: LambdaTerms::FRICTION_ONLY,
                });
            }
        }
    }
    if only.as_deref() != Some("bgk") {
        methods.push(Method::LAMBDA_WALL);
        for weighting in [Weighting::SolidFraction, Weighting::NobleTorczynski] {
            methods.push(Method {
                weighting,
                ..Method::LAMBDA
            });
        }
    }
    println!("Drag error of the periodic square array against Sangani & Acrivos, l = {cell} nodes (Re = 0.01):");
    println!();
    print!("| operator | fluid | weighting | c |");
    for tau in TAUS {
        print!(" τ = {tau} |");
    }
    println!(" spread |");
    print!("|---|---|---|---|");
    for _ in TAUS {
        print!("---|");
    }
    println!("---|");
    for m in methods {
        for &c in &cs {
            let errors: Vec<f64> = TAUS
                .iter()
                .map(|&tau| {
                    let r = square_array(cell, c, tau, m);
                    eprintln!(
                        "{} {} {} c={c} τ={tau}: {:+.3} % ({} steps{})",
                        operator_name(m),
                        m.fluid.name(),
                        weighting_name(m.weighting),
                        100.0 * r.error,
                        r.steps,
                        if r.steady { "" } else { ", NOT steady" }
                    );
                    r.error
                })
                .collect();
            let lo = errors.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = errors.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            print!(
                "| {} | {} | {} | {c} |",
                operator_name(m),
                m.fluid.name(),
                weighting_name(m.weighting)
            );
            for e in &errors {
                print!(" {:+.2} % |", 100.0 * e);
            }
            println!(" {:.2} % |", 100.0 * (hi - lo));
        }
    }
}
