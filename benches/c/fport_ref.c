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
// busnoop detects). Not covered (busnoop has them): F.Port 2 / FBUS (fport2_ref.c), other
// S.Port frames and sensors, MSP requests, frames cut short, unusual escapes and ArduPilot's
// pad byte: these fall back to a generic row, so their cells differ from busnoop's, not their
// cost. The tables and the control and data cells are in fport_rows.h (shared with F.Port 2).
//
//   cc -O2 -march=x86-64-v2 -o fport_ref fport_ref.c
//   ./fport_ref FILE > out.tsv
//   "$BIN" fport FILE -f tsv --no-config | cmp - out.tsv
#include "ref_io.h"

static unsigned char ibuf[RD];

#include "ref_text.h"

#include "fport_rows.h"  // tables, Counter and Millis, garbage, checksum, control and data cells

// ---- rows ---------------------------------------------------------------------------------
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
        w = control_cells(w, f + 2);
    } else if ((ty == 0x01 || ty == 0x81) && len == 0x08 && f[2] == 0x00 && ty == 0x01 && !(f[3] | f[4] | f[5] | f[6] | f[7] | f[8])) {
        w = PUTS(w, "27\tFC\t\t\t\t\t\t\tDownlink\t");  // the poll
    } else if (ty == 0x81 && len == 0x08 && f[2] == 0x10) {
        w = PUTS(w, "27\tFC\t");
        w = data_cells(w, (unsigned)(f[3] | f[4] << 8), le32(f + 5));
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
