//! The `random` class: global problems with a block-diagonal SPD M (random 3 × 3 blocks
//! A Aᵀ + ½ I), a sparse random H (each contact acts on one or two random "bodies" of three
//! dofs), random f, μ ∈ [0.1, 1], in d = 2 and 3, and their local forms.
//!
//! When m ≤ n, w is random (existence is then not established by the construction: H may
//! have a kernel when several contacts act on one body). When m > n, w = s − Hᵀ v₀ with v₀ random and s in the interior of
//! the dual cone (μ ‖s_T‖ < s_N): then u = Hᵀ v₀ + w = s, so (4.4) holds and a solution exists.

use super::{both_forms, Item, Preset, Rng};
use coulomb::{CscMatrix, GlobalProblem};

fn problem(d: usize, contacts: usize, n: usize, rng: &mut Rng) -> anyhow::Result<GlobalProblem> {
    let m = d * contacts;
    // M: 3 × 3 (last one smaller) SPD blocks A Aᵀ + ½ I
    let (mut mr, mut mc, mut mv) = (Vec::new(), Vec::new(), Vec::new());
    let mut start = 0;
    while start < n {
        let k = (n - start).min(3);
        let a: Vec<f64> = (0..k * k).map(|_| rng.normal()).collect();
        for i in 0..k {
            for j in 0..k {
                let mut s: f64 = (0..k).map(|l| a[i * k + l] * a[j * k + l]).sum();
                if i == j {
                    s += 0.5;
                }
                mr.push(start + i);
                mc.push(start + j);
                mv.push(s);
            }
        }
        start += k;
    }
    let mmat = CscMatrix::from_triplets(n, n, &mr, &mc, &mv)?;
    // H: each contact touches one or two bodies of three dofs
    let bodies = n.div_ceil(3);
    let (mut hr, mut hc, mut hv) = (Vec::new(), Vec::new(), Vec::new());
    for c in 0..contacts {
        let first = rng.below(bodies);
        let mut touched = vec![first];
        if bodies > 1 && rng.below(3) > 0 {
            let mut other = rng.below(bodies);
            if other == first {
                other = (first + 1) % bodies;
            }
            touched.push(other);
        }
        for b in touched {
            for dof in 3 * b..(3 * b + 3).min(n) {
                for j in 0..d {
                    hr.push(dof);
                    hc.push(d * c + j);
                    hv.push(rng.normal());
                }
            }
        }
    }
    let hmat = CscMatrix::from_triplets(n, m, &hr, &hc, &hv)?;
    let f: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let mu: Vec<f64> = (0..contacts).map(|_| rng.uniform(0.1, 1.0)).collect();
    let w = if m <= n {
        (0..m).map(|_| rng.normal()).collect()
    } else {
        let v0: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let mut s = vec![0.0; m];
        for (c, sc) in s.chunks_mut(d).enumerate() {
            sc[0] = rng.uniform(0.5, 1.5);
            let bound = 0.5 * sc[0] / mu[c];
            for x in &mut sc[1..] {
                *x = rng.uniform(-1.0, 1.0) * bound / (d as f64 - 1.0).sqrt();
            }
        }
        let hv0 = hmat.mul_t_vec(&v0);
        s.iter().zip(&hv0).map(|(a, b)| a - b).collect()
    };
    Ok(GlobalProblem::new(d as i64, mmat, hmat, f, w, mu)?)
}

/// Writes the class.
pub fn generate(
    preset: Preset,
    seed: u64,
    sink: &mut dyn FnMut(Item) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    // (d, contacts, dofs)
    let cases: Vec<(usize, usize, usize)> = match preset {
        Preset::Small => vec![(2, 5, 12), (3, 8, 30), (3, 20, 30), (2, 15, 12)],
        Preset::Full => {
            let mut v = Vec::new();
            for d in [2, 3] {
                for c in [5, 20, 100, 400] {
                    let m = d * c;
                    // under-determined (m < n) and over-determined (m > n) contact sets
                    v.push((d, c, m + m / 2 + 3));
                    v.push((d, c, (m / 2).max(3)));
                }
            }
            v.iter().flat_map(|&x| [x, x]).collect()
        }
    };
    for (k, (d, contacts, n)) in cases.into_iter().enumerate() {
        let mut rng = Rng::new(seed.wrapping_mul(7_777_777).wrapping_add(k as u64));
        let g = problem(d, contacts, n, &mut rng)?;
        let m = d * contacts;
        let existence = (m > n).then(|| {
            (
                "exists",
                "(4.4): w = s - H^T v0 with s in the interior of the dual cone".to_string(),
            )
        });
        both_forms(
            "random",
            &format!("d{d}-c{contacts}-n{n}-{k}"),
            g,
            existence,
            serde_json::json!({"d": d, "contacts": contacts, "dofs": n, "index": k}),
            sink,
        )?;
    }
    Ok(())
}
