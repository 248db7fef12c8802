//! The JSON of `Settings` (the serde feature): the method parameters live in
//! `Settings::params`, but the JSON keeps them at the top level, in the order they had before
//! they moved there, so that stored settings (a sphere checkpoint's `/json/solver`) read and
//! write unchanged. `data/settings-default.json` is `Settings::default()` as the layout before
//! the move wrote it.

use coulomb::deadline::Cancel;
use coulomb::{InnerKind, MethodParams, OuterKind, Settings};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

const DEFAULT_JSON: &str = include_str!("data/settings-default.json");

/// The top-level keys, in the order they are written.
const KEYS: [&str; 15] = [
    "tol",
    "inner",
    "outer",
    "fallback",
    "warmup_sweeps",
    "barrier_steps",
    "max_outer",
    "max_inner",
    "time_limit",
    "fixed_point_tol",
    "facets",
    "inner_tol_factor",
    "newton_steps",
    "newton_start",
    "tuning",
];

/// Settings with every field away from its default.
fn changed() -> Settings {
    let mut params = MethodParams {
        warmup_sweeps: 7,
        barrier_steps: 11,
        fixed_point_tol: Some(0.01),
        facets: 12,
        inner_tol_factor: 0.25,
        newton_steps: 3,
        newton_start: 1.0 / 3.0,
        ..MethodParams::default()
    };
    params.tuning.newton.retry = 0.3;
    params.tuning.multiplier.starts = 2;
    params.tuning.inner.apgd_barzilai_borwein = true;
    Settings {
        tol: 1.0 / 7.0,
        inner: InnerKind::Pgs,
        outer: OuterKind::Fused,
        fallback: None,
        max_outer: 9,
        max_inner: 13,
        time_limit: Some(Duration::from_millis(1500)),
        cancel: None,
        params,
    }
}

#[test]
fn the_default_settings_write_the_json_they_wrote_before_the_parameters_moved() {
    let json = serde_json::to_string(&Settings::default()).unwrap();
    assert_eq!(json, DEFAULT_JSON.trim_end());
    let back: Settings = serde_json::from_str(DEFAULT_JSON).unwrap();
    assert_eq!(back, Settings::default());
}

#[test]
fn every_field_round_trips_with_the_parameters_at_the_top_level() {
    for s in [
        changed(),
        Settings::paper(InnerKind::Apgd),
        Settings::method(InnerKind::Ipm, OuterKind::Anderson),
    ] {
        let json = serde_json::to_string(&s).unwrap();
        let back: Settings = serde_json::from_str(&json).unwrap();
        assert_eq!(back, s);
        // each key's first occurrence is the top-level one (`tuning` comes last); they come
        // in the order of KEYS, and `params` and `cancel` are not written
        let at: Vec<usize> = KEYS
            .iter()
            .map(|k| json.find(&format!("\"{k}\":")).unwrap())
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{json}");
        assert!(!json.contains("\"params\"") && !json.contains("\"cancel\""));
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(value.as_object().unwrap().len(), KEYS.len());
    }
}

#[test]
fn a_missing_field_is_refused_and_an_unknown_one_ignored_as_before() {
    // serde reads a missing `Option` field as None (as it did before the move); every other
    // field must be there
    for key in KEYS {
        let mut value: serde_json::Value = serde_json::from_str(DEFAULT_JSON).unwrap();
        value.as_object_mut().unwrap().remove(key);
        let read = serde_json::from_value::<Settings>(value);
        let mut expected = Settings::default();
        match key {
            "fallback" => expected.fallback = None,
            "time_limit" => expected.time_limit = None,
            "fixed_point_tol" => expected.params.fixed_point_tol = None,
            _ => {
                let e = read.unwrap_err().to_string();
                assert!(e.contains(&format!("missing field `{key}`")), "{e}");
                continue;
            }
        }
        assert_eq!(read.unwrap(), expected, "{key}");
    }
    // Settings has never refused unknown keys (no `deny_unknown_fields`), the nested shape
    // of the Rust struct included: it is read from the top-level keys only
    let mut value: serde_json::Value = serde_json::from_str(DEFAULT_JSON).unwrap();
    let nested = serde_json::to_value(changed().params).unwrap();
    let object = value.as_object_mut().unwrap();
    object.insert("params".into(), nested);
    object.insert("verbosity".into(), 3.into());
    assert_eq!(
        serde_json::from_value::<Settings>(value).unwrap(),
        Settings::default()
    );
}

#[test]
fn the_cancel_request_is_not_stored() {
    static FLAG: AtomicBool = AtomicBool::new(false);
    let s = Settings {
        cancel: Some(Cancel::new(&FLAG)),
        ..changed()
    };
    let json = serde_json::to_string(&s).unwrap();
    assert_eq!(json, serde_json::to_string(&changed()).unwrap());
    let back: Settings = serde_json::from_str(&json).unwrap();
    assert_eq!(back.cancel, None);
}
