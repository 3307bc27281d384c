//! How numbers, times, sizes and latent points read in every command's
//! output: one home, so that `fit`, `map`, `reconstruct`, `demo` and the
//! report agree.

use std::ops::Range;
use std::time::Duration;

/// `0.123 s`.
pub fn secs(t: Duration) -> String {
    format!("{:.3} s", t.as_secs_f64())
}

/// `35.0 MB`, `1.75 GB`.
pub fn size(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else {
        format!("{:.1} kB", b / 1e3)
    }
}

/// Four decimals where the magnitude lies in `fixed` (or the value is 0),
/// scientific with `exp_digits` decimals otherwise.
fn fixed_or_exp(v: f64, fixed: Range<f64>, exp_digits: usize) -> String {
    if v == 0.0 || fixed.contains(&v.abs()) {
        format!("{v:.4}")
    } else {
        format!("{v:.exp_digits$e}")
    }
}

/// A cost (negative log likelihood) in a fixed width of significant digits.
pub fn cost(v: f64) -> String {
    fixed_or_exp(v, 1e-2..1e7, 6)
}

/// A value in at most 10 characters: fixed point where that reads well,
/// scientific otherwise, `-` where there is none (no measured value).
pub fn table_value(v: f64) -> String {
    if v.is_finite() {
        fixed_or_exp(v, 0.01..1000.0, 3)
    } else {
        "-".into()
    }
}

/// An error or cost in a report table: four decimals or four significant digits.
pub fn g4(v: f64) -> String {
    fixed_or_exp(v, 1e-3..1e5, 3)
}

/// A fraction as a percentage: `25%`, `1.50%`, `5.0e-3%`.
pub fn pct(v: f64) -> String {
    if v >= 0.1 {
        format!("{:.0}%", 100.0 * v)
    } else if v >= 0.001 {
        format!("{:.2}%", 100.0 * v)
    } else {
        format!("{:.1e}%", 100.0 * v)
    }
}

/// A latent point as the commands print it: `(0.3000, -0.5000)`.
pub fn point(x: &[f64]) -> String {
    format!("({})", coordinates(x, 4))
}

/// Coordinates with `digits` decimals, separated by `, `.
pub fn coordinates(x: &[f64], digits: usize) -> String {
    x.iter()
        .map(|v| format!("{v:.digits$}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What a sampled field's check says, for a summary line: `, 4.9% off
/// exact albedos at worst and 0.62% on average at 32 points of its domain`,
/// or nothing for a field saved before fields were checked.
pub fn field_check(check: Option<brdf_atlas_core::FieldCheck>) -> String {
    match check {
        Some(c) => format!(
            ", {} off exact albedos at worst and {} on average at {} points of its domain",
            pct(c.worst),
            pct(c.mean),
            c.points
        ),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_times_and_costs_read_well() {
        assert_eq!(size(34_992_012), "35.0 MB");
        assert_eq!(size(1_749_600_064), "1.75 GB");
        assert_eq!(size(12_345), "12.3 kB");
        assert_eq!(cost(-1234.56789), "-1234.5679");
        assert_eq!(cost(-2.5e8), "-2.500000e8");
        assert_eq!(secs(Duration::from_millis(1500)), "1.500 s");
    }

    #[test]
    fn table_values_fit_their_column() {
        for v in [
            0.0,
            1e-9,
            0.0123,
            0.5,
            12.345,
            999.99,
            1234.5,
            1.5e5,
            -0.25,
            -3e-4,
            f64::NAN,
            f64::INFINITY,
        ] {
            let s = table_value(v);
            assert!(s.len() <= 10, "{v}: {s}");
        }
        assert_eq!(table_value(0.5), "0.5000");
        assert_eq!(table_value(1.5e5), "1.500e5");
        assert_eq!(table_value(f64::NAN), "-");
    }

    #[test]
    fn report_numbers_and_points() {
        assert_eq!(g4(0.0), "0.0000");
        assert_eq!(g4(0.01234), "0.0123");
        assert_eq!(g4(1.5e-4), "1.500e-4");
        assert_eq!(g4(-2.5e6), "-2.500e6");
        assert_eq!(pct(0.25), "25%");
        assert_eq!(pct(0.015), "1.50%");
        assert_eq!(pct(5e-5), "5.0e-3%");
        assert_eq!(point(&[0.3, -0.5]), "(0.3000, -0.5000)");
        assert_eq!(coordinates(&[0.3, -0.5], 3), "0.300, -0.500");
    }
}
