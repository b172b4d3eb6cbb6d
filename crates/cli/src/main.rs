//! `pcaline`: line detection, line mapping and localization aiding for 2D
//! LIDAR, on simulated scenes and real logs.
//!
//! Exit codes: 0 success, 2 bad input (unreadable, malformed or invalid file,
//! bad argument value), 1 any other failure. Results go to stdout or to files;
//! messages and progress go to stderr.

// The one crate that talks to a terminal.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod detect;
mod draw;
mod eval_cmd;
mod eval_real;
mod log_args;
mod map_cmd;
mod mcap_out;
mod out;
mod picture;
mod pipeline;
mod progress;
mod reproduce;
mod run;
mod scene_cmd;
mod svg;

/// Scans are parsed on one thread of the pool and freed on the writing
/// thread: glibc's allocator made them wait on each other's arena locks
/// (`perf`: a third of the writing thread's context switches), mimalloc
/// frees across threads without them (BENCHMARKS.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use clap::{Parser, Subcommand};
use pcaline_cli::{config_file, exit};
use std::process::ExitCode;

/// PCA-based line detection from 2D LIDAR range data (Opromolla et al. 2017), and beyond.
#[derive(Debug, Parser)]
#[command(name = "pcaline", version, about, long_about = None, after_help = EXAMPLES)]
struct Cli {
    /// Print nothing but results and errors.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Threads for work that is independent scan by scan or run by run
    /// (`detect`, the detection of `map`, the runs of `eval`). Default: one
    /// per core (or `RAYON_NUM_THREADS`). The results are the same byte for
    /// byte whatever the number.
    #[arg(long, global = true, value_name = "N", value_parser = count_at_least_one)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

const EXAMPLES: &str = "Examples:
  pcaline run                                   simulate the default maze, detect, summarise
  pcaline run sim-scenes/hall-pillars.toml --seed 3 --out out/hall
  pcaline scene check sim-scenes/*.toml
  pcaline scene generate --seed 7 --cols 6 --rows 4 -o my-maze.toml
  pcaline reproduce all                         the paper's Tables 1-3 and ETh experiment
  pcaline detect scans.bag --csv -o lines.csv   lines of every scan of a ROS 1 bag
  pcaline detect log.clf --fov 180               CARMEN FLASER lines of unusual beam counts
  pcaline map mit-csail.clf --out out/csail      line map and aided trajectory of a log
  pcaline draw scan scans.db3 --index 40 -o scan.svg   one scan as in the paper's Figures 1-3";

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a scene (default: the embedded paper-like maze), detect lines
    /// in every scan, and write pictures and JSON to an output folder.
    Run(run::RunArgs),
    /// Detect the lines of every scan of a log or scan file (CARMEN, ROS 1
    /// bag, ROS 2 bag, MCAP, JSON, CSV) and write them as JSON or CSV.
    Detect(detect::DetectArgs),
    /// Build the line map and the aided trajectory of a log, with the log's
    /// odometry as the localization source.
    Map(map_cmd::MapArgs),
    /// Pictures: one scan with its break-points, clusters and lines (Figures
    /// 1-3); a saved map with trajectories (Figure 10); headings over time (Figure 11).
    #[command(subcommand)]
    Draw(draw::DrawCommand),
    /// Generate, check or draw scene files.
    #[command(subcommand)]
    Scene(scene_cmd::SceneCommand),
    /// Evaluate line detection against ground truth on the shipped scenes
    /// (recall, false positives, fragmentation, errors) at several noise levels.
    Eval(eval_cmd::EvalArgs),
    /// Reproduce the paper's Tables 1-3 and its ETh experiment, with the
    /// paper's values beside ours.
    Reproduce(reproduce::ReproduceArgs),
}

/// A count option (`--runs`, `--scans`): a whole number of at least 1, so a
/// run over nothing cannot report "recall 1.000" and NaNs.
fn count_at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        Ok(_) => Err("must be at least 1".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// The error as one line: each cause in the chain once. A cause whose text
/// its parent already ends with (an I/O error behind a message that quotes
/// it) is not repeated.
fn one_line(err: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if line.ends_with(&text) || line.contains(&format!("{text}: ")) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

fn main() -> ExitCode {
    // An interrupted write leaves no temporary file (exit 130, as a shell
    // reports SIGINT).
    let _ = ctrlc::set_handler(|| {
        pcaline_io::remove_temporary_files();
        std::process::exit(130);
    });
    let cli = Cli::parse();
    if let Some(n) = cli.threads
        && let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(n).build_global()
    {
        eprintln!("error: --threads {n}: {e}");
        return ExitCode::FAILURE;
    }
    let result = match cli.command {
        Command::Run(args) => run::run(&args, cli.quiet),
        Command::Scene(cmd) => scene_cmd::run(&cmd, cli.quiet),
        Command::Detect(args) => detect::run(&args, cli.quiet),
        Command::Map(args) => map_cmd::run(&args, cli.quiet),
        Command::Draw(cmd) => draw::run(&cmd, cli.quiet),
        Command::Reproduce(args) => reproduce::run(&args, cli.quiet),
        Command::Eval(args) => eval_cmd::run(&args, cli.quiet),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if err.is::<exit::StdoutClosed>() => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", one_line(&err));
            exit::code_for(&err)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_chain_is_one_line_without_repeats() {
        let io = std::io::Error::from(std::io::ErrorKind::NotFound);
        let text = io.to_string();
        let err = anyhow::Error::from(pcaline_io::IoError::io("a.json", io));
        assert_eq!(one_line(&err), format!("a.json: {text}"));
        let err = anyhow::anyhow!("inner").context("outer");
        assert_eq!(one_line(&err), "outer: inner");
    }
}
