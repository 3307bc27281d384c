//! Parsing comma-separated numbers: latent points (`--at`), directions as
//! angles in degrees (`--wi`, `--wo`) and view windows (`--view`).

use std::path::Path;

use brdf_atlas_core::View;
use brdf_merl::Vec3;

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

    /// `(0.3000, -0.5000)`, for reports.
    pub fn show(x: &[f64]) -> String {
        let parts: Vec<String> = x.iter().map(|v| format!("{v:.4}")).collect();
        format!("({})", parts.join(", "))
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
    const EXPECTED: &str =
        "--view expects four numbers x0,x1,y0,y1 with x0 < x1 and y0 < y1, like -1.1,1.1,-1.1,1.1";
    match numbers(text).as_deref() {
        Some(&[x0, x1, y0, y1]) => {
            let v = View { x0, x1, y0, y1 };
            v.check()
                .map(|()| v)
                .map_err(|_| format!("{EXPECTED}, got {text:?}"))
        }
        _ => Err(format!("{EXPECTED}, got {text:?}")),
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
        for bad in ["1,-1,0,1", "0,1,0,0", "0,1,0", "a,b,c,d"] {
            assert!(
                view(bad).unwrap_err().starts_with("--view expects"),
                "{bad}"
            );
        }
    }
}
