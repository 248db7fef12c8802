#!/usr/bin/env bash
# mpirun on this one machine, with the flags Open MPI needs here (docs/distributed.md):
#   --allow-run-as-root  when run as root (Open MPI refuses root without it)
#   --oversubscribe      when more ranks are asked for than the machine has cores
# Everything else is passed to mpirun unchanged, e.g.
#   scripts/mpirun-local.sh -np 4 target/release/coulomb simulate box --beads 2000 --until-rest --output run/
# Other MPI implementations (MPICH's hydra) need neither flag: mpirun is run as given.
# The exit status is mpirun's (that of the ranks: 0, 1 for --until-rest at its step cap, ...).
set -euo pipefail

if ! command -v mpirun >/dev/null 2>&1; then
  echo "mpirun-local.sh: mpirun not found; install an MPI implementation (Debian/Ubuntu:" \
    "apt-get install openmpi-bin libopenmpi-dev libclang-dev) and build coulomb with" \
    "--features coulomb-cli/mpi (docs/distributed.md)" >&2
  exit 127
fi

# the number of ranks asked for: the first -np/-n/--np N (mpirun's options come before the
# program and its arguments); empty when not given (mpirun then starts one rank per slot)
ranks=""
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  case "${args[i]}" in
    -np | -n | --np | --n | -c)
      ranks="${args[i + 1]:-}"
      break
      ;;
    -np=* | --np=* | -n=* | --n=*)
      ranks="${args[i]#*=}"
      break
      ;;
  esac
done

# cores: the smaller of the CPUs this process may use and the physical cores (Open MPI counts
# one slot per physical core by default, not per hardware thread)
cores=$(nproc 2>/dev/null || echo 1)
if command -v lscpu >/dev/null 2>&1; then
  physical=$(lscpu -p=core,socket 2>/dev/null | grep -v '^#' | sort -u | wc -l)
  if [ "${physical:-0}" -gt 0 ] && [ "$physical" -lt "$cores" ]; then
    cores=$physical
  fi
fi

flags=()
if mpirun --version 2>&1 | grep -qiE 'open ?mpi|open ?rte'; then
  if [ "$(id -u)" = 0 ]; then
    flags+=(--allow-run-as-root)
  fi
  if [[ "$ranks" =~ ^[0-9]+$ ]] && [ "$ranks" -gt "$cores" ]; then
    flags+=(--oversubscribe)
  fi
fi
if [ ${#flags[@]} -gt 0 ]; then
  echo "mpirun-local.sh: mpirun ${flags[*]} (uid $(id -u), ${ranks:-default} ranks, $cores cores)" >&2
fi
exec mpirun ${flags[@]+"${flags[@]}"} "$@"
