#!/usr/bin/env bash
# Regenerates the FCLIB files of data/ (data/README.md says what each is). Every file is written
# by coulomb itself, deterministically: running this again gives the same bytes (the SHA-256
# sums printed at the end are those listed in data/README.md).
#
#   bash scripts/make-data.sh                 # builds target/release/coulomb first
#   COULOMB=target/debug/coulomb bash scripts/make-data.sh   # any built binary
set -euo pipefail
cd "$(dirname "$0")/.."

B=${COULOMB:-}
if [ -z "$B" ]; then
  cargo build --release -q -p coulomb-cli
  B=target/release/coulomb
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p data

# The test corpus (docs/corpus.md), seed 1: the classes granular and nonsym (which also writes
# the rigid boxes it perturbs). Three of its files are kept under shorter names.
"$B" corpus --output "$tmp" --preset small --seed 1 --class granular --class nonsym >/dev/null 2>&1
cp "$tmp/granular--box-n120-mu0.3-settled-s40-local.hdf5" data/box-local.hdf5
cp "$tmp/granular--box-n120-mu0.3-settled-s40-global.hdf5" data/box-global.hdf5
cp "$tmp/nonsym--pile-2x2x2-mu0.8-rest-local-asym1e-5.hdf5" data/pile-nonsym-local.hdf5

# Painlevé's rod (2.12) at θ = 60°, μ = 0.8, u0 = 1: a solution exists, by (4.1).
"$B" example painleve --theta 60 --mu 0.8 --u0 1 --output data/painleve.hdf5 >/dev/null

# each file solves to the default tolerance 1e-8 (exit status 0), in well under a second
for f in data/box-local.hdf5 data/box-global.hdf5 data/pile-nonsym-local.hdf5 data/painleve.hdf5; do
  "$B" solve "$f" --time-limit 10 >/dev/null
done
sha256sum data/*.hdf5
