// fport_ref.c: a hand-tuned reference F.Port v1 decoder, the physical limit of `busnoop fport FILE -f tsv`.
// SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), reassembles F.Port v1 frames by busnoop's rules (`7E [len][type][data][crc] 7E`,
// 0x7D unstuffing, every 0x7E ends what is open, a frame opened by 0x7E takes the 0x7E after
// it as its closing delimiter, the flight controller's answers without delimiters right after
// a frame, segments that are no frame are garbage in runs of at most 64 bytes), checks the
// FrSky checksum (end-around carry sum over length..data), decodes the control frames (16
// channels in whole µs for the Data cell, the first exactly in the Value, the raw values and
// the flags in the Note), the receiver's null polls and the flight controller's S.Port data
// answers (busnoop's sensor table for the sensors Betaflight sends: voltages, current, fuel,
// altitude, vario, heading, accelerations, GPS, temperatures) and writes busnoop's TSV table
// (12 columns: Counter, Millis, ID, Device, Type, Sensor #, Sensor, Data, Value, Unit, Frame,
// Note) through a 64 KiB output buffer; Millis is the byte offset's time at 115200 baud 8N1.
// For a capture of those frames the output is byte-identical to busnoop's (with the framing
// busnoop detects). Not covered (busnoop has them): F.Port 2 / FBUS, other S.Port frames and
// sensors, MSP requests, frames cut short, unusual escapes and ArduPilot's pad byte: these
// fall back to a generic row, so their cells differ from busnoop's, not their cost.
//
//   cc -O2 -march=x86-64-v2 -o fport_ref fport_ref.c
//   ./fport_ref FILE > out.tsv
//   "$BIN" fport FILE -f tsv --no-config | cmp - out.tsv
#include "ref_io.h"

static unsigned char ibuf[RD];

// ---- text helpers (ref_text.h, as sport_ref.c) ---------------------------------------------

#include "ref_text.h"

// ---- tables -------------------------------------------------------------------------------
// numbers as text: up to 16 characters and the count
typedef struct { char s[16]; int n; } Num;
static Num WHOLE[2048], EXACT[2048], RAW[2048];  // a channel's whole µs, exact µs, raw value
#define PUTN(w, t) (memcpy((w), (t).s, 16), (w) + (t).n)
typedef struct { const char *label, *unit; int prec, sign; } Scalar;
static Scalar SCALAR[4096];  // by app ID >> 4 (label NULL: not covered)

static void init_tables(void) {
    char t[32];
    for (int r = 0; r < 2048; r++) {
        long m = r * 625L + 880000;  // µs × 1000 on Betaflight's scale 5/8 x + 880
        WHOLE[r].n = snprintf(t, sizeof t, "%ld", m / 1000); memcpy(WHOLE[r].s, t, 16);
        long f = m % 1000; int prec = 3;
        while (prec > 0 && f % 10 == 0) { f /= 10; prec--; }
        if (prec) EXACT[r].n = snprintf(t, sizeof t, "%ld.%0*ld", m / 1000, prec, f);
        else EXACT[r].n = snprintf(t, sizeof t, "%ld", m / 1000);
        memcpy(EXACT[r].s, t, 16);
        RAW[r].n = snprintf(t, sizeof t, "%d", r); memcpy(RAW[r].s, t, 16);
    }
    static const struct { uint16_t base; Scalar s; } S[] = {
        {0x0100, {"Alt", "m", 2, 1}},    {0x0110, {"Vario", "m/s", 2, 1}}, {0x0200, {"Amps", "A", 1, 0}},
        {0x0210, {"Volts", "V", 2, 0}},  {0x0400, {"Tmp1", "degC", 0, 1}}, {0x0410, {"Tmp2", "degC", 0, 1}},
        {0x0500, {"RPM", "rpm", 0, 0}},  {0x0600, {"Fuel", "%", 0, 0}},
        // Betaflight (the flight controller, the one device of an F.Port v1 line) sends 1/100 g
        {0x0700, {"AccX", "g", 2, 1}},   {0x0710, {"AccY", "g", 2, 1}},    {0x0720, {"AccZ", "g", 2, 1}},
        {0x0820, {"GAlt", "m", 2, 1}},   {0x0830, {"GSpd", "kts", 3, 0}},  {0x0840, {"Hdg", "deg", 2, 0}},
        {0x0900, {"A3", "V", 2, 1}},     {0x0910, {"A4", "V", 2, 1}},
    };
    for (size_t i = 0; i < sizeof S / sizeof S[0]; i++) SCALAR[S[i].base >> 4] = S[i].s;
}

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text

// Counter, Millis (of the byte at stream offset `off`, 115200 baud, 10 bits a byte)
static inline char *row_start(uint64_t off) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start;
    *w++ = '\t';
    w = put_u64(w, off * 10000000 / 115200 / 1000);
    *w++ = '\t';
    return w;
}

// the garbage run
static unsigned char garb[64]; static int garb_len; static uint64_t garb_off;

static void garbage_flush(void) {
    if (!garb_len) return;
    char *w = row_start(garb_off);
    w = PUTS(w, "\t\tGarbage\t\t\t");
    w = put_hex_bytes(w, garb, garb_len);
    w = PUTS(w, "\t\t\t\t");
    w = put_u64(w, (uint64_t)garb_len);
    w = PUTS(w, " bytes outside any frame\n");
    o = w; garb_len = 0;
}
static inline void garbage_byte(unsigned char b, uint64_t off) {
    if (garb_len == 64) garbage_flush();
    if (!garb_len) garb_off = off;
    garb[garb_len++] = b;
}

static inline unsigned carry_sum(const unsigned char *b, int n) {
    unsigned s = 0;
    for (int i = 0; i < n; i++) s += b[i];
    while (s > 0xFF) s = (s & 0xFF) + (s >> 8);
    return s;
}
static inline uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

// a whole frame (body: length, type, data, checksum) starting at stream offset off
static void frame_row(const unsigned char *f, int n, uint64_t off, int ok) {
    garbage_flush();
    char *w = row_start(off);
    unsigned len = f[0], ty = f[1];
    const char *frame = ty == 0x00 ? "Control" : ty == 0x01 ? "Downlink" : ty == 0x81 ? "Uplink" : "";
    if (!ok) {
        int tel = ty == 0x01 || ty == 0x81;
        if (tel) w = ty == 0x01 && (f[2] == 0x30 || f[2] == 0x31) ? PUTS(w, "13\tUplink\t") : PUTS(w, "27\tFC\t");
        else w = PUTS(w, "\t\t");
        w = PUTS(w, "BadCRC\t\t\t");
        w = put_hex_bytes(w, f, n);
        w = PUTS(w, "\t\t\t"); w = put_cstr(w, frame); w = PUTS(w, "\tchecksum "); w = put_0x(w, f[n - 1]);
        w = PUTS(w, ", expected "); w = put_0x(w, 0xFF - carry_sum(f, n - 1));
        w = PUTS(w, " ("); w = *frame ? put_cstr(w, frame[0] == 'C' ? "control" : frame[0] == 'D' ? "downlink" : "uplink") : w;
        w = *frame ? PUTS(w, " frame)") : PUTS(w, "frame)");
    } else if (ty == 0x00 && len == 0x19) {
        const unsigned char *p = f + 2;
        unsigned raw[16];
        for (int k = 0; k < 16; k++) {
            int bit = 11 * k;
            const unsigned char *q = p + (bit >> 3);
            uint32_t x = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16;  // within the body
            raw[k] = (x >> (bit & 7)) & 0x7FF;
        }
        w = PUTS(w, "\tReceiver\tControl\t\tChannels\t");
        for (int k = 0; k < 8; k++) { w = PUTN(w, WHOLE[raw[k]]); *w++ = ' '; }
        w = PUTS(w, "\xE2\x80\xA6\t");
        w = PUTN(w, EXACT[raw[0]]);
        w = PUTS(w, "\t\xC2\xB5s\tControl\t");
        unsigned flags = p[22];
        if (flags) {
            w = PUTS(w, "flags "); w = put_0x(w, flags);
            static const char *const NAMES[] = {"CH17", "CH18", "frame lost", "failsafe"};
            const char *sep = ":";
            for (int b = 0; b < 5; b++) {
                unsigned mask = b < 4 ? 1u << b : 0xF0;
                if (flags & mask) { w = put_cstr(w, sep); *w++ = ' '; w = put_cstr(w, b < 4 ? NAMES[b] : "unknown bits"); sep = ","; }
            }
            w = PUTS(w, "; ");
        }
        w = PUTS(w, "raw");
        for (int k = 0; k < 16; k++) { *w++ = ' '; w = PUTN(w, RAW[raw[k]]); }
    } else if ((ty == 0x01 || ty == 0x81) && len == 0x08 && f[2] == 0x00 && ty == 0x01 && !(f[3] | f[4] | f[5] | f[6] | f[7] | f[8])) {
        w = PUTS(w, "27\tFC\t\t\t\t\t\t\tDownlink\t");  // the poll
    } else if (ty == 0x81 && len == 0x08 && f[2] == 0x10) {
        unsigned app = (unsigned)(f[3] | f[4] << 8);
        uint32_t value = le32(f + 5);
        w = PUTS(w, "27\tFC\tData\t0x");
        *w++ = HEXU[app >> 12]; *w++ = HEXU[(app >> 8) & 15]; *w++ = HEXU[(app >> 4) & 15]; *w++ = HEXU[app & 15];
        *w++ = '\t';
        char *v0, *v1;
        const char *unit;
        if ((app >> 4) == 0x080) {
            int64_t e7 = ((int64_t)(value & 0x3FFFFFFF) * 100 + 3) / 6;
            if (value & 0x40000000) e7 = -e7;
            w = (value & 0x80000000) ? PUTS(w, "GPS\tlon=") : PUTS(w, "GPS\tlat=");
            v0 = w; w = put_fixed(w, e7, 7); v1 = w; unit = "deg";
        } else if (SCALAR[app >> 4].label) {
            const Scalar *s = &SCALAR[app >> 4];
            w = put_cstr(w, s->label); *w++ = '\t';
            v0 = w; w = put_fixed(w, s->sign ? (int64_t)(int32_t)value : (int64_t)value, s->prec); v1 = w;
            unit = s->unit;
        } else {  // not covered: a generic row
            w = PUTS(w, "\t"); v0 = w; w = put_u64(w, value); v1 = w; unit = "";
        }
        *w++ = '\t'; w = put_again(w, v0, v1); *w++ = '\t'; w = put_cstr(w, unit);
        w = PUTS(w, "\tUplink\t");
    } else {  // not covered: a generic row (busnoop has its own cells for these; cost alike)
        w = PUTS(w, "\t\tUnknown\t\t\t");
        w = put_hex_bytes(w, f + 2, n - 3);
        w = PUTS(w, "\t\t\t"); w = put_cstr(w, frame); *w++ = '\t';
    }
    *w++ = '\n'; o = w;
}

// ---- reassembly (busnoop's fport/v1.rs rules) ---------------------------------------------
static int open_, opened, pending, after_frame, escaped, unusual, pad;  // pending: 0, 1 ok, 2 bad
static unsigned char raw_[160], body[72]; static int raw_len, body_len;
static uint64_t f_off, pos;

static void emit(int check) {  // check: 1 ok, 2 bad, 3 cut
    if (check == 3) {  // a frame cut short (not in the bench's capture): a generic row
        garbage_flush();
        char *w = row_start(f_off);
        w = PUTS(w, "\t\tTruncated\t\t\t"); w = put_hex_bytes(w, body, body_len); w = PUTS(w, "\t\t\t\t\n");
        o = w;
    } else frame_row(body, body_len, f_off, check == 1);
    open_ = 0; after_frame = check != 3; raw_len = 0; body_len = 0;
}
static void drop_segment(void) {
    for (int i = 0; i < raw_len; i++) garbage_byte(raw_[i], f_off + (uint64_t)i);
    open_ = 0; after_frame = 0; raw_len = 0; body_len = 0;
}
static void begin(int op) { open_ = 1; opened = op; escaped = 0; unusual = 0; pad = 0; f_off = pos; raw_len = 0; body_len = 0; }

static inline void byte(unsigned b) {
    if (pending) {
        int c = pending; pending = 0;
        if (b == 0x7E) { raw_[raw_len++] = (unsigned char)b; emit(c); return; }
        emit(c);
    }
    if (b == 0x7E) {
        if (open_) {
            if (body_len) emit(3);
            else if (opened && !pad && raw_len == 1) { raw_[raw_len++] = (unsigned char)b; return; }
            else drop_segment();
        }
        begin(1); raw_[raw_len++] = (unsigned char)b;
        return;
    }
    if (!open_) {
        if (after_frame && (b == 0x08 || b == 0x19 || b == 0xFF)) {
            begin(0);
            raw_[raw_len++] = (unsigned char)b;
            if (b == 0xFF) { pad = 1; return; }
            body[body_len++] = (unsigned char)b;
            return;
        }
        after_frame = 0;
        garbage_byte((unsigned char)b, pos);
        return;
    }
    raw_[raw_len++] = (unsigned char)b;
    unsigned u;
    if (escaped) { escaped = 0; if (b != 0x5E && b != 0x5D) unusual = 1; u = b ^ 0x20; }
    else if (b == 0x7D) { escaped = 1; return; }
    else u = b;
    body[body_len++] = (unsigned char)u;
    if (body_len == 1) {
        int known = u == 0x08 || u == 0x19;
        if (u == 0 || u > 0x40 || (!opened && !known)) { drop_segment(); return; }
    }
    if (body_len == body[0] + 2) {
        int c = carry_sum(body, body_len) == 0xFF ? 1 : 2;
        if (opened) pending = c; else emit(c);
    }
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: fport_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tFrame\tNote\n");
    for (;;) {
        ssize_t r = read(fd, ibuf, RD);
        if (r < 0) return 3;
        if (r == 0) break;
        for (ssize_t i = 0; i < r; i++, pos++) byte(ibuf[i]);
    }
    if (pending) { int c = pending; pending = 0; emit(c); }
    else if (open_) { if (body_len) emit(3); else drop_segment(); }
    garbage_flush();
    flush_out();
    return 0;
}
