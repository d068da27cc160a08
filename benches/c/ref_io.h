// busnoop's C reference decoders (benches/c/*_ref.c, README here): what they all share — the
// includes, the read size, the output buffer with its flush, hex digits, and eight decimal
// digits at once. Same licence as busnoop (MIT OR Apache-2.0). A decoder that writes rows longer
// than 4 KiB past the 64 KiB mark defines OBUF_EXTRA before it includes this file.
#ifndef REF_IO_H
#define REF_IO_H
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define RD (256 * 1024)   // bytes a read asks for
#define HIGH (64 * 1024)  // the output is written out once it holds this much
#ifndef OBUF_EXTRA
#define OBUF_EXTRA 4096   // room for the row that crosses HIGH
#endif
static char obuf[HIGH + OBUF_EXTRA];
static char *o = obuf;

static void flush_out(void) {
    const char *p = obuf;
    size_t n = (size_t)(o - obuf);
    while (n) {
        ssize_t w = write(1, p, n);
        if (w <= 0) exit(3);
        p += w; n -= (size_t)w;
    }
    o = obuf;
}

static const char HEXU[] = "0123456789ABCDEF";

// The eight decimal digits of v < 10^8 (leading zeros included), the first digit in the lowest
// byte, all at once with multiplications (D. Lemire; busnoop's digits::eight_digits).
static inline uint64_t eight_digits(uint32_t v) {
    uint64_t merged = (uint64_t)(v / 10000) | (uint64_t)(v % 10000) << 32;
    uint64_t top = ((merged * 10486) >> 20) & (0x7Full << 32 | 0x7F);
    uint64_t bottom = merged - 100 * top;
    uint64_t hundreds = (bottom << 16) + top;
    uint64_t tens = ((hundreds * 103) >> 10) & (0xFull << 48 | 0xFull << 32 | 0xFull << 16 | 0xF);
    tens += (hundreds - 10 * tens) << 8;
    return tens;
}
#define ZEROS 0x3030303030303030ull

#endif
