//! The drawing primitives of the map and swatch pictures: an sRGB-encoded
//! canvas with alpha blending (in display space, as the pictures have always
//! blended), anti-aliased lines, soft discs,
//! rectangles, and antialiased text in DejaVu Sans.
//!
//! The font is the one the report's plots use (`assets/DejaVuSans.ttf` in
//! this crate, Bitstream Vera licence in `assets/DejaVuSans-LICENSE.txt`),
//! embedded once here as [`FONT`] and rasterised with ab_glyph, so no system
//! font library is needed.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

/// DejaVu Sans, the TrueType bytes (the report's plots register the same bytes).
pub static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The parsed [`FONT`]; `None` if the embedded bytes did not parse (then
/// text is measured as empty and not drawn: pictures lose their words, never
/// their data).
fn font() -> Option<&'static FontRef<'static>> {
    static PARSED: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    PARSED
        .get_or_init(|| FontRef::try_from_slice(FONT).ok())
        .as_ref()
}

/// An axis-aligned box in pixel coordinates, `[x0, y0, x1, y1]`, y down.
pub type Rect = [f32; 4];

/// Do two boxes share interior points?
pub fn overlaps(a: &Rect, b: &Rect) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// A picture in progress: sRGB-encoded values in `[0, 1]`, row-major, row 0 at the top.
pub struct Canvas {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The pixels.
    pub px: Vec<[f32; 3]>,
}

/// sRGB encoding of a linear value in `[0, 1]`.
pub fn srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

impl Canvas {
    /// Blend `colour` into pixel `(x, y)` with `alpha` (outside: nothing).
    pub fn blend(&mut self, x: i64, y: i64, colour: [f32; 3], alpha: f32) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 || alpha <= 0.0 {
            return;
        }
        let p = &mut self.px[y as usize * self.width + x as usize];
        for c in 0..3 {
            p[c] += alpha.min(1.0) * (colour[c] - p[c]);
        }
    }

    /// An anti-aliased line: samples every half pixel, splatted bilinearly.
    pub fn line(&mut self, a: [f32; 2], b: [f32; 2], colour: [f32; 3], alpha: f32) {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let steps = (len * 2.0).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f32 / steps as f32;
            let (x, y) = (
                a[0] + t * (b[0] - a[0]) - 0.5,
                a[1] + t * (b[1] - a[1]) - 0.5,
            );
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let k = alpha / (steps as f32 / len.max(0.5)).max(1.0) * 1.6;
            for (dx, dy, wgt) in [
                (0, 0, (1.0 - fx) * (1.0 - fy)),
                (1, 0, fx * (1.0 - fy)),
                (0, 1, (1.0 - fx) * fy),
                (1, 1, fx * fy),
            ] {
                self.blend(x0 as i64 + dx, y0 as i64 + dy, colour, k * wgt);
            }
        }
    }

    /// A filled disc with a soft edge.
    pub fn disc(&mut self, cx: f32, cy: f32, r: f32, colour: [f32; 3]) {
        let (x0, x1) = ((cx - r - 1.0).floor() as i64, (cx + r + 1.0).ceil() as i64);
        let (y0, y1) = ((cy - r - 1.0).floor() as i64, (cy + r + 1.0).ceil() as i64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt();
                self.blend(x, y, colour, (r + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }

    /// Fill the pixels whose centres lie in `r` with `colour` at `alpha`.
    pub fn rect(&mut self, r: Rect, colour: [f32; 3], alpha: f32) {
        let (x0, x1) = (r[0].round() as i64, r[2].round() as i64);
        let (y0, y1) = (r[1].round() as i64, r[3].round() as i64);
        for y in y0..y1 {
            for x in x0..x1 {
                self.blend(x, y, colour, alpha);
            }
        }
    }

    /// Draw `s` at `px` pixels with its top-left corner at `(x, y)` (the
    /// box of [`text_size`]), antialiased.
    pub fn text(&mut self, x: f32, y: f32, s: &str, px: f32, colour: [f32; 3]) {
        let Some(font) = font() else { return };
        let scale = PxScale::from(px);
        let scaled = font.as_scaled(scale);
        let baseline = y + scaled.ascent();
        let mut caret = x;
        let mut last = None;
        for c in s.chars() {
            let id = font.glyph_id(c);
            if let Some(prev) = last {
                caret += scaled.kern(prev, id);
            }
            let glyph = id.with_scale_and_position(scale, point(caret, baseline));
            caret += scaled.h_advance(id);
            last = Some(id);
            if let Some(outline) = font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                outline.draw(|gx, gy, cover| {
                    self.blend(
                        b.min.x as i64 + gx as i64,
                        b.min.y as i64 + gy as i64,
                        colour,
                        cover,
                    );
                });
            }
        }
    }

    /// The picture as 8-bit sRGB, row-major RGB triples.
    pub fn to_8bit(&self) -> Vec<u8> {
        self.px
            .iter()
            .flat_map(|c| c.map(|v| (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8))
            .collect()
    }
}

/// Width and height of `s` drawn at `px` pixels (advance width; ascent
/// minus descent).
pub fn text_size(s: &str, px: f32) -> [f32; 2] {
    let Some(font) = font() else {
        return [0.0, 0.0];
    };
    let scaled = font.as_scaled(PxScale::from(px));
    let mut width = 0.0;
    let mut last = None;
    for c in s.chars() {
        let id = font.glyph_id(c);
        if let Some(prev) = last {
            width += scaled.kern(prev, id);
        }
        width += scaled.h_advance(id);
        last = Some(id);
    }
    [width, scaled.ascent() - scaled.descent()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_font_parses_and_text_stays_in_its_box() {
        assert!(font().is_some());
        let [w, h] = text_size("gold-metallic-paint2", 12.0);
        assert!(w > 60.0 && w < 200.0 && h > 10.0 && h < 20.0, "{w} x {h}");
        let mut c = Canvas {
            width: 300,
            height: 40,
            px: vec![[0.0; 3]; 300 * 40],
        };
        c.text(10.0, 10.0, "gold-metallic-paint2", 12.0, [1.0; 3]);
        let mut inked = 0;
        for y in 0..40 {
            for x in 0..300 {
                if c.px[y * 300 + x][0] > 0.0 {
                    inked += 1;
                    let (xf, yf) = (x as f32, y as f32);
                    assert!(xf >= 9.0 && xf <= 11.0 + w && yf >= 9.0 && yf <= 11.0 + h);
                }
            }
        }
        assert!(inked > 100, "{inked} pixels inked");
    }
}
