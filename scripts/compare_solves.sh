#!/usr/bin/env bash
# Compares two builds of the CLI, solve by solve: `coulomb solve FILE --json --output OUT.hdf5`
# (plus the extra solve options given after the files, e.g. `--inner apgd --outer fixed-point`)
# on every FILE; the JSON must be the same except its timing (`solve_time_s`) and the output
# files byte-identical. Prints one line per file and a summary; exit 1 on any difference.
#
#   scripts/compare_solves.sh OLD_BIN NEW_BIN FILE... [-- SOLVE_OPTIONS...]
set -u
old=$1 new=$2; shift 2
files=() opts=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then shift; opts=("$@"); break; fi
  files+=("$1"); shift
done
work=$(mktemp -d)
strip='import json,sys; d=json.load(sys.stdin); d.pop("solve_time_s",None); print(json.dumps(d,sort_keys=True))'
same=0 differ=0
for f in "${files[@]}"; do
  b=$(basename "$f" .hdf5)
  "$old" solve "$f" --json --output "$work/$b.old.hdf5" "${opts[@]}" >"$work/$b.old.json" 2>/dev/null
  "$new" solve "$f" --json --output "$work/$b.new.hdf5" "${opts[@]}" >"$work/$b.new.json" 2>/dev/null
  jo=$(python3 -c "$strip" <"$work/$b.old.json") jn=$(python3 -c "$strip" <"$work/$b.new.json")
  if [ "$jo" = "$jn" ] && cmp -s "$work/$b.old.hdf5" "$work/$b.new.hdf5"; then
    same=$((same + 1)); echo "same    $f"
  else
    differ=$((differ + 1)); echo "DIFFERS $f"; diff <(echo "$jo") <(echo "$jn") | head -4
  fi
done
rm -rf "$work"
echo "$((same + differ)) files${opts:+ (${opts[*]})}: $same identical, $differ different"
[ "$differ" -eq 0 ]
