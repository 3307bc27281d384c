//! Everything a map picture draws over the albedo: the materials' dots, their
//! labels ([`crate::labels`]), the axis ticks and the colour key
//! ([`crate::ticks_and_key`]), and a note on what could not be labelled. Laid out
//! once, so the PNG and the sidecar's label boxes come from the same layout.

use brdf_atlas_core::View;

use crate::canvas::{Canvas, Rect, text_size};
use crate::labels::{self, dot_box};
use crate::sidecar::{LabelBox, Reference};
use crate::ticks_and_key::{self, INK, Key, Tick};

/// What a picture shows besides the map and its contours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Names beside the dots.
    pub labels: bool,
    /// The colour key and the latent-axis ticks (only on pictures of at
    /// least [`MIN_DECORATED_SIDE`] pixels a side).
    pub key: bool,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            labels: true,
            key: true,
        }
    }
}

/// Smallest side on which a picture gets its key and ticks.
pub const MIN_DECORATED_SIDE: usize = 200;
/// Radius of a material's dot, pixels.
const DOT: f32 = 3.6;

/// A drawn label.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// The material's index among the references.
    pub index: usize,
    /// Its box (text and paper).
    pub rect: Rect,
    /// The leader from the dot, if the box is not beside it.
    pub leader: Option<[[f32; 2]; 2]>,
}

/// The layout of a picture's overlay.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlay {
    /// Font size, pixels.
    pub px: f32,
    /// The axis ticks.
    pub ticks: Vec<Tick>,
    /// The colour key.
    pub key: Option<Key>,
    /// The labels drawn.
    pub labels: Vec<Label>,
    /// Materials in the view left without a label.
    pub unlabelled: usize,
    /// The note saying so, and its box.
    pub note: Option<(String, Rect)>,
}

/// Font size for a picture of `side` pixels.
fn font_px(side: usize) -> f32 {
    (side as f32 / 64.0).clamp(10.0, 14.0)
}

impl Overlay {
    /// Lay out the overlay of a `width x height` picture of `view`.
    pub fn new(
        view: &View,
        width: usize,
        height: usize,
        references: &[Reference],
        levels: &[f32],
        range: [f32; 2],
        style: Style,
    ) -> Overlay {
        let px = font_px(width.min(height));
        let (w, h) = (width as f32, height as f32);
        let pixel = |r: &Reference| [r.pixel[0] as f32, r.pixel[1] as f32];
        let visible: Vec<usize> = (0..references.len())
            .filter(|&i| {
                let [x, y] = pixel(&references[i]);
                (0.0..w).contains(&x) && (0.0..h).contains(&y)
            })
            .collect();
        let dots: Vec<Rect> = visible
            .iter()
            .map(|&i| dot_box(pixel(&references[i]), DOT))
            .collect();
        let decorated = style.key && width.min(height) >= MIN_DECORATED_SIDE;
        let ticks = if decorated {
            ticks_and_key::axis_ticks(view, width, height, px, &dots)
        } else {
            Vec::new()
        };
        let key = if decorated {
            ticks_and_key::key(range, levels, width, height, px, &dots, &ticks)
        } else {
            None
        };
        let mut reserved: Vec<Rect> = ticks.iter().map(|t| t.rect).collect();
        reserved.extend(ticks.iter().map(|t| {
            let [[x0, y0], [x1, y1]] = t.mark;
            [
                x0.min(x1) - 1.0,
                y0.min(y1) - 1.0,
                x0.max(x1) + 1.0,
                y0.max(y1) + 1.0,
            ]
        }));
        reserved.extend(key.as_ref().map(|k| k.rect));
        let mut overlay = Overlay {
            px,
            ticks,
            key,
            labels: Vec::new(),
            unlabelled: 0,
            note: None,
        };
        if !style.labels {
            return overlay;
        }
        let centres: Vec<[f32; 2]> = visible.iter().map(|&i| pixel(&references[i])).collect();
        let sizes: Vec<[f32; 2]> = visible
            .iter()
            .map(|&i| {
                let [tw, th] = text_size(&references[i].name, px);
                [tw + 4.0, th + 2.0]
            })
            .collect();
        let bounds = [0.0, 0.0, w, h];
        let mut layout = labels::place(&centres, &sizes, DOT, bounds, &reserved);
        if !layout.left_out.is_empty() {
            // Room for the note (sized for the largest count), then again.
            let widest = note_text(visible.len(), visible.len());
            let left = overlay
                .ticks
                .iter()
                .filter(|t| t.mark[0][0] <= 0.5)
                .map(|t| t.rect[2])
                .fold(0.0f32, f32::max);
            let rect = ticks_and_key::note_box(&widest, width, px, left, &dots, &reserved);
            reserved.push(rect);
            layout = labels::place(&centres, &sizes, DOT, bounds, &reserved);
            let text = note_text(layout.left_out.len(), visible.len());
            let [tw, th] = text_size(&text, px);
            overlay.note = Some((
                text,
                [rect[0], rect[1], rect[0] + tw + 4.0, rect[1] + th + 2.0],
            ));
        }
        overlay.unlabelled = layout.left_out.len();
        overlay.labels = layout
            .placed
            .into_iter()
            .map(|p| Label {
                index: visible[p.index],
                rect: p.rect,
                leader: p.leader,
            })
            .collect();
        overlay
    }

    /// The labels as the sidecar records them.
    pub fn label_boxes(&self, references: &[Reference]) -> Vec<LabelBox> {
        self.labels
            .iter()
            .map(|l| LabelBox {
                name: references[l.index].name.clone(),
                rect: l.rect,
            })
            .collect()
    }

    /// Draw the overlay: ticks and key, every dot, then labels and note.
    pub fn draw(&self, canvas: &mut Canvas, references: &[Reference]) {
        ticks_and_key::draw_ticks(canvas, &self.ticks, self.px);
        if let Some(key) = &self.key {
            ticks_and_key::draw_key(canvas, key, self.px);
        }
        for r in references {
            let (cx, cy) = (r.pixel[0] as f32, r.pixel[1] as f32);
            canvas.disc(cx, cy, DOT, [0.0; 3]);
            canvas.disc(cx, cy, DOT - 1.4, [1.0; 3]);
        }
        for l in &self.labels {
            if let Some([a, b]) = l.leader {
                canvas.line(a, b, INK, 0.8);
            }
            ticks_and_key::draw_text_box(canvas, l.rect, &references[l.index].name, self.px);
        }
        if let Some((text, rect)) = &self.note {
            ticks_and_key::draw_text_box(canvas, *rect, text, self.px);
        }
    }
}

/// The note for `left_out` of `count` materials without a label.
fn note_text(left_out: usize, count: usize) -> String {
    format!("{left_out} of {count} materials not labelled (the JSON sidecar names all)")
}
