// crsf_ref.c: a hand-tuned reference CRSF decoder, the physical limit of `busnoop crsf FILE -f tsv`.
// SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), finds the frames by busnoop's resynchronisation rule (a plausible address, a length
// 2..62 and a passing CRC-8/DVB-S2 over type and payload; a failed candidate is a bad frame
// unless a valid frame starts inside it, then only its first byte is garbage; garbage in runs
// of at most 64 bytes), decodes the frames of an ExpressLRS receiver and a Betaflight flight
// controller (RC channels 0x16 in µs on Betaflight's scale with their raw values, link
// statistics 0x14, battery 0x08, GPS 0x02, attitude 0x1E, flight mode 0x21) and writes
// busnoop's TSV table (11 columns: Counter, Millis, ID, Device, Type, Sensor #, Sensor, Data,
// Value, Unit, Note) through a 64 KiB output buffer; Millis is the byte offset's time at
// 420000 baud 8N1. For a capture of those frames the output is byte-identical to busnoop's.
// Not covered (busnoop has them): every other frame type, payloads of other lengths than the
// senders write and unknown RF power indexes: these
// fall back to a generic hex row, so their cells differ from busnoop's, not their cost.
//
//   cc -O2 -march=x86-64-v2 -o crsf_ref crsf_ref.c
//   ./crsf_ref FILE > out.tsv
//   "$BIN" crsf FILE -f tsv --no-config | cmp - out.tsv
#define OBUF_EXTRA 8192
#include "ref_io.h"

#define LOOK 160  // bytes a decision may need past its position: two frames and more
static unsigned char ibuf[RD + LOOK + 64];

// ---- text helpers (ref_text.h, as sport_ref.c) ---------------------------------------------

#include "ref_text.h"

// ---- tables -------------------------------------------------------------------------------
static unsigned char CRC[256];   // CRC-8/DVB-S2, polynomial 0xD5
static unsigned char ADDR[256];  // bytes that may start a frame
static const unsigned char ADDRS[] = {
    0x00, 0x0E, 0x10, 0x12, 0x13, 0x14, 0x80, 0x8A, 0x90, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97,
    0xB0, 0xB2, 0xC0, 0xC2, 0xC4, 0xC8, 0xCA, 0xCC, 0xCE, 0xEA, 0xEC, 0xEE, 0xEF, 0xF0, 0xF2};
static const char *DEVICE[256];
static const char *TYPE[256];
// a channel's µs and raw value as text: up to 4 digits and the count
typedef struct { char s[4]; int n; } Num4;
static Num4 US[2048], RAW[2048];
static const uint16_t POWER_MW[9] = {0, 10, 25, 100, 500, 1000, 2000, 250, 50};

static void init_tables(void) {
    for (int i = 0; i < 256; i++) {
        unsigned c = (unsigned)i;
        for (int k = 0; k < 8; k++) c = c & 0x80 ? ((c << 1) ^ 0xD5) & 0xFF : (c << 1) & 0xFF;
        CRC[i] = (unsigned char)c;
        DEVICE[i] = "";
    }
    for (size_t i = 0; i < sizeof ADDRS; i++) ADDR[ADDRS[i]] = 1;
    static const struct { unsigned char a; const char *n; } D[] = {
        {0x00, "Broadcast"}, {0x0E, "Cloud"}, {0x10, "USB"}, {0x12, "Bluetooth"}, {0x13, "WiFi RX"},
        {0x14, "VRX"}, {0x80, "OSD"}, {0x8A, "Reserved"}, {0xCA, "Reserved"}, {0xF0, "Reserved"},
        {0xF2, "Reserved"}, {0x90, "ESC1"}, {0x91, "ESC2"}, {0x92, "ESC3"}, {0x93, "ESC4"},
        {0x94, "ESC5"}, {0x95, "ESC6"}, {0x96, "ESC7"}, {0x97, "ESC8"}, {0xB0, "Crossfire"},
        {0xB2, "Crossfire"}, {0xC0, "Current sensor"}, {0xC2, "GPS"}, {0xC4, "Blackbox"},
        {0xC8, "FC"}, {0xCC, "Race tag"}, {0xCE, "VTX"}, {0xEA, "Radio"}, {0xEC, "Receiver"},
        {0xEE, "TX module"}, {0xEF, "ELRS Lua"}};
    for (size_t i = 0; i < sizeof D / sizeof D[0]; i++) DEVICE[D[i].a] = D[i].n;
    static const struct { unsigned char t; const char *n; } T[] = {
        {0x02, "GPS"}, {0x08, "Battery"}, {0x14, "LinkStats"}, {0x16, "RC"}, {0x1E, "Attitude"},
        {0x21, "FlightMode"}};
    for (size_t i = 0; i < sizeof T / sizeof T[0]; i++) TYPE[T[i].t] = T[i].n;
    for (int r = 0; r < 2048; r++) {
        char t[16];
        // Betaflight's scale, rounded to the nearest µs
        long us = (long)(0.62477120195241 * (double)r + 881.0 + 0.5);  // x > 0: as round()
        US[r].n = snprintf(t, sizeof t, "%ld", us); memcpy(US[r].s, t, 4);
        RAW[r].n = snprintf(t, sizeof t, "%d", r); memcpy(RAW[r].s, t, 4);
    }
}

// ---- rows ---------------------------------------------------------------------------------
static inline const char *type_name(unsigned addr, unsigned ty) { (void)addr; return TYPE[ty]; }
#define REF_NAME "crsf_ref"
#include "crsf_frame.h"

static inline int be16(const unsigned char *p) { return (int16_t)(p[0] << 8 | p[1]); }
static inline unsigned ube16(const unsigned char *p) { return (unsigned)(p[0] << 8 | p[1]); }
static inline int32_t be32(const unsigned char *p) { return (int32_t)((uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]); }
static inline int64_t rssi(unsigned b) { return b >= 0x80 ? (int64_t)(int8_t)b : -(int64_t)b; }

// a valid frame f[0..len): its row
static void frame_row(const unsigned char *f, int len, uint64_t off) {
    garbage_flush();
    frames++;
    const unsigned char *p = f + 3;
    int n = len - 4;  // payload bytes
    unsigned ty = f[2];
    char *w = row_start(off);
    w = put_addr(w, f[0]);
    char *v0, *v1;
    if (ty == 0x16 && n == 22) {
        w = PUTS(w, "RC\t0x16\tCH1\t");
        unsigned raw[16];
        for (int k = 0; k < 16; k++) {
            int bit = 11 * k;
            const unsigned char *q = p + (bit >> 3);
            uint32_t x = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16;  // q[2] may be the CRC
            raw[k] = (x >> (bit & 7)) & 0x7FF;
        }
        for (int k = 0; k < 16; k++) {
            const Num4 *u = &US[raw[k]];
            memcpy(w, u->s, 4); w += u->n; *w++ = ' ';
        }
        w[-1] = '\t';
        const Num4 *u = &US[raw[0]];
        memcpy(w, u->s, 4); w += u->n;
        w = PUTS(w, "\tus\traw");
        for (int k = 0; k < 16; k++) {
            const Num4 *r = &RAW[raw[k]];
            *w++ = ' '; memcpy(w, r->s, 4); w += r->n;
        }
    } else if (ty == 0x14 && n == 10 && p[6] < 9) {
        w = PUTS(w, "LinkStats\t0x14\t1RSS\t1RSS=");
        v0 = w; w = put_i64(w, rssi(p[0])); v1 = w;
        w = PUTS(w, "dBm 2RSS="); w = put_i64(w, rssi(p[1]));
        w = PUTS(w, "dBm RQly="); w = put_u64(w, p[2]);
        w = PUTS(w, "% RSNR="); w = put_i64(w, (int8_t)p[3]);
        w = PUTS(w, "dB ANT="); w = put_u64(w, p[4]);
        w = PUTS(w, " RFMD="); w = put_u64(w, p[5]);
        w = PUTS(w, " TPWR="); w = put_u64(w, POWER_MW[p[6]]);
        w = PUTS(w, "mW TRSS="); w = put_i64(w, rssi(p[7]));
        w = PUTS(w, "dBm TQly="); w = put_u64(w, p[8]);
        w = PUTS(w, "% TSNR="); w = put_i64(w, (int8_t)p[9]);
        w = PUTS(w, "dB\t"); w = put_again(w, v0, v1); w = PUTS(w, "\tdBm\t");
    } else if (ty == 0x08 && n == 8) {
        w = PUTS(w, "Battery\t0x08\tRxBt\tRxBt=");
        v0 = w; w = put_fixed(w, be16(p), 1); v1 = w;
        w = PUTS(w, "V Curr="); w = put_fixed(w, be16(p + 2), 1);
        w = PUTS(w, "A Capa="); w = put_u64(w, (uint64_t)p[4] << 16 | (uint64_t)p[5] << 8 | p[6]);
        w = PUTS(w, "mAh Bat%="); w = put_u64(w, p[7]);
        w = PUTS(w, "%\t"); w = put_again(w, v0, v1); w = PUTS(w, "\tV\t");
    } else if (ty == 0x02 && n == 15) {
        w = PUTS(w, "GPS\t0x02\tGPS\tLat=");
        v0 = w; w = put_fixed(w, be32(p), 7); v1 = w;
        w = PUTS(w, "deg Lon="); w = put_fixed(w, be32(p + 4), 7);
        w = PUTS(w, "deg GSpd="); w = put_fixed(w, ube16(p + 8), 1);
        w = PUTS(w, "km/h Hdg="); w = put_fixed(w, ube16(p + 10), 2);
        w = PUTS(w, "deg Alt="); w = put_i64(w, (int64_t)ube16(p + 12) - 1000);
        w = PUTS(w, "m Sats="); w = put_u64(w, p[14]);
        *w++ = '\t'; w = put_again(w, v0, v1); w = PUTS(w, "\tdeg\t");
    } else if (ty == 0x1E && n == 6) {
        w = PUTS(w, "Attitude\t0x1E\tPtch\tPtch=");
        v0 = w; w = put_fixed(w, be16(p), 4); v1 = w;
        w = PUTS(w, "rad Roll="); w = put_fixed(w, be16(p + 2), 4);
        w = PUTS(w, "rad Yaw="); w = put_fixed(w, be16(p + 4), 4);
        w = PUTS(w, "rad\t"); w = put_again(w, v0, v1); w = PUTS(w, "\trad\t");
    } else if (ty == 0x21 && n >= 1 && p[n - 1] == 0 && memchr(p, 0, (size_t)n) == p + n - 1) {
        w = PUTS(w, "FlightMode\t0x21\tFM\t");
        for (int k = 0; k < n - 1; k++) {
            unsigned char c = p[k];
            if (c >= 0x20 && c < 0x7F) *w++ = (char)c;
            else { *w++ = '\\'; *w++ = 'x'; *w++ = HEXU[c >> 4]; *w++ = HEXU[c & 15]; }
        }
        w = PUTS(w, "\t\t\t");
    } else {  // not covered: a generic row (busnoop has its own cells for these; cost alike)
        w = put_cstr(w, TYPE[ty] ? TYPE[ty] : "Unknown"); *w++ = '\t';
        w = put_0x(w, ty); w = PUTS(w, "\t\t");
        w = put_hex_bytes(w, p, n);
        w = PUTS(w, "\t\t\t");
    }
    *w++ = '\n'; o = w;
}
