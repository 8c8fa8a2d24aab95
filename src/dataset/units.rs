//! Writing numbers so that they read back bit for bit.

use crate::model::Unit;

/// How many neighbouring floats on each side [`report_value`] tries.
const SEARCH_ULPS: usize = 16;

/// A float in TOML syntax that parses back to exactly `x` (Rust's shortest round-trip
/// form, which always has a `.` or an exponent, so it stays a float).
pub(crate) fn toml_float(x: f64) -> String {
    format!("{x:?}")
}

/// A float in CSV: Rust's shortest round-trip form.
pub(crate) fn csv_float(x: f64) -> String {
    format!("{x}")
}

/// The value to write for internal value `x` (rad or mm) in report units (deg or mm).
///
/// Degrees → radians is a multiplication that is not invertible in floating point, so
/// `to_report` alone does not always read back to `x`. Among the floats within a few ulps of
/// `to_report(x)`, this picks the one with the shortest decimal form for which
/// `from_report` gives `x` exactly; when there is none (some radians are not the image of
/// any float number of degrees), `to_report(x)`, which reads back within an ulp or two.
pub(crate) fn report_value(unit: Unit, x: f64) -> f64 {
    let y = unit.to_report(x);
    if !unit.is_scaled() || !y.is_finite() {
        return y;
    }
    let mut best: Option<(usize, f64, f64)> = None;
    let mut consider = |c: f64| {
        if unit.from_report(c).to_bits() == x.to_bits() {
            let key = (toml_float(c).len(), (c - y).abs());
            if best.is_none_or(|(len, dist, _)| key < (len, dist)) {
                best = Some((key.0, key.1, c));
            }
        }
    };
    consider(y);
    let (mut down, mut up) = (y, y);
    for _ in 0..SEARCH_ULPS {
        down = down.next_down();
        up = up.next_up();
        consider(down);
        consider(up);
    }
    best.map_or(y, |(_, _, c)| c)
}

/// [`report_value`] for an angle: the degrees to write for `rad`.
pub(crate) fn degrees_for(rad: f64) -> f64 {
    report_value(Unit::Deg, rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_read_back() {
        for x in [
            0.0,
            -0.0,
            0.1,
            1.0 / 3.0,
            1e20,
            -1e-7,
            5e-324,
            f64::MAX,
            640.0,
        ] {
            let t = toml_float(x);
            assert!(t.contains('.') || t.contains('e'), "{t}");
            assert_eq!(t.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{t}");
            assert_eq!(csv_float(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
    }

    #[test]
    fn degrees_prefer_short_exact_decimals() {
        assert_eq!(degrees_for(39.7f64.to_radians()), 39.7);
        assert_eq!(degrees_for(0.4764f64.to_radians()), 0.4764);
        assert_eq!(degrees_for(-4.5627f64.to_radians()), -4.5627);
        assert_eq!(report_value(Unit::Mm, 0.1), 0.1);
    }

    #[test]
    fn degrees_read_back_exactly_when_possible() {
        // Radians that come from some float of degrees always read back exactly; any other
        // radians read back within a couple of ulps.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..20_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let deg = (state >> 11) as f64 / (1u64 << 53) as f64 * 360.0 - 180.0;
            let rad = deg.to_radians();
            assert_eq!(
                degrees_for(rad).to_radians().to_bits(),
                rad.to_bits(),
                "{deg}"
            );
            let odd = rad.next_up();
            let back = degrees_for(odd).to_radians();
            assert!(
                (back - odd).abs() <= 4.0 * f64::EPSILON * odd.abs().max(1e-300),
                "{odd}"
            );
        }
    }
}
