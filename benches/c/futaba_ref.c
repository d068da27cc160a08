// futaba_ref.c: a hand-tuned reference Futaba SBUS / SBUS2 decoder, the physical limit of
// `busnoop futaba FILE -f tsv --no-config` on a raw capture (100000 baud 8E2, inverted by the
// adapter). SPDX-License-Identifier: MIT OR Apache-2.0
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks (as
// busnoop), reassembles 25-byte frames (0x0F, 22 bytes of 16 x 11-bit channels, flags, end byte
// 00 / 04 14 24 34 / 08) and the SBUS2 telemetry slots after a frame that announces a group
// (3 bytes: slot id, value hi, value lo; at most 8), with busnoop's resynchronisation rules (a
// frame cut short by a lost byte, a wrong end byte, a slot cut by a frame, garbage runs of at
// most 64 bytes, what the end of the input cuts), unpacks the channels, converts them to
// microseconds (Betaflight's 5 * x / 8 + 880) and writes busnoop's TSV table (11 columns:
// Counter, Millis, ID, Device, Type, Sensor #, Sensor, Data, Value, Unit, Note) through a 64 KiB
// output buffer. Millis are the byte's place on the wire (12 bits a byte at 100000 baud), as
// busnoop gives raw files without times. Byte-identical to busnoop's output on any raw capture.
//
//   cc -O2 -march=x86-64-v2 -o futaba_ref futaba_ref.c
//   ./futaba_ref FILE > out.tsv
//   busnoop futaba FILE -f tsv --no-config | cmp - out.tsv
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
static inline char *put_hex2(char *w, unsigned b) { w[0] = HEXU[(b >> 4) & 15]; w[1] = HEXU[b & 15]; return w + 2; }
static inline char *put_hex_bytes(char *w, const unsigned char *b, size_t n) {
    for (size_t i = 0; i < n; i++) { if (i) *w++ = ' '; w = put_hex2(w, b[i]); }
    return w;
}
// a constant string of up to 40 bytes with its length: one fixed-size copy
typedef struct { char s[40]; int n; } Str;
static inline char *put_str(char *w, const Str *s) { memcpy(w, s->s, 40); return w + s->n; }
static void mkstr(Str *s, const char *t) { memset(s->s, 0, 40); s->n = (int)strlen(t); memcpy(s->s, t, (size_t)s->n); }

// ---- tables -------------------------------------------------------------------------------
// The decimal text of every 11-bit raw value and of its microseconds, 8 bytes each (with a
// leading blank for the lists), and the length.
static char RAW_T[2048][8], US_T[2048][8];
static unsigned char RAW_N[2048], US_N[2048];
static Str END_T[256];   // "\t0x04\tSBUS2\t" … by end byte
static Str GROUP_T[256]; // "; slots 0-7 follow" … by end byte (empty for 00)
static Str SLOT_HEAD[32];  // "0\tReceiver\tSlot\t0x03\tRxV\t0x"
static const char *GROUPS[4] = {"slots 0-7", "slots 8-15", "slots 16-23", "slots 24-31"};

static int end_ok(unsigned e) { return e == 0x00 || e == 0x08 || e == 0x04 || e == 0x14 || e == 0x24 || e == 0x34; }
static unsigned char END_OK[256];
static int rev5(int v) { return ((v & 1) << 4) | ((v & 2) << 2) | (v & 4) | ((v & 8) >> 2) | ((v & 16) >> 4); }

static void init_tables(void) {
    for (int x = 0; x < 2048; x++) {
        char t[16];
        RAW_N[x] = (unsigned char)snprintf(t, sizeof t, " %d", x); memcpy(RAW_T[x], t, 8);
        US_N[x] = (unsigned char)snprintf(t, sizeof t, " %d", 5 * x / 8 + 880); memcpy(US_T[x], t, 8);
    }
    for (int e = 0; e < 256; e++) {
        END_OK[e] = (unsigned char)end_ok((unsigned)e);
        char t[40];
        snprintf(t, sizeof t, "\t0x%02X\t%s\t", e, e == 0 ? "SBUS" : "SBUS2"); mkstr(&END_T[e], t);
        if (e == 0x04 || e == 0x14 || e == 0x24 || e == 0x34) snprintf(t, sizeof t, "; %s follow", GROUPS[e >> 4]);
        else if (e == 0x08) snprintf(t, sizeof t, "; SBUS2 fast pace, no slots");
        else t[0] = 0;
        mkstr(&GROUP_T[e], t);
    }
    for (int n = 0; n < 32; n++) {
        char t[40];
        snprintf(t, sizeof t, "%d\t%s\tSlot\t0x%02X\t%s\t0x", n, n ? "Sensor" : "Receiver", rev5(n) << 3 | 3, n ? "" : "RxV");
        mkstr(&SLOT_HEAD[n], t);
    }
}

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text (digits ctr[start..32))

// Counter, Millis (the byte's place at 120 us a byte) and the tab before ID.
static inline char *row_start(uint64_t off) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start; // counters below 10^16
    *w++ = '\t';
    w = put_u64(w, off * 12 / 100);
    *w++ = '\t';
    return w;
}

// the 11 bits of channel i, from the 22 data bytes at d
#define CH(d, i) ((unsigned)((d)[(11 * (i)) / 8] | (d)[(11 * (i)) / 8 + 1] << 8 | (d)[(11 * (i)) / 8 + 2] << 16) >> ((11 * (i)) % 8) & 0x7FF)

static void frame_row(uint64_t off, const unsigned char *f) {
    char *w = row_start(off);
    unsigned flags = f[23], end = f[24];
    const unsigned char *d = f + 1;
    unsigned ch[16];
    ch[0] = CH(d, 0); ch[1] = CH(d, 1); ch[2] = CH(d, 2); ch[3] = CH(d, 3);
    ch[4] = CH(d, 4); ch[5] = CH(d, 5); ch[6] = CH(d, 6); ch[7] = CH(d, 7);
    ch[8] = CH(d, 8); ch[9] = CH(d, 9); ch[10] = CH(d, 10); ch[11] = CH(d, 11);
    ch[12] = CH(d, 12); ch[13] = CH(d, 13); ch[14] = CH(d, 14); ch[15] = CH(d, 15);
    w = PUTS(w, "\t\tChannels");
    w = put_str(w, &END_T[end]);
    // Data: the microseconds (the first without its blank), then the first again as Value
    memcpy(w, US_T[ch[0]] + 1, 8); w += US_N[ch[0]] - 1;
    for (int i = 1; i < 16; i++) { memcpy(w, US_T[ch[i]], 8); w += US_N[ch[i]]; }
    *w++ = '\t';
    memcpy(w, US_T[ch[0]] + 1, 8); w += US_N[ch[0]] - 1;
    w = PUTS(w, "\tus\tCH17=0 CH18=0 FrameLost=0 Failsafe=0");
    w[-31] = (char)('0' + (flags & 1));
    w[-24] = (char)('0' + (flags >> 1 & 1));
    w[-12] = (char)('0' + (flags >> 2 & 1));
    w[-1] = (char)('0' + (flags >> 3 & 1));
    if (flags & 0xF0) { w = PUTS(w, "; unused flag bits set (flags 0x"); w = put_hex2(w, flags); *w++ = ')'; }
    w = put_str(w, &GROUP_T[end]);
    w = PUTS(w, "; raw");
    for (int i = 0; i < 16; i++) { memcpy(w, RAW_T[ch[i]], 8); w += RAW_N[ch[i]]; }
    *w++ = '\n';
    o = w;
}

static void slot_row(uint64_t off, const unsigned char *b, unsigned group) {
    char *w = row_start(off);
    unsigned n = (unsigned)rev5(b[0] >> 3);
    unsigned v = (unsigned)b[1] << 8 | b[2];
    w = put_str(w, &SLOT_HEAD[n]);
    w = put_hex2(w, b[1]); w = put_hex2(w, b[2]);
    *w++ = '\t';
    w = put_u64(w, v);
    w = n ? PUTS(w, "\t\traw value (the sensor is assigned on the transmitter)") : PUTS(w, "\t\treceiver voltage slot, raw value");
    if (n / 8 != group) {
        w = PUTS(w, "; answered after a frame announcing ");
        const char *g = GROUPS[group & 3]; size_t k = strlen(g); memcpy(w, g, k); w += k;
    }
    *w++ = '\n';
    o = w;
}

enum { CUT, WRONG_END, AT_END, SLOT_CUT, GARBAGE };

static void broken_row(uint64_t off, int why, const unsigned char *b, size_t len) {
    char *w = row_start(off);
    int slot = (why == AT_END && b[0] != 0x0F) || why == SLOT_CUT;
    if (slot) {
        unsigned n = (unsigned)rev5(b[0] >> 3);
        w = put_u64(w, n);
        w = n ? PUTS(w, "\tSensor\t") : PUTS(w, "\tReceiver\t");
    } else w = PUTS(w, "\t\t");
    w = (why == WRONG_END || why == GARBAGE) ? PUTS(w, "Garbage\t\t\t") : PUTS(w, "Truncated\t\t\t");
    w = put_hex_bytes(w, b, len);
    w = PUTS(w, "\t\t\t");
    if (why == WRONG_END) {
        w = PUTS(w, "0x0F and 24 bytes, but the last is 0x"); w = put_hex2(w, b[24]);
        w = PUTS(w, ", not an end byte (00, 04, 14, 24, 34, 08): not a frame");
    } else {
        w = put_u64(w, len);
        switch (why) {
        case CUT: w = PUTS(w, " of 25 bytes before the next frame start: frame cut short"); break;
        case AT_END: w = slot ? PUTS(w, " of 3 bytes of a slot answer before the input ended") : PUTS(w, " of 25 bytes before the input ended"); break;
        case SLOT_CUT: w = PUTS(w, " of 3 bytes of a slot answer, then a frame"); break;
        default: w = len == 1 ? PUTS(w, " byte outside frames and slots") : PUTS(w, " bytes outside frames and slots");
        }
    }
    *w++ = '\n';
    o = w;
}

// ---- reassembly (busnoop's rules, src/futaba/wire.rs) ---------------------------------------
static int slots_open;          // after an SBUS2 frame announcing a group
static unsigned slot_group, slot_index;

// the first 0x0F in b[1..limit), or 0
static inline size_t next_start(const unsigned char *b, size_t limit) {
    if (limit <= 1) return 0;
    const unsigned char *q = memchr(b + 1, 0x0F, limit - 1);
    return q ? (size_t)(q - b) : 0;
}

// What starts at b (len bytes there, `end`: no more come): 0 when more bytes are needed,
// otherwise the bytes taken; the row is written.
static size_t step(const unsigned char *b, size_t len, int end, uint64_t off) {
    unsigned first = b[0];
    if (first == 0x0F) {
        if (len < 25) {
            if (!end) return 0;
            size_t q = next_start(b, len);
            slots_open = 0;
            if (q) { broken_row(off, CUT, b, q); return q; }
            broken_row(off, AT_END, b, len); return len;
        }
        if (END_OK[b[24]]) {
            unsigned e = b[24];
            slots_open = e == 0x04 || e == 0x14 || e == 0x24 || e == 0x34;
            slot_group = e >> 4; slot_index = 0;
            frame_row(off, b);
            return 25;
        }
        size_t from = 1;
        for (;;) {
            size_t q = next_start(b + from - 1, 25 - from + 1);
            if (!q) break;
            q += from - 1;
            if (len < q + 25) { if (!end) return 0; break; }
            if (END_OK[b[q + 24]]) { slots_open = 0; broken_row(off, CUT, b, q); return q; }
            from = q + 1;
        }
        slots_open = 0;
        broken_row(off, WRONG_END, b, 25);
        return 25;
    }
    if (slots_open && (first & 7) == 3) {
        if (len < 3) {
            if (!end) return 0;
            slots_open = 0; broken_row(off, AT_END, b, len); return len;
        }
        if (b[1] != 0x0F && b[2] != 0x0F) goto slot;
        if (len < 28 && !end) return 0;
#define FRAME_AT(i) ((i) < len && b[i] == 0x0F && (i) + 24 < len && END_OK[b[(i) + 24]])
        int fits = len == 3 || FRAME_AT(3);
        if (!fits) {
            for (size_t i = 1; i < 3; i++)
                if (FRAME_AT(i)) { slots_open = 0; broken_row(off, SLOT_CUT, b, i); return i; }
        }
    slot:
        slot_row(off, b, slot_group);
        if (++slot_index >= 8) slots_open = 0;
        return 3;
    }
    size_t limit = len < 64 ? len : 64;
    size_t q = next_start(b, limit);
    if (!q) {
        if (limit < 64 && !end) return 0;
        q = limit;
    }
    slots_open = 0;
    broken_row(off, GARBAGE, b, q);
    return q;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: futaba_ref FILE\n"); return 2; }
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
            // almost every step: a whole frame with its end byte
            if (b[i] == 0x0F && i + 25 <= n && END_OK[b[i + 24]]) {
                unsigned e = b[i + 24];
                slots_open = e == 0x04 || e == 0x14 || e == 0x24 || e == 0x34;
                slot_group = e >> 4; slot_index = 0;
                frame_row(base + i, b + i);
                i += 25;
                continue;
            }
            size_t k = step(b + i, n - i, eof, base + i);
            if (!k) break;
            i += k;
        }
        carry = n - i;
        if (carry) memmove(ibuf, ibuf + i, carry);
        base += i;
        if (eof) break;
    }
    flush_out();
    return 0;
}
