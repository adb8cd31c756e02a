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

impl ExecArgs {
    /// The execution settings these options name (refusing unknown names and levels this CPU lacks).
    fn exec(&self) -> lbdem::error::Result<lbdem::engine::exec::Exec> {
        lbdem::engine::exec::Exec::from_names(
            self.threads,
            self.simd.as_deref(),
            self.streaming.as_deref(),
        )
    }
}

/// Options of `run` and `resume`: the execution settings, the stop request raised by Ctrl-C/SIGTERM, and the
/// testing aid `LBDEM_TEST_HOLD=STEP:FILE` (see `lbdem::run::RunOptions::hold_at`).
fn run_options(
    exec: &ExecArgs,
    overwrite: bool,
    quiet: bool,
) -> lbdem::error::Result<lbdem::app::RunOptions> {
    let stop = lbdem::run::Stop::new();
    stop.install_signal_handler();
    let hold_at = std::env::var("LBDEM_TEST_HOLD").ok().and_then(|v| {
        let (step, file) = v.split_once(':')?;
        Some((step.parse().ok()?, PathBuf::from(file)))
    });
    Ok(lbdem::app::RunOptions {
        overwrite,
        quiet,
        exec: exec.exec()?,
        stop,
        stop_after: None,
        hold_at,
    })
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
        } => run_options(&exec, overwrite, quiet)
            .and_then(|opts| lbdem::app::run(&scene, &out, &opts))
            .map(|_| ()),
        Command::Resume { dir, exec, quiet } => run_options(&exec, false, quiet)
            .and_then(|opts| lbdem::app::resume(&dir, &opts))
            .map(|_| ()),
        Command::Check { scene } => lbdem::app::check(&scene).map(|s| print!("{s}")),
        Command::CompareBreaks { dirs, out } => lbdem::kinds::fracture::compare_breaks(&dirs, &out),
        Command::Study {
            study: StudyCommand::SpeedVsError { out, quick, exec },
        } => exec.exec().and_then(|exec| {
            let plan = if quick {
                lbdem::study::StudyPlan::quick()
            } else {
                lbdem::study::StudyPlan::full()
            };
            lbdem::study::speed_vs_error(&out, &plan, &exec, |r| {
                eprintln!("{}", lbdem::study::progress_line(r))
            })
            .map(|md| print!("{md}"))
        }),
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
