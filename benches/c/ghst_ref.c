// ghst_ref.c: a hand-tuned reference GHST decoder, the physical limit of `busnoop ghst FILE -f tsv`.
// SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), finds the frames by busnoop's resynchronisation rule (CRSF's framing with Ghost's
// addresses 0x80-0x89: a plausible address, a length 2..62 and a passing CRC-8/DVB-S2 over type
// and payload; a failed candidate is a bad frame unless a valid frame starts inside it, then
// only its first byte is garbage; garbage in runs of at most 64 bytes), decodes the frames of a
// Ghost receiver and a Betaflight flight controller on their one wire (RC frames 0x30-0x32: CH1-4
// of 12 bits and four 8-bit aux channels, in µs and raw; 0x33: CH1-4 and the RF protocol;
// telemetry to the receiver: battery 0x23, GPS 0x25, GPS 2 0x26, magnetometer/baro 0x27) and
// writes busnoop's TSV table (11 columns: Counter, Millis, ID, Device, Type, Sensor #, Sensor,
// Data, Value, Unit, Note) through a 64 KiB output buffer; Millis is the byte offset's time at
// 420000 baud 8N1. For a capture of those frames the output is byte-identical to busnoop's.
// Not covered (busnoop has them): the legacy RC types 0x10-0x1F, link and VTX statistics,
// menus, sync, MSP, and payloads of other lengths than the ten bytes Betaflight and the
// receiver send: these fall back to a generic hex row, so their cells differ from busnoop's,
// not their cost.
//
//   cc -O2 -march=x86-64-v2 -o ghst_ref ghst_ref.c
//   ./ghst_ref FILE > out.tsv
//   "$BIN" ghst FILE -f tsv --no-config | cmp - out.tsv
#define OBUF_EXTRA 8192
#include "ref_io.h"

#define LOOK 160  // bytes a decision may need past its position: two frames and more
static unsigned char ibuf[RD + LOOK + 64];

// ---- text helpers (ref_text.h, as sport_ref.c) ---------------------------------------------

#include "ref_text.h"

// ---- tables -------------------------------------------------------------------------------
static unsigned char CRC[256];   // CRC-8/DVB-S2, polynomial 0xD5
static unsigned char ADDR[256];  // bytes that may start a frame: 0x80-0x89
static const char *DEVICE[256];
#define FC 0x82
// numbers as text: up to 8 characters and the count
typedef struct { char s[8]; int n; } Num8;
static Num8 US12[4096], RAW12[4096], AUXUS[256], RAW8[256];
static const char *RFPROTO[256];
static const char *const GNAMES[] = {"Battery", "", "GPS", "GPS2", "MagBaro", "MSPResp"};  // 0x23..0x28

// the Type column of frame type ty sent to addr (NULL: unknown), as busnoop's names::frame_type
static const char *type_name(unsigned addr, unsigned ty) {
    if (ty == 0x13 && addr != FC) return "MenuCtrl";
    if (ty == 0x13 || ty == 0x33) return "RCLink";
    if ((ty >= 0x10 && ty <= 0x1F) || (ty >= 0x30 && ty <= 0x3F)) return "RC";
    if (ty == 0x20) return "Sync";
    if (ty == 0x21) return addr == FC ? "MSPReq" : "LinkStats";
    if (ty == 0x22) return addr == FC ? "MSPWrite" : "VTXStats";
    if (ty == 0x24) return "Menu";
    if (ty >= 0x23 && ty <= 0x28) return GNAMES[ty - 0x23];
    return NULL;
}

static void init_tables(void) {
    for (int i = 0; i < 256; i++) {
        unsigned c = (unsigned)i;
        for (int k = 0; k < 8; k++) c = c & 0x80 ? ((c << 1) ^ 0xD5) & 0xFF : (c << 1) & 0xFF;
        CRC[i] = (unsigned char)c;
        DEVICE[i] = "";
        RFPROTO[i] = "unknown";
    }
    static const char *const D[] = {"Radio", "TX module", "FC", "Goggles", "Tee 1", "Tee 2",
                                    "Gateway", "5G clock", "TX module 115k", "Receiver"};
    for (int a = 0; a < 10; a++) { ADDR[0x80 + a] = 1; DEVICE[0x80 + a] = D[a]; }
    RFPROTO[0x00] = "undefined"; RFPROTO[0x05] = "Normal"; RFPROTO[0x06] = "Race";
    RFPROTO[0x07] = "PureRace"; RFPROTO[0x08] = "LongRange"; RFPROTO[0x0A] = "Race250";
    RFPROTO[0x0B] = "Race500"; RFPROTO[0x0C] = "Solid150"; RFPROTO[0x0D] = "Solid250";
    char t[24];
    for (int r = 0; r < 4096; r++) {
        long h = 98800 + 25L * r;  // µs × 100 on the 12-bit scale (988 + v / 4)
        US12[r].n = snprintf(t, sizeof t, "%ld.%02ld", h / 100, h % 100); memcpy(US12[r].s, t, 8);
        RAW12[r].n = snprintf(t, sizeof t, "%d", r); memcpy(RAW12[r].s, t, 8);
    }
    for (int a = 0; a < 256; a++) {
        AUXUS[a].n = snprintf(t, sizeof t, "%d", 988 + 4 * a); memcpy(AUXUS[a].s, t, 8);
        RAW8[a].n = snprintf(t, sizeof t, "%d", a); memcpy(RAW8[a].s, t, 8);
    }
}

// ---- rows ---------------------------------------------------------------------------------
#define REF_NAME "ghst_ref"
#include "crsf_frame.h"

static inline unsigned le16(const unsigned char *p) { return (unsigned)(p[0] | p[1] << 8); }
static inline int sle16(const unsigned char *p) { return (int16_t)(p[0] | p[1] << 8); }
static inline int32_t le32(const unsigned char *p) { return (int32_t)((uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0]); }
#define PUTN(w, t) (memcpy((w), (t).s, 8), (w) + (t).n)

// a valid frame f[0..len): its row
static void frame_row(const unsigned char *f, int len, uint64_t off) {
    garbage_flush();
    frames++;
    const unsigned char *p = f + 3;
    int n = len - 4;  // payload bytes
    unsigned ty = f[2], addr = f[0];
    char *w = row_start(off);
    w = put_addr(w, addr);
    char *v0, *v1;
    if (ty >= 0x30 && ty <= 0x33 && n == 10 && !(ty == 0x33 && addr != FC)) {
        unsigned raw[4];
        raw[0] = (unsigned)(p[0] | (p[1] & 15) << 8); raw[1] = (unsigned)(p[1] >> 4 | p[2] << 4);
        raw[2] = (unsigned)(p[3] | (p[4] & 15) << 8); raw[3] = (unsigned)(p[4] >> 4 | p[5] << 4);
        w = ty == 0x33 ? PUTS(w, "RCLink\t0x33\tCH1\t") : PUTS(w, "RC\t0x3");
        if (ty != 0x33) { *w++ = (char)('0' + (ty & 15)); w = PUTS(w, "\tCH1\t"); }
        for (int k = 0; k < 4; k++) { w = PUTN(w, US12[raw[k]]); *w++ = ' '; }
        if (ty != 0x33)
            for (int k = 0; k < 4; k++) { w = PUTN(w, AUXUS[p[6 + k]]); *w++ = ' '; }
        w[-1] = '\t';
        w = PUTN(w, US12[raw[0]]);
        w = PUTS(w, "\tus\traw");
        for (int k = 0; k < 4; k++) { *w++ = ' '; w = PUTN(w, RAW12[raw[k]]); }
        if (ty != 0x33) {
            w = PUTS(w, "; aux raw");
            for (int k = 0; k < 4; k++) { *w++ = ' '; w = PUTN(w, RAW8[p[6 + k]]); }
        } else {
            w = PUTS(w, "; RF protocol "); w = put_cstr(w, RFPROTO[p[8]]);
        }
        w = PUTS(w, "; 12-bit scale");
    } else if (ty == 0x23 && n == 10) {
        w = PUTS(w, "Battery\t0x23\tRxBt\tRxBt=");
        v0 = w; w = put_fixed(w, le16(p), 2); v1 = w;
        w = PUTS(w, "V Curr="); w = put_fixed(w, le16(p + 2), 2);
        w = PUTS(w, "A Capa="); w = put_u64(w, (uint64_t)le16(p + 4) * 10);
        w = PUTS(w, "mAh RxV="); w = put_fixed(w, p[6], 1);
        w = PUTS(w, "V\t"); w = put_again(w, v0, v1); w = PUTS(w, "\tV\t");
    } else if (ty == 0x25 && n == 10) {
        w = PUTS(w, "GPS\t0x25\tGPS\tLat=");
        v0 = w; w = put_fixed(w, le32(p), 7); v1 = w;
        w = PUTS(w, "deg Lon="); w = put_fixed(w, le32(p + 4), 7);
        w = PUTS(w, "deg Alt="); w = put_i64(w, sle16(p + 8));
        w = PUTS(w, "m\t"); w = put_again(w, v0, v1); w = PUTS(w, "\tdeg\t");
    } else if (ty == 0x26 && n == 10) {
        w = PUTS(w, "GPS2\t0x26\tGSpd\tGSpd=");
        v0 = w; w = put_fixed(w, ((int64_t)le16(p) * 36 + 50) / 100, 1); v1 = w;
        w = PUTS(w, "km/h Hdg="); w = put_fixed(w, le16(p + 2), 1);
        w = PUTS(w, "deg Sats="); w = put_u64(w, p[4]);
        w = PUTS(w, " Dist="); w = put_u64(w, (uint64_t)le16(p + 5) * 10);
        w = PUTS(w, "m HDir="); w = put_fixed(w, le16(p + 7), 1);
        w = PUTS(w, "deg\t"); w = put_again(w, v0, v1); w = PUTS(w, "\tkm/h\t");
        w = p[9] & 1 ? PUTS(w, "fix") : PUTS(w, "no fix");
        w = p[9] & 2 ? PUTS(w, ", home set") : PUTS(w, ", no home");
    } else if (ty == 0x27 && n == 10 && (p[9] & 7) >= 2) {  // at least the altitude valid
        unsigned fl = p[9];
        const char *unit;
        w = PUTS(w, "MagBaro\t0x27\t");
        if (fl & 1) {
            w = PUTS(w, "MHdg\tMHdg="); v0 = w; w = put_fixed(w, sle16(p), 1); v1 = w;
            w = PUTS(w, "deg BAlt="); w = put_i64(w, sle16(p + 2)); w = PUTS(w, "m"); unit = "deg";
        } else {
            w = PUTS(w, "BAlt\tBAlt="); v0 = w; w = put_i64(w, sle16(p + 2)); v1 = w;
            w = PUTS(w, "m"); unit = "m";
        }
        if (fl & 4) { w = PUTS(w, " VSpd="); w = put_fixed(w, (int8_t)p[4], 2); w = PUTS(w, "m/s"); }
        *w++ = '\t'; w = put_again(w, v0, v1); *w++ = '\t'; w = put_cstr(w, unit); *w++ = '\t';
        if ((fl & 7) != 7) { w = PUTS(w, "flags "); w = put_0x(w, fl); w = PUTS(w, ": only the fields flagged valid are shown"); }
    } else {  // not covered: a generic row (busnoop has its own cells for these; cost alike)
        const char *name = type_name(addr, ty);
        w = put_cstr(w, name ? name : "Unknown"); *w++ = '\t';
        w = put_0x(w, ty); w = PUTS(w, "\t\t");
        w = put_hex_bytes(w, p, n);
        w = PUTS(w, "\t\t\t");
    }
    *w++ = '\n'; o = w;
}
