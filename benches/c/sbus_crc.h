// busnoop's C reference decoders: what ether_ref.c and sbus_ref.c share for Saia S-Bus, big-endian
// reads and the CRC-16/XMODEM (slice-by-8 tables; crc_init() once before use).
// Same licence as busnoop (MIT OR Apache-2.0). Include after ref_io.h.
#ifndef SBUS_CRC_H
#define SBUS_CRC_H

static inline uint16_t be16(const unsigned char *p) { return (uint16_t)(p[0] << 8 | p[1]); }
static inline uint32_t be32(const unsigned char *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }

static uint16_t T[8][256];
static void crc_init(void) {
    for (int i = 0; i < 256; i++) {
        uint16_t c = (uint16_t)(i << 8);
        for (int k = 0; k < 8; k++) c = (uint16_t)(c & 0x8000 ? (c << 1) ^ 0x1021 : c << 1);
        T[0][i] = c;
    }
    for (int i = 0; i < 256; i++)
        for (int s = 1; s < 8; s++) T[s][i] = (uint16_t)((T[s - 1][i] << 8) ^ T[0][T[s - 1][i] >> 8]);
}
static inline uint16_t crc16(const unsigned char *p, size_t n) {
    uint16_t c = 0;
    while (n >= 8) {
        c = (uint16_t)(T[7][(c >> 8) ^ p[0]] ^ T[6][(c & 0xFF) ^ p[1]] ^ T[5][p[2]] ^ T[4][p[3]] ^
                       T[3][p[4]] ^ T[2][p[5]] ^ T[1][p[6]] ^ T[0][p[7]]);
        p += 8; n -= 8;
    }
    while (n--) c = (uint16_t)((c << 8) ^ T[0][(c >> 8) ^ *p++]);
    return c;
}

#endif
