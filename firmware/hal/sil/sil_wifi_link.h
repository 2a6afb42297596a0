/* The board's WiFi link in SIL: the NINA module model (sil_nina.h) driven through core/rw_wifi_supervisor.h as
 * the board's hal/arduino/arduino_link.cpp drives the real module, over the SIL's UDP socket (sil_link.h), which
 * stands for the air: datagrams pass only while the policy says UP and the modelled module is associated with its
 * socket open.
 *
 * As on the board:
 *  - boot (sil_wifi_link_boot_step, before the control tick starts; the ESCs hold the bottom pulse): the
 *    module reset and its ready line awaited at most RW_WIFI_BOOT_READY_MS (else NO_MODULE, without a call),
 *    its first status answer, WiFi.begin blocking at most RW_WIFI_BOOT_CONNECT_TIMEOUT_MS, then noLowPowerMode
 *    and udp.begin, each after the ready line within RW_WIFI_CALL_READY_WAIT_US;
 *  - the background loop (sil_wifi_link_service, one pass after each tick): one step of the policy, a
 *    status poll, a connection step only while the rope is down, closing the socket after a loss; every call
 *    only after the ready line says ready (a pass that finds it busy is counted), the waits between the calls
 *    of one step bounded by RW_WIFI_CALL_READY_WAIT_US (counted when they expire);
 *  - after a PROVISION_COMMIT that changed the credentials (rope down): the connection dropped and a new one
 *    started (sil_wifi_link_reconfigure).
 * The background loop's time is the plant's: a pass that waits (a slow module) delays the next passes, never
 * the tick. Not as on the board: the SIL's access point is the loopback network, joined whatever the SSID (also
 * none: NOT_PROVISIONED is not modelled); datagrams move between the socket and the core directly (the board's
 * one-per-pass queues and their WiFiNINA calls are not modelled). */
#ifndef SIL_WIFI_LINK_H
#define SIL_WIFI_LINK_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_config.h"
#include "rw_wifi_supervisor.h"
#include "sil_link.h"
#include "sil_nina.h"

typedef enum {
    SIL_WIFI_BOOT_START = 0,   /* the module not reset yet */
    SIL_WIFI_BOOT_WAIT_READY,  /* reset, its ready line awaited */
    SIL_WIFI_BOOT_JOINING,     /* WiFi.begin blocking until associated or its timeout */
    SIL_WIFI_BOOT_DONE,
} sil_wifi_boot_phase;

typedef struct sil_wifi_link_counters {
    uint32_t ready_waits_expired; /* bounded waits for the ready line that ran out (the step abandoned) */
    uint32_t passes;              /* background passes made */
    uint32_t passes_skipped;      /* ticks whose pass did not start: the previous one was still waiting */
    uint32_t max_pass_us;         /* longest pass (its calls and waits), us */
    uint32_t boot_ms;             /* how long the boot took (reset to the state reached), ms */
} sil_wifi_link_counters;

typedef struct sil_wifi_link {
    sil_nina nina;
    sil_link *air;
    char ssid[RW_CONFIG_SSID_LEN];
    char password[RW_CONFIG_PASSWORD_LEN];
    rw_wifi_supervisor supervisor;
    uint8_t boot_phase;           /* sil_wifi_boot_phase */
    uint64_t boot_start_us;
    uint64_t join_start_us;
    uint64_t busy_until_us;       /* the background loop is still in its previous pass until then */
    sil_wifi_link_counters counters;
} sil_wifi_link;

void sil_wifi_link_init(sil_wifi_link *link, const sil_nina_faults *faults, sil_link *air);
/* Every tick, first: the module's state at now_us (access point, associations) and whether datagrams pass. */
void sil_wifi_link_update(sil_wifi_link *link, uint64_t now_us);
/* One tick of the boot (before the control tick starts); true once it has reached a state (then the tick runs). */
bool sil_wifi_link_boot_step(sil_wifi_link *link, uint64_t now_us);
/* The credentials in use: the core's record after its first tick (no action). */
void sil_wifi_link_take_credentials(sil_wifi_link *link, const rw_config *config);
/* A PROVISION_COMMIT (rope down): the record's credentials; if they changed, a new connection at once. */
void sil_wifi_link_reconfigure(sil_wifi_link *link, uint64_t now_us, const rw_config *config);
/* The background pass after a tick. */
void sil_wifi_link_service(sil_wifi_link *link, uint64_t now_us, bool rope_down);

static inline uint8_t sil_wifi_link_state(const sil_wifi_link *link)
{
    return link->boot_phase == SIL_WIFI_BOOT_DONE ? link->supervisor.state : (uint8_t)RW_WIFI_CONNECTING;
}

#endif /* SIL_WIFI_LINK_H */
