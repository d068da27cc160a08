#!/usr/bin/env python3
"""Writes F.Port v1 and F.Port 2 traffic into fixtures/, with what each frame must decode to.

Written from the protocol facts in docs/fport.md (the FrSky F.Port v2.1 document, Betaflight,
INAV and ArduPilot behaviour), independently of busnoop's own encoders, so that the sessions
check the decoder against a second reading of the same facts:

  fixtures/fport-v1-session.bin   F.Port v1: 7E-delimited, stuffed, checksum over len..data
  fixtures/fport2-session.bin     F.Port 2: length-prefixed, checksum over type..data
  fixtures/fport-sessions.tsv     one line per row busnoop must show, in order

Usage: python3 tools/fport-gen/gen.py   (from the repository root; deterministic)

The traffic: a short flight (16 channels moving, RSSI falling and rising, a few lost frames
and one failsafe), telemetry polls answered by the flight controller with S.Port sensor
frames (Betaflight-style bare answers, PDF-style delimited ones, one ArduPilot answer after a
0xFF pad), a null answer, MSP over S.Port (read request, reply), in F.Port 2 also 8- and
24-channel frames, polls of another physical ID and an OTA firmware-update exchange; and the
faults a sniffer must show: line noise, a frame with a bad checksum, a frame cut short.
"""

import math
import os
import random

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
FIXTURES = os.path.join(ROOT, "fixtures")


def frsky_sum(data):
    """The FrSky checksum byte: 0xFF minus the sum with end-around carry."""
    s = 0
    for b in data:
        s += b
        s = (s & 0xFF) + (s >> 8)
    return 0xFF - s


def pack11(channels):
    """11-bit channels, least significant bit first (the SBUS packing)."""
    bits = 0
    for i, c in enumerate(channels):
        bits |= (c & 0x7FF) << (11 * i)
    return bits.to_bytes((11 * len(channels) + 7) // 8, "little")


def stuff(data):
    out = bytearray()
    for b in data:
        if b in (0x7E, 0x7D):
            out += bytes([0x7D, b ^ 0x20])
        else:
            out.append(b)
    return bytes(out)


def us_text(raw):
    """Betaflight's 5/8 x + 880, exactly, without trailing zeros."""
    milli = raw * 625 + 880000
    text = "%d.%03d" % (milli // 1000, milli % 1000)
    return text.rstrip("0").rstrip(".")


def sport_payload(kind, app_id, value):
    return bytes([kind]) + app_id.to_bytes(2, "little") + (value & 0xFFFFFFFF).to_bytes(4, "little")


# Sensor answers of a flight controller (physical ID 27): app ID, raw value, the Value busnoop
# (as `busnoop sport`) shows. Scales from EdgeTX's sensor table as docs/sport.md lists them;
# AccX from the flight-controller slot is 0.01 g (Betaflight, INAV).
SENSORS = [
    (0x0210, 1680, "16.80"),  # VFAS, 0.01 V
    (0x0200, 123, "12.3"),  # Curr, 0.1 A
    (0x0600, 87, "87"),  # Fuel, %
    (0x0100, 6543, "65.43"),  # Alt, 0.01 m
    (0x0700, -20, "-0.20"),  # AccX, 0.01 g from the FC
    (0x0110, -150, "-1.50"),  # VSpd, 0.01 m/s
]


class Session:
    def __init__(self, name):
        self.name = name
        self.bytes = bytearray()
        self.rows = []

    def add(self, raw, kind, rid="", sensor_no="", value=""):
        self.rows.append((self.name, len(self.bytes), len(raw), kind, rid, sensor_no, value))
        self.bytes += raw


def v1_frame(kind, data):
    body = bytes([len(data) + 1, kind]) + data
    return body + bytes([frsky_sum(body)])


def v1_wire(kind, data):
    return b"\x7e" + stuff(v1_frame(kind, data)) + b"\x7e"


def v2_frame(length, kind, data):
    return bytes([length, kind]) + data + bytes([frsky_sum(bytes([kind]) + data)])


def sticks(i, n=16):
    ch = [992] * n
    ch[0] = 992 + int(700 * math.sin(i / 5))
    ch[1] = 992 + int(500 * math.cos(i / 7))
    ch[2] = 172 + (i * 37) % 1640
    ch[3] = 993
    for k in range(4, n):
        ch[k] = 172 if (i // 8 + k) % 2 else 1811
    return ch


def control_data(ch, flags, rssi):
    return pack11(ch) + bytes([flags, rssi])


def control_flags(i):
    flags = 0
    if i % 13 == 12:
        flags |= 0x04  # frame lost
    if i == 30:
        flags |= 0x08  # failsafe
    if i % 10 == 5:
        flags |= 0x01  # CH17
    return flags


def v1_session(rng):
    s = Session("fport-v1-session.bin")
    for i in range(40):
        ch = sticks(i)
        rssi = max(0, 100 - abs(20 - i) * 3)
        flags = control_flags(i)
        data = control_data(ch, flags, rssi)
        if i == 17:
            # A bad checksum: one channel bit flipped on the way.
            raw = bytearray(v1_wire(0x00, data))
            raw[6] ^= 0x10
            assert 0x7E not in raw[1:-1]
            s.add(bytes(raw), "BadCRC")
        elif i == 23:
            # Cut short after 14 bytes: the next frame's 0x7E ends it.
            s.add(v1_wire(0x00, data)[:14], "Truncated")
        else:
            s.add(v1_wire(0x00, data), "Control", "", "", us_text(ch[0]))
        if i == 9:
            # Line noise between frames (no 0x7E; not a frame start after a frame).
            noise = bytes(rng.choice([b for b in range(256) if b not in (0x7E, 0x08, 0x19, 0xFF)]) for _ in range(7))
            s.add(noise, "Garbage")
        s.add(v1_wire(0x01, bytes(7)), "Poll", "27")
        if i == 20:
            # MSP over S.Port: the radio's read request forwarded, the FC's reply.
            s.add(v1_wire(0x01, sport_payload(0x30, 0x0730, 0x6401)), "Read", "13", "0x0730")
            continue
        if i == 21:
            s.add(stuff(v1_frame(0x81, sport_payload(0x32, 0x0730, 0x64))), "Reply", "27", "0x0730")
            continue
        if i % 7 == 6:
            # Nothing to send: a null answer.
            s.add(stuff(v1_frame(0x81, bytes(7))), "Null", "27")
            continue
        app_id, value, text = SENSORS[i % len(SENSORS)]
        answer = v1_frame(0x81, sport_payload(0x10, app_id, value))
        if i % 5 == 1:
            raw = b"\x7e" + stuff(answer) + b"\x7e"  # PDF style: delimited
        elif i == 14:
            raw = b"\xff" + stuff(answer)  # ArduPilot with its pad byte
        else:
            raw = stuff(answer)  # Betaflight style: bare
        s.add(raw, "Data", "27", "0x%04X" % app_id, text)
    return s


def v2_session(rng):
    s = Session("fport2-session.bin")
    for i in range(40):
        n = 8 if i == 3 else 24 if i == 4 else 16
        ch = sticks(i, n)
        rssi = max(0, 100 - abs(20 - i) * 3)
        flags = control_flags(i)
        length = {8: 0x0D, 16: 0x18, 24: 0x23}[n]
        frame = v2_frame(length, 0xFF, control_data(ch, flags, rssi))
        if i == 17:
            raw = bytearray(frame)
            raw[6] ^= 0x10
            s.add(bytes(raw), "BadCRC")
        elif i == 23:
            s.add(frame[:14], "Truncated")
        else:
            s.add(frame, "Control", "", "", us_text(ch[0]))
        if i == 9:
            noise = bytes(rng.choice([b for b in range(256) if b not in (0x0D, 0x18, 0x23, 0x20, 0x08)]) for _ in range(7))
            s.add(noise, "Garbage")
            # After garbage the next frame must be a control frame (telemetry needs one before it).
            s.add(v2_frame(0x18, 0xFF, control_data(sticks(i), 0, rssi)), "Control", "", "", us_text(sticks(i)[0]))
        if i == 23:
            # The cut frame is followed by a whole one, which starts inside its length.
            s.add(frame, "Control", "", "", us_text(ch[0]))
        if i == 20:
            s.add(v2_frame(0x08, 0x0D, sport_payload(0x30, 0x0730, 0x6401)), "Read", "13", "0x0730")
            s.add(v2_frame(0x08, 0x1B, sport_payload(0x32, 0x0730, 0x64)), "Reply", "27", "0x0730")
            continue
        if i == 25:
            # Over-the-air firmware update (INAV's reading): start, data at address 0, stop.
            s.add(v2_frame(0x18, 0xF0, bytes([2, 3]) + bytes(22)), "OtaStart")
            s.add(v2_frame(0x08, 0x1B, sport_payload(0xF0, 0, 0)), "OtaStart", "27")
            s.add(v2_frame(0x08, 0x1B, sport_payload(0xF0, 0, 0)), "OtaStart", "27")
            s.add(v2_frame(0x20, 0xF1, bytes(range(32))), "OtaData")
            s.add(v2_frame(0x08, 0x1B, sport_payload(0xF1, 0, 0)), "OtaData", "27")
            s.add(v2_frame(0x08, 0x1B, sport_payload(0xF1, 0, 0)), "OtaData", "27")
            s.add(v2_frame(0x18, 0xF2, bytes(24)), "OtaStop")
            continue
        if i % 4 == 2:
            # A poll of the receiver's own ID (0x98 = physical ID 24), unanswered.
            s.add(v2_frame(0x08, 0x98, bytes(7)), "Poll", "24")
            continue
        s.add(v2_frame(0x08, 0x1B, bytes(7)), "Poll", "27")
        if i % 7 == 6:
            s.add(v2_frame(0x08, 0x1B, bytes(7)), "Null", "27")
            continue
        app_id, value, text = SENSORS[i % len(SENSORS)]
        s.add(v2_frame(0x08, 0x1B, sport_payload(0x10, app_id, value)), "Data", "27", "0x%04X" % app_id, text)
    return s


def main():
    rng = random.Random(34)
    sessions = [v1_session(rng), v2_session(rng)]
    lines = ["file\toffset\tlength\ttype\tid\tsensor_no\tvalue"]
    for s in sessions:
        with open(os.path.join(FIXTURES, s.name), "wb") as f:
            f.write(s.bytes)
        for row in s.rows:
            lines.append("\t".join(str(x) for x in row))
    with open(os.path.join(FIXTURES, "fport-sessions.tsv"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
