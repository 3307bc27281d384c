//! Whether a cheap rule's error at a latent point follows the materials
//! nearby: the 1024-sample per-pixel rule's albedo at random points of the
//! default view, corrected by the kernel-weighted average of its error at
//! the materials' own points (absolute or relative), against the dense
//! rule. `cargo run --release -p brdf-atlas-core --example material_bias
//! -- MODEL [POINTS] [SAMPLES]`.

use brdf_atlas_core::map_error::albedo_error;
use brdf_atlas_core::{AlbedoRequest, Atlas, Integration, Model, View};
use brdf_merl::Quadrature;
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: material_bias MODEL [POINTS] [SAMPLES]")?;
    let count: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let samples: usize = args.next().map_or(Ok(1024), |s| s.parse())?;
    let atlas = Atlas::new(Model::open(&path)?);
    let rule = Quadrature::with_samples_shaped(atlas.albedo_rule(), samples, atlas.shape());
    let cheap = AlbedoRequest::new().integration(Integration::Rule(&rule));
    let latent = atlas.latent();
    let n = latent.nrows();
    let own: Vec<[f64; 2]> = (0..n).map(|i| [latent[(i, 0)], latent[(i, 1)]]).collect();
    let own_dense = atlas.exact_albedos(&own, AlbedoRequest::new())?;
    let own_cheap = atlas.exact_albedos(&own, cheap)?;
    let kernel = atlas.file().kernel;
    for (name, view) in [("default", View::default()), ("[-3,3]^2", View::wide())] {
        let mut rng = SplitMix64::new(7);
        let pts: Vec<[f64; 2]> = (0..count)
            .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
            .collect();
        let dense = atlas.exact_albedos(&pts, AlbedoRequest::new())?;
        let got = atlas.exact_albedos(&pts, cheap)?;
        for scale in [1.0, 0.5, 0.25] {
            let k = brdf_atlas_core::Kernel {
                length_scale: kernel.length_scale * scale,
                ..kernel
            };
            let (mut abs, mut rel) = (Vec::new(), Vec::new());
            for (p, g) in pts.iter().zip(&got) {
                let w: Vec<f64> = own.iter().map(|o| k.eval(p, o)).collect();
                let s: f64 = w.iter().sum::<f64>().max(1e-300);
                let mut a = *g;
                let mut r = *g;
                for c in 0..3 {
                    let mut ba = 0.0;
                    let mut br = 0.0;
                    for i in 0..n {
                        ba += w[i] / s * (own_cheap[i][c] - own_dense[i][c]);
                        br += w[i] / s * (own_cheap[i][c] / own_dense[i][c].max(1e-12));
                    }
                    a[c] -= ba;
                    r[c] /= br.max(1e-12);
                }
                abs.push(a);
                rel.push(r);
            }
            let (w0, m0) = albedo_error(&got, &dense);
            let (w1, m1) = albedo_error(&abs, &dense);
            let (w2, m2) = albedo_error(&rel, &dense);
            println!(
                "{name:9} l x {scale:4}: rule {w0:.2e} / {m0:.2e}, corrected abs {w1:.2e} / {m1:.2e}, rel {w2:.2e} / {m2:.2e}"
            );
        }
    }
    Ok(())
}
