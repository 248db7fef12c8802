//! Value parsers shared by every subcommand, so that each numeric option is checked the same
//! way everywhere and a bad value is refused by clap (exit status 2) with a message about the
//! value: `error: invalid value 'nan' for '--tol <TOL>': must be a positive finite number`.
//!
//! Negative numbers are accepted as values by the parser (`main` sets
//! `allow_negative_numbers` on every argument), so `--tol -1` reaches these checks instead of
//! being taken for an unknown option.

/// Largest accepted wall-clock limit, in seconds (one week).
pub const MAX_TIME_LIMIT_S: f64 = 7.0 * 24.0 * 3600.0;

fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .map_err(|_| "not a number".to_string())
}

/// A finite number > 0 (tolerances).
pub fn positive(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err("must be a positive finite number".into())
    }
}

/// A tolerance on the error of docs/error.md: above 0 and below 1
/// ([`coulomb::settings::check_tol`], the rule of every entry point).
pub fn tolerance(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    coulomb::settings::check_tol(x).map(|()| x)
}

/// A finite number ≥ 0 (friction coefficients, tolerances where 0 means "off").
pub fn nonnegative(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err("must be a finite number ≥ 0".into())
    }
}

/// Any finite number (velocities, gravity: the sign is meaningful).
pub fn finite(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err("must be a finite number".into())
    }
}

/// A finite number in [0, 1] (restitution coefficient, θ of the position update).
pub fn unit_interval(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x.is_finite() && (0.0..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err("must be a number in [0, 1]".into())
    }
}

/// A wall-clock limit in seconds: finite, > 0 and at most [`MAX_TIME_LIMIT_S`].
pub fn time_limit(s: &str) -> Result<f64, String> {
    let x = number(s)?;
    if x.is_finite() && x > 0.0 && x <= MAX_TIME_LIMIT_S {
        Ok(x)
    } else {
        Err(format!(
            "must be a positive number of seconds up to {MAX_TIME_LIMIT_S} (one week)"
        ))
    }
}

fn whole(s: &str) -> Result<u64, String> {
    let t = s.trim();
    if t.starts_with('-') {
        return Err("must be a whole number ≥ 0, not negative".into());
    }
    t.parse::<u64>()
        .map_err(|_| "must be a whole number (digits only)".to_string())
}

/// A count ≥ 1 (beads, steps, iteration caps, repeats).
pub fn count(s: &str) -> Result<usize, String> {
    let n = whole(s)?;
    if n == 0 {
        return Err("must be at least 1".into());
    }
    usize::try_from(n).map_err(|_| "is too large".into())
}

/// A count ≥ 0 (where 0 means "none", e.g. --frames-every 0).
pub fn count0(s: &str) -> Result<usize, String> {
    usize::try_from(whole(s)?).map_err(|_| "is too large".into())
}

/// A grid of subdomains `PXxPY` (two counts ≥ 1, e.g. `2x2`).
#[cfg(feature = "mpi")]
pub fn grid(s: &str) -> Result<[usize; 2], String> {
    let (a, b) = s
        .trim()
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| "must be PXxPY, e.g. 2x2".to_string())?;
    Ok([count(a)?, count(b)?])
}

/// An over-relaxation factor ω ∈ [1, 2).
pub fn relaxation(s: &str) -> Result<f64, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| "is not a number".to_string())?;
    if !(1.0..2.0).contains(&x) {
        return Err("must be in [1, 2)".into());
    }
    Ok(x)
}

/// A number of worker threads: 1 to 1024.
pub fn threads(s: &str) -> Result<usize, String> {
    let n = count(s)?;
    if n > 1024 {
        return Err("must be at most 1024".into());
    }
    Ok(n)
}

/// A seed: any whole number ≥ 0.
pub fn seed(s: &str) -> Result<u64, String> {
    whole(s)
}

/// Beads of a simulation: 1 to 1 000 000 (the limit of `simulate`).
pub fn beads(s: &str) -> Result<usize, String> {
    let n = count(s)?;
    if n > 1_000_000 {
        return Err("must be at most 1000000".into());
    }
    Ok(n)
}

/// One of the names of `all` (`name` of each, with its help `about` when given), parsed back
/// into its value: clap's list of possible values in `--help` and in the error of a bad value,
/// for the plain enums of `coulomb_lab` (which do not depend on clap).
pub fn one_of<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
    about: Option<fn(T) -> &'static str>,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(all.iter().map(move |&t| {
        let v = PossibleValue::new(name(t));
        match about {
            Some(about) => v.help(about(t)),
            None => v,
        }
    }))
    .try_map(move |s| {
        all.iter()
            .copied()
            .find(|&t| name(t) == s)
            .ok_or("not one of the listed names")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_refuse_nan_inf_zero_negative_where_meaningless() {
        for bad in ["nan", "NaN", "inf", "-inf", "0", "-1", "x", ""] {
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(positive("1e-8"), Ok(1e-8));
        assert_eq!(nonnegative("0"), Ok(0.0));
        assert!(nonnegative("-0.01").is_err());
        assert_eq!(finite("-0.5"), Ok(-0.5));
        assert!(finite("inf").is_err());
        assert!(unit_interval("1.5").is_err());
        assert_eq!(unit_interval("1"), Ok(1.0));
        for bad in ["1e30", "1e19", "inf", "0", "-1", "nan"] {
            assert!(time_limit(bad).is_err(), "{bad}");
        }
        assert_eq!(time_limit("2.5"), Ok(2.5));
        assert!(count("0").is_err() && count("-3").is_err() && count("1.5").is_err());
        assert_eq!(count("7"), Ok(7));
        assert_eq!(count0("0"), Ok(0));
        assert!(beads("100000000").is_err());
        assert_eq!(beads("1000000"), Ok(1_000_000));
    }
}
