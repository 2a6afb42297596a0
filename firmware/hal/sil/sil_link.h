/* SIL command link: the rw_hal_link over a UDP socket on 127.0.0.1, same frames as WiFi on the board.
 * Datagrams are read from the socket into a FIFO with their senders; the core takes one per tick.
 * The socket stands for the air between the host and the NINA module: datagrams pass only while `open`
 * (the modelled module is associated and its socket open, set each tick by sil_wifi_link.h); otherwise what
 * arrives is read (the lockstep barrier counts it) and lost, and what the core sends is lost (counted). */
#ifndef SIL_LINK_H
#define SIL_LINK_H

#include <netinet/in.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_hal_link.h"
#include "rw_protocol.h"

#define SIL_LINK_FIFO_LEN 32u
#define SIL_LINK_DATAGRAM_MAX 512u

typedef struct sil_datagram {
    uint8_t bytes[SIL_LINK_DATAGRAM_MAX];
    size_t len; /* real datagram length (may exceed SIL_LINK_DATAGRAM_MAX: then truncated) */
    struct sockaddr_in from;
} sil_datagram;

typedef struct sil_link {
    int fd;
    uint16_t port;
    sil_datagram fifo[SIL_LINK_FIFO_LEN];
    unsigned head;
    unsigned count;
    uint32_t received_total; /* datagrams read from the socket since start */
    uint32_t fifo_overflows;
    struct sockaddr_in last_from;
    bool has_last;
    struct sockaddr_in peer;
    bool has_peer;
    bool open;               /* datagrams pass (true from sil_link_open until the WiFi model says otherwise) */
    uint32_t delivered;      /* datagrams the core took */
    uint32_t sent;           /* datagrams the core sent that left */
    uint32_t lost_rx;        /* datagrams that arrived while the link was not open */
    uint32_t lost_tx;        /* datagrams the core sent while the link was not open */
} sil_link;

/* Bind 127.0.0.1:port (0 = any free port; the bound port is in link->port). false on error (errno set). */
bool sil_link_open(sil_link *link, uint16_t port);
void sil_link_close(sil_link *link);
/* Read every datagram waiting on the socket into the FIFO. */
void sil_link_poll(sil_link *link);
/* Lockstep barrier: wait (up to timeout_ms) until received_total >= frames; false on timeout. */
bool sil_link_wait_for(sil_link *link, uint32_t frames, int timeout_ms);
/* The rw_hal_link view of this link. */
rw_hal_link sil_link_hal(sil_link *link);

#endif /* SIL_LINK_H */
