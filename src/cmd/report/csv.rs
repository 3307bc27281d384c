//! The report's CSV tables: every number the markdown summarises, a row
//! per measurement.

use std::fmt::Display;
use std::io::Write;
use std::path::Path;
use std::time::Duration;

use super::results::Results;
use super::write_file;
use crate::error::Error;
use crate::format::coordinates;

/// A header line and one line per row.
fn table(header: &str, rows: impl IntoIterator<Item = String>) -> String {
    let mut s = format!("{header}\n");
    for row in rows {
        s.push_str(&row);
        s.push('\n');
    }
    s
}

/// Cells separated by commas.
fn row(cells: &[&dyn Display]) -> String {
    let cells: Vec<String> = cells.iter().map(|c| c.to_string()).collect();
    cells.join(",")
}

/// Full precision, scientific: `1.25e-3`.
pub(super) fn e(v: f64) -> String {
    format!("{v:e}")
}

/// Seconds with `digits` decimals.
fn seconds(t: Duration, digits: usize) -> String {
    format!("{:.digits$}", t.as_secs_f64())
}

/// Write every table into `dir`.
pub fn write_all(dir: &Path, r: &Results) -> Result<(), Error> {
    let loo = table(
        "transform,method,q,rmse_reflectance,rmse_cos_log,rmse_transformed,pca_in_sample_rmse_transformed",
        r.loo.iter().map(|l| {
            let in_sample = l.in_sample.map_or(String::new(), e);
            let name = l.transform.name();
            row(&[
                &name,
                &l.method,
                &l.q,
                &e(l.raw),
                &e(l.log),
                &e(l.transformed),
                &in_sample,
            ])
        }),
    );
    let per_material = table(
        "transform,method,q,material,rmse_reflectance,rmse_cos_log",
        r.loo.iter().flat_map(|l| {
            r.names.iter().zip(&l.materials).map(|(name, &(raw, log))| {
                row(&[&l.transform.name(), &l.method, &l.q, name, &e(raw), &e(log)])
            })
        }),
    );
    let fits = table(
        "transform,q,optimizer,min_step,seconds,initial_cost,cost,evaluations",
        r.fits.iter().chain(&r.sweep).map(|f| {
            let (t, q, opt, step) = (f.transform.name(), f.q, f.optimizer.name(), f.min_step);
            let (time, evaluations) = (seconds(f.time, 4), f.evaluations);
            row(&[
                &t,
                &q,
                &opt,
                &step,
                &time,
                &e(f.initial_cost),
                &e(f.cost),
                &evaluations,
            ])
        }),
    );
    let samples = table(
        "samples,bins,max_rel_error,mean_rel_error,seconds",
        r.samples.iter().map(|m| {
            let time = seconds(m.time, 4);
            row(&[&m.samples, &m.bins, &e(m.max_err), &e(m.mean_err), &time])
        }),
    );
    let rules = table(
        "rule,bins,max_rel_error,mean_rel_error,seconds_per_point",
        r.rules.iter().map(|m| {
            let (rule, time) = (format!("\"{}\"", m.rule), seconds(m.per_point, 5));
            row(&[&rule, &m.bins, &e(m.max_err), &e(m.mean_err), &time])
        }),
    );
    let sizes = table(
        "method,size,seconds",
        r.sizes
            .iter()
            .map(|m| row(&[&m.method, &m.size, &seconds(m.time, 4)])),
    );
    let stores = table(
        "transform,precision,build_seconds,bytes",
        r.stores.iter().map(|st| {
            let (transform, precision) = (st.transform.name(), st.precision.name());
            row(&[&transform, &precision, &seconds(st.time, 3), &st.bytes])
        }),
    );
    let precision = table(
        "point,max_abs_diff,max_diff_over_peak,rms_diff,seconds_f32,seconds_f64",
        r.precision.iter().map(|p| {
            let point = format!("\"{}\"", coordinates(&p.point, 3));
            let times = (seconds(p.time32, 4), seconds(p.time64, 4));
            let diffs = (e(p.max_abs), e(p.max_rel), e(p.rms));
            row(&[&point, &diffs.0, &diffs.1, &diffs.2, &times.0, &times.1])
        }),
    );
    for (name, text) in [
        ("loo.csv", loo),
        ("loo-materials.csv", per_material),
        ("fits.csv", fits),
        ("map-samples.csv", samples),
        ("map-rules.csv", rules),
        ("map-size.csv", sizes),
        ("stores.csv", stores),
        ("precision.csv", precision),
    ] {
        write_file(&dir.join(name), |w| w.write_all(text.as_bytes()))?;
    }
    Ok(())
}
