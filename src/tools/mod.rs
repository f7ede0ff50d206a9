//! The tools around the pipeline, never inside it: `preview` draws the camera path and a
//! contact sheet, `measure` weighs speed against accuracy on one frame, `bench` times this
//! machine. Each reads a `Sequence` and calls the tracer like any other caller.

pub(crate) mod bench;
pub mod measure;
pub mod meshgen;
pub mod preview;
