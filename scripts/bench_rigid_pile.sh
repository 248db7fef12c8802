#!/usr/bin/env bash
# Rock-pile benchmark of the rigid-body simulator (issue #41, docs/rigid-bodies.md): N random
# convex rocks poured in a box (crates/coulomb-granular/src/validation/rigid.rs, rock_pile),
# S steps at tolerance 1e-4: time per step, share of collision detection (parry's BVH broad
# phase and contact manifolds), Gauss–Seidel sweeps per step, contacts per step.
# Usage: scripts/bench_rigid_pile.sh [ROCKS [STEPS]]   (default 200 rocks, 300 steps)
# Runs in the test profile (opt-level 2, as `cargo test`); say whether the machine was loaded
# next to any figure you keep.
set -euo pipefail
cd "$(dirname "$0")/.."
RIGID_PILE_ROCKS="${1:-200}" RIGID_PILE_STEPS="${2:-300}" \
  cargo test -p coulomb-granular --test integration unit::validation::rigid::bench -- --ignored --nocapture 2>&1 \
  | grep -E '^rocks '
