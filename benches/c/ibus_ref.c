// ibus_ref.c: a hand-tuned reference FlySky iBUS decoder, the physical limit of
// `busnoop ibus FILE -f tsv --no-config` on a raw capture (115200 baud 8N1).
// SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), finds the frames `[len][cmd][payload][checksum LE16]` of any length 4-32 whose
// checksum (0xFFFF minus the byte sum) holds, with busnoop's rules for what is not a frame (a
// known header with a wrong checksum, or cut short by a frame starting inside it; garbage runs
// up to the next frame or known header, at most 64 bytes; what the end of the input cuts),
// pairs every sensor poll `04 [cmd|addr]` with the frame after it when that answers it
// (discover echo, type answer, measurement answer, another command's answer), learns each
// address's sensor type from its type answer and decodes its measurements in that type's
// units (the whole type table of src/ibus/sensors.rs), reads RC frames as 14 channels or, when
// a high nibble is set, 18, and writes busnoop's TSV table (Counter, Millis, ID, Device, Type,
// Sensor #, Sensor, Data, Value, Unit, Note) through a 64 KiB output buffer. Millis are the
// byte's place on the wire (10 bits a byte at 115200 baud), as busnoop gives raw files.
//
//   cc -O2 -march=x86-64-v2 -o ibus_ref ibus_ref.c
//   ./ibus_ref FILE > out.tsv
//   busnoop ibus FILE -f tsv --no-config | cmp - out.tsv
#include "ref_io.h"

static unsigned char ibuf[RD + 256];

// ---- text helpers -------------------------------------------------------------------------
#define PUTS(w, s) (memcpy((w), (s), sizeof(s) - 1), (w) + sizeof(s) - 1)
static inline char *put_u64(char *w, uint64_t v) {
    char t[24]; int i = 24;
    do { t[--i] = (char)('0' + v % 10); v /= 10; } while (v);
    memcpy(w, t + i, (size_t)(24 - i));
    return w + 24 - i;
}
static inline char *put_cstr(char *w, const char *s) { size_t n = strlen(s); memcpy(w, s, n); return w + n; }
static inline char *put_hex2(char *w, unsigned b) { w[0] = HEXU[(b >> 4) & 15]; w[1] = HEXU[b & 15]; return w + 2; }
static inline char *put_0x(char *w, unsigned b) { w[0] = '0'; w[1] = 'x'; return put_hex2(w + 2, b); }
static inline char *put_0x16(char *w, unsigned v) { w = put_0x(w, v >> 8); return put_hex2(w, v & 0xFF); }
static inline char *put_hex_bytes(char *w, const unsigned char *b, size_t n) {
    for (size_t i = 0; i < n; i++) { if (i) *w++ = ' '; w = put_hex2(w, b[i]); }
    return w;
}
// raw / 10^prec with prec decimals
static char *put_fixed(char *w, int64_t raw, int prec) {
    if (raw < 0) { *w++ = '-'; raw = -raw; }
    uint64_t v = (uint64_t)raw;
    if (!prec) return put_u64(w, v);
    uint64_t p = 1;
    for (int i = 0; i < prec; i++) p *= 10;
    w = put_u64(w, v / p);
    *w++ = '.';
    uint64_t f = v % p;
    for (int i = prec - 1; i >= 0; i--) { w[i] = (char)('0' + f % 10); f /= 10; }
    return w + prec;
}

// ---- sensor types (src/ibus/sensors.rs) ---------------------------------------------------
enum { U16, S16, TEMP, S32, GPSST, PRES, RAWE };
typedef struct { int code; const char *name, *part, *lng, *unit; int prec, enc; } Type;
static const Type TYPES[] = {
    {0x00, "IntV", "IntV", "internal voltage", "V", 2, U16},
    {0x01, "Temp", "Temp", "temperature", "degC", 1, TEMP},
    {0x02, "RPM", "RPM", "rotation speed", "rpm", 0, U16},
    {0x03, "ExtV", "ExtV", "external voltage", "V", 2, S16},
    {0x04, "Cels", "Cels", "average cell voltage", "V", 2, U16},
    {0x05, "Curr", "Curr", "battery current", "A", 2, U16},
    {0x06, "Fuel", "Fuel", "fuel or battery remaining", "%", 0, U16},
    {0x07, "RPM", "RPM", "throttle value or battery capacity", "", 0, U16},
    {0x08, "Hdg", "Hdg", "compass heading", "deg", 0, U16},
    {0x09, "VSpd", "VSpd", "climb rate", "m/s", 2, S16},
    {0x0A, "Hdg", "Hdg", "course over ground", "deg", 2, U16},
    {0x0B, "Sats", "Sats", "GPS status", "", 0, GPSST},
    {0x0C, "AccX", "AccX", "acceleration X", "m/s2", 2, S16},
    {0x0D, "AccY", "AccY", "acceleration Y", "m/s2", 2, S16},
    {0x0E, "AccZ", "AccZ", "acceleration Z", "m/s2", 2, S16},
    {0x0F, "Roll", "Roll", "roll", "deg", 2, S16},
    {0x10, "Ptch", "Ptch", "pitch", "deg", 2, S16},
    {0x11, "Yaw", "Yaw", "yaw", "deg", 2, S16},
    {0x12, "VSpd", "VSpd", "vertical speed", "m/s", 2, S16},
    {0x13, "GSpd", "GSpd", "ground speed", "m/s", 2, U16},
    {0x14, "Dist", "Dist", "distance from home", "m", 0, U16},
    {0x15, "Arm", "Arm", "armed", "", 0, U16},
    {0x16, "FM", "FM", "flight mode", "", 0, U16},
    {0x41, "Pres", "Pres", "pressure and temperature", "", 0, PRES},
    {0x7C, "Odo1", "Odo1", "odometer 1", "", 0, RAWE},
    {0x7D, "Odo2", "Odo2", "odometer 2", "", 0, RAWE},
    {0x7E, "ASpd", "ASpd", "speed", "", 0, RAWE},
    {0x7F, "TX_V", "TX_V", "transmitter voltage", "V", 2, U16},
    {0x80, "GPS", "Lat", "GPS latitude", "deg", 7, S32},
    {0x81, "GPS", "Lon", "GPS longitude", "deg", 7, S32},
    {0x82, "GAlt", "GAlt", "GPS altitude", "m", 2, S32},
    {0x83, "Alt", "Alt", "altitude", "m", 2, S32},
    {0xF9, "Alt", "Alt", "altitude (FlySky native)", "m", 0, S16},
    {0xFA, "RSNR", "RSNR", "receiver SNR", "", 0, RAWE},
    {0xFB, "RNse", "RNse", "receiver noise", "", 0, RAWE},
    {0xFC, "RSSI", "RSSI", "receiver RSSI", "", 0, RAWE},
    {0xFE, "RQly", "RQly", "receiver error rate", "", 0, RAWE},
};
static const Type *TYPE_OF[256];

// what was learned per address: the type code (and whether any), and the cells
// "ID\t\tMeasure\t0xNN\tName\t" of its measurement rows
static int learned[16];
static unsigned learned_code[16];
static char MEAS_HEAD[16][48];
static int MEAS_HEAD_N[16];

static void set_head(unsigned a) {
    char *w = MEAS_HEAD[a];
    w = put_u64(w, a);
    w = PUTS(w, "\t\tMeasure\t");
    if (learned[a]) {
        w = put_0x(w, learned_code[a]);
        *w++ = '\t';
        const Type *t = TYPE_OF[learned_code[a]];
        if (t) w = put_cstr(w, t->name);
    } else *w++ = '\t';
    *w++ = '\t';
    MEAS_HEAD_N[a] = (int)(w - MEAS_HEAD[a]);
}

// the Sensor # and Sensor cells of an address (with the tab before each)
static char *sensor_cells(char *w, unsigned a) {
    *w++ = '\t';
    if (learned[a]) {
        w = put_0x(w, learned_code[a]);
        *w++ = '\t';
        const Type *t = TYPE_OF[learned_code[a]];
        if (t) w = put_cstr(w, t->name);
    } else *w++ = '\t';
    return w;
}

// ---- tables -------------------------------------------------------------------------------
static char CH_T[4096][8];   // " 1500" …
static unsigned char CH_N[4096];

static void init_tables(void) {
    for (int x = 0; x < 4096; x++) {
        char t[16];
        CH_N[x] = (unsigned char)snprintf(t, sizeof t, " %d", x); memcpy(CH_T[x], t, 8);
    }
    for (size_t i = 0; i < sizeof TYPES / sizeof TYPES[0]; i++) TYPE_OF[TYPES[i].code] = &TYPES[i];
    for (unsigned a = 0; a < 16; a++) set_head(a);
}

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text (digits ctr[start..32))

// Counter, Millis (the byte's place at 10 bits a byte, 115200 baud) and the tab before ID.
static inline char *row_start(uint64_t off) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start; // counters below 10^16
    *w++ = '\t';
    w = put_u64(w, off * 100 / 1152);
    *w++ = '\t';
    return w;
}

static inline char *note_sep(char *w, char *note_start) {
    if (w != note_start) { *w++ = ';'; *w++ = ' '; }
    return w;
}

static void rc_row(uint64_t off, const unsigned char *b) {
    char *w = row_start(off);
    unsigned s[14], ch[18], high = 0;
    for (int i = 0; i < 14; i++) { s[i] = (unsigned)b[2 + 2 * i] | (unsigned)b[3 + 2 * i] << 8; ch[i] = s[i] & 0xFFF; high |= s[i] >> 12; }
    int n = 14;
    if (high) {
        n = 18;
        for (int k = 0; k < 4; k++) ch[14 + k] = s[3 * k] >> 12 | (s[3 * k + 1] >> 12) << 4 | (s[3 * k + 2] >> 12) << 8;
    }
    w = PUTS(w, "\t\tChannels\t\t\t");
    memcpy(w, CH_T[ch[0]] + 1, 8); w += CH_N[ch[0]] - 1;
    for (int i = 1; i < n; i++) { memcpy(w, CH_T[ch[i]], 8); w += CH_N[ch[i]]; }
    *w++ = '\t';
    memcpy(w, CH_T[ch[0]] + 1, 8); w += CH_N[ch[0]] - 1;
    w = PUTS(w, "\tus\t");
    if (b[1] != 0x40) {
        w = PUTS(w, "command byte "); w = put_0x(w, b[1]);
        w = PUTS(w, ", not 0x40 (read as channels, as Betaflight does); ");
    }
    w = high ? PUTS(w, "18 channels (15-18 from the high nibbles)\n") : PUTS(w, "14 channels\n");
    o = w;
}

// the value bytes as 0x… (most significant first)
static char *put_raw_hex(char *w, const unsigned char *v, size_t n) {
    w = PUTS(w, "0x");
    if (n > 4) n = 4;
    for (size_t i = n; i > 0; i--) w = put_hex2(w, v[i - 1]);
    return w;
}

// a measurement answer a (len bytes) of address addr; stray: its poll was not seen
static void measure_row(uint64_t off, unsigned addr, const unsigned char *a, size_t len, int stray) {
    char *w = row_start(off);
    memcpy(w, MEAS_HEAD[addr], 48); w += MEAS_HEAD_N[addr];
    const unsigned char *v = a + 2;
    size_t n = len - 4;
    uint32_t r = 0;
    for (size_t i = 0; i < n && i < 4; i++) r |= (uint32_t)v[i] << (8 * i);
    const Type *t = learned[addr] ? TYPE_OF[learned_code[addr]] : NULL;
    const char *raw_note = NULL;
    int width = 0;
    if (t) width = (t->enc == S32 || t->enc == PRES) ? 4 : t->enc == RAWE ? 0 : 2;
    if (!learned[addr]) raw_note = "sensor type unknown (no type answer seen): raw";
    else if (!t) raw_note = "type not in Betaflight's or EdgeTX's tables: raw";
    else if (t->enc == RAWE) raw_note = "the sources do not settle the scale: raw";
    if (raw_note || (width && (size_t)width != n)) {
        w = put_raw_hex(w, v, n);
        *w++ = '\t';
        w = put_u64(w, r);
        w = PUTS(w, "\t\t");
        char *ns = w;
        if (stray) w = PUTS(w, "answer without its poll");
        w = note_sep(w, ns);
        if (raw_note) w = put_cstr(w, raw_note);
        else {
            w = put_cstr(w, t->lng); w = PUTS(w, " is sent in "); w = put_u64(w, (uint64_t)width);
            w = PUTS(w, " bytes, not "); w = put_u64(w, n); w = PUTS(w, ": raw");
        }
        *w++ = '\n';
        o = w;
        return;
    }
    char *d = w;
    const char *unit = t->unit;
    int note8000 = 0;
    switch (t->enc) {
    case U16: w = put_fixed(w, (uint16_t)r, t->prec); break;
    case S16: w = put_fixed(w, (int16_t)(uint16_t)r, t->prec); note8000 = t->code == 3 && r == 0x8000; break;
    case TEMP: w = put_fixed(w, (int64_t)(uint16_t)r - 400, 1); break;
    case S32: w = put_fixed(w, (int32_t)r, t->prec); break;
    case GPSST: w = put_u64(w, r >> 8 & 0xFF); break;
    default: w = put_u64(w, r & 0x7FFFF); break; // PRES
    }
    size_t vn = (size_t)(w - d);
    if (t->enc == GPSST) { w = PUTS(w, " satellites, fix "); w = put_u64(w, r & 0xFF); unit = ""; }
    else if (t->enc == PRES) { w = PUTS(w, ", "); w = put_fixed(w, (int64_t)(r >> 19) - 400, 1); w = PUTS(w, " degC"); unit = ""; }
    *w++ = '\t';
    memmove(w, d, vn); w += vn;
    *w++ = '\t';
    w = put_cstr(w, unit);
    *w++ = '\t';
    char *ns = w;
    if (stray) w = PUTS(w, "answer without its poll");
    if (note8000) { w = note_sep(w, ns); w = PUTS(w, "0x8000: no value (Betaflight)"); }
    *w++ = '\n';
    o = w;
}

static void type_row(uint64_t off, unsigned addr, const unsigned char *a, int stray) {
    char *w = row_start(off);
    unsigned code = a[2], size = a[3];
    int before = learned[addr];
    unsigned before_code = learned_code[addr];
    learned[addr] = 1; learned_code[addr] = code; set_head(addr);
    const Type *t = TYPE_OF[code];
    w = put_u64(w, addr);
    w = PUTS(w, "\t\tSensorType\t");
    w = put_0x(w, code); *w++ = '\t';
    if (t) w = put_cstr(w, t->name);
    *w++ = '\t';
    if (t) w = put_cstr(w, t->name); else w = put_0x(w, code);
    w = PUTS(w, ", "); w = put_u64(w, size); w = PUTS(w, " bytes\t\t\t");
    char *ns = w;
    if (stray) w = PUTS(w, "answer without its poll");
    w = note_sep(w, ns);
    w = t ? put_cstr(w, t->lng) : PUTS(w, "type not in Betaflight's or EdgeTX's tables");
    if (before && before_code != code) { w = PUTS(w, "; type changed from "); w = put_0x(w, before_code); }
    *w++ = '\n';
    o = w;
}

static const char *cmd_words(unsigned cmd) {
    return cmd == 8 ? "discover" : cmd == 9 ? "type query" : cmd == 0xA ? "measurement" : "command";
}

// a poll p and its answer a (NULL: none)
static void exchange(uint64_t off, const unsigned char *p, const unsigned char *a, size_t alen) {
    unsigned cmd = p[1] >> 4, addr = p[1] & 15;
    if (a && cmd == 0xA) { measure_row(off, addr, a, alen, 0); return; }
    if (a && cmd == 9) { type_row(off, addr, a, 0); return; }
    char *w = row_start(off);
    w = put_u64(w, addr);
    w = PUTS(w, "\t\t");
    if (!a) {
        w = sensor_cells(w, addr);
        w = PUTS(w, "\t\t\t\t");
        w = put_cstr(w, cmd_words(cmd));
        if (cmd < 8 || cmd > 0xA) { *w++ = ' '; w = put_0x(w, p[1] & 0xF0); }
        w = PUTS(w, " poll, no answer\n");
    } else if (cmd == 8) {
        w = PUTS(w, "Discover");
        w = sensor_cells(w, addr);
        w = PUTS(w, "\tpresent\t\t\tthe sensor echoed the poll\n");
    } else {
        w = PUTS(w, "Other\t\t\t");
        w = put_hex_bytes(w, a + 2, alen - 4);
        w = PUTS(w, "\t\t\tcommand "); w = put_0x(w, p[1] & 0xF0); w = PUTS(w, " answered\n");
    }
    o = w;
}

static int known_header(unsigned len, unsigned cmd) {
    switch (len) {
    case 0x20: return cmd == 0x40 || cmd == 0;
    case 4: return cmd >> 4 >= 8;
    case 6: case 8: return cmd >> 4 == 9 || cmd >> 4 == 0xA;
    default: return 0;
    }
}

// a valid frame that is no poll and answers none
static void frame_row(uint64_t off, const unsigned char *b, size_t len) {
    if (len == 32) { rc_row(off, b); return; }
    unsigned cmd = b[1] >> 4, addr = b[1] & 15;
    if (len == 6 && cmd == 9) { type_row(off, addr, b, 1); return; }
    if (len > 4 && cmd == 0xA) { measure_row(off, addr, b, len, 1); return; }
    char *w = row_start(off);
    w = PUTS(w, "\t\tUnknown\t\t\t");
    w = put_hex_bytes(w, b + 1, len - 3);
    w = PUTS(w, "\t\t\ta valid frame of no known kind\n");
    o = w;
}

enum { BADCHECK, CUT, ATEND, GARBAGE };

static uint16_t checksum(const unsigned char *b, size_t n) {
    unsigned s = 0;
    for (size_t i = 0; i < n; i++) s += b[i];
    return (uint16_t)(0xFFFF - (s & 0xFFFF));
}

static void broken_row(uint64_t off, int why, const unsigned char *b, size_t len) {
    char *w = row_start(off);
    int sensor = len >= 2 && known_header(b[0], b[1]) && b[0] != 0x20;
    if (sensor) w = put_u64(w, b[1] & 15);
    w = PUTS(w, "\t\t");
    w = why == BADCHECK ? PUTS(w, "BadCRC") : why == GARBAGE ? PUTS(w, "Garbage") : PUTS(w, "Truncated");
    w = PUTS(w, "\t\t\t");
    w = put_hex_bytes(w, b, len);
    w = PUTS(w, "\t\t\t");
    const char *what = "frame";
    if (b[0] == 0x20) what = "RC frame";
    else if (len >= 2) {
        unsigned c = b[1] >> 4;
        if (b[0] == 4) what = c == 8 ? "discover poll" : c == 9 ? "type query" : c == 0xA ? "measurement poll" : "poll";
        else what = c == 9 ? "type answer" : "measurement answer";
    }
    if (why == BADCHECK) {
        w = PUTS(w, "checksum "); w = put_0x16(w, (unsigned)b[len - 2] | (unsigned)b[len - 1] << 8);
        w = PUTS(w, ", expected "); w = put_0x16(w, checksum(b, len - 2));
        w = PUTS(w, " ("); w = put_cstr(w, what); *w++ = ')';
    } else if (why == GARBAGE) {
        w = put_u64(w, len);
        w = len == 1 ? PUTS(w, " byte outside frames") : PUTS(w, " bytes outside frames");
    } else {
        w = put_u64(w, len); w = PUTS(w, " of "); w = put_u64(w, b[0]);
        w = PUTS(w, " bytes of a "); w = put_cstr(w, what);
        w = why == CUT ? PUTS(w, ", then a frame starts") : PUTS(w, " before the input ended");
    }
    *w++ = '\n';
    o = w;
}

// ---- framing and pairing (busnoop's rules, src/ibus/wire.rs) --------------------------------
#define MORE ((size_t)-1)
// a valid frame at b (avail bytes there): its length, 0 when none, MORE when more bytes could tell
static inline size_t frame_at(const unsigned char *b, size_t avail) {
    size_t len = b[0];
    if (len < 4 || len > 32) return 0;
    if (avail < len) return MORE;
    return checksum(b, len - 2) == ((unsigned)b[len - 2] | (unsigned)b[len - 1] << 8) ? len : 0;
}

// the first q in from..to where a valid frame starts; 0 when none; MORE
static size_t first_frame(const unsigned char *b, size_t avail, size_t from, size_t to, int end) {
    for (size_t q = from; q < to; q++) {
        size_t f = frame_at(b + q, avail - q);
        if (f == MORE) { if (!end) return MORE; continue; }
        if (f) return q;
    }
    return 0;
}

static int pending;
static unsigned char pend[4];
static uint64_t pend_off;

static inline void flush_pending(void) {
    if (pending) { pending = 0; exchange(pend_off, pend, NULL, 0); }
}

static inline void frame(uint64_t off, const unsigned char *b, size_t len) {
    if (pending) {
        unsigned c = pend[1] >> 4;
        int ans = c == 8 ? (len == 4 && memcmp(b, pend, 4) == 0)
                : c == 9 ? (len == 6 && b[1] == pend[1])
                : (len > 4 && b[1] == pend[1]);
        pending = 0;
        if (ans) { exchange(pend_off, pend, b, len); return; }
        exchange(pend_off, pend, NULL, 0);
    }
    if (len == 4 && b[1] >> 4 >= 8) { pending = 1; memcpy(pend, b, 4); pend_off = off; return; }
    frame_row(off, b, len);
}

static inline void broken(uint64_t off, int why, const unsigned char *b, size_t len) {
    flush_pending();
    broken_row(off, why, b, len);
}

// What starts at b (avail bytes, `end`: no more come): the bytes taken, 0 when more are needed.
static size_t step(const unsigned char *b, size_t avail, int end, uint64_t off) {
    size_t f = frame_at(b, avail);
    if (f && f != MORE) { frame(off, b, f); return f; }
    if (f == MORE) {
        if (!end) return 0;
        if (avail >= 2 && known_header(b[0], b[1])) {
            size_t q = first_frame(b, avail, 1, avail, 1);
            if (q) { broken(off, CUT, b, q); return q; }
            broken(off, ATEND, b, avail); return avail;
        }
    }
    size_t len = b[0];
    if (avail >= len && len >= 4 && known_header(b[0], b[1])) {
        size_t q = first_frame(b, avail, 1, len, end);
        if (q == MORE) return 0;
        if (q) { broken(off, CUT, b, q); return q; }
        broken(off, BADCHECK, b, len); return len;
    }
    size_t limit = avail < 64 ? avail : 64;
    for (size_t i = 1; i < limit; i++) {
        size_t g = frame_at(b + i, avail - i);
        if (g == MORE) { if (!end) return 0; }
        else if (g) { broken(off, GARBAGE, b, i); return i; }
        if (i + 1 < avail && known_header(b[i], b[i + 1])) { broken(off, GARBAGE, b, i); return i; }
    }
    if (limit == 64 || end) { broken(off, GARBAGE, b, limit); return limit; }
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: ibus_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\n");
    size_t carry = 0;
    uint64_t base = 0;  // stream position of ibuf[0]
    for (;;) {
        ssize_t r = read(fd, ibuf + carry, RD);
        if (r < 0) return 3;
        int eof = r == 0;
        size_t n = carry + (size_t)r, i = 0;
        const unsigned char *b = ibuf;
        while (i < n) {
            size_t k = step(b + i, n - i, eof, base + i);
            if (!k) break;
            i += k;
        }
        carry = n - i;
        if (carry) memmove(ibuf, ibuf + i, carry);
        base += i;
        if (eof) break;
    }
    flush_pending();
    flush_out();
    return 0;
}
