//! The existence report as JSON: `coulomb check --json`, and the `existence` field of
//! `coulomb solve --json` when a solve fails.

use coulomb::existence::{Conclusion, Criterion, CriterionReport, ExistenceReport};
use std::path::Path;

/// The criteria in the order they are printed: the necessary one first.
pub const ORDER: [Criterion; 5] = [
    Criterion::C4_5,
    Criterion::C4_1,
    Criterion::C4_4,
    Criterion::C4_6,
    Criterion::C5_1,
];

/// The JSON of `--json`: {"file", "criteria": {"4.1": {"verdict", "certificate_residual"}, …},
/// "conclusion": "exists" | "none" | "unknown", "by": "4.1" | … | null, "note": why the
/// conclusion is weaker than a criterion that holds (non-symmetric W or M), or null}.
pub fn to_json(file: &Path, report: &ExistenceReport, certificates: bool) -> serde_json::Value {
    let mut criteria = serde_json::Map::new();
    for criterion in ORDER {
        let label = criterion.label();
        let c: &CriterionReport = report.criteria.get(criterion);
        // the same columns as the table: verdict, residual, margin, detail
        let mut o = serde_json::json!({
            "verdict": c.verdict,
            "certificate_residual": c.certificate_residual,
            "margin": c.margin,
            "detail": c.detail,
        });
        if certificates {
            o["certificate_kind"] = serde_json::json!(c.certificate_kind);
            o["certificate"] = serde_json::json!(c.certificate);
        }
        criteria.insert(label.to_string(), o);
    }
    let by = match &report.conclusion {
        Conclusion::Exists { by, .. } | Conclusion::None { by, .. } => Some(by.label()),
        Conclusion::Unknown => None,
    };
    serde_json::json!({
        "file": file.display().to_string(),
        "kind": report.kind,
        "contacts": report.contacts,
        "criteria": criteria,
        "conclusion": report.conclusion.label(),
        "by": by,
        "note": report.note,
    })
}
