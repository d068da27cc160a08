#!/usr/bin/env bash
# Instructions per row: the output benchmark's reference writer against busnoop, and busnoop's
# table writer against everything else (docs/performance-history.md, "What the targets ask, per row").
#
#   cargo build --release && cargo bench --bench output_limit --no-run
#   BUSNOOP_BENCH_MB=1 BUSNOOP_BENCH_PACKETS=10000 BUSNOOP_BENCH_RUNS=1 cargo bench --bench output_limit
#   tools/budget.sh target/bench-data tsv        # FORMAT: tsv, csv, jsonl or pretty
#   BUSNOOP=path/to/busnoop tools/budget.sh DIR FORMAT
#
# DIR holds the benchmark's captures (sport-*mib.bin, sbus-data-*, sbus-break-*,
# sbus-ether-*.pcap, sab-sync-*, sab-hdlc-*; the first of each is used). Per capture: busnoop's
# output in FORMAT, the reference writer (`output_limit --reference`, busnoop's first 1000 lines
# as its template, busnoop's output size) under cachegrind, busnoop under callgrind for
# `Table::write`'s inclusive count. Needs valgrind. Slow: about a minute per capture.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:?usage: tools/budget.sh DIR FORMAT}
fmt=${2:?usage: tools/budget.sh DIR FORMAT}
bin=${BUSNOOP:-target/release/busnoop}
ref=$(ls -t target/release/deps/output_limit-* 2>/dev/null | grep -v '\.d$' | head -1 || true)
[ -x "$bin" ] || { echo "budget: build $bin first (cargo build --release)" >&2; exit 2; }
[ -n "$ref" ] || { echo "budget: cargo bench --bench output_limit --no-run first" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
irefs() { grep 'I *refs' | awk '{gsub(",","",$NF); print $NF}'; }
echo "capture | rows | reference/row | busnoop/row | table/row | else/row | share"
# start byte (what the reference writer looks for), capture pattern, busnoop arguments
while read -r start pattern args; do
  file=$(ls "$dir"/$pattern 2>/dev/null | head -1 || true)
  [ -n "$file" ] || { echo "$pattern: not in $dir" >&2; continue; }
  # shellcheck disable=SC2086
  "$bin" $args --no-config "$file" -f "$fmt" >"$tmp/out" 2>/dev/null || true
  rows=$(($(wc -l <"$tmp/out") - 1))
  [ "$fmt" = jsonl ] && rows=$((rows + 1))
  [ "$rows" -gt 0 ] || { echo "$file: no rows" >&2; continue; }
  sed -n "2,1001p" "$tmp/out" >"$tmp/template"
  size=$(stat -c %s "$tmp/out")
  r=$(valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
    "$ref" --reference "$file" "$start" "$tmp/template" "$size" 2>&1 | irefs)
  # shellcheck disable=SC2086
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg" "$bin" $args --no-config "$file" \
    -f "$fmt" >/dev/null 2>&1 || true
  total=$(callgrind_annotate "$tmp/cg" 2>/dev/null | grep 'PROGRAM TOTALS' | awk '{gsub(",","",$1); print $1}')
  table=$(callgrind_annotate --inclusive=yes "$tmp/cg" 2>/dev/null |
    grep 'busnoop::sink::Table::write \[' | head -1 | awk '{gsub(",","",$1); print $1}')
  echo "$(basename "$file") $args | $rows | $((r / rows)) | $((total / rows)) | $((table / rows)) |" \
    "$(((total - table) / rows)) | $((100 * r / total)) %"
done <<'CAPTURES'
126 sport-*mib.bin sport
181 sbus-data-*mib.bin sbus --mode data
1 sbus-break-*mib.bin sbus --mode break
69 sbus-ether-*.pcap sbus
84 sab-sync-*mib.bin sab2
126 sab-hdlc-*mib.bin sab2
CAPTURES
