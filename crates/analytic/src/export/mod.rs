//! The files a fitted material is exported as: a glTF 2.0 binary
//! (`NAME.glb`, [`gltf`]), a MaterialX document (`NAME.mtlx`) and a
//! Mitsuba 3 `principled` dictionary (`NAME.mitsuba.json`, both
//! [`documents`]), and the fit's record (`NAME.fit.json`, [`record`]: the
//! parameters, every error and how it was measured).
//!
//! An [`Export`] names the material and carries its [`Fits`]; the
//! rendered errors ([`RenderedErrors`]) come from a renderer of the
//! caller's (this crate draws nothing), and where there are none the record
//! and the notes give the table errors only. [`stage`] stages the four
//! files (`brdf_atomic`: nothing is in place until the caller commits),
//! [`write`] stages and puts them in place together: a failed write leaves
//! none of them.
//!
//! ```
//! use brdf_atlas_analytic::export::{self, Export};
//! use brdf_atlas_analytic::{Analytic, Principled, SWATCH_LIGHTS, fit_as_exported};
//! use brdf_merl::{Dims, MerlTable};
//! let truth = Principled { base_color: [0.6, 0.3, 0.1], roughness: 0.4, ..Principled::default() };
//! let dims = Dims::new(16, 16, 32).unwrap();
//! let table = MerlTable::from_fn(dims, |bin| {
//!     let (wi, wo) = dims.angles_of(bin).directions();
//!     Some(truth.eval(wi, wo))
//! });
//! let fits = fit_as_exported(&table, "orange", &SWATCH_LIGHTS).unwrap();
//! let dir = tempfile::tempdir().unwrap();
//! let e = Export { name: "orange", source: "a table of a known material", fits: &fits, rendered: None };
//! let written = export::write(dir.path(), &e).unwrap();
//! assert_eq!(written.len(), export::EXTENSIONS.len());
//! assert!(dir.path().join("orange.glb").is_file());
//! ```

pub mod documents;
pub mod gltf;

use std::io::Write as _;
use std::path::{Path, PathBuf};

use brdf_atomic::{PendingFile, commit_all};
use serde_json::{Value, json};

use crate::samples::EPSILON;
use crate::{Analytic, AnalyticError, Fits, Light, Principled, Result};

/// The endings of the files [`write`] writes for a material `NAME`
/// (`NAME.glb`, ...), in the order it stages them.
pub const EXTENSIONS: [&str; 4] = ["glb", "mtlx", "mitsuba.json", "fit.json"];

/// The rendered errors of a fit, measured by the caller: `sum |L' - L| /
/// sum L` over a lit sphere's pixels (coverage weighted) and RGB, in linear
/// radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedErrors {
    /// The principled fit.
    pub principled: f64,
    /// One GGX lobe over a Lambertian base.
    pub single_lobe: f64,
    /// The Lambertian of the albedo.
    pub lambertian: f64,
    /// The principled fit under `held_out_lights`.
    pub held_out: f64,
    /// The lights the errors are measured under.
    pub lights: Vec<Light>,
    /// Lights the fit never saw.
    pub held_out_lights: Vec<Light>,
    /// Side of the sphere, pixels.
    pub sphere_pixels: usize,
}

/// One material to export.
#[derive(Debug, Clone, Copy)]
pub struct Export<'a> {
    /// Its name: the files' stem, the glTF material's and MaterialX's names.
    pub name: &'a str,
    /// Where the material came from, in words (a file, a point of a model).
    pub source: &'a str,
    /// Its fits ([`crate::fit_as_exported`]).
    pub fits: &'a Fits,
    /// Its rendered errors, where the caller measured them.
    pub rendered: Option<&'a RenderedErrors>,
}

impl Export<'_> {
    /// The fitted material.
    pub fn principled(&self) -> &Principled {
        &self.fits.principled.model
    }
}

/// Whether `stem` can name the files in a directory: not empty, no
/// directory separator, no leading dot (no hidden files, no `..`).
pub fn is_file_stem(stem: &str) -> bool {
    !(stem.is_empty() || stem.contains(['/', '\\']) || stem.starts_with('.'))
}

fn lights(lights: &[Light]) -> Vec<Value> {
    lights
        .iter()
        .map(|l| json!({"direction": l.direction, "intensity": l.intensity}))
        .collect()
}

/// The fit's record, `NAME.fit.json`: parameters, errors and how they were
/// measured; `rendered_error` only where [`Export::rendered`] is given.
pub fn record(e: &Export) -> Value {
    let fits = e.fits;
    let p = e.principled();
    let mut rec = json!({
        "format": "brdf-atlas-export",
        "version": 1,
        "name": e.name,
        "source": e.source,
        "model": Principled::NAME,
        "parameters": {
            "base_color": p.base_color,
            "metallic": p.metallic,
            "roughness": p.roughness,
            "specular": p.specular,
            "specular_color": p.specular_color,
            "ior": p.ior,
        },
        "table_error": {
            "principled": fits.principled.error,
            "single_lobe": fits.single_lobe.error,
            "lambertian": fits.lambertian.error,
            "metric": format!("RMS over a subsample of bins and RGB of ln((f_fit + e) / (f + e)), e = {EPSILON}, weighted by cos_i cos_o"),
        },
        "single_lobe": {
            "diffuse": fits.single_lobe.model.diffuse,
            "specular": fits.single_lobe.model.specular,
            "roughness": fits.single_lobe.model.roughness,
        },
        "albedo": fits.lambertian.model.albedo,
    });
    if let Some(r) = e.rendered {
        rec["rendered_error"] = json!({
            "principled": r.principled,
            "single_lobe": r.single_lobe,
            "lambertian": r.lambertian,
            "principled_held_out_lights": r.held_out,
            "held_out_lights": lights(&r.held_out_lights),
            "metric": "sum |L_fit - L_measured| / sum L_measured over a lit sphere's pixels (coverage weighted) and RGB, linear radiance",
            "sphere_pixels": r.sphere_pixels,
            "lights": lights(&r.lights),
        });
    }
    rec
}

/// One line on what the fit loses, for the MaterialX document's comment:
/// the rendered error where there is one, else the table error.
pub fn note(e: &Export) -> String {
    match e.rendered {
        Some(r) => format!(
            "brdf-atlas export of {}: rendered error {:.2}% (sum |L' - L| / sum L, swatch lights)",
            e.source,
            100.0 * r.principled
        ),
        None => format!(
            "brdf-atlas export of {}: table error {:.4} (RMS of ln((f' + e) / (f + e)) over a subsample of bins, cosine weighted)",
            e.source, e.fits.principled.error
        ),
    }
}

fn pretty(value: &Value, path: &Path) -> Result<Vec<u8>> {
    let mut text = serde_json::to_vec_pretty(value).map_err(|e| AnalyticError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    text.push(b'\n');
    Ok(text)
}

fn staged(path: PathBuf, bytes: &[u8]) -> Result<PendingFile> {
    brdf_atomic::stage(&path, |f| f.write_all(bytes))
        .map_err(|source| AnalyticError::Write { path, source })
}

/// Stage the four files of `e` in `dir` (an existing directory), in the
/// order of [`EXTENSIONS`]; none is in place until the caller commits
/// them (`brdf_atomic::commit_all`). The name is taken as it is: [`write`]
/// checks it ([`is_file_stem`]).
pub fn stage(dir: &Path, e: &Export) -> Result<Vec<PendingFile>> {
    let p = e.principled();
    let rec = record(e);
    let [glb, mtlx, mitsuba, fit] = EXTENSIONS.map(|ext| dir.join(format!("{}.{ext}", e.name)));
    let mitsuba_text = pretty(&documents::mitsuba(p), &mitsuba)?;
    let record_text = pretty(&rec, &fit)?;
    Ok(vec![
        staged(glb, &gltf::glb(p, e.name, json!({"brdf_atlas": rec})))?,
        staged(mtlx, documents::materialx(p, e.name, &note(e)).as_bytes())?,
        staged(mitsuba, &mitsuba_text)?,
        staged(fit, &record_text)?,
    ])
}

/// Write the four files of `e` into `dir`, which must exist, together: all
/// of them or (on an error) none. `e.name` must be a file name
/// ([`is_file_stem`]). Returns their paths, in the order of
/// [`EXTENSIONS`].
pub fn write(dir: &Path, e: &Export) -> Result<Vec<PathBuf>> {
    if !is_file_stem(e.name) {
        return Err(AnalyticError::Stem {
            stem: e.name.to_owned(),
        });
    }
    if !dir.is_dir() {
        return Err(AnalyticError::NotADirectory {
            path: dir.to_path_buf(),
        });
    }
    let files = stage(dir, e)?;
    let paths: Vec<PathBuf> = files.iter().map(|f| f.target().to_path_buf()).collect();
    commit_all(files).map_err(|(path, source)| AnalyticError::Write { path, source })?;
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Fitted, GgxLambert, Lambertian};

    fn fitted<M>(model: M, error: f64) -> Fitted<M> {
        Fitted {
            model,
            error,
            iterations: 1,
        }
    }

    fn fits() -> Fits {
        Fits {
            principled: fitted(Principled::default(), 0.25),
            single_lobe: fitted(
                GgxLambert {
                    diffuse: [0.5; 3],
                    specular: [0.1; 3],
                    roughness: 0.3,
                },
                0.3,
            ),
            lambertian: fitted(Lambertian { albedo: [0.5; 3] }, 1.5),
        }
    }

    #[test]
    fn the_record_has_rendered_errors_only_where_measured() {
        let fits = fits();
        let mut e = Export {
            name: "m",
            source: "a test",
            fits: &fits,
            rendered: None,
        };
        let rec = record(&e);
        assert!(rec.get("rendered_error").is_none());
        assert_eq!(rec["table_error"]["principled"], 0.25);
        assert!(note(&e).contains("table error 0.2500"));
        let rendered = RenderedErrors {
            principled: 0.064,
            single_lobe: 0.066,
            lambertian: 0.336,
            held_out: 0.072,
            lights: crate::SWATCH_LIGHTS.to_vec(),
            held_out_lights: vec![],
            sphere_pixels: 128,
        };
        e.rendered = Some(&rendered);
        assert_eq!(record(&e)["rendered_error"]["principled"], 0.064);
        assert!(note(&e).contains("rendered error 6.40%"));
    }

    #[test]
    fn write_refuses_a_bad_name_or_directory_and_writes_nothing() {
        let fits = fits();
        let dir = tempfile::tempdir().unwrap();
        for stem in ["", "a/b", "..", ".hidden", "a\\b"] {
            let e = Export {
                name: stem,
                source: "a test",
                fits: &fits,
                rendered: None,
            };
            let err = write(dir.path(), &e).unwrap_err();
            assert!(matches!(err, AnalyticError::Stem { .. }), "{stem:?}: {err}");
        }
        let e = Export {
            name: "m",
            source: "a test",
            fits: &fits,
            rendered: None,
        };
        let missing = dir.path().join("missing");
        let err = write(&missing, &e).unwrap_err().to_string();
        assert!(
            err.ends_with("missing: is not a directory (it must exist)"),
            "{err}"
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let written = write(dir.path(), &e).unwrap();
        assert_eq!(
            written,
            EXTENSIONS.map(|x| dir.path().join(format!("m.{x}")))
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 4);
    }
}
