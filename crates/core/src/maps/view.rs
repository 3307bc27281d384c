//! A window of the latent plane and its pixel <-> latent mapping, shared
//! by the map and the albedo field.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

/// A window of the latent plane: `x` in `[x0, x1]`, `y` in `[y0, y1]`, y up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Left edge.
    pub x0: f64,
    /// Right edge.
    pub x1: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Top edge.
    pub y1: f64,
}

impl Default for View {
    /// The box `[-1, 1]^2` plus a 10% margin.
    fn default() -> Self {
        let h = crate::limits::DEFAULT_VIEW_HALF_WIDTH;
        View {
            x0: -h,
            x1: h,
            y0: -h,
            y1: h,
        }
    }
}

impl View {
    /// The view a hundred times smaller than the default one, centred at
    /// (0.137, -0.291): between materials of the 100 NBRDF-derived
    /// materials' default model, where the albedo varies. The report, the
    /// benchmarks and the map accuracy example measure zoomed-in maps on it.
    pub fn zoomed_hundredfold() -> View {
        let (cx, cy) = (0.137, -0.291);
        let h = View::default().x1 / 100.0;
        View {
            x0: cx - h,
            x1: cx + h,
            y0: cy - h,
            y1: cy + h,
        }
    }

    /// `[-3, 3]^2`: the default view zoomed out about three times, where
    /// most of the picture is far from every material. `brdf-atlas fit`
    /// saves its map's field beside the model with the default view's: its
    /// domain holds the map panel's windows, wider than they are high.
    pub fn wide() -> View {
        View {
            x0: -3.0,
            x1: 3.0,
            y0: -3.0,
            y1: 3.0,
        }
    }

    /// Whether `other` lies inside this window (edges included).
    pub fn holds(&self, other: View) -> bool {
        self.x0 <= other.x0 && other.x1 <= self.x1 && self.y0 <= other.y0 && other.y1 <= self.y1
    }

    /// The window's area.
    pub fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// Check the window is finite and not empty.
    pub fn check(&self) -> Result<()> {
        let ok = [self.x0, self.x1, self.y0, self.y1]
            .iter()
            .all(|v| v.is_finite())
            && self.x0 < self.x1
            && self.y0 < self.y1;
        if ok {
            Ok(())
        } else {
            Err(CoreError::BadQuery(format!(
                "view window {self:?} must be finite with x0 < x1 and y0 < y1"
            )))
        }
    }

    /// Latent point at the centre of pixel `(px, py)` of a `width x height` image (row 0 at the top).
    pub fn pixel_to_latent(&self, px: f64, py: f64, width: usize, height: usize) -> [f64; 2] {
        [
            self.x0 + (px + 0.5) * (self.x1 - self.x0) / width as f64,
            self.y1 - (py + 0.5) * (self.y1 - self.y0) / height as f64,
        ]
    }

    /// Pixel coordinates (continuous, centres at `k + 0.5`) of a latent point.
    pub fn latent_to_pixel(&self, x: [f64; 2], width: usize, height: usize) -> [f64; 2] {
        [
            (x[0] - self.x0) / (self.x1 - self.x0) * width as f64,
            (self.y1 - x[1]) / (self.y1 - self.y0) * height as f64,
        ]
    }
}

/// The domain of `view`: per axis, the smallest interval of the lattice of
/// the default view's side over powers of two, offset by half lengths, that
/// holds the view's interval (the view itself past 60 halvings or doublings).
pub fn domain_of(view: View) -> View {
    let d = View::default();
    let axis = |a: f64, len: f64, v0: f64, v1: f64| -> (f64, f64) {
        for k in (-60..=60).rev() {
            let s = len * 2f64.powi(-k);
            let i = ((v0 - a) / (0.5 * s)).floor();
            let lo = a + i * 0.5 * s;
            if lo <= v0 && lo + s >= v1 {
                return (lo, lo + s);
            }
        }
        (v0, v1)
    };
    let (x0, x1) = axis(d.x0, d.x1 - d.x0, view.x0, view.x1);
    let (y0, y1) = axis(d.y0, d.y1 - d.y0, view.y0, view.y1);
    View { x0, x1, y0, y1 }
}
