//! The subcommands: each turns validated arguments into calls down the pipeline.

mod camera;
mod check;
mod estimate;
mod grain;
mod meshes;
mod poses;
mod render;
mod screen;
mod tools;
mod video;

use crate::cli::job::JobError;
use crate::cli::{Cli, Command};
use crate::console::{self, printable};
use crate::schedule::RunError;
use crate::sequence::{LoadError, Sequence};
use crate::warnings;
use std::path::Path;

/// The whole program behind the command line: `main` maps the error to its exit code.
pub fn run(cli: Cli) -> Result<(), Error> {
    STARTED.get_or_init(std::time::Instant::now);
    match cli.command {
        Command::Render(args) => render::render(args),
        Command::Status(args) => render::status(args),
        Command::Check(args) => check::check(args),
        Command::Preview(args) => tools::preview(args),
        Command::Camera(args) => camera::camera(args),
        Command::Measure(args) => tools::measure(args),
        Command::Bench(args) => tools::bench(args),
    }
}

/// When the command started: what loading the sequence took counts in an estimate's setup.
static STARTED: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

/// Everything that ends a run early, with the exit code it maps to.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The sequence file or a flag is wrong: nothing was rendered (exit 2).
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The command line asks for something impossible (exit 2).
    #[error("{0}")]
    Usage(String),
    /// Rendering or writing failed (exit 1).
    #[error("{0}")]
    Failed(String),
    /// A run stopped short: a frame could not be rendered, encoded or written (exit 1).
    #[error(transparent)]
    Run(#[from] RunError),
    /// `status` found frames that are not up to date (exit 1).
    #[error("{0}")]
    Incomplete(String),
    /// Ctrl-C or SIGTERM: the exit code is 128 + the signal (130 for SIGINT, 143 for SIGTERM).
    #[error("{0}")]
    Interrupted(String, u8),
}

impl Error {
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Load(LoadError::Memory { .. }) => 1,
            Error::Load(_) | Error::Usage(_) => 2,
            Error::Failed(_) | Error::Run(_) | Error::Incomplete(_) => 1,
            Error::Interrupted(_, code) => *code,
        }
    }
}

impl From<JobError> for Error {
    fn from(e: JobError) -> Error {
        match e {
            JobError::Load(e) => Error::Load(e),
            JobError::Usage(text) => Error::Usage(text),
        }
    }
}

fn print_warnings(seq: &Sequence) {
    for w in warnings::for_sequence(seq) {
        eprintln!("warning: {w}");
    }
}

/// The command's model libraries (`--assets`, RAYREEL_ASSETS); a folder that is not one is a
/// usage error.
fn assets(flags: &[std::path::PathBuf]) -> Result<Vec<std::path::PathBuf>, Error> {
    crate::cli::asset_folders(flags).map_err(Error::Usage)
}

/// A folder `name` in the frames' directory (`frames/orbit/preview`).
fn beside_frames(seq: &Sequence, name: &str) -> std::path::PathBuf {
    crate::plan::directory(Path::new(&seq.output)).join(name)
}

/// A path as the terminal may show it (see `console::printable`).
pub(crate) fn shown(path: &Path) -> String {
    printable(&path.display().to_string()).into_owned()
}

/// Text on stdout; a closed stdout is a normal end (see `console::print`).
pub(crate) fn out(text: &str) -> Result<(), Error> {
    console::print(text).map_err(Error::Failed)
}
