#!/usr/bin/env python3
"""Writes fixtures/futaba-session.bin (Futaba SBUS / SBUS2 wire bytes) and
fixtures/futaba-session.tsv (the rows busnoop must print for them).

Written from the public descriptions of the frame (Betaflight rx/sbus.c and sbus_channels.h, the
SBUS2 slot ids of INAV telemetry/sbus2.c, docs/futaba.md), independently of busnoop's own
encoder, so the test that reads both files (tests/futaba_fixtures.rs) checks the decoder against
a second implementation. Deterministic: the same files every run.

    tools/futaba_gen.py            # rewrites both files
"""

import os
import random

START = 0x0F
# INAV telemetry/sbus2.c, sbus2SlotIds: slot n's id byte.
SLOT_IDS = [
    0x03, 0x83, 0x43, 0xC3, 0x23, 0xA3, 0x63, 0xE3,
    0x13, 0x93, 0x53, 0xD3, 0x33, 0xB3, 0x73, 0xF3,
    0x0B, 0x8B, 0x4B, 0xCB, 0x2B, 0xAB, 0x6B, 0xEB,
    0x1B, 0x9B, 0x5B, 0xDB, 0x3B, 0xBB, 0x7B, 0xFB,
]
END_OF_GROUP = [0x04, 0x14, 0x24, 0x34]


def frame(channels, flags, end):
    """0F, 16 channels of 11 bits packed little-endian, flags, end byte."""
    bits = 0
    for i, c in enumerate(channels):
        bits |= (c & 0x7FF) << (11 * i)
    return bytes([START]) + bits.to_bytes(22, "little") + bytes([flags, end])


def micros(x):
    """Betaflight sbusChannelsReadRawRC: 5 * x / 8 + 880 in integers."""
    return 5 * x // 8 + 880


class Session:
    def __init__(self):
        self.wire = bytearray()
        self.rows = []

    def row(self, kind, id_, sensor_no, sensor, data, value, raw):
        self.rows.append((kind, id_, sensor_no, sensor, data, value, raw.hex(" ").upper()))
        self.wire += raw

    def frame(self, channels, flags=0, end=0x00):
        raw = frame(channels, flags, end)
        us = [micros(c) for c in channels]
        self.row("Channels", "", f"0x{end:02X}", "SBUS" if end == 0 else "SBUS2",
                 " ".join(map(str, us)), str(us[0]), raw)
        return raw

    def slot(self, n, value):
        raw = bytes([SLOT_IDS[n], value >> 8, value & 0xFF])
        self.row("Slot", str(n), f"0x{SLOT_IDS[n]:02X}", "RxV" if n == 0 else "",
                 f"0x{value:04X}", str(value), raw)

    def broken(self, kind, raw, id_=""):
        self.row(kind, id_, "", "", raw.hex(" ").upper(), "", raw)


def main():
    rng = random.Random(2024)
    s = Session()
    sticks = [992] * 16

    def move():
        for i in range(4):
            sticks[i] = max(172, min(1811, sticks[i] + rng.randint(-40, 40)))
        sticks[4] = rng.choice([172, 992, 1811])
        return list(sticks)

    # Plain SBUS, with the extremes Betaflight's comments name (200/1000/1800, 173/1812).
    s.frame([200, 1000, 1800, 173, 1812] + [992] * 11)
    for _ in range(5):
        s.frame(move())
    s.frame(move(), flags=0x01 | 0x02)  # CH17, CH18
    s.frame(move(), flags=0x04)  # frame lost
    s.frame(move(), flags=0x0C)  # frame lost + failsafe
    # SBUS2: the four slot groups in turn, with the receiver voltage in slot 0 and sensors.
    for round_ in range(3):
        for g in range(4):
            s.frame(move(), end=END_OF_GROUP[g])
            for k in range(8):
                n = 8 * g + k
                if n == 0:
                    s.slot(0, 0x8000 | (50 + round_))  # as a SBS-01V first voltage: 5.0 V
                elif k in (1, 2, 5) or (g == 1 and k < 8):
                    s.slot(n, rng.randrange(0x10000))
    # A value byte 0F inside a slot is still a slot.
    s.frame(move(), end=0x04)
    s.slot(0, 0x800F)
    s.slot(1, 0x0F0F)
    # INAV's fast pace: end byte 08, no slots.
    s.frame(move(), end=0x08)
    # Damage: noise between frames, a frame cut short by the next one, a wrong end byte, a slot
    # cut by a frame, the input ending inside a frame.
    s.broken("Garbage", bytes([0x55, 0xAA, 0x00]))
    s.frame(move())
    whole = frame(move(), 0, 0)
    s.broken("Truncated", whole[:13])
    s.frame(move())
    wrong = bytearray(frame([1500] * 16, 0, 0))
    wrong[24] = 0x77
    s.broken("Garbage", bytes(wrong))
    s.frame(move(), end=0x14)
    s.slot(8, 0x1234)
    s.broken("Truncated", bytes([SLOT_IDS[9]]), id_="9")
    s.frame(move())
    s.broken("Truncated", frame(move(), 0, 0)[:9])

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures")
    with open(os.path.join(root, "futaba-session.bin"), "wb") as f:
        f.write(s.wire)
    with open(os.path.join(root, "futaba-session.tsv"), "w") as f:
        f.write("# rows of futaba-session.bin, written by tools/futaba_gen.py\n")
        f.write("kind\tid\tsensor_no\tsensor\tdata\tvalue\traw\n")
        for r in s.rows:
            f.write("\t".join(r) + "\n")


if __name__ == "__main__":
    main()
