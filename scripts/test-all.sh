#!/usr/bin/env bash
# The project's one test command (README, .ci/run): the Rust workspace tests, then the Python
# package crates/coulomb-py built into a virtual environment and its pytest suite.
#
#   bash scripts/test-all.sh
#
# Environment: COULOMB_PY_VENV (default target/py-venv), PYTHON (default python3).
# The Python extension is built in cargo's dev profile with opt-level 2 (the settings of the test
# profile of Cargo.toml), not a release build of faer/Clarabel (over 6 min). It does not reuse
# what `cargo test --workspace` built: cargo resolves the features of a build of the binding crate
# alone (`-p`) without the other members' dev-dependencies (serde's `alloc`, zerocopy's `derive`),
# so faer, Clarabel and coulomb compile again (measured: about 2 min).
set -euo pipefail
cd "$(dirname "$0")/.."

cargo test --workspace

VENV=${COULOMB_PY_VENV:-target/py-venv}
PYTHON=${PYTHON:-python3}
if [ ! -x "$VENV/bin/python" ]; then
  "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
  "maturin>=1.7,<2" numpy scipy pytest h5py
(
  cd crates/coulomb-py
  VIRTUAL_ENV="$PWD/../../$VENV" PATH="$PWD/../../$VENV/bin:$PATH" \
    CARGO_PROFILE_DEV_OPT_LEVEL=2 maturin develop --quiet
)

# the CLI binary `cargo test` built, for the CLI-equality tests
export COULOMB_CLI="$PWD/target/debug/coulomb"
# pytest's exit code fails the script: 1 for failures, 5 when no test was collected
# (set -e makes both fail the run; nothing is masked)
"$VENV/bin/python" -m pytest crates/coulomb-py/tests -q -rs

# the distributed feature (docs/distributed.md): its unit tests and `coulomb simulate` under
# `mpirun -np 2`, when an MPI implementation is installed (.ci/run installs one); last, because
# its build replaces target/debug/coulomb by the MPI-enabled binary
if command -v mpicc >/dev/null && command -v mpirun >/dev/null; then
  cargo test --workspace --features coulomb-cli/mpi --lib --test cli_mpi -- distributed
else
  echo "skipped: the distributed (mpi) tests need mpicc and mpirun (apt-get install libopenmpi-dev openmpi-bin libclang-dev)"
fi
