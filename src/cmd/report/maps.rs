//! The report's map measurements: what the per-pixel rule's sample count
//! buys, the default method (the albedo field where it fits its budget)
//! and the prepared map (the lattice of `brdf-atlas prepare`) against it,
//! and the time of each size.

use std::time::Instant;

use brdf_atlas_core::map_error::{albedo_error, map_error};
use brdf_atlas_core::{
    AlbedoMethod, AlbedoRequest, Atlas, BlendRule, DEFAULT_SAMPLES, FIELD_SAMPLES, Integration,
    LATTICE_TOLERANCE, NODE_PHI_D_STEP, NoProgress, View,
};

use brdf_merl::Quadrature;

use super::plan::Plan;
use super::results::{MethodRow, Results, RuleRow, SampleRow, SizeRow};
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

/// Seed of the points of the rules' table.
const RULE_SEED: u64 = 5;

/// What the exact albedo costs by rule: the default material's albedo at
/// random points of the default view from one pass a rule, against the
/// dense rule's: the map's nodes' rule, reduced rules that integrate a
/// cubic or linear interpolant through every few theta_d and phi_d bins,
/// the per-pixel rule and the sampled field's nodes' rule (one bin standing
/// for each box of bins), and Monte Carlo sampling of the dense rule.
pub fn rules(model: &Atlas, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    let view = View::default();
    let mut rng = brdf_merl::synth::SplitMix64::new(RULE_SEED);
    let points: Vec<[f64; 2]> = (0..plan.rule_points)
        .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
        .collect();
    let count = points.len().max(1) as u32;
    let dense = model.albedo_rule().clone();
    let request = AlbedoRequest::new().rule(BlendRule::Floor);
    let t = Instant::now();
    let reference = model.exact_albedos(&points, request)?;
    r.rules.push(RuleRow {
        rule: "dense (the reference: every bin, 2 sub-cells a side)".into(),
        bins: dense.len(),
        per_point: t.elapsed() / count,
        max_err: 0.0,
        mean_err: 0.0,
    });
    let step = NODE_PHI_D_STEP;
    let rules: Vec<(String, Quadrature)> = vec![
        (
            format!("cubic interpolant, every {step}th phi_d bin (the map's nodes)"),
            model.reduced_rule(1, step, true),
        ),
        (
            format!("every {step}th phi_d bin, its cell's weight"),
            dense.every_phi_d(step),
        ),
        (
            "cubic interpolant, every 2nd theta_d and 4th phi_d bin".into(),
            model.reduced_rule(2, 4, true),
        ),
        (
            "cubic interpolant, every 3rd theta_d and 6th phi_d bin".into(),
            model.reduced_rule(3, 6, true),
        ),
        (
            "linear interpolant, every 3rd theta_d and 6th phi_d bin".into(),
            model.reduced_rule(3, 6, false),
        ),
        (
            format!("{DEFAULT_SAMPLES} samples, one bin a box (the per-pixel rule)"),
            Quadrature::with_samples_shaped(&dense, DEFAULT_SAMPLES, model.shape()),
        ),
        (
            format!("{FIELD_SAMPLES} samples, one bin a box (the sampled field's nodes)"),
            Quadrature::with_samples_shaped(&dense, FIELD_SAMPLES, model.shape()),
        ),
        (
            "Monte Carlo, 4096 bins drawn by weight".into(),
            dense.monte_carlo(4096, RULE_SEED),
        ),
        (
            "Monte Carlo, 65536 bins drawn by weight".into(),
            dense.monte_carlo(65536, RULE_SEED),
        ),
    ];
    for (name, rule) in rules {
        let t = Instant::now();
        let got = model.exact_albedos(&points, request.integration(Integration::Rule(&rule)))?;
        let per_point = t.elapsed() / count;
        let (max_err, mean_err) = albedo_error(&got, &reference);
        r.rules.push(RuleRow {
            rule: name,
            bins: rule.len(),
            per_point,
            max_err,
            mean_err,
        });
    }
    r.rule_points = points.len();
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
            let sampled = matches!(map.method, AlbedoMethod::SampledField { .. });
            let (method, field) = match map.method {
                AlbedoMethod::Field { nodes, .. } => (format!("field, {nodes} exact nodes"), true),
                AlbedoMethod::SampledField { samples, nodes, .. } => (
                    format!("sampled field, {nodes} nodes of {samples} samples"),
                    false,
                ),
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
                sampled,
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
            sampled: false,
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
