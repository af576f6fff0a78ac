/*
 * tribo_board: the board side of the bayestribo acquisition protocol, version 1.
 * See tribo_board.h for the interface and docs/protocol.md for the protocol.
 */
#include "tribo_board.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- encoding ---- */

/* CRC-32/ISO-HDLC (reflected 0xEDB88320, init and final XOR 0xFFFFFFFF), four bits
   at a time: a 64-byte table, fast enough for 100 kB/s on a small MCU. */
static const uint32_t crc_nibble[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
    0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
    0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu};

uint32_t tb_crc32(uint32_t crc, const uint8_t *p, size_t n)
{
    uint32_t c = ~crc;
    while (n--) {
        c ^= *p++;
        c = (c >> 4) ^ crc_nibble[c & 15u];
        c = (c >> 4) ^ crc_nibble[c & 15u];
    }
    return ~c;
}

void tb_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

void tb_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

/* The binary64 bits of a binary32 value (for compilers whose double is 32-bit). */
uint64_t tb_f64_bits_from_f32(uint32_t f)
{
    uint64_t sign = (uint64_t)(f >> 31) << 63;
    uint32_t exponent = (f >> 23) & 0xFFu;
    uint32_t mantissa = f & 0x7FFFFFu;
    int e;
    if (exponent == 0xFFu) /* infinity, NaN */
        return sign | ((uint64_t)0x7FF << 52) | ((uint64_t)mantissa << 29);
    if (exponent == 0) {
        if (mantissa == 0)
            return sign; /* ±0 */
        e = -126;        /* subnormal: normalise */
        while (!(mantissa & 0x800000u)) {
            mantissa <<= 1;
            e--;
        }
        mantissa &= 0x7FFFFFu;
        return sign | ((uint64_t)(e + 1023) << 52) | ((uint64_t)mantissa << 29);
    }
    e = (int)exponent - 127;
    return sign | ((uint64_t)(e + 1023) << 52) | ((uint64_t)mantissa << 29);
}

void tb_put_f64(uint8_t *p, double v)
{
    uint64_t bits;
    int k;
    if (sizeof(double) == 8) {
        memcpy(&bits, &v, 8); /* the value's own bits, not a struct layout */
    } else {
        float f = (float)v;
        uint32_t b32;
        memcpy(&b32, &f, 4);
        bits = tb_f64_bits_from_f32(b32);
    }
    for (k = 0; k < 8; k++)
        p[k] = (uint8_t)((bits >> (8 * k)) & 0xFFu);
}

/* ------------------------------------------------------------------ frames ---- */

static void emit(tb_board *b, const uint8_t *p, size_t n, uint32_t *crc)
{
    if (n == 0)
        return;
    *crc = tb_crc32(*crc, p, n);
    b->io.write(b->io.ctx, p, n);
}

static void frame_begin(tb_board *b, uint8_t type, uint32_t seq, uint16_t len, uint32_t *crc)
{
    uint8_t h[TB_PREFIX];
    h[0] = 0xA5;
    h[1] = 0x5A;
    h[2] = type;
    tb_put_u16(h + 3, len);
    tb_put_u32(h + 5, seq);
    *crc = tb_crc32(0, h + 2, TB_PREFIX - 2); /* type, length, sequence number */
    b->io.write(b->io.ctx, h, TB_PREFIX);
}

static void frame_end(tb_board *b, uint8_t type, uint32_t seq, uint32_t crc)
{
    uint8_t c[TB_CRC];
    tb_put_u32(c, crc);
    b->io.write(b->io.ctx, c, TB_CRC);
    if (b->io.frame_done)
        b->io.frame_done(b->io.ctx, type, seq);
}

static void send_frame(tb_board *b, uint8_t type, uint32_t seq, const uint8_t *p, size_t n)
{
    uint32_t crc;
    frame_begin(b, type, seq, (uint16_t)n, &crc);
    emit(b, p, n, &crc);
    frame_end(b, type, seq, crc);
}

static void send_text(tb_board *b, uint8_t type, const char *text)
{
    send_frame(b, type, 0, (const uint8_t *)text, strlen(text));
}

static void send_data(tb_board *b, const tb_frame *f, uint32_t seq)
{
    uint8_t chunk[64];
    size_t fill = 0;
    uint16_t k;
    uint32_t crc;
    frame_begin(b, TB_DATA, seq, (uint16_t)(4 + 4 * f->n), &crc);
    tb_put_u32(chunk, f->first);
    fill = 4;
    for (k = 0; k < f->n; k++) {
        tb_put_u16(chunk + fill, (uint16_t)f->s[k][0]); /* two's complement, little-endian */
        tb_put_u16(chunk + fill + 2, (uint16_t)f->s[k][1]);
        fill += 4;
        if (fill == sizeof chunk) {
            emit(b, chunk, fill, &crc);
            fill = 0;
        }
    }
    emit(b, chunk, fill, &crc);
    frame_end(b, TB_DATA, seq, crc);
}

size_t tb_header_payload(const tb_board *b, uint8_t *out, size_t size)
{
    size_t label = strlen(b->label);
    if (size < TB_HEADER_FIXED + label)
        return 0;
    out[0] = TB_PROTOCOL_VERSION;
    out[1] = TB_CHANNELS;
    tb_put_u16(out + 2, b->spf);
    tb_put_f64(out + 4, b->rate_hz);
    tb_put_f64(out + 12, b->disp_scale_m);
    tb_put_f64(out + 20, b->vel_scale_m_per_s);
    tb_put_f64(out + 28, b->disp_range_m);
    tb_put_f64(out + 36, b->vel_range_m_per_s);
    memcpy(out + TB_HEADER_FIXED, b->label, label);
    return TB_HEADER_FIXED + label;
}

static void send_header(tb_board *b, uint32_t seq)
{
    uint8_t payload[TB_HEADER_FIXED + TB_MAX_LABEL];
    size_t n = tb_header_payload(b, payload, sizeof payload);
    send_frame(b, TB_HEADER, seq, payload, n);
}

/* ------------------------------------------------------------- the run ---- */

static void critical(tb_board *b, int enter)
{
    if (b->io.critical)
        b->io.critical(b->io.ctx, enter);
}

static void hardware(void (*fn)(void *, int), void *ctx, int on)
{
    if (fn)
        fn(ctx, on);
}

static uint32_t samples_for(double seconds, double rate_hz)
{
    return (uint32_t)floor(seconds * rate_hz + 0.5);
}

/* End the run now (caller holds the critical section): the frame being filled is
   closed, shorter, and sent before END. */
static void end_run_locked(tb_board *b)
{
    if (b->filling) {
        b->count++;
        b->filling = 0;
    } else if (b->skipping) {
        b->lost_pending++;
        b->frames_lost++;
        b->skipping = 0;
    }
    b->end_pending = 1;
    hardware(b->io.sampling, b->io.ctx, 0);
    hardware(b->io.magnet, b->io.ctx, 0);
}

void tb_push_sample(tb_board *b, int16_t displacement, int16_t velocity)
{
    tb_frame *f;
    int full, ended;
    if (b->state == TB_IDLE || b->end_pending)
        return;
    f = &b->ring[(b->tail + b->count) % TB_NBUF];
    if (!b->filling && !b->skipping) {
        if (b->count < TB_NBUF) {
            f->first = b->index;
            f->n = 0;
            f->lost_before = b->lost_pending;
            b->lost_pending = 0;
            b->filling = 1;
        } else {
            /* Overrun: no free buffer. The frame is lost whole; its sequence number
               is still used, so the host sees exactly which samples are missing. */
            b->skipping = 1;
            b->skip_n = 0;
        }
    }
    if (b->filling) {
        f->s[f->n][0] = displacement;
        f->s[f->n][1] = velocity;
        f->n++;
        full = f->n >= b->spf;
    } else {
        b->skip_n++;
        full = b->skip_n >= b->spf;
    }
    b->index++;
    ended = b->index >= b->stop_index;
    if (full && !ended) {
        if (b->filling) {
            b->count++;
            b->filling = 0;
        } else {
            b->lost_pending++;
            b->frames_lost++;
            b->skipping = 0;
        }
    }
    if (ended)
        end_run_locked(b);
}

void tb_poll(tb_board *b)
{
    while (b->count > 0) {
        tb_frame *f = &b->ring[b->tail];
        size_t size = TB_PREFIX + 4 + 4 * (size_t)f->n + TB_CRC;
        if (b->io.tx_room && b->io.tx_room(b->io.ctx) < size)
            return; /* the link is busy: the frame waits in its buffer */
        b->seq += f->lost_before;
        send_data(b, f, b->seq++);
        critical(b, 1);
        b->tail = (uint8_t)((b->tail + 1) % TB_NBUF);
        b->count--;
        critical(b, 0);
    }
    if (b->end_pending && b->state != TB_IDLE) {
        uint8_t payload[8];
        critical(b, 1);
        b->seq += b->lost_pending;
        b->lost_pending = 0;
        critical(b, 0);
        /* END carries its own sequence number: the frames of the run before it. */
        tb_put_u32(payload, b->seq);
        tb_put_u32(payload + 4, b->index);
        send_frame(b, TB_END, b->seq, payload, sizeof payload);
        b->state = TB_IDLE;
        b->end_pending = 0;
    }
}

/* ------------------------------------------------------------- commands ---- */

/* A whole-string decimal number (strtod syntax, e.g. 20000, 0.5, 1e+06). */
static int parse_number(const char *text, double *out)
{
    char *end;
    double v;
    if (*text == '\0')
        return 0;
    v = strtod(text, &end);
    if (end == text || *end != '\0' || !(v == v) || v > 1e300 || v < -1e300)
        return 0;
    *out = v;
    return 1;
}

/* Bits per second a UART (8N1) needs for RATE and SPF. */
static double link_bits(double rate_hz, uint16_t spf)
{
    return rate_hz / spf * (TB_PREFIX + 4 + 4.0 * spf + TB_CRC) * 10.0;
}

static int fits_link(tb_board *b, double rate_hz, uint16_t spf)
{
    if (b->link_bps == 0 || link_bits(rate_hz, spf) <= 0.9 * b->link_bps)
        return 1;
    send_text(b, TB_ERROR, "RATE x SPF needs more than 90 % of the link's bit/s");
    return 0;
}

static int fits_index(tb_board *b, double rate_hz, double dur_s)
{
    /* The sample index is 32-bit: the longest pretrigger and DUR must fit. */
    if ((double)samples_for(TB_PRETRIGGER_LIMIT_S, rate_hz) + dur_s * rate_hz <= 4294967295.0)
        return 1;
    send_text(b, TB_ERROR, "DUR x RATE exceeds the 32-bit sample index");
    return 0;
}

static void start_run(tb_board *b)
{
    critical(b, 1);
    b->tail = b->count = b->filling = b->skipping = 0;
    b->lost_pending = 0;
    b->frames_lost = 0;
    b->end_pending = 0;
    b->index = 0;
    b->release_index = 0;
    b->stop_index = samples_for(TB_PRETRIGGER_LIMIT_S, b->rate_hz);
    b->state = TB_ARMED;
    critical(b, 0);
    send_header(b, 0); /* the run's first frame */
    b->seq = 1;
    hardware(b->io.magnet, b->io.ctx, 1);
    hardware(b->io.sampling, b->io.ctx, 1);
}

static void fire(tb_board *b)
{
    uint8_t payload[4];
    critical(b, 1);
    hardware(b->io.magnet, b->io.ctx, 0);
    b->release_index = b->index; /* the first sample taken after the release */
    b->stop_index = b->release_index + samples_for(b->dur_s, b->rate_hz);
    b->state = TB_RELEASED;
    if (b->stop_index <= b->index)
        end_run_locked(b);
    critical(b, 0);
    tb_put_u32(payload, b->release_index);
    send_frame(b, TB_RELEASE, b->seq++, payload, sizeof payload);
}

void tb_command(tb_board *b, const char *line)
{
    int running = b->state != TB_IDLE;
    double v;
    if (strcmp(line, "ID?") == 0) {
        send_text(b, TB_IDENT, b->ident);
    } else if (strcmp(line, "CFG?") == 0) {
        if (running)
            send_text(b, TB_ERROR, "busy: a run is in progress");
        else
            send_header(b, 0);
    } else if (strncmp(line, "RATE ", 5) == 0 || strncmp(line, "SPF ", 4) == 0 ||
               strncmp(line, "DUR ", 4) == 0) {
        const char *arg = strchr(line, ' ');
        while (*arg == ' ')
            arg++;
        if (running) {
            send_text(b, TB_ERROR, "busy: a run is in progress");
        } else if (!parse_number(arg, &v)) {
            send_text(b, TB_ERROR, "expected a decimal number");
        } else if (line[0] == 'R') {
            double actual = v;
            if (!(v >= 1.0 && v <= TB_MAX_RATE_HZ))
                send_text(b, TB_ERROR, "RATE out of range");
            else if (fits_link(b, v, b->spf) && fits_index(b, v, b->dur_s)) {
                if (b->io.set_rate && b->io.set_rate(b->io.ctx, v, &actual) != 0)
                    send_text(b, TB_ERROR, "RATE cannot be made by the sample clock");
                else {
                    b->rate_hz = actual;
                    send_text(b, TB_ACK, line);
                }
            }
        } else if (line[0] == 'S') {
            if (!(v >= 1 && v <= TB_MAX_SPF && v == floor(v)))
                send_text(b, TB_ERROR, "SPF out of range");
            else if (fits_link(b, b->rate_hz, (uint16_t)v)) {
                b->spf = (uint16_t)v;
                send_text(b, TB_ACK, line);
            }
        } else {
            if (!(v > 0 && v <= TB_MAX_DUR_S))
                send_text(b, TB_ERROR, "DUR out of range");
            else if (fits_index(b, b->rate_hz, v)) {
                b->dur_s = v;
                send_text(b, TB_ACK, line);
            }
        }
    } else if (strcmp(line, "ARM") == 0) {
        if (running)
            send_text(b, TB_ERROR, "busy: a run is in progress");
        else
            start_run(b);
    } else if (strcmp(line, "FIRE") == 0) {
        if (b->state == TB_ARMED && !b->end_pending)
            fire(b);
        else if (b->state == TB_RELEASED && !b->end_pending)
            send_text(b, TB_ERROR, "released already");
        else
            send_text(b, TB_ERROR, "no run: ARM first");
    } else if (strcmp(line, "STOP") == 0) {
        if (running && !b->end_pending) {
            critical(b, 1);
            end_run_locked(b);
            critical(b, 0);
        } else if (!running) {
            send_text(b, TB_ERROR, "no run");
        }
    } else {
        send_text(b, TB_ERROR, "unknown command");
    }
}

void tb_rx_byte(tb_board *b, uint8_t c)
{
    if (c != '\n') {
        if (b->line_len < TB_MAX_LINE + 1) /* room for a '\r' before the '\n' */
            b->line[b->line_len++] = (char)c;
        else
            b->line_overflow = 1;
        return;
    }
    {
        uint8_t n = b->line_len;
        char *start = b->line;
        int overflow = b->line_overflow;
        b->line_len = 0;
        b->line_overflow = 0;
        if (n > 0 && b->line[n - 1] == '\r')
            n--;
        if (overflow || n > TB_MAX_LINE) {
            send_text(b, TB_ERROR, "line too long");
            return;
        }
        b->line[n] = '\0';
        while (n > 0 && (b->line[n - 1] == ' ' || b->line[n - 1] == '\t'))
            b->line[--n] = '\0';
        while (*start == ' ' || *start == '\t')
            start++;
        if (*start != '\0') /* an empty line is ignored */
            tb_command(b, start);
    }
}

void tb_init(tb_board *b, const tb_io *io, const char *ident)
{
    memset(b, 0, sizeof *b);
    b->io = *io;
    b->rate_hz = TB_DEFAULT_RATE_HZ;
    b->spf = TB_DEFAULT_SPF <= TB_MAX_SPF ? TB_DEFAULT_SPF : TB_MAX_SPF;
    b->dur_s = TB_DEFAULT_DUR_S;
    b->disp_range_m = 2e-3;
    b->vel_range_m_per_s = 0.5;
    b->disp_scale_m = 2e-3 / 32767.0;
    b->vel_scale_m_per_s = 0.5 / 32767.0;
    strncpy(b->ident, ident ? ident : "", TB_MAX_IDENT);
    b->state = TB_IDLE;
    if (b->io.set_rate) {
        double actual = b->rate_hz;
        if (b->io.set_rate(b->io.ctx, b->rate_hz, &actual) == 0)
            b->rate_hz = actual;
    }
}
