// sab_ref.c: a hand-tuned reference modm SAB2 decoder, the physical limit of
// `busnoop sab FILE --framing hdlc -f tsv`.
//
// Does the real job, in one pass, no intermediate row: reads the capture in 256 KiB chunks
// (as busnoop), reassembles SAB2 frames (every 0x7E ends a frame and opens the next, 0x7D byte
// stuffing, frames that straddle two reads carried over), checks the CRC-16/MODBUS, decodes
// header (flags, 6-bit address), command and payload (hex plus the little-endian integer
// reading of 1, 2 and 4 bytes, the Value column), pairs every response with the open request
// as modm's master does (response time from the request's first byte to the response's last,
// in nanoseconds reconstructed from the byte position at 115200 baud 8N1; a `Timeout` row when
// the next request comes first or the 10 ms deadline passes; late and repeated responses),
// names the NACK codes, and writes busnoop's TSV table (14 columns: Counter, Millis, ID,
// Device, Type, Sensor #, Sensor, Data, Value, Unit, Addr, Resp ms, Framing, Note) through a
// 64 KiB output buffer. For a capture of requests, ACKs, NACKs, missing answers and bad-CRC
// answers the output is byte-identical to busnoop's with the framing forced (`--framing hdlc`:
// detection would also read every byte with the SAB v1 reassembler). Not covered (busnoop has
// them): SAB v1 framing, garbage, runts, aborts, overlong frames, unusual escapes, the input
// ending inside a frame or a request, responses after the next request; they are left out of
// the bench's capture. `sab1_ref.c` includes this file with SAB_V1 defined (the Framing
// column, the framing note, the CRC-8 note) and brings its own reading loop, `reassemble`.
//
//   cc -O2 -march=x86-64-v2 -o sab_ref sab_ref.c
//   ./sab_ref FILE > out.tsv
//   "$BIN" sab FILE --framing hdlc -f tsv --no-config | cmp - out.tsv
//   cc -O2 -march=x86-64-v2 -DDECODE_ONLY -o sab_decode sab_ref.c   # the same without the text
//
// SPDX-License-Identifier: MIT OR Apache-2.0
#include "ref_io.h"

#define CARRY_MAX (64 * 1024)
static unsigned char ibuf[CARRY_MAX + RD + 64];

// ---- text helpers -------------------------------------------------------------------------

#include "ref_text.h"
// µs as ms with three decimals (busnoop's push_ms: 0.868, 12.500)
static inline char *put_ms3(char *w, uint64_t micros) {
    w = put_u64(w, micros / 1000);
    unsigned f = (unsigned)(micros % 1000);
    w[0] = '.'; w[1] = (char)('0' + f / 100); w[2] = (char)('0' + f / 10 % 10); w[3] = (char)('0' + f % 10);
    return w + 4;
}
static inline char *put_0x16(char *w, unsigned v) { w = put_0x(w, v >> 8); *w++ = HEXU[(v >> 4) & 15]; *w++ = HEXU[v & 15]; return w; }

// ---- tables -------------------------------------------------------------------------------
static uint16_t CRC16[256];
// "ID\tDevice\tTYPE\t0xCC\tSensor\t" for a header and a command: built per row from these
static char ADDR_DEC[64][4];
static const char TYPES[6][8] = {"Request", "Reserved", "NACK", "ACK", "Timeout", "BadCRC"};

static void init_tables(void) {
    for (unsigned i = 0; i < 256; i++) {
        unsigned c = i;
        for (int k = 0; k < 8; k++) c = c & 1 ? (c >> 1) ^ 0xA001 : c >> 1;
        CRC16[i] = (uint16_t)c;
    }
    for (int a = 0; a < 64; a++) snprintf(ADDR_DEC[a], 4, "%d", a);
}
static inline unsigned crc16(const unsigned char *b, size_t n) {
    unsigned c = 0xFFFF;
    for (size_t i = 0; i < n; i++) c = (c >> 8) ^ CRC16[(c ^ b[i]) & 0xFF];
    return c;
}

// ---- pairing (busnoop's sab::pairing, the cases a master that asks one at a time makes) ----
#define TIMEOUT_NS 10000000ull  // --timeout-ms 10
typedef struct { int open; unsigned addr, cmd; uint64_t time; uint32_t answers; int reported, late; } Open;
static Open op;

// ---- rows ---------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;  // the Counter, kept as text (digits ctr[start..32))
static int framing_note = 1;                     // said on the first row
#ifdef SAB_V1
#define FRAMING_COL "sync"
#define FRAMING_NOTE "framing sync: SAB v1 framing (0x54 SYNC, LENGTH, CRC-8/MAXIM-DOW), forced by --framing"
#else
#define FRAMING_COL "hdlc"
#define FRAMING_NOTE "framing hdlc: SAB2 framing (0x7E flags, byte stuffing, CRC-16/MODBUS), forced by --framing"
#endif

static inline char *row_start(uint64_t ns) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start; // counters below 10^16
    *w++ = '\t';
    w = put_u64(w, ns / 1000000);
    *w++ = '\t';
    return w;
}
// ID, Device (empty), Type, Sensor #, Sensor (empty)
static inline char *ident(char *w, unsigned addr, const char *type, size_t tlen, unsigned cmd) {
    const char *a = ADDR_DEC[addr];
    *w++ = a[0]; if (a[1]) { *w++ = a[1]; }
    *w++ = '\t'; *w++ = '\t';
    memcpy(w, type, 8); w += tlen; *w++ = '\t';
    w = put_0x(w, cmd); *w++ = '\t'; *w++ = '\t';
    return w;
}
static inline char *note_start(char *w, int *notes) {
    if ((*notes)++) { *w++ = ';'; *w++ = ' '; }
    else if (framing_note) { framing_note = 0; w = PUTS(w, FRAMING_NOTE); *w++ = ';'; *w++ = ' '; }
    return w;
}
static inline char *row_end(char *w, int notes) {
    if (!notes && framing_note) { framing_note = 0; w = PUTS(w, FRAMING_NOTE); }
    *w++ = '\n';
    return w;
}
// Data: payload hex, and the reading " (u)" / " (u, s)" of 1, 2 or 4 bytes; Value: u (when
// `value`), or empty
static inline char *data_value(char *w, const unsigned char *p, size_t n, int value) {
    if (n == 0) { *w++ = '\t'; *w++ = '\t'; return w; }
    w = put_hex_bytes(w, p, n);
    uint32_t u; int32_t s;
    if (n == 1) { u = p[0]; s = (int8_t)p[0]; }
    else if (n == 2) { u = (uint32_t)p[0] | (uint32_t)p[1] << 8; s = (int16_t)u; }
    else if (n == 4) { memcpy(&u, p, 4); s = (int32_t)u; }
    else { *w++ = '\t'; *w++ = '\t'; return w; }
    *w++ = ' '; *w++ = '(';
    char *num = w;
    w = put_u64(w, u);
    size_t len = (size_t)(w - num);
    if (s < 0) { *w++ = ','; *w++ = ' '; w = put_i64(w, s); }
    *w++ = ')'; *w++ = '\t';
    if (value) { memmove(w, num, 16); w += len; }
    *w++ = '\t';
    return w;
}

static void timeout_row(const Open *r, uint64_t at, int next_request, uint64_t waited) {
    char *w = row_start(at);
    w = ident(w, r->addr, TYPES[4], 7, r->cmd);
    w = PUTS(w, "\t\t\t");  // Data, Value, Unit
    w = put_0x(w, r->addr);
    w = PUTS(w, "\t\t" FRAMING_COL "\t");
    int notes = 0;
    w = note_start(w, &notes);
    if (next_request) {
        w = PUTS(w, "no response before the next request (after ");
        w = put_ms3(w, waited / 1000);
        w = PUTS(w, " ms)");
    } else w = PUTS(w, "no response within 10 ms");
    o = row_end(w, notes);
}

// A request opens; the one open before, still due, gets its Timeout row.
static inline void request(unsigned addr, unsigned cmd, uint64_t start) {
    if (op.open && !op.reported && (op.answers == 0 || op.late)) {
        uint64_t deadline = op.time + TIMEOUT_NS;
        if (op.answers == 0) timeout_row(&op, deadline < start ? deadline : start, 1, start - op.time);
        else timeout_row(&op, deadline < start ? deadline : start, 0, TIMEOUT_NS);
    }
    op.open = 1; op.addr = addr; op.cmd = cmd; op.time = start; op.answers = 0; op.reported = 0; op.late = 0;
}

static const char *NACK_NOTE[4] = {
    "NACK GENERAL_ERROR (general error)",
    "NACK NO_ACTION (no action registered for the command)",
    "NACK WRONG_PAYLOAD_LENGTH (request payload length differs from what the action expects)",
    "NACK NO_RESPONSE (the action returned without answering)",
};

// A valid frame: body = header, command, payload (CRC removed)
static inline void frame(const unsigned char *body, size_t n, uint64_t start, uint64_t end) {
    unsigned hdr = body[0], cmd = body[1], flags = hdr >> 6, addr = hdr & 0x3F;
    const unsigned char *p = body + 2;
    size_t plen = n - 2;
    int paired = 0, late = 0, repeat = 0, unpaired = 0, waiting = 0;
    uint64_t micros = 0;
    if (flags & 2) {
        if (op.open && op.addr == addr && op.cmd == cmd) {
            int expired = op.reported;
            op.answers++;
            int overdue = end > op.time + TIMEOUT_NS;
            if (overdue && op.answers == 1 && !op.reported) op.late = 1;
            micros = (end - op.time) / 1000;
            paired = 1; late = expired || overdue; repeat = op.answers > 1;
        } else { unpaired = 1; waiting = op.open && op.answers == 0 && !op.reported; }
    } else request(addr, cmd, start);
#ifdef DECODE_ONLY
    extern uint64_t sink_sum; sink_sum += hdr + cmd + plen + micros + (uint64_t)paired; return;
#endif
    char *w = row_start(start);
    static const unsigned char TLEN[4] = {7, 8, 4, 3};
    w = ident(w, addr, TYPES[flags], TLEN[flags], cmd);
    w = data_value(w, p, plen, flags != 2 && flags != 1);
    *w++ = '\t';  // Unit
    w = put_0x(w, addr); *w++ = '\t';
    if (paired) w = put_ms3(w, micros);
    w = PUTS(w, "\t" FRAMING_COL "\t");
    int notes = 0;
    if (flags == 1) { w = note_start(w, &notes); w = PUTS(w, "reserved flag bits 01 (never sent by modm; handled as a request)"); }
    if (flags == 2) {
        w = note_start(w, &notes);
        if (plen == 0) w = PUTS(w, "NACK without an error code (modm sends 1 byte)");
        else {
            unsigned code = p[0];
            if (code < 4) { const char *s = NACK_NOTE[code]; size_t k = strlen(s); memcpy(w, s, k); w += k; }
            else if (code < 0x20) { w = PUTS(w, "NACK reserved "); w = put_0x(w, code); w = PUTS(w, " (system code not defined by modm)"); }
            else { w = PUTS(w, "NACK user "); w = put_0x(w, code); w = PUTS(w, " (user-defined error)"); }
            if (plen > 1) { w = PUTS(w, "; "); w = put_u64(w, plen); w = PUTS(w, " payload bytes (modm sends 1)"); }
        }
    }
    if (repeat) { w = note_start(w, &notes); w = PUTS(w, "repeated response to the same request (two slaves on one address?)"); }
    if (paired && late) { w = note_start(w, &notes); w = PUTS(w, "late: after the master's 10 ms timeout"); }
    if (unpaired) {
        w = note_start(w, &notes); w = PUTS(w, "no matching request");
        if (waiting) { w = PUTS(w, " (the master waits for address "); w = put_u64(w, op.addr); w = PUTS(w, " command "); w = put_0x(w, op.cmd); *w++ = ')'; }
    }
    if (plen > 32) {
        w = note_start(w, &notes); w = PUTS(w, "overlong: "); w = put_u64(w, plen);
        w = PUTS(w, "-byte payload, more than --max-payload 32 (a modm receiver with N = 32 drops it)");
    }
    o = row_end(w, notes);
}

// A bad frame: body = header, command, payload (CRC removed); `with_sync`: the CRC matches when
// SYNC is covered too (SAB v1)
static void bad_crc(const unsigned char *body, size_t n, unsigned received, unsigned computed, int with_sync, uint64_t start) {
#ifdef DECODE_ONLY
    extern uint64_t sink_sum; sink_sum += received + computed; return;
#endif
    unsigned hdr = body[0], flags = hdr >> 6, addr = hdr & 0x3F;
    char *w = row_start(start);
    w = ident(w, addr, TYPES[5], 6, body[1]);
    w = data_value(w, body + 2, n - 2, 0);
    *w++ = '\t';
    w = put_0x(w, addr);
    w = PUTS(w, "\t\t" FRAMING_COL "\t");
    int notes = 0;
    w = note_start(w, &notes);
#ifdef SAB_V1
    w = PUTS(w, "CRC-8 "); w = put_0x(w, received); w = PUTS(w, ", expected "); w = put_0x(w, computed);
#else
    w = PUTS(w, "CRC-16 "); w = put_0x16(w, received); w = PUTS(w, ", expected "); w = put_0x16(w, computed);
#endif
    w = PUTS(w, "; read as ");
    static const unsigned char TLEN[4] = {7, 8, 4, 3};
    memcpy(w, TYPES[flags], 8); w += TLEN[flags];
    if (with_sync) w = PUTS(w, "; the CRC matches if SYNC is covered too (not modm's rule)");
    o = row_end(w, notes);
}

// ---- reassembly ---------------------------------------------------------------------------
uint64_t sink_sum;
static inline uint64_t ns_at(uint64_t pos) { return pos * 10000000000ull / 115200; }

// Before every event starting at `start`: a request's deadline that passed, its Timeout row
static inline void deadline(uint64_t start) {
    if (op.open && !op.reported && (op.answers == 0 || op.late) && start > op.time + TIMEOUT_NS) {
        op.reported = 1;
        timeout_row(&op, op.time + TIMEOUT_NS, 0, TIMEOUT_NS);
    }
}

#ifdef SAB_V1
static void reassemble(int fd);  // sab1_ref.c: the SAB v1 framing
#else
// The run between two flags (none in it): [open, close) of the stream, `run` its wire bytes
static inline void run_between(const unsigned char *run, size_t len, uint64_t open_pos) {
    if (len == 0) return;  // back-to-back flags
    unsigned char tmp[300];
    const unsigned char *body = run;
    size_t n = len;
    const unsigned char *e = memchr(run, 0x7D, len);
    if (e) {  // unstuff
        size_t k = (size_t)(e - run);
        if (len > 260 * 2) { fprintf(stderr, "overlong run: not covered\n"); exit(4); }
        memcpy(tmp, run, k);
        for (size_t i = k; i < len; i++) {
            unsigned c = run[i];
            if (c == 0x7D) {
                if (++i == len || (run[i] != 0x5E && run[i] != 0x5D)) { fprintf(stderr, "abort/unusual escape: not covered\n"); exit(4); }
                c = run[i] ^ 0x20;
            }
            tmp[k++] = (unsigned char)c;
        }
        body = tmp; n = k;
    }
    if (n < 4 || n > 259) { fprintf(stderr, "runt/overlong frame: not covered\n"); exit(4); }
    uint64_t start = ns_at(open_pos);
    deadline(start);
    unsigned received = (unsigned)body[n - 2] | (unsigned)body[n - 1] << 8, computed = crc16(body, n - 2);
    if (received == computed) frame(body, n - 2, start, ns_at(open_pos + len + 2));
    else bad_crc(body, n - 2, received, computed, 0, start);
}

// Reads the capture and hands every run between two flags to run_between
static void reassemble(int fd) {
    size_t carry = 0;     // bytes from the last opening flag on, kept for the next read
    uint64_t base = 0;    // stream position of ibuf[0]
    int seen_flag = 0;
    for (;;) {
        ssize_t r = read(fd, ibuf + carry, RD);
        if (r < 0) exit(3);
        if (r == 0) break;
        size_t n = carry + (size_t)r;
        const unsigned char *b = ibuf, *end = ibuf + n;
        const unsigned char *f = b;
        if (!seen_flag) {
            f = memchr(b, 0x7E, n);
            if (f != b) { fprintf(stderr, "garbage before the first flag: not covered\n"); exit(4); }
            seen_flag = 1;
        }
        // f points at an opening flag
        for (;;) {
            const unsigned char *g = memchr(f + 1, 0x7E, (size_t)(end - f - 1));
            if (!g) break;
            run_between(f + 1, (size_t)(g - f - 1), base + (uint64_t)(f - b));
            f = g;
        }
        carry = (size_t)(end - f);
        if (carry > CARRY_MAX) { fprintf(stderr, "run too long: not covered\n"); exit(4); }
        memmove(ibuf, f, carry);
        base += (uint64_t)(f - b);
    }
    if (carry > 1) { fprintf(stderr, "input ends inside a frame: not covered\n"); exit(4); }
}
#endif  // SAB_V1

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: %s FILE\n", argv[0]); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    init_tables();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tUnit\tAddr\tResp ms\tFraming\tNote\n");
    reassemble(fd);
    // the end of the capture: a request still waiting is not covered
    if (op.open && op.answers == 0 && !op.reported) { fprintf(stderr, "a request open at the end: not covered\n"); return 4; }
#ifdef DECODE_ONLY
    fprintf(stderr, "sum %llu\n", (unsigned long long)sink_sum);
    o = obuf;
#endif
    flush_out();
    return 0;
}
