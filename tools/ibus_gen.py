#!/usr/bin/env python3
"""Writes FlySky iBUS fixtures and the rows busnoop must print for them:

* fixtures/ibus-sensors.bin / .tsv: a sensor-bus session (power-up, discovery, type queries,
  measurements of seven sensor types, a daisy-chained sensor's unanswered polls, a retried poll,
  damage);
* fixtures/ibus-rc.bin / .tsv: RC frames of 14 and 18 channels, with damage.

Written from the public descriptions (Betaflight rx/ibus.c, telemetry/ibus_shared.c/.h and their
unit tests, EdgeTX flysky_ibus.cpp, docs/ibus.md), independently of busnoop's own encoder, so the
test that reads both files (tests/rc_fixtures.rs) checks the decoder against a second
implementation. Deterministic: the same files every run.

    tools/ibus_gen.py            # rewrites the four files
"""

import os
import random
import struct


def frame(cmd, payload=b""):
    body = bytes([len(payload) + 4, cmd]) + bytes(payload)
    chk = (0xFFFF - sum(body)) & 0xFFFF
    return body + struct.pack("<H", chk)


def poll(cmd, addr):
    return frame(cmd << 4 | addr)


class Session:
    def __init__(self):
        self.wire = bytearray()
        self.rows = []

    def row(self, kind, id_, sensor_no, sensor, data, value, unit, raw):
        self.rows.append((kind, id_, sensor_no, sensor, data, value, unit, raw.hex(" ").upper()))
        self.wire += raw


# type code -> (name, unit, how the value prints)
def temp(raw):
    v = raw - 400
    return f"{'-' if v < 0 else ''}{abs(v) // 10}.{abs(v) % 10}"


def hundredths(raw):
    return f"{'-' if raw < 0 else ''}{abs(raw) // 100}.{abs(raw) % 100:02d}"


def deg7(raw):
    return f"{'-' if raw < 0 else ''}{abs(raw) // 10**7}.{abs(raw) % 10**7:07d}"


TYPES = {
    0x00: ("IntV", "V", 2, hundredths, False),
    0x01: ("Temp", "degC", 2, temp, False),
    0x02: ("RPM", "rpm", 2, str, False),
    0x03: ("ExtV", "V", 2, hundredths, True),  # signed, as EdgeTX reads voltages
    0x05: ("Curr", "A", 2, hundredths, False),
    0x06: ("Fuel", "%", 2, str, False),
    0x80: ("GPS", "deg", 4, deg7, True),
}


def sensors():
    rng = random.Random(7)
    s = Session()
    # Power-up: the FS-iA6B sends `04 F0 0B FF` (command 0xF to address 0) before discovering.
    for _ in range(3):
        s.row("", "0", "", "", "", "", "", poll(0xF, 0))
    # Sensors at 1..7: discovery (echo), type query; address 8 is empty.
    plan = {1: 0x00, 2: 0x01, 3: 0x02, 4: 0x03, 5: 0x05, 6: 0x06, 7: 0x80}
    for addr in range(1, 9):
        p = poll(0x8, addr)
        if addr in plan:
            s.row("Discover", str(addr), "", "", "present", "", "", p + p)
        else:
            s.row("", str(addr), "", "", "", "", "", p)
    for addr, code in plan.items():
        name, _, size, _, _ = TYPES[code]
        s.row("SensorType", str(addr), f"0x{code:02X}", name, f"{name}, {size} bytes", "", "",
              poll(0x9, addr) + frame(0x90 | addr, bytes([code, size])))
    values = {
        1: [512, 498, 0],
        2: [400 + 253, 0, 1900],  # 25.3 degC, -40.0, 150.0
        3: [0, 12345, 65535],
        4: [1260, -1, -32768],  # 12.60 V, FF FF = -0.01 V, 00 80 = Betaflight's 'no value'
        5: [0, 1575, 20000],
        6: [100, 57, 3],
        7: [525200000, -337000000, 0],
    }
    for rnd in range(3):
        for addr, code in plan.items():
            name, unit, size, show, signed = TYPES[code]
            raw = values[addr][rnd]
            fmt = ("<" + {2: "h", 4: "i"}[size]) if signed else ("<" + {2: "H", 4: "I"}[size])
            payload = struct.pack(fmt, raw)
            text = show(raw)
            s.row("Measure", str(addr), f"0x{code:02X}", name, text, text, unit,
                  poll(0xA, addr) + frame(0xA0 | addr, payload))
            if rnd == 1 and addr == 2:
                # The receiver's next poll, not answered in time, then retried and answered.
                s.row("", "3", "0x02", "RPM", "", "", "", poll(0xA, 3))
        # A daisy-chained sensor 9 polled downstream of the probe: never answered here.
        s.row("", "9", "", "", "", "", "", poll(0xA, 9))
    # Damage: a bad checksum on an answer (its poll goes unanswered), line noise, an answer cut
    # by the next poll, the input ending inside a poll.
    s.row("", "1", "0x00", "IntV", "", "", "", poll(0xA, 1))
    bad = bytearray(frame(0xA1, struct.pack("<H", 500)))
    bad[-1] ^= 0x40
    s.row("BadCRC", "1", "", "", bytes(bad).hex(" ").upper(), "", "", bytes(bad))
    noise = bytes([0x55, 0x13, 0x99])
    s.row("Garbage", "", "", "", noise.hex(" ").upper(), "", "", noise)
    s.row("", "2", "0x01", "Temp", "", "", "", poll(0xA, 2))
    cut = frame(0xA2, struct.pack("<H", 700))[:3]
    s.row("Truncated", "2", "", "", cut.hex(" ").upper(), "", "", cut)
    v = rng.randrange(0, 5000)
    s.row("Measure", "3", "0x02", "RPM", str(v), str(v), "rpm",
          poll(0xA, 3) + frame(0xA3, struct.pack("<H", v)))
    tail = poll(0xA, 4)[:2]
    s.row("Truncated", "4", "", "", tail.hex(" ").upper(), "", "", tail)
    return s


def rc_frame(channels):
    """20 40, 14 slots of the low 12 bits; channels 15-18 in the slots' high nibbles."""
    slots = [c & 0x0FFF for c in channels[:14]] + [0] * (14 - len(channels[:14]))
    for k, c in enumerate(channels[14:18]):
        for j in range(3):
            slots[3 * k + j] |= ((c >> (4 * j)) & 0xF) << 12
    return frame(0x40, b"".join(struct.pack("<H", v) for v in slots))


def rc():
    rng = random.Random(11)
    s = Session()
    sticks = [1500, 1500, 1000, 1500, 1000, 1000, 2000, 1500, 1500, 1500, 1000, 1000, 1000, 1000]
    for i in range(20):
        for k in range(4):
            sticks[k] = max(1000, min(2000, sticks[k] + rng.randint(-25, 25)))
        ch = list(sticks)
        if i >= 10:
            ch += [1000 + 100 * k + i for k in range(4)]  # an 18-channel receiver
        raw = rc_frame(ch)
        s.row("Channels", "", "", "", " ".join(map(str, ch)), str(ch[0]), "us", raw)
        if i == 5:
            bad = bytearray(rc_frame(ch))
            bad[10] ^= 0x01
            s.row("BadCRC", "", "", "", bytes(bad).hex(" ").upper(), "", "", bytes(bad))
        if i == 12:
            noise = bytes([0x00, 0xFF, 0x7E])
            s.row("Garbage", "", "", "", noise.hex(" ").upper(), "", "", noise)
    return s


def write(name, s):
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures")
    with open(os.path.join(root, name + ".bin"), "wb") as f:
        f.write(s.wire)
    with open(os.path.join(root, name + ".tsv"), "w") as f:
        f.write(f"# rows of {name}.bin, written by tools/ibus_gen.py\n")
        f.write("kind\tid\tsensor_no\tsensor\tdata\tvalue\tunit\traw\n")
        for r in s.rows:
            f.write("\t".join(r) + "\n")


if __name__ == "__main__":
    write("ibus-sensors", sensors())
    write("ibus-rc", rc())
