//! A synthetic material database from analytic BRDFs, in the MERL layout.
//!
//! Each material is a Lambertian base plus a GGX microfacet lobe with Smith
//! shadowing and Schlick's Fresnel; metals have no diffuse part and a
//! coloured `F0`, dielectrics a coloured base and `F0 = 0.04`. Parameters
//! come from a seeded generator, so a seed and a count always give the same
//! database. This is the embedded default that `brdf-atlas demo` runs on.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::angles::{Dims, HalfDiff, Vec3};
use crate::error::Result;
use crate::table::{INVALID, MerlTable, raw_from_physical, write_named};

/// An analytic isotropic BRDF: Lambert + GGX microfacet with Fresnel.
#[derive(Debug, Clone, PartialEq)]
pub struct Analytic {
    /// Lambertian albedo per channel (0 for metals).
    pub diffuse: [f64; 3],
    /// Fresnel reflectance at normal incidence per channel.
    pub f0: [f64; 3],
    /// GGX roughness alpha (> 0).
    pub alpha: f64,
}

impl Analytic {
    /// Reflectance at half/difference angles (1/sr). Zero below the horizon.
    pub fn eval_half_diff(&self, hd: &HalfDiff) -> [f64; 3] {
        let (ci, co) = hd.cosines();
        if ci <= 0.0 || co <= 0.0 {
            return [0.0; 3];
        }
        let a2 = self.alpha * self.alpha;
        let ch = hd.theta_h.cos();
        let t = ch * ch * (a2 - 1.0) + 1.0;
        let d = a2 / (PI * t * t);
        let g1 = |c: f64| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
        let g = g1(ci) * g1(co);
        let m = (1.0 - hd.theta_d.cos()).clamp(0.0, 1.0);
        let schlick = m * m * m * m * m;
        let spec = d * g / (4.0 * ci * co);
        [0, 1, 2].map(|c| {
            let f = self.f0[c] + (1.0 - self.f0[c]) * schlick;
            self.diffuse[c] / PI + f * spec
        })
    }

    /// Reflectance at a pair of directions (1/sr). Zero below the horizon.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> [f64; 3] {
        match HalfDiff::from_directions(wi, wo) {
            Some(hd) => self.eval_half_diff(&hd),
            None => [0.0; 3],
        }
    }

    /// Tabulate on a MERL grid: each bin holds the value at the centre of
    /// its cell; bins whose representative directions (the cell's lower
    /// corner, as in the measured data) fall at or below the horizon get
    /// MERL's invalid marker.
    pub fn table(&self, dims: Dims) -> MerlTable {
        let n = dims.bins();
        let mut values = vec![0.0; dims.values()];
        let (r, rest) = values.split_at_mut(n);
        let (g, b) = rest.split_at_mut(n);
        (r, g, b).into_par_iter_bins(n, |bin| {
            let hd = dims.angles_of(bin);
            let (ci, co) = hd.cosines();
            if ci <= 0.0 || co <= 0.0 {
                [INVALID; 3]
            } else {
                // The value at the centre of the bin's cell: the lower corner
                // alone overestimates a sharp specular peak, enough to push a
                // mirror-like metal's albedo above 1.
                let (ih, id, ip) = dims.unbin(bin);
                let u = (ih as f64 + 0.5) / dims.theta_h as f64;
                let centre = HalfDiff {
                    theta_h: u * u * std::f64::consts::FRAC_PI_2,
                    phi_h: 0.0,
                    theta_d: (id as f64 + 0.5) / dims.theta_d as f64 * std::f64::consts::FRAC_PI_2,
                    phi_d: (ip as f64 + 0.5) / dims.phi_d as f64 * PI,
                };
                let v = self.eval_half_diff(&centre);
                [0, 1, 2].map(|c| raw_from_physical(c, v[c]))
            }
        });
        MerlTable::from_raw(dims, values).expect("length matches dims")
    }
}

/// Fill three channel planes in parallel from a per-bin function.
trait ParBins {
    fn into_par_iter_bins(self, n: usize, f: impl Fn(usize) -> [f64; 3] + Sync);
}

impl ParBins for (&mut [f64], &mut [f64], &mut [f64]) {
    fn into_par_iter_bins(self, n: usize, f: impl Fn(usize) -> [f64; 3] + Sync) {
        const CHUNK: usize = 4096;
        let (r, g, b) = self;
        r.par_chunks_mut(CHUNK)
            .zip(g.par_chunks_mut(CHUNK))
            .zip(b.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, ((r, g), b))| {
                for i in 0..r.len() {
                    let bin = k * CHUNK + i;
                    debug_assert!(bin < n);
                    let v = f(bin);
                    (r[i], g[i], b[i]) = (v[0], v[1], v[2]);
                }
            });
    }
}

/// One material of the synthetic database: a name and its BRDF.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthMaterial {
    /// File stem, unique within a database: `NNN-kind-colour-rX.XX`.
    pub name: String,
    /// The analytic BRDF.
    pub brdf: Analytic,
}

/// SplitMix64: a tiny, well-mixed, seedable generator (Steele et al. 2014).
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

const METALS: [(&str, [f64; 3]); 6] = [
    ("gold", [1.0, 0.78, 0.34]),
    ("copper", [0.95, 0.64, 0.54]),
    ("silver", [0.97, 0.96, 0.91]),
    ("aluminium", [0.91, 0.92, 0.92]),
    ("brass", [0.91, 0.78, 0.42]),
    ("chrome", [0.55, 0.56, 0.55]),
];

const PAINTS: [(&str, [f64; 3]); 8] = [
    ("red", [0.6, 0.05, 0.04]),
    ("green", [0.08, 0.45, 0.1]),
    ("blue", [0.05, 0.12, 0.6]),
    ("white", [0.8, 0.8, 0.78]),
    ("black", [0.02, 0.02, 0.02]),
    ("yellow", [0.75, 0.6, 0.05]),
    ("orange", [0.8, 0.3, 0.05]),
    ("violet", [0.35, 0.1, 0.5]),
];

/// The `count` materials of the database with this `seed`. The first
/// material of the set is a metal, the second a dielectric, and so on
/// alternating; colours and roughness vary with the seed.
pub fn database(count: usize, seed: u64) -> Vec<SynthMaterial> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|i| {
            let jitter = |rng: &mut SplitMix64, c: [f64; 3]| {
                c.map(|v| (v * rng.range(0.85, 1.15)).clamp(0.0, 1.0))
            };
            // Roughness spread log-uniformly from mirror-like to very rough.
            let alpha = (rng.range(0.03f64.ln(), 0.7f64.ln())).exp();
            let metal = i % 2 == 0;
            let (kind, colour, brdf) = if metal {
                let (name, f0) = METALS[(rng.next_u64() % METALS.len() as u64) as usize];
                (
                    "metal",
                    name,
                    Analytic {
                        diffuse: [0.0; 3],
                        f0: jitter(&mut rng, f0),
                        alpha,
                    },
                )
            } else {
                let (name, base) = PAINTS[(rng.next_u64() % PAINTS.len() as u64) as usize];
                let f0 = [0.04; 3];
                (
                    "plastic",
                    name,
                    Analytic {
                        diffuse: jitter(&mut rng, base),
                        f0,
                        alpha,
                    },
                )
            };
            SynthMaterial {
                name: format!("{i:03}-{kind}-{colour}-r{alpha:.2}"),
                brdf,
            }
        })
        .collect()
}

/// Write the database of `count` materials with `seed`, tabulated at `dims`,
/// into `dir` (created if missing): one MERL file `<name>.binary` a
/// material. Returns the paths in database order.
///
/// Every file is written under a temporary name first, and all take their
/// places only once all are written: a failed run replaces no file and
/// leaves no partial one.
///
/// ```
/// use brdf_merl::{Dims, MerlFile, synth};
///
/// let dir = std::env::temp_dir().join(format!("brdf-merl-doc-{}", std::process::id()));
/// let paths = synth::write_dir(&dir, 2, Dims::new(4, 4, 8).unwrap(), 1).unwrap();
/// assert_eq!(paths.len(), 2);
/// assert_eq!(MerlFile::open(&paths[0]).unwrap().dims(), Dims::new(4, 4, 8).unwrap());
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_dir(dir: &Path, count: usize, dims: Dims, seed: u64) -> Result<Vec<PathBuf>> {
    write_named(
        dir,
        &database(count, seed),
        |m| &m.name,
        |m| m.brdf.table(dims),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::albedo::Quadrature;
    use crate::angles::direction;

    /// Monte Carlo albedo of the analytic function itself (no table):
    /// cosine-weighted sampling of both directions gives albedo = pi * E[f].
    fn monte_carlo(brdf: &Analytic, n: usize, seed: u64) -> ([f64; 3], [f64; 3]) {
        let mut rng = SplitMix64::new(seed);
        let cos_sample = |rng: &mut SplitMix64| {
            let (r1, r2) = (rng.next_f64(), rng.next_f64());
            direction(r1.sqrt().asin(), 2.0 * PI * r2)
        };
        let (mut s, mut s2) = ([0.0; 3], [0.0; 3]);
        for _ in 0..n {
            let wi = cos_sample(&mut rng);
            let wo = cos_sample(&mut rng);
            let f = brdf.eval(wi, wo);
            for c in 0..3 {
                s[c] += PI * f[c];
                s2[c] += (PI * f[c]).powi(2);
            }
        }
        let mean = s.map(|v| v / n as f64);
        let se = [0, 1, 2].map(|c| ((s2[c] / n as f64 - mean[c] * mean[c]) / n as f64).sqrt());
        (mean, se)
    }

    #[test]
    fn microfacet_table_albedo_matches_monte_carlo() {
        let q = Quadrature::dense(Dims::MERL, 2);
        for brdf in [
            Analytic {
                diffuse: [0.5, 0.2, 0.1],
                f0: [0.04; 3],
                alpha: 0.3,
            },
            Analytic {
                diffuse: [0.0; 3],
                f0: [0.95, 0.64, 0.54],
                alpha: 0.5,
            },
        ] {
            let table = brdf.table(Dims::MERL);
            let quad = q.albedo(&table);
            let (mc, se) = monte_carlo(&brdf, 2_000_000, 7);
            for c in 0..3 {
                // The tolerance: 4 standard errors of the estimate plus the
                // tabulation error of a 90x90x180 grid sampled at cell centres (measured: under 0.1%).
                let tol = 4.0 * se[c] + 0.002 * mc[c];
                assert!(
                    (quad[c] - mc[c]).abs() < tol,
                    "{brdf:?} channel {c}: quadrature {} vs MC {} ± {}",
                    quad[c],
                    mc[c],
                    se[c]
                );
            }
        }
    }

    #[test]
    fn no_material_reflects_more_than_it_receives() {
        let q = Quadrature::dense(Dims::MERL, 2);
        for m in database(40, 1).iter().filter(|m| m.brdf.alpha < 0.1) {
            let a = q.albedo(&m.brdf.table(Dims::MERL));
            assert!(a.iter().all(|&v| v <= 1.0), "{}: albedo {a:?}", m.name);
        }
    }

    #[test]
    fn database_is_deterministic_and_varied() {
        let a = database(12, 42);
        assert_eq!(a, database(12, 42));
        assert_ne!(a, database(12, 43));
        let names: std::collections::HashSet<_> = a.iter().map(|m| m.name.clone()).collect();
        assert_eq!(names.len(), 12);
        assert!(
            a.iter().any(|m| m.brdf.diffuse == [0.0; 3])
                && a.iter().any(|m| m.brdf.diffuse != [0.0; 3])
        );
    }

    #[test]
    fn table_marks_below_horizon_bins_invalid() {
        let dims = Dims::new(10, 10, 20).unwrap();
        let t = database(1, 1)[0].brdf.table(dims);
        for bin in 0..dims.bins() {
            let (ci, co) = dims.angles_of(bin).cosines();
            assert_eq!(
                t.value(0, bin).is_none(),
                ci <= 0.0 || co <= 0.0,
                "bin {bin}"
            );
        }
    }

    #[test]
    fn write_dir_writes_the_database_tables_by_name() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("made/by/write_dir");
        let dims = Dims::new(4, 4, 8).unwrap();
        let paths = write_dir(&dir, 3, dims, 7).unwrap();
        let materials = database(3, 7);
        assert_eq!(paths.len(), 3);
        for (path, m) in paths.iter().zip(&materials) {
            assert_eq!(path, &dir.join(format!("{}.binary", m.name)));
            assert_eq!(MerlTable::read(path).unwrap(), m.brdf.table(dims));
        }
        // Nothing else: no temporary file is left behind.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 3);
        // A directory in a file's place fails the run and replaces nothing.
        let blocked = tmp.path().join("blocked");
        std::fs::create_dir_all(blocked.join(format!("{}.binary", materials[1].name))).unwrap();
        assert!(write_dir(&blocked, 3, dims, 7).is_err());
        assert_eq!(std::fs::read_dir(&blocked).unwrap().count(), 1);
    }
}
