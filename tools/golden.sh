#!/usr/bin/env bash
# Golden outputs for refactors that must not change behaviour.
#
# Runs target/release/busnoop over every file in fixtures/ and fuzz/seeds/ with each subcommand
# (sport; sbus --mode auto/data/break; sab2 --framing auto/sync/hdlc; futaba; ibus; fport
# --variant auto/v1/v2; crsf; ghst; modbus) and each format
# (tsv, csv, jsonl, pretty --color always), with --raw and --stats, and stores stdout, stderr
# and the exit code of every run in one directory (sbus and sport once more with --time abs
# --utc, for the capture times of pcaps, recordings and logs). Prints one sha256 over that directory.
#
#   tools/golden.sh [OUT_DIR]          # default: target/golden
#   GOLDEN_CORPUS=1 tools/golden.sh    # also the fuzz corpora of sbus_serial, sab, sbus_ether,
#                                      # recording, crsf and futaba (tsv only)
#   GOLDEN_BENCH=1 tools/golden.sh     # also the benchmark captures in target/bench-data (tsv,
#                                      # stored as the sha256 of stdout; run the benches first)
#   BUSNOOP=path/to/busnoop tools/golden.sh   # another binary (e.g. a copy of the old one)
#
# The pretty runs write into files, which are never fitted to a terminal's width (only a pretty
# table on a terminal is, unless --no-fit): fitting does not change these outputs.
#
# Build first (cargo build --release); compare the printed hash before and after a change, or
# diff -r two output directories to see what moved.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${BUSNOOP:-target/release/busnoop}
out=${1:-target/golden}
[ -x "$bin" ] || { echo "golden: build $bin first (cargo build --release)" >&2; exit 2; }
rm -rf "$out"
mkdir -p "$out"

commands=(
  "sport"
  "sbus --mode auto" "sbus --mode data" "sbus --mode break"
  "sab2 --framing auto" "sab2 --framing sync" "sab2 --framing hdlc"
  "futaba" "ibus"
  "fport" "fport --variant v1" "fport --variant v2"
  "crsf" "ghst" "modbus"
)
formats=("tsv" "csv" "jsonl" "pretty --color always")

run() { # name, file, args...
  local name=$1 file=$2
  shift 2
  local rc=0
  "$bin" "$@" --raw --stats "$file" >"$out/$name.out" 2>"$out/$name.err" </dev/null || rc=$?
  echo "$rc" >"$out/$name.rc"
}

slug() { echo "$*" | tr ' /' '__' | tr -s '_' | sed 's/--//g'; }

files=()
while IFS= read -r f; do files+=("$f"); done < <(find fixtures fuzz/seeds -type f | sort)
for f in "${files[@]}"; do
  for c in "${commands[@]}"; do
    for fmt in "${formats[@]}"; do
      # shellcheck disable=SC2086
      run "$(slug "$f $c $fmt")" "$f" $c -f $fmt
    done
  done
done

# Wall-clock times (taken from pcap and recording headers, EdgeTX log lines) in UTC.
for f in "${files[@]}"; do
  for c in "sbus" "sport"; do
    run "$(slug "$f $c time abs utc")" "$f" $c --time abs --utc -f tsv
  done
done

if [ "${GOLDEN_CORPUS:-0}" = 1 ]; then
  for f in fuzz/corpus/sbus_ether/* fuzz/corpus/recording/*; do
    run "$(slug "$f sbus")" "$f" sbus --time abs --utc -f tsv
  done
  for f in fuzz/corpus/recording/*; do
    run "$(slug "$f sport")" "$f" sport --time abs --utc -f tsv
  done
  for f in fuzz/corpus/sbus_serial/*; do
    for c in "sbus --mode auto" "sbus --mode data" "sbus --mode break"; do
      # shellcheck disable=SC2086
      run "$(slug "$f $c")" "$f" $c -f tsv
    done
  done
  for f in fuzz/corpus/sab/*; do
    # shellcheck disable=SC2086
    run "$(slug "$f sab2")" "$f" sab2 -f tsv
  done
  for p in crsf futaba; do
    for f in fuzz/corpus/$p/*; do
      run "$(slug "$f $p")" "$f" $p -f tsv
    done
  done
fi

if [ "${GOLDEN_BENCH:-0}" = 1 ]; then
  for f in target/bench-data/*; do
    case "$(basename "$f")" in
      sab-*) cmds=("sab2") ;;
      sbus-ether*) cmds=("sbus") ;;
      sbus-*) cmds=("sbus --mode auto" "sbus --mode data" "sbus --mode break") ;;
      sport-*) cmds=("sport") ;;
      *) continue ;;
    esac
    for c in "${cmds[@]}"; do
      name=$(slug "$f $c")
      rc=0
      # shellcheck disable=SC2086
      "$bin" $c -f tsv --raw --stats "$f" 2>"$out/$name.err" </dev/null | sha256sum >"$out/$name.out.sha256" || rc=$?
      echo "$rc" >"$out/$name.rc"
    done
  done
fi

echo "$(find "$out" -type f | wc -l) files in $out"
(cd "$out" && find . -type f -print0 | sort -z | xargs -0 sha256sum) | sha256sum | cut -d' ' -f1
