//! `coulomb simulate` and `coulomb paper table1|fig8|fig9|scaling`, run as the built binary on
//! tiny sizes (a few beads, a few steps) so that the suite stays fast.

use crate::common;
use common::*;

use serde_json::Value;
use std::path::Path;

fn is_svg(path: &Path) {
    let text = std::fs::read_to_string(path).expect("the SVG was written");
    assert!(text.contains("<svg"), "{} is not an SVG", path.display());
}

#[test]
fn table1_tiny_runs_both_solvers_and_writes_markdown_and_stats() {
    let dir = temp_dir("paper-table1");
    let md = dir.join("table1.md");
    let out = coulomb(&[
        "paper",
        "table1",
        "--beads",
        "12",
        "--steps",
        "6",
        "--output",
        dir.to_str().unwrap(),
        "--markdown",
        md.to_str().unwrap(),
    ]);
    let stdout = ok(&out);
    let text = std::fs::read_to_string(&md).expect("markdown written");
    assert_eq!(text, stdout, "--markdown holds exactly what is printed");
    assert!(text.contains("coulomb paper table1 --beads 12 --steps 6"));
    for solver in ["pg", "ip"] {
        let row = format!("| 12 | {} | 6 |", solver.to_uppercase());
        assert!(text.contains(&row), "missing row {row} in\n{text}");
        let stats = read_json(&dir.join(format!("box_12_{solver}")).join("stats.json"));
        let steps = stats.as_array().expect("array of step records");
        assert_eq!(steps.len(), 6);
        for s in steps {
            let err = s["error"].as_f64().expect("error is reported per step");
            assert!(err.is_finite() && err >= 0.0);
            let contacts = s["contacts"].as_u64().unwrap();
            // the (6.1) rule or the cap of 20 ends every step with contacts
            let sub = s["details"]["subproblems"].as_u64().unwrap();
            assert!(sub <= 20);
            if contacts == 0 {
                assert_eq!(sub, 0);
            }
        }
    }
}

#[test]
fn fig8_from_table1_output_writes_svg_and_csv() {
    let dir = temp_dir("paper-fig8");
    ok(&coulomb(&[
        "paper",
        "table1",
        "--beads",
        "10",
        "--steps",
        "4",
        "--output",
        dir.to_str().unwrap(),
    ]));
    let svg = dir.join("fig8.svg");
    ok(&coulomb(&[
        "paper",
        "fig8",
        "--beads",
        "10",
        "--from",
        dir.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]));
    is_svg(&svg);
    let csv = std::fs::read_to_string(dir.join("fig8.csv")).expect("CSV beside the SVG");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "solver,step,contacts,solve_ms");
    // 4 steps for each of PG and IP
    assert_eq!(lines.len(), 1 + 8);
    assert_eq!(lines.iter().filter(|l| l.starts_with("PG,")).count(), 4);
    assert_eq!(lines.iter().filter(|l| l.starts_with("IP,")).count(), 4);
}

#[test]
fn fig9_tiny_stops_by_rule_6_1_or_the_cap() {
    let dir = temp_dir("paper-fig9");
    let svg = dir.join("fig9.svg");
    ok(&coulomb(&[
        "paper",
        "fig9",
        "--beads",
        "30",
        "--contacts",
        "10",
        "--mu",
        "0.2,0.8",
        "--max-outer",
        "6",
        "--max-steps",
        "60",
        "--svg",
        svg.to_str().unwrap(),
    ]));
    is_svg(&svg);
    let data = read_json(&dir.join("fig9.json"));
    let curves = data.as_array().expect("array of curves");
    assert_eq!(curves.len(), 2);
    for c in curves {
        assert!(c["contacts"].as_u64().unwrap() >= 10);
        let rule: Vec<f64> = c["rule_6_1"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let err = c["error"].as_array().unwrap();
        assert_eq!(rule.len(), err.len());
        assert!(!rule.is_empty() && rule.len() <= 6);
        // the loop ends when (6.1) ≤ 1e-4 or after 6 iterations
        let last = *rule.last().unwrap();
        assert!(last <= 1e-4 || rule.len() == 6, "{rule:?}");
        assert!(rule[..rule.len() - 1].iter().all(|&x| x > 1e-4), "{rule:?}");
    }
}

#[test]
fn scaling_tiny_writes_json_svg_and_markdown() {
    let dir = temp_dir("paper-scaling");
    let svg = dir.join("scaling.svg");
    let md = dir.join("scaling.md");
    ok(&coulomb(&[
        "paper",
        "scaling",
        "--beads",
        "10,40",
        "--settle",
        "4",
        "--window",
        "3",
        "--svg",
        svg.to_str().unwrap(),
        "--markdown",
        md.to_str().unwrap(),
    ]));
    is_svg(&svg);
    let data = read_json(&dir.join("scaling.json"));
    let points = data.as_array().expect("array of points");
    assert_eq!(points.len(), 2);
    assert_eq!(points[0]["beads"], 10);
    assert_eq!(points[1]["beads"], 40);
    for p in points {
        assert_eq!(p["timed_steps"], 3);
        assert_eq!(p["settle_steps"], 4);
        let solve = p["solve_ms"].as_f64().unwrap();
        let asm = p["assembly_ms"].as_f64().unwrap();
        let del = p["delassus_ms"].as_f64().unwrap();
        assert!(solve >= 0.0 && asm >= 0.0 && del >= 0.0);
        assert!((p["step_ms"].as_f64().unwrap() - (solve + asm)).abs() < 1e-9);
        // the box floor grows with the number of beads
        assert!(p["box_x"].as_f64().unwrap() > 0.1);
    }
    assert!(points[1]["box_x"].as_f64().unwrap() > points[0]["box_x"].as_f64().unwrap());
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(text.contains("| 40 |"));
}

#[test]
fn simulate_box_layout_overrides_are_checked() {
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "5",
        "--steps",
        "2",
        "--box-side",
        "0.01",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--box-side"));
    let out = coulomb(&[
        "simulate",
        "box",
        "--beads",
        "8",
        "--steps",
        "3",
        "--box-side",
        "0.5",
        "--layer-pitch",
        "0.3",
        "--drop-base",
        "0.2",
        "--json",
    ]);
    let v: Value = serde_json::from_str(ok(&out).trim()).expect("one JSON summary");
    assert_eq!(v["bodies"], 8);
    assert_eq!(v["steps"], 3);
    // dropped from 0.2 m: no bead reaches the ground within 3 steps (it falls ≈ 0.02 m), so at
    // most the four walls touch each bead
    assert!(v["mean_contacts"].as_f64().unwrap() <= 2.0 * 8.0);
}

#[test]
fn scaling_accurate_converges_and_matches_across_threads() {
    let dir = temp_dir("paper-scaling-accurate");
    let svg = dir.join("acc.svg");
    let md = dir.join("acc.md");
    ok(&coulomb(&[
        "paper",
        "scaling",
        "--accurate",
        "--beads",
        "60",
        "--threads",
        "1,2",
        "--settle",
        "6",
        "--window",
        "4",
        "--svg",
        svg.to_str().unwrap(),
        "--markdown",
        md.to_str().unwrap(),
    ]));
    is_svg(&svg);
    let data = read_json(&dir.join("acc.json"));
    let points = data.as_array().expect("array of points");
    assert_eq!(points.len(), 2);
    for p in points {
        assert_eq!(p["beads"], 60);
        assert_eq!(p["timed_steps"], 4);
        assert_eq!(p["steps_all"], 10);
        assert_eq!(p["converged_all"], 10, "{p}");
        assert!(p["max_error"].as_f64().unwrap() <= 1e-4);
        assert!(p["contacts"].as_f64().unwrap() > 0.0);
    }
    // bitwise the same final state for 1 and 2 threads
    assert_eq!(points[0]["state_hash"], points[1]["state_hash"]);
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(
        text.contains("| 60 | 2 |") && !text.contains("| NO |"),
        "{text}"
    );
}
