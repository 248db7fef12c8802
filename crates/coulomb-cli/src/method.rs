//! The library's method names on the command line, shared by every subcommand: `--inner` and
//! `--outer` parse into [`coulomb::InnerKind`] / [`coulomb::OuterKind`] through their
//! `FromStr` (one spelling for the CLI, the Python bindings and the reports), with clap's list
//! of possible values in `--help` and in the error of a bad value; and the solver settings of
//! `simulate`, built on the library's presets (those of `paper`:
//! [`coulomb_lab::paper::paper_settings`]).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use coulomb::{InnerKind, Method, MethodParams, OuterKind, Settings};

/// The command-line spelling of a library name: `fixed_point` is written `fixed-point`.
fn cli_name(name: &'static str) -> &'static str {
    match name {
        "fixed_point" => "fixed-point",
        other => other,
    }
}

fn possible(names: impl Iterator<Item = &'static str>) -> PossibleValuesParser {
    PossibleValuesParser::new(names.map(|n| {
        let v = PossibleValue::new(cli_name(n));
        if n.contains('_') {
            v.alias(n)
        } else {
            v
        }
    }))
}

/// `--inner`: ipm, apgd, pgs, faceted.
pub fn inner() -> impl TypedValueParser<Value = InnerKind> {
    possible(InnerKind::ALL.iter().map(|k| k.as_str()))
        .map(|s| s.parse::<InnerKind>().expect("one of the listed names"))
}

/// `--outer`: fixed-point, anderson, fused.
pub fn outer() -> impl TypedValueParser<Value = OuterKind> {
    possible(OuterKind::ALL.iter().map(|k| k.as_str()))
        .map(|s| s.parse::<OuterKind>().expect("one of the listed names"))
}

/// The solver settings of a simulation: `inner` alone (Anderson-mixed outer iteration, each
/// subproblem solved accurately: [`Settings::time_stepping`]), the paper's outer rule (6.1)
/// with ε = `fp_tol` when `fp_tol` > 0.
pub fn time_stepping_settings(
    inner: InnerKind,
    tol: f64,
    fp_tol: f64,
    max_outer: usize,
    max_inner: Option<usize>,
) -> Settings {
    let d = Settings::time_stepping(Method::new(inner, Settings::default().outer));
    Settings {
        tol,
        max_outer,
        max_inner: max_inner.unwrap_or(d.max_inner),
        params: MethodParams {
            fixed_point_tol: (fp_tol > 0.0).then_some(fp_tol),
            ..d.params
        },
        ..d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_the_former_hand_built_settings() {
        // what simulate built by hand before the library had presets (paper's:
        // coulomb_lab::paper's tests)
        let sim = time_stepping_settings(InnerKind::Pgs, 1e-4, 0.0, 20, None);
        let mut by_hand = Settings {
            tol: 1e-4,
            max_outer: 20,
            ..Settings::method(InnerKind::Pgs, OuterKind::Anderson)
        };
        by_hand.params.inner_tol_factor = 1e-6;
        assert_eq!(sim, by_hand);
    }

    #[test]
    fn names_parse_as_the_library_spells_them() {
        use clap::builder::TypedValueParser as _;
        let cmd = clap::Command::new("t");
        let p = outer();
        for (name, kind) in [
            ("fixed-point", OuterKind::FixedPoint),
            ("fixed_point", OuterKind::FixedPoint),
            ("fused", OuterKind::Fused),
        ] {
            assert_eq!(p.parse_ref(&cmd, None, name.as_ref()).unwrap(), kind);
        }
        assert!(inner().parse_ref(&cmd, None, "simplex".as_ref()).is_err());
    }
}
