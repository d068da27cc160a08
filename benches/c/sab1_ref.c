// sab1_ref.c: a hand-tuned reference modm SAB v1 decoder, the physical limit of
// `busnoop sab FILE --framing sync -f tsv`.
//
// The SAB v1 framing (`54 LEN HDR CMD DATA[LEN] CRC8`, CRC-8/MAXIM-DOW over LENGTH … DATA)
// with busnoop's resynchronisation (`src/sab/sync.rs`), on top of everything else of
// `sab_ref.c` (decoding, pairing, the rows, the output buffer), which it includes with
// `SAB_V1` defined: that selects the `sync` Framing column, the framing note and the CRC-8
// note of BadCRC rows, and leaves the reading loop to this file. Reads in 256 KiB chunks,
// keeps a carry of at least LOOK bytes past the place it decides (every rule below looks at
// most 111 bytes ahead), and decides each 0x54 as busnoop does:
//
//   * a complete candidate whose CRC passes is a frame, unless a valid frame starts inside
//     it and (reaching past its end, with no valid frame at its end but one at the later
//     frame's end; or nested, with the reading from its second byte finding more than one
//     frame more) shows it is a damaged frame whose CRC passed by chance: then its 0x54 is
//     a false one (garbage);
//   * a LENGTH above 32: the 0x54 is garbage;
//   * a failed candidate with a valid frame starting inside it: a false 0x54 (garbage);
//   * else a bad frame (a BadCRC row), its bytes consumed;
//   * every other byte is garbage, collected into rows of at most 64 bytes with the counts
//     of false 0x54 and bad LENGTHs.
//
// Not covered (it stops with a message): garbage before the first frame, the input ending
// inside a candidate, a request still open at the end.
//
//   cc -O2 -march=x86-64-v2 -o sab1_ref sab1_ref.c
//   ./sab1_ref FILE > out.tsv
//   "$BIN" sab FILE --framing sync -f tsv --no-config | cmp - out.tsv
//
// SPDX-License-Identifier: MIT OR Apache-2.0
#define SAB_V1 1
#include "sab_ref.c"

#define SYNC 0x54
#define MAX_PAYLOAD 32
#define OVERHEAD 5
#define MAX_FRAME (MAX_PAYLOAD + OVERHEAD)
#define LOOK 128  // bytes past a 0x54 that decide it (3 frame lengths suffice)
#define INVALID (-1)
#define INCOMPLETE (-2)

static uint8_t CRC8[256];
static inline unsigned crc8(const unsigned char *b, size_t n) {
    unsigned c = 0;
    for (size_t i = 0; i < n; i++) c = CRC8[c ^ b[i]];
    return c;
}

static int eof;  // the input ends at the end of the buffer

// The candidate at b (avail bytes there): its length when complete and valid
static inline int check_at(const unsigned char *b, size_t avail) {
    if (avail < 1 || b[0] != SYNC) return INVALID;
    if (avail < 2) return INCOMPLETE;
    unsigned len = b[1];
    if (len > MAX_PAYLOAD) return INVALID;
    size_t end = len + OVERHEAD;
    if (avail < end) return INCOMPLETE;
    return crc8(b + 1, end - 2) == b[end - 1] ? (int)end : INVALID;
}
static void undecided(void) { fprintf(stderr, "input ends inside a candidate: not covered\n"); exit(4); }
static inline int check_in(const unsigned char *b, size_t avail, size_t at) {
    int c = at < avail ? check_at(b + at, avail - at) : (eof ? INVALID : INCOMPLETE);
    if (c == INCOMPLETE && !eof) undecided();
    return c;
}

// Valid frames read greedily from `from`, the ones starting before `horizon`: their number
static int chain(const unsigned char *b, size_t avail, size_t from, size_t horizon) {
    int n = 0;
    size_t p = from;
    while (p < horizon) {
        if (p >= avail) { if (!eof) undecided(); return n; }
        size_t to = horizon < avail ? horizon : avail;
        const unsigned char *k = memchr(b + p, SYNC, to - p);
        if (!k) { p = to; continue; }
        p = (size_t)(k - b);
        int len = check_in(b, avail, p);
        if (len > 0) { n++; p += (size_t)len; } else p++;
    }
    return n;
}

// A valid frame ending at `end` at b: 1 when it stands, 0 when its 0x54 is a false one
static int stands(const unsigned char *b, size_t avail, size_t end) {
    size_t p = 1;
    int nested = 0;
    while (p < end) {
        const unsigned char *k = memchr(b + p, SYNC, end - p);
        if (!k) break;
        p = (size_t)(k - b);
        int len = check_in(b, avail, p);
        if (len > 0 && p + (size_t)len > end) {
            if (check_in(b, avail, end) > 0 || (end < avail && b[end] == SYNC && check_in(b, avail, end + 1) > 0))
                return 1;
            if (p == end - 1 || check_in(b, avail, p + (size_t)len) > 0) return 0;
            nested = 1;
            break;
        }
        if (len > 0) nested = 1;
        p++;
    }
    if (!nested) return 1;
    size_t horizon = end + MAX_FRAME;
    int n = chain(b, avail, end, horizon), m = chain(b, avail, 1, horizon);
    return !(m > n + 1);
}

// ---- garbage ------------------------------------------------------------------------------
static unsigned char run[64];
static size_t run_len;
static uint64_t run_pos;
static unsigned false_syncs, bad_lengths;
static uint64_t frames;

static void flush_garbage(void) {
    if (!run_len) return;
    uint64_t start = ns_at(run_pos);
    deadline(start);
#ifndef DECODE_ONLY
    char *w = row_start(start);
    w = PUTS(w, "\t\tGarbage\t\t\t");
    w = put_hex_bytes(w, run, run_len);
    w = PUTS(w, "\t\t\t\t\t" FRAMING_COL "\t");
    int notes = 0;
    w = note_start(w, &notes);
    w = put_u64(w, run_len);
    w = run_len == 1 ? PUTS(w, " byte") : PUTS(w, " bytes");
    w = PUTS(w, " between frames");
    if (false_syncs) { w = PUTS(w, "; "); w = put_u64(w, false_syncs); w = PUTS(w, " false 0x54 (the frame it announced overlapped a valid frame)"); }
    if (bad_lengths) { w = PUTS(w, "; "); w = put_u64(w, bad_lengths); w = PUTS(w, " 0x54 followed by a LENGTH above 32"); }
    o = row_end(w, notes);
#endif
    run_len = 0; false_syncs = 0; bad_lengths = 0;
}
static inline void garbage(const unsigned char *b, size_t n, uint64_t pos) {
    if (!frames) { fprintf(stderr, "garbage before the first frame: not covered\n"); exit(4); }
    while (n) {
        if (!run_len) run_pos = pos;
        size_t k = n < 64 - run_len ? n : 64 - run_len;
        memcpy(run + run_len, b, k);
        run_len += k; b += k; n -= k; pos += k;
        if (run_len == 64) flush_garbage();
    }
}

// ---- the reading loop ---------------------------------------------------------------------
// Decides the bytes of b[0..n) up to `limit` (more when a frame ends past it); returns where it
// stopped. `base`: the stream position of b[0].
static size_t decide(const unsigned char *b, size_t n, size_t limit, uint64_t base) {
    size_t p = 0;
    while (p < limit) {
        const unsigned char *k = memchr(b + p, SYNC, limit - p);
        size_t q = k ? (size_t)(k - b) : limit;
        if (q > p) { garbage(b + p, q - p, base + p); p = q; continue; }
        const unsigned char *c = b + p;
        size_t avail = n - p;
        int len = check_at(c, avail);
        if (len == INCOMPLETE) undecided();
        if (len > 0) {
            if (stands(c, avail, (size_t)len)) {
                flush_garbage();
                frames++;
                uint64_t start = ns_at(base + p);
                deadline(start);
                frame(c + 2, (size_t)len - 3, start, ns_at(base + p + (size_t)len));
                p += (size_t)len;
            } else { false_syncs++; garbage(c, 1, base + p); p++; }
            continue;
        }
        if (c[1] > MAX_PAYLOAD) { bad_lengths++; garbage(c, 1, base + p); p++; continue; }
        size_t full = (size_t)c[1] + OVERHEAD;
        int false_sync = 0;
        for (size_t i = 1; i < full; i++)
            if (c[i] == SYNC && check_in(c, avail, i) > 0) { false_sync = 1; break; }
        if (false_sync) { false_syncs++; garbage(c, 1, base + p); p++; continue; }
        flush_garbage();
        uint64_t start = ns_at(base + p);
        deadline(start);
        unsigned received = c[full - 1], computed = crc8(c + 1, full - 2);
        bad_crc(c + 2, full - 3, received, computed, crc8(c, full - 1) == received, start);
        p += full;
    }
    return p;
}

static void reassemble(int fd) {
    for (unsigned i = 0; i < 256; i++) {
        unsigned c = i;
        for (int k = 0; k < 8; k++) c = c & 1 ? (c >> 1) ^ 0x8C : c >> 1;
        CRC8[i] = (uint8_t)c;
    }
    size_t carry = 0;   // undecided bytes, kept for the next read
    uint64_t base = 0;  // stream position of ibuf[0]
    for (;;) {
        ssize_t r = read(fd, ibuf + carry, RD);
        if (r < 0) exit(3);
        size_t n = carry + (size_t)r;
        eof = r == 0;
        size_t limit = eof ? n : (n > LOOK ? n - LOOK : 0);
        size_t p = decide(ibuf, n, limit, base);
        carry = n - p;
        memmove(ibuf, ibuf + p, carry);
        base += p;
        if (eof) break;
    }
    flush_garbage();
}
