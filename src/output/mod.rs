//! Sinks: where finished frames go. Encoders turn a frame into bytes without I/O; `atomic`
//! puts bytes under a final name only once they are complete on disk.

pub mod atomic;
pub mod pattern;
pub mod png;
