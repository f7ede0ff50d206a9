//! rayreel: sequence file → validated scene + timeline → per-frame camera → tracer → frame
//! buffer → sinks. `commands::run` is the whole program behind the command line.

pub mod camera;
pub mod claim;
pub mod cli;
pub mod commands;
pub mod console;
pub mod frame;
pub mod frameset;
mod lanes;
pub mod output;
pub mod pattern;
pub mod plan;
pub mod progress;
pub mod scene;
pub mod schedule;
pub mod sequence;
pub mod settings;
pub mod shutter;
pub mod signals;
pub mod timeline;
pub mod tools;
pub mod tracer;
pub mod transfer;
pub mod warnings;
