//! The report's first section: does each material's marker give it back?
//! Settings of the transform and the kernel (the paper's, the default, and
//! between) compared on the errors a person sees, each material at its own
//! point and predicted from the others ([`brdf_atlas_core::fidelity`]),
//! beside the older `ln(1 + v)` RMSE, how far apart the materials land, what
//! the model knows over the map's view, how plausible its materials are,
//! and what the fit costs.

use std::io::{self, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use brdf_atlas_core::fidelity::{Summary, fidelity, known_share, spacing};
use brdf_atlas_core::{
    Atlas, BlendRule, DEFAULT_NOISE, DEFAULT_TRANSFORM, Dataset, GplvmParams, Kernel, NoProgress,
    PAPER_KERNEL, PAPER_TRANSFORM, Precision, TransformKind, View, default_kernel,
};
use brdf_merl::synth::SplitMix64;

use super::measure::{Built, build_timed, in_memory_model};
use super::plot::{Axis, COLORS, Series, chart};
use super::results::{FidelityRow as Row, Results, Setting};
use super::steps::Steps;
use crate::error::Error;

/// The settings compared for `n` materials: the paper's, the default, and
/// a step of each between them.
pub fn settings(n: usize) -> [Setting; 5] {
    let default = default_kernel(n);
    [
        Setting {
            transform: PAPER_TRANSFORM,
            kernel: PAPER_KERNEL,
            label: "the paper's (`--paper`)",
        },
        Setting {
            transform: PAPER_TRANSFORM,
            kernel: default,
            label: "`log`, the default kernel",
        },
        Setting {
            transform: DEFAULT_TRANSFORM,
            kernel: PAPER_KERNEL,
            label: "`rel-log`, the paper's kernel",
        },
        Setting {
            transform: DEFAULT_TRANSFORM,
            kernel: Kernel {
                length_scale: 0.5 * (default.length_scale + PAPER_KERNEL.length_scale),
                noise: DEFAULT_NOISE,
            },
            label: "`rel-log`, l halfway",
        },
        Setting {
            transform: DEFAULT_TRANSFORM,
            kernel: default,
            label: "the default",
        },
    ]
}

/// Random points of the default view whose materials' plausibility is measured.
const PLAUSIBILITY_POINTS: usize = 32;

/// Fit every setting on `data` (one store per transform, in `work`,
/// shared by that transform's settings) and measure it; with `quick`, the
/// paper's, `rel-log` with the paper's kernel and the default only. Gives
/// back the f32 log store, for the leave-one-out section to use.
pub fn measure(
    data: &Dataset,
    work: &Path,
    quick: bool,
    steps: &mut Steps,
    r: &mut Results,
) -> Result<Option<Built>, Error> {
    let all = settings(r.names.len());
    let chosen: Vec<Setting> = if quick {
        vec![all[0], all[2], all[4]]
    } else {
        all.to_vec()
    };
    let mut stores: Vec<(TransformKind, Built)> = Vec::new();
    for setting in chosen {
        steps.say(&format!(
            "fidelity: {} ({}, l = {}, mu = {:e})",
            setting.label,
            setting.transform.name(),
            setting.kernel.length_scale,
            setting.kernel.noise
        ))?;
        let params = GplvmParams::new(2)
            .length_scale(setting.kernel.length_scale)
            .noise(setting.kernel.noise)
            .check()?;
        // The store of a transform is built by its first setting, whose
        // fit time includes it.
        let built_time = match stores.iter().position(|(t, _)| *t == setting.transform) {
            Some(_) => Duration::ZERO,
            None => {
                let b = build_timed(data, setting.transform, Precision::F32, work)?;
                let time = b.time;
                stores.push((setting.transform, b));
                time
            }
        };
        let b = &stores
            .iter()
            .find(|(t, _)| *t == setting.transform)
            .expect("built above")
            .1;
        let t = Instant::now();
        let fit = params.fit(&b.gram, &NoProgress)?;
        let fit_time = built_time + t.elapsed();
        let name = format!("fidelity-{}", setting.transform.name());
        let m = Atlas::new(in_memory_model(
            work, &name, data, &fit, &b.store, &b.y, &b.gram,
        )?);
        let f = fidelity(
            m.store(),
            m.latent().as_ref(),
            &m.file().kernel,
            true,
            brdf_atlas_core::fidelity::JUDGED_BINS,
            &NoProgress,
        )?;
        let spacing = spacing(m.latent().as_ref());
        r.fidelity.push(Row {
            setting,
            own: f.own,
            held_out: f.held_out.unwrap_or_default(),
            spacing,
            known: known_share(&m, 41)?,
            max_albedo: max_albedo(&m)?,
            fit_time,
        });
    }
    Ok(stores
        .into_iter()
        .find(|(t, _)| *t == TransformKind::Log)
        .map(|(_, b)| b))
}

/// 90th percentile and worst of the largest directional albedo of the
/// default material at random points of the default view (seed 1).
fn max_albedo(m: &Atlas) -> Result<[f64; 2], Error> {
    let v = View::default();
    let mut rng = SplitMix64::new(1);
    let xs: Vec<[f64; 2]> = (0..PLAUSIBILITY_POINTS)
        .map(|_| [rng.range(v.x0, v.x1), rng.range(v.y0, v.y1)])
        .collect();
    // The albedo figures only (no pass over the store for the clamp's),
    // every point from one read of the directional rule's rows.
    let mut a: Vec<f64> = m
        .largest_albedos(&xs, BlendRule::Floor)?
        .into_iter()
        .map(|(a, _)| a)
        .collect();
    a.sort_by(f64::total_cmp);
    Ok([a[a.len() * 9 / 10], a[a.len() - 1]])
}

/// The section's text: the table, the materials not given back, the plot.
pub fn markdown(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    if r.fidelity.is_empty() {
        return Ok(());
    }
    writeln!(w, "## Does each marker give its material back?\n")?;
    writeln!(
        w,
        "Each setting fitted with L-BFGS, then every material judged at its own point (the \
         default rule, the soft floor) and predicted from the others (leave-one-out, closed \
         form), on every 8th phi_d bin (as `fit` judges its own points): the relative albedo error of every channel (median / \
         90th percentile / worst), the log-relative table error (RMSE of ln((v' + e) / (v + e)), \
         e = 0.001, median) and the older ln(1 + v) RMSE (median). `known`: the share of the \
         default view where the predictive variance is below 0.1; `albedo`: the largest \
         directional albedo of the default material at {PLAUSIBILITY_POINTS} random points of \
         the default view (90th percentile / worst; at most 1 for a physical material). \
         `fit`: building the transform's f32 store and Gram matrix (for the first setting \
         of each transform; the later ones share them) and the optimiser. \
         `fidelity.csv` has every material.\n"
    )?;
    writeln!(
        w,
        "| setting | own point: albedo | log-rel | left out: albedo | log-rel | ln(1 + v) | NN distance median (smallest; within 0.01) | known | albedo | fit |"
    )?;
    writeln!(w, "|{}", "---|".repeat(10))?;
    for row in &r.fidelity {
        let (own, held) = (Summary::of(&row.own), Summary::of(&row.held_out));
        let s = row.setting;
        writeln!(
            w,
            "| {} ({}, l = {}, mu = {:e}) | {} | {:.4} | {} | {:.3} | {:.4} | {:.3} ({:.4}; {}) | {:.0}% | {:.2} / {:.2} | {:.2} s |",
            s.label,
            s.transform.name(),
            s.kernel.length_scale,
            s.kernel.noise,
            spread(own.albedo),
            own.log_rel.median,
            spread(held.albedo),
            held.log_rel.median,
            held.log.median,
            row.spacing.median,
            row.spacing.smallest,
            row.spacing.close,
            100.0 * row.known,
            row.max_albedo[0],
            row.max_albedo[1],
            row.fit_time.as_secs_f64()
        )?;
    }
    writeln!(w)?;
    for row in &r.fidelity {
        let mut missed: Vec<(f64, usize)> = row
            .own
            .iter()
            .enumerate()
            .filter(|(_, j)| !j.gives_back())
            .map(|(i, j)| (j.albedo_error(), i))
            .collect();
        missed.sort_by(|a, b| b.0.total_cmp(&a.0));
        if missed.is_empty() {
            writeln!(
                w,
                "- {}: every material's point gives it back.",
                row.setting.label
            )?;
            continue;
        }
        let names: Vec<String> = missed
            .iter()
            .take(8)
            .map(|&(_, i)| format!("{} ({}x)", r.names[i], ratio(row.own[i].worst_ratio())))
            .collect();
        writeln!(
            w,
            "- {}: {} of {} materials not given back (albedo more than 5% off), worst first: {}{}.",
            row.setting.label,
            missed.len(),
            row.own.len(),
            names.join(", "),
            if missed.len() > 8 { ", ..." } else { "" }
        )?;
    }
    writeln!(
        w,
        "\n![Own-point albedo error of every material by setting](fidelity.png)\n"
    )
}

/// `median / p90 / worst` as percentages.
fn spread(s: brdf_atlas_core::fidelity::Spread) -> String {
    format!(
        "{:.2}% / {:.2}% / {:.1}%",
        100.0 * s.median,
        100.0 * s.p90,
        100.0 * s.worst
    )
}

fn ratio(r: f64) -> String {
    if r >= 10.0 {
        format!("{r:.0}")
    } else {
        format!("{r:.2}")
    }
}

/// `fidelity.csv`: every material under every setting.
pub fn csv(dir: &Path, r: &Results) -> Result<(), Error> {
    if r.fidelity.is_empty() {
        return Ok(());
    }
    super::write_file(&dir.join("fidelity.csv"), |f| {
        writeln!(
            f,
            "transform,length_scale,noise,material,prediction,albedo_r,albedo_g,albedo_b,predicted_r,predicted_g,predicted_b,largest_relative_error,log_rel_rmse,log_rmse"
        )?;
        for row in &r.fidelity {
            let s = row.setting;
            for (what, judged) in [("own", &row.own), ("left-out", &row.held_out)] {
                for (name, j) in r.names.iter().zip(judged.iter()) {
                    writeln!(
                        f,
                        "{},{},{:e},{name},{what},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                        s.transform.name(),
                        s.kernel.length_scale,
                        s.kernel.noise,
                        j.albedo[0],
                        j.albedo[1],
                        j.albedo[2],
                        j.predicted[0],
                        j.predicted[1],
                        j.predicted[2],
                        j.albedo_error(),
                        j.log_rel,
                        j.log
                    )?;
                }
            }
        }
        Ok(())
    })
}

/// `fidelity.png`: each material's own-point albedo error (largest
/// channel), sorted, one line per setting, on a log axis.
pub fn picture(dir: &Path, r: &Results) -> Result<(), Error> {
    if r.fidelity.is_empty() {
        return Ok(());
    }
    let series: Vec<Series> = r
        .fidelity
        .iter()
        .enumerate()
        .map(|(k, row)| {
            let mut e: Vec<f64> = row.own.iter().map(|j| j.albedo_error().max(1e-6)).collect();
            e.sort_by(f64::total_cmp);
            Series {
                name: row.setting.label.replace('`', ""),
                color: COLORS[k % COLORS.len()],
                points: e
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| ((i + 1) as f64, v.log10()))
                    .collect(),
                markers_only: false,
            }
        })
        .collect();
    chart(
        &dir.join("fidelity.png"),
        "Each material at its own point: albedo error, largest channel (5% and above: not given back)",
        Axis {
            label: "materials, sorted by error",
            log: false,
            integer: true,
        },
        Axis {
            label: "relative albedo error",
            log: true,
            integer: false,
        },
        &series,
    )
}
