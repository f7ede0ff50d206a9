//! The independent reference for adaptive sampling of frames that are not film frames:
//! `tests/reference/adaptive_reference.py`, written from docs/spec/tracer.md (**Sample offsets**,
//! **Adaptive passes** with *Smooth pixels*, **Pixel**) and docs/spec/texture.md (**The pixel**)
//! alone, on top of `texture_reference.py`'s textured frames, `mesh_reference.py`'s tracer and
//! `motion_reference.py`'s sphere and rect lights, renders checker scenes (shadows, reflections, a
//! sky, spot lights, area lights (soft shadows, a rect's back side, light points below the
//! horizon, beside point and spot lights), neighbouring checker objects, `max_depth: 1`, an image
//! beside a checker, a mesh, glass) and plain ones with one, two (R2) and four (stratified)
//! first-pass samples, and compares every channel value of 8- and 16-bit PNGs with rayreel.

mod common;

#[test]
fn the_independent_reference_reproduces_adaptive_frames() {
    common::independent_reference(
        &[
            "adaptive_reference.py",
            "texture_reference.py",
            "mesh_reference.py",
            "motion_reference.py",
            "camera_reference.py",
            "film_reference.py",
        ],
        "adaptive",
    );
}
