//! The independent reference for textured frames: `tests/reference/texture_reference.py`, written
//! from docs/spec/texture.md (and the tracer, mesh and output pages) alone, on top of
//! `mesh_reference.py`'s tracer, renders its scenes and compares every channel byte with rayreel.

mod common;

#[test]
fn the_independent_reference_reproduces_texture_frames() {
    common::independent_reference(&["texture_reference.py", "mesh_reference.py"], "texture");
}
