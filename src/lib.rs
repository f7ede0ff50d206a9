//! rayreel: sequence file → validated scene + timeline → per-frame camera → tracer → frame
//! buffer → sinks. `run` is the whole program behind the command line.

pub mod camera;
pub mod claim;
pub mod cli;
pub mod console;
pub mod frame;
pub mod frameset;
mod lanes;
pub mod output;
pub mod plan;
pub mod progress;
pub mod scene;
pub mod schedule;
pub mod sequence;
pub mod shutter;
pub mod signals;
pub mod timeline;
pub mod tools;
pub mod tracer;
pub mod transfer;

mod commands;

pub use commands::run;

/// Everything that ends a run early, with the exit code it maps to.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The sequence file or a flag is wrong: nothing was rendered (exit 2).
    #[error(transparent)]
    Load(#[from] sequence::LoadError),
    /// The command line asks for something impossible (exit 2).
    #[error("{0}")]
    Usage(String),
    /// Rendering or writing failed (exit 1).
    #[error("{0}")]
    Failed(String),
    /// A run stopped short: a frame could not be rendered, encoded or written (exit 1).
    #[error(transparent)]
    Run(#[from] schedule::RunError),
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
            Error::Load(_) | Error::Usage(_) => 2,
            Error::Failed(_) | Error::Run(_) | Error::Incomplete(_) => 1,
            Error::Interrupted(_, code) => *code,
        }
    }
}
