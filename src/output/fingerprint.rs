//! Fingerprints: a 128-bit hash of everything that decides a frame file's content — the scene
//! in canonical form, that frame's resolved camera, the render settings, the file format and
//! the renderer's version. It is stored inside the frame file (PNG tEXt chunk, EXR header
//! attribute), so a frame describes itself wherever it is copied, and shards on a shared
//! directory need no common manifest.

use crate::output::FileFormat;
use crate::scene::Scene;
use crate::tracer::Settings;
use crate::transfer::Encoding;

/// Key of the PNG text chunk and the EXR attribute that hold the fingerprint.
pub const KEY: &str = "rayreel:fingerprint";

/// FNV-1a over 128 bits: simple, stable across machines and releases of Rust.
#[derive(Clone, Copy)]
pub struct Hasher(u128);

impl Hasher {
    pub fn new() -> Hasher {
        Hasher(0x6c62272e07bb014262b821756295c58d)
    }

    pub fn write(&mut self, bytes: &[u8]) -> &mut Hasher {
        for &b in bytes {
            self.0 ^= u128::from(b);
            self.0 = self.0.wrapping_mul(0x0000000001000000000000000000013B);
        }
        self
    }

    pub fn hex(&self) -> String {
        format!("{:032x}", self.0)
    }
}

impl Default for Hasher {
    fn default() -> Self {
        Hasher::new()
    }
}

/// The part shared by every frame of a run: version, scene, settings and format. `Debug`
/// prints every f64 in its shortest round-trip form, which makes it a canonical text.
pub fn of_run(scene: &Scene, settings: &Settings, format: &FileFormat) -> Hasher {
    // EXR frames are linear whatever the encoding, which must not make them stale.
    let settings = match format {
        FileFormat::Exr { .. } => &Settings {
            encoding: Encoding::Linear,
            ..*settings
        },
        FileFormat::Png { .. } => settings,
    };
    let mut h = Hasher::new();
    h.write(concat!("rayreel ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
    h.write(format!("{scene:?}\n{settings:?}\n{:?}\n", format.content()).as_bytes());
    h
}

/// The fingerprint of one frame: the run's hash extended with the frame's camera, as text
/// (`exposure::describe`: the pose's `Debug` form, and the lens and the cameras of the open
/// interval when they matter).
pub fn of_frame(run: &Hasher, camera: &str) -> String {
    let mut h = *run;
    h.write(camera.as_bytes());
    h.hex()
}
