#!/usr/bin/env bash
# Regenerates fixtures/sbus-digimat.pcap and fixtures/sbus-digimat-tshark.tsv: a real
# Ether-S-Bus session between two digimat-saia processes (server station 10 on UDP 5050,
# client on UDP 15050), captured by tcpdump on `lo` inside a private network namespace that has
# nothing but a loopback interface. Needs root, tcpdump, tshark (4.0.17 tested) and Python 3.
# Not used by the tests: they read the files it wrote.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
fixtures="$here/../../fixtures"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/venv"
"$work/venv/bin/pip" install -q digimat-saia==0.1.71
cp "$here/peer.py" "$work/"
cd "$work"
unshare -n sh -c '
  ip link set lo up
  tcpdump -i lo -U -w sbus.pcap udp port 5050 2>tcpdump.log & TD=$!
  sleep 1
  venv/bin/python peer.py server 16 > server.log 2>&1 & SRV=$!
  sleep 2
  venv/bin/python peer.py client
  wait $SRV
  sleep 1
  kill $TD; wait $TD || true
'
cp sbus.pcap "$fixtures/sbus-digimat.pcap"
tshark -2 -r sbus.pcap --disable-heuristic pana_udp -T fields -E header=y -E separator=/t \
  -E occurrence=a -E aggregator=, \
  -e frame.number -e frame.time_relative -e ip.src -e udp.srcport -e ip.dst -e udp.dstport \
  -e sbus.len -e sbus.vers -e sbus.proto -e sbus.seq -e sbus.att -e sbus.destination \
  -e sbus.cmd -e sbus.rcount -e sbus.wcount -e sbus.fio_count -e sbus.addr_RTC \
  -e sbus.addr_IOF -e sbus.data_rtc -e sbus.data_iof -e sbus.nakcode -e sbus.crc.status \
  -e sbus.response_to -e sbus.response_in -e _ws.col.Info \
  > "$fixtures/sbus-digimat-tshark.tsv"
echo "wrote $fixtures/sbus-digimat.pcap and $fixtures/sbus-digimat-tshark.tsv"
