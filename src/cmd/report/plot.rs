//! The report's plots: plotters on an RGB buffer, encoded with the png
//! crate. Text uses DejaVu Sans embedded in the binary (assets/, Bitstream
//! Vera licence, see assets/DejaVuSans-LICENSE.txt), so no system font
//! library is needed. Log axes are drawn as linear axes over `log10` of the
//! values, labelled with the values themselves.

use std::io;
use std::path::Path;

use brdf_atlas_core::{OptimizerKind, TransformKind};
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::results::{LooRow, Results, SampleRow};
use super::write_file;
use crate::error::Error;

/// The font the map pictures draw with too (embedded once, in the core).
static FONT: &[u8] = brdf_atlas_pictures::FONT;

const WIDTH: u32 = 720;
const HEIGHT: u32 = 440;

/// A series: name, colour, points (already on the plotted scale), markers only?
pub struct Series {
    pub name: String,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
    pub markers_only: bool,
}

/// One axis: label and whether values are log10 of the data.
pub struct Axis<'a> {
    pub label: &'a str,
    pub log: bool,
    /// Integer data (ticks on whole numbers only).
    pub integer: bool,
}

/// A plot that could not be drawn is an output that could not be written.
fn err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        source: io::Error::other(format!("cannot draw plot: {e}")),
    }
}

fn scale(v: f64, log: bool) -> f64 {
    if log { v.max(1e-300).log10() } else { v }
}

fn tick(v: f64, log: bool) -> String {
    let x = if log { 10f64.powf(v) } else { v };
    if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e4 || x.abs() < 1e-2 {
        format!("{x:.0e}")
    } else if x.abs() >= 10.0 {
        format!("{x:.0}")
    } else {
        format!("{:.2}", x)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

pub const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
];

pub fn chart(path: &Path, title: &str, x: Axis, y: Axis, series: &[Series]) -> Result<(), Error> {
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .map(|(a, b)| (scale(a, x.log), scale(b, y.log)))
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let range = |v: Vec<f64>| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if !lo.is_finite() {
            return (0.0, 1.0);
        }
        let pad = ((hi - lo) * 0.08).max(if hi.abs() > 0.0 {
            hi.abs() * 0.05
        } else {
            0.05
        });
        (lo - pad, hi + pad)
    };
    let (x0, x1) = range(pts.iter().map(|p| p.0).collect());
    let (y0, y1) = range(pts.iter().map(|p| p.1).collect());
    // Room at the top for the legend.
    let y1 = y1 + 0.3 * (y1 - y0);
    let x_ticks = if x.integer {
        ((x1 - x0).round() as usize + 1).clamp(2, 20)
    } else {
        8
    };
    let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(path, e))?;
        let mut c = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(path, e))?;
        c.configure_mesh()
            .x_desc(x.label)
            .y_desc(y.label)
            .x_labels(x_ticks)
            .x_label_formatter(&|v| {
                if x.integer {
                    format!("{}", v.round())
                } else {
                    tick(*v, x.log)
                }
            })
            .y_label_formatter(&|v| tick(*v, y.log))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| err(path, e))?;
        for s in series {
            let p: Vec<(f64, f64)> = s
                .points
                .iter()
                .map(|&(a, b)| (scale(a, x.log), scale(b, y.log)))
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .collect();
            let color = s.color;
            let style = ShapeStyle::from(&color).stroke_width(2);
            if s.markers_only {
                c.draw_series(p.iter().map(|&q| Cross::new(q, 7, style)))
                    .map_err(|e| err(path, e))?
                    .label(s.name.clone())
                    .legend(move |(a, b)| Cross::new((a + 10, b), 5, style));
            } else {
                c.draw_series(LineSeries::new(p.clone(), style))
                    .map_err(|e| err(path, e))?
                    .label(s.name.clone())
                    .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 20, b)], style));
                c.draw_series(p.iter().map(|&q| Circle::new(q, 3, color.filled())))
                    .map_err(|e| err(path, e))?;
            }
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(path, e))?;
        root.present().map_err(|e| err(path, e))?;
    }
    write_png(path, &buf)
}

fn write_png(path: &Path, rgb: &[u8]) -> Result<(), Error> {
    let encoding = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => e,
        e => io::Error::other(e),
    };
    write_file(path, |file| {
        let mut enc = png::Encoder::new(file, WIDTH, HEIGHT);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(encoding)?;
        w.write_image_data(rgb).map_err(encoding)?;
        w.finish().map_err(encoding)
    })
}

/// Draw every plot of the report into `dir`.
pub fn all(dir: &Path, r: &Results) -> Result<(), Error> {
    // Registering twice (a demo then a report in one process) is harmless.
    register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| Error::Input("embedded font DejaVuSans.ttf is invalid".into()))?;
    let loo_series = |metric: fn(&LooRow) -> f64| {
        let mut out = Vec::new();
        let mut k = 0;
        for t in [TransformKind::Log, TransformKind::Raw] {
            for (method, label) in [("gplvm", "GPLVM"), ("pca", "PCA held out")] {
                let points: Vec<(f64, f64)> = r
                    .loo
                    .iter()
                    .filter(|l| l.transform == t && l.method == method)
                    .map(|l| (l.q as f64, metric(l)))
                    .collect();
                if !points.is_empty() {
                    out.push(Series {
                        name: format!("{label}, {} transform", t.name()),
                        color: COLORS[k],
                        points,
                        markers_only: false,
                    });
                }
                k += 1;
            }
        }
        out
    };
    let n = r.names.len();
    chart(
        &dir.join("loo.png"),
        &format!("Leave-one-out error, {n} materials: cosine-weighted log RMSE"),
        Axis {
            label: "latent dimension q (PCA: components)",
            log: false,
            integer: true,
        },
        Axis {
            label: "RMSE of log(1 + f cos_i cos_o)",
            log: true,
            integer: false,
        },
        &loo_series(|l| l.log),
    )?;
    chart(
        &dir.join("loo-reflectance.png"),
        &format!("Leave-one-out error, {n} materials: reflectance RMSE"),
        Axis {
            label: "latent dimension q (PCA: components)",
            log: false,
            integer: true,
        },
        Axis {
            label: "reflectance RMSE (1/sr)",
            log: true,
            integer: false,
        },
        &loo_series(|l| l.raw),
    )?;
    if !r.sweep.is_empty() {
        let mut series = vec![Series {
            name: "Hooke-Jeeves, min step 1e-1 .. 1e-4".into(),
            color: COLORS[0],
            points: r
                .sweep
                .iter()
                .map(|f| (f.time.as_secs_f64(), f.cost))
                .collect(),
            markers_only: false,
        }];
        let lb: Vec<(f64, f64)> = r
            .fits
            .iter()
            .filter(|f| {
                f.transform == TransformKind::Log && f.q == 2 && f.optimizer == OptimizerKind::Lbfgs
            })
            .map(|f| (f.time.as_secs_f64(), f.cost))
            .collect();
        series.push(Series {
            name: "L-BFGS".into(),
            color: COLORS[1],
            points: lb,
            markers_only: true,
        });
        chart(
            &dir.join("optimizers.png"),
            "Fit of q = 2, log transform: cost reached vs time",
            Axis {
                label: "optimiser time (s)",
                log: true,
                integer: false,
            },
            Axis {
                label: "final cost (negative log likelihood)",
                log: false,
                integer: false,
            },
            &series,
        )?;
    }
    if !r.samples.is_empty() {
        let pts = |f: fn(&SampleRow) -> f64| -> Vec<(f64, f64)> {
            r.samples.iter().map(|m| (m.samples as f64, f(m))).collect()
        };
        chart(
            &dir.join("map-samples.png"),
            "Albedo map (log transform): error vs quadrature samples",
            Axis {
                label: "quadrature samples per pixel",
                log: true,
                integer: false,
            },
            Axis {
                label: "albedo error (relative)",
                log: true,
                integer: false,
            },
            &[
                Series {
                    name: "max error".into(),
                    color: COLORS[1],
                    points: pts(|m| m.max_err),
                    markers_only: false,
                },
                Series {
                    name: "mean error".into(),
                    color: COLORS[0],
                    points: pts(|m| m.mean_err),
                    markers_only: false,
                },
            ],
        )?;
        let mut methods: Vec<&str> = r.sizes.iter().map(|m| m.method.as_str()).collect();
        methods.dedup();
        methods.sort();
        methods.dedup();
        let series: Vec<Series> = methods
            .iter()
            .enumerate()
            .map(|(k, name)| Series {
                name: name.to_string(),
                color: COLORS[k],
                points: r
                    .sizes
                    .iter()
                    .filter(|m| m.method == *name)
                    .map(|m| ((m.size * m.size) as f64, m.time.as_secs_f64()))
                    .collect(),
                markers_only: false,
            })
            .collect();
        chart(
            &dir.join("map-size.png"),
            "Albedo map: time vs pixels",
            Axis {
                label: "pixels (size x size)",
                log: true,
                integer: false,
            },
            Axis {
                label: "time (s)",
                log: true,
                integer: false,
            },
            &series,
        )?;
    }
    Ok(())
}
