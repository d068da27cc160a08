// ether_ref.c: a hand-tuned reference Ether-S-Bus decoder, the physical limit of
// `busnoop sbus FILE.pcap -f tsv` for read/write-register traffic.
//
// Does the real job, in one pass, no intermediate row: reads a classic pcap (Ethernet link type,
// microsecond or nanosecond stamps, little-endian) in 256 KiB chunks, takes the UDP datagrams
// to or from port 5050 out of Ethernet II/IPv4 (fixed offsets; other packets are skipped),
// checks the Ether-S-Bus header (length, version, protocol type, attribute) and its CRC-16/XMODEM
// (slice-by-8 tables), pairs each answer with its conversation's open request by sequence number
// (a direct-mapped table of conversations keyed by both ends), and writes busnoop's TSV table
// (12 columns: Counter, Millis, ID, Device, Type, Sensor #, Sensor, Data, Value, Resp ms, Seq,
// Note) through a 64 KiB buffer: read-register requests (range R57..R63), their responses (one
// signed value per register), write-register requests (values) and their ACK/NAK, the response
// time to a tenth of a millisecond. For a generated capture of the covered commands the output is
// byte-identical to busnoop's. Not covered (busnoop has them): other
// commands and media, broadcasts, retries, timeouts by deadline, statistics, VLAN/IPv6/other link
// layers, pcapng: a datagram of another command gets a generic row (hex), so its cells differ
// from busnoop's, not its cost.
//
//   cc -O2 -march=x86-64-v2 -o ether_ref ether_ref.c
//   ./ether_ref FILE.pcap > out.tsv
//   "$BIN" sbus FILE.pcap -f tsv --no-config | cmp - out.tsv   # busnoop: $BIN (built from ${PROJECT:-.})
#define OBUF_EXTRA 8192
#include "ref_io.h"

#define MAXREC (256 * 1024)
static unsigned char ibuf[RD + MAXREC + 64];

#include "ref_text.h"
#include "sbus_crc.h"

// ---- conversations --------------------------------------------------------------------------
typedef struct {
    uint64_t client, server;  // address << 16 | port
    int used, open, have_seq;
    uint16_t seq, last_seq;   // the open request's, the last request's
    uint8_t station, cmd, count;
    uint16_t addr;
    uint64_t t;
} Conv;
#define NCONV 1024
static Conv conv[NCONV];
static Conv *conv_get(uint64_t client, uint64_t server) {
    uint64_t h = (client * 0x9E3779B97F4A7C15ull) ^ (server * 0xC2B2AE3D27D4EB4Full);
    for (unsigned i = (unsigned)(h >> 54), k = 0; k < NCONV; k++, i = (i + 1) & (NCONV - 1)) {
        Conv *c = &conv[i];
        if (c->used && c->client == client && c->server == server) return c;
        if (!c->used) { memset(c, 0, sizeof *c); c->used = 1; c->client = client; c->server = server; return c; }
    }
    exit(4);  // more than NCONV conversations: not this program's case
}

// The Device column (the PLC's address and port), built once per PLC seen last.
static uint64_t dev_key = ~0ull; static char dev_text[32]; static int dev_len;
static inline char *put_device(char *w, uint64_t server) {
    if (server != dev_key) {
        dev_key = server;
        char *d = dev_text;
        uint32_t ip = (uint32_t)(server >> 16);
        for (int i = 3; i >= 0; i--) { d = put_u64(d, (ip >> (8 * i)) & 0xFF); if (i) *d++ = '.'; }
        *d++ = ':'; d = put_u64(d, server & 0xFFFF);
        dev_len = (int)(d - dev_text);
    }
    memcpy(w, dev_text, 32);
    return w + dev_len;
}

// ---- rows -----------------------------------------------------------------------------------
static char ctr[48]; static int ctr_start = 31;
static uint64_t t0; static int have_t0;

static inline char *row_start(uint64_t micros) {
    if (o - obuf >= HIGH) flush_out();
    int i = 31;
    while (ctr[i] == '9') ctr[i--] = '0';
    ctr[i]++;
    if (i < ctr_start) ctr_start = i;
    char *w = o;
    memcpy(w, ctr + ctr_start, 16); w += 32 - ctr_start;
    *w++ = '\t';
    w = put_u64(w, micros / 1000);
    *w++ = '\t';
    return w;
}
static inline char *reg(char *w, uint32_t a) { *w++ = 'R'; return put_u64(w, a); }
// `R57=v R58=v ...` from `n` big-endian words; the first value's text is [*v0, *v1)
static inline char *reg_list(char *w, uint32_t addr, const unsigned char *d, int n, char **v0, char **v1) {
    for (int i = 0; i < n; i++) {
        if (i) *w++ = ' ';
        w = reg(w, addr + (uint32_t)i); *w++ = '=';
        if (!i) *v0 = w;
        w = put_i64(w, (int32_t)be32(d + 4 * i));
        if (!i) *v1 = w;
    }
    return w;
}
static inline char *copy24(char *w, const char *a, const char *b) {  // at most 24 bytes, loads first
    uint64_t x0, x1, x2; memcpy(&x0, a, 8); memcpy(&x1, a + 8, 8); memcpy(&x2, a + 16, 8);
    memcpy(w, &x0, 8); memcpy(w + 8, &x1, 8); memcpy(w + 16, &x2, 8);
    return w + (b - a);
}
static inline char *resp_ms(char *w, uint64_t us) {
    int64_t tenths = ((int64_t)us + 50) / 100;
    w = put_u64(w, (uint64_t)(tenths / 10)); *w++ = '.'; *w++ = (char)('0' + tenths % 10);
    return w;
}

static void datagram(const unsigned char *p, size_t n, uint64_t src, uint64_t dst, uint64_t micros, uint64_t t) {
    // Ether-S-Bus header: length(4) version protocol seq(2) attribute, telegram, CRC(2)
    if (n < 11 || be32(p) != n || p[4] > 1 || p[5] > 1 || p[8] > 2) {
        char *w = row_start(micros);  // not Ether-S-Bus: a Garbage row, as busnoop's (note shortened)
        w = PUTS(w, "\t\tGarbage\t\t\t"); w = put_hex_bytes(w, p, n); w = PUTS(w, "\t\t\t\tnot Ether-S-Bus\n");
        o = w; return;
    }
    unsigned at = p[8];
    uint16_t seq = be16(p + 6);
    const unsigned char *tg = p + 9;
    size_t tn = n - 11;
    int ok = crc16(p, n - 2) == be16(p + n - 2);
    // the PLC (server) is the destination of a request, the source of an answer
    uint64_t sv = at == 0 ? dst : src;
    Conv *c = at == 0 ? conv_get(src, dst) : conv_get(dst, src);
    char *w = row_start(micros);
    char *v0 = 0, *v1 = 0;
    const char *note = 0;
    if (!ok) {
        w = PUTS(w, "\t"); w = put_device(w, sv);
        w = PUTS(w, "\tBadCRC\t\t\t"); w = put_hex_bytes(w, tg, tn); *w++ = '\t';
        *w++ = '\t'; *w++ = '\t'; w = put_u64(w, seq); w = PUTS(w, "\tCRC error\n");
        o = w; return;
    }
    if (at == 0 && tn >= 2) {  // a request
        uint8_t stn = tg[0], cmd = tg[1];
        w = put_u64(w, stn); *w++ = '\t'; w = put_device(w, sv);
        w = PUTS(w, "\tRequest\t");
        if (cmd == 0x06 && tn == 5) {  // read registers: count-1, address
            uint32_t cnt = (uint32_t)tg[2] + 1, addr = be16(tg + 3);
            w = reg(w, addr); w = PUTS(w, "\tRead register(s)\t"); w = reg(w, addr);
            if (cnt > 1) { w = PUTS(w, ".."); w = reg(w, addr + cnt - 1); }
            *w++ = '\t';
            c->count = (uint8_t)cnt; c->addr = (uint16_t)addr;
        } else if (cmd == 0x0E && tn >= 5 && (tn - 5) % 4 == 0 && tg[2] == (tn - 5) + 1) {  // write registers
            uint32_t addr = be16(tg + 3);
            int cnt = (int)(tn - 5) / 4;
            w = reg(w, addr); w = PUTS(w, "\tWrite register(s)\t");
            w = reg_list(w, addr, tg + 5, cnt, &v0, &v1);
            *w++ = '\t';
            if (cnt) w = copy24(w, v0, v1);
            c->count = (uint8_t)cnt; c->addr = (uint16_t)addr;
        } else {  // other commands: generic (busnoop names and decodes them)
            w = PUTS(w, "\t\t"); w = put_hex_bytes(w, tg + 2, tn - 2); *w++ = '\t';
            c->count = 0; c->addr = 0;
        }
        if (c->have_seq && seq != (uint16_t)(c->last_seq + 1)) note = "sequence gap";
        c->have_seq = 1; c->last_seq = seq;
        c->open = 1; c->seq = seq; c->station = stn; c->cmd = cmd; c->t = t;
        w = PUTS(w, "\t\t"); w = put_u64(w, seq); *w++ = '\t';
    } else if (at != 0 && c->open && c->seq == seq) {  // an answer to the open request
        c->open = 0;
        w = put_u64(w, c->station); *w++ = '\t'; w = put_device(w, sv);
        const char *sensor = c->cmd == 0x06 ? "Read register(s)" : c->cmd == 0x0E ? "Write register(s)" : "";
        if (at == 1) {
            w = PUTS(w, "\tResponse\t"); w = reg(w, c->addr); *w++ = '\t';
            w = stpcpy(w, sensor); *w++ = '\t';
            if (c->cmd == 0x06 && tn == 4u * c->count) {
                w = reg_list(w, c->addr, tg, c->count, &v0, &v1); *w++ = '\t'; w = copy24(w, v0, v1);
            } else { w = put_hex_bytes(w, tg, tn); *w++ = '\t'; note = "length does not fit the request"; }
        } else {
            uint16_t code = tn == 2 ? be16(tg) : 0xFFFF;
            w = code == 0 ? PUTS(w, "\tACK\t") : PUTS(w, "\tNAK\t");
            w = reg(w, c->addr); *w++ = '\t'; w = stpcpy(w, sensor); *w++ = '\t';
            static const char *NAMES[] = {"ACK", "NAK, no reason specified", "NAK, because of password",
                                          "NAK, PGU port is in reduced protocol", "NAK, PGU port is already used"};
            w = stpcpy(w, code < 5 ? NAMES[code] : "NAK, unknown code");
            w = PUTS(w, " (0x");
            *w++ = HEXU[code >> 12]; *w++ = HEXU[(code >> 8) & 15]; *w++ = HEXU[(code >> 4) & 15]; *w++ = HEXU[code & 15];
            *w++ = ')'; *w++ = '\t';
        }
        *w++ = '\t'; w = resp_ms(w, t - c->t); *w++ = '\t'; w = put_u64(w, seq); *w++ = '\t';
    } else {  // an answer without its request
        *w++ = '\t'; w = put_device(w, sv);
        w = at == 1 ? PUTS(w, "\tResponse\t\t\t") : PUTS(w, "\tACK\t\t\t");
        w = put_hex_bytes(w, tg, tn); w = PUTS(w, "\t\t\t"); w = put_u64(w, seq); *w++ = '\t';
        note = "no request";
    }
    if (note) w = stpcpy(w, note);
    *w++ = '\n';
    o = w;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: ether_ref FILE.pcap\n"); return 2; }
    int fd = open(argv[1], O_RDONLY);
    if (fd < 0) { perror(argv[1]); return 3; }
    crc_init();
    memset(ctr, '0', sizeof ctr);
    o = PUTS(o, "Counter\tMillis\tID\tDevice\tType\tSensor #\tSensor\tData\tValue\tResp ms\tSeq\tNote\n");
    size_t have = 0, at = 0;
    int header = 1, nanos = 0;
    for (;;) {
        ssize_t r = read(fd, ibuf + have, RD);
        if (r < 0) return 3;
        have += (size_t)r;
        if (header) {
            if (have < 24) { if (r == 0) break; continue; }
            uint32_t magic; memcpy(&magic, ibuf, 4);
            if (magic == 0xA1B23C4D) nanos = 1;
            else if (magic != 0xA1B2C3D4) { fprintf(stderr, "not a little-endian pcap\n"); return 5; }
            uint32_t link; memcpy(&link, ibuf + 20, 4);
            if (link != 1) { fprintf(stderr, "link type %u: only Ethernet here\n", link); return 5; }
            header = 0; at = 24;
        }
        while (have - at >= 16) {
            const unsigned char *h = ibuf + at;
            uint32_t sec, frac, incl;
            memcpy(&sec, h, 4); memcpy(&frac, h + 4, 4); memcpy(&incl, h + 8, 4);
            if (incl > MAXREC) { fprintf(stderr, "record too long\n"); return 5; }
            if (have - at - 16 < incl) break;
            const unsigned char *d = h + 16;
            at += 16 + incl;
            uint64_t t = (uint64_t)sec * 1000000 + (nanos ? frac / 1000 : frac);
            if (!have_t0) { have_t0 = 1; t0 = t; }
            uint64_t micros = t - t0;
            // Ethernet II, IPv4 without options, not fragmented, UDP
            if (incl < 42 || be16(d + 12) != 0x0800 || d[14] != 0x45 || (be16(d + 20) & 0x3FFF) || d[23] != 17) continue;
            size_t total = be16(d + 16), ulen = be16(d + 38);
            if (total < 28 || 14 + total > incl || ulen < 8 || 34 + ulen > 14 + total) continue;
            uint16_t sp = be16(d + 34), dp = be16(d + 36);
            if (sp != 5050 && dp != 5050) continue;
            uint64_t src = (uint64_t)be32(d + 26) << 16 | sp, dst = (uint64_t)be32(d + 30) << 16 | dp;
            datagram(d + 42, ulen - 8, src, dst, micros, t);
        }
        memmove(ibuf, ibuf + at, have - at);
        have -= at; at = 0;
        if (r == 0) break;
    }
    flush_out();
    return 0;
}
