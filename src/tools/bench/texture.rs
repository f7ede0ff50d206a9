//! `rayreel bench --only texture`: what footprint filtering buys on the classic moiré test, a
//! checker floor running to the horizon seen from low above it (1280×720; `--quick` 320×180).
//! Each frame is compared with a many-sample reference of the same frame (1024 point samples a
//! pixel, `--quick` 64: the pixel's true mean, which the filter at the eye would otherwise
//! carry into its own reference), filtered and point-sampled, at one sample and at default
//! sampling.

use super::{BenchError, Options, load, render_only};
use crate::frame::Frame;
use crate::tracer::World;

/// Ambient and one point light over an endless checker floor, the sky the floor's mean.
const FLOOR: &str = "render: { max_depth: 1, background: [0.5, 0.5, 0.5] }
materials:
  tiles: { diffuse: { checker: { size: 1, colors: [[0.85, 0.85, 0.85], [0.08, 0.08, 0.08]] } }, ambient: [0.05, 0.05, 0.05], specular: [0.3, 0.3, 0.3], shininess: 60 }
objects:
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: tiles }
lights:
  - point: { position: [4, 8, 4], ambient: [1, 1, 1], diffuse: [0.6, 0.6, 0.6], specular: [0.6, 0.6, 0.6] }
camera: { position: [0.3, 0.6, 6], look_at: [0, 0.2, -20], fov: 70 }
";

pub(super) fn textures(
    o: &Options,
    out: &mut dyn FnMut(&str),
    cmd: &str,
) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let size = if o.quick { (320, 180) } else { (1280, 720) };
    let many = if o.quick { 64 } else { 1024 };
    let base = load(FLOOR, size)?;
    let world = World::new(base.scene.clone());
    let point = world.clone().point_sampled();
    let with = |samples: u32, adaptive: bool| {
        let mut seq = base.clone();
        seq.settings.samples = samples;
        if !adaptive {
            seq.settings.adaptive = None;
        }
        seq
    };
    let (_, reference) = render_only(&point, &with(many, false), cores, 1)?;
    let one = with(1, false);
    let default = with(base.settings.samples, true);
    let mut line = format!(
        "texture checker floor to the horizon {}x{}, PSNR of sRGB values against {many} point samples:",
        size.0, size.1
    );
    for (name, seq) in [("1 sample", &one), ("default sampling", &default)] {
        let (tf, filtered) = render_only(&world, seq, cores, o.runs)?;
        let (tp, pointed) = render_only(&point, seq, cores, o.runs)?;
        line += &format!(
            " {name}: filtered {:.1} dB ({:.3} s), point-sampled {:.1} dB ({:.3} s);",
            psnr(&filtered, &reference),
            tf.median,
            psnr(&pointed, &reference),
            tp.median
        );
    }
    line.pop();
    out(&format!("{line}   [{cmd}]"));
    Ok(())
}

/// 10·log10(1/MSE) over the sRGB-encoded channels (what a viewer shows), each linear value
/// clamped to [0, 1] first.
fn psnr(a: &Frame, b: &Frame) -> f64 {
    let srgb = |x: f32| {
        let x = f64::from(x.clamp(0.0, 1.0));
        if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
    };
    let mse = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| (srgb(*x) - srgb(*y)).powi(2))
        .sum::<f64>()
        / a.rgb.len() as f64;
    10.0 * (1.0 / mse).log10()
}
