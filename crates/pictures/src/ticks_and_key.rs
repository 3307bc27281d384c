//! What a map picture says about itself: latent-axis ticks along the bottom
//! and left edges, a colour key for luminance in a corner, and a note when
//! some materials could not be labelled. Each piece is laid out first (its
//! box reserved, so labels keep clear of it), then drawn.

use brdf_atlas_core::View;

use crate::canvas::{Canvas, Rect, overlaps, srgb, text_size};

/// Ink of the decorations and labels (sRGB-encoded, as the canvas).
pub const INK: [f32; 3] = [0.02, 0.02, 0.02];
/// Background of text boxes and its opacity.
pub const PAPER: ([f32; 3], f32) = ([1.0, 1.0, 1.0], 0.78);
/// Length of a tick mark, pixels.
const TICK: f32 = 6.0;
/// Space between the image edge and a decoration, pixels.
const MARGIN: f32 = 6.0;

/// A number or word drawn in a box, with the mark it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    /// The tick mark, pixel coordinates.
    pub mark: [[f32; 2]; 2],
    /// The text and its box.
    pub text: String,
    /// Box of the text (with its paper).
    pub rect: Rect,
}

/// The colour key: a grey ramp of the luminance (the grey of that
/// luminance, as the map's pixels are encoded) from the map's smallest (bottom) to
/// largest (top) luminance, with a mark at every contour level.
#[derive(Debug, Clone, PartialEq)]
pub struct Key {
    /// The whole panel.
    pub rect: Rect,
    /// The ramp.
    pub bar: Rect,
    /// The title's top-left corner.
    pub title: [f32; 2],
    /// Luminance at the bottom and top of the ramp.
    pub range: [f32; 2],
    /// Contour levels (drawn as lines across the ramp).
    pub levels: Vec<f32>,
    /// Numbers beside the ramp.
    pub ticks: Vec<Tick>,
}

/// A step of 1, 2, 2.5 or 5 times a power of ten giving 3 to 8 ticks over `span`.
fn nice_step(span: f64) -> f64 {
    let base = 10f64.powf((span / 5.0).log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * base)
        .find(|s| span / s <= 8.0)
        .unwrap_or(10.0 * base)
}

/// `v` with as many decimals as `step` needs.
fn number(v: f64, step: f64) -> String {
    let mut decimals = (-step.log10().floor()).max(0.0) as usize;
    if (step / 10f64.powi(-(decimals as i32)) - (step / 10f64.powi(-(decimals as i32))).round())
        .abs()
        > 1e-6
    {
        decimals += 1;
    }
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// Multiples of `step` strictly inside `(lo, hi)`.
fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let first = (lo / step).floor() as i64 + 1;
    (first..)
        .map(|k| k as f64 * step)
        .take_while(|v| *v < hi - 1e-9 * step)
        .filter(|v| *v > lo + 1e-9 * step)
        .collect()
}

fn paper(at: [f32; 2], s: &str, px: f32) -> Rect {
    let [w, h] = text_size(s, px);
    [at[0], at[1], at[0] + w + 4.0, at[1] + h + 2.0]
}

/// Ticks at round latent values along the bottom (x) and left (y) edges of
/// a `width x height` picture of `view`; those whose number would leave the
/// picture, meet another or cover one of the `dots` are dropped.
pub fn axis_ticks(view: &View, width: usize, height: usize, px: f32, dots: &[Rect]) -> Vec<Tick> {
    let (w, h) = (width as f32, height as f32);
    let mut out: Vec<Tick> = Vec::new();
    let step = nice_step(view.x1 - view.x0);
    for v in multiples(view.x0, view.x1, step) {
        let x = view.latent_to_pixel([v, view.y0], width, height)[0] as f32;
        let text = number(v, step);
        let r = paper([0.0, 0.0], &text, px);
        let rect = [
            x - r[2] / 2.0,
            h - TICK - 1.0 - r[3],
            x + r[2] / 2.0,
            h - TICK - 1.0,
        ];
        out.push(Tick {
            mark: [[x, h], [x, h - TICK]],
            text,
            rect,
        });
    }
    let step = nice_step(view.y1 - view.y0);
    for v in multiples(view.y0, view.y1, step) {
        let y = view.latent_to_pixel([view.x0, v], width, height)[1] as f32;
        let text = number(v, step);
        let r = paper([0.0, 0.0], &text, px);
        let rect = [
            TICK + 1.0,
            y - r[3] / 2.0,
            TICK + 1.0 + r[2],
            y + r[3] / 2.0,
        ];
        out.push(Tick {
            mark: [[0.0, y], [TICK, y]],
            text,
            rect,
        });
    }
    let inside = |r: &Rect| r[0] >= 0.0 && r[1] >= 0.0 && r[2] <= w && r[3] <= h;
    let mut kept: Vec<Tick> = Vec::new();
    for t in out {
        let clear = !kept.iter().any(|k| overlaps(&k.rect, &t.rect))
            && !dots.iter().any(|d| overlaps(d, &t.rect));
        if inside(&t.rect) && clear {
            kept.push(t);
        }
    }
    kept
}

/// The key's layout in the corner (top-right, top-left, bottom-right) that
/// covers the fewest `dots`, clear of `ticks`; `None` if the picture is too
/// small to hold it.
pub fn key(
    range: [f32; 2],
    levels: &[f32],
    width: usize,
    height: usize,
    px: f32,
    dots: &[Rect],
    ticks: &[Tick],
) -> Option<Key> {
    let (w, h) = (width as f32, height as f32);
    let title = "luminance";
    let [tw, th] = text_size(title, px);
    let bar_h = (0.3 * h).clamp(60.0, 220.0);
    let bar_w = 12.0;
    let span = (range[1] - range[0]) as f64;
    let mut values = vec![range[0] as f64, range[1] as f64];
    if span > 0.0 {
        let step = nice_step(span);
        values = multiples(range[0] as f64, range[1] as f64, step);
        values.insert(0, range[0] as f64);
        values.push(range[1] as f64);
    }
    let label_step = if span > 0.0 {
        nice_step(span) / 10.0
    } else {
        0.01
    };
    let texts: Vec<String> = values.iter().map(|&v| number(v, label_step)).collect();
    let number_w = texts
        .iter()
        .map(|t| text_size(t, px)[0])
        .fold(0.0f32, f32::max);
    let pad = 5.0;
    let panel_w = (pad + bar_w + 4.0 + number_w + 4.0 + pad).max(tw + 2.0 * pad);
    let panel_h = pad + th + 4.0 + bar_h + th / 2.0 + pad;
    if panel_w + 2.0 * MARGIN > w / 2.0 || panel_h + 2.0 * MARGIN > h / 2.0 {
        return None;
    }
    let bottom_zone = ticks
        .iter()
        .filter(|t| t.mark[0][1] >= h - 0.5)
        .map(|t| h - t.rect[1])
        .fold(0.0f32, f32::max);
    let left_zone = ticks
        .iter()
        .filter(|t| t.mark[0][0] <= 0.5)
        .map(|t| t.rect[2])
        .fold(0.0f32, f32::max);
    let corners = [
        [w - MARGIN - panel_w, MARGIN],
        [left_zone + MARGIN, MARGIN],
        [w - MARGIN - panel_w, h - bottom_zone - MARGIN - panel_h],
    ];
    let at = corners
        .iter()
        .map(|&[x, y]| [x, y, x + panel_w, y + panel_h])
        .filter(|r| !ticks.iter().any(|t| overlaps(r, &t.rect)))
        .min_by_key(|r| dots.iter().filter(|d| overlaps(r, d)).count())?;
    let bar = [
        at[0] + pad,
        at[1] + pad + th + 4.0,
        at[0] + pad + bar_w,
        at[1] + pad + th + 4.0 + bar_h,
    ];
    let y_of = |v: f64| {
        if span > 0.0 {
            bar[3] - ((v - range[0] as f64) / span) as f32 * bar_h
        } else {
            bar[3]
        }
    };
    // The ends first, so that a round value too close to one gives way.
    let mut order: Vec<usize> = (0..values.len()).collect();
    if order.len() > 2 {
        order.rotate_right(1);
        order.swap(0, 1);
    }
    let mut ticks: Vec<Tick> = Vec::new();
    for tick in order
        .into_iter()
        .map(|k| (values[k], texts[k].clone()))
        .map(|(v, text)| {
            let y = y_of(v);
            let r = paper([0.0, 0.0], &text, px);
            Tick {
                mark: [[bar[2], y], [bar[2] + 4.0, y]],
                rect: [
                    bar[2] + 4.0,
                    y - r[3] / 2.0,
                    bar[2] + 4.0 + r[2],
                    y + r[3] / 2.0,
                ],
                text,
            }
        })
    {
        if !ticks.iter().any(|t| overlaps(&t.rect, &tick.rect)) {
            ticks.push(tick);
        }
    }
    Some(Key {
        rect: at,
        bar,
        title: [at[0] + pad + (panel_w - 2.0 * pad - tw) / 2.0, at[1] + pad],
        range,
        levels: levels.to_vec(),
        ticks,
    })
}

/// A note's box in the first free place along the top edge (left, right,
/// centre), clear of `reserved` and covering the fewest `dots`.
pub fn note_box(
    text: &str,
    width: usize,
    px: f32,
    left: f32,
    dots: &[Rect],
    reserved: &[Rect],
) -> Rect {
    let r = paper([0.0, 0.0], text, px);
    let w = width as f32;
    let xs = [left + MARGIN, w - MARGIN - r[2], (w - r[2]) / 2.0];
    xs.iter()
        .map(|&x| [x, MARGIN, x + r[2], MARGIN + r[3]])
        .filter(|b| b[0] >= 0.0 && b[2] <= w)
        .min_by_key(|b| {
            let blocked = reserved.iter().any(|r| overlaps(b, r));
            (blocked, dots.iter().filter(|d| overlaps(b, d)).count())
        })
        .unwrap_or([0.0, 0.0, r[2].min(w), r[3]])
}

/// Text on paper at the top-left of `rect`.
pub fn draw_text_box(canvas: &mut Canvas, rect: Rect, text: &str, px: f32) {
    canvas.rect(rect, PAPER.0, PAPER.1);
    canvas.text(rect[0] + 2.0, rect[1] + 1.0, text, px, INK);
}

/// Draw ticks (marks and numbers).
pub fn draw_ticks(canvas: &mut Canvas, ticks: &[Tick], px: f32) {
    for t in ticks {
        canvas.line(t.mark[0], t.mark[1], INK, 0.9);
        draw_text_box(canvas, t.rect, &t.text, px);
    }
}

/// Draw the key.
pub fn draw_key(canvas: &mut Canvas, key: &Key, px: f32) {
    canvas.rect(key.rect, PAPER.0, PAPER.1);
    canvas.text(key.title[0], key.title[1], "luminance", px, INK);
    let [x0, y0, x1, y1] = key.bar.map(|v| v.round());
    let span = key.range[1] - key.range[0];
    for y in y0 as i64..y1 as i64 {
        let t = (y1 - 0.5 - y as f32) / (y1 - y0);
        let l = srgb((key.range[0] + t * span).clamp(0.0, 1.0));
        for x in x0 as i64..x1 as i64 {
            canvas.blend(x, y, [l; 3], 1.0);
        }
    }
    for &level in &key.levels {
        if span > 0.0 {
            let y = y1 - (level - key.range[0]) / span * (y1 - y0);
            canvas.line([x0, y], [x1, y], INK, 0.55);
        }
    }
    for (a, b) in [
        ([x0, y0], [x1, y0]),
        ([x1, y0], [x1, y1]),
        ([x1, y1], [x0, y1]),
        ([x0, y1], [x0, y0]),
    ] {
        canvas.line(a, b, INK, 0.7);
    }
    for t in &key.ticks {
        canvas.line(t.mark[0], t.mark[1], INK, 0.9);
        canvas.text(t.rect[0] + 2.0, t.rect[1] + 1.0, &t.text, px, INK);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_fall_on_round_values_at_their_pixels() {
        let view = View::default();
        assert_eq!(nice_step(2.2), 0.5);
        assert_eq!(number(-0.5, 0.5), "-0.5");
        assert_eq!(number(1.0, 0.5), "1.0");
        assert_eq!(number(-0.0, 0.5), "0.0");
        assert_eq!(number(0.25, 0.25), "0.25");
        let ticks = axis_ticks(&view, 768, 768, 12.0, &[]);
        let xs: Vec<&str> = ticks
            .iter()
            .filter(|t| t.mark[0][1] == 768.0)
            .map(|t| t.text.as_str())
            .collect();
        assert_eq!(xs, ["-1.0", "-0.5", "0.0", "0.5", "1.0"]);
        for t in &ticks {
            let v: f64 = t.text.parse().unwrap();
            let [x, y] = t.mark[0];
            let want = if y == 768.0 {
                view.latent_to_pixel([v, 0.0], 768, 768)[0] as f32 - x
            } else {
                view.latent_to_pixel([0.0, v], 768, 768)[1] as f32 - y
            };
            assert!(want.abs() < 1e-3, "{t:?}");
        }
    }
}
