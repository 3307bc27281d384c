//! The report's map measurements: what the per-pixel rule's sample count
//! buys, the default method (the albedo field where it fits its budget)
//! and the prepared map (the lattice of `brdf-atlas prepare`) against it,
//! and the time of each size.

use std::time::Instant;

use brdf_atlas_core::map_error::map_error;
use brdf_atlas_core::{
    AlbedoMethod, Atlas, BlendRule, DEFAULT_SAMPLES, LATTICE_TOLERANCE, NoProgress, View,
};

use brdf_merl::Quadrature;

use super::plan::Plan;
use super::results::{MethodRow, Results, SampleRow, SizeRow};
use super::timed;
use crate::error::Error;
use crate::progress::Bars;

/// The log map's error (against dense references on a small grid) and
/// time for each sample count.
pub fn samples(model: &Atlas, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    let view = View::default();
    let w = 4 * plan.grid;
    let pixels: Vec<(usize, usize)> = (0..plan.grid)
        .flat_map(|a| (0..plan.grid).map(move |b| (2 + 4 * a, 2 + 4 * b)))
        .collect();
    let dense = Quadrature::dense(model.dims(), 1);
    let t = Instant::now();
    let reference = references(model, &view, &pixels, w, &dense)?;
    r.reference_time = t.elapsed();
    r.reference_pixels = pixels.len();
    let bars = Bars::new("map sample counts");
    for &s in &plan.samples {
        let small = model.map(
            brdf_atlas_core::MapRequest::new(w, w)
                .view(view)
                .samples(Some(s)),
        )?;
        let (max_err, mean_err) = map_error(&small, &pixels, &reference);
        let size = plan.timed_size;
        let (map, time) = timed(plan.repeat, || {
            Ok(model.map(
                brdf_atlas_core::MapRequest::new(size, size)
                    .view(view)
                    .samples(Some(s))
                    .progress(&bars),
            )?)
        })?;
        let bins = match map.method {
            AlbedoMethod::Quadrature { bins, .. } => bins,
            _ => 0,
        };
        r.samples.push(SampleRow {
            samples: s,
            bins,
            max_err,
            mean_err,
            time,
        });
    }
    Ok(())
}

/// The default map (the albedo field where it fits its budget) and the
/// per-pixel rule with the default samples, at random pixels of the default
/// view and of one a hundred times smaller: error against dense references
/// and time, first and again (a field is kept by the model).
pub fn methods(model: &Atlas, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    let size = plan.timed_size;
    let small = View::zoomed_hundredfold();
    let mut seed = 0x5eed_u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 33) as usize) % size
    };
    // The prepared map, built once for both views (if the plan says so).
    let t = Instant::now();
    let lattice = match plan.prepare {
        true => Some(model.prepare_map(BlendRule::default(), LATTICE_TOLERANCE, &NoProgress)?),
        false => None,
    };
    let build = t.elapsed();
    for (name, view) in [("default", View::default()), ("1/100", small)] {
        let pixels: Vec<(usize, usize)> = (0..plan.grid * plan.grid)
            .map(|_| (next(), next()))
            .collect();
        let reference = references(model, &view, &pixels, size, model.albedo_rule())?;
        for samples in [None, Some(DEFAULT_SAMPLES)] {
            // A default that is the per-pixel rule at the default samples
            // is the next row's map: measured once, shown in both rows.
            if let (Some(_), Some(last)) = (samples, r.methods.last())
                && last.view == name
                && last.method == format!("default (per pixel, {DEFAULT_SAMPLES} samples)")
            {
                let mut row = last.clone();
                row.method = format!("per pixel, {DEFAULT_SAMPLES} samples");
                r.methods.push(row);
                continue;
            }
            let t = Instant::now();
            let map = model.map(
                brdf_atlas_core::MapRequest::new(size, size)
                    .view(view)
                    .samples(samples),
            )?;
            let first = t.elapsed();
            let t = Instant::now();
            model.map(
                brdf_atlas_core::MapRequest::new(size, size)
                    .view(view)
                    .samples(samples),
            )?;
            let again = t.elapsed();
            let (max_err, mean_err) = map_error(&map, &pixels, &reference);
            let (method, field) = match map.method {
                AlbedoMethod::Field { nodes, .. } => (format!("field, {nodes} exact nodes"), true),
                AlbedoMethod::Lattice { nodes, .. } => (format!("lattice, {nodes} nodes"), true),
                AlbedoMethod::Quadrature { samples, .. } => {
                    (format!("per pixel, {samples} samples"), false)
                }
                AlbedoMethod::Linear => ("linear".into(), false),
            };
            let method = match samples {
                None => format!("default ({method})"),
                Some(_) => method,
            };
            r.methods.push(MethodRow {
                view: name,
                method,
                field,
                prepared: false,
                max_err,
                mean_err,
                first,
                again,
            });
        }
        let Some(lattice) = &lattice else {
            continue;
        };
        let t = Instant::now();
        let map = model.map(
            brdf_atlas_core::MapRequest::new(size, size)
                .view(view)
                .lattice(lattice),
        )?;
        let again = t.elapsed();
        let (max_err, mean_err) = map_error(&map, &pixels, &reference);
        r.methods.push(MethodRow {
            view: name,
            method: format!("prepared lattice, {} exact albedos", lattice.nodes()),
            field: false,
            prepared: true,
            max_err,
            mean_err,
            first: build + again,
            again,
        });
    }
    r.methods_size = size;
    Ok(())
}

/// The dense references of `pixels` of a `size x size` map of `view`
/// (the default blend, integrated with `rule`): all of them from one pass
/// over the rule's rows ([`Atlas::exact_albedos`], equal to
/// [`brdf_atlas_core::map_error::reference_albedo`] point by point to rounding).
fn references(
    model: &Atlas,
    view: &View,
    pixels: &[(usize, usize)],
    size: usize,
    rule: &Quadrature,
) -> Result<Vec<[f64; 3]>, Error> {
    let points: Vec<[f64; 2]> = pixels
        .iter()
        .map(|&(px, py)| view.pixel_to_latent(px as f64, py as f64, size, size))
        .collect();
    Ok(model.exact_albedos(
        &points,
        brdf_atlas_core::AlbedoRequest::new().integration(brdf_atlas_core::Integration::Rule(rule)),
    )?)
}

/// The time of a map of each size, log (default samples; the sample
/// sweep's at its size) and raw (linear).
pub fn sizes(log: &Atlas, raw: &Atlas, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    let view = View::default();
    // The sample sweep timed this map already at its size.
    let swept = r
        .samples
        .iter()
        .find(|m| m.samples == DEFAULT_SAMPLES)
        .map(|m| m.time);
    for &s in &plan.sizes {
        let t = match swept {
            Some(t) if s == plan.timed_size => t,
            _ => {
                timed(plan.repeat, || {
                    Ok(log.map(
                        brdf_atlas_core::MapRequest::new(s, s)
                            .view(view)
                            .samples(Some(DEFAULT_SAMPLES)),
                    )?)
                })?
                .1
            }
        };
        r.sizes.push(SizeRow {
            method: format!("log, {DEFAULT_SAMPLES} samples"),
            size: s,
            time: t,
        });
        let (_, t) = timed(plan.repeat, || {
            Ok(raw.map(brdf_atlas_core::MapRequest::new(s, s).view(view))?)
        })?;
        r.sizes.push(SizeRow {
            method: "raw, linear".into(),
            size: s,
            time: t,
        });
    }
    Ok(())
}
