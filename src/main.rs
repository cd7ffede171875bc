//! The `grainflow` command: `run` a case, or `check` it.

use clap::{Parser, Subcommand};
use grainflow::case::Case;
use grainflow::{check, simulation, RunError};
use grainflow_core::Communicator;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "grainflow",
    version,
    about = "Resolved grains in fluids: soft-sphere DEM, immersed boundaries, hard contact"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case file.
    Run {
        case: PathBuf,
        /// Output directory (default: out/<case name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a key of the case file, e.g. --set time.end=0.1
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// Threads (default: one per 10,000 grains of a dry scene, at most
        /// the cores; all cores for a fluid).
        #[arg(long)]
        threads: Option<usize>,
        /// Print the whole summary as JSON (what `summary.json` holds)
        /// instead of the few lines for a person.
        #[arg(long)]
        json: bool,
        /// Resume from a checkpoint: `latest` (the newest in the output
        /// folder), `auto` (the newest if any, else start afresh) or a
        /// checkpoint folder. The case may change only its end time,
        /// outputs, checkpoints and wall limit.
        #[arg(long, value_name = "latest|auto|CHECKPOINT")]
        restart: Option<simulation::Restart>,
    },
    /// Validate a case and print its derived numbers without running it.
    Check {
        case: PathBuf,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// Also show how the scene would be shared among this many MPI
        /// ranks (process grid, grains and cells per rank).
        #[arg(long)]
        ranks: Option<usize>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // With the feature `mpi`, every process is a rank of the MPI job (one
    // rank when started without mpirun); the universe finalises MPI at exit.
    #[cfg(feature = "mpi")]
    let universe = match grainflow_core::communicator::mpi_backend::initialize() {
        Some(universe) => universe,
        None => {
            eprintln!("error: MPI could not be initialised");
            return ExitCode::from(5);
        }
    };
    #[cfg(feature = "mpi")]
    let communicator = Communicator::world(universe.world());
    #[cfg(not(feature = "mpi"))]
    let communicator = Communicator::serial();
    if communicator.size() > 1 {
        // A panic on one rank must stop the others, not leave them waiting.
        let abort_on = communicator.clone();
        let default_hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            default_hook(info);
            abort_on.abort_others(&format!("{info}"));
        }));
    }
    let root = communicator.is_root();
    match cli.command {
        Command::Run {
            case,
            out,
            overrides,
            threads,
            json,
            restart,
        } => {
            let mut overrides = overrides;
            if let Some(n) = threads {
                // The pool for the flow; the DEM reads it from the case.
                let _ = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build_global();
                overrides.push(format!("parallel.threads={n}"));
            }
            let loaded = match Case::load(&case, &overrides) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            let out = out.unwrap_or_else(|| {
                PathBuf::from("out")
                    .join(case.file_stem().map(|s| s.to_owned()).unwrap_or_default())
            });
            // Case errors and instabilities are found by every rank alike
            // (the checks are global); an output error is one rank's own and
            // stops the job.
            let options = simulation::RunOptions {
                show_progress: true,
                listen_to_signals: true,
                restart,
            };
            match simulation::run_with(&loaded, &out, communicator.clone(), &options) {
                Ok(summary) if summary.stopped.is_some() => {
                    if root {
                        eprintln!("{}", summary.stopped.unwrap_or_default());
                    }
                    ExitCode::from(simulation::stop::EXIT_STOPPED)
                }
                Ok(summary) => {
                    if root && json {
                        println!("{}", serde_json::to_string_pretty(&summary.json).unwrap());
                    } else if root {
                        print!("{}", grainflow::report::text(&loaded, &summary.json, &out));
                    }
                    ExitCode::SUCCESS
                }
                Err(RunError::Case(message)) => {
                    if root {
                        eprintln!("error: {message}");
                    }
                    ExitCode::from(2)
                }
                Err(RunError::Unstable(message)) => {
                    if root {
                        eprintln!(
                            "error: {message}\nthe outputs in {} hold the last good state",
                            out.display()
                        );
                    }
                    ExitCode::from(3)
                }
                Err(RunError::Io(e)) => {
                    let message = format!("writing {}: {e}", out.display());
                    communicator.abort_others(&message);
                    eprintln!("error: {message}");
                    ExitCode::from(4)
                }
            }
        }
        Command::Check {
            case,
            overrides,
            ranks,
        } => {
            let loaded = match Case::load(&case, &overrides) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            match check::report_on(&loaded, ranks.unwrap_or(1)) {
                Ok(text) => {
                    print!("{text}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
    }
}
