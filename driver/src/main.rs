//! The `lbdem` command line.
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Coupled lattice-Boltzmann / discrete-element simulator for porous rock.
#[derive(Parser)]
#[command(name = "lbdem", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its outputs (summary.json, CSV) into --out.
    Run {
        /// Scene file (TOML, physical units).
        scene: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Replace a previous run in the output directory.
        #[arg(long)]
        overwrite: bool,
        #[command(flatten)]
        exec: ExecArgs,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Continue an interrupted run (Ctrl-C, or stopped after a checkpoint) in DIR to its end, from
    /// DIR/checkpoint.bin and the scene copy DIR/scene.toml; the outputs equal an uninterrupted run's.
    Resume {
        /// Output directory of the interrupted run.
        dir: PathBuf,
        #[command(flatten)]
        exec: ExecArgs,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Validate a scene and print its derived lattice parameters without running it.
    Check {
        /// Scene file.
        scene: PathBuf,
    },
    /// Overlay the broken bonds against time of several fracture runs in one PNG (e.g. the permeability study).
    CompareBreaks {
        /// Output directories of fracture runs (each holds history.csv and scene.toml).
        dirs: Vec<PathBuf>,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Parameter studies over the validation problems.
    Study {
        #[command(subcommand)]
        study: StudyCommand,
    },
}

#[derive(Subcommand)]
enum StudyCommand {
    /// Error against wall time for the Poiseuille channels and the cylinder array, f32 and f64: writes
    /// speed_vs_error.csv, .png and .md into --out and prints the markdown table and recommendations.
    SpeedVsError {
        /// Output directory (created if missing; the study's files in it are replaced).
        #[arg(long)]
        out: PathBuf,
        /// Run only the coarse end of every resolution ladder (a few seconds).
        #[arg(long)]
        quick: bool,
        #[command(flatten)]
        exec: ExecArgs,
    },
}

/// How the work is executed: none of these options changes a single bit of the results, only speed and memory.
#[derive(clap::Args)]
struct ExecArgs {
    /// Worker threads (default: all cores). Results are bitwise identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Instruction set of the fluid's bulk pass (default: the widest this CPU has). Results are bitwise
    /// identical at every level; only speed changes.
    #[arg(long, value_parser = ["baseline", "avx2", "avx512"])]
    simd: Option<String>,
    /// Streaming scheme of the fluid (default: aa, in place, one population buffer). two-lattice uses two
    /// buffers and moves 1.5 times the bytes per step. Results are bitwise identical with either.
    #[arg(long, value_parser = ["aa", "two-lattice"])]
    streaming: Option<String>,
}

fn configure(exec: ExecArgs) -> bool {
    let ExecArgs {
        threads,
        simd,
        streaming,
    } = exec;
    if let Some(s) = streaming
        .as_deref()
        .and_then(lbdem::lattice::Streaming::from_name)
    {
        lbdem::lattice::set_default_streaming(s);
    }
    if let Some(name) = simd {
        let level = lbdem::exec::SimdLevel::from_name(&name);
        if let Err(e) = level
            .ok_or(format!("--simd {name}: unknown level"))
            .and_then(lbdem::exec::set_default_level)
        {
            eprintln!("lbdem: error: {e}");
            return false;
        }
    }
    if let Some(n) = threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
        {
            eprintln!("lbdem: cannot set up {n} threads: {e}");
            return false;
        }
    }
    true
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scene,
            out,
            overwrite,
            exec,
            quiet,
        } => {
            if !configure(exec) {
                return ExitCode::FAILURE;
            }
            lbdem::longrun::install_interrupt_handler();
            lbdem::run::run(&scene, &out, &lbdem::run::RunOptions { overwrite, quiet }).map(|_| ())
        }
        Command::Resume { dir, exec, quiet } => {
            if !configure(exec) {
                return ExitCode::FAILURE;
            }
            lbdem::longrun::install_interrupt_handler();
            lbdem::resume::resume(&dir, quiet)
        }
        Command::Check { scene } => lbdem::run::check(&scene).map(|s| print!("{s}")),
        Command::CompareBreaks { dirs, out } => lbdem::fracture::compare_breaks(&dirs, &out),
        Command::Study {
            study: StudyCommand::SpeedVsError { out, quick, exec },
        } => {
            if !configure(exec) {
                return ExitCode::FAILURE;
            }
            lbdem::study::speed_vs_error(&out, quick, true).map(|md| print!("{md}"))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ lbdem::error::LbdemError::Interrupted { .. }) => {
            eprintln!("lbdem: {e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("lbdem: error: {e}");
            ExitCode::FAILURE
        }
    }
}
