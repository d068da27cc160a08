// sport_ref.c: a hand-tuned reference S.Port decoder, the physical limit of `busnoop sport FILE -f tsv`.
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks
// (as busnoop), reassembles slots (0x7E, header, 8 body bytes with 0x7D byte stuffing; a poll
// without answer, truncated frames, garbage between slots), checks the S.Port CRC (end-around
// carry sum), decodes the value of every common sensor (all scalar sensors of
// busnoop's table, FLVSS cells, GPS lat/lon) and writes busnoop's TSV table (11 columns: Counter,
// Millis, ID, Device, Type, Sensor #, Sensor, Data, Value, Unit, Note) through a 64 KiB output
// buffer. For a capture of those sensors the output is byte-identical to busnoop's. Not covered
// (busnoop has them): hub IDs 0x00xx, pairs (0x0730, 0x0Bx0, 0x0E50),
// passthrough 0x50xx, servo, date/time, receiver IDs 0xF1xx, config/maintenance/firmware frames:
// these fall back to a generic hex row, so their cells differ from busnoop's, not their cost.
//
//   cc -O2 -march=x86-64-v2 -o sport_ref sport_ref.c
//   ./sport_ref FILE > out.tsv
//   "$BIN" sport FILE -f tsv --no-config | cmp - out.tsv   # busnoop: $BIN (built from ${PROJECT:-.})
//   cc -O2 -march=x86-64-v2 -DDECODE_ONLY -o sport_decode sport_ref.c   # the same without the text
#include "ref_io.h"

static unsigned char ibuf[RD + 64];

// ---- text helpers -------------------------------------------------------------------------

#include "ref_text.h"
// a constant string of up to 32 bytes with its length: one fixed-size copy
typedef struct { char s[32]; int n; } Str;
static inline char *put_str(char *w, const Str *s) { memcpy(w, s->s, 32); return w + s->n; }
static void mkstr(Str *s, const char *t) { memset(s->s, 0, 32); s->n = (int)strlen(t); memcpy(s->s, t, (size_t)s->n); }

// ---- tables -------------------------------------------------------------------------------
static const char *DEVICES[32] = {
    "Vario", "FLVSS", "FAS-40S", "GPS", "RPM", "SP2UART-H", "SP2UART-R", "FCS-150A", "", "ASS-70",
    "", "", "", "Uplink", "", "", "ESC", "Config", "", "", "Downlink", "", "Gas Suite", "IMU",
    "Receiver", "Power Box", "Temp", "FC", "", "", "", ""};
static Str PREFIX[32];      // "ID\tDevice\t"
static unsigned char HDR_OK[32];

enum { K_NONE = 0, K_CELLS = 1, K_GPS = 2, K_SCALAR = 3 };
typedef struct { const char *label, *unit; int prec, sign; } Scalar;
static const struct { uint16_t base; Scalar s; } SCALARS[] = {
    {0x0100, {"Alt", "m", 2, 1}},      {0x0110, {"Vario", "m/s", 2, 1}}, {0x0200, {"Amps", "A", 1, 0}},
    {0x0210, {"Volts", "V", 2, 0}},    {0x0400, {"Tmp1", "degC", 0, 1}}, {0x0410, {"Tmp2", "degC", 0, 1}},
    {0x0500, {"RPM", "rpm", 0, 0}},    {0x0600, {"Fuel", "%", 0, 0}},    {0x0700, {"AccX", "g", 3, 1}},
    {0x0710, {"AccY", "g", 3, 1}},     {0x0720, {"AccZ", "g", 3, 1}},    {0x0820, {"GAlt", "m", 2, 1}},
    {0x0830, {"GSpd", "kts", 3, 0}},   {0x0840, {"Hdg", "deg", 2, 0}},   {0x0900, {"A3", "V", 2, 1}},
    {0x0910, {"A4", "V", 2, 1}},       {0x0A00, {"ASpd", "kts", 1, 0}},  {0x0A10, {"Fuel", "ml", 2, 0}},
    {0x0B40, {"Chan", "", 0, 0}},      {0x0D00, {"GTp1", "degC", 0, 1}}, {0x0D10, {"GTp2", "degC", 0, 1}},
    {0x0D20, {"GRPM", "rpm", 0, 0}},   {0x0D30, {"GRVl", "ml", 0, 0}},   {0x0D40, {"GRPc", "%", 0, 0}},
    {0x0D50, {"GFlo", "ml/min", 0, 0}}, {0x0D60, {"GMFl", "ml/min", 0, 0}}, {0x0D70, {"GAFl", "ml/min", 0, 0}},
};
#define NSCALAR (sizeof SCALARS / sizeof SCALARS[0])
typedef struct { Str mid, tail; int prec, sign; const char *unit; } Sensor; // mid "\tAlt\t", tail "\tm\t"
static Sensor SENS[NSCALAR + 3];
static unsigned char KIND[4096];  // app_id >> 4 -> index into SENS (0: none)
static int CELLS_I, GPS_I;

static void init_tables(void) {
    for (int i = 0; i < 32; i++) {
        char t[32]; snprintf(t, sizeof t, "%d\t%s\t", i, DEVICES[i]); mkstr(&PREFIX[i], t);
        int b[5]; for (int k = 0; k < 5; k++) b[k] = (i >> k) & 1;
        HDR_OK[i] = (unsigned char)(i | (b[0] ^ b[1] ^ b[2]) << 5 | (b[2] ^ b[3] ^ b[4]) << 6 | (b[0] ^ b[2] ^ b[4]) << 7);
    }
    int n = 1;
    for (size_t i = 0; i < NSCALAR; i++, n++) {
        char t[32]; const Scalar *s = &SCALARS[i].s;
        snprintf(t, sizeof t, "\t%s\t", s->label); mkstr(&SENS[n].mid, t);
        snprintf(t, sizeof t, "\t%s\t", s->unit); mkstr(&SENS[n].tail, t);
        SENS[n].prec = s->prec; SENS[n].sign = s->sign; SENS[n].unit = s->unit;
        KIND[SCALARS[i].base >> 4] = (unsigned char)n;
    }
    CELLS_I = n; mkstr(&SENS[n].mid, "\tCels\t"); mkstr(&SENS[n].tail, "\tV\t"); KIND[0x030] = (unsigned char)n++;
    GPS_I = n; mkstr(&SENS[n].mid, "\tGPS\t"); mkstr(&SENS[n].tail, "\tdeg\t"); KIND[0x080] = (unsigned char)n++;
}

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text (digits ctr[start..32))
static uint64_t next_index;                      // slots so far
static int64_t last_slot = -1;
static unsigned char garb[64]; static int garb_len; static int64_t garb_after;

static inline char *row_start(uint64_t millis) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start; // counters below 10^16
    *w++ = '\t';
    w = put_u64(w, millis);
    *w++ = '\t';
    return w;
}

static void garbage_flush(void) {
    if (!garb_len) return;
    char *w = row_start(garb_after < 0 ? 0 : (uint64_t)garb_after * 12);
    w = PUTS(w, "\t\tGarbage\t\t\t");
    w = put_hex_bytes(w, garb, garb_len);
    w = PUTS(w, "\t\t\t");
    if (garb_len == 1 && garb[0] == 0x7E) w = PUTS(w, "0x7E without a header byte");
    else { w = put_u64(w, (uint64_t)garb_len); w = garb_after < 0 ? PUTS(w, " bytes before the first 0x7E") : PUTS(w, " bytes after a complete frame"); }
    *w++ = '\n';
    o = w; garb_len = 0;
}
static inline void garbage_byte(unsigned char b) {
    if (!garb_len) garb_after = last_slot;
    garb[garb_len++] = b;
    if (garb_len == 64) garbage_flush();
}

static inline char *note_header(char *w, unsigned hdr, int *notes) {
    if (HDR_OK[hdr & 31] != hdr) { if ((*notes)++) w = PUTS(w, "; "); w = PUTS(w, "non-standard check bits (header "); w = put_0x(w, hdr); *w++ = ')'; }
    return w;
}
static inline char *note_escape(char *w, int unusual, int *notes) {
    if (unusual) { if ((*notes)++) w = PUTS(w, "; "); w = PUTS(w, "unusual escape (0x7D not followed by 0x5E/0x5D)"); }
    return w;
}

// a slot without a complete body: an unanswered poll (len 0) or a truncated frame
static void slot_short(unsigned hdr, const unsigned char *body, int len, int truncated, int unusual) {
    uint64_t idx = next_index++; last_slot = (int64_t)idx;
#ifdef DECODE_ONLY
    extern uint64_t sink_sum; sink_sum += hdr + (unsigned)len + (unsigned)truncated + (unsigned)unusual + body[0]; return;
#endif
    char *w = row_start(idx * 12);
    w = put_str(w, &PREFIX[hdr & 31]);
    int notes = 0;
    if (!truncated) w = PUTS(w, "\t\t\t\t\t\t");
    else {
        w = PUTS(w, "Truncated\t\t\t"); w = put_hex_bytes(w, body, len); w = PUTS(w, "\t\t\t");
        *w++ = (char)('0' + len); w = PUTS(w, " of 8 bytes before the frame was cut"); notes = 1;
    }
    w = note_header(w, hdr, &notes); w = note_escape(w, unusual, &notes);
    *w++ = '\n'; o = w;
}

// a complete slot: header and 8 unstuffed body bytes
#ifdef DECODE_ONLY  // the same work without the text: reassembly, CRC, the value as a number
uint64_t sink_sum;
static inline void slot_full(unsigned hdr, uint64_t body, int unusual) {
    uint64_t idx = next_index++; last_slot = (int64_t)idx;
    uint64_t pairs = (body & 0x00FF00FF00FF00FFull) + ((body >> 8) & 0x00FF00FF00FF00FFull);
    unsigned s = (unsigned)((pairs * 0x0001000100010001ull) >> 48);
    while (s > 0xFF) s = (s & 0xFF) + (s >> 8);
    unsigned type = (unsigned)(body & 0xFF), app = (unsigned)(body >> 8) & 0xFFFF;
    uint32_t value = (uint32_t)(body >> 24);
    int64_t v = value;
    int k = KIND[app >> 4];
    if (type == 0x10 && k) {
        if (k == CELLS_I) v = ((value >> 8) & 0xFFF) * 2 + ((value >> 20) * 2 << 16);
        else if (k == GPS_I) { v = ((int64_t)(value & 0x3FFFFFFF) * 100 + 3) / 6; if (value & 0x40000000) v = -v; }
        else if (SENS[k].sign) v = (int32_t)value;
    }
    sink_sum += (uint64_t)v + (s == 0xFF) + (unsigned)k + hdr + (unsigned)unusual + idx;
}
#else
static inline void slot_full(unsigned hdr, uint64_t body, int unusual) {
    uint64_t idx = next_index++; last_slot = (int64_t)idx;
    char *w = row_start(idx * 12);
    w = put_str(w, &PREFIX[hdr & 31]);
    // CRC: end-around-carry sum of the 8 bytes is 0xFF (four 16-bit lanes, one multiply)
    uint64_t pairs = (body & 0x00FF00FF00FF00FFull) + ((body >> 8) & 0x00FF00FF00FF00FFull);
    unsigned s = (unsigned)((pairs * 0x0001000100010001ull) >> 48);
    while (s > 0xFF) s = (s & 0xFF) + (s >> 8);
    int ok = s == 0xFF;
    unsigned type = (unsigned)(body & 0xFF), app = (unsigned)(body >> 8) & 0xFFFF;
    uint32_t value = (uint32_t)(body >> 24);
    int notes = 0;
    if (type == 0x00 && app == 0 && value == 0) {
        if (ok) w = PUTS(w, "Null\t\t\t\t\t\t");
        else { w = PUTS(w, "BadCRC\t\t\t\t\t\tCRC "); w = put_0x(w, (unsigned)(body >> 56)); w = PUTS(w, ", expected 0xFF (Null frame)"); notes = 1; }
    } else if (type == 0x10) {
        w = ok ? PUTS(w, "Data\t0x") : PUTS(w, "BadCRC\t0x");
        *w++ = HEXU[app >> 12]; *w++ = HEXU[(app >> 8) & 15]; *w++ = HEXU[(app >> 4) & 15]; *w++ = HEXU[app & 15];
        int k = KIND[app >> 4];
        const Sensor *se = &SENS[k];
        char *v0, *v1;  // the Value column's text (the first number)
        if (k == 0) {  // unknown app ID: busnoop names it by its hex and shows the integer
            w = PUTS(w, "\t0x");
            *w++ = HEXU[app >> 12]; *w++ = HEXU[(app >> 8) & 15]; *w++ = HEXU[(app >> 4) & 15]; *w++ = HEXU[app & 15];
            *w++ = '\t';
            v0 = w; w = put_u64(w, value); v1 = w;
        } else {
            w = put_str(w, &se->mid);
            if (k == CELLS_I) {
                unsigned index = value & 15, count = (value >> 4) & 15;
                w = PUTS(w, "count="); w = put_u64(w, count);
                w = PUTS(w, " cell"); w = put_u64(w, index + 1); *w++ = '=';
                v0 = w; w = put_fixed(w, (int64_t)(((value >> 8) & 0xFFF) * 2), 3); v1 = w;
                if (index + 1 < count) { w = PUTS(w, " cell"); w = put_u64(w, ((index + 1) & 15) + 1); *w++ = '='; w = put_fixed(w, (int64_t)((value >> 20) * 2), 3); }
            } else if (k == GPS_I) {
                int64_t e7 = ((int64_t)(value & 0x3FFFFFFF) * 100 + 3) / 6;
                if (value & 0x40000000) e7 = -e7;
                w = (value & 0x80000000) ? PUTS(w, "lon=") : PUTS(w, "lat=");
                v0 = w; w = put_fixed(w, e7, 7); v1 = w;
            } else {
                int64_t raw = se->sign ? (int64_t)(int32_t)value : (int64_t)value;
                v0 = w; w = put_fixed(w, raw, se->prec); v1 = w;
            }
        }
        *w++ = '\t';
        if (ok) {  // the Value: the first number again (at most 24 bytes; loads before stores)
            uint64_t x0, x1, x2; memcpy(&x0, v0, 8); memcpy(&x1, v0 + 8, 8); memcpy(&x2, v0 + 16, 8);
            memcpy(w, &x0, 8); memcpy(w + 8, &x1, 8); memcpy(w + 16, &x2, 8); w += v1 - v0;
        }
        if (k == 0) { *w++ = '\t'; *w++ = '\t'; } else w = put_str(w, &se->tail);
        if (!ok) {
            unsigned x = 0; for (int i = 0; i < 7; i++) x += (unsigned)(body >> (8 * i)) & 0xFF;
            while (x > 0xFF) x = (x & 0xFF) + (x >> 8);
            w = PUTS(w, "CRC "); w = put_0x(w, (unsigned)(body >> 56)); w = PUTS(w, ", expected "); w = put_0x(w, 0xFF - x);
            w = PUTS(w, " (Data frame)"); notes = 1;
        }
    } else {  // other frame types: generic row (busnoop has its own cells for these; cost alike)
        w = PUTS(w, "Unknown\t\t\t");
        unsigned char b[8]; memcpy(b, &body, 8);
        w = put_hex_bytes(w, b + 1, 6);
        w = PUTS(w, "\t\t\tunknown frame type "); w = put_0x(w, type); notes = 1;
    }
    w = note_header(w, hdr, &notes); w = note_escape(w, unusual, &notes);
    *w++ = '\n'; o = w;
}
#endif

// ---- reassembly ---------------------------------------------------------------------------
static inline int plain(uint64_t v) {
    const uint64_t ONES = 0x0101010101010101ull, HIGHS = 0x8080808080808080ull;
    uint64_t a = v ^ (0x7Eull * ONES), b = v ^ (0x7Dull * ONES);
    return (((a - ONES) & ~a) | ((b - ONES) & ~b)) & HIGHS ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: sport_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tNote\n");
    size_t carry = 0;
    int outside = 1;  // between slots (bytes there are garbage)
    for (;;) {
        ssize_t r = read(fd, ibuf + carry, RD);
        if (r < 0) return 3;
        int eof = r == 0;
        size_t n = carry + (size_t)r, i = 0;
        carry = 0;
        const unsigned char *b = ibuf;
        while (i < n) {
            if (outside && b[i] == 0x7E) outside = 0;  // right after a frame: the next slot's 0x7E
            if (outside) {
                const unsigned char *q = memchr(b + i, 0x7E, n - i);
                size_t at = q ? (size_t)(q - b) : n;
                for (; i < at; i++) garbage_byte(b[i]);
                if (!q) break;
                outside = 0;
            }
            // b[i] is 0x7E: a slot starts
            garbage_flush();
            if (i + 1 >= n) { if (eof) { garbage_byte(0x7E); i++; outside = 1; } else { carry = n - i; } break; }
            unsigned hdr = b[i + 1];
            if (hdr == 0x7E) { garbage_byte(0x7E); i++; continue; }  // lone start, the next 0x7E opens
            size_t j = i + 2;
            uint64_t v;
            if (j + 8 <= n && (memcpy(&v, b + j, 8), plain(v))) {  // almost every frame
                slot_full(hdr, v, 0);
                i = j + 8; outside = 1;
                continue;
            }
            unsigned char body[8]; int got = 0, esc = 0, unusual = 0;
            size_t k = j;
            for (;;) {
                if (k >= n) break;
                unsigned c = b[k];
                if (c == 0x7E) break;
                k++;
                if (esc) { esc = 0; if (c != 0x5E && c != 0x5D) unusual = 1; body[got++] = (unsigned char)(c ^ 0x20); }
                else if (c == 0x7D) esc = 1;
                else body[got++] = (unsigned char)c;
                if (got == 8) break;
            }
            if (got == 8) { memcpy(&v, body, 8); slot_full(hdr, v, unusual); i = k; outside = 1; continue; }
            if (k >= n && !eof) { carry = n - i; break; }  // the slot goes on in the next chunk
            // cut by the next 0x7E (or the end of the input)
            slot_short(hdr, body, got, got > 0 || esc, unusual);
            i = k; outside = k >= n;
            if (k >= n) break;
        }
        if (carry) memmove(ibuf, ibuf + n - carry, carry);
        if (eof) break;
    }
    garbage_flush();
#ifdef DECODE_ONLY
    fprintf(stderr, "rows %llu, sum %llu\n", (unsigned long long)next_index, (unsigned long long)sink_sum);
    o = obuf;
#endif
    flush_out();
    return 0;
}
