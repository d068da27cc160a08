#!/usr/bin/env python3
"""Checks busnoop's logic-analyzer reader against the real traces of ../shared/field/ that
cannot enter the test suite (GPL), and writes what it finds (docs/logic.md, "Checked against
real traces"):

* the iBus2PPM Saleae async-serial exports give the bytes of the .bin files beside them;
* sigrok's own Modbus decoder output (sigrok-test) for the sigrok-dumps sessions: every
  server-id and function annotation begins one bit after the start of one of busnoop's
  characters.

Usage: cargo build --release && tools/logic-check.py [FIELD_DIR]   (default ../shared/field)

Characters and their times come from `busnoop sbus --channel C --line L --record X.pcap`
(a recording holds the line's bytes with their times, one RTAC serial record each).
"""

import os
import re
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUSNOOP = os.environ.get("BUSNOOP", os.path.join(ROOT, "target/release/busnoop"))


def characters(trace, channel, line):
    """(µs, byte) of every character busnoop reads on `channel` of `trace`."""
    with tempfile.TemporaryDirectory() as d:
        rec = os.path.join(d, "rec.pcap")
        args = [BUSNOOP, "sbus", "--line", line, "--record", rec, "-o", os.devnull]
        if channel is not None:
            args += ["--channel", channel]
        subprocess.run(args + [trace], stderr=subprocess.DEVNULL, check=False)
        data = open(rec, "rb").read()
    out, pos, t0 = [], 24, None
    while pos + 16 <= len(data):
        sec, usec, incl, _ = struct.unpack_from("<IIII", data, pos)
        body = data[pos + 16 : pos + 16 + incl]
        pos += 16 + incl
        if len(body) < 12 or body[8] not in (1, 2, 3, 4, 7, 8, 9):
            if t0 is None:
                t0 = sec * 1_000_000 + usec  # the start record: time 0 of the trace
            continue
        us = sec * 1_000_000 + usec - (t0 or 0)
        out.extend((us, b) for b in body[12:])
    return out


def ibus(field):
    for txt, binary in [
        ("iBus-startup-sensors.txt", "ibus2ppm-startup.bin"),
        ("between-2-sensors.txt", "ibus2ppm-between-sensors.bin"),
    ]:
        got = bytes(b for _, b in characters(os.path.join(field, "ibus", txt), None, "115200-8N1"))
        want = open(os.path.join(field, "ibus", binary), "rb").read()
        print(f"iBUS {txt}: {len(got)} bytes, {binary} {len(want)}: "
              f"{'identical' if got == want else 'DIFFERENT'}")


def sigrok(field):
    d = os.path.join(field, "modbus")
    cases = [
        ("brainchild-io-16do.sr", "1", "19200-8E1", 1_000_000, "brainchild_io_16do", "cs-"),
        ("brainchild-io-16do.sr", "0", "19200-8E1", 1_000_000, "brainchild_io_16do", "sc-"),
        ("flowmeter_graph_tool.sr", "RXTX", "9600-8N1", 4_000_000, "flowmeter_graph_tool", "cs-"),
        ("wizmodbus.sr", "RX", "9600-8N1", 1_000_000, "wizmodbus", "cs-"),
        ("wizmodbus.sr", "TX", "9600-8N1", 1_000_000, "wizmodbus", "sc-"),
        ("wizmodbus.sr", "BA+", "9600-8N1", 1_000_000, "wizmodbus_bus", "cs-"),
    ]
    for sr, channel, line, rate, test, prefix in cases:
        baud = int(line.split("-")[0])
        bit = rate / baud
        starts = [us * rate // 1_000_000 for us, _ in characters(os.path.join(d, sr), channel, line)]
        marks = []
        for l in open(os.path.join(d, f"{test}.sigrok-test.output")):
            m = re.match(r'(\d+)-(\d+) modbus: (\S+): ', l)
            if m and m.group(3).startswith(prefix) and m.group(3).endswith(("server-id", "function")):
                marks.append(int(m.group(1)))
        # sigrok's annotation of a byte begins at its first data bit, one bit after the start.
        dev = [min(abs(s - (m - bit)) for s in starts) for m in marks] if starts else []
        ok = sum(1 for x in dev if x <= bit / 2)
        worst = max(dev) if dev else float("nan")
        print(f"sigrok {sr} channel {channel} ({prefix}): {ok}/{len(marks)} annotations one bit "
              f"after a character, worst {worst:.1f} samples (a bit is {bit:.1f})")


def main():
    field = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "..", "shared", "field")
    ibus(field)
    sigrok(field)


if __name__ == "__main__":
    main()
