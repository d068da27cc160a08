// busnoop's C reference decoders: what crsf_ref.c and ghst_ref.c share, CRSF's framing (an
// address byte, a length, a type, the payload and a CRC-8/DVB-S2, resynchronising at the next
// valid frame): the Counter kept as text, the start of a row, runs of garbage, bad frames and
// the reading loop. Same licence as busnoop (MIT OR Apache-2.0). The including file defines
// before it: REF_NAME, the tables CRC and ADDR, DEVICE, type_name(addr, type), init_tables(),
// and after it frame_row(f, len, off), the row of a valid frame.
#ifndef CRSF_FRAME_H
#define CRSF_FRAME_H

static void frame_row(const unsigned char *f, int len, uint64_t off);

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
    if (argc < 2) { fprintf(stderr, "usage: " REF_NAME " FILE\n"); return 2; }
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


#endif
