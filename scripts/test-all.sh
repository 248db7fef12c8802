#!/usr/bin/env bash
# The project's one test command (README, .ci/run): the Rust workspace tests, then the Python
# package crates/coulomb-py built into a virtual environment and its pytest suite, then the MPI
# tests where MPI is installed. Ends with one line "N passed, N failed, N skipped" (docs/testing.md).
#
#   bash scripts/test-all.sh
#
# Environment: COULOMB_PY_VENV (default target/py-venv), PYTHON (default python3).
set -euo pipefail
cd "$(dirname "$0")/.."

mkdir -p target
LOG=target/test-all.log
: >"$LOG"

# The closing line, also when a step fails: totals over cargo's "test result:" lines (passed,
# failed, ignored) and pytest's summary line (passed; failed and errors; skipped). Tests that
# need ../shared are ignored (Rust) or skipped (pytest) without it, never counted as passed.
summary() {
  local status=$?
  awk '
    /^test result: / {
      for (i = 1; i <= NF; i++) {
        w = $(i + 1); sub(/[;,]$/, "", w)
        if (w == "passed") p += $i; else if (w == "failed") f += $i; else if (w == "ignored") s += $i
      }
      next
    }
    / in [0-9.]+s( \([0-9:]+\))?( =+)?$/ && /(passed|failed|skipped|error)/ {
      line = $0; gsub(/=+/, "", line); sub(/ in [0-9.]+s.*$/, "", line)
      n = split(line, parts, ", ")
      for (k = 1; k <= n; k++) {
        split(parts[k], kv, " "); c = kv[1] + 0; w = kv[2]
        if (w == "passed") p += c; else if (w == "failed" || w == "error" || w == "errors") f += c
        else if (w == "skipped") s += c
      }
    }
    END { printf "%d passed, %d failed, %d skipped\n", p, f, s }
  ' "$LOG"
  exit "$status"
}
trap summary EXIT

# One build for every stage. Where an MPI implementation is installed (.ci/run installs one) the
# whole suite is built with the distributed feature `mpi` (docs/distributed.md) from the start, so
# that its tests at the end reuse every artifact; building it only for the last stage compiled
# coulomb-granular, the CLI, the lab and the bindings a second time (2 min 22 s of CI, docs/testing.md).
# The feature adds code paths (run under mpirun) and changes no default behaviour.
FEATURES=()
if command -v mpicc >/dev/null && command -v mpirun >/dev/null; then
  FEATURES=(--features coulomb-cli/mpi)
fi
# A fresh build gains nothing from incremental compilation's caches (they cost time and disk:
# docs/testing.md); a developer's own setting is kept.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

# The Python side first, so that it overlaps the build: the virtual environment (seconds), then
# its packages installed in the background (downloads and unpacking, ~15 s, mostly waiting)
# while cargo compiles; the script waits for them before pytest.
VENV=${COULOMB_PY_VENV:-target/py-venv}
PYTHON=${PYTHON:-python3}
if [ ! -x "$VENV/bin/python" ]; then
  "$PYTHON" -m venv "$VENV"
fi
PY="$(cd "$VENV" && pwd)/bin/python"
"$PY" -m pip install --quiet --disable-pip-version-check numpy scipy pytest h5py \
  >target/pip-install.log 2>&1 &
PIP_PID=$!
# pyo3 reads the interpreter from PYO3_PYTHON and rebuilds when it changes: one value for every
# cargo command below, so that each reuses the artifacts of the first.
export PYO3_PYTHON="$PY"

# The packages: the workspace without coulomb-bench, the criterion benchmarks' crate, which has
# no tests: its library would compile criterion and its dependencies (22 s of CI, more on a
# fresh clone) that only `cargo bench` needs. It is left out of every cargo command below, so
# that all of them resolve the same features (with it in one and not another, plotters, whose
# features criterion widens, and coulomb-lab compiled a second time).
PACKAGES=(--workspace --exclude coulomb-bench)

# One build of everything the tests use, the Python extension included: `--lib` adds the binding
# crate's cdylib and pyo3 (not built by `cargo test --tests`, since that crate has no tests of
# its own), compiled in the same cargo run as the rest, on the core the long compile of
# coulomb-granular leaves idle at the end, instead of afterwards on their own (~40 s).
cargo build "${PACKAGES[@]}" "${FEATURES[@]}" --lib --tests --profile test 2>&1 | tee -a "$LOG"

# Unit and integration tests, then the doc tests: `--tests` leaves out the examples, which a
# plain `cargo test` would also compile and link at opt-level 2 only to check that they build
# (one of them took over a minute); clippy --all-targets (.ci/run) checks that they compile.
# --no-fail-fast: every test binary runs even when an earlier one fails, so that the counts
# are complete.
# Three test threads on the two cores of CI (a developer's RUST_TEST_THREADS is kept): the
# command-line tests spend much of their time waiting on the processes they start (coulomb,
# mpirun), and took 35 s instead of 43 s; the other binaries, busy computing, took the same
# time (docs/testing.md).
RUST_TEST_THREADS="${RUST_TEST_THREADS:-3}" \
  cargo test "${PACKAGES[@]}" "${FEATURES[@]}" --tests --no-fail-fast 2>&1 | tee -a "$LOG"
cargo test "${PACKAGES[@]}" "${FEATURES[@]}" --doc --no-fail-fast 2>&1 | tee -a "$LOG"

# The extension: the binding crate built above by cargo within the workspace, in the test
# profile, reusing every artifact the tests use. `maturin develop` builds the crate alone, for
# which cargo resolves other features (the other members' dev-dependencies turn on serde's
# `alloc` and zerocopy's `derive`), and so compiled faer, Clarabel and coulomb a second time
# (~2 min of CI). The library then goes where `maturin develop` puts it in this mixed
# Rust/Python layout: next to the package's Python sources (python/coulomb/_coulomb.abi3.so,
# git-ignored), which a .pth file in the venv puts on Python's path.
lib=target/debug/lib_coulomb.so
[ -f "$lib" ] || lib=target/debug/lib_coulomb.dylib
cp "$lib" crates/coulomb-py/python/coulomb/_coulomb.abi3.so
if ! wait "$PIP_PID"; then
  cat target/pip-install.log
  echo "error: pip could not install numpy, scipy, pytest and h5py into $VENV"
  exit 1
fi
site=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
echo "$PWD/crates/coulomb-py/python" >"$site/coulomb-dev.pth"

# the CLI binary `cargo test` built, for the CLI-equality tests
export COULOMB_CLI="$PWD/target/debug/coulomb"
# pytest's exit code fails the script: 1 for failures, 5 when no test was collected
# (set -e and pipefail make both fail the run; nothing is masked)
"$PY" -m pytest crates/coulomb-py/tests -q -rs 2>&1 | tee -a "$LOG"

# The distributed feature's tests (its unit tests and `coulomb simulate` under `mpirun -np 2`,
# tests/cli_mpi.rs) ran above with the rest when MPI is installed.
if [ ${#FEATURES[@]} -eq 0 ]; then
  echo "note: the distributed (mpi) tests were not built: they need mpicc and mpirun (apt-get install libopenmpi-dev openmpi-bin libclang-dev)"
fi
