#include "sil_serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

bool sil_serial_open(sil_serial *s)
{
    memset(s, 0, sizeof *s);
    rw_cobs_deframer_reset(&s->rx);
    s->fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (s->fd < 0 || grantpt(s->fd) != 0 || unlockpt(s->fd) != 0) {
        return false;
    }
    const char *name = ptsname(s->fd);
    if (name == NULL || strlen(name) >= sizeof s->path) {
        return false;
    }
    strcpy(s->path, name);
    /* raw bytes both ways, as a USB CDC port: no echo, no line discipline */
    int slave = open(s->path, O_RDWR | O_NOCTTY);
    if (slave >= 0) {
        struct termios t;
        if (tcgetattr(slave, &t) == 0) {
            cfmakeraw(&t);
            tcsetattr(slave, TCSANOW, &t);
        }
        close(slave);
    }
    int flags = fcntl(s->fd, F_GETFL, 0);
    fcntl(s->fd, F_SETFL, flags | O_NONBLOCK);
    return true;
}

void sil_serial_close(sil_serial *s)
{
    if (s->fd >= 0) {
        close(s->fd);
        s->fd = -1;
    }
}

/* Read bytes until one whole COBS frame is decoded into buf (returns its length) or none is waiting. */
static size_t hal_recv(void *ctx, uint8_t *buf, size_t cap)
{
    sil_serial *s = ctx;
    uint8_t byte;
    while (read(s->fd, &byte, 1) == 1) {
        const size_t len = rw_cobs_deframer_put(&s->rx, byte, buf, cap);
        if (len != 0u) {
            return len;
        }
    }
    return 0u;
}

static void write_all(int fd, const uint8_t *p, size_t n)
{
    while (n > 0u) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR) {
                continue;
            }
            return; /* buffer full (nobody reading) or nobody on the other end: dropped, as USB CDC drops */
        }
        p += w;
        n -= (size_t)w;
    }
}

static void hal_send(void *ctx, const uint8_t *frame, size_t len)
{
    sil_serial *s = ctx;
    uint8_t out[RW_COBS_MAX_ENCODED(RW_MAX_FRAME_LEN) + 1u];
    size_t n = rw_cobs_encode(frame, len, out, sizeof out - 1u);
    if (n == 0u) {
        return;
    }
    out[n++] = 0u;
    write_all(s->fd, out, n);
}

bool sil_serial_listening(const sil_serial *s)
{
    struct pollfd pfd = { .fd = s->fd, .events = POLLOUT, .revents = 0 };
    return poll(&pfd, 1, 0) >= 0 && (pfd.revents & (POLLHUP | POLLERR)) == 0; /* no other side open: HUP */
}

void sil_serial_note(sil_serial *s, const char *text)
{
    if (!sil_serial_listening(s)) {
        ++s->notes_dropped;
        return;
    }
    char line[200];
    const size_t n = strlen(text) < sizeof line - 6u ? strlen(text) : sizeof line - 6u;
    memcpy(line, "rw: ", 4u);
    memcpy(line + 4u, text, n);
    line[4u + n] = '\n';
    line[5u + n] = '\0';
    ++s->notes;
    write_all(s->fd, (const uint8_t *)line, n + 6u);
}

static void hal_accept_peer(void *ctx)
{
    (void)ctx; /* one cable, one peer */
}

rw_hal_link sil_serial_hal(sil_serial *s)
{
    rw_hal_link hal = { .ctx = s, .recv = hal_recv, .reply = hal_send, .accept_peer = hal_accept_peer, .send = hal_send };
    return hal;
}
