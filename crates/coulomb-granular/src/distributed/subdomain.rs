//! The nonsmooth Gauss–Seidel sweep of one subdomain, on the body-level step problem of
//! [`crate::nsgs`] built over the rank's owned and ghost beads.
//!
//! For contact i between bead A and B (bead or obstacle), u_i = J_A v_A + J_B v_B + w_i and
//! W_ii = J_A M_A⁻¹ J_Aᵀ + J_B M_B⁻¹ J_Bᵀ ([`crate::nsgs::ContactRow`]); one update
//! ([`crate::nsgs::update_contact`]) solves Coulomb's law (2.9) for contact i with the others
//! frozen and moves v_A, v_B by M⁻¹ J ᵀ Δr_i. A subdomain sweep visits the rank's contacts in
//! global id order and also records, per bead, the velocity change it made, so that the
//! changes of ghost beads can be sent to their owners (module [`super`]).

use crate::nsgs::{update_contact, ContactRow, StepProblem, UpdateSums};

/// One Gauss–Seidel sweep over the contacts of `p` in order: r (3 per contact) and v (per
/// local bead) updated in place; `dv` accumulates each bead's velocity change. The update of a
/// contact whose beads are all `relaxed` (per local bead: the caller marks owned beads away
/// from the interface) is over-relaxed by `omega` as on one process
/// ([`crate::nsgs::update_contact`]); the others keep ω = 1. Returns the sums of the pairs
/// (uᵢ, rᵢ) met before each update (the error proxy of [`crate::nsgs`]).
///
/// The rows of `split` (ascending row index) replace those of `p`: contacts on a bead that
/// the sweeps of several ranks move, seen with that bead's mass divided by their number
/// ([`SplitRow`]).
pub fn sweep(
    p: &StepProblem,
    split: &[SplitRow],
    r: &mut [f64],
    v: &mut [[f64; 6]],
    dv: &mut [[f64; 6]],
    omega: f64,
    relaxed: &[bool],
) -> UpdateSums {
    let mut sums = UpdateSums::default();
    let mut next = split.iter().peekable();
    for (i, row) in p.rows.iter().enumerate() {
        let (a, b) = (row.a, row.b);
        let (row, minv_a, minv_b) = match next.next_if(|s| s.i == i) {
            Some(s) => (&s.row, &s.minv_a, &s.minv_b),
            None => (
                row,
                &p.inv_mass[a],
                b.map_or(&p.inv_mass[a], |b| &p.inv_mass[b]),
            ),
        };
        let inner = relaxed[a] && b.is_none_or(|b| relaxed[b]);
        let om = if inner { omega } else { 1.0 };
        let old_a = v[a];
        let mut va = old_a;
        let mut ri = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
        match b {
            Some(b) => {
                let old_b = v[b];
                let mut vb = old_b;
                sums = sums
                    + update_contact(row, minv_a, &mut va, Some((minv_b, &mut vb)), &mut ri, om);
                v[b] = vb;
                for d in 0..6 {
                    dv[b][d] += vb[d] - old_b[d];
                }
            }
            None => {
                sums = sums + update_contact(row, minv_a, &mut va, None, &mut ri, om);
            }
        }
        v[a] = va;
        for d in 0..6 {
            dv[a][d] += va[d] - old_a[d];
        }
        r[3 * i..3 * i + 3].copy_from_slice(&ri);
    }
    sums
}

/// Contact `i` of a subdomain's problem as its sweep sees it when a bead of it is moved by the
/// sweeps of k > 1 ranks (mass splitting): that bead's M⁻¹ multiplied by k in the update and
/// in W_ii. Each rank's change to the bead is then k times too large and the owner averages
/// them, so the velocity change is M⁻¹ Σ J ᵀ Δr with the true mass and M v = H r + f is kept;
/// each rank's step on the shared bead is damped instead of the ranks' steps adding up.
#[derive(Debug, Clone)]
pub struct SplitRow {
    /// the contact's index in the problem
    pub i: usize,
    /// the row with W_ii and W_ii⁻¹ of the split masses
    pub row: ContactRow,
    /// M⁻¹ of bead A as the sweep sees it
    pub minv_a: [f64; 6],
    /// M⁻¹ of bead B as the sweep sees it (A's for an obstacle contact, unused)
    pub minv_b: [f64; 6],
}

/// The [`SplitRow`]s of `p` for `share[l]`, the number of ranks whose sweeps move local bead
/// l (0 or 1: not split). A row whose split W_ii would not be positive definite (never seen:
/// scaling M⁻¹ up keeps it so) keeps its true masses; the sweeps then move that bead by a
/// slightly wrong amount until the next exact refresh of v from r, which the error is always
/// computed after.
pub fn split_rows(p: &StepProblem, share: &[f64]) -> Vec<SplitRow> {
    let k = |l: usize| share.get(l).copied().unwrap_or(1.0).max(1.0);
    let scaled = |l: usize| p.inv_mass[l].map(|m| m * k(l));
    p.rows
        .iter()
        .enumerate()
        .filter(|(_, row)| k(row.a) > 1.0 || row.b.is_some_and(|b| k(b) > 1.0))
        .filter_map(|(i, row)| {
            let minv_a = scaled(row.a);
            let minv_b = row.b.map_or(minv_a, scaled);
            let mut split = row.clone();
            split.set_delassus(&minv_a, row.b.map(|_| &minv_b))?;
            Some(SplitRow {
                i,
                row: split,
                minv_a,
                minv_b,
            })
        })
        .collect()
}

/// imp += H r restricted to the subdomain's contacts: J_Aᵀ r_i and J_Bᵀ r_i added to the
/// impulses of A and B.
pub fn impulses(p: &StepProblem, r: &[f64], imp: &mut [[f64; 6]]) {
    for (i, row) in p.rows.iter().enumerate() {
        let ri = &r[3 * i..3 * i + 3];
        let side = |j: [[f64; 6]; 3], x: &mut [f64; 6]| {
            for (d, xd) in x.iter_mut().enumerate() {
                *xd += j[0][d] * ri[0] + j[1][d] * ri[1] + j[2][d] * ri[2];
            }
        };
        side(row.jacobian(false), &mut imp[row.a]);
        if let Some(b) = row.b {
            side(row.jacobian(true), &mut imp[b]);
        }
    }
}

/// u_i = J_A v_A + J_B v_B + w_i of every contact, with the entries of H as stored.
pub fn velocities(p: &StepProblem, v: &[[f64; 6]]) -> Vec<[f64; 3]> {
    p.rows
        .iter()
        .map(|row| row.velocity(&v[row.a], row.b.map(|b| &v[b])))
        .collect()
}

/// Sums over the contacts for the error of docs/error.md, every entry multiplied by `alpha`
/// first (a power of two, exact): [Σ‖eᵢ‖², Σ‖qᵢ‖², Σ‖rᵢ‖², Σ‖uᵢ‖²].
pub fn error_sums(
    p: &StepProblem,
    q: &[[f64; 3]],
    r: &[f64],
    u: &[[f64; 3]],
    alpha: f64,
) -> [f64; 4] {
    let mut s = [0.0; 4];
    for (i, row) in p.rows.iter().enumerate() {
        let mut rs = [0.0; 3];
        let mut us = [0.0; 3];
        for k in 0..3 {
            rs[k] = r[3 * i + k] * alpha;
            us[k] = u[i][k] * alpha;
            let qk = q[i][k] * alpha;
            s[1] += qk * qk;
            s[2] += rs[k] * rs[k];
            s[3] += us[k] * us[k];
        }
        s[0] += coulomb::law::contact_residual_sq(row.mu, &us, &rs);
    }
    s
}

/// Largest magnitude of the entries of r, u and q (NaN when one is NaN).
pub fn max_entry(q: &[[f64; 3]], r: &[f64], u: &[[f64; 3]]) -> f64 {
    let mut m = 0.0f64;
    for x in q.iter().flatten().chain(r).chain(u.iter().flatten()) {
        if x.is_nan() {
            return f64::NAN;
        }
        m = m.max(x.abs());
    }
    m
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::assembly::{assemble, StepData};
    use crate::contact::{detect, Activation};
    use crate::scene::Scene;

    /// A 120-bead box after 40 steps, and the problem of its next step.
    struct Settled {
        sim: crate::Simulation,
        contacts: Vec<crate::contact::Contact>,
        data: StepData,
        p: StepProblem,
        /// M⁻¹ f
        v_free: Vec<[f64; 6]>,
        /// H ᵀ M⁻¹ f + w
        q: Vec<[f64; 3]>,
    }

    fn settled_box() -> Settled {
        let mut sim =
            crate::Simulation::new(Scene::Box.build(120, 3), crate::Params::default()).unwrap();
        for _ in 0..40 {
            sim.step().unwrap();
        }
        let h = sim.params.h;
        let contacts = detect(&sim.world, sim.time, h, &Activation::accurate());
        assert!(contacts.len() > 50, "{}", contacts.len());
        let data = StepData {
            h,
            t_end: sim.time + h,
            restitution: 0.2,
            mu: 0.3,
            close_gaps: true,
        };
        let p = StepProblem::new(&sim.world, &contacts, &data).unwrap();
        let v_free: Vec<[f64; 6]> =
            p.f.iter()
                .zip(&p.inv_mass)
                .map(|(f, m)| std::array::from_fn(|d| f[d] * m[d]))
                .collect();
        let q = velocities(&p, &v_free);
        Settled {
            sim,
            contacts,
            data,
            p,
            v_free,
            q,
        }
    }

    /// Sweeps (over-relaxed from the second on, as on one process) keep M v = H r + f, record
    /// the velocity changes exactly, and drive the error of docs/error.md (from these sums)
    /// below 1e-4, in agreement with the library's measure on the assembled problem.
    pub fn distributed_subdomain_sweeps_converge_and_keep_the_balance() {
        let Settled {
            sim,
            contacts,
            data,
            p,
            v_free,
            q,
        } = settled_box();
        let world = &sim.world;
        let mut r = vec![0.0; 3 * p.rows.len()];
        let mut v = v_free.clone();
        let mut dv = vec![[0.0; 6]; v.len()];
        let err = |r: &[f64], v: &[[f64; 6]]| {
            let s = error_sums(&p, &q, r, &velocities(&p, v), 1.0);
            s[0].sqrt() / s[1].sqrt().max(s[2].sqrt()).max(s[3].sqrt())
        };
        let e0 = err(&r, &v);
        let owned = vec![true; v.len()];
        for k in 0..300 {
            sweep(
                &p,
                &[],
                &mut r,
                &mut v,
                &mut dv,
                if k == 0 { 1.0 } else { 1.5 },
                &owned,
            );
        }
        let e1 = err(&r, &v);
        assert!(e1 < 1e-4 && e1 < e0 * 1e-2, "{e0} → {e1}");
        let mut imp = vec![[0.0; 6]; v.len()];
        impulses(&p, &r, &mut imp);
        for j in 0..v.len() {
            for d in 0..6 {
                let exact = (p.f[j][d] + imp[j][d]) * p.inv_mass[j][d];
                assert!((v[j][d] - exact).abs() <= 1e-9 * (1.0 + exact.abs()), "{j}");
                let change = v[j][d] - v_free[j][d];
                assert!((dv[j][d] - change).abs() <= 1e-9 * (1.0 + change.abs()));
            }
        }
        let g = assemble(world, &contacts, &data).unwrap();
        let flat: Vec<f64> = v.iter().flatten().copied().collect();
        let u = g.velocity(&flat);
        let qflat: Vec<f64> = q.iter().flatten().copied().collect();
        let lib = coulomb::law::error_measure(3, &g.mu, &r, &u, coulomb::law::norm(&qflat));
        assert!(
            (lib.error - e1).abs() <= 1e-9 + 1e-6 * e1,
            "{} vs {e1}",
            lib.error
        );
        assert!(max_entry(&q, &r, &velocities(&p, &v)) > 0.0);
    }

    /// Two subdomains in one process, as two ranks run them: each sweeps its half of the
    /// contacts from the same v with the beads both move split ([`split_rows`]), then every
    /// bead takes the mean of the changes (the owner's rule in `super`). M v = H r + f holds
    /// after every round without any exact refresh, and the error falls below 1e-4.
    pub fn split_sweeps_of_two_subdomains_keep_the_balance_and_converge() {
        let Settled { p, v_free, q, .. } = settled_box();
        let nb = p.inv_mass.len();
        let half = p.rows.len() / 2;
        let mut parts = [p.clone(), p.clone()];
        parts[0].rows.truncate(half);
        parts[1].rows.drain(..half);
        let mut share = vec![0.0; nb];
        for part in &parts {
            let mut touched = vec![false; nb];
            for row in &part.rows {
                touched[row.a] = true;
                if let Some(b) = row.b {
                    touched[b] = true;
                }
            }
            for (s, t) in share.iter_mut().zip(touched) {
                *s += f64::from(u8::from(t));
            }
        }
        let shared = share.iter().filter(|&&k| k > 1.0).count();
        assert!(shared > 0, "no bead in both halves");
        let splits = [split_rows(&parts[0], &share), split_rows(&parts[1], &share)];
        assert!(!splits[0].is_empty() && !splits[1].is_empty());
        for (part, split) in parts.iter().zip(&splits) {
            for s in split {
                let row = &part.rows[s.i];
                let k = share[row.a].max(row.b.map_or(1.0, |b| share[b]));
                assert!(
                    k > 1.0 && s.row.w_ii[0] > row.w_ii[0],
                    "row {} not split",
                    s.i
                );
            }
        }
        let mut r = [vec![0.0; 3 * half], vec![0.0; 3 * (p.rows.len() - half)]];
        let mut v = v_free.clone();
        let relaxed = vec![false; nb];
        let whole = |r: &[Vec<f64>; 2]| -> Vec<f64> { r.concat() };
        let err = |r: &[f64], v: &[[f64; 6]]| {
            let s = error_sums(&p, &q, r, &velocities(&p, v), 1.0);
            s[0].sqrt() / s[1].sqrt().max(s[2].sqrt()).max(s[3].sqrt())
        };
        let mut rounds = 0;
        while err(&whole(&r), &v) > 1e-5 && rounds < 2000 {
            let mut total = vec![[0.0; 6]; nb];
            for s in 0..2 {
                let mut vs = v.clone();
                let mut dv = vec![[0.0; 6]; nb];
                sweep(
                    &parts[s], &splits[s], &mut r[s], &mut vs, &mut dv, 1.0, &relaxed,
                );
                for (t, d) in total.iter_mut().zip(&dv) {
                    for k in 0..6 {
                        t[k] += d[k];
                    }
                }
            }
            for (j, t) in total.iter().enumerate() {
                let k = share[j].max(1.0);
                for d in 0..6 {
                    v[j][d] += t[d] / k;
                }
            }
            rounds += 1;
            // the balance M v = H r + f after every round
            let mut imp = vec![[0.0; 6]; nb];
            impulses(&p, &whole(&r), &mut imp);
            for j in 0..nb {
                for d in 0..6 {
                    let exact = (p.f[j][d] + imp[j][d]) * p.inv_mass[j][d];
                    assert!(
                        (v[j][d] - exact).abs() <= 1e-9 * (1.0 + exact.abs()),
                        "round {rounds}, bead {j}"
                    );
                }
            }
        }
        let e = err(&whole(&r), &v);
        assert!(e <= 1e-5, "{rounds} rounds: error {e}");
    }
}
