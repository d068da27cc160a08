#!/usr/bin/env python3
"""Writes CRSF and GHST traffic for busnoop's fixtures, from the protocol texts alone.

Written from the TBS text (tbs-fpv/tbs-crsf-spec crsf.md: frame format, CRC-8 0xD5, the
command frames' CRC-8 0xBA, the payload layouts) and the values Betaflight and EdgeTX show
(Betaflight's channel scale 0.62477120195241 * raw + 881; EdgeTX's sensor names), without
busnoop's code: the fixtures check the decoder against a second, independent reading.

Before writing anything it rebuilds the public vectors (Betaflight rx_crsf_unittest.cc,
EdgeTX tests/crossfire.cpp) byte for byte and stops if one differs.

For every file it writes `<name>.bin` (the raw wire bytes) and `<name>.expect.tsv`: one line
per row busnoop must show, found by this script's own reading of the resync rule (docs/crsf.md):
offset, length, kind (Frame, BadCRC, Truncated, Garbage), the type byte, the Type name, and for
the frames it built the numbers it put in (`name=text`, busnoop's decimals).

    python3 tools/crsf_gen.py [FIXTURES_DIR]        (default: fixtures)
"""

import math
import os
import random
import sys

MAX_GARBAGE = 64


def crc_table(poly):
    t = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = ((c << 1) ^ poly) & 0xFF if c & 0x80 else (c << 1) & 0xFF
        t.append(c)
    return t


D5 = crc_table(0xD5)
BA = crc_table(0xBA)


def crc(table, data):
    c = 0
    for b in data:
        c = table[c ^ b]
    return c


def frame(addr, ty, payload):
    payload = bytes(payload)
    assert len(payload) <= 60
    body = bytes([ty]) + payload
    return bytes([addr, len(body) + 1]) + body + bytes([crc(D5, body)])


def ext(addr, ty, dest, origin, payload):
    return frame(addr, ty, bytes([dest, origin]) + bytes(payload))


def command(addr, dest, origin, cmd, sub, data):
    p = bytes([dest, origin, cmd, sub]) + bytes(data)
    return frame(addr, 0x32, p + bytes([crc(BA, bytes([0x32]) + p)]))


def pack(values, bits):
    acc, have, out = 0, 0, bytearray()
    for v in values:
        acc |= (v & ((1 << bits) - 1)) << have
        have += bits
        while have >= 8:
            out.append(acc & 0xFF)
            acc >>= 8
            have -= 8
    if have:
        out.append(acc & 0xFF)
    return bytes(out)


def unpack(data, bits, count):
    acc, have, i, out = 0, 0, 0, []
    for _ in range(count):
        while have < bits:
            acc |= (data[i] if i < len(data) else 0) << have
            i += 1
            have += 8
        out.append(acc & ((1 << bits) - 1))
        acc >>= bits
        have -= bits
    return out


def be(v, n, signed=False):
    return int(v).to_bytes(n, "big", signed=signed)


def le(v, n, signed=False):
    return int(v).to_bytes(n, "little", signed=signed)


def fixed(raw, prec):
    """raw / 10**prec with exactly prec decimals, as busnoop prints its numbers."""
    raw = int(raw)
    if prec == 0:
        return str(raw)
    sign = "-" if raw < 0 else ""
    digits = str(abs(raw)).rjust(prec + 1, "0")
    return f"{sign}{digits[:-prec]}.{digits[-prec:]}"


def bf_us(raw):
    """Betaflight's CRSF channel scale, rounded to the nearest µs."""
    return math.floor(0.62477120195241 * raw + 881 + 0.5)


def rssi(b):
    return b - 256 if b >= 128 else -b


def h(text):
    return bytes.fromhex(text)


def check_public_vectors():
    """Stops unless this script rebuilds the public vectors exactly."""
    rc = h("00 18 16 BD 08 9F F4 AE F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 6C")
    ch = unpack(rc[3:25], 11, 16)
    assert ch[:4] == [189, 993, 978, 983], ch
    assert [bf_us(c) for c in ch[:4]] == [999, 1501, 1492, 1495]
    assert frame(0x00, 0x16, pack(ch, 11)) == rc
    rc2 = h("00 18 16 BD 08 9F F4 AA F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 94")
    assert frame(0x00, 0x16, rc2[3:25]) == rc2 and unpack(rc2[3:25], 11, 4)[3] == 981
    assert frame(0xC8, 0x17, bytes([0x24]) + pack([0, 820, 1959, 2047], 11)) == h(
        "C8 09 17 24 00 A0 D9 E9 FF 0F D1"
    )
    assert command(0xC8, 0xC8, 0xEC, 0x0A, 0x70, h("01 00 1E 84 80")) == h(
        "C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 22 72"
    )
    assert frame(0x00, 0x14, h("00 00 00 00 FF 01 03 00 00 00")) == h(
        "00 0C 14 00 00 00 00 FF 01 03 00 00 00 F4"
    )
    for f in EDGETX_FRAMES:
        assert frame(f[0], f[2], f[3:-1]) == f
    assert [bf_us(x) for x in (172, 992, 1811)] == [988, 1501, 2012]
    assert crc(D5, b"123456789") == 0xBC


# EdgeTX tests/crossfire.cpp frameParser_badFrames: its three frames (type 0xFF).
EDGETX_FRAMES = [
    h("EA 14 FF 11 FD 05 00 00 13 01 01 2A 00 00 00 00 00 00 01 5D 98 B4"),
    h("EA 21 FF 1E FD 12 00 00 14 01 01 4A 00 00 00 00 00 00 00 00 00 00 8F C2 35 3F FD C7 D1 3C"
      " 4C 01 92 3F 31"),
    h("EA 1F FF 1C FD 10 00 00 15 01 01 24 00 00 35 7D F2 40 E8 03 E8 03 DC 05 DC 05 E1 05 E1 05"
      " 2A FE 5F"),
]

CRSF_ADDRESSES = {
    0x00, 0x0E, 0x10, 0x12, 0x13, 0x14, 0x80, 0x8A, 0x90, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96,
    0x97, 0xB0, 0xB2, 0xC0, 0xC2, 0xC4, 0xC8, 0xCA, 0xCC, 0xCE, 0xEA, 0xEC, 0xEE, 0xEF, 0xF0, 0xF2,
}
GHST_ADDRESSES = set(range(0x80, 0x8A))


def classify(data, addrs):
    """The resync rule over the whole input: [(offset, length, kind)]."""
    n = len(data)

    def cand(p):
        if data[p] not in addrs:
            return None
        if p + 1 >= n:
            return (1, False, False)
        ln = data[p + 1]
        if not 2 <= ln <= 62:
            return None
        end = p + ln + 2
        if end > n:
            return (n - p, False, False)
        return (end - p, crc(D5, data[p + 2:end - 1]) == data[end - 1], True)

    def valid(q):
        c = cand(q)
        return c is not None and c[1]

    out, garbage, p = [], None, 0

    def flush(to):
        nonlocal garbage
        if garbage is not None:
            a = garbage
            while a < to:
                b = min(a + MAX_GARBAGE, to)
                out.append((a, b - a, "Garbage"))
                a = b
            garbage = None

    while p < n:
        c = cand(p)
        if c is not None and c[1]:
            flush(p)
            out.append((p, c[0], "Frame"))
            p += c[0]
        elif c is not None and not any(valid(q) for q in range(p + 1, p + c[0])):
            flush(p)
            out.append((p, c[0], "BadCRC" if c[2] else "Truncated"))
            p += c[0]
        else:
            if garbage is None:
                garbage = p
            p += 1
    flush(p)
    return out


class Stream:
    def __init__(self, addrs):
        self.data = bytearray()
        self.addrs = addrs
        self.frames = {}  # offset -> (Type name, parts or None)

    def add(self, f, name, parts=None):
        self.frames[len(self.data)] = (name, parts)
        self.data += f

    def raw(self, b):
        self.data += bytes(b)

    def noise(self, rnd, n):
        """Bytes that start no candidate."""
        pool = [b for b in range(256) if b not in self.addrs]
        self.data += bytes(rnd.choice(pool) for _ in range(n))

    def write(self, directory, name):
        rows = classify(bytes(self.data), self.addrs)
        at = {off: (ln, kind) for off, ln, kind in rows}
        for off, (tname, _) in self.frames.items():
            assert at.get(off, (0, ""))[1] == "Frame", f"{name}: {tname} at {off} is not a frame"
        with open(os.path.join(directory, name + ".bin"), "wb") as f:
            f.write(self.data)
        with open(os.path.join(directory, name + ".expect.tsv"), "w") as f:
            f.write("# offset\tlength\tkind\ttype\tname\tparts  (written by tools/crsf_gen.py)\n")
            for off, ln, kind in rows:
                ty, tname, parts = "", "", ""
                if kind in ("Frame", "BadCRC") or (kind == "Truncated" and ln >= 3):
                    ty = f"0x{self.data[off + 2]:02X}"
                if kind == "Frame":
                    tname, p = self.frames.get(off, ("", None))
                    parts = " ".join(p) if p else ""
                f.write(f"{off}\t{ln}\t{kind}\t{ty}\t{tname}\t{parts}\n")
        kinds = {}
        for _, _, k in rows:
            kinds[k] = kinds.get(k, 0) + 1
        print(f"{name}: {len(self.data)} bytes, {kinds}")


# --- CRSF ----------------------------------------------------------------------------------


def rc_frame(addr, ch):
    return frame(addr, 0x16, pack(ch, 11)), [f"CH{i + 1}={bf_us(c)}" for i, c in enumerate(ch)]


def sticks(i):
    ch = [992] * 16
    for k in range(4):
        ch[k] = 992 + int(800 * math.sin(i / (17.0 + 5 * k)))
    ch[4] = 1811 if (i // 200) % 2 else 172
    ch[5] = [172, 992, 1811][(i // 70) % 3]
    return ch


def link_stats(i, addr=0xC8):
    r1, r2 = 40 + i % 50, 45 + (i * 3) % 40
    lq = 100 - (i * 7) % 23
    snr = (i % 21) - 10
    p = [r1, r2, lq, snr & 0xFF, i % 2, 7, 2, 60 + i % 30, 99 - i % 5, (i % 9) & 0xFF]
    parts = [f"1RSS={-r1}", f"2RSS={-r2}", f"RQly={lq}", f"RSNR={snr}", f"ANT={i % 2}",
             "RFMD=7", "TPWR=25", f"TRSS={-(60 + i % 30)}", f"TQly={99 - i % 5}", f"TSNR={i % 9}"]
    return frame(addr, 0x14, p), parts


def telemetry(k, i):
    """The k-th telemetry frame kind (every type of the TBS text), FC to receiver."""
    a = 0xC8
    kinds = [
        lambda: (frame(a, 0x08, be(168 - i % 20, 2) + be(123, 2) + be(1000 + i, 3) + bytes([80])),
                 "Battery", [f"RxBt={fixed(168 - i % 20, 1)}", "Curr=12.3", f"Capa={1000 + i}",
                             "Bat%=80"]),
        lambda: (frame(a, 0x02, be(473977000 + i, 4, True) + be(-86000000 - i, 4, True)
                       + be(587, 2) + be(14790, 2) + be(1000 + 120, 2) + bytes([11])),
                 "GPS", [f"Lat={fixed(473977000 + i, 7)}", f"Lon={fixed(-86000000 - i, 7)}",
                         "GSpd=58.7", "Hdg=147.90", "Alt=120", "Sats=11"]),
        lambda: (frame(a, 0x1E, be(11833, 2, True) + be(-2000 + i, 2, True) + be(-31398, 2, True)),
                 "Attitude", ["Ptch=1.1833", f"Roll={fixed(-2000 + i, 4)}", "Yaw=-3.1398"]),
        lambda: (frame(a, 0x21, b"ACRO*\0"), "FlightMode", None),
        lambda: (frame(a, 0x07, be(-150 + i % 300, 2, True)), "Vario",
                 [f"VSpd={fixed(-150 + i % 300, 2)}"]),
        lambda: (frame(a, 0x09, be(10000 + 1234, 2) + be(-42, 2, True)), "Baro",
                 ["BAlt=123.4", "VSpd=-0.42"]),
        lambda: (frame(a, 0x09, be(0x8000 | 2500, 2) + bytes([0])), "Baro",
                 ["BAlt=2500.0", "VSpd=0.00"]),
        lambda: (frame(a, 0x0A, be(523, 2)), "Airspeed", ["ASpd=52.3"]),
        lambda: (frame(a, 0x0B, be(0xC8, 2)), "Heartbeat", None),
        lambda: (frame(a, 0x0C, bytes([0]) + be(21000, 3) + be(-21000, 3, True) + be(0, 3)),
                 "RPM", ["RPM1=21000", "RPM2=-21000", "RPM3=0"]),
        lambda: (frame(a, 0x0D, bytes([0]) + be(455, 2, True) + be(-32, 2, True)), "Temp",
                 ["Tmp1=45.5", "Tmp2=-3.2"]),
        lambda: (frame(a, 0x0E, bytes([0]) + be(4105, 2) + be(4098, 2) + be(4110, 2)
                       + be(4101, 2)), "Voltages",
                 ["Cel1=4.105", "Cel2=4.098", "Cel3=4.110", "Cel4=4.101"]),
        lambda: (frame(a, 0x10, bytes([0xCE, 14]) + be(5740, 2) + bytes([0])), "VTX",
                 ["VPwr=14", "VFrq=5740"]),
        lambda: (frame(a, 0x03, be(2024, 2, True) + bytes([6, 30, 14, 5, 9]) + be(120, 2)),
                 "GPSTime", None),
        lambda: (frame(a, 0x06, bytes([3]) + be(120, 2, True) + be(-40, 2, True) + be(15, 2, True)
                       + be(30, 2, True) + be(12, 2, True) + be(168, 2, True) + be(180, 2, True)
                       + be(290, 2, True) + bytes([0, 8, 13])), "GPSExt",
                 ["Fix=3", "NSpd=1.20", "ESpd=-0.40", "GVSp=0.15", "SAcc=0.30", "TAcc=1.2",
                  "EAlt=168", "HAcc=1.80", "VAcc=2.90", "HDOP=0.8", "VDOP=1.3"]),
        lambda: (frame(0xEA, 0x1C, bytes([70, 55, 100, 9, 20])), "LinkRX",
                 ["RRSS=-70", "RRSP=55", "RQly=100", "RSNR=9", "TPWR=20"]),
        lambda: (frame(0xEA, 0x1D, bytes([66, 60, 98, 6, 17, 50])), "LinkTX",
                 ["TRSS=-66", "TRSP=60", "TQly=98", "TSNR=6", "RPWR=17", "TFPS=500"]),
        lambda: (frame(a, 0x1F, be(1200, 2, True) + bytes([0x81]) + be(5, 4) + bytes([3, 1])),
                 "MAVLinkFC", None),
        lambda: (frame(a, 0x22, bytes([1, 3]) + b"1:02.345".ljust(15, b"\0")
                       + b"0:58.100".ljust(15, b"\0") + b"GO".ljust(20, b"\0")), "ESPNow", None),
        lambda: (ext(a, 0x28, 0x00, 0xEA, b""), "Ping", None),
        lambda: (ext(0xEA, 0x29, 0xEA, 0xEC, b"ELRS RX\0ELRS" + be(0x12, 4) + bytes([0, 3, 4, 1, 20, 0])),
                 "DeviceInfo", None),
        lambda: (ext(0xEE, 0x2C, 0xEE, 0xEA, bytes([4, 0])), "ParamRead", None),
        lambda: (ext(0xEA, 0x2B, 0xEA, 0xEE, bytes([4, 0, 1, 9]) + b"Packet Rate\0"
                     + b"50Hz;150Hz;250Hz\0" + bytes([2, 0, 2, 1]) + b"\0"), "ParamEntry", None),
        lambda: (ext(0xEE, 0x2D, 0xEE, 0xEA, bytes([4, 1])), "ParamWrite", None),
        lambda: (command(a, 0xEC, 0xC8, 0x01, 0x01, b""), "Command", None),
        lambda: (frame(a, 0x34, be(3, 2) + be(1000 + i, 4) + be(7, 4)), "Logging", None),
        lambda: (ext(0xEA, 0x3A, 0xEA, 0xEE, bytes([0x10]) + be(40000, 4) + be(-25, 4, True)),
                 "Radio", ["Intv=4000.0", "Offs=-2.5"]),
        lambda: (ext(a, 0x3C, 0xC8, 0xEA, bytes([1]) + be(-10, 2, True)), "Game", None),
        lambda: (ext(a, 0x7A, 0xC8, 0xEA, bytes([0x30, 0, 101])), "MSPReq", None),
        lambda: (ext(0xEA, 0x7B, 0xEA, 0xC8, bytes([0x30, 3, 101, 1, 2, 3])), "MSPResp", None),
        lambda: (frame(a, 0x80, bytes([0xF0]) + le(0x5003, 2) + le(1234, 4)), "APPassthru", None),
        lambda: (frame(a, 0xAA, bytes([0x21, 10]) + h("FD 05 00 00 07 01 01 21 00 00")),
                 "MAVLink", None),
        lambda: (frame(a, 0xAC, be(0xFF, 4) + be(0x0F, 4) + be(0x0E, 4)), "MAVSysStatus", None),
    ]
    return kinds[k % len(kinds)]()


TELEMETRY_KINDS = 33


def crsf_mixed(rnd):
    s = Stream(CRSF_ADDRESSES)
    # The public vectors first.
    for f, name in [
        (h("00 18 16 BD 08 9F F4 AE F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 6C"), "RC"),
        (h("00 18 16 BD 08 9F F4 AA F7 BD EF 7D EF FB AD FD 45 2B 5A 01 00 00 00 00 00 94"), "RC"),
        (h("C8 09 17 24 00 A0 D9 E9 FF 0F D1"), "RCSubset"),
        (h("C8 0C 32 C8 EC 0A 70 01 00 1E 84 80 22 72"), "Command"),
        (h("00 0C 14 00 00 00 00 FF 01 03 00 00 00 F4"), "LinkStats"),
    ]:
        s.add(f, name)
    # EdgeTX's bad-frames stream: a frame, three random bytes (a false start), a frame, the
    # bad-CRC frame EA 02 00 01, a frame.
    s.add(EDGETX_FRAMES[0], "Unknown")
    s.raw(h("00 35 A4"))
    s.add(EDGETX_FRAMES[1], "Unknown")
    s.raw(h("EA 02 00 01"))
    s.add(EDGETX_FRAMES[2], "Unknown")
    s.add(command(0xC8, 0xC8, 0xEC, 0x0A, 0x71, bytes([1, 1])), "Command")
    for i in range(1500):
        f, parts = rc_frame(0xC8, sticks(i))
        s.add(f, "RC", parts)
        if i % 4 == 1:
            f, parts = link_stats(i)
            s.add(f, "LinkStats", parts)
        if i % 5 == 2:
            f, name, parts = telemetry(i // 5, i)
            s.add(f, name, parts)
        if i == 300:
            s.noise(rnd, 150)
        if i == 500:
            f, _ = rc_frame(0xC8, sticks(i))
            bad = bytearray(f)
            bad[7] ^= 0x40
            s.raw(bad)
        if i == 700:
            f, _, _ = telemetry(0, i)
            s.raw(f[:7])
        if i == 900:
            s.raw(h("00 35 A4"))
    f, _ = rc_frame(0xC8, sticks(0))
    s.raw(f[:10])
    return s


def crsf_direction(rnd, rx_to_fc):
    s = Stream(CRSF_ADDRESSES)
    for i in range(300):
        if rx_to_fc:
            f, parts = rc_frame(0xC8, sticks(i))
            s.add(f, "RC", parts)
            if i % 4 == 0:
                f, parts = link_stats(i)
                s.add(f, "LinkStats", parts)
        elif i % 2 == 0:
            f, name, parts = telemetry(i // 2, i)
            s.add(f, name, parts)
        if i == 150:
            s.noise(rnd, 5)
    return s


# --- GHST ----------------------------------------------------------------------------------


def ghst_primary(v, legacy):
    q = ((5 * v) >> 2) - 430 if legacy else v
    return fixed(98800 + q * 25, 2)


def ghst_aux(a, legacy):
    return str(880 + 5 * a if legacy else 988 + 4 * a)


def ghst_rc(ty, i):
    legacy = ty < 0x30
    prim = [(1984 if legacy else 2048) + int(1500 * math.sin(i / (11.0 + 3 * k))) for k in range(4)]
    parts = [f"CH{k + 1}={ghst_primary(v, legacy)}" for k, v in enumerate(prim)]
    p = pack(prim, 12)
    if ty & 0x0F == 3:
        lq, r = 100 - i % 13, 60 + i % 40
        p += bytes([lq, r, 5, 20])
        parts += [f"RQly={lq}", f"RSSI={-r}", "RFMD=5", "TPWR=20"]
        name = "RCLink"
    else:
        first = 4 + 4 * (ty & 0x0F)
        aux = [(i * 7 + 40 * k) % 256 for k in range(4)]
        p += bytes(aux)
        parts += [f"CH{first + k + 1}={ghst_aux(a, legacy)}" for k, a in enumerate(aux)]
        name = "RC"
    return frame(0x82, ty, p), name, parts


def ghst_telemetry(k, i):
    kinds = [
        lambda: (frame(0x89, 0x23, le(1680 - i % 50, 2) + le(250, 2) + le(123, 2) + bytes([50, 0, 0, 0])),
                 "Battery", [f"RxBt={fixed(1680 - i % 50, 2)}", "Curr=2.50", "Capa=1230", "RxV=5.0"]),
        lambda: (frame(0x89, 0x25, le(473977000 + i, 4, True) + le(-86000000, 4, True) + le(412, 2, True)),
                 "GPS", [f"Lat={fixed(473977000 + i, 7)}", "Lon=-8.6000000", "Alt=412"]),
        lambda: (frame(0x89, 0x26, le(1630, 2) + le(1479, 2) + bytes([9]) + le(120, 2) + le(900, 2)
                       + bytes([3])), "GPS2",
                 ["GSpd=58.7", "Hdg=147.9", "Sats=9", "Dist=1200", "HDir=90.0"]),
        lambda: (frame(0x89, 0x27, le(1234, 2, True) + le(100, 2, True) + bytes([50, 0, 0, 0, 0, 7])),
                 "MagBaro", ["MHdg=123.4", "BAlt=100", "VSpd=0.50"]),
        lambda: (frame(0x89, 0x28, bytes([0x30, 2, 101, 0x11, 0x22, 0, 0, 0, 0, 0])), "MSPResp", None),
        lambda: (frame(0x82, 0x21, bytes([0x30, 0, 101, 0, 0, 0, 0, 0, 0, 0])), "MSPReq", None),
        lambda: (frame(0x80, 0x21, bytes([70, 100, 12]) + be(100, 2) + be(250, 2) + be(300, 2)
                       + bytes([2])), "LinkStats",
                 ["RSSI=-70", "RQly=100", "RSNR=12", "TPWR=100", "FRat=250", "TLat=300", "RFMD=2"]),
        lambda: (frame(0x80, 0x22, bytes([0]) + be(5800, 2) + be(25, 2) + bytes([2, 4, 0, 0, 0])),
                 "VTXStats", ["VFrq=5800", "VPwr=25", "VChn=4"]),
        lambda: (frame(0x80, 0x20, be(40000, 4) + be(-25, 4, True)), "Sync",
                 ["Intv=4000.0", "Offs=-2.5"]),
        lambda: (frame(0x80, 0x24, bytes([1, 0, 2]) + b"Band|Race".ljust(20, b"\0")), "Menu", None),
    ]
    return kinds[k % len(kinds)]()


def ghst_mixed(rnd):
    s = Stream(GHST_ADDRESSES)
    for i in range(1200):
        ty = [0x10, 0x11, 0x12, 0x13][i % 4] if i < 600 else [0x30, 0x31, 0x32, 0x33][i % 4]
        f, name, parts = ghst_rc(ty, i)
        s.add(f, name, parts)
        if i % 3 == 1:
            f, name, parts = ghst_telemetry(i // 3, i)
            s.add(f, name, parts)
        if i == 200:
            s.noise(rnd, 90)
        if i == 400:
            f, _, _ = ghst_rc(0x10, i)
            bad = bytearray(f)
            bad[5] ^= 0x01
            s.raw(bad)
        if i == 800:
            f, _, _ = ghst_telemetry(0, i)
            s.raw(f[:6])
    f, _, _ = ghst_rc(0x31, 0)
    s.raw(f[:8])
    return s


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "fixtures"
    check_public_vectors()
    rnd = random.Random(27)
    crsf_mixed(rnd).write(out, "crsf-mixed")
    crsf_direction(rnd, True).write(out, "crsf-rx-to-fc")
    crsf_direction(rnd, False).write(out, "crsf-fc-to-rx")
    ghst_mixed(rnd).write(out, "ghst-mixed")


if __name__ == "__main__":
    main()
