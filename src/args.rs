//! Argument values several commands share: comma-separated numbers
//! (latent points `--at`, directions as angles in degrees `--wi`/`--wo`,
//! view windows `--view`, table dims `--dims`) and the choices of
//! `--transform`, `--optimizer` and `--store-precision`.

use std::path::{Path, PathBuf};

use brdf_atlas_core::{Blend, BlendRule, Model, View};
use brdf_atlas_core::{OptimizerKind, Precision, TransformKind};
use brdf_merl::{Dims, Vec3};
use clap::ValueEnum;

use crate::error::Error;

/// What every bad `--at` value is told.
pub const AT_EXPECTED: &str = "--at expects two numbers like 0.3,-0.5";

/// Comma-separated finite numbers, or `None`.
fn numbers(text: &str) -> Option<Vec<f64>> {
    text.split(',')
        .map(|s| s.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect()
}

/// A latent point as given; its length is checked against the model by [`Point::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct Point(pub Vec<f64>);

/// Parse `x,y` (or `q` numbers for a `q`-dimensional latent space).
pub fn point(text: &str) -> Result<Point, String> {
    numbers(text).map(Point).ok_or_else(|| {
        format!("{AT_EXPECTED} (q numbers for a model with q latent dimensions), got {text:?}")
    })
}

impl Point {
    /// The coordinates, if there is one per latent dimension of `model` (`q`).
    pub fn check(&self, q: usize, model: &Path) -> Result<&[f64], Error> {
        if self.0.len() == q {
            return Ok(&self.0);
        }
        let given = self.0.len();
        Err(Error::Input(if q == 2 {
            format!(
                "{AT_EXPECTED} for {} (a 2-D latent space), got {given}",
                model.display()
            )
        } else {
            let example: Vec<&str> = ["0.3", "-0.5", "0.1", "0.7"]
                .iter()
                .cycle()
                .take(q)
                .copied()
                .collect();
            format!(
                "--at expects {q} numbers like {} for {} (q = {q}), got {given}",
                example.join(","),
                model.display()
            )
        }))
    }
}

/// A model and a latent point in it: the first arguments of `reconstruct`
/// and `eval`.
#[derive(Debug, clap::Args)]
pub struct ModelPoint {
    /// Model file written by `fit`.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Latent point, x,y (q numbers for a q-dimensional model).
    #[arg(long, value_name = "X,Y", value_parser = point, allow_hyphen_values = true)]
    pub at: Point,
    /// How the point's material is formed: `floor` (the default: the
    /// GPLVM's prediction, each value lifted softly onto a floor at 0.3
    /// times a kernel-weighted average of the materials: never clamped, the
    /// material the map shows), `gp` (the GPLVM's prediction as it is,
    /// values clamped to >= 0) or `plausible` (the GP's weights moved
    /// towards that average just far enough that the clamp removes at most
    /// 0.05% of the reflectance; one more pass over the store).
    #[arg(long, value_name = "RULE", default_value = "floor", value_parser = blend_rule)]
    pub blend: BlendRule,
}

/// Parse a blend rule name.
pub(crate) fn blend_rule(text: &str) -> Result<BlendRule, String> {
    BlendRule::parse(text).ok_or_else(|| format!("expected floor, gp or plausible, got {text:?}"))
}

impl ModelPoint {
    /// Open the model and check the point against it.
    pub fn open(&self) -> Result<(Model, &[f64]), Error> {
        let model = Model::open(&self.model)?;
        let x = self.at.check(model.q(), &self.model)?;
        Ok((model, x))
    }

    /// The blend at the point under the chosen rule.
    pub fn blend<'m>(&self, model: &'m Model, x: &[f64]) -> Result<Blend<'m>, Error> {
        Ok(model.at(x, self.blend)?)
    }
}

/// A direction given as angles in degrees: `theta` from the normal, `phi` around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    /// Polar angle from the surface normal, degrees.
    pub theta: f64,
    /// Azimuth, degrees.
    pub phi: f64,
}

impl Angles {
    /// The unit vector, as [`brdf_merl::angles::direction`] builds it.
    pub fn direction(self) -> Vec3 {
        brdf_merl::angles::direction(self.theta.to_radians(), self.phi.to_radians())
    }
}

/// What every bad angle pair is told.
pub const ANGLES_EXPECTED: &str =
    "expected two angles in degrees like 30,90 (theta from the normal, phi around it)";

/// Parse `theta,phi` in degrees.
pub fn angles(text: &str) -> Result<Angles, String> {
    match numbers(text).as_deref() {
        Some(&[theta, phi]) => Ok(Angles { theta, phi }),
        _ => Err(format!("{ANGLES_EXPECTED}, got {text:?}")),
    }
}

/// Parse `x0,x1,y0,y1` into a checked [`View`].
pub fn view(text: &str) -> Result<View, String> {
    let expected = || {
        format!(
            "--view expects four numbers x0,x1,y0,y1 with x0 < x1 and y0 < y1, like {}, got {text:?}",
            default_view()
        )
    };
    match numbers(text).as_deref() {
        Some(&[x0, x1, y0, y1]) => {
            let v = View { x0, x1, y0, y1 };
            v.check().map(|()| v).map_err(|_| expected())
        }
        _ => Err(expected()),
    }
}

/// The default view as `--view` takes it: `-1.1,1.1,-1.1,1.1`.
pub fn default_view() -> String {
    let View { x0, x1, y0, y1 } = View::default();
    format!("{x0},{x1},{y0},{y1}")
}

/// What every bad `--dims` value is told.
const DIMS_EXPECTED: &str = "--dims expects three positive integers like 90,90,180";

/// Parse `n_theta_h,n_theta_d,n_phi_d` into checked [`Dims`].
pub fn dims(text: &str) -> Result<Dims, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [a, b, c] = parts[..] else {
        return Err(format!("{DIMS_EXPECTED}, got {} value(s)", parts.len()));
    };
    let num = |s: &str| {
        s.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{DIMS_EXPECTED}, got {s:?}"))
    };
    Dims::new(num(a)?, num(b)?, num(c)?).map_err(|e| format!("{DIMS_EXPECTED}: {e}"))
}

/// `--transform` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TransformArg {
    /// The reflectance itself (1/sr).
    Raw,
    /// log(1 + f cos_i cos_o): highlights weigh less, dark materials look alike.
    Log,
    /// log(1 + f cos_i cos_o / 0.001): relative differences count alike, dark or bright.
    RelLog,
}

impl From<TransformArg> for TransformKind {
    fn from(t: TransformArg) -> Self {
        match t {
            TransformArg::Raw => TransformKind::Raw,
            TransformArg::Log => TransformKind::Log,
            TransformArg::RelLog => TransformKind::RelLog,
        }
    }
}

/// `--optimizer` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OptimizerArg {
    /// Direct search with O(N^2) rank-one updates per trial.
    HookeJeeves,
    /// Projected L-BFGS on the analytic gradient.
    Lbfgs,
}

impl From<OptimizerArg> for OptimizerKind {
    fn from(o: OptimizerArg) -> Self {
        match o {
            OptimizerArg::HookeJeeves => OptimizerKind::HookeJeeves,
            OptimizerArg::Lbfgs => OptimizerKind::Lbfgs,
        }
    }
}

/// `--store-precision` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    /// 4 bytes a value.
    F32,
    /// 8 bytes a value.
    F64,
}

impl From<PrecisionArg> for Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F64 => Precision::F64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_take_any_number_of_finite_coordinates() {
        assert_eq!(point("0.3,-0.5").unwrap(), Point(vec![0.3, -0.5]));
        assert_eq!(point(" 1 , 2 ,3").unwrap(), Point(vec![1.0, 2.0, 3.0]));
        for bad in ["", "a,b", "0.3,", "0.3;0.5", "nan,0", "inf,1", "1e999,0"] {
            let e = point(bad).unwrap_err();
            assert!(e.starts_with(AT_EXPECTED), "{bad:?}: {e}");
        }
    }

    #[test]
    fn point_length_is_checked_against_the_model() {
        let m = Path::new("m.atlas");
        assert_eq!(Point(vec![0.1, 0.2]).check(2, m).unwrap(), &[0.1, 0.2][..]);
        let e = Point(vec![0.1, 0.2, 0.3]).check(2, m).unwrap_err();
        assert!(e.to_string().starts_with(AT_EXPECTED), "{e}");
        assert!(e.to_string().contains("m.atlas"), "{e}");
        let e = Point(vec![0.1, 0.2]).check(3, m).unwrap_err().to_string();
        assert!(
            e.contains("--at expects 3 numbers like 0.3,-0.5,0.1"),
            "{e}"
        );
    }

    #[test]
    fn angles_are_two_numbers_in_degrees() {
        let a = angles("90,0").unwrap();
        let d = a.direction();
        assert!((d[0] - 1.0).abs() < 1e-15 && d[2].abs() < 1e-15, "{d:?}");
        assert_eq!(angles("0,0").unwrap().direction(), [0.0, 0.0, 1.0]);
        for bad in ["30", "30,40,50", "x,1", ""] {
            assert!(angles(bad).unwrap_err().starts_with(ANGLES_EXPECTED));
        }
    }

    #[test]
    fn views_are_ordered_windows() {
        let v = view("-1,1,-0.5,0.5").unwrap();
        assert_eq!((v.x0, v.x1, v.y0, v.y1), (-1.0, 1.0, -0.5, 0.5));
        assert_eq!(default_view(), "-1.1,1.1,-1.1,1.1");
        assert_eq!(view(&default_view()).unwrap(), View::default());
        for bad in ["1,-1,0,1", "0,1,0,0", "0,1,0", "a,b,c,d"] {
            assert!(
                view(bad).unwrap_err().starts_with("--view expects"),
                "{bad}"
            );
        }
    }

    #[test]
    fn accepts_three_positive_integers() {
        assert_eq!(dims("90,90,180").unwrap(), Dims::MERL);
        assert_eq!(dims(" 8, 8 ,16").unwrap(), Dims::new(8, 8, 16).unwrap());
    }

    #[test]
    fn rejects_everything_else_with_the_expected_form() {
        for bad in [
            "",
            "90,90",
            "90,90,180,1",
            "a,b,c",
            "0,90,180",
            "-1,90,180",
            "90,90,1e3",
            "90,,180",
            "90,90,2000",
        ] {
            let err = dims(bad).unwrap_err();
            assert!(err.starts_with(DIMS_EXPECTED), "{bad:?}: {err}");
            assert!(!err.contains('\n'), "{err}");
        }
    }
}
