#!/usr/bin/env python3
"""Compares busnoop's Modbus decoding of a capture with what sigrok's Modbus decoder prints for it.

Run outside the test suite (sigrok-test's outputs are GPL and stay out of the repository):

    busnoop modbus fixtures/modbus-wizmodbus-bus.bin --line 9600-8N1 -f jsonl > /tmp/b.jsonl
    tools/modbus-sigrok-compare.py ../shared/field/modbus/wizmodbus_bus.sigrok-test.output /tmp/b.jsonl

The sigrok output has lines `start-end modbus: <class>: "<text>"`; a frame's annotations run from
`cs-server-id` (client to server: a request) or `sc-server-id` (a response) to its `-crc` line. Only
frames sigrok marks "CRC correct" count (on a single bus channel sigrok reads every frame both
ways, and only one reading checks). Both sides are brought to one form per frame, on wire
addresses (sigrok's 5-digit references are left out):

    Request 1 0x03 start=1000 count=2
    Response 1 0x03 1000=21094 1001=22279

and the two lists are compared in order. Prints the counts and every difference; exits 1 on a
difference. Standard library only.
"""

import json
import re
import sys


def sigrok_frames(path):
    frames = []
    current = {}
    for line in open(path, encoding="utf-8"):
        m = re.match(r'(\d+)-(\d+) modbus: (cs|sc)-([a-z-]+): "(.*)"$', line.strip())
        if not m:
            continue
        start, _, side, what, text = m.groups()
        if what == "server-id":
            current[side] = {"side": side, "fields": [], "slave": text, "at": int(start)}
            continue
        f = current.get(side)
        if f is None:
            continue
        if what == "crc":
            if text == "CRC correct":
                frames.append(f)
            current.pop(side)
        elif what == "error":
            current.pop(side)
        else:
            f["fields"].append((what, text))
    # On a single bus channel sigrok reads every frame both ways; a frame whose bytes check as
    # a request and as a response (a write and its echo) comes out twice at one place.
    frames.sort(key=lambda f: (f["at"], f["side"] != "cs"))
    out = []
    for f in frames:
        if out and out[-1][0] == f["at"]:
            out[-1][1].append(normal_sigrok(f))
        else:
            out.append((f["at"], [normal_sigrok(f)]))
    return [readings for _, readings in out]


def normal_sigrok(f):
    slave = int(re.search(r"(\d+)", f["slave"]).group(1)) if "ID:" in f["slave"] else 0
    fc = None
    start = None
    count = None
    values = []
    coils = None
    data_bytes = []
    for what, text in f["fields"]:
        if what == "function":
            fc = int(re.match(r"Function (\d+)", text).group(1))
        elif what == "address":
            start = int(re.search(r"0x([0-9A-Fa-f]+)", text).group(1), 16)
        elif what == "length":
            m = re.match(r"(Read|Write) (\d+) ", text)
            if m:
                count = int(m.group(2))
        elif what == "data":
            m = re.match(r"0x([0-9A-Fa-f]+) / (\d+)$", text)
            if m:
                values.append(int(m.group(2)))
                continue
            m = re.match(r"Register Value 0x[0-9A-Fa-f]+ / (\d+)$", text)
            if m:
                values.append(int(m.group(1)))
                continue
            m = re.match(r"Coil Value (ON|OFF)$", text)
            if m:
                values.append(1 if m.group(1) == "ON" else 0)
                continue
            m = re.match(r"Value 0x([0-9A-Fa-f]+)$", text)
            if m:
                data_bytes.append(int(m.group(1), 16))
                continue
            m = re.match(r"([01]{8})$", text)
            if m:
                coils = (coils or []) + [int(b) for b in reversed(m.group(1))]
                continue
            m = re.match(r"Write (\d+) ", text)
            if m:
                count = int(m.group(1))
    request = f["side"] == "cs"
    if request:
        if fc in (1, 2, 3, 4):
            return f"Request {slave} 0x{fc:02X} start={start} count={count}"
        if fc == 5:
            return f"Request {slave} 0x{fc:02X} start={start} count=1 {start}={values[0]}"
        if fc == 6:
            return f"Request {slave} 0x{fc:02X} start={start} count=1 {start}={values[0]}"
        if fc == 15:
            bits = [(data_bytes[i // 8] >> (i % 8)) & 1 for i in range(count)]
            vals = " ".join(f"{start + i}={b}" for i, b in enumerate(bits))
            return f"Request {slave} 0x{fc:02X} start={start} count={count} {vals}"
        if fc == 16:
            regs = [data_bytes[i] << 8 | data_bytes[i + 1] for i in range(0, 2 * count, 2)]
            vals = " ".join(f"{start + i}={v}" for i, v in enumerate(regs))
            return f"Request {slave} 0x{fc:02X} start={start} count={count} {vals}"
        return f"Request {slave} 0x{fc:02X} ?"
    if fc in (1, 2):
        return ("Response", slave, fc, "coils", coils)
    if fc in (3, 4):
        return ("Response", slave, fc, "registers", values)
    if fc in (5, 6):
        return f"Response {slave} 0x{fc:02X} {start}={values[0]}"
    if fc in (15, 16):
        return f"Response {slave} 0x{fc:02X} start={start} count={count}"
    return f"Response {slave} 0x{fc:02X} ?"


def busnoop_frames(path):
    out = []
    for line in open(path, encoding="utf-8"):
        row = json.loads(line)
        if row.get("type") not in ("Request", "Response", "Exception"):
            continue
        parts = row.get("parts", {})
        fc = int(row["sensor_no"], 16)
        text = []
        for name, value in parts.items():
            m = re.match(r"[RC](\d+)$", name)
            text.append(f"{m.group(1)}={value}" if m else f"{name}={value}")
        out.append(f"{row['type']} {row['id']} 0x{fc:02X} " + " ".join(text))
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sig = sigrok_frames(sys.argv[1])
    bus = busnoop_frames(sys.argv[2])
    # A sigrok response lists values without addresses: take them from the request before it.
    last_start = {}
    resolved = []
    for readings in sig:
        texts = []
        for s in readings:
            if isinstance(s, tuple):
                _, slave, fc, kind, vals = s
                start, count = last_start.get((slave, fc), (0, 0))
                if kind == "coils":
                    vals = (vals or [])[:count]
                s = f"Response {slave} 0x{fc:02X} " + " ".join(
                    f"{start + i}={v}" for i, v in enumerate(vals)
                )
            elif len(readings) == 1:
                m = re.match(r"Request (\d+) 0x([0-9A-F]{2}) start=(\d+) count=(\d+)", s)
                if m:
                    last_start[(int(m.group(1)), int(m.group(2), 16))] = (
                        int(m.group(3)),
                        int(m.group(4)),
                    )
            texts.append(s.strip())
        resolved.append(texts)
    bus = [b.strip() for b in bus]
    # Longest common subsequence: a frame one side lacks shows as one difference, not a shift.
    n, m = len(resolved), len(bus)
    lcs = [[0] * (m + 1) for _ in range(n + 1)]
    for i in range(n - 1, -1, -1):
        for j in range(m - 1, -1, -1):
            if bus[j] in resolved[i]:
                lcs[i][j] = 1 + lcs[i + 1][j + 1]
            else:
                lcs[i][j] = max(lcs[i + 1][j], lcs[i][j + 1])
    both = sum(1 for a in resolved if len(a) > 1)
    print(f"sigrok: {n} frames with a correct CRC "
          f"({sum(1 for a in resolved if len(a) == 1 and a[0].startswith('Request'))} requests, "
          f"{both} read both ways as request and response); "
          f"busnoop: {m} checked frames; the same in order: {lcs[0][0]}")
    i = j = 0
    while i < n or j < m:
        if i < n and j < m and bus[j] in resolved[i]:
            i += 1
            j += 1
        elif j < m and (i == n or lcs[i][j + 1] >= lcs[i + 1][j]):
            print(f"  only busnoop (its frame {j}): {bus[j]}")
            j += 1
        else:
            print(f"  only sigrok (its frame {i}): {' | '.join(resolved[i])}")
            i += 1
    sys.exit(0 if lcs[0][0] == n == m else 1)


if __name__ == "__main__":
    main()
