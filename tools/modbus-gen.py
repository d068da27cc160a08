#!/usr/bin/env python3
"""Generates Modbus RTU traffic as a USB-serial adapter delivers it, for busnoop's fixtures.

A master polls three slaves on a 19200 8E1 line: reads of holding and input registers, coils and
discrete inputs, writes of single and multiple registers and coils, read/write multiple
registers, diagnostics and a device identification; a long response (125 registers, 255 bytes,
about 146 ms on the wire); exceptions; a slave that does not answer (the master's retry after
1.2 s, then it gives up and polls the next); an answer after the timeout; a broadcast write; a
response with a bit error; and RS-485 turnaround bytes (0x00 or 0xFF) after a third of the frames.

The adapter is modelled as an FTDI chip: it hands bytes over in USB transfers of at most 62 bytes,
when 62 have arrived or 16 ms (its latency timer) after the first one of a transfer; each read
gets the time it is handed over. So a long response arrives in many reads, and a request and a
quick answer in one.

Writes, into the folder given (default fixtures/):

    modbus-gen.pcap    a busnoop recording (pcap, link type RTAC serial 250), one record a read
    modbus-gen.bin     the same bytes without times
    modbus-gen.expect  the rows busnoop must show, one a line: TYPE ID FUNCTION, and `timed` after
                       a row that only a timed source can show (a deadline passed)

Standard library only; the seed is fixed, so the files are always the same.
"""

import os
import random
import struct
import sys

BAUD = 19200
BITS = 11  # 8E1
CHAR_US = BITS * 1_000_000 / BAUD
TIMEOUT_US = 1_000_000  # busnoop's default master timeout
USB_MAX = 62
LATENCY_US = 16_000


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def frame(*pdu):
    body = bytes(pdu)
    c = crc16(body)
    return body + bytes([c & 0xFF, c >> 8])


def u16(v):
    return [v >> 8 & 0xFF, v & 0xFF]


class Line:
    def __init__(self, rng):
        self.rng = rng
        self.t = 0.0  # µs, the end of the last byte on the line
        self.bytes = []  # (arrival µs, byte)
        self.expect = []

    def send(self, data, gap_us, row):
        """`data` starts `gap_us` after the line went quiet and shows as `row` (TYPE, ID,
        FUNCTION); a turnaround byte may follow."""
        self.t += gap_us
        for b in data:
            self.t += CHAR_US
            self.bytes.append((self.t, b))
        self.row(*row)
        if self.rng.random() < 0.35:
            self.t += CHAR_US
            self.bytes.append((self.t, self.rng.choice([0x00, 0xFF])))
            self.expect.append(("Garbage", "-", "-"))

    def row(self, kind, slave, fc, timed=False):
        self.expect.append((kind, str(slave), f"0x{fc:02X}") + (("timed",) if timed else ()))


def request(line, slave, pdu, gap=None):
    gap = gap if gap is not None else line.rng.uniform(20_000, 60_000)
    line.send(frame(slave, *pdu), gap, ("Request", slave, pdu[0]))


def answer(line, slave, pdu, delay=None, kind="Response"):
    delay = delay if delay is not None else line.rng.uniform(3_000, 25_000)
    line.send(frame(slave, *pdu), delay, (kind, slave, pdu[0] & 0x7F))


def exchange(line, slave, fc):
    r = line.rng
    start = r.randrange(0, 2000)
    if fc in (3, 4):
        n = r.randrange(1, 10)
        request(line, slave, [fc, *u16(start), *u16(n)])
        vals = []
        for _ in range(n):
            vals += u16(r.randrange(0, 65536))
        answer(line, slave, [fc, 2 * n, *vals])
    elif fc in (1, 2):
        n = r.randrange(1, 40)
        request(line, slave, [fc, *u16(start), *u16(n)])
        nb = (n + 7) // 8
        answer(line, slave, [fc, nb, *[r.randrange(256) for _ in range(nb)]])
    elif fc == 5:
        pdu = [5, *u16(start), r.choice([0xFF, 0x00]), 0]
        request(line, slave, pdu)
        answer(line, slave, pdu)
    elif fc == 6:
        pdu = [6, *u16(start), *u16(r.randrange(65536))]
        request(line, slave, pdu)
        answer(line, slave, pdu)
    elif fc == 15:
        n = r.randrange(1, 20)
        nb = (n + 7) // 8
        request(line, slave, [15, *u16(start), *u16(n), nb, *[r.randrange(256) for _ in range(nb)]])
        answer(line, slave, [15, *u16(start), *u16(n)])
    elif fc == 16:
        n = r.randrange(1, 6)
        vals = []
        for _ in range(n):
            vals += u16(r.randrange(65536))
        request(line, slave, [16, *u16(start), *u16(n), 2 * n, *vals])
        answer(line, slave, [16, *u16(start), *u16(n)])
    elif fc == 23:
        n, w = r.randrange(1, 5), r.randrange(1, 4)
        vals = []
        for _ in range(w):
            vals += u16(r.randrange(65536))
        request(line, slave, [23, *u16(start), *u16(n), *u16(start + 100), *u16(w), 2 * w, *vals])
        rv = []
        for _ in range(n):
            rv += u16(r.randrange(65536))
        answer(line, slave, [23, 2 * n, *rv])
    elif fc == 8:
        pdu = [8, 0, 0, *u16(r.randrange(65536))]
        request(line, slave, pdu)
        answer(line, slave, pdu)
    elif fc == 43:
        request(line, slave, [43, 14, 1, 0])
        objs = []
        for i, text in enumerate([b"busnoop", b"GEN-1", b"1.0"]):
            objs += [i, len(text), *text]
        answer(line, slave, [43, 14, 1, 1, 0, 0, 3, *objs])


def session(seed=28):
    r = random.Random(seed)
    line = Line(r)
    slaves = [1, 2, 7]
    plain = [3, 4, 1, 2, 6, 16, 5, 15, 23, 8]
    for i in range(60):
        slave = slaves[i % 3]
        special = i % 10
        if i == 5:
            # A long response: 125 registers, 255 bytes, in about ten USB transfers.
            request(line, slave, [3, 0, 0, 0, 125])
            vals = []
            for k in range(125):
                vals += u16(k * 7)
            answer(line, slave, [3, 250, *vals])
        elif i == 12:
            # No answer: the master tries again after 1.2 s, then gives up and moves on.
            pdu = [3, 0, 10, 0, 2]
            request(line, 7, pdu)
            line.row("Timeout", 7, 3)
            line.send(frame(7, *pdu), 1_200_000, ("Request", 7, 3))
            line.row("Timeout", 7, 3)
            request(line, 1, [4, 0, 0, 0, 1], gap=1_300_000)
            answer(line, 1, [4, 2, 0, 42])
        elif i == 20:
            # An exception.
            request(line, slave, [3, *u16(9000), 0, 4])
            answer(line, slave, [0x83, 2], kind="Exception")
        elif i == 27:
            # A broadcast write: nobody answers.
            line.send(frame(0, 6, 0, 1, 0, 7), 40_000, ("Request", 0, 6))
        elif i == 33:
            # A response with a bit error: no Timeout row for its request.
            request(line, 2, [3, 0, 20, 0, 2])
            bad = bytearray(frame(2, 3, 4, 1, 2, 3, 4))
            bad[4] ^= 0x08
            line.send(bytes(bad), 8_000, ("BadCRC", 2, 3))
        elif i == 41:
            # An answer after the master timeout: late (a Timeout row first, when timed).
            request(line, 2, [4, 0, 5, 0, 1])
            line.row("Timeout", 2, 4, timed=True)
            answer(line, 2, [4, 2, 1, 0], delay=1_100_000)
        elif i == 50:
            request(line, 1, [43, 14, 1, 0])
            objs = []
            for k, text in enumerate([b"busnoop", b"GEN-1", b"1.0"]):
                objs += [k, len(text), *text]
            answer(line, 1, [43, 14, 1, 1, 0, 0, 3, *objs])
        else:
            exchange(line, slave, plain[(i + special) % len(plain)])
    return line


def reads(line):
    """The line's bytes as an FTDI adapter hands them over: (time µs, bytes)."""
    out = []
    chunk = []
    first = None
    for t, b in line.bytes:
        if chunk and (t > first + LATENCY_US or len(chunk) == USB_MAX):
            out.append((min(first + LATENCY_US, t), bytes(chunk)))
            chunk = []
        if not chunk:
            first = t
        chunk.append(b)
    if chunk:
        out.append((first + LATENCY_US, bytes(chunk)))
    return out


def pcap(records, start_s=1_767_225_600):
    """A busnoop recording: classic pcap, link type 250 (RTAC serial)."""
    out = bytearray(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 250))

    def rec(us, event, data):
        s, u = start_s + us // 1_000_000, us % 1_000_000
        payload = struct.pack(">IIBBH", s, u, event, 0, 0) + data
        out.extend(struct.pack("<IIII", s, u, len(payload), len(payload)))
        out.extend(payload)

    rec(0, 0x00, b"busnoop capture start")
    for t, data in records:
        rec(int(t), 0x02, data)
    return bytes(out)


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else "fixtures"
    line = session()
    rs = reads(line)
    with open(os.path.join(folder, "modbus-gen.pcap"), "wb") as f:
        f.write(pcap(rs))
    with open(os.path.join(folder, "modbus-gen.bin"), "wb") as f:
        f.write(bytes(b for _, b in line.bytes))
    with open(os.path.join(folder, "modbus-gen.expect"), "w") as f:
        f.write("# TYPE ID FUNCTION [timed]: the rows of modbus-gen.pcap (tools/modbus-gen.py)\n")
        for e in line.expect:
            f.write(" ".join(e) + "\n")
    print(f"{len(line.bytes)} bytes in {len(rs)} reads, {len(line.expect)} rows expected")


if __name__ == "__main__":
    main()
