//! Texture maps of `diffuse` and `ambient`: a checker, or an image file resolved against the
//! sequence file's folder (kept inside it, like meshes), read once however many materials use
//! it, decoded to linear RGB and reduced to its mip pyramid (docs/spec/texture.md).
//!
//! ```yaml
//! diffuse: { checker: { size: 1, colors: [[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]] } }
//! diffuse: { image: textures/wood.png, scale: [2, 2] }
//! ```

use super::*;
use crate::budget::OutOfMemory;
use crate::scene::{Image, Level, Sky, Texture};
use glam::DVec2;
use std::collections::HashMap;
use std::sync::Arc;

/// Files above this many bytes are refused unread.
pub const MAX_TEXTURE_BYTES: u64 = 1 << 30;
/// At most this many pixels a side, and `MAX_TEXELS` in all (768 MiB of f32 RGB, a third
/// more with its pyramid).
pub const MAX_SIDE: u32 = 16384;
pub const MAX_TEXELS: u64 = 1 << 26;
/// A checker cell at least this large, at most `MAX_MAGNITUDE`.
const MIN_CELL: f64 = 1e-100;

/// The images the materials use, in order of first use, each read once.
pub(super) struct Textures {
    folders: super::meshes::Folders,
    by_path: HashMap<(PathBuf, bool), Arc<Image>>,
    /// Bytes the images read so far hold (texels and pyramids), for a refusal's figures.
    held: u64,
}

impl Textures {
    pub(super) fn new(folders: &super::meshes::Folders) -> Textures {
        Textures {
            folders: folders.clone(),
            by_path: HashMap::new(),
            held: 0,
        }
    }

    /// A colour, or the texture and the colour that stands for it where one colour must do
    /// (its mean: the checker's two colours halved, the image's last mip level).
    pub(super) fn paint(&mut self, field: &str, p: &raw::Paint) -> Check<(DVec3, Option<Texture>)> {
        let map = match p {
            raw::Paint::Color(c) => return Ok((color(field, *c)?, None)),
            raw::Paint::Map(m) => m,
        };
        let texture = match (&map.checker, &map.image) {
            (Some(c), None) => checker(field, c, map)?,
            (None, Some(file)) => self.image(field, file, map)?,
            (None, None) => {
                return invalid(field, "a texture map needs `checker:` or `image:`");
            }
            (Some(_), Some(_)) => {
                return invalid(field, "give `checker:` or `image:`, not both");
            }
        };
        Ok((mean(&texture), Some(texture)))
    }

    fn image(&mut self, field: &str, file: &str, map: &raw::TextureMap) -> Check<Texture> {
        let scale = match map.scale {
            None => DVec2::ONE,
            Some(s) => {
                let f = format!("{field}.scale");
                let v = vector(&f, [s[0], s[1], 1.0])?;
                if v.x.abs().min(v.y.abs()) < MIN_CELL || v.x.abs().max(v.y.abs()) > MAX_MAGNITUDE {
                    return invalid(
                        &f,
                        format!(
                            "each factor must be non-zero and at most 1e100 in size {}",
                            got(format!("[{}, {}]", num(s[0]), num(s[1])))
                        ),
                    );
                }
                DVec2::new(v.x, v.y)
            }
        };
        let linear = map.encoding == Some(raw::ImageEncoding::Linear);
        let image = self.read(&format!("{field}.image"), file, linear)?;
        Ok(Texture::Image { image, scale })
    }

    /// The image `file` names (field `f`), read once for every use with the same decoding.
    fn read(&mut self, f: &str, file: &str, linear: bool) -> Check<Arc<Image>> {
        let path = super::meshes::resolve(&self.folders, f, file, "an image")?;
        let key = (
            std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone()),
            linear,
        );
        if let Some(i) = self.by_path.get(&key) {
            return Ok(i.clone());
        }
        let image = load(&path, linear).or_else(|e| match e {
            Refusal::File(m) => invalid(f, m),
            Refusal::Memory(mut e) => {
                if self.held > 0 {
                    e.taken = Some(format!(
                        "the textures read before it hold {}",
                        crate::budget::size(self.held)
                    ));
                }
                no_memory(f, e.to_string())
            }
        })?;
        self.held += image_bytes(&image.levels);
        let image = Arc::new(image);
        self.by_path.insert(key, image.clone());
        Ok(image)
    }

    /// `render.background`: a colour, or a sky and the colour that stands for it where one
    /// colour must do (the image's mean, the gradient's horizon).
    pub(super) fn background(
        &mut self,
        b: Option<&raw::Background>,
    ) -> Check<(DVec3, Option<Sky>)> {
        const F: &str = "render.background";
        let sky = match b {
            None => return Ok((DVec3::ZERO, None)),
            Some(raw::Background::Color(c)) => return Ok((color(F, *c)?, None)),
            Some(raw::Background::Sky(s)) => s,
        };
        match (&sky.image, &sky.gradient) {
            (Some(file), None) => {
                let intensity = in_range(
                    &format!("{F}.intensity"),
                    sky.intensity.unwrap_or(1.0),
                    0.0,
                    MAX_COLOR,
                    "in [0, 1e6]",
                )?;
                let rotate = number(&format!("{F}.rotate"), sky.rotate.unwrap_or(0.0))?;
                let linear = sky.encoding == Some(raw::ImageEncoding::Linear);
                let image = self.read(&format!("{F}.image"), file, linear)?;
                let texture = Texture::Image {
                    image: image.clone(),
                    scale: DVec2::ONE,
                };
                let mean = mean(&texture) * intensity;
                let sky = Sky::Image {
                    image,
                    rotate,
                    intensity,
                };
                Ok((mean, Some(sky)))
            }
            (None, Some(g)) => {
                if sky.rotate.is_some() || sky.encoding.is_some() || sky.intensity.is_some() {
                    return invalid(
                        F,
                        "`rotate`, `encoding` and `intensity` belong to an image sky; a gradient has only its three colours",
                    );
                }
                let horizon = color(&format!("{F}.gradient.horizon"), g.horizon)?;
                let sky = Sky::Gradient {
                    zenith: color(&format!("{F}.gradient.zenith"), g.zenith)?,
                    horizon,
                    ground: match g.ground {
                        Some(c) => color(&format!("{F}.gradient.ground"), c)?,
                        None => horizon,
                    },
                };
                Ok((horizon, Some(sky)))
            }
            (None, None) => invalid(
                F,
                "a sky needs `image:` or `gradient:` (or give a colour [r, g, b])",
            ),
            (Some(_), Some(_)) => invalid(F, "give `image:` or `gradient:`, not both"),
        }
    }
}

fn checker(field: &str, c: &raw::Checker, map: &raw::TextureMap) -> Check<Texture> {
    if map.scale.is_some() || map.encoding.is_some() {
        return invalid(
            field,
            "`scale` and `encoding` belong to image maps; a checker's cells are `size` wide",
        );
    }
    let size = in_range(
        &format!("{field}.checker.size"),
        c.size.unwrap_or(1.0),
        MIN_CELL,
        MAX_MAGNITUDE,
        "a positive length in [1e-100, 1e100]",
    )?;
    let colors = [
        color(&format!("{field}.checker.colors[0]"), c.colors[0])?,
        color(&format!("{field}.checker.colors[1]"), c.colors[1])?,
    ];
    Ok(Texture::Checker { size, colors })
}

/// The one colour that stands for a texture.
fn mean(t: &Texture) -> DVec3 {
    match t {
        Texture::Checker { colors, .. } => (colors[0] + colors[1]) * 0.5,
        Texture::Image { image, .. } => {
            let top = &image.levels[image.levels.len() - 1].texels[0];
            DVec3::from_array(top.map(f64::from))
        }
    }
}

/// Why an image was not read: the file (its message), or the memory it would need.
#[derive(Debug)]
pub(crate) enum Refusal {
    File(String),
    Memory(OutOfMemory),
}

impl From<String> for Refusal {
    fn from(m: String) -> Refusal {
        Refusal::File(m)
    }
}

impl From<OutOfMemory> for Refusal {
    fn from(e: OutOfMemory) -> Refusal {
        Refusal::Memory(e)
    }
}

/// The bytes `levels` hold.
fn image_bytes(levels: &[Level]) -> u64 {
    levels.iter().map(|l| l.texels.len() as u64 * 12).sum()
}

/// The bytes a w×h level's pyramid above it will hold: each level a quarter of the one below,
/// rounded up, so at most a third of level 0 and a texel a level.
fn pyramid_bytes(width: u32, height: u32) -> u64 {
    (u64::from(width) * u64::from(height) / 3 + 64) * 12
}

/// Reads and decodes `path` (PNG or EXR by its name), and builds the pyramid; the memory
/// budget admits each step before it allocates.
fn load(path: &Path, linear: bool) -> Result<Image, Refusal> {
    let started = std::time::Instant::now();
    let name = path.to_string_lossy().to_lowercase();
    let png = name.ends_with(".png");
    if !png && !name.ends_with(".exr") {
        return Err(Refusal::File(
            "unknown image format: the file name must end in .png or .exr".into(),
        ));
    }
    if linear && !png {
        return Err(Refusal::File(
            "`encoding` applies to PNG images; EXR values are linear already".into(),
        ));
    }
    let bytes = read_regular(path, png)?;
    Ok(Image {
        file: path.to_owned(),
        levels: decode(&bytes, png, linear, &path.display().to_string())?,
        // The file's bytes, then the encoding: the file alone does not say how it is read.
        digest: mesh::fnv1a_on(mesh::fnv1a(&bytes), &[u8::from(linear)]),
        bytes: bytes.len() as u64,
        load_seconds: started.elapsed().as_secs_f64(),
    })
}

/// A PNG or EXR file's bytes as the levels of its pyramid; `shown` names it in messages.
pub(crate) fn decode(
    bytes: &[u8],
    png: bool,
    linear: bool,
    shown: &str,
) -> Result<Vec<Level>, Refusal> {
    let (width, height, texels) = match png {
        true => png_texels(bytes, linear, shown)?,
        false => exr_texels(bytes, shown)?,
    };
    crate::budget::admit(pyramid_bytes(width, height), || {
        format!("the mip pyramid of {shown} ({width}x{height})")
    })?;
    Ok(pyramid(Level {
        width,
        height,
        texels,
    }))
}

/// The file's bytes: a regular file only (a FIFO must not hang the load), at most
/// `MAX_TEXTURE_BYTES`, that starts as a PNG or an EXR file does (a sparse or foreign file is
/// refused after 8 bytes, not read whole), read once the memory budget admits its size.
fn read_regular(path: &Path, png: bool) -> Result<Vec<u8>, Refusal> {
    use crate::regular::{self, Links, Refused};
    use std::io::Read;
    let shown = path.display();
    let (f, meta) = regular::open(path, Links::Follow).map_err(|e| match e {
        Refused::NotRegular(what) => {
            format!("{shown} is {what}, not a regular file; a texture must be an image file")
        }
        Refused::Missing => format!("cannot read {shown}: no such file"),
        Refused::Io(e) => format!("cannot read {shown}: {e}"),
    })?;
    if meta.len() > MAX_TEXTURE_BYTES {
        return Err(Refusal::File(format!(
            "{shown} is {} bytes; texture files are limited to 1 GiB",
            meta.len()
        )));
    }
    let (magic, kind): (&[u8], &str) = match png {
        true => (b"\x89PNG\r\n\x1a\n", "PNG"),
        false => (&[0x76, 0x2f, 0x31, 0x01], "EXR"),
    };
    let mut start = vec![0u8; magic.len()];
    let read = (&f).take(magic.len() as u64).read(&mut start);
    if read.map_err(|e| format!("cannot read {shown}: {e}"))? < magic.len() || start != magic {
        return Err(Refusal::File(format!(
            "unreadable {kind}: {shown} does not start as a {kind} file does"
        )));
    }
    let mut bytes = start;
    crate::budget::grow(&mut bytes, meta.len() as usize, || {
        format!("reading {shown}")
    })?;
    (&f).take(MAX_TEXTURE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read {shown}: {e}"))?;
    Ok(bytes)
}

fn check_size(width: u64, height: u64) -> Result<(u32, u32), String> {
    if width == 0 || height == 0 {
        return Err("the image is empty".into());
    }
    if width > u64::from(MAX_SIDE) || height > u64::from(MAX_SIDE) || width * height > MAX_TEXELS {
        return Err(format!(
            "the image is {width}x{height}; textures are limited to {MAX_SIDE} pixels a side and {MAX_TEXELS} pixels in all"
        ));
    }
    Ok((width as u32, height as u32))
}

/// 8- or 16-bit PNG (grey, grey+alpha, RGB, RGBA or palette; alpha ignored) as linear RGB:
/// each value v of bit depth b is x = v / (2^b − 1), sRGB-decoded unless `linear`. The
/// decoded samples and the texels are admitted by the memory budget before either exists.
fn png_texels(
    bytes: &[u8],
    linear: bool,
    shown: &str,
) -> Result<(u32, u32, Vec<[f32; 3]>), Refusal> {
    use image::{ColorType, ImageDecoder};
    let unreadable = |e: image::ImageError| format!("unreadable PNG: {e}");
    let mut decoder =
        image::codecs::png::PngDecoder::new(std::io::Cursor::new(bytes)).map_err(unreadable)?;
    let (w, h) = decoder.dimensions();
    let (w, h) = check_size(u64::from(w), u64::from(h))?;
    let samples = decoder.total_bytes();
    let texels = u64::from(w) * u64::from(h) * 12;
    crate::budget::admit(samples + texels, || format!("decoding {shown} ({w}x{h})"))?;
    decoder
        .set_limits(image::Limits::no_limits())
        .map_err(unreadable)?;
    let color = decoder.color_type();
    let mut raw = Vec::new();
    crate::budget::grow(&mut raw, samples as usize, || format!("decoding {shown}"))?;
    raw.resize(samples as usize, 0);
    decoder.read_image(&mut raw).map_err(unreadable)?;
    let (channels, wide) = match color {
        ColorType::L8 => (1, false),
        ColorType::La8 => (2, false),
        ColorType::Rgb8 => (3, false),
        ColorType::Rgba8 => (4, false),
        ColorType::L16 => (1, true),
        ColorType::La16 => (2, true),
        ColorType::Rgb16 => (3, true),
        ColorType::Rgba16 => (4, true),
        other => {
            return Err(Refusal::File(format!(
                "unreadable PNG: colour type {other:?}"
            )));
        }
    };
    let table = decode_table(linear);
    // 8-bit codes as 16-bit ones (v·257, the same fraction); 16-bit samples in native order.
    let code = |px: &[u8], c: usize| match wide {
        true => usize::from(u16::from_ne_bytes([px[2 * c], px[2 * c + 1]])),
        false => usize::from(px[c]) * 257,
    };
    let size = channels * if wide { 2 } else { 1 };
    let mut out = Vec::new();
    crate::budget::grow(&mut out, (w as usize) * (h as usize), || {
        format!("the texels of {shown}")
    })?;
    out.extend(raw.chunks_exact(size).map(|px| {
        // Grey is each of R, G and B; alpha is dropped.
        let rgb = match channels {
            1 | 2 => [0, 0, 0],
            _ => [0, 1, 2],
        };
        rgb.map(|c| table[code(px, c)])
    }));
    Ok((w, h, out))
}

/// The linear value of each 16-bit code (8-bit codes arrive as v·257, the same fraction).
fn decode_table(linear: bool) -> Vec<f32> {
    (0..=65535u32)
        .map(|v| {
            let x = f64::from(v) / 65535.0;
            let y = if linear {
                x
            } else if x <= 0.04045 {
                x / 12.92
            } else {
                libm::pow((x + 0.055) / 1.055, 2.4)
            };
            y as f32
        })
        .collect()
}

/// The first part of an EXR with channels named R, G and B (others are ignored; alpha too),
/// as f32 (values that are not finite, or negative, are refused: a texture is a
/// reflectance).
fn exr_texels(bytes: &[u8], shown: &str) -> Result<(u32, u32, Vec<[f32; 3]>), Refusal> {
    use exr::prelude::*;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| format!("unreadable EXR: {e}"))?;
    // Every part is sized before any is decoded: the one read is the first with R, G and B
    // channels, and none may be larger than a texture can be.
    let mut largest = 0;
    for header in &meta.headers {
        let size = header.layer_size;
        check_size(size.width() as u64, size.height() as u64)?;
        largest = largest.max(size.width() as u64 * size.height() as u64);
    }
    crate::budget::admit(largest * 12, || format!("decoding {shown}"))?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
            |(width, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *width + pos.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| {
            format!("unreadable EXR (a texture needs a part with channels named R, G and B): {e}")
        })?;
    let size = image.layer_data.size;
    let (w, h) = check_size(size.width() as u64, size.height() as u64)?;
    let texels = image.layer_data.channel_data.pixels.1;
    if texels.iter().flatten().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Refusal::File(
            "the EXR holds a negative, infinite or NaN value; a texture holds reflectances ≥ 0"
                .into(),
        ));
    }
    Ok((w, h, texels))
}

/// Level k + 1 is ⌈w/2⌉ × ⌈h/2⌉; its texel (x, y) is the f32 sum
/// ((a + b) + (c + d)) · 0.25 of level k's texels (2x, 2y), (2x+1, 2y), (2x, 2y+1),
/// (2x+1, 2y+1), indices wrapping (mod width, mod height) as the texture repeats.
pub fn pyramid(level0: Level) -> Vec<Level> {
    let mut levels = vec![level0];
    loop {
        let l = &levels[levels.len() - 1];
        if l.width == 1 && l.height == 1 {
            return levels;
        }
        let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
        let at = |x: u32, y: u32| l.texels[((y % l.height) * l.width + x % l.width) as usize];
        let mut texels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (at(2 * x, 2 * y), at(2 * x + 1, 2 * y));
                let (c, d) = (at(2 * x, 2 * y + 1), at(2 * x + 1, 2 * y + 1));
                texels.push(std::array::from_fn(|i| {
                    ((a[i] + b[i]) + (c[i] + d[i])) * 0.25
                }));
            }
        }
        levels.push(Level {
            width: w,
            height: h,
            texels,
        });
    }
}
