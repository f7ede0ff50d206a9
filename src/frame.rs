//! Frame: the tracer's linear, unclamped f32 RGB (+ optional depth), row-major from the top
//! left, and its conversions to the integer pixels files and streams carry.

#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// 3 floats per pixel, row-major, top row first.
    pub rgb: Vec<f32>,
    /// Distance along the eye ray to the first hit (+inf for background), when asked for.
    pub depth: Option<Vec<f32>>,
    /// Colour values the tracer produced as NaN or beyond f32 and that were replaced before
    /// storing; the test suite asserts this stays 0 on every extreme scene.
    pub non_finite: u64,
    /// Eye-ray samples traced for the colour (the cost measure of sampling strategies).
    pub samples: u64,
    /// All rays cast for the colour: eye, shadow and reflection rays.
    pub rays: u64,
}

impl Frame {
    pub fn pixel(&self, row: u32, col: u32) -> [f32; 3] {
        let i = 3 * (row as usize * self.width as usize + col as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// 8-bit RGB: round(255 · clamp(c, 0, 1)), no gamma (as the talk writes its images).
    pub fn to_rgb8(&self) -> Vec<u8> {
        self.rgb.iter().map(|&c| quantize(c, 255.0) as u8).collect()
    }

    /// 16-bit RGB: round(65535 · clamp(c, 0, 1)).
    pub fn to_rgb16(&self) -> Vec<u16> {
        self.rgb
            .iter()
            .map(|&c| quantize(c, 65535.0) as u16)
            .collect()
    }
}

/// round(max · clamp(c, 0, 1)), halves rounding up, without a libm call (x86-64's baseline has
/// no rounding instruction): the integer part and y − it are both exact for y < 2^24.
/// NaN never reaches a frame; it would map to 0.
#[inline]
fn quantize(c: f32, max: f32) -> f32 {
    let y = c.clamp(0.0, 1.0) * max;
    let whole = y as u32 as f32;
    if y - whole >= 0.5 { whole + 1.0 } else { whole }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantization_rounds_and_clamps() {
        let f = Frame {
            width: 2,
            height: 1,
            rgb: vec![0.0, 0.5, 1.0, -3.0, 7.0, 0.2],
            depth: None,
            non_finite: 0,
            samples: 2,
            rays: 2,
        };
        assert_eq!(f.to_rgb8(), vec![0, 128, 255, 0, 255, 51]);
        assert_eq!(f.to_rgb16()[1], 32768);
    }
}
