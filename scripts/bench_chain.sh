#!/usr/bin/env bash
# The 1 000-link chain benchmark of issue 53 (docs/joints.md, "Benchmark"): a chain of LINKS
# bars (0.1 x 0.02 x 0.02 m) on revolute joints, laid along a wave 5 cm above the floor,
# falls onto it (examples/scenes/rigid/make_joint_scenes.py chain). Runs `coulomb simulate`
# for STEPS steps and prints its summary (--json), the wall-clock and CPU seconds per step, the
# per-step detection and solve seconds of stats.json, and, where `perf` works, the share of
# the CPU samples in the joints' code (coulomb_granular::rigid::joints, the Gauss–Seidel's
# joint updates, the step's solve of all the equality rows together, rigid::step::equality,
# and the library's elimination of the equality rows, coulomb::equality), in the contacts'
# (the Gauss–Seidel's contact updates and the contact law), in faer (the sparse Cholesky of
# the step's equality rows, and the library's factorizations), in the library's own linear
# algebra (coulomb::linalg) and in the collision detection (parry3d).
#
# Usage: scripts/bench_chain.sh [LINKS] [STEPS]     (defaults 1000 and 250)
# Environment: COULOMB (the binary; default: build the dev profile, opt-level 2, and use
#   target/debug/coulomb), CARGO_PROFILE=release (build and use target/release/coulomb).
set -euo pipefail
cd "$(dirname "$0")/.."
links=${1:-1000}
steps=${2:-250}
if [ -z "${COULOMB:-}" ]; then
  if [ "${CARGO_PROFILE:-dev}" = release ]; then
    cargo build -q --release --workspace --bins
    COULOMB=target/release/coulomb
  else
    cargo build -q --workspace --bins
    COULOMB=target/debug/coulomb
  fi
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 examples/scenes/rigid/make_joint_scenes.py chain "$links" "$tmp/chain.toml" "$steps"
perf_cmd=()
if command -v perf > /dev/null && perf record -q -o "$tmp/probe.data" true > /dev/null 2>&1; then
  perf_cmd=(perf record -q -F 499 -o "$tmp/perf.data")
fi
TIMEFORMAT='%R %U'
{ time "${perf_cmd[@]}" "$COULOMB" simulate "$tmp/chain.toml" --output "$tmp/out" \
    --frames-every "$steps" --json > "$tmp/summary.json" 2> /dev/null || true; } 2> "$tmp/time"
cat "$tmp/summary.json"
python3 - "$tmp" "$steps" "${#perf_cmd[@]}" <<'PY'
import json, subprocess, sys
tmp, steps, perf = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]) > 0
real, user = (float(x) for x in open(f"{tmp}/time").read().split())
rows = json.load(open(f"{tmp}/out/stats.json"))
det = sum(r["details"]["detection_seconds"] for r in rows) / len(rows)
sol = sum(r["solve_seconds"] for r in rows) / len(rows)
lib = sum(1 for r in rows if r["details"]["method"] == "nsgs+library")
print(f"steps {len(rows)}: wall {1e3 * real / steps:.1f} ms/step, cpu {1e3 * user / steps:.1f} ms/step "
      f"(whole run); detection {1e3 * det:.2f} ms/step, solve {1e3 * sol:.1f} ms/step; "
      f"steps finished by the library: {lib}")
if perf:
    out = subprocess.run(["perf", "report", "-i", f"{tmp}/perf.data", "--sort", "sym", "--stdio"],
                         capture_output=True, text=True).stdout
    groups = {"joints": 0.0, "contacts": 0.0, "faer": 0.0, "library linalg": 0.0,
              "detection": 0.0, "other": 0.0}
    for line in out.splitlines():
        if line.startswith("#") or "%" not in line:
            continue
        pct, sym = line.split("%", 1)
        share = float(pct)
        if ("rigid::joints" in sym or "update_joint" in sym or "coulomb::equality" in sym
                or "step::equality" in sym):
            g = "joints"
        elif "Problem::update" in sym or "contact" in sym or "cone::" in sym:
            g = "contacts"
        elif "faer" in sym:
            g = "faer"
        elif "coulomb::linalg" in sym or "gemm" in sym:
            g = "library linalg"
        elif "parry" in sym:
            g = "detection"
        else:
            g = "other"
        groups[g] += share
    print("share of CPU samples: " + ", ".join(f"{k} {v:.1f} %" for k, v in groups.items()))
    print("top symbols:")
    print("\n".join(l for l in out.splitlines() if l.strip() and not l.startswith("#"))[:1200])
PY
