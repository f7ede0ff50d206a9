//! rayreel: sequence file → validated scene + timeline → per-frame camera → tracer → frame
//! buffer → sinks. `commands::run` is the whole program behind the command line.
//!
//! Visibility: `pub(crate)` is the default. The modules declared `pub` here, and the `pub`
//! items in them, are what `main.rs`, the integration tests (`tests/`), the benchmarks and the
//! fuzz targets reach; everything else is crate-private. Items of the private modules that
//! are `pub` are re-exported by a public module (`tracer` re-exports `settings`' types,
//! `tools::preview` `frameset::evenly_spaced`) or named in its public signatures.

/// Every `eprintln!` in this crate is this one, not std's: a stderr that fails (a full disk
/// under a farm's log, a closed terminal) is a lost console, never a reason to stop, so the
/// line is written and a failure ignored where std's would panic. Defined ahead of the
/// modules, so it shadows std's in every one of them.
macro_rules! eprintln {
    () => {
        $crate::console::stderr_write("\n")
    };
    ($($arg:tt)*) => {
        $crate::console::stderr_line(format_args!($($arg)*))
    };
}

mod budget;
pub mod camera;
mod claim;
pub mod cli;
pub mod commands;
pub mod console;
mod denoise;
pub mod frame;
mod frameset;
#[doc(hidden)]
pub mod fuzzing;
mod lanes;
pub mod output;
mod pattern;
mod plan;
mod progress;
mod regular;
pub mod scene;
pub mod schedule;
pub mod sequence;
mod settings;
pub mod shutter;
mod signals;
#[cfg(test)]
mod testing;
pub mod timeline;
pub mod tools;
pub mod tracer;
mod transfer;
mod warnings;
