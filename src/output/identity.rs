//! A frame's identity: the file it goes to, its fingerprint and the metadata its file records
//! (number, time, fps, fingerprint, camera matrices). What a run's frames share is hashed once
//! (`RunIdentity`); each frame adds its view (`shutter::FrameView`: its pose and its exposure,
//! built once per frame and handed on), so neither the renderer, the resume check nor the
//! encoders build a frame's camera again.

use super::fingerprint::{self, Hasher};
use super::format::FileFormat;
use super::record;
use crate::pattern::Pattern;
use crate::sequence::Sequence;
use crate::shutter::FrameView;
use std::path::PathBuf;

/// Where frame files go and in which format.
#[derive(Debug, Clone)]
pub(crate) struct Files {
    pub(crate) pattern: Pattern,
    pub(crate) format: FileFormat,
}

impl Files {
    /// The file of frame `n`.
    pub(crate) fn frame_path(&self, n: u64) -> PathBuf {
        self.pattern.frame_path(n)
    }
}

/// What a frame file records about itself.
#[derive(Debug, Clone)]
pub(crate) struct FrameMeta {
    pub(crate) frame: u64,
    pub(crate) time: f64,
    /// `framesPerSecond`: the exact fraction, or the closest that an EXR header holds.
    pub(crate) fps: (i32, u32),
    pub(crate) fingerprint: String,
    /// The settings record (`record::of_frame`).
    pub(crate) record: String,
    /// `worldToCamera` and `worldToNDC` (row-major, row vectors) when the frame has a camera.
    pub(crate) matrices: Option<[glam::DMat4; 2]>,
}

/// What every frame file of a run shares: the hash of the renderer's version, the scene, the
/// settings and the file format (`fingerprint::of_run`, and for EXR the frame rate its header
/// records), the frame rate, the image size and the run's lines of the settings record.
#[derive(Clone)]
pub(crate) struct RunIdentity {
    run: Hasher,
    record: String,
    fps: (i32, u32),
    size: (u32, u32),
}

impl RunIdentity {
    pub(crate) fn new(seq: &Sequence, format: &FileFormat) -> RunIdentity {
        let s = &seq.settings;
        let t = &seq.timeline;
        let fps = super::exr::frames_per_second(t.fps, t.clock.fraction);
        let run = fingerprint::of_run(&seq.scene, s, format);
        let exr = matches!(format, FileFormat::Exr { .. });
        RunIdentity {
            record: record::of_run(seq, format, exr.then_some(fps)),
            run: match exr {
                true => fingerprint::with_exr_rate(&run, fps),
                false => run,
            },
            fps,
            size: (s.width, s.height),
        }
    }

    /// The fingerprint of the frame `view` shows: what its file carries, and what the resume
    /// check compares an existing file with.
    pub(crate) fn fingerprint(&self, view: &FrameView) -> String {
        fingerprint::of_frame(&self.run, view)
    }

    /// The settings record of the frame `view` shows: what its file carries, and what the
    /// resume check compares an existing file's record with.
    pub(crate) fn record(&self, view: &FrameView) -> String {
        record::of_frame(&self.record, view)
    }

    /// Everything the file of the frame `view` shows records about it.
    pub(crate) fn meta(&self, view: &FrameView) -> FrameMeta {
        let (width, height) = self.size;
        FrameMeta {
            frame: view.frame,
            time: view.time,
            fps: self.fps,
            fingerprint: self.fingerprint(view),
            record: self.record(view),
            matrices: view
                .exposure
                .as_ref()
                .ok()
                .map(|e| e.camera.exr_matrices(width, height)),
        }
    }
}
