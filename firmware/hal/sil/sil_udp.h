/* A UDP socket bound on 127.0.0.1 (the SIL talks to its host and its plant over loopback only). */
#ifndef SIL_UDP_H
#define SIL_UDP_H

#include <stdint.h>

/* Bind a datagram socket to 127.0.0.1:port (0 = any free port); *bound_port gets the port bound.
 * Returns the descriptor, or -1 (errno set). */
int sil_udp_bind_loopback(uint16_t port, uint16_t *bound_port);

#endif /* SIL_UDP_H */
