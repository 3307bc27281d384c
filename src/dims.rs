//! Parsing `--dims a,b,c`.

use brdf_merl::Dims;

/// What every bad `--dims` value is told.
const EXPECTED: &str = "--dims expects three positive integers like 90,90,180";

/// Parse `n_theta_h,n_theta_d,n_phi_d` into checked [`Dims`].
pub fn parse(text: &str) -> Result<Dims, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [a, b, c] = parts[..] else {
        return Err(format!("{EXPECTED}, got {} value(s)", parts.len()));
    };
    let num = |s: &str| {
        s.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{EXPECTED}, got {s:?}"))
    };
    Dims::new(num(a)?, num(b)?, num(c)?).map_err(|e| format!("{EXPECTED}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_three_positive_integers() {
        assert_eq!(parse("90,90,180").unwrap(), Dims::MERL);
        assert_eq!(parse(" 8, 8 ,16").unwrap(), Dims::new(8, 8, 16).unwrap());
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
            let err = parse(bad).unwrap_err();
            assert!(err.starts_with(EXPECTED), "{bad:?}: {err}");
            assert!(!err.contains('\n'), "{err}");
        }
    }
}
