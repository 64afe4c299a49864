//! The `drapery` command: run cloth scenes and write frame caches.
//!
//! `main` holds only the argument definitions and the dispatch; each subcommand lives in its own
//! file. Errors are printed as one line, `error: <message>`, with exit code 1; clap's own usage
//! errors keep clap's exit code 2. `drapery check` also exits with 1 when it finds an intersection.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod allocator;
mod bench;
mod check;
mod colliders;
mod formats;
mod render;
mod run;
mod state;
mod validate;
mod writer;

/// Implicit mass-spring cloth simulation (Baraff & Witkin 1998).
#[derive(Parser)]
#[command(name = "drapery", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and write one file per output frame.
    Run(run::RunArgs),
    /// Draw the frames of a run folder as an animated GIF or a PNG still.
    Render(render::RenderArgs),
    /// Time the standard benchmark scenes (hang, drape, pile) and print one table.
    Bench(bench::BenchArgs),
    /// Load and check a scene and its meshes without simulating; print what it holds.
    Validate(validate::ValidateArgs),
    /// Count intersections in the frames of a run: cloth through cloth and, with --scene, cloth
    /// inside colliders. Exit code 1 when anything intersects.
    Check(check::CheckArgs),
}

fn main() -> ExitCode {
    allocator::keep_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args).map(|()| true),
        Command::Validate(args) => validate::validate(args).map(|()| true),
        Command::Render(args) => render::render_cmd(args).map(|()| true),
        Command::Bench(args) => bench::bench(args).map(|()| true),
        Command::Check(args) => check::check(args),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            // One line, whatever the error chain holds.
            let msg = format!("{e:#}").replace(['\n', '\r'], " ");
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}
