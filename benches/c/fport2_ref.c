// fport2_ref.c: a hand-tuned reference F.Port 2 decoder, the physical limit of `busnoop fport FILE -f tsv`
// on an F.Port 2 line.
// SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), reassembles F.Port 2 frames by busnoop's rules (`[len][type][data][crc]`, no
// delimiters, no stuffing: a frame is recognised by its first two bytes — control `0D|18|23 FF`,
// OTA `18|20 F0-F2`, telemetry `08 [physical ID]` as the downlink after a control frame and the
// uplink after a downlink, elsewhere only with valid S.Port check bits and a good checksum —
// and a frame whose checksum fails is searched for a good frame starting inside it, which cuts
// it short), checks the FrSky checksum (end-around carry sum over type..data), decodes the
// control frames of 16 channels (in whole µs for the Data cell, the first exactly in the Value,
// the raw values and the flags in the Note), the receiver's null polls of any physical ID, the
// flight controller's null answers and its S.Port data answers (busnoop's sensor table for the
// sensors INAV and Betaflight send: voltages, current, fuel, altitude, vario, heading,
// accelerations, GPS, temperatures), bad-checksum and cut frames and garbage, and writes
// busnoop's TSV table (12 columns, as fport_ref.c) through a 64 KiB output buffer; Millis is the
// byte offset's time at 115200 baud 8N1. For a capture of those frames the output is
// byte-identical to busnoop's (with the framing busnoop detects). Not covered (busnoop has
// them): 8- and 24-channel control frames, OTA frames, other S.Port frames and sensors, MSP,
// frames without a control frame before them (direction guessed), wrong check bits: these fall
// back to a generic row, so their cells differ from busnoop's, not their cost. FBUS is the same
// framing at 460800 baud (busnoop's Millis then differ: not covered).
//
//   cc -O2 -march=x86-64-v2 -o fport2_ref fport2_ref.c
//   ./fport2_ref FILE > out.tsv
//   "$BIN" fport FILE -f tsv --no-config | cmp - out.tsv
#include "ref_io.h"
#include "ref_text.h"
#include "fport_rows.h"

#define KEEP 128                        // bytes held back for a frame and the search inside it
static unsigned char buf[KEEP + RD];    // the bytes not yet consumed, then the chunk read
static const char *const DEVICE[32] = {
    "Vario", "FLVSS", "FAS-40S", "GPS", "RPM", "SP2UART-H", "SP2UART-R", "FCS-150A", "", "ASS-70", "", "",
    "", "Uplink", "", "", "ESC", "Config", "", "", "Downlink", "", "Gas Suite", "IMU", "Receiver",
    "Power Box", "Temp", "FC", "", "", "", "",
};
static unsigned char HEADER[32];  // the S.Port header byte (ID and check bits) of each ID

enum { NONE, CONTROL, DOWNLINK, UPLINK };  // roles, and what the frame before was (ctx)
enum { NO, MORE, FRAME };
typedef struct { int what, total, ok, role, strong, guessed; } Cand;
static int at_eof;  // the input has ended

static inline int check_ok(const unsigned char *p, int total) { return carry_sum(p + 1, total - 1) == 0xFF; }

// what starts at p (end: the first byte not there) when the frame before was ctx
static Cand candidate(const unsigned char *p, const unsigned char *end, int ctx) {
    Cand c = {MORE, 0, 0, NONE, 0, 0};
    if (p >= end) return c;
    unsigned b0 = p[0];
    if (!(b0 == 0x0D || b0 == 0x18 || b0 == 0x23 || b0 == 0x20 || b0 == 0x08)) { c.what = NO; return c; }
    if (p + 1 >= end) return c;
    unsigned b1 = p[1];
    int avail = (int)(end - p);
    if (b1 == 0xFF && b0 != 0x20 && b0 != 0x08) {
        c.total = (int)b0 + 3; c.role = CONTROL; c.strong = 1;
    } else if ((b0 == 0x18 || b0 == 0x20) && b1 >= 0xF0 && b1 <= 0xF2) {  // OTA: either size
        int total = (int)b0 + 3, other = b0 == 0x20 ? 0x18 + 3 : 0x20 + 3;
        c.role = CONTROL; c.strong = 1;
        int w = total <= avail ? check_ok(p, total) : -1, v = other <= avail ? check_ok(p, other) : -1;
        if (w == 1) { c.what = FRAME; c.total = total; c.ok = 1; }
        else if (w == 0 && v == 1) { c.what = FRAME; c.total = other; c.ok = 1; }
        else if (w == 0 && v == 0) { c.what = FRAME; c.total = total; }
        else if (w == 0 && v < 0 && at_eof) { c.what = FRAME; c.total = total; }
        return c;  // otherwise MORE (strong)
    } else if (b0 == 0x08) {
        c.total = 10;
        if (ctx == CONTROL) { c.role = DOWNLINK; c.strong = 1; }
        else if (ctx == DOWNLINK) { c.role = UPLINK; c.strong = 1; }
        else if (HEADER[b1 & 0x1F] == b1) {
            c.role = (p + 2 < end && (p[2] == 0x10 || p[2] == 0x32)) ? UPLINK : DOWNLINK; c.guessed = 1;
        } else { c.what = NO; return c; }
    } else { c.what = NO; return c; }
    if (c.total > avail) return c;
    c.ok = check_ok(p, c.total);
    if (c.ok || c.strong) c.what = FRAME; else c.what = NO;
    return c;
}

static const char *const FRAME_NAME[4] = {"", "Control", "Downlink", "Uplink"};
static const char *const LONG_NAME[4] = {"frame", "control frame", "downlink frame", "uplink frame"};

static inline char *id_cells(char *w, int role, unsigned b1) {
    if (role == DOWNLINK || role == UPLINK) {
        w = put_u64(w, b1 & 0x1F); *w++ = '\t'; w = put_cstr(w, DEVICE[b1 & 0x1F]); *w++ = '\t';
    } else { *w++ = '\t'; *w++ = '\t'; }
    return w;
}

// a frame of n bytes at stream offset off; check: 1 ok, 2 bad, 3 cut
static void frame_row(const unsigned char *f, int n, uint64_t off, int check, int role, int guessed) {
    garbage_flush();
    char *w = row_start(off);
    if (check != 1) {
        w = id_cells(w, n < 2 ? NONE : role, n < 2 ? 0 : f[1]);
        w = check == 2 ? PUTS(w, "BadCRC\t\t\t") : PUTS(w, "Truncated\t\t\t");
        w = put_hex_bytes(w, f, n);
        w = PUTS(w, "\t\t\t"); w = put_cstr(w, FRAME_NAME[role]); *w++ = '\t';
        if (check == 2) {
            w = PUTS(w, "checksum "); w = put_0x(w, f[n - 1]);
            w = PUTS(w, ", expected "); w = put_0x(w, 0xFF - carry_sum(f + 1, n - 2));
            w = PUTS(w, " ("); w = put_cstr(w, LONG_NAME[role]); *w++ = ')';
        } else {
            w = put_u64(w, (uint64_t)n); w = PUTS(w, " of ");
            w = put_u64(w, f[0] == 0x08 ? 10 : (uint64_t)f[0] + 3);
            w = PUTS(w, " bytes before the "); w = put_cstr(w, LONG_NAME[role]); w = PUTS(w, " was cut");
        }
    } else if (role == CONTROL && f[0] == 0x18 && f[1] == 0xFF) {
        w = control_cells(w, f + 2);
    } else if (!guessed && role == DOWNLINK && HEADER[f[1] & 0x1F] == f[1] &&
               !(f[2] | f[3] | f[4] | f[5] | f[6] | f[7] | f[8])) {  // the receiver's poll
        w = id_cells(w, role, f[1]);
        w = PUTS(w, "\t\t\t\t\t\tDownlink\t");
    } else if (!guessed && role == UPLINK && HEADER[f[1] & 0x1F] == f[1] && f[2] == 0x10) {
        w = id_cells(w, role, f[1]);
        w = data_cells(w, (unsigned)(f[3] | f[4] << 8), le32(f + 5));
    } else if (!guessed && role == UPLINK && HEADER[f[1] & 0x1F] == f[1] &&
               !(f[2] | f[3] | f[4] | f[5] | f[6] | f[7] | f[8])) {  // a null answer
        w = id_cells(w, role, f[1]);
        w = PUTS(w, "Null\t\t\t\t\t\tUplink\t");
    } else {  // not covered: a generic row (busnoop has its own cells for these; cost alike)
        w = id_cells(w, role, f[1]);
        w = PUTS(w, "Unknown\t\t\t");
        w = put_hex_bytes(w, f + 2, n - 3);
        w = PUTS(w, "\t\t\t"); w = put_cstr(w, FRAME_NAME[role]); *w++ = '\t';
    }
    *w++ = '\n'; o = w;
}

// ---- reassembly (busnoop's fport/v2.rs rules) ---------------------------------------------
static int ctx = NONE;
static uint64_t base;  // stream offset of buf[0]

// Reads from p up to end; stops (returns where) when a decision needs bytes not there yet
// (never at the end of the input, eof).
static const unsigned char *run(const unsigned char *p, const unsigned char *end, int eof) {
    at_eof = eof;
    while (p < end) {
        if (!eof && end - p < KEEP) return p;  // a frame and the search inside it fit in KEEP
        Cand c = candidate(p, end, ctx);
        uint64_t off = base + (uint64_t)(p - buf);
        if (c.what == NO || (c.what == MORE && !c.strong)) {
            garbage_byte(*p, off); p++; ctx = NONE;
            continue;
        }
        int after = c.role;  // what an 08 frame after this one is
        int total = c.what == MORE ? (int)(end - p) : c.total, q = 0;
        if (c.what == MORE || !c.ok) {  // a good frame inside it cuts it short
            for (int k = 1; k < total && !q; k++) {
                Cand in = candidate(p + k, end, after);
                if (in.what == FRAME && in.ok) q = k;
            }
        }
        if (q) frame_row(p, q, off, 3, c.role, 0), total = q;
        else frame_row(p, total, off, c.what == MORE ? 3 : c.ok ? 1 : 2, c.role, c.guessed);
        p += total; ctx = after;
    }
    return p;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: fport2_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    for (int id = 0; id < 32; id++) {
        unsigned b0 = id & 1, b1 = id >> 1 & 1, b2 = id >> 2 & 1, b3 = id >> 3 & 1, b4 = id >> 4 & 1;
        HEADER[id] = (unsigned char)(id | (b0 ^ b1 ^ b2) << 5 | (b2 ^ b3 ^ b4) << 6 | (b0 ^ b2 ^ b4) << 7);
    }
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tFrame\tNote\n");
    size_t held = 0;
    for (;;) {
        ssize_t r = read(fd, buf + held, RD);
        if (r < 0) return 3;
        const unsigned char *end = buf + held + (size_t)r;
        const unsigned char *p = run(buf, end, r == 0);
        if (r == 0) break;
        held = (size_t)(end - p);
        memmove(buf, p, held);
        base += (uint64_t)(p - buf);
    }
    garbage_flush();
    flush_out();
    return 0;
}
