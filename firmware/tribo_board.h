/*
 * tribo_board: the board side of the bayestribo acquisition protocol, version 1
 * (docs/protocol.md), in portable C99 without dynamic memory.
 *
 * The library frames, checksums and sends (CRC-32/ISO-HDLC, packed little-endian
 * fields written byte by byte), parses the host's command lines and runs the state
 * machine of a run: ARM -> HEADER and DATA frames, FIRE -> RELEASE, END after DUR
 * seconds past the release, on STOP, or 10 s after ARM without FIRE.
 *
 * The hardware is behind a table of functions (tb_io): writing bytes, the magnet,
 * the sample clock. Three entry points drive it:
 *
 *   tb_rx_byte(board, byte)        every byte received from the host (main loop)
 *   tb_push_sample(board, d, v)    every sample pair, at the sample rate (may be the
 *                                  ADC interrupt; wrap tb_poll/tb_rx_byte in the
 *                                  critical-section hooks, see tb_io)
 *   tb_poll(board)                 often, from the main loop: sends the DATA frames
 *                                  that are complete and the END frame
 *
 * Memory: TB_NBUF frame buffers of TB_MAX_SPF sample pairs (4 bytes each). Both are
 * compile-time settings, e.g. -DTB_MAX_SPF=128 -DTB_NBUF=4 on a small board.
 */
#ifndef TRIBO_BOARD_H
#define TRIBO_BOARD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TB_PROTOCOL_VERSION 1
#define TB_CHANNELS 2

#ifndef TB_MAX_SPF
#define TB_MAX_SPF 1024 /* largest SPF this build accepts (the protocol's limit is 1024) */
#endif
#ifndef TB_NBUF
#define TB_NBUF 4 /* frame buffers between the sample clock and the link */
#endif
#ifndef TB_MAX_RATE_HZ
#define TB_MAX_RATE_HZ 100000.0 /* fastest sample rate this build accepts [Hz] */
#endif

#define TB_MAX_LINE 32           /* longest command line, without its line ending */
#define TB_MAX_LABEL 256         /* longest range label [bytes of UTF-8] */
#define TB_MAX_IDENT 64          /* longest IDENT text [bytes] */
#define TB_HEADER_FIXED 44       /* fixed part of a HEADER payload [bytes] */
#define TB_PREFIX 9              /* sync, type, length, sequence number [bytes] */
#define TB_CRC 4                 /* trailing CRC-32 [bytes] */
#define TB_MAX_DUR_S 86400.0     /* longest DUR [s] */
#define TB_PRETRIGGER_LIMIT_S 10.0 /* a run without FIRE ends this long after ARM [s] */

#define TB_DEFAULT_RATE_HZ 20000.0
#define TB_DEFAULT_SPF 128
#define TB_DEFAULT_DUR_S 10.0

/* Frame types. */
enum {
    TB_IDENT = 0x01,
    TB_HEADER = 0x02,
    TB_ACK = 0x03,
    TB_ERROR = 0x04,
    TB_DATA = 0x10,
    TB_RELEASE = 0x11,
    TB_END = 0x1F
};

/* Run states. */
enum { TB_IDLE = 0, TB_ARMED = 1, TB_RELEASED = 2 };

/* The hardware. Any function pointer but write may be NULL. */
typedef struct {
    void *ctx;
    /* Send bytes to the host (blocking is fine; the library never calls it from
       tb_push_sample). */
    void (*write)(void *ctx, const uint8_t *data, size_t n);
    /* Called after the last byte of every frame, with its type and sequence number
       (a USB stack may flush here; a test harness sees the frame boundaries). */
    void (*frame_done)(void *ctx, uint8_t type, uint32_t seq);
    /* Bytes the link takes now without blocking; DATA frames wait in their buffers
       until a whole one fits (NULL: always). */
    size_t (*tx_room)(void *ctx);
    /* Set the sample clock to rate_hz; store the rate actually obtained in *actual
       (it goes into the HEADER). Return 0, or nonzero if the rate cannot be made. */
    int (*set_rate)(void *ctx, double rate_hz, double *actual);
    void (*sampling)(void *ctx, int on); /* start (1) or stop (0) the sample clock */
    void (*magnet)(void *ctx, int on);   /* hold (1) or release (0) the pin */
    void (*critical)(void *ctx, int enter); /* disable (1) / restore (0) the sample interrupt */
} tb_io;

/* One DATA frame being filled or waiting to be sent. */
typedef struct {
    uint32_t first;       /* index of its first sample since ARM */
    uint32_t lost_before; /* frames lost to overrun just before it (sequence numbers) */
    uint16_t n;           /* sample pairs in it */
    int16_t s[TB_MAX_SPF][2];
} tb_frame;

typedef struct {
    tb_io io;
    /* Configuration (RATE, SPF, DUR, and what the board knows of the vibrometer). */
    double rate_hz;
    uint16_t spf;
    double dur_s;
    double disp_scale_m;       /* metres per displacement count */
    double vel_scale_m_per_s;  /* metres per second per velocity count */
    double disp_range_m;       /* ± displacement range of the vibrometer setting */
    double vel_range_m_per_s;  /* ± velocity range of the vibrometer setting */
    char label[TB_MAX_LABEL + 1];
    char ident[TB_MAX_IDENT + 1];
    uint32_t link_bps; /* bit/s of a UART link (8N1) to check RATE x SPF against; 0: USB */
    /* Run state. */
    volatile uint8_t state;
    volatile uint8_t end_pending;  /* the run has ended: send what is left, then END */
    uint32_t seq;                  /* next sequence number */
    volatile uint32_t index;       /* next sample index */
    uint32_t release_index;
    uint32_t stop_index;           /* the run ends when index reaches it */
    /* Frame ring: `count` complete frames from `tail`, then the one being filled. */
    tb_frame ring[TB_NBUF];
    volatile uint8_t tail, count, filling, skipping;
    uint16_t skip_n;
    volatile uint32_t lost_pending; /* frames lost since the last one stored */
    uint32_t frames_lost;           /* in this run (diagnostics) */
    /* Command line being received. */
    char line[TB_MAX_LINE + 1];
    uint8_t line_len;
    uint8_t line_overflow;
} tb_board;

/* CRC-32/ISO-HDLC (zlib): crc = tb_crc32(0, p, n) to start, then chain. */
uint32_t tb_crc32(uint32_t crc, const uint8_t *p, size_t n);

/* Little-endian encoders (byte by byte: no struct layout, no host endianness). */
void tb_put_u16(uint8_t *p, uint16_t v);
void tb_put_u32(uint8_t *p, uint32_t v);
void tb_put_f64(uint8_t *p, double v); /* IEEE 754 binary64, also where double is 32-bit */
uint64_t tb_f64_bits_from_f32(uint32_t f); /* binary64 bits of a binary32 value */

/* Defaults: RATE 20000 Hz, SPF 128, DUR 10 s, ranges ±2 mm and ±0.5 m/s over 32767
   counts, no label. Set the fields after tb_init to describe the real board. */
void tb_init(tb_board *b, const tb_io *io, const char *ident);

/* The fixed 44 bytes and the label of a HEADER payload; returns its length. */
size_t tb_header_payload(const tb_board *b, uint8_t *out, size_t size);

void tb_rx_byte(tb_board *b, uint8_t c);
void tb_push_sample(tb_board *b, int16_t displacement, int16_t velocity);
void tb_poll(tb_board *b);

/* Execute one command line (without its line ending), as tb_rx_byte does at '\n'. */
void tb_command(tb_board *b, const char *line);

#ifdef __cplusplus
}
#endif

#endif /* TRIBO_BOARD_H */
