// busnoop's C reference decoders: what fport_ref.c (F.Port v1) and fport2_ref.c (F.Port 2)
// share — the channel and sensor tables, the Counter and Millis cells (115200 baud, 10 bits a
// byte), garbage runs, the FrSky checksum, and the cells of a 16-channel control row and of a
// flight controller's S.Port data answer. Same licence as busnoop (MIT OR Apache-2.0). Include
// after ref_io.h and ref_text.h.
#ifndef FPORT_ROWS_H
#define FPORT_ROWS_H

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
        // the flight controller (physical ID 27) sends 1/100 g
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

// the FrSky sum with end-around carry (the checksum is 0xFF minus it)
static inline unsigned carry_sum(const unsigned char *b, int n) {
    unsigned s = 0;
    for (int i = 0; i < n; i++) s += b[i];
    while (s > 0xFF) s = (s & 0xFF) + (s >> 8);
    return s;
}
static inline uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

// Sensor #, Sensor, Data, Value, Unit, Frame and Note of a 16-channel control frame whose 22
// channel bytes start at p (the flags byte after them), after the Counter, Millis and ID cells
static inline char *control_cells(char *w, const unsigned char *p) {
    unsigned raw[16];
    for (int k = 0; k < 16; k++) {
        int bit = 11 * k;
        const unsigned char *q = p + (bit >> 3);
        uint32_t x = (uint32_t)q[0] | (uint32_t)q[1] << 8 | (uint32_t)q[2] << 16;  // within the frame
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
    return w;
}

// Type .. Frame of the flight controller's S.Port data answer (app ID, value), Note empty
static inline char *data_cells(char *w, unsigned app, uint32_t value) {
    w = PUTS(w, "Data\t0x");
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
    return PUTS(w, "\tUplink\t");
}

#endif
