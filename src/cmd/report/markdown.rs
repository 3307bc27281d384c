//! The report's `report.md`: what was measured, how, and the tables, with
//! links to the plots and the CSV files.

use std::fmt::Display;
use std::io::{self, Write};
use std::time::Duration;

use brdf_atlas_core::{DEFAULT_SAMPLES, TransformKind};

use super::Args;
use super::plan::Plan;
use super::results::Results;
use crate::format::{coordinates, g4, pct, secs, size};
use crate::machine;

/// Write the whole report: `total` is the run's wall time, `load` the load
/// average at its start and end.
pub fn write(
    w: &mut dyn Write,
    args: &Args,
    plan: &Plan,
    r: &Results,
    total: Duration,
    load: [&str; 2],
) -> io::Result<()> {
    let n = r.names.len();
    let [load_start, load_end] = load;
    writeln!(w, "# brdf-atlas report: what accuracy costs\n")?;
    writeln!(
        w,
        "Data: {n} materials ({}, d = {} values each) from `{}`. Measured on {} by \
         brdf-atlas {}{}, in {} in all.\n",
        r.dims,
        r.d,
        args.dir.display(),
        machine::today(),
        env!("CARGO_PKG_VERSION"),
        if args.quick { " with `--quick`" } else { "" },
        secs(total)
    )?;
    writeln!(
        w,
        "Machine: {} ({} hardware threads available), {} rayon threads; load average \
         {load_start} at the start, {load_end} at the end. The machine may be shared: times \
         are wall times of single runs{}, \
         upper bounds rather than best cases. Files were read through the page cache.\n",
        machine::cpu_model(),
        std::thread::available_parallelism().map_or(0, |p| p.get()),
        rayon::current_num_threads(),
        if plan.repeat {
            format!(
                " (the median of three when a run takes under {})",
                secs(super::plan::REPEAT_BELOW)
            )
        } else {
            String::new()
        }
    )?;
    writeln!(
        w,
        "Opening and validating the {n} files took {}. Files here: `loo.csv`, `loo-materials.csv`, `fits.csv`, `stores.csv`, \
         `precision.csv`, `map-samples.csv`, `map-rules.csv`, `map-size.csv`, `plausibility.csv`, `fidelity.csv`, and the plots below.\n",
        secs(r.scan.wall)
    )?;
    super::fidelity::markdown(w, r)?;
    leave_one_out(w, plan, r)?;
    fits(w, r)?;
    maps(w, plan, r)?;
    super::plausible::markdown(w, r, plan)?;
    precision(w, r)?;
    super::growth::markdown(w, r)?;
    super::analytic::markdown(w, r)?;
    times(w, r, total)
}

/// How long each section took, in the order run.
fn times(w: &mut dyn Write, r: &Results, total: Duration) -> io::Result<()> {
    writeln!(w, "\n## Time by section\n")?;
    writeln!(
        w,
        "Wall time of each part of this run, in the order run (the rest of the {} in \
         all: writing this file and moving the report into place), and the CPU time it \
         used (user + system, every thread; on a shared machine the wall time grows with \
         the load, the CPU time much less).\n",
        secs(total)
    )?;
    head(w, &["section", "wall", "CPU"])?;
    let scan = ("Opening and validating the files".to_string(), r.scan);
    for (name, time) in std::iter::once(&scan).chain(&r.times) {
        let cpu = time.cpu.map_or_else(|| "unknown".to_string(), secs);
        row(w, &[name, &secs(time.wall), &cpu])?;
    }
    Ok(())
}

/// Leave-one-out errors of the GPLVM and PCA by latent dimension.
fn leave_one_out(w: &mut dyn Write, plan: &Plan, r: &Results) -> io::Result<()> {
    let n = r.names.len();
    writeln!(w, "## Leave-one-out reconstruction error\n")?;
    writeln!(
        w,
        "![Leave-one-out error vs latent dimension](loo.png)\n\n\
         Each material is predicted from the other {} and compared with itself. \
         **GPLVM**: the model's prediction at the held-out material's latent point, \
         `z_i - (K^-1 Z)_i / (K^-1)_ii` in closed form, with the mean material also \
         re-estimated without it (closed form too); the latent points and \
         hyperparameters are those fitted on all {n} materials (no refit), so the \
         held-out material still shaped where it sits. Fits by {} (L-BFGS is \
         `fit`'s default; Hooke-Jeeves runs with minimum step 1e-3), and at q = 2 \
         by {} too. **PCA held out**: the \
         material projected on the top q principal directions of the other {} \
         materials, centred by their own mean (a proper leave-one-out, one \
         eigen-decomposition of their Gram matrix per material). **PCA in sample** \
         (transformed space only): the residual when every material is projected on \
         the directions of all {n}, itself included, from the discarded eigenvalues \
         of `Z Z^T`; it is not a held-out error, and is the best any q-component linear model can do on these materials (the GPLVM is not linear and can beat it).\n",
        n - 1,
        plan.optimizer.name(),
        plan.other_optimizer().name(),
        n - 1
    )?;
    writeln!(
        w,
        "Metrics, over all materials and the {} of {} table values that some input \
         measured and that are not grazing (`cos_i cos_o >= 1e-6`){}: **reflectance \
         RMSE** in 1/sr (the prediction inverted from the model's transform per value \
         and clamped to >= 0, as `reconstruct` writes it; highlights dominate it) and \
         **cosine-weighted log RMSE**, the RMSE of `log(1 + f cos_i cos_o)` \
         (Sztrajman et al. 2021). The reference values are the materials as stored \
         (f32, unmeasured samples read as 0). The transformed-space RMSE is over all \
         values{}.\n",
        r.scored_rows,
        r.d,
        if plan.eighth {
            ", on every 8th phi_d bin (`--quick`), where the plausible rule's held-out steps judge their clamp budgets too"
        } else {
            ""
        },
        if plan.eighth { " of those bins" } else { "" }
    )?;
    head(
        w,
        &[
            "q",
            "transform",
            "GPLVM refl.",
            "GPLVM log",
            "PCA held out refl.",
            "PCA held out log",
            "GPLVM transformed",
            "PCA held out transformed",
            "PCA in sample transformed",
        ],
    )?;
    for q in 1..=plan.q_max {
        for t in [TransformKind::Log, TransformKind::Raw] {
            if let (Some(g), Some(p)) = (r.loo_row(t, "gplvm", q), r.loo_row(t, "pca", q)) {
                row(
                    w,
                    &[
                        &q,
                        &t.name(),
                        &g4(g.raw),
                        &g4(g.log),
                        &g4(p.raw),
                        &g4(p.log),
                        &g4(g.transformed),
                        &g4(p.transformed),
                        &p.in_sample.map_or("-".into(), g4),
                    ],
                )?;
            }
        }
    }
    for t in [TransformKind::Log, TransformKind::Raw] {
        if let Some(l) = r.loo_row(t, "gplvm-other", 2) {
            writeln!(
                w,
                "\nGPLVM q = 2 fitted by {} instead ({} transform): reflectance RMSE {}, log RMSE {}.",
                plan.other_optimizer().name(),
                t.name(),
                g4(l.raw),
                g4(l.log)
            )?;
        }
    }
    writeln!(w, "\n![Reflectance RMSE](loo-reflectance.png)\n")?;
    for (t, count, time) in &r.loo_times {
        writeln!(
            w,
            "The {} transform's leave-one-out pass: {count} predictors in {} (one streaming \
             pass over the store, all predictors at once).",
            t.name(),
            secs(*time)
        )?;
    }
    worst_materials(w, plan, r)
}

/// The five worst materials at the default settings (log transform, q = 2).
fn worst_materials(w: &mut dyn Write, plan: &Plan, r: &Results) -> io::Result<()> {
    let n = r.names.len();
    if let Some(l) = r.loo_row(TransformKind::Log, "gplvm", 2.min(plan.q_max)) {
        writeln!(
            w,
            "\n### Worst materials (GPLVM, log transform, q = {})\n",
            l.q
        )?;
        head(
            w,
            &[
                "by log RMSE",
                "log RMSE",
                "by reflectance RMSE",
                "refl. RMSE",
            ],
        )?;
        let mut by_log: Vec<usize> = (0..n).collect();
        by_log.sort_by(|&a, &b| l.materials[b].1.total_cmp(&l.materials[a].1));
        let mut by_raw: Vec<usize> = (0..n).collect();
        by_raw.sort_by(|&a, &b| l.materials[b].0.total_cmp(&l.materials[a].0));
        for k in 0..5.min(n) {
            row(
                w,
                &[
                    &r.names[by_log[k]],
                    &g4(l.materials[by_log[k]].1),
                    &r.names[by_raw[k]],
                    &g4(l.materials[by_raw[k]].0),
                ],
            )?;
        }
        writeln!(w, "\nEvery material and method: `loo-materials.csv`.")?;
    }
    Ok(())
}

/// The optimisers compared, and Hooke-Jeeves' minimum step sweep.
fn fits(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    writeln!(w, "\n## Fitting: Hooke-Jeeves vs L-BFGS\n")?;
    writeln!(
        w,
        "Times are the optimiser alone (PCA start included), from the Gram matrix \
         each transform's store pass built once; the cost is the negative log \
         likelihood of the normalised data (lower is better).\n"
    )?;
    head(
        w,
        &[
            "transform",
            "q",
            "optimiser",
            "time",
            "start cost",
            "final cost",
            "evaluations",
        ],
    )?;
    for f in &r.fits {
        row(
            w,
            &[
                &f.transform.name(),
                &f.q,
                &f.optimizer.name(),
                &secs(f.time),
                &g4(f.initial_cost),
                &g4(f.cost),
                &f.evaluations,
            ],
        )?;
    }
    if !r.sweep.is_empty() {
        writeln!(
            w,
            "\n![Cost reached vs time](optimizers.png)\n\nHooke-Jeeves' minimum step \
             (log transform, q = 2; the default is 1e-3):\n"
        )?;
        head(w, &["min step", "time", "final cost", "evaluations"])?;
        for f in &r.sweep {
            let min_step = format!("{:e}", f.min_step);
            row(w, &[&min_step, &secs(f.time), &g4(f.cost), &f.evaluations])?;
        }
    }
    Ok(())
}

/// The albedo map's error and time by sample count, and time by size.
fn maps(w: &mut dyn Write, plan: &Plan, r: &Results) -> io::Result<()> {
    if !r.samples.is_empty() {
        writeln!(w, "\n## Albedo map (log transform, q = 2)\n")?;
        writeln!(
            w,
            "![Map error and time vs quadrature samples](map-samples.png)\n\n\
             Error: at {} pixels of a small map, the per-pixel quadrature albedo against \
             the dense rule (every bin, 8 sub-cells) applied to the full reconstruction \
             at the same latent point ({} for the references, all of them from one pass over \
             the store), relative to the \
             reference's largest channel. Time: one {}x{} map.\n",
            r.reference_pixels,
            secs(r.reference_time),
            plan.timed_size,
            plan.timed_size
        )?;
        head(
            w,
            &["samples", "bins read", "max error", "mean error", "time"],
        )?;
        for m in &r.samples {
            let default = if m.samples == DEFAULT_SAMPLES {
                " (default)"
            } else {
                ""
            };
            let samples = format!("{}{default}", m.samples);
            let (max, mean) = (pct(m.max_err), pct(m.mean_err));
            row(w, &[&samples, &m.bins, &max, &mean, &secs(m.time)])?;
        }
        rules(w, r)?;
        methods(w, r)?;
        writeln!(w, "\n![Map time vs size](map-size.png)\n")?;
        head(w, &["size", "method", "time"])?;
        for m in &r.sizes {
            let size = format!("{0}x{0}", m.size);
            row(w, &[&size, &m.method, &secs(m.time)])?;
        }
    }
    Ok(())
}

/// The exact-albedo rules against the dense rule.
fn rules(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    if r.rules.is_empty() {
        return Ok(());
    }
    writeln!(
        w,
        "\nWhat the exact albedo of a point costs by quadrature rule (what a map's node, a \
         lattice node or a reconstruction's albedo pays): the default material's albedo at {} \
         random points of the default view, all of them from one pass over the rule's rows of \
         the store, against the dense rule's, relative to the reference's largest channel. \
         Time: the pass divided by the points. The reconstructed table has kinks (the clamp \
         at 0, the soft floor's largest material), so interpolants of higher order gain \
         little for the rows they read. The rules that read one bin for each box of bins \
         (the per-pixel rule, the sampled field's nodes) read the fewest rows of all but \
         Monte Carlo's, and their error is what a map drawn with them cannot do better than. \
         `map-rules.csv` has the figures.\n",
        r.rule_points
    )?;
    head(
        w,
        &[
            "rule",
            "bins read",
            "max error",
            "mean error",
            "time a point",
        ],
    )?;
    for m in &r.rules {
        let (max, mean) = (pct(m.max_err), pct(m.mean_err));
        row(w, &[&m.rule, &m.bins, &max, &mean, &secs(m.per_point)])?;
    }
    Ok(())
}

/// The default map method (the albedo field, or the sampled field where an
/// exact one is over budget) against the per-pixel rule,
/// and whether the map can be drawn in real time.
fn methods(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    if r.methods.is_empty() {
        return Ok(());
    }
    let n = r.methods_size;
    writeln!(
        w,
        "\nThe default method and the prepared map against the per-pixel rule: error at {} \
         random pixels of a {n}x{n} map of the default view and of a view a hundred times \
         smaller, against the dense rule on the full reconstruction; time of the first map \
         of the view and of the next (the model keeps a field it built; the prepared map's \
         first includes preparing its lattice).\n",
        r.reference_pixels
    )?;
    head(
        w,
        &[
            "view",
            "method",
            "max error",
            "mean error",
            "first map",
            "next map",
        ],
    )?;
    for m in &r.methods {
        let (max, mean) = (pct(m.max_err), pct(m.mean_err));
        row(
            w,
            &[
                &m.view,
                &m.method,
                &max,
                &mean,
                &secs(m.first),
                &secs(m.again),
            ],
        )?;
    }
    let find = |view: &str, field: bool| {
        r.methods
            .iter()
            .find(|m| m.view == view && m.field == field)
    };
    let pixel = |view: &str| {
        r.methods
            .iter()
            .find(|m| m.view == view && !m.field && !m.prepared && !m.method.starts_with("default"))
    };
    let sampled = |view: &str| r.methods.iter().find(|m| m.view == view && m.sampled);
    let prepared = |view: &str| r.methods.iter().find(|m| m.view == view && m.prepared);
    write!(w, "\n**Can the map be drawn in real time?** ")?;
    if let (Some(d), Some(z), Some(p)) = (prepared("default"), prepared("1/100"), pixel("default"))
    {
        return writeln!(
            w,
            "Yes, once the model's map is prepared (`brdf-atlas prepare`: {} once): a {n}x{n} \
             map of the default view then takes {}, within {} of the dense rule at the worst \
             pixel (the per-pixel rule: {}, {} off), and of a view a hundred times smaller {}, \
             within {}.",
            secs(d.first - d.again),
            secs(d.again),
            pct(d.max_err),
            secs(p.first),
            pct(p.max_err),
            secs(z.again),
            pct(z.max_err)
        );
    }
    let (Some(f), Some(p)) = (find("1/100", true), pixel("default")) else {
        return writeln!(w, "not measured with a field here (see the table).");
    };
    write!(
        w,
        "Zoomed in, yes once its field is built: a {n}x{n} map of a view a hundred times \
         smaller takes {} the first time and {} after, within {} of the dense rule \
         (the per-pixel rule: {}, {} off)",
        secs(f.first),
        secs(f.again),
        pct(f.max_err),
        secs(pixel("1/100").map_or(p.first, |q| q.first)),
        pct(pixel("1/100").map_or(p.max_err, |q| q.max_err)),
    )?;
    match sampled("default") {
        Some(s) => writeln!(
            w,
            ". The whole default view, approximately: its albedo has more detail than an \
             exact field within budget resolves, so it is drawn from a sampled field \
             (albedos integrated from a sampled rule at its nodes) in {} the first time and \
             {} after, up to {} off ({} on average), where integrating every pixel takes {}, \
             up to {} off; within 0.1% it needs the model's map prepared (`brdf-atlas \
             prepare`; `report --prepare` or `--thorough` measures it here).",
            secs(s.first),
            secs(s.again),
            pct(s.max_err),
            pct(s.mean_err),
            secs(p.first),
            pct(p.max_err)
        ),
        None => writeln!(
            w,
            "; the whole default view is not: its albedo has more detail than a field within \
             budget resolves, so it is integrated per pixel in {}, up to {} off, until the \
             model's map is prepared (`brdf-atlas prepare`; `report --prepare` or \
             `--thorough` measures it here).",
            secs(p.first),
            pct(p.max_err)
        ),
    }
}

/// The f32 and the f64 store compared.
fn precision(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    writeln!(w, "\n## Store precision: f32 vs f64\n")?;
    head(
        w,
        &[
            "transform",
            "precision",
            "store build (pass + Gram)",
            "size",
        ],
    )?;
    for st in &r.stores {
        let (transform, precision) = (st.transform.name(), st.precision.name());
        row(
            w,
            &[&transform, &precision, &secs(st.time), &size(st.bytes)],
        )?;
    }
    writeln!(
        w,
        "\nThe store is memory-mapped: its size is the memory a reconstruction or map \
         touches. Gram matrix from the f32 store vs the f64 store: largest difference \
         {} of its largest entry.\n",
        g4(r.gram_rel_diff)
    )?;
    if !r.precision.is_empty() {
        writeln!(
            w,
            "Full reconstructions (log transform, q = 2) at the same latent points and \
             weights from the f32 and the f64 store, in reflectance (1/sr):\n"
        )?;
        head(
            w,
            &[
                "latent point",
                "max difference",
                "max / peak value",
                "RMS difference",
                "time f32",
                "time f64",
            ],
        )?;
        for p in &r.precision {
            let point = format!("({})", coordinates(&p.point, 3));
            let (max, rel, rms) = (g4(p.max_abs), g4(p.max_rel), g4(p.rms));
            let times = (secs(p.time32), secs(p.time64));
            row(w, &[&point, &max, &rel, &rms, &times.0, &times.1])?;
        }
    }
    Ok(())
}

/// The header row of a markdown table and the rule under it.
fn head(w: &mut dyn Write, columns: &[&str]) -> io::Result<()> {
    let cells: Vec<&dyn Display> = columns.iter().map(|c| c as &dyn Display).collect();
    row(w, &cells)?;
    writeln!(w, "|{}", "---|".repeat(columns.len()))
}

/// One row of a markdown table.
fn row(w: &mut dyn Write, cells: &[&dyn Display]) -> io::Result<()> {
    write!(w, "|")?;
    for cell in cells {
        write!(w, " {cell} |")?;
    }
    writeln!(w)
}
