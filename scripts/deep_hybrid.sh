#!/usr/bin/env bash
# Issue #54, third route: an interior point (Clarabel) on the paper's convex inner problem
# (3.15), then projected Gauss–Seidel (pgs + fused) warm-started from its r, against pgs + fused
# cold, on deep heap steps dumped by the simulator. Every verdict is Solver::solve's on the
# problem as stored (crates/coulomb-lab/examples/deep_hybrid.rs). One thread
# (RAYON_NUM_THREADS=1) so that the CPU seconds of each phase are a measure of its work on a
# loaded machine; the wall times are printed too.
#
#   scripts/deep_hybrid.sh OUT.jsonl VARIANTS FILE...       e.g.
#   scripts/deep_hybrid.sh deep-4.jsonl pgs,ipm1,ipm2,gs300:ipm1,ipm1+newton /tmp/deep/fc4/step_0000{30,45,59}.hdf5
#   TABLE_ONLY=1 scripts/deep_hybrid.sh OUT.jsonl        only the table of a run already there
# The files: `coulomb simulate box --beads 1600 (4 layers) | 3200 (8 layers) --box-side 2.5
# --steps 60 --threads 1 --frames-every 0 --dump-fclib DIR` (h = 0.02).
# Variants: pgs (cold), ipmK (K fixed-point iterations s ← ‖u_T‖ with (3.15) by Clarabel to
# 1e-6, from s = 0, then pgs + fused from the last r), ipmK+newton (then the semismooth Newton
# end game on (3.9), at most 20 steps, then pgs + fused), gsN:ipmK (N sweeps of pgs + fused
# first, s from that point, then ipmK).
set -euo pipefail
out=$1
root=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${TABLE_ONLY:-}" ]; then
  variants=$2
  shift 2
  [ -n "${NO_BUILD:-}" ] || (cd "$root" && cargo build --workspace --example deep_hybrid)
  : >"$out"
  for f in "$@"; do
    RAYON_NUM_THREADS=1 "$root/target/debug/examples/deep_hybrid" "$f" 1e-4 "$variants" >>"$out"
  done
fi
python3 - "$out" <<'PY'
import json, os, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
base = {}
for j in rows:
    if j["variant"] == "pgs":
        base[j["file"]] = j
print("| file | variant | sweeps before | IPM iterations | err after IPM | Newton (steps, err) | sweeps after | CPU s before pgs | CPU s pgs | CPU s total | × pgs cold (CPU) | status, err (stored problem) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for j in rows:
    f = os.path.basename(os.path.dirname(j["file"])) + "/" + os.path.basename(j["file"])
    pre = j.get("pre_sweeps_error")
    pre_s = f"{pre[0]} (err {pre[1]:.1e})" if pre else "0"
    ipm = "+".join(str(k) for k in j["ipm_iterations"]) or "–"
    ipm_err = f"{j['ipm_errors'][-1]:.1e}" if j["ipm_errors"] else "–"
    newton = f"{j['newton'][0]}, {j['newton'][2]:.1e}" if j.get("newton") else "–"
    b = base.get(j["file"])
    ratio = f"{j['cpu_total_s'] / b['cpu_total_s']:.2f}" if b and b["cpu_total_s"] > 0 else "–"
    print(f"| {f} | {j['variant']} | {pre_s} | {ipm} | {ipm_err} | {newton} | {j['sweeps']} | "
          f"{j['cpu_before_pgs_s'] + j['cpu_newton_s']:.1f} | {j['cpu_pgs_s']:.1f} | {j['cpu_total_s']:.1f} | "
          f"{ratio} | {j['status']}, {j['error']:.2e} |")
PY
