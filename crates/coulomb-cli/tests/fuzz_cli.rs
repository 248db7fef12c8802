//! A fuzz harness of the command line: random subcommands with random option values (NaN, ±∞,
//! 0, negative, 10³⁰, huge integers, text), random files (valid, byte-mutated, garbage,
//! missing, a directory) and random outputs (new, existing, the input itself, unwritable),
//! run through the built binary under a wall-clock cap. Checked for every case:
//!
//! - no panic (status 101 or "panicked" on stderr) and no hang (the cap);
//! - the exit status is one of the documented ones (0, 1, 2, 3, 4);
//! - no input file is changed (bytes compared before and after);
//! - a `solve` that says converged wrote a /solution whose error, recomputed by
//!   `coulomb::fclib::evaluate` on the file as read, is ≤ tol.
//!
//! `fuzz_cli_short` runs a fixed number of cases (CI); `fuzz_cli_long` (ignored) runs for
//! `COULOMB_CLI_FUZZ_SECS` seconds (default 600), with the binary `COULOMB_BIN` when set.
//! Results: docs/fuzz.md.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CAP: Duration = Duration::from_secs(90);

/// xorshift64*: a small deterministic generator (no extra dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
    fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
}

const NUMBERS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "0",
    "-0",
    "-1",
    "1e30",
    "1e19",
    "1e-300",
    "1",
    "2",
    "0.5",
    "-0.01",
    "abc",
    "",
    "1e308",
    "18446744073709551616",
    "3",
    "1e-8",
    "0.3",
    "7",
];
const SMALL: &[&str] = &["1", "2", "3", "0", "-1", "nan", "1e30", "x", "100000000"];
/// Step counts: no large valid value (a long run on purpose is not a hang).
const STEPS: &[&str] = &[
    "1",
    "2",
    "0",
    "-1",
    "nan",
    "1e30",
    "x",
    "18446744073709551616",
];

struct Files {
    dir: PathBuf,
    inputs: Vec<PathBuf>,
}

/// Input files of the campaign: copies of data/'s three smallest files, byte-mutated copies,
/// garbage.
fn files(tag: &str) -> Option<Files> {
    let dir = common::temp_dir(tag);
    let mut inputs = Vec::new();
    for name in ["box-local", "painleve", "box-global"] {
        let to = dir.join(format!("{name}.hdf5"));
        std::fs::copy(common::data_file(&format!("{name}.hdf5")), &to).ok()?;
        inputs.push(to);
    }
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let base = std::fs::read(&inputs[0]).ok()?;
    for k in 0..6 {
        let mut b = base.clone();
        for _ in 0..1 + rng.below(4) {
            let i = b.len() / 4 + rng.below(b.len() * 3 / 4 - 8);
            let specials = [f64::NAN, f64::INFINITY, 1e308, -1.0, 1e155, 0.0];
            let x = specials[rng.below(specials.len())];
            let i = i / 8 * 8;
            b[i..i + 8].copy_from_slice(&x.to_le_bytes());
        }
        let to = dir.join(format!("mutated{k}.hdf5"));
        std::fs::write(&to, b).ok()?;
        inputs.push(to);
    }
    let garbage = dir.join("garbage.hdf5");
    std::fs::write(&garbage, b"garbage, not HDF5").ok()?;
    inputs.push(garbage);
    Some(Files { dir, inputs })
}

/// One random command line; returns the arguments and the output file it names (if any).
fn command(rng: &mut Rng, f: &Files, case: u64) -> (Vec<String>, Option<PathBuf>) {
    let input = |rng: &mut Rng| -> String {
        match rng.below(12) {
            0 => f.dir.join("missing.hdf5").display().to_string(),
            1 => f.dir.display().to_string(),
            _ => f.inputs[rng.below(f.inputs.len())].display().to_string(),
        }
    };
    let output = |rng: &mut Rng, ext: &str| -> PathBuf {
        match rng.below(6) {
            0 => f.inputs[rng.below(f.inputs.len())].clone(),
            1 => PathBuf::from(format!("/proc/x.{ext}")),
            2 => f.dir.join("no-such-folder").join(format!("x.{ext}")),
            3 => f.dir.join(format!("existing.{ext}")),
            _ => f.dir.join(format!("out{case}.{ext}")),
        }
    };
    let num = |rng: &mut Rng| rng.pick(NUMBERS).to_string();
    let mut a: Vec<String> = Vec::new();
    let mut out = None;
    let opt =
        |a: &mut Vec<String>, rng: &mut Rng, name: &str, p: f64, v: &dyn Fn(&mut Rng) -> String| {
            if rng.chance(p) {
                a.push(name.to_string());
                a.push(v(rng));
            }
        };
    match rng.below(8) {
        0 => {
            a.push("info".into());
            for _ in 0..1 + rng.below(3) {
                a.push(input(rng));
            }
        }
        1 => {
            a.push("error".into());
            a.push(input(rng));
            opt(&mut a, rng, "--tol", 0.7, &num);
            opt(&mut a, rng, "--solution", 0.3, &|r: &mut Rng| input(r));
        }
        2 => {
            a.push("solve".into());
            a.push(input(rng));
            opt(&mut a, rng, "--tol", 0.5, &num);
            opt(&mut a, rng, "--max-outer", 0.3, &|r: &mut Rng| {
                r.pick(SMALL).to_string()
            });
            opt(&mut a, rng, "--time-limit", 0.5, &num);
            opt(&mut a, rng, "--inner", 0.4, &|r: &mut Rng| {
                r.pick(&["ipm", "apgd", "pgs", "faceted", "x"]).to_string()
            });
            opt(&mut a, rng, "--outer", 0.4, &|r: &mut Rng| {
                r.pick(&["fixed-point", "anderson", "fused"]).to_string()
            });
            if rng.chance(0.6) {
                let o = output(rng, "hdf5");
                a.push("--output".into());
                a.push(o.display().to_string());
                out = Some(o);
            }
        }
        3 => {
            a.push("check".into());
            a.push(input(rng));
            opt(&mut a, rng, "--tol", 0.5, &num);
            opt(&mut a, rng, "--certificate-tol", 0.5, &num);
        }
        4 => {
            a.push("example".into());
            a.push(
                rng.pick(&["crushed-ball", "rectangle", "moving-obstacle", "painleve"])
                    .into(),
            );
            opt(&mut a, rng, "--mu", 0.7, &num);
            if a[1] == "painleve" {
                for o in ["--theta", "--mu", "--u0"] {
                    a.push(o.into());
                    a.push(num(rng));
                }
            }
            let o = output(rng, "hdf5");
            a.push("--output".into());
            a.push(o.display().to_string());
            out = Some(o);
        }
        5 => {
            a.push("simulate".into());
            a.push(rng.pick(&["box", "funnel", "nowhere"]).into());
            // small runs only: beads and steps always given
            a.push("--beads".into());
            a.push(rng.pick(SMALL).to_string());
            a.push("--steps".into());
            a.push(rng.pick(STEPS).to_string());
            for o in [
                "--mu",
                "--dt",
                "--restitution",
                "--theta",
                "--tol",
                "--fp-tol",
                "--gamma",
            ] {
                opt(&mut a, rng, o, 0.2, &num);
            }
            if rng.chance(0.5) {
                a.push("--json".into());
            }
        }
        6 => {
            a.push("bench".into());
            a.push(input(rng));
            a.push("--solvers".into());
            a.push(
                rng.pick(&["pgs", "apgd", "pgs,apgd+anderson", "newton"])
                    .into(),
            );
            opt(&mut a, rng, "--tol", 0.4, &num);
            // always a short time limit (the default, 60 s per solve, over a folder is a long
            // run on purpose, not a hang)
            a.push("--time-limit".into());
            a.push(rng.pick(&["0.2", "1", "0", "-1", "nan", "1e30"]).into());
            opt(&mut a, rng, "--repeat", 0.3, &|r: &mut Rng| {
                r.pick(&["1", "2", "0", "-1", "x"]).to_string()
            });
            if rng.chance(0.6) {
                let o = output(rng, "json");
                a.push("--json".into());
                a.push(o.display().to_string());
                out = Some(o);
            }
        }
        _ => {
            // paper and demo only with an output that cannot be written or a bad number,
            // so that they end at once (their real runs take minutes)
            if rng.chance(0.5) {
                a.push("paper".into());
                a.push(rng.pick(&["table1", "scaling"]).into());
                a.push("--markdown".into());
                a.push("/proc/x.md".into());
                opt(&mut a, rng, "--tol", 0.5, &num);
            } else {
                a.push("demo".into());
                a.push("--beads".into());
                a.push(rng.pick(&["0", "-1", "nan", "100000000", "1e30"]).into());
                a.push("--output".into());
                a.push(f.dir.join(format!("demo{case}")).display().to_string());
            }
        }
    }
    if rng.chance(0.4)
        && !a.iter().any(|x| x == "--json")
        && ["info", "error", "solve", "check"].contains(&a[0].as_str())
    {
        a.push("--json".into());
    }
    (a, out)
}

#[derive(Default, Debug)]
struct Tally {
    cases: u64,
    by_status: [u64; 5],
    panics: u64,
    hangs: u64,
    bad_status: u64,
    inputs_changed: u64,
    false_converged: u64,
    notes: Vec<String>,
}

fn run_one(args: &[String]) -> (Option<i32>, String, String, bool) {
    // COULOMB_BIN: a copy of the binary for long runs, so that rebuilding does not swap it
    let bin = std::env::var("COULOMB_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_coulomb").into());
    let mut child = Command::new(bin)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let start = Instant::now();
    // drain the pipes on threads so that a chatty child cannot block
    let mut so = child.stdout.take().unwrap();
    let mut se = child.stderr.take().unwrap();
    let t1 = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut so, &mut s);
        s
    });
    let t2 = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut se, &mut s);
        s
    });
    let mut hung = false;
    let status = loop {
        if let Ok(Some(st)) = child.try_wait() {
            break st.code();
        }
        if start.elapsed() > CAP {
            let _ = child.kill();
            let _ = child.wait();
            hung = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (
        status,
        t1.join().unwrap_or_default(),
        t2.join().unwrap_or_default(),
        hung,
    )
}

fn campaign(seed: u64, n: u64, budget: Duration) -> Option<Tally> {
    let f = files(&format!("fuzz-cli-{seed}"))?;
    let before: Vec<Vec<u8>> = f.inputs.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut t = Tally::default();
    let start = Instant::now();
    while t.cases < n && start.elapsed() < budget {
        let case = t.cases;
        t.cases += 1;
        std::fs::write(f.dir.join("existing.hdf5"), b"old").unwrap();
        std::fs::write(f.dir.join("existing.json"), b"old").unwrap();
        let (args, out) = command(&mut rng, &f, case);
        let (status, stdout, stderr, hung) = run_one(&args);
        let line = args.join(" ");
        if hung {
            t.hangs += 1;
            t.notes.push(format!("HANG: {line}"));
            continue;
        }
        match status {
            Some(c @ 0..=4) => t.by_status[c as usize] += 1,
            Some(101) => {
                t.panics += 1;
                t.notes.push(format!("PANIC: {line}: {stderr}"));
            }
            other => {
                t.bad_status += 1;
                t.notes.push(format!("status {other:?}: {line}: {stderr}"));
            }
        }
        if stderr.contains("panicked") && status != Some(101) {
            t.panics += 1;
            t.notes.push(format!("PANIC: {line}: {stderr}"));
        }
        // a converged solve wrote a real solution
        if args[0] == "solve" && status == Some(0) {
            if let Some(o) = &out {
                let tol = args
                    .iter()
                    .position(|a| a == "--tol")
                    .and_then(|i| args[i + 1].parse::<f64>().ok())
                    .unwrap_or(1e-8);
                // the problem as stored, exactly as `solve` read it
                let problem = coulomb::fclib::read(Path::new(&args[1]));
                let sol = coulomb::fclib::read_solution(o);
                let ok = match (problem, sol) {
                    (Ok(p), Ok(Some(s))) => coulomb::fclib::evaluate(&p.problem, &s)
                        .is_ok_and(|e| e.measure.error.is_finite() && e.measure.error <= tol),
                    _ => false,
                };
                if !ok {
                    t.false_converged += 1;
                    t.notes.push(format!("FALSE CONVERGED: {line}: {stdout}"));
                }
            }
        }
        for (p, b) in f.inputs.iter().zip(&before) {
            if std::fs::read(p).ok().as_ref() != Some(b) {
                // an input of this run (named as such, not only as the output) must not change;
                // a file named only as the output of a command without inputs may be replaced
                let named = args.iter().filter(|x| Path::new(x.as_str()) == p).count();
                let only_output = out.as_deref() == Some(p.as_path()) && named == 1;
                if !only_output {
                    t.inputs_changed += 1;
                    t.notes
                        .push(format!("INPUT CHANGED {}: {line}", p.display()));
                }
                std::fs::write(p, b).unwrap();
            }
        }
    }
    let _ = std::fs::remove_dir_all(&f.dir);
    Some(t)
}

fn check(t: &Tally) {
    assert!(
        t.panics == 0
            && t.hangs == 0
            && t.bad_status == 0
            && t.inputs_changed == 0
            && t.false_converged == 0,
        "{t:?}\n{}",
        t.notes.join("\n")
    );
}

#[test]
fn fuzz_cli_short() {
    let Some(t) = campaign(1, 60, Duration::from_secs(120)) else {
        return;
    };
    println!("{t:?}");
    assert!(t.cases >= 20);
    // both ends of the statuses are reached: runs that succeed and inputs that are refused
    assert!(t.by_status[0] > 0 && t.by_status[2] > 0, "{t:?}");
    check(&t);
}

#[test]
#[ignore = "long CLI fuzz run: COULOMB_CLI_FUZZ_SECS (default 600)"]
fn fuzz_cli_long() {
    let secs: u64 = std::env::var("COULOMB_CLI_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(600);
    let Some(t) = campaign(1000, u64::MAX, Duration::from_secs(secs)) else {
        return;
    };
    println!(
        "final: {} cases, statuses 0/1/2/3/4 = {:?}, panics {}, hangs {}, other statuses {}, inputs changed {}, false converged {}",
        t.cases, t.by_status, t.panics, t.hangs, t.bad_status, t.inputs_changed, t.false_converged
    );
    for n in &t.notes {
        println!("{n}");
    }
    check(&t);
}
