// busnoop's C reference decoders: the text helpers they share (sport_ref.c, sab_ref.c, crsf_ref.c,
// ghst_ref.c, fport_ref.c, ether_ref.c, sbus_ref.c) (decimal digits without leading zeros, signed and fixed-point numbers, hex, a short copy).
// Same licence as busnoop (MIT OR Apache-2.0). Include after ref_io.h.
#ifndef REF_TEXT_H
#define REF_TEXT_H

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
static inline char *put_hex_bytes(char *w, const unsigned char *b, size_t n) {
    for (size_t i = 0; i < n; i++) { if (i) *w++ = ' '; *w++ = HEXU[b[i] >> 4]; *w++ = HEXU[b[i] & 15]; }
    return w;
}
static inline char *put_0x(char *w, unsigned b) { *w++ = '0'; *w++ = 'x'; *w++ = HEXU[(b >> 4) & 15]; *w++ = HEXU[b & 15]; return w; }
// a copy of the text between a and b (at most 32 bytes), loads before stores
static inline char *put_again(char *w, const char *a, const char *b) {
    uint64_t x0, x1, x2, x3; memcpy(&x0, a, 8); memcpy(&x1, a + 8, 8); memcpy(&x2, a + 16, 8); memcpy(&x3, a + 24, 8);
    memcpy(w, &x0, 8); memcpy(w + 8, &x1, 8); memcpy(w + 16, &x2, 8); memcpy(w + 24, &x3, 8);
    return w + (b - a);
}

#endif
