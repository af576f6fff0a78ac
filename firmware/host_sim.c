/*
 * host_sim: the tribo_board library on a PC, behind a pseudo-terminal.
 *
 * Opens a pty, prints the device path of its slave side on the first line of
 * standard output, and answers the host (bayestribo acquire --port PATH) exactly as a
 * board would: the library does the protocol, this file is the "hardware". The
 * sample clock is the wall clock (or as fast as the host reads, --unpaced); the
 * vibrometer is a synthetic damped oscillation, held at its start until FIRE.
 *
 *   host_sim [--unpaced] [--once] [--samples FILE] [--drop N] [--corrupt N]
 *            [--garbage N] [--stall-link N MS] [--link-bps BPS] [--selftest]
 *
 *   --unpaced      after the release, send as fast as the host reads (before it,
 *                   samples are always taken at the sample rate)
 *   --samples FILE  write every sample pair taken (int16 little-endian displacement,
 *                   velocity; pair k is sample index k) to FILE, lost frames included
 *   --drop N        do not send DATA frame N of a run (0 = first); repeatable
 *   --corrupt N     send DATA frame N with one payload byte flipped; repeatable
 *   --garbage N     send 64 bytes of garbage, with false sync pairs, before DATA frame N
 *   --stall-link N MS  after DATA frame N the link takes nothing while the board
 *                   takes MS milliseconds of samples (counted on its sample clock, so
 *                   a host_sim descheduled by a loaded machine stalls just as long):
 *                   frames wait in the board's buffers, then are lost whole (overrun)
 *   --once          exit after the first run's END has been read by the host
 *   --selftest      check the CRC and the binary64 encoding, print "selftest ok"
 *
 * Build: cc -std=c99 -O2 -o host_sim host_sim.c tribo_board.c -lm
 */
#define _DEFAULT_SOURCE 1
#define _XOPEN_SOURCE 600
#define _DARWIN_C_SOURCE 1

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "tribo_board.h"

#define MAX_FAULTS 16
#define PI 3.14159265358979323846

typedef struct {
    int master, slave;
    FILE *samples;
    uint8_t frame[TB_PREFIX + 4100 + TB_CRC + 64];
    size_t fill;
    long data_frames; /* DATA frames of the current run so far */
    long drop[MAX_FAULTS], corrupt[MAX_FAULTS], garbage[MAX_FAULTS];
    int n_drop, n_corrupt, n_garbage;
    uint32_t lcg;
    long stall_after; /* after this DATA frame, the link takes nothing for stall_s */
    double stall_s;
    uint32_t stall_until; /* sample index at which the stall ends */
    const tb_board *board;
    int sampling;
    int ended; /* an END frame was sent */
} harness;

static double now_s(void);

static int listed(const long *list, int n, long value)
{
    int k;
    for (k = 0; k < n; k++)
        if (list[k] == value)
            return 1;
    return 0;
}

static void write_all(int fd, const uint8_t *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR || errno == EAGAIN)
                continue;
            perror("host_sim: write");
            exit(2);
        }
        p += w;
        n -= (size_t)w;
    }
}

/* tb_io: bytes of a frame are gathered, then sent (or not) when the frame is done. */
static void io_write(void *ctx, const uint8_t *data, size_t n)
{
    harness *h = ctx;
    if (h->fill + n > sizeof h->frame) {
        fprintf(stderr, "host_sim: frame larger than its buffer\n");
        exit(2);
    }
    memcpy(h->frame + h->fill, data, n);
    h->fill += n;
}

static void io_frame_done(void *ctx, uint8_t type, uint32_t seq)
{
    harness *h = ctx;
    (void)seq;
    if (type == TB_HEADER && seq == 0)
        h->data_frames = 0;
    if (type == TB_DATA) {
        long number = h->data_frames++;
        if (listed(h->garbage, h->n_garbage, number)) {
            uint8_t junk[64];
            int k;
            for (k = 0; k < 64; k++) {
                h->lcg = h->lcg * 1103515245u + 12345u;
                junk[k] = (uint8_t)(h->lcg >> 16);
            }
            junk[0] = 0xA5; /* false sync pairs, one with a plausible DATA prefix */
            junk[1] = 0x5A;
            memcpy(junk + 5, "\xA5\x5A\x10\x00\x01\x07\x00", 7);
            write_all(h->master, junk, sizeof junk);
        }
        if (listed(h->drop, h->n_drop, number)) {
            h->fill = 0;
            return;
        }
        if (listed(h->corrupt, h->n_corrupt, number))
            h->frame[13] ^= 0xFF;
    }
    if (type == TB_END) {
        h->ended = 1;
        if (h->samples)
            fflush(h->samples); /* complete before the host can see the END */
    }
    write_all(h->master, h->frame, h->fill);
    h->fill = 0;
    if (type == TB_DATA && h->data_frames - 1 == h->stall_after)
        h->stall_until = h->board->index + (uint32_t)lrint(h->stall_s * h->board->rate_hz);
}

/* The link's room: none while a stall lasts (the frames wait, then overrun). The stall
   is measured in samples taken, not in wall time: a burst of samples after a
   scheduling delay falls inside it as the same samples would when paced. */
static size_t io_tx_room(void *ctx)
{
    harness *h = ctx;
    return h->board->index < h->stall_until ? 0 : (size_t)-1;
}

static void io_sampling(void *ctx, int on)
{
    ((harness *)ctx)->sampling = on;
}

/* ------------------------------------------------------------ the "rig" ---- */

/* Displacement and velocity counts of sample i: held at X0 until the release, then
   x = X0 e^(-zeta w t) cos(wd t) and v = dx/dt (velocity positive when the
   displacement increases, as the protocol requires). */
static void rig_sample(const tb_board *b, uint32_t i, int16_t *d, int16_t *v)
{
    const double x0 = 5e-4, f = 32.6, zeta = 0.02;
    double w = 2 * PI * f, wd = w * sqrt(1 - zeta * zeta), x = x0, xv = 0;
    if (b->state == TB_RELEASED && i >= b->release_index) {
        double t = (i - b->release_index) / b->rate_hz;
        double e = x0 * exp(-zeta * w * t);
        x = e * cos(wd * t);
        xv = e * (-zeta * w * cos(wd * t) - wd * sin(wd * t));
    }
    *d = (int16_t)lrint(x / b->disp_scale_m);
    *v = (int16_t)lrint(xv / b->vel_scale_m_per_s);
}

static void take_sample(harness *h, tb_board *b)
{
    int16_t d, v;
    uint8_t pair[4];
    rig_sample(b, b->index, &d, &v);
    if (h->samples) {
        tb_put_u16(pair, (uint16_t)d);
        tb_put_u16(pair + 2, (uint16_t)v);
        fwrite(pair, 1, 4, h->samples);
    }
    tb_push_sample(b, d, v);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Bytes written to the master that the host has not read yet. */
static int unread(const harness *h)
{
    int n = 0;
    if (ioctl(h->slave, FIONREAD, &n) < 0)
        return 0;
    return n;
}

/* ------------------------------------------------------------- self test ---- */

static int selftest(void)
{
    static const float values[] = {1.0f, -2.5f, 3.0517578e-05f, 1e-40f, 0.0f, -0.0f, 6.1e4f};
    uint8_t p[8];
    double back;
    uint64_t bits;
    size_t k;
    int ok = tb_crc32(0, (const uint8_t *)"123456789", 9) == 0xCBF43926u;
    ok = ok && tb_crc32(tb_crc32(0, (const uint8_t *)"1234", 4), (const uint8_t *)"56789", 5) ==
                   0xCBF43926u;
    for (k = 0; k < sizeof values / sizeof values[0]; k++) {
        uint32_t b32;
        double expected = (double)values[k];
        memcpy(&b32, &values[k], 4);
        bits = tb_f64_bits_from_f32(b32);
        memcpy(&back, &bits, 8);
        ok = ok && memcmp(&back, &expected, 8) == 0;
    }
    tb_put_f64(p, 20000.0);
    /* 20000.0 is 0x40D3880000000000 */
    ok = ok && p[7] == 0x40 && p[6] == 0xD3 && p[5] == 0x88 && p[0] == 0 && p[4] == 0;
    puts(ok ? "selftest ok" : "selftest FAILED");
    return ok ? 0 : 1;
}

/* ------------------------------------------------------------------ main ---- */

static long number_arg(int argc, char **argv, int *k)
{
    char *end;
    long v;
    if (*k + 1 >= argc) {
        fprintf(stderr, "host_sim: %s needs a number\n", argv[*k]);
        exit(2);
    }
    v = strtol(argv[++*k], &end, 10);
    if (*end != '\0' || v < 0) {
        fprintf(stderr, "host_sim: %s: expected a number >= 0, got %s\n", argv[*k - 1], argv[*k]);
        exit(2);
    }
    return v;
}

int main(int argc, char **argv)
{
    static harness h;
    static tb_board board;
    tb_io io;
    struct termios raw;
    int paced = 1, once = 0, k;
    uint32_t link_bps = 0;
    double t0 = 0;
    const char *slave_name;

    memset(&io, 0, sizeof io);
    h.lcg = 12345u;
    h.stall_after = -1;
    for (k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--selftest"))
            return selftest();
        else if (!strcmp(argv[k], "--unpaced"))
            paced = 0;
        else if (!strcmp(argv[k], "--once"))
            once = 1;
        else if (!strcmp(argv[k], "--samples") && k + 1 < argc) {
            h.samples = fopen(argv[++k], "wb");
            if (!h.samples) {
                perror(argv[k]);
                return 2;
            }
        } else if (!strcmp(argv[k], "--drop") && h.n_drop < MAX_FAULTS)
            h.drop[h.n_drop++] = number_arg(argc, argv, &k);
        else if (!strcmp(argv[k], "--corrupt") && h.n_corrupt < MAX_FAULTS)
            h.corrupt[h.n_corrupt++] = number_arg(argc, argv, &k);
        else if (!strcmp(argv[k], "--garbage") && h.n_garbage < MAX_FAULTS)
            h.garbage[h.n_garbage++] = number_arg(argc, argv, &k);
        else if (!strcmp(argv[k], "--stall-link")) {
            h.stall_after = number_arg(argc, argv, &k);
            h.stall_s = number_arg(argc, argv, &k) / 1000.0;
        } else if (!strcmp(argv[k], "--link-bps"))
            link_bps = (uint32_t)number_arg(argc, argv, &k);
        else {
            fprintf(stderr, "host_sim: unknown option %s\n", argv[k]);
            return 2;
        }
    }

    h.master = posix_openpt(O_RDWR | O_NOCTTY);
    if (h.master < 0 || grantpt(h.master) || unlockpt(h.master) || !(slave_name = ptsname(h.master))) {
        perror("host_sim: pty");
        return 2;
    }
    /* Hold the slave open, so the master never reads EIO between host connections. */
    h.slave = open(slave_name, O_RDWR | O_NOCTTY);
    if (h.slave < 0 || tcgetattr(h.slave, &raw)) {
        perror("host_sim: pty slave");
        return 2;
    }
    cfmakeraw(&raw);
    tcsetattr(h.slave, TCSANOW, &raw);

    io.ctx = &h;
    io.write = io_write;
    io.frame_done = io_frame_done;
    io.tx_room = io_tx_room;
    io.sampling = io_sampling;
    h.board = &board; /* before the library can ask for the link's room */
    tb_init(&board, &io, "bayestribo,host_sim,0001,tribo_board-1");
    strcpy(board.label, "host_sim: displacement +-2 mm, velocity +-0.5 m/s");
    board.link_bps = link_bps;

    printf("%s\n", slave_name);
    fflush(stdout);

    for (;;) {
        struct pollfd pfd;
        int timeout_ms = 50;
        uint32_t due = 0;
        pfd.fd = h.master;
        pfd.events = POLLIN;
        /* Paced before the release always (FIRE must come before the pretrigger
           limit); with --unpaced, as fast as the host reads after it. */
        int pace = paced || board.state == TB_ARMED;
        if (h.sampling) {
            if (!pace) {
                timeout_ms = 0;
            } else {
                double ahead = (board.index + 1) / board.rate_hz - (now_s() - t0);
                timeout_ms = ahead > 0 ? (int)(ahead * 1000) : 0;
            }
        }
        if (poll(&pfd, 1, timeout_ms) > 0 && (pfd.revents & POLLIN)) {
            uint8_t buf[256];
            ssize_t n = read(h.master, buf, sizeof buf);
            ssize_t j;
            for (j = 0; j < n; j++) {
                int was_idle = board.state == TB_IDLE;
                tb_rx_byte(&board, buf[j]);
                if (was_idle && board.state != TB_IDLE)
                    t0 = now_s(); /* ARM: sample 0 now */
            }
        }
        if (h.sampling) {
            if (pace) {
                double elapsed = now_s() - t0;
                double target = floor(elapsed * board.rate_hz);
                due = target > board.index ? (uint32_t)(target - board.index) : 0;
            } else {
                due = board.spf;
            }
            /* The main loop of a board sends while its sample interrupt fills the
               next buffer: here, a frame is sent as soon as it is complete, so a burst
               of samples after a scheduling delay overruns nothing. */
            while (due-- > 0 && h.sampling) {
                take_sample(&h, &board);
                if (board.count > 0)
                    tb_poll(&board);
            }
        }
        tb_poll(&board);
        if (once && h.ended && board.state == TB_IDLE) {
            /* Exit once the host has read everything (a pty drops unread bytes). */
            double start = now_s(), empty_since = -1;
            while (now_s() - start < 3.0) {
                if (unread(&h) > 0)
                    empty_since = -1;
                else if (empty_since < 0)
                    empty_since = now_s();
                else if (now_s() - empty_since > 0.1)
                    break;
                usleep(5000);
            }
            if (h.samples)
                fclose(h.samples);
            return 0;
        }
    }
}
