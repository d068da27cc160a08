#!/usr/bin/env bash
# Peak memory of every protocol at 64 MiB and at 1 GiB, with --stats (docs/performance.md,
# "Memory at 1 GiB"). Each capture is one of the fixtures repeated to the size (a pcap's
# packets repeated with their times moved on, so that time keeps increasing); busnoop writes
# TSV to /dev/null; peak memory is /usr/bin/time's maximum resident set size.
#
#   cargo build --release && tools/memory-1g.sh              # every protocol, 64 MiB and 1 GiB
#   SIZES="64 256" tools/memory-1g.sh crsf ghst               # sizes in MiB, some protocols
#   BUSNOOP=path/to/busnoop tools/memory-1g.sh
#
# Needs python3 and GNU time (/usr/bin/time). One capture at a time is on disk (in $TMPDIR).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${BUSNOOP:-target/release/busnoop}
sizes=${SIZES:-64 1024}
[ -x "$bin" ] || { echo "memory-1g: build $bin first (cargo build --release)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "memory-1g: needs GNU time in /usr/bin/time" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# name, fixture, busnoop's arguments before the file
cases='
sport    fixtures/sport-sample.bin          sport
sbus     fixtures/sbus-digimat.pcap         sbus
sab1     fixtures/sab1-session.bin          sab
sab2     fixtures/sab2-session.bin          sab
crsf     fixtures/crsf-mixed.bin            crsf
ghst     fixtures/ghst-mixed.bin            ghst
fport    fixtures/fport-v1-session.bin      fport
fport2   fixtures/fport2-session.bin        fport
futaba   fixtures/futaba-session.bin        futaba
ibus     fixtures/ibus-sensors.bin          ibus
modbus   fixtures/modbus-gen.bin            modbus
log      fixtures/edgetx-MODELE24-2014-07-11.csv      log
'

# Writes FILE repeated to MIB MiB into OUT.
repeat() {
  python3 - "$1" "$2" "$3" <<'PY'
import struct, sys
src, mib, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
data = open(src, 'rb').read()
want = mib << 20
with open(out, 'wb') as f:
    if data[:4] in (b'\xd4\xc3\xb2\xa1', b'\x4d\x3c\xb2\xa1'):
        # classic little-endian pcap: the header once, the records again and again, each
        # copy's times moved on past the previous copy's last time
        f.write(data[:24])
        recs, i = [], 24
        while i + 16 <= len(data):
            sec, frac, incl, orig = struct.unpack_from('<IIII', data, i)
            recs.append((sec, frac, data[i + 8:i + 16 + incl]))
            i += 16 + incl
        span = recs[-1][0] - recs[0][0] + 1
        done, shift = 24, 0
        while done < want:
            for sec, frac, rest in recs:
                f.write(struct.pack('<II', sec + shift, frac) + rest)
                done += 8 + len(rest)
            shift += span
    else:
        done = 0
        while done < want:
            f.write(data)
            done += len(data)
PY
}

printf '%-8s' protocol
for s in $sizes; do printf ' | %12s' "$s MiB"; done
printf ' | %s\n' 'CPU at the largest'
for want in "$@"; do
  grep -q "^$want " <<<"$cases" || { echo "memory-1g: no case $want" >&2; exit 2; }
done
while read -r name fixture args; do
  [ -n "$name" ] || continue
  if [ $# -gt 0 ] && ! printf '%s\n' "$@" | grep -qx "$name"; then continue; fi
  printf '%-8s' "$name"
  cpu=
  for s in $sizes; do
    rc=0
    repeat "$fixture" "$s" "$tmp/capture"
    # shellcheck disable=SC2086
    /usr/bin/time -o "$tmp/time" -f '%M %U %S' "$bin" $args --no-config --stats -f tsv \
      "$tmp/capture" >/dev/null 2>"$tmp/err" || rc=$?
    # the last line (GNU time puts "Command exited with non-zero status N" before it)
    read -r kb user sys < <(tail -1 "$tmp/time")
    if [ "$rc" -gt 1 ]; then echo; tail -3 "$tmp/err" >&2; exit 1; fi
    printf ' | %9.1f MB' "$(echo "$kb * 1.024 / 1000" | bc -l)"
    cpu=$(echo "$user + $sys" | bc -l)
    rm -f "$tmp/capture"
  done
  printf ' | %s s\n' "$cpu"
done <<<"$cases"
