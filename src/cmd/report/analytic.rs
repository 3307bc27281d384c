//! The analytic fits of the database's materials (`brdf-atlas export`'s
//! fit of each MERL file), against the two baselines measured the same
//! way: how much of each material's rendered light the glTF material gets
//! wrong, the distribution over materials, and the worst named.

use std::io::{self, Write};
use std::path::Path;

use brdf_atlas_core::Dataset;
use brdf_atlas_pictures::sphere::DEFAULT_LIGHTS;
use rayon::prelude::*;

use super::results::{AnalyticRow, Results};
use super::steps::Steps;
use super::write_file;
use crate::cmd::export::SPHERE;
use crate::cmd::export::compare::compare;
use crate::error::Error;
use crate::format::secs;

/// Side of the spheres with `--quick`: smaller than the default, but not
/// the fit's own 48-pixel picture.
const QUICK_SPHERE: usize = 64;
/// Materials named as the worst.
const WORST: usize = 8;
/// Materials fitted with `--quick`, spread evenly over the database (each
/// fit takes about a second; the default report fits every one).
const QUICK_MATERIALS: usize = 4;

/// Fit every material of `data` (in parallel, each fit on one thread).
pub fn measure(
    data: &Dataset,
    quick: bool,
    steps: &mut Steps,
    r: &mut Results,
) -> Result<(), Error> {
    let size = if quick { QUICK_SPHERE } else { SPHERE };
    let step = if quick {
        data.len().div_ceil(QUICK_MATERIALS).max(1)
    } else {
        1
    };
    let picked: Vec<usize> = (0..data.len()).step_by(step).collect();
    steps.say(&format!(
        "analytic fits: {} of {} materials, spheres of {size} px",
        picked.len(),
        data.len()
    ))?;
    r.analytic_of = data.len();
    let rows: Vec<Result<AnalyticRow, Error>> = picked
        .into_par_iter()
        .map(|k| {
            let table = data.files[k].to_table();
            let c = compare(&table, &data.names[k], size, &DEFAULT_LIGHTS)?;
            Ok(AnalyticRow {
                name: data.names[k].clone(),
                rendered: [
                    c.rendered.principled,
                    c.rendered.single_lobe,
                    c.rendered.lambertian,
                    c.rendered.held_out,
                ],
                table: [
                    c.fits.principled.error,
                    c.fits.single_lobe.error,
                    c.fits.lambertian.error,
                ],
                time: c.fit_time,
                sphere: size,
            })
        })
        .collect();
    r.analytic = rows.into_iter().collect::<Result<_, _>>()?;
    Ok(())
}

/// `analytic.csv`: one row a material.
pub fn csv(dir: &Path, r: &Results) -> Result<(), Error> {
    write_file(&dir.join("analytic.csv"), |w| {
        writeln!(
            w,
            "material,rendered_gltf,rendered_single_lobe,rendered_lambertian,rendered_gltf_held_out_lights,table_gltf,table_single_lobe,table_lambertian,fit_seconds"
        )?;
        for a in &r.analytic {
            writeln!(
                w,
                "{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.3}",
                a.name,
                a.rendered[0],
                a.rendered[1],
                a.rendered[2],
                a.rendered[3],
                a.table[0],
                a.table[1],
                a.table[2],
                a.time.as_secs_f64()
            )?;
        }
        Ok(())
    })
}

/// `2nd`, `3rd`, `4th`, ... (steps below 20).
fn ordinal(k: usize) -> String {
    let suffix = match k {
        2 => "nd",
        3 => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// The `q`-quantile of `v` (nearest rank).
fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(
        ((q * s.len() as f64).ceil() as usize)
            .saturating_sub(1)
            .min(s.len().saturating_sub(1)),
    )
    .copied()
    .unwrap_or(f64::NAN)
}

/// The analytic section of `report.md`.
pub fn markdown(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    let a = &r.analytic;
    if a.is_empty() {
        return Ok(());
    }
    writeln!(w, "## Analytic fits: the materials as glTF\n")?;
    writeln!(
        w,
        "Each material fitted as `brdf-atlas export` fits it: glTF 2.0 metallic-roughness with \
         KHR_materials_specular and KHR_materials_ior, in the cosine-weighted log-relative table \
         error over a subsample of bins plus the radiance of a 48-pixel sphere under the swatch \
         lights. Rendered error: sum |L_fit - L| / sum L over a lit sphere's pixels ({size} \
         across; linear radiance, the swatch renderer's default lights); held out: the same under two lights the \
         fit never sees. Baselines measured the same way: the Lambertian of the material's albedo \
         (not fitted) and one GGX lobe over a Lambertian base (fitted like the glTF model). \
         Table: `analytic.csv`.\n",
        size = a[0].sphere
    )?;
    if a.len() < r.analytic_of {
        writeln!(
            w,
            "This quick report fits {} of the {} materials (every {} by name); the default \
             report fits every one.\n",
            a.len(),
            r.analytic_of,
            ordinal(r.analytic_of.div_ceil(a.len()))
        )?;
    }
    writeln!(
        w,
        "| model | median | 90th percentile | worst | median table error |"
    )?;
    writeln!(w, "|---|---|---|---|---|")?;
    let col = |k: usize| a.iter().map(|x| x.rendered[k]).collect::<Vec<_>>();
    let tcol = |k: usize| a.iter().map(|x| x.table[k]).collect::<Vec<_>>();
    for (k, name) in [
        (0, "glTF fit"),
        (3, "glTF fit, held-out lights"),
        (1, "one GGX lobe + Lambertian"),
        (2, "Lambertian of the albedo"),
    ] {
        let v = col(k);
        let table = if k == 3 {
            String::new()
        } else {
            format!("{:.3}", quantile(&tcol([0, 1, 2, 0][k]), 0.5))
        };
        writeln!(
            w,
            "| {name} | {:.1}% | {:.1}% | {:.1}% | {table} |",
            100.0 * quantile(&v, 0.5),
            100.0 * quantile(&v, 0.9),
            100.0 * quantile(&v, 1.0),
        )?;
    }
    let beats = |k: usize| a.iter().filter(|x| x.rendered[0] < x.rendered[k]).count();
    let times: Vec<f64> = a.iter().map(|x| x.time.as_secs_f64()).collect();
    writeln!(
        w,
        "\nThe glTF fit renders closer than the Lambertian for {} of {n} materials and than the \
         single lobe for {} of {n}. Fit time per material (both models, {} fits in parallel): \
         median {}, worst {}.\n",
        beats(2),
        beats(1),
        rayon::current_num_threads(),
        secs(std::time::Duration::from_secs_f64(quantile(&times, 0.5))),
        secs(std::time::Duration::from_secs_f64(quantile(&times, 1.0))),
        n = a.len(),
    )?;
    let mut worst: Vec<&AnalyticRow> = a.iter().collect();
    worst.sort_by(|x, y| {
        y.rendered[0]
            .total_cmp(&x.rendered[0])
            .then(x.name.cmp(&y.name))
    });
    writeln!(w, "Worst fits:\n")?;
    writeln!(
        w,
        "| material | glTF | held-out lights | single lobe | Lambertian |"
    )?;
    writeln!(w, "|---|---|---|---|---|")?;
    for x in worst.iter().take(WORST) {
        writeln!(
            w,
            "| {} | {:.1}% | {:.1}% | {:.1}% | {:.1}% |",
            x.name,
            100.0 * x.rendered[0],
            100.0 * x.rendered[3],
            100.0 * x.rendered[1],
            100.0 * x.rendered[2]
        )?;
    }
    writeln!(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_nearest_rank() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert_eq!(quantile(&v, 1.0), 5.0);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
