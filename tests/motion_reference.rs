//! The independent reference for moving objects and lights: `tests/reference/motion_reference.py`,
//! written from docs/spec/motion.md (and the timeline, tracer, mesh, f32 and output pages) alone,
//! on top of `camera_reference.py`'s tracks, `mesh_reference.py`'s tracer, `texture_reference.py`'s
//! image maps and `film_reference.py`'s (and `film_f32_reference.py`'s) film frames, renders keyed
//! spheres, planes, meshes and lights (area lights included, a rect's edges keyed) at still and
//! open shutters and through a lens in f64 and f32, and an image-mapped plane whose `u_axis` turns
//! with its keyed normal, and compares every channel byte (PNG, and float EXR where Python has
//! OpenEXR) of 53 frames with rayreel.

mod common;

#[test]
fn the_independent_reference_reproduces_moving_frames() {
    common::independent_reference(
        &[
            "motion_reference.py",
            "camera_reference.py",
            "film_reference.py",
            "film_f32_reference.py",
            "mesh_reference.py",
            "texture_reference.py",
        ],
        "motion",
    );
}
