//! Fingerprints: a 128-bit hash of everything that decides a frame file's content — the scene
//! in canonical form, that frame's resolved camera, the render settings, the file format and
//! the renderer's version. It is stored inside the frame file (PNG tEXt chunk, EXR header
//! attribute), so a frame describes itself wherever it is copied, and shards on a shared
//! directory need no common manifest.

use super::format::{ExrPrecision, FileFormat};
use crate::camera::{Camera, Pose};
use crate::scene::{Intensity, Light, Material, Object, Scene, Shape, Sky, Texture};
use crate::settings::{Adaptive, Precision, Sampler, Settings};
use crate::shutter::{Exposure, FrameView, Staged};
use crate::timeline::motion::{Posed, Thing};
use crate::transfer::Encoding;
use glam::DVec3;

/// Key of the PNG text chunk and the EXR attribute that hold the fingerprint.
pub(crate) const KEY: &str = "rayreel:fingerprint";

/// FNV-1a over 128 bits: simple, stable across machines and releases of Rust.
#[derive(Clone, Copy)]
pub(crate) struct Hasher(u128);

impl Hasher {
    pub(crate) fn new() -> Hasher {
        Hasher(0x6c62272e07bb014262b821756295c58d)
    }

    pub(crate) fn write(&mut self, bytes: &[u8]) -> &mut Hasher {
        for &b in bytes {
            self.0 ^= u128::from(b);
            self.0 = self.0.wrapping_mul(0x0000000001000000000000000000013B);
        }
        self
    }

    pub(crate) fn hex(&self) -> String {
        format!("{:032x}", self.0)
    }
}

impl Default for Hasher {
    fn default() -> Self {
        Hasher::new()
    }
}

/// Names the encoding below; a change to it (a field added, an order changed) must change
/// this name, so frames made under the old one count as stale rather than as the same job.
pub(crate) const ENCODING: &str = "rayreel fingerprint v2";

/// The part shared by every frame of a run: the renderer's version, then the scene, the
/// render settings and the file content in the canonical encoding of `Canon`.
pub(crate) fn of_run(scene: &Scene, settings: &Settings, format: &FileFormat) -> Hasher {
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
    h.write(ENCODING.as_bytes());
    scene.canon(&mut h);
    settings.canon(&mut h);
    format.canon(&mut h);
    h
}

/// The run's hash extended with what an EXR header records for the whole run beyond its
/// pixels: `framesPerSecond` (numerator and denominator as stored), after the bytes
/// `exr rate`. A PNG records no frame rate, and its fingerprint stays as it was.
pub(crate) fn with_exr_rate(run: &Hasher, (num, den): (i32, u32)) -> Hasher {
    let mut h = *run;
    h.write(b"exr rate");
    h.write(&num.to_le_bytes());
    den.canon(&mut h);
    h
}

/// The fingerprint of one frame: the run's hash extended with the frame's number (its
/// samples are seeded from it), its camera pose at the frame time, and what its exposure adds:
/// the lens when open, and the camera at every instant of the shutter's open interval when the
/// camera moves while it is open (a still camera gives the same image with a shutter or
/// without, and the same fingerprint); last, the time the file records (`rayreel:time`, in a
/// PNG's text and an EXR's header), which a change of fps or first frame moves even where the
/// camera holds still: a fingerprint covers everything its file states.
pub(crate) fn of_frame(run: &Hasher, view: &FrameView) -> String {
    let mut h = *run;
    view.frame.canon(&mut h);
    view.pose.canon(&mut h);
    match &view.exposure {
        Ok(e) => {
            let lens = (e.camera.lens_radius > 0.0)
                .then_some([e.camera.lens_radius, e.camera.focus_distance]);
            tagged(&mut h, 0, &[&lens, &e.instants]);
        }
        // Never rendered: the run stops on it.
        Err(_) => tagged(&mut h, 1, &[]),
    }
    view.time.canon(&mut h);
    // Only where objects or lights move: their poses at the frame's time and at each
    // instant of the open shutter while they move during it.
    if let Some(m) = motion(view) {
        poses(&mut h, m);
    }
    // Only with the motion pass, whose run part already differs (`Settings`).
    if let Some(next) = &view.next {
        h.write(b"next camera");
        next.camera.canon(&mut h);
        // Only where things move, so other frames keep their fingerprints.
        if !next.poses.is_empty() {
            h.write(b"next poses");
            next.poses.canon(&mut h);
        }
    }
    h.hex()
}

/// The poses of the objects and lights that move during the frame `view` shows, if any do.
pub(crate) fn motion(view: &FrameView) -> Option<&Staged> {
    match &view.exposure {
        Ok(Exposure {
            motion: Some(m), ..
        }) => Some(m),
        _ => None,
    }
}

/// The bytes `poses`, then the poses at the frame's time and at each instant.
pub(crate) fn poses(h: &mut Hasher, m: &Staged) {
    h.write(b"poses");
    m.at.canon(h);
    m.instants.canon(h);
}

/// The canonical encoding: every value as fixed-size little-endian bytes (an f64 as its
/// IEEE-754 bits, so nothing depends on how numbers print), a list as its length then its
/// items, an enum as a tag byte then its fields, a struct as its fields in declaration
/// order. Structs are destructured whole, so a field added without being encoded here does
/// not compile.
pub(crate) trait Canon {
    fn canon(&self, h: &mut Hasher);
}

impl Canon for f64 {
    fn canon(&self, h: &mut Hasher) {
        h.write(&self.to_bits().to_le_bytes());
    }
}

impl Canon for f32 {
    fn canon(&self, h: &mut Hasher) {
        h.write(&self.to_bits().to_le_bytes());
    }
}

impl Canon for u64 {
    fn canon(&self, h: &mut Hasher) {
        h.write(&self.to_le_bytes());
    }
}

impl Canon for u32 {
    fn canon(&self, h: &mut Hasher) {
        h.write(&self.to_le_bytes());
    }
}

impl Canon for usize {
    fn canon(&self, h: &mut Hasher) {
        (*self as u64).canon(h);
    }
}

impl Canon for bool {
    fn canon(&self, h: &mut Hasher) {
        h.write(&[u8::from(*self)]);
    }
}

impl Canon for DVec3 {
    fn canon(&self, h: &mut Hasher) {
        [self.x, self.y, self.z].iter().for_each(|v| v.canon(h));
    }
}

impl<T: Canon> Canon for [T] {
    fn canon(&self, h: &mut Hasher) {
        self.len().canon(h);
        self.iter().for_each(|v| v.canon(h));
    }
}

impl<T: Canon> Canon for Vec<T> {
    fn canon(&self, h: &mut Hasher) {
        self[..].canon(h);
    }
}

impl<T: Canon, const N: usize> Canon for [T; N] {
    fn canon(&self, h: &mut Hasher) {
        self.iter().for_each(|v| v.canon(h));
    }
}

impl<T: Canon> Canon for Option<T> {
    fn canon(&self, h: &mut Hasher) {
        match self {
            None => {
                h.write(&[0]);
            }
            Some(v) => {
                h.write(&[1]);
                v.canon(h);
            }
        }
    }
}

/// `canon_struct!(Type { a, b })`: encodes a `Type` field by field, in the order given (the
/// declaration order). The value is destructured whole, so a field added to `Type` and not
/// listed here does not compile.
macro_rules! canon_struct {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        impl Canon for $ty {
            fn canon(&self, h: &mut Hasher) {
                let $ty { $($field),* } = self;
                $($field.canon(h);)*
            }
        }
    };
}

/// A moving object (tag 0) or light (tag 1) by its index.
impl Canon for Thing {
    fn canon(&self, h: &mut Hasher) {
        match self {
            Thing::Object(i) => tagged(h, 0, &[i]),
            Thing::Light(i) => tagged(h, 1, &[i]),
        }
    }
}

/// An object or light as posed, encoded as in the scene.
impl Canon for Posed {
    fn canon(&self, h: &mut Hasher) {
        match self {
            Posed::Object(o) => o.canon(h),
            Posed::Light(l) => l.canon(h),
        }
    }
}

impl<A: Canon, B: Canon> Canon for (A, B) {
    fn canon(&self, h: &mut Hasher) {
        self.0.canon(h);
        self.1.canon(h);
    }
}

/// A tag byte, then the fields.
fn tagged(h: &mut Hasher, tag: u8, fields: &[&dyn Canon]) {
    h.write(&[tag]);
    fields.iter().for_each(|f| f.canon(h));
}

/// A scene without meshes encodes exactly as before meshes existed; with them, each mesh's
/// content (the digest of its file's bytes) follows, so a changed model makes frames stale.
impl Canon for Scene {
    fn canon(&self, h: &mut Hasher) {
        let Scene {
            objects,
            meshes,
            materials,
            lights,
            background,
            sky,
        } = self;
        objects.canon(h);
        materials.canon(h);
        lights.canon(h);
        background.canon(h);
        if !meshes.is_empty() {
            h.write(b"meshes");
            meshes.len().canon(h);
            meshes.iter().for_each(|m| m.digest.canon(h));
        }
        // A flat background encodes as before skies existed.
        if let Some(sky) = sky {
            h.write(b"sky");
            sky.canon(h);
        }
    }
}

/// An image sky by its content (the digest of its file and decoding), its turn and
/// intensity; a gradient by its three colours.
impl Canon for Sky {
    fn canon(&self, h: &mut Hasher) {
        match self {
            Sky::Image {
                image,
                rotate,
                intensity,
            } => tagged(h, 0, &[&image.digest, rotate, intensity]),
            Sky::Gradient {
                zenith,
                horizon,
                ground,
            } => tagged(h, 1, &[zenith, horizon, ground]),
        }
    }
}

impl Canon for Object {
    fn canon(&self, h: &mut Hasher) {
        let Object { shape, material } = self;
        match shape {
            Shape::Sphere { center, radius } => tagged(h, 0, &[center, radius]),
            // A plane without `u_axis` encodes as before textures existed.
            Shape::Plane {
                point,
                normal,
                u_axis: None,
            } => tagged(h, 1, &[point, normal]),
            Shape::Plane {
                point,
                normal,
                u_axis: Some(u),
            } => tagged(h, 3, &[point, normal, u]),
            Shape::Mesh {
                mesh,
                place,
                shading,
            } => {
                let r = place.rotation;
                let rotation = [r.x_axis, r.y_axis, r.z_axis];
                let shading = *shading as u32;
                tagged(
                    h,
                    2,
                    &[mesh, &place.scale, &rotation, &place.translate, &shading],
                )
            }
        }
        material.canon(h);
    }
}

/// A material without textures encodes as before textures existed; a texture follows its
/// tag (`maps`), an image by its content (the digest of its file and decoding) and scale.
impl Canon for Material {
    fn canon(&self, h: &mut Hasher) {
        let Material {
            ambient,
            diffuse,
            specular,
            exponent,
            specular_floor,
            reflection,
            transmission,
            ior,
            fresnel,
            diffuse_map,
            ambient_map,
        } = self;
        let plain: [&dyn Canon; 9] = [
            ambient,
            diffuse,
            specular,
            exponent,
            specular_floor,
            reflection,
            transmission,
            ior,
            fresnel,
        ];
        plain.iter().for_each(|f| f.canon(h));
        if diffuse_map.is_some() || ambient_map.is_some() {
            h.write(b"maps");
            diffuse_map.canon(h);
            ambient_map.canon(h);
        }
    }
}

impl Canon for Texture {
    fn canon(&self, h: &mut Hasher) {
        match self {
            // Tag 3 since adaptive marks skip pixels smooth on one object (2 since eye hits
            // read the pixel's average, 0 before): checker frames written under an earlier
            // rule count as stale once.
            Texture::Checker { size, colors } => tagged(h, 3, &[size, colors]),
            Texture::Image { image, scale } => {
                let scale = [scale.x, scale.y];
                tagged(h, 1, &[&image.digest, &scale])
            }
        }
    }
}

canon_struct!(Intensity {
    ambient,
    diffuse,
    specular,
});

impl Canon for Light {
    fn canon(&self, h: &mut Hasher) {
        match self {
            Light::Point {
                position,
                intensity,
            } => tagged(h, 0, &[position, intensity]),
            Light::Directional {
                to_light,
                intensity,
            } => tagged(h, 1, &[to_light, intensity]),
            Light::Spot {
                position,
                axis,
                cos_inner,
                cos_outer,
                intensity,
            } => tagged(h, 2, &[position, axis, cos_inner, cos_outer, intensity]),
            Light::Ambient { color } => tagged(h, 3, &[color]),
            Light::Sphere {
                center,
                radius,
                samples,
                intensity,
            } => tagged(h, 4, &[center, radius, samples, intensity]),
            Light::Rect {
                corner,
                edge_u,
                edge_v,
                normal,
                samples,
                intensity,
            } => tagged(h, 5, &[corner, edge_u, edge_v, normal, samples, intensity]),
        }
    }
}

impl Canon for Settings {
    fn canon(&self, h: &mut Hasher) {
        let Settings {
            width,
            height,
            max_depth,
            depth,
            samples,
            adaptive,
            sampler,
            // Enters through each frame's cameras (`of_frame`), so a frame whose camera holds
            // still while the shutter is open keeps its fingerprint.
            shutter: _,
            alpha,
            exposure,
            encoding,
            precision,
            aov,
            denoise,
        } = self;
        let fields: [&dyn Canon; 6] = [width, height, max_depth, depth, samples, adaptive];
        fields.iter().for_each(|f| f.canon(h));
        let tag = match sampler {
            Sampler::Stratified => 0,
            Sampler::Random => 1,
        };
        h.write(&[tag]);
        let fields: [&dyn Canon; 2] = [alpha, exposure];
        fields.iter().for_each(|f| f.canon(h));
        h.write(&[match encoding {
            Encoding::Srgb => 0,
            Encoding::Linear => 1,
        }]);
        // Optional, so every f64 frame keeps the fingerprint it had: f32 adds the byte 2,
        // which no file-format tag (0, 1) that follows the settings takes.
        if *precision == Precision::F32 {
            h.write(&[2]);
        }
        // Optional too: passes add the byte 3 and their bits, a tag nothing else here takes.
        if !aov.is_empty() {
            h.write(&[3, aov.bits()]);
        }
        // And the film filter adds the byte 5 (it is only ever on for film). It was 4 before
        // lens frames took the filter's three passes: film frames written then are stale once.
        if *denoise {
            h.write(&[5]);
        }
    }
}

canon_struct!(Adaptive {
    threshold,
    max_samples,
});

/// What decides the decoded content; PNG compression only changes how it is packed.
impl Canon for FileFormat {
    fn canon(&self, h: &mut Hasher) {
        match self {
            FileFormat::Png { sixteen_bit, .. } => tagged(h, 0, &[sixteen_bit]),
            FileFormat::Exr { precision } => {
                let float = *precision == ExrPrecision::Float;
                tagged(h, 1, &[&float])
            }
        }
    }
}

canon_struct!(Pose {
    position,
    look_at,
    up,
    fov,
});

canon_struct!(Camera {
    origin,
    forward,
    right,
    up,
    tan_half_fov,
    lens_radius,
    focus_distance,
});

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shutter::Shutter;
    use crate::timeline::Timeline;

    /// A still camera at (x, 0, 1) looking at the origin, with a lens of `aperture`.
    fn still(x: f64, aperture: f64) -> Timeline {
        let pose = Pose {
            position: DVec3::new(x, 0.0, 1.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov: 90.0,
        };
        Timeline::still(crate::timeline::Key {
            time: 0.0,
            pose,
            ease: crate::timeline::Ease::Pass,
            aperture,
            focus_distance: None,
        })
    }

    #[test]
    fn the_encoding_is_what_the_readme_says() {
        let settings = Settings {
            width: 2,
            height: 1,
            max_depth: 3,
            depth: false,
            samples: 1,
            adaptive: None,
            sampler: Sampler::Stratified,
            shutter: None,
            alpha: false,
            exposure: 0.0,
            encoding: Encoding::Srgb,
            precision: Precision::F64,
            aov: Default::default(),
            denoise: false,
        };
        let scene = Scene {
            objects: Vec::new(),
            meshes: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            background: DVec3::ZERO,
            sky: None,
        };
        let png = FileFormat::Png {
            sixteen_bit: false,
            compression: crate::output::format::Compression::Fast,
        };
        let run = of_run(&scene, &settings, &png);
        let mut bytes = Vec::new();
        bytes.extend(concat!("rayreel ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
        bytes.extend(ENCODING.as_bytes());
        bytes.extend([0u8; 24]); // three empty lists
        bytes.extend([0u8; 24]); // background (0, 0, 0)
        for v in [2u32, 1, 3] {
            bytes.extend(v.to_le_bytes());
        }
        bytes.push(0); // depth
        bytes.extend(1u32.to_le_bytes());
        bytes.extend([0, 0]); // no adaptive, stratified
        bytes.push(0); // no alpha
        bytes.extend(0f64.to_bits().to_le_bytes()); // exposure
        bytes.push(0); // srgb
        bytes.extend([0, 0]); // png, 8 bits
        assert_eq!(run.hex(), Hasher::new().write(&bytes).hex());
        // An EXR's run adds the rate its header stores, its frames the time they record.
        let mut rate = bytes.clone();
        rate.extend(b"exr rate");
        rate.extend(30000i32.to_le_bytes());
        rate.extend(1001u32.to_le_bytes());
        let exr = with_exr_rate(&run, (30000, 1001));
        assert_eq!(exr.hex(), Hasher::new().write(&rate).hex());
        // The frame's number, camera and lens each change it; a shutter on a still camera
        // and the compression do not.
        let at = |x, aperture, n, shutter| {
            of_frame(&run, &FrameView::of_frame(&still(x, aperture), shutter, n))
        };
        let open = Some(Shutter {
            angle: 180.0,
            offset: 0.0,
        });
        assert_ne!(at(0.0, 0.0, 0, None), at(0.0, 0.0, 1, None));
        assert_ne!(at(0.0, 0.0, 0, None), at(-0.0, 0.0, 0, None));
        assert_ne!(at(0.0, 0.0, 0, None), at(0.0, 0.1, 0, None));
        assert_eq!(at(0.0, 0.0, 0, None), at(0.0, 0.0, 0, open));
        let best = FileFormat::Png {
            sixteen_bit: false,
            compression: crate::output::format::Compression::Best,
        };
        assert_eq!(run.hex(), of_run(&scene, &settings, &best).hex());
        // f32 appends the byte 2 after the encoding.
        let f32 = Settings {
            precision: Precision::F32,
            ..settings
        };
        let n = bytes.len();
        bytes.insert(n - 2, 2);
        assert_eq!(
            of_run(&scene, &f32, &png).hex(),
            Hasher::new().write(&bytes).hex()
        );
        // Compositing passes append the byte 3 and their bits after that.
        use crate::settings::{Aov, Aovs};
        let passes = Settings {
            aov: Aovs::of(&[Aov::Motion, Aov::Normal]),
            ..f32
        };
        let n = bytes.len();
        bytes.splice(n - 2..n - 2, [3, 0b01001]);
        assert_eq!(
            of_run(&scene, &passes, &png).hex(),
            Hasher::new().write(&bytes).hex()
        );
        // The film filter appends the byte 5 after those.
        let filtered = Settings {
            denoise: true,
            ..passes
        };
        let n = bytes.len();
        bytes.insert(n - 2, 5);
        assert_eq!(
            of_run(&scene, &filtered, &png).hex(),
            Hasher::new().write(&bytes).hex()
        );
    }
}
