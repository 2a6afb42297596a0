#include "sil_link.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "sil_udp.h"

bool sil_link_open(sil_link *link, uint16_t port)
{
    memset(link, 0, sizeof *link);
    link->fd = sil_udp_bind_loopback(port, &link->port);
    if (link->fd < 0) {
        return false;
    }
    int flags = fcntl(link->fd, F_GETFL, 0);
    fcntl(link->fd, F_SETFL, flags | O_NONBLOCK);
    link->open = true;
    return true;
}

void sil_link_close(sil_link *link)
{
    if (link->fd >= 0) {
        close(link->fd);
        link->fd = -1;
    }
}

void sil_link_poll(sil_link *link)
{
    for (;;) {
        sil_datagram scratch;
        sil_datagram *d = link->count < SIL_LINK_FIFO_LEN
                              ? &link->fifo[(link->head + link->count) % SIL_LINK_FIFO_LEN]
                              : &scratch;
        socklen_t alen = sizeof d->from;
        ssize_t n = recvfrom(link->fd, d->bytes, sizeof d->bytes, MSG_TRUNC, (struct sockaddr *)&d->from, &alen);
        if (n < 0) {
            return; /* EAGAIN: nothing more */
        }
        d->len = (size_t)n;
        ++link->received_total;
        if (!link->open) {
            ++link->lost_rx; /* never reached the module */
        } else if (d == &scratch) {
            ++link->fifo_overflows; /* as a full WiFi buffer would: the datagram is lost */
        } else {
            ++link->count;
        }
    }
}

bool sil_link_wait_for(sil_link *link, uint32_t frames, int timeout_ms)
{
    int waited_ms = 0;
    sil_link_poll(link);
    while ((int32_t)(link->received_total - frames) < 0) {
        if (waited_ms >= timeout_ms) {
            return false;
        }
        struct pollfd pfd = { .fd = link->fd, .events = POLLIN, .revents = 0 };
        poll(&pfd, 1, 10);
        waited_ms += 10;
        sil_link_poll(link);
    }
    return true;
}

static size_t hal_recv(void *ctx, uint8_t *buf, size_t cap)
{
    sil_link *link = ctx;
    sil_link_poll(link);
    if (!link->open) {
        link->lost_rx += link->count; /* the module's socket closed with them */
        link->count = 0u;
        return 0u;
    }
    if (link->count == 0u) {
        return 0u;
    }
    sil_datagram *d = &link->fifo[link->head];
    link->head = (link->head + 1u) % SIL_LINK_FIFO_LEN;
    --link->count;
    link->last_from = d->from;
    link->has_last = true;
    ++link->delivered;
    if (d->len > cap) {
        memcpy(buf, d->bytes, cap);
        return cap + 1u;
    }
    memcpy(buf, d->bytes, d->len);
    return d->len;
}

static void hal_reply(void *ctx, const uint8_t *frame, size_t len)
{
    sil_link *link = ctx;
    if (!link->open) {
        ++link->lost_tx;
        return;
    }
    if (link->has_last) {
        ++link->sent;
        sendto(link->fd, frame, len, 0, (const struct sockaddr *)&link->last_from, sizeof link->last_from);
    }
}

static void hal_accept_peer(void *ctx)
{
    sil_link *link = ctx;
    if (link->has_last) {
        link->peer = link->last_from;
        link->has_peer = true;
    }
}

static void hal_send(void *ctx, const uint8_t *frame, size_t len)
{
    sil_link *link = ctx;
    if (!link->open) {
        ++link->lost_tx;
        return;
    }
    if (link->has_peer) {
        ++link->sent;
        sendto(link->fd, frame, len, 0, (const struct sockaddr *)&link->peer, sizeof link->peer);
    }
}

rw_hal_link sil_link_hal(sil_link *link)
{
    rw_hal_link hal = { .ctx = link, .recv = hal_recv, .reply = hal_reply, .accept_peer = hal_accept_peer, .send = hal_send };
    return hal;
}
