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

// ---- text helpers (as sport_ref.c) ----------------------------------------------------------

static inline int lead_digits(char *t, uint32_t v) {  // v < 10^8, without leading zeros
    uint64_t d = eight_digits(v);
    int lead = v ? __builtin_ctzll(d) / 8 : 7;
    d = (d >> (lead * 8)) | ZEROS; memcpy(t, &d, 8);
    return 8 - lead;
}
static inline int udigits(char *t, uint64_t v) {
    if (v < 100000000) return lead_digits(t, (uint32_t)v);
    uint64_t hi = v / 100000000, d;
    int k;
    if (hi < 100000000) k = lead_digits(t, (uint32_t)hi);
    else {
        k = lead_digits(t, (uint32_t)(hi / 100000000));
        d = eight_digits((uint32_t)(hi % 100000000)) | ZEROS; memcpy(t + k, &d, 8); k += 8;
    }
    d = eight_digits((uint32_t)(v % 100000000)) | ZEROS; memcpy(t + k, &d, 8);
    return k + 8;
}
static inline char *put_u64(char *w, uint64_t v) { return w + udigits(w, v); }
static inline char *put_i64(char *w, int64_t v) {
    if (v < 0) { *w++ = '-'; return put_u64(w, (uint64_t)0 - (uint64_t)v); }
    return put_u64(w, (uint64_t)v);
}
// raw / 10^prec (prec <= 7), as busnoop's push_decimal (16.8, -0.1996, 0.5)
static inline char *put_fixed(char *w, int64_t raw, int prec) {
    uint64_t m = raw < 0 ? (uint64_t)0 - (uint64_t)raw : (uint64_t)raw;
    if (raw < 0) *w++ = '-';
    if (prec == 0) return put_u64(w, m);
    char t[40];
    int nd = udigits(t, m);
    if (nd > prec) {
        memcpy(w, t, 24); w += nd - prec;
        *w = '.'; memcpy(w + 1, t + nd - prec, 8); return w + 1 + prec;
    }
    memcpy(w, "0.00000000", 10); w += 2 + prec - nd;
    memcpy(w, t, 8); return w + nd;
}
#define PUTS(w, s) (memcpy((w), (s), sizeof(s) - 1), (w) + sizeof(s) - 1)
static inline char *put_cstr(char *w, const char *s) { size_t n = strlen(s); memcpy(w, s, n); return w + n; }
static inline char *put_hex_bytes(char *w, const unsigned char *b, int n) {
    for (int i = 0; i < n; i++) { if (i) *w++ = ' '; *w++ = HEXU[b[i] >> 4]; *w++ = HEXU[b[i] & 15]; }
    return w;
}
static inline char *put_0x(char *w, unsigned b) { *w++ = '0'; *w++ = 'x'; *w++ = HEXU[(b >> 4) & 15]; *w++ = HEXU[b & 15]; return w; }
// a copy of the text between a and b (at most 32 bytes), loads before stores
static inline char *put_again(char *w, const char *a, const char *b) {
    uint64_t x0, x1, x2, x3; memcpy(&x0, a, 8); memcpy(&x1, a + 8, 8); memcpy(&x2, a + 16, 8); memcpy(&x3, a + 24, 8);
    memcpy(w, &x0, 8); memcpy(w + 8, &x1, 8); memcpy(w + 16, &x2, 8); memcpy(w + 24, &x3, 8);
    return w + (b - a);
}

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
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text
static uint64_t frames;                          // valid frames so far

// Counter, Millis (of the byte at stream offset `off`, 420000 baud, 10 bits a byte)
static inline char *row_start(uint64_t off) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start;
    *w++ = '\t';
    w = put_u64(w, off * 10000000 / 420000 / 1000);
    *w++ = '\t';
    return w;
}
// ID and Device
static inline char *put_addr(char *w, unsigned a) {
    w = put_u64(w, a); *w++ = '\t';
    w = put_cstr(w, DEVICE[a]); *w++ = '\t';
    return w;
}

// the garbage run
static unsigned char garb[64]; static int garb_len, garb_false, garb_before; static uint64_t garb_off;

static void garbage_flush(void) {
    if (!garb_len) return;
    char *w = row_start(garb_off);
    w = PUTS(w, "\t\tGarbage\t\t\t");
    w = put_hex_bytes(w, garb, garb_len);
    w = PUTS(w, "\t\t\t");
    w = put_u64(w, (uint64_t)garb_len);
    w = garb_len == 1 ? PUTS(w, " byte") : PUTS(w, " bytes");
    w = garb_before ? PUTS(w, " before the first frame") : PUTS(w, " outside any frame");
    if (garb_false) {
        w = PUTS(w, "; "); w = put_u64(w, (uint64_t)garb_false);
        w = garb_false == 1 ? PUTS(w, " false frame start (a frame began inside it)")
                            : PUTS(w, " false frame starts (a frame began inside each)");
    }
    *w++ = '\n';
    o = w; garb_len = 0; garb_false = 0;
}
static inline void garbage_byte(unsigned char b, uint64_t off) {
    if (!garb_len) { garb_off = off; garb_before = frames == 0; }
    garb[garb_len++] = b;
    if (garb_len == 64) garbage_flush();
}

// a frame whose CRC failed, with no valid frame inside it
static void bad_frame(const unsigned char *f, int len, uint64_t off, unsigned crc) {
    garbage_flush();
    char *w = row_start(off);
    w = put_addr(w, f[0]);
    w = PUTS(w, "BadCRC\t"); w = put_0x(w, f[2]); w = PUTS(w, "\t\t");
    w = put_hex_bytes(w, f + 3, len - 4);
    w = PUTS(w, "\t\t\tCRC "); w = put_0x(w, f[len - 1]); w = PUTS(w, ", expected "); w = put_0x(w, crc);
    const char *name = type_name(f[0], f[2]);
    if (name) { w = PUTS(w, " ("); w = put_cstr(w, name); w = PUTS(w, " frame)"); }
    else w = PUTS(w, " (a frame of unknown type)");
    *w++ = '\n'; o = w;
}

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

// ---- reassembly ---------------------------------------------------------------------------
static inline unsigned crc8(const unsigned char *b, int n) {
    unsigned c = 0;
    for (int i = 0; i < n; i++) c = CRC[c ^ b[i]];
    return c;
}
// a valid frame starts at b[q] (with `avail` bytes there)
static inline int valid_at(const unsigned char *b, size_t avail) {
    if (avail < 2 || !ADDR[b[0]]) return 0;
    unsigned len = b[1];
    if (len < 2 || len > 62 || len + 2 > avail) return 0;
    return crc8(b + 2, (int)len - 1) == b[len + 1];
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: ghst_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\n");
    size_t carry = 0;
    uint64_t base = 0;  // stream offset of ibuf[0]
    for (;;) {
        ssize_t r = read(fd, ibuf + carry, RD);
        if (r < 0) return 3;
        int eof = r == 0;
        size_t n = carry + (size_t)r, i = 0;
        const unsigned char *b = ibuf;
        size_t stop = eof ? n : (n > LOOK ? n - LOOK : 0);  // decide positions below it
        while (i < stop) {
            unsigned a = b[i];
            if (!ADDR[a]) { garbage_byte((unsigned char)a, base + i); i++; continue; }
            unsigned len = i + 1 < n ? b[i + 1] : 2;  // a lone address at the end: cut
            if (len < 2 || len > 62) { garbage_byte((unsigned char)a, base + i); i++; continue; }
            size_t end = i + len + 2;
            if (end > n) {  // cut by the end of the input (eof): a truncated frame
                int inside = 0;
                for (size_t q = i + 1; q < n && !inside; q++) inside = valid_at(b + q, n - q);
                if (inside) { garb_false++; garbage_byte((unsigned char)a, base + i); i++; continue; }
                garbage_flush();
                char *w = row_start(base + i);
                w = put_addr(w, a); w = PUTS(w, "Truncated\t");
                if (n - i >= 3) w = put_0x(w, b[i + 2]);
                w = PUTS(w, "\t\t");
                w = put_hex_bytes(w, b + i, (int)(n - i)); w = PUTS(w, "\t\t\t");
                w = put_u64(w, n - i);
                if (n - i >= 2) { w = PUTS(w, " of "); w = put_u64(w, len + 2); }
                w = PUTS(w, " bytes, cut by the end of the input\n");
                o = w; i = n; break;
            }
            unsigned c = crc8(b + i + 2, (int)len - 1);
            if (c == b[end - 1]) { frame_row(b + i, (int)len + 2, base + i); i = end; continue; }
            // a failed candidate: a false start when a valid frame starts inside it
            int inside = 0;
            for (size_t q = i + 1; q < end && !inside; q++) inside = valid_at(b + q, n - q);
            if (inside) {
                if (!garb_len) garb_false = 0;
                garb_false++;
                garbage_byte((unsigned char)a, base + i); i++; continue;
            }
            bad_frame(b + i, (int)len + 2, base + i, c);
            i = end;
        }
        carry = n - i;
        if (carry) memmove(ibuf, ibuf + i, carry);
        base += i;
        if (eof) break;
    }
    garbage_flush();
    flush_out();
    return 0;
}
