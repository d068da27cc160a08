// modbus_ref.c: a hand-tuned reference Modbus RTU decoder, the physical limit of
// `busnoop modbus FILE -f tsv --no-config` on a raw capture (bytes without times).
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks
// (as busnoop), frames it by content as busnoop does (never by silence): at each place the
// frame's length is read as a request and as a response of the function code there (fixed
// lengths, byte counts, Read Device Identification's objects, exceptions), the response the
// last request awaits is tried first, then the shortest reading whose CRC-16/MODBUS checks
// (slice-by-16 tables), with the stray-zero-byte trap, the retry test and the limits for
// readings among junk; bytes that hold no frame are sorted into BadCRC, Truncated and Garbage
// rows as busnoop's `classify` does. Requests and answers are paired (one request waits;
// retries, "no answer before the retry / next request", unpaired answers, a broken answer
// spoiling the wait), and the Data cell of requests and responses of functions 1-6, 15 and 16
// and of exceptions is written with the first number as Value, busnoop's TSV table (12
// columns: Counter, Millis, ID, Device, Type, Sensor #, Sensor, Data, Value, Unit, Resp ms,
// Note) through a 64 KiB output buffer. Millis is the byte offset times 11 bits at 19200 baud
// (busnoop's default line, 8E1). For a capture of those functions the output is
// byte-identical to busnoop's. Not covered (busnoop has them): the Data cells of functions 7,
// 8, 11, 12, 17, 20-24 and 43 (framed alike, their rows here show an empty Data cell), the
// register map (names, types, units), times (recordings, live lines: response times,
// deadlines, late answers), `--stats`.
//
//   cc -O2 -march=x86-64-v2 -o modbus_ref modbus_ref.c
//   ./modbus_ref FILE > out.tsv
//   "$BIN" modbus FILE -f tsv --no-config | cmp - out.tsv   # busnoop: $BIN
#define OBUF_EXTRA 16384
#include "ref_io.h"

typedef uint8_t u8;
typedef uint16_t u16;

static u8 ibuf[2 * RD + 4096];

// ---- text helpers -------------------------------------------------------------------------

static inline int lead_digits(char *t, uint32_t v) {  // v < 10^8; 8 bytes written
    uint64_t d = eight_digits(v);
    int lead = v ? __builtin_ctzll(d) / 8 : 7;
    d = (d >> (lead * 8)) | ZEROS; memcpy(t, &d, 8);
    return 8 - lead;
}
static inline char *put_u64(char *w, uint64_t v) {
    if (v < 100000000) return w + lead_digits(w, (uint32_t)v);
    int k = lead_digits(w, (uint32_t)(v / 100000000));  // below 10^16
    uint64_t d = eight_digits((uint32_t)(v % 100000000)) | ZEROS; memcpy(w + k, &d, 8);
    return w + k + 8;
}
#define PUTS(w, s) (memcpy((w), (s), sizeof(s) - 1), (w) + sizeof(s) - 1)
static inline char *put_hex_bytes(char *w, const u8 *b, size_t n) {
    for (size_t i = 0; i < n; i++) { if (i) *w++ = ' '; *w++ = HEXU[b[i] >> 4]; *w++ = HEXU[b[i] & 15]; }
    return w;
}
static inline char *put_0x(char *w, unsigned b) { *w++ = '0'; *w++ = 'x'; *w++ = HEXU[(b >> 4) & 15]; *w++ = HEXU[b & 15]; return w; }
static inline char *put_0x16(char *w, unsigned v) { w = put_0x(w, v >> 8); *w++ = HEXU[(v >> 4) & 15]; *w++ = HEXU[v & 15]; return w; }
static inline char *put_str(char *w, const char *s) { size_t n = strlen(s); memcpy(w, s, n); return w + n; }

// ---- CRC-16/MODBUS, slice by 16 -----------------------------------------------------------
static u16 T[16][256];
static void crc_init(void) {
    for (int i = 0; i < 256; i++) {
        unsigned c = (unsigned)i;
        for (int k = 0; k < 8; k++) c = c & 1 ? (c >> 1) ^ 0xA001 : c >> 1;
        T[0][i] = (u16)c;
    }
    for (int t = 1; t < 16; t++)
        for (int i = 0; i < 256; i++) T[t][i] = (u16)((T[t - 1][i] >> 8) ^ T[0][T[t - 1][i] & 0xFF]);
}
static inline unsigned crc16(const u8 *b, size_t n) {
    unsigned c = 0xFFFF;
    while (n >= 16) {
        c ^= (unsigned)b[0] | (unsigned)b[1] << 8;
        c = T[15][c & 0xFF] ^ T[14][c >> 8] ^ T[13][b[2]] ^ T[12][b[3]] ^ T[11][b[4]] ^ T[10][b[5]] ^
            T[9][b[6]] ^ T[8][b[7]] ^ T[7][b[8]] ^ T[6][b[9]] ^ T[5][b[10]] ^ T[4][b[11]] ^
            T[3][b[12]] ^ T[2][b[13]] ^ T[1][b[14]] ^ T[0][b[15]];
        b += 16; n -= 16;
    }
    while (n--) c = (c >> 8) ^ T[0][(c ^ *b++) & 0xFF];
    return c;
}
static inline int crc_ok(const u8 *b, size_t n) { return n >= 3 && crc16(b, n) == 0; }

// ---- functions: names and frame lengths ---------------------------------------------------
static const char *NAME[128];
static const char *const EXC[12] = {"", "Illegal Function", "Illegal Data Address", "Illegal Data Value",
    "Server Device Failure", "Acknowledge", "Server Device Busy", "", "Memory Parity Error", "",
    "Gateway Path Unavailable", "Gateway Target Device Failed to Respond"};
static void names_init(void) {
    for (int i = 0; i < 128; i++) NAME[i] = "";
    NAME[1] = "Read Coils"; NAME[2] = "Read Discrete Inputs"; NAME[3] = "Read Holding Registers";
    NAME[4] = "Read Input Registers"; NAME[5] = "Write Single Coil"; NAME[6] = "Write Single Register";
    NAME[7] = "Read Exception Status"; NAME[8] = "Diagnostics"; NAME[11] = "Get Comm Event Counter";
    NAME[12] = "Get Comm Event Log"; NAME[15] = "Write Multiple Coils"; NAME[16] = "Write Multiple Registers";
    NAME[17] = "Report Server ID"; NAME[20] = "Read File Record"; NAME[21] = "Write File Record";
    NAME[22] = "Mask Write Register"; NAME[23] = "Read/Write Multiple Registers"; NAME[24] = "Read FIFO Queue";
    NAME[43] = "Read Device Identification";
}
static inline int is_public(unsigned fc) { return fc < 128 && NAME[fc][0]; }
static inline int broadcastable(unsigned fc) { return fc == 5 || fc == 6 || fc == 15 || fc == 16 || fc == 21 || fc == 22; }

enum { NO = -1, NEED = -2, BIG = 1 << 30 };  // lengths: >= 0 known
enum { REQ = 0, RESP = 1 };
static inline int within(int n) { return n <= 256 ? n : NO; }
static inline int even(int n) { return n >= 2 && n % 2 == 0 && n <= 250; }

// The length of the frame that starts with b[0..n) read as a request or a response.
static int frame_len(const u8 *b, size_t n, int dir) {
    if (n < 2) return NEED;
    unsigned addr = b[0], fc = b[1];
    if (addr > 247) return NO;
    if (fc & 0x80) return dir == RESP && addr != 0 && is_public(fc & 0x7F) ? 5 : NO;
    if (addr == 0 && (dir == RESP || !broadcastable(fc))) return NO;
#define COUNTED(at, extra, cond) do { if ((at) >= n) return NEED; int v_ = b[at]; return (cond) ? within((extra) + v_) : NO; } while (0)
    if (dir == REQ) {
        switch (fc) {
        case 1: case 2: case 3: case 4: case 5: case 6: case 8: return 8;
        case 7: case 11: case 12: case 17: return 4;
        case 15: COUNTED(6, 9, v_ >= 1 && v_ <= 246);
        case 16: COUNTED(6, 9, even(v_));
        case 20: COUNTED(2, 5, v_ >= 7 && v_ <= 245 && v_ % 7 == 0);
        case 21: COUNTED(2, 5, v_ >= 7 && v_ <= 245);
        case 22: return 10;
        case 23: COUNTED(10, 13, even(v_));
        case 24: return 6;
        case 43: if (n < 3) return NEED; return b[2] == 14 ? 7 : NO;
        default: return NO;
        }
    }
    switch (fc) {
    case 1: case 2: COUNTED(2, 5, v_ >= 1 && v_ <= 250);
    case 3: case 4: case 23: COUNTED(2, 5, even(v_));
    case 5: case 6: case 8: case 11: case 15: case 16: return 8;
    case 7: return 5;
    case 12: COUNTED(2, 5, v_ >= 6 && v_ <= 250);
    case 17: COUNTED(2, 5, v_ >= 1 && v_ <= 250);
    case 20: case 21: COUNTED(2, 5, v_ >= 7 && v_ <= 245);
    case 22: return 10;
    case 24: {
        if (n < 4) return NEED;
        int v = b[2] << 8 | b[3];
        return even(v) ? within(6 + v) : NO;
    }
    case 43: {
        if (n < 3) return NEED;
        if (b[2] != 14) return NO;
        if (n < 8) return NEED;
        size_t at = 8;
        for (unsigned k = 0; k < b[7]; k++) {
            if (at + 1 >= n) return NEED;
            at += 2 + b[at + 1];
            if (at + 2 > 256) return NO;
        }
        return within((int)at + 2);
    }
    default: return NO;
    }
#undef COUNTED
}

// Whether the whole frame b[0..n) read as `dir` keeps the specification's limits.
static int plausible(const u8 *b, size_t n, int dir) {
    if (n < 7) return 1;
#define W(i) ((i) + 1 < n ? (unsigned)(b[i] << 8 | b[(i) + 1]) : 0u)
    unsigned fc = b[1], w4 = W(4), cb = b[6];
    switch (fc) {
    case 1: case 2: return dir == REQ ? w4 >= 1 && w4 <= 2000 : 1;
    case 3: case 4: return dir == REQ ? w4 >= 1 && w4 <= 125 : 1;
    case 5: return w4 == 0xFF00 || w4 == 0;
    case 15: return dir == REQ ? w4 >= 1 && w4 <= 1968 && cb == (w4 + 7) / 8 : w4 >= 1 && w4 <= 1968;
    case 16: return dir == REQ ? w4 >= 1 && w4 <= 123 && cb == 2 * w4 : w4 >= 1 && w4 <= 123;
    case 23: {
        if (dir != REQ) return 1;
        unsigned w8 = W(8);
        return w4 >= 1 && w4 <= 125 && w8 >= 1 && w8 <= 121 && n > 10 && b[10] == 2 * w8;
    }
    default: return 1;
    }
#undef W
}

// ---- the framer (busnoop's wire.rs) -------------------------------------------------------
enum { K_REQ, K_RESP, K_EXC };
typedef struct { int on; u8 addr, fc; int len; } Expect;  // len < 0: not told
static Expect expect;
static u8 wreq[256]; static size_t wreq_len;  // the waiting request's bytes, CRC included

static int response_len(const u8 *r, size_t n) {
#define W(i) ((i) + 1 < n ? (int)(r[i] << 8 | r[(i) + 1]) : -1)
    int v;
    switch (r[1]) {
    case 1: case 2: if ((v = W(4)) < 0) return -1; v = 5 + (v + 7) / 8; break;
    case 3: case 4: case 23: if ((v = W(4)) < 0) return -1; v = 5 + 2 * v; break;
    case 5: case 6: case 8: case 11: case 15: case 16: v = 8; break;
    case 7: v = 5; break;
    case 22: v = 10; break;
    case 21: v = (int)n; break;
    default: return -1;
    }
    return v <= 256 ? v : -1;
#undef W
}

enum { V_WAIT = -1, V_NOT = -2 };
typedef struct { int len, kind, ambiguous, weak; } Verdict;  // len: V_WAIT, V_NOT or the length
static inline int answer_kind(unsigned fc) { return fc & 0x80 ? K_EXC : K_RESP; }
static inline int all_zero(const u8 *b, size_t from, size_t to) {
    for (size_t i = from; i < to; i++) if (b[i]) return 0;
    return 1;
}
static inline int is_retry(const u8 *b, int n, int req) {
    return req >= 0 && req < n && (size_t)req == wreq_len && memcmp(b, wreq, wreq_len) == 0 && all_zero(b, (size_t)req, (size_t)n);
}

// Judges the place b[0..n): `w` the response awaited (or NULL), `clean` right after a frame.
static Verdict judge(const u8 *b, size_t n, int fin, int clean, const Expect *w) {
    Verdict v = {V_NOT, 0, 0, 0};
    if (n == 0) { if (!fin) v.len = V_WAIT; return v; }
    if (b[0] > 247) return v;
    if (n == 1) { if (!fin) v.len = V_WAIT; return v; }
    unsigned addr = b[0], fc = b[1];
    int req = frame_len(b, n, REQ), resp = frame_len(b, n, RESP);
    int expected = w && w->addr == addr && (fc == w->fc || fc == (w->fc | 0x80u));
#define WEAK(len) (!clean && !((req == (len) && plausible(b, (size_t)(len), REQ)) || (resp == (len) && plausible(b, (size_t)(len), RESP))))
    if (expected) {
        int want = fc & 0x80 ? 5 : w->len;
        if (want >= 0 && resp >= 0 && want == resp) {
            if ((size_t)want > n) {
                if (!fin) { v.len = V_WAIT; return v; }
            } else if (crc_ok(b, (size_t)want) && !is_retry(b, want, req)) {
                v.len = want; v.kind = answer_kind(fc); v.ambiguous = req == want; v.weak = WEAK(want);
                return v;
            }
        }
    }
    int r = req >= 0 ? req : BIG, a = resp >= 0 ? resp : BIG;
    int shrt = r < a ? r : a, lng = r < a ? a : r;
    for (int i = 0; i < 2; i++) {
        int nn = i == 0 ? shrt : lng;
        if (nn == BIG || (i == 1 && lng == shrt)) continue;
        if ((size_t)nn > n) { if (fin) continue; v.len = V_WAIT; return v; }
        if (!crc_ok(b, (size_t)nn)) continue;
        if (i == 0 && lng != BIG && lng != shrt) {
            size_t end = (size_t)lng < n ? (size_t)lng : n;
            if (all_zero(b, (size_t)nn, end)) {
                if ((size_t)lng > n) {
                    if (!fin) { v.len = V_WAIT; return v; }
                } else {  // both readings check: the response when one is awaited
                    int retry = expected && is_retry(b, a, req);
                    if (expected && !retry) { v.len = a; v.kind = answer_kind(fc); }
                    else { v.len = r; v.kind = K_REQ; }
                    v.ambiguous = 1; v.weak = WEAK(v.len);
                    return v;
                }
            }
        }
        int is_req = r == nn, is_resp = a == nn;
        v.kind = is_req && is_resp && expected ? answer_kind(fc) : is_req ? K_REQ : answer_kind(fc);
        v.len = nn; v.ambiguous = is_req && is_resp; v.weak = WEAK(nn);
        return v;
    }
#undef WEAK
    if (!fin && (req == NEED || resp == NEED)) v.len = V_WAIT;
    return v;
}

// ---- sorting junk out (busnoop's classify) ------------------------------------------------
enum { B_BAD, B_TRUNC, B_GARB };
typedef struct { size_t start, len; int what; } Piece;
static Piece pieces[1200]; static int npieces;
static inline void piece(size_t s, size_t l, int what) { pieces[npieces].start = s; pieces[npieces].len = l; pieces[npieces].what = what; npieces++; }

// The lengths (>= 4) the readings of b give: lens[0..2] (-1 none); *need: a length field lies beyond b.
static inline void lengths(const u8 *b, size_t n, int lens[2], int *need) {
    *need = 0;
    for (int d = 0; d < 2; d++) {
        int l = frame_len(b, n, d);
        lens[d] = l >= 4 ? l : -1;
        if (l == NEED) *need = 1;
    }
}

static void cut_or_garbage(const u8 *j, size_t n, int at_end) {
    if (n == 0) return;
    size_t least = at_end ? 2 : 4;
    for (size_t r = 0; r <= (n - 1 < 3 ? n - 1 : 3); r++) {
        size_t left = n - r;
        if (left < least) break;
        int lens[2], need;
        lengths(j + r, left, lens, &need);
        int cut = need || (lens[0] >= 0 && (size_t)lens[0] > left) || (lens[1] >= 0 && (size_t)lens[1] > left);
        if (cut) {
            if (r > 0) piece(0, r, B_GARB);
            piece(r, left, B_TRUNC);
            return;
        }
    }
    piece(0, n, B_GARB);
}

static int okl[1200], oks[1200], strays[1200];  // okl < 0: no run from here
static void classify(const u8 *j, size_t n, int at_end) {
    okl[n] = 0; oks[n] = 0; strays[n] = 0;
    for (size_t i = n; i-- > 0;) {
        int lens[2], need, best = -1, bl = 0, bs = 0;
        lengths(j + i, n - i, lens, &need);
        for (int d = 0; d < 2; d++) {
            if (lens[d] < 0) continue;
            for (int s = 0; s <= 3; s++) {
                size_t next = i + (size_t)lens[d] + (size_t)s;
                if (next <= n && okl[next] >= 0) {
                    int cost = s + strays[next];
                    if (best < 0 || cost < best) { best = cost; bl = lens[d]; bs = s; }
                }
            }
        }
        okl[i] = best < 0 ? -1 : bl; oks[i] = bs; strays[i] = best < 0 ? 0 : best;
    }
    size_t run = n;
    size_t key = (size_t)-1;
    for (size_t i = 0; i < n; i++)
        if (okl[i] >= 0 && i + (size_t)strays[i] < key) { key = i + (size_t)strays[i]; run = i; }
    cut_or_garbage(j, run, at_end && run == n);
    size_t i = run;
    while (i < n && okl[i] >= 0) {
        size_t l = (size_t)okl[i], s = (size_t)oks[i];
        piece(i, l, B_BAD);
        if (s) piece(i + l, s, B_GARB);
        i += l + s;
    }
}

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, as text
static char note[1024]; static char *nt;         // the Note being built
static inline void note_sep(void) { if (nt != note) { *nt++ = ';'; *nt++ = ' '; } }

static inline char *row_start(uint64_t offset) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start;
    *w++ = '\t';
    w = put_u64(w, offset * 11000000u / 19200u / 1000u);  // 8E1 at 19200 baud
    *w++ = '\t';
    return w;
}
static inline char *row_end(char *w) {  // Unit, Resp ms (empty), Note
    *w++ = '\t'; *w++ = '\t'; *w++ = '\t';
    size_t n = (size_t)(nt - note); memcpy(w, note, n); w += n;
    *w++ = '\n';
    return w;
}

// pairing (busnoop's modbus/pairing.rs; no times)
typedef struct { int on; u8 slave, fc; u16 start, count; int spoiled; unsigned sends; } Pending;
static Pending pend;
static u8 lastpdu[256]; static size_t lastlen; static int last_answered = 1;

static inline unsigned word(const u8 *b, size_t n, size_t i) { return i + 1 < n ? (unsigned)(b[i] << 8 | b[i + 1]) : 0; }

static void timeout_row(const Pending *p, const char *why, uint64_t offset) {
    char *w = row_start(offset);
    w = put_u64(w, p->slave);
    w = PUTS(w, "\t\tTimeout\t"); w = put_0x(w, p->fc); *w++ = '\t'; w = put_str(w, NAME[p->fc & 0x7F]); *w++ = '\t';
    switch (p->fc) {
    case 1: case 2: case 3: case 4: case 15: case 16: case 23:
        w = PUTS(w, "start="); w = put_u64(w, p->start); w = PUTS(w, " count="); w = put_u64(w, p->count);
    }
    *w++ = '\t';  // Value
    nt = note; nt = put_str(nt, why);
    o = row_end(w);
}

// A number of the Data cell: a blank before all but the first; the first is the Value.
static char *v0, *v1;
static inline char *num_start(char *w, char *data) { if (w != data) *w++ = ' '; return w; }
static inline char *num_end(char *w, char *at) { if (!v0) { v0 = at; v1 = w; } return w; }
static inline char *named(char *w, char *data, const char *name, unsigned v) {
    w = num_start(w, data); w = put_str(w, name); *w++ = '='; char *a = w; w = put_u64(w, v); return num_end(w, a);
}
// `R<addr>=v` (letter 'R' or 'C'), or `R+<i>=v` without an address (unpaired)
static inline char *reg(char *w, char *data, char letter, int has, uint32_t addr, uint32_t i, unsigned v) {
    w = num_start(w, data); *w++ = letter;
    if (has) w = put_u64(w, addr); else { *w++ = '+'; w = put_u64(w, i); }
    *w++ = '='; char *a = w; w = put_u64(w, v); return num_end(w, a);
}
static inline void count_note(unsigned count, unsigned max) {
    if (count == 0 || count > max) {
        note_sep(); nt = PUTS(nt, "count "); nt = put_u64(nt, count); nt = PUTS(nt, " outside 1-"); nt = put_u64(nt, max);
    }
}
static inline void byte_count_note(const u8 *d, size_t dn, size_t at, unsigned want) {
    if (at < dn && d[at] != want) {
        note_sep(); nt = PUTS(nt, "byte count "); nt = put_u64(nt, d[at]); nt = PUTS(nt, ", the count needs "); nt = put_u64(nt, want);
    }
}
static inline char *coil_value(char *w, char *data, unsigned addr, unsigned v) {
    if (v == 0xFF00 || v == 0) return reg(w, data, 'C', 1, addr, 0, v != 0);
    note_sep(); nt = PUTS(nt, "coil value "); nt = put_0x16(nt, v); nt = PUTS(nt, " is neither 0xFF00 (on) nor 0x0000 (off)");
    return w;
}
static inline char *coils(char *w, char *data, const u8 *bytes, size_t nb, int has, unsigned start, size_t count) {
    size_t m = count < nb * 8 ? count : nb * 8;
    for (size_t i = 0; i < m; i++) w = reg(w, data, 'C', has, start + (uint32_t)i, (uint32_t)i, (bytes[i / 8] >> (i % 8)) & 1);
    return w;
}
static inline char *registers(char *w, char *data, const u8 *bytes, size_t nb, int has, unsigned start) {
    for (size_t i = 0; i + 1 < nb; i += 2)
        w = reg(w, data, 'R', has, start + (uint32_t)(i / 2), (uint32_t)(i / 2), (unsigned)(bytes[i] << 8 | bytes[i + 1]));
    return w;
}
static inline char *start_count(char *w, char *data, const u8 *d, size_t dn, unsigned *s, unsigned *c) {
    *s = word(d, dn, 0); *c = word(d, dn, 2);
    w = named(w, data, "start", *s); return named(w, data, "count", *c);
}

// A checked frame f[0..len) (CRC included) at `offset`.
static void frame_row(const u8 *f, size_t len, int kind, int ambiguous, uint64_t offset) {
    const u8 *pdu = f; size_t pn = len - 2;
    unsigned slave = f[0], fc = f[1];
    const u8 *d = pdu + 2; size_t dn = pn - 2;
    nt = note; v0 = v1 = NULL;
    int paired = 0; unsigned rstart = 0, rcount = 0;
    const char *type;
    if (kind == K_REQ) {
        unsigned s = 0, c = 0;
        switch (fc) {
        case 1: case 2: case 3: case 4: case 15: case 16: case 23: s = word(pdu, pn, 2); c = word(pdu, pn, 4); break;
        case 5: case 6: case 22: s = word(pdu, pn, 2); c = 1; break;
        case 8: case 24: s = word(pdu, pn, 2); break;
        case 43: s = pn > 4 ? pdu[4] : 0; break;
        }
        int same = !last_answered && lastlen == pn && memcmp(lastpdu, pdu, pn) == 0;
        unsigned sends = 1, retry = 0;
        if (pend.on) {
            if (!pend.spoiled) timeout_row(&pend, same ? "no answer before the retry" : "no answer before the next request", offset);
            if (same) { retry = pend.sends; sends = pend.sends + 1; }
            pend.on = 0;
        }
        memcpy(lastpdu, pdu, pn); lastlen = pn;
        last_answered = slave == 0;
        if (slave != 0) { pend.on = 1; pend.slave = (u8)slave; pend.fc = (u8)fc; pend.start = (u16)s; pend.count = (u16)c; pend.spoiled = 0; pend.sends = sends; }
        nt = note;
        if (slave == 0) { nt = PUTS(nt, "broadcast"); }
        if (retry) { note_sep(); nt = PUTS(nt, "retry "); nt = put_u64(nt, retry); }
        type = "Request";
    } else {
        if (!pend.on) { nt = PUTS(nt, "no request seen"); }
        else if (pend.slave != slave || pend.fc != (fc & 0x7F)) {
            nt = PUTS(nt, "no request for it (slave "); nt = put_u64(nt, pend.slave); nt = PUTS(nt, " function ");
            nt = put_0x(nt, pend.fc); nt = PUTS(nt, " waits)");
        } else {
            paired = 1; rstart = pend.start; rcount = pend.count;
            pend.on = 0; last_answered = 1;
        }
        type = kind == K_EXC ? "Exception" : "Response";
    }
    char *w = row_start(offset);
    w = put_u64(w, slave); *w++ = '\t'; *w++ = '\t';
    w = put_str(w, type); *w++ = '\t';
    w = put_0x(w, fc & 0x7F); *w++ = '\t'; w = put_str(w, NAME[fc & 0x7F]); *w++ = '\t';
    char *data = w;
    if (kind == K_EXC) {
        unsigned code = dn ? d[0] : 0;
        const char *en = code < 12 ? EXC[code] : "";
        w = en[0] ? put_str(w, en) : PUTS(w, "unknown exception");
        *w++ = ' '; *w++ = '(';
        v0 = w; w = put_u64(w, code); v1 = w;
        *w++ = ')';
    } else if (kind == K_REQ) {
        unsigned s, c;
        switch (fc) {
        case 1: case 2: case 3: case 4:
            w = start_count(w, data, d, dn, &s, &c); count_note(c, fc <= 2 ? 2000 : 125); break;
        case 5:
            s = word(d, dn, 0); w = named(w, data, "start", s); w = named(w, data, "count", 1);
            w = coil_value(w, data, s, word(d, dn, 2)); break;
        case 6:
            s = word(d, dn, 0); w = named(w, data, "start", s); w = named(w, data, "count", 1);
            w = registers(w, data, d + 2, dn > 2 ? (dn < 4 ? dn - 2 : 2) : 0, 1, s); break;
        case 15:
            w = start_count(w, data, d, dn, &s, &c); count_note(c, 1968);
            byte_count_note(d, dn, 4, (c + 7) / 8);
            w = coils(w, data, d + 5, dn > 5 ? dn - 5 : 0, 1, s, c); break;
        case 16:
            w = start_count(w, data, d, dn, &s, &c); count_note(c, 123);
            byte_count_note(d, dn, 4, 2 * c);
            w = registers(w, data, d + 5, dn > 5 ? dn - 5 : 0, 1, s); break;
        }
    } else {
        unsigned s, c;
        switch (fc) {
        case 1: case 2: {
            size_t nb = dn > 1 ? dn - 1 : 0;
            size_t count = nb * 8;
            if (paired) { byte_count_note(d, dn, 0, (rcount + 7) / 8); count = rcount; }
            w = coils(w, data, d + 1, nb, paired, rstart, count); break;
        }
        case 3: case 4: {
            size_t nb = dn > 1 ? dn - 1 : 0;
            if (paired && nb != 2 * rcount) byte_count_note(d, dn, 0, 2 * rcount);
            w = registers(w, data, d + 1, nb, paired, rstart); break;
        }
        case 5: w = coil_value(w, data, word(d, dn, 0), word(d, dn, 2)); break;
        case 6: w = registers(w, data, d + 2, dn > 2 ? (dn < 4 ? dn - 2 : 2) : 0, 1, word(d, dn, 0)); break;
        case 15: case 16: w = start_count(w, data, d, dn, &s, &c); break;
        }
    }
    *w++ = '\t';
    if (v0) { size_t vn = (size_t)(v1 - v0); memmove(w, v0, vn); w += vn; }
    if (kind == K_EXC) { note_sep(); nt = PUTS(nt, "function "); nt = put_0x(nt, fc); }
    if (ambiguous && !paired && kind != K_REQ) { note_sep(); nt = PUTS(nt, "read as a response by its place after the request"); }
    o = row_end(w);
}

// Bytes that are no checked frame.
static void junk_row(const u8 *b, size_t n, int what, uint64_t offset) {
    int head = what != B_GARB && n >= 2 && b[0] <= 247 && is_public(b[1] & 0x7F);
    char *w = row_start(offset);
    nt = note;
    if (head) { w = put_u64(w, b[0]); *w++ = '\t'; *w++ = '\t'; }
    else { *w++ = '\t'; *w++ = '\t'; }
    if (what == B_GARB) {
        w = PUTS(w, "Garbage\t\t\t");
        nt = put_u64(nt, n);
        nt = n == 1 ? PUTS(nt, " byte outside any frame") : PUTS(nt, " bytes outside any frame");
    } else {
        w = what == B_BAD ? PUTS(w, "BadCRC\t") : PUTS(w, "Truncated\t");
        if (head) { w = put_0x(w, b[1] & 0x7F); *w++ = '\t'; w = put_str(w, NAME[b[1] & 0x7F]); *w++ = '\t'; }
        else { *w++ = '\t'; *w++ = '\t'; }
        if (what == B_BAD) {
            if (n >= 2) {
                nt = PUTS(nt, "CRC "); nt = put_0x16(nt, (unsigned)(b[n - 2] | b[n - 1] << 8));
                nt = PUTS(nt, ", computed "); nt = put_0x16(nt, crc16(b, n - 2));
            }
        } else { nt = PUTS(nt, "cut after "); nt = put_u64(nt, n); nt = PUTS(nt, " bytes"); }
    }
    w = put_hex_bytes(w, b, n);
    *w++ = '\t';  // Value
    o = row_end(w);
    // a broken frame from the slave asked may have been its answer
    if (head && pend.on && pend.slave == b[0]) pend.spoiled = 1;
}

// ---- the framer's loop --------------------------------------------------------------------
static size_t blen, head, scan;  // ibuf[head..blen) not given out; ibuf[head..head+scan) junk so far
static uint64_t base;            // stream offset of ibuf[0]
static int answer_seen; static size_t seen_upto;

static void give_pieces(void) {
    for (int k = 0; k < npieces; k++) {
        size_t start = pieces[k].start, len = pieces[k].len;
        int what = pieces[k].what;
        size_t step = what == B_GARB ? 64 : (len ? len : 1);
        for (size_t at = start; at < start + len; at += step) {
            size_t m = start + len - at < step ? start + len - at : step;
            const u8 *b = ibuf + head + at;
            junk_row(b, m, what, base + head + at);
            if (what != B_GARB && expect.on && m >= 2 && b[0] == expect.addr && (b[1] == expect.fc || b[1] == (expect.fc | 0x80)))
                expect.on = 0;
        }
    }
}

static void junk(size_t n, int at_end) {
    npieces = 0;
    classify(ibuf + head, n, at_end);
    give_pieces();
    head += n; scan = 0; answer_seen = 0; seen_upto = 0;
}

static void run(int fin) {
    for (;;) {
        size_t pending = blen - head, at = scan;
        if (at >= pending) { if (fin && at > 0) junk(at, 1); return; }
        if (!answer_seen && at >= 2 && expect.on) {
            size_t from = head + (seen_upto ? seen_upto - 1 : 0);
            for (size_t i = from; i + 1 < head + at; i++)
                if (ibuf[i] == expect.addr && (ibuf[i + 1] == expect.fc || ibuf[i + 1] == (expect.fc | 0x80))) { answer_seen = 1; break; }
        }
        seen_upto = at;
        const Expect *w = !answer_seen && expect.on ? &expect : NULL;
        const u8 *b = ibuf + head + at;
        size_t n = pending - at;
        Verdict v = judge(b, n, fin, at == 0, w);
        if (v.len >= 0 && v.weak) {  // a frame within the limits that starts inside it wins
            for (int r = 1; r < v.len; r++) {
                Verdict v2 = judge(b + r, n - (size_t)r, fin, 0, w);
                if (v2.len >= 0 && !v2.weak) { v.len = V_NOT; break; }
                if (v2.len == V_WAIT) { v.len = V_WAIT; break; }
            }
        }
        if (v.len == V_WAIT) return;
        if (v.len == V_NOT) {
            if (++scan >= 512) {  // given up as garbage, 64 bytes at a time
                npieces = 0; piece(0, 64, B_GARB); give_pieces();
                head += 64; scan -= 64; answer_seen = 0; seen_upto = 0;
            }
            continue;
        }
        if (at > 0) junk(at, 0);
        answer_seen = 0; seen_upto = 0;
        const u8 *f = ibuf + head;
        size_t len = (size_t)v.len;
        frame_row(f, len, v.kind, v.ambiguous, base + head);
        if (v.kind == K_REQ && f[0] != 0) {
            expect.on = 1; expect.addr = f[0]; expect.fc = f[1]; expect.len = response_len(f, len);
            memcpy(wreq, f, len); wreq_len = len;
        } else { expect.on = 0; wreq_len = 0; }
        head += len;
    }
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: modbus_ref FILE\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    crc_init(); names_init();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tResp ms\tNote\n");
    for (;;) {
        if (head > 0) {  // keep what is not given out at the front
            memmove(ibuf, ibuf + head, blen - head);
            base += head; blen -= head; head = 0;
        }
        ssize_t r = read(fd, ibuf + blen, RD);
        if (r < 0) return 3;
        if (r == 0) break;
        blen += (size_t)r;
        run(0);
    }
    run(1);
    flush_out();
    return 0;
}
