#include "sil_lockstep.h"

#include "rw_throttle_map.h"

#include <arpa/inet.h>
#include <errno.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "sil_udp.h"

bool sil_lockstep_open(sil_lockstep *ls, uint16_t port)
{
    memset(ls, 0, sizeof *ls);
    ls->fd = sil_udp_bind_loopback(port, &ls->port);
    if (ls->fd < 0) {
        return false;
    }
    ls->esc_pulse_us = 0u; /* no pulse until the core's first tick */
    ls->esc_pulse_third_us = 0u;
    return true;
}

void sil_lockstep_close(sil_lockstep *ls)
{
    if (ls->fd >= 0) {
        close(ls->fd);
        ls->fd = -1;
    }
}

int sil_lockstep_wait_sensors(sil_lockstep *ls, int timeout_ms)
{
    struct pollfd pfd = { .fd = ls->fd, .events = POLLIN, .revents = 0 };
    for (;;) {
        int r = poll(&pfd, 1, timeout_ms);
        if (r == 0) {
            return 0;
        }
        if (r < 0) {
            return -1;
        }
        uint8_t buf[RW_MAX_FRAME_LEN + 1u];
        struct sockaddr_in from;
        socklen_t alen = sizeof from;
        ssize_t n = recvfrom(ls->fd, buf, sizeof buf, 0, (struct sockaddr *)&from, &alen);
        if (n < 0) {
            return errno == EINTR ? -1 : 0;
        }
        rw_frame frame;
        if (rw_frame_decode(buf, (size_t)n, &frame) != RW_DECODE_OK || frame.msg_id != RW_MSG_ID_SIL_SENSORS) {
            ++ls->bad_datagrams;
            continue;
        }
        rw_msg_sil_sensors_unpack(&ls->sensors, frame.payload);
        ls->plant = from;
        ls->has_plant = true;
        return 1;
    }
}

void sil_lockstep_send_actuators(sil_lockstep *ls)
{
    if (!ls->has_plant) {
        return;
    }
    rw_msg_sil_actuators msg = {
        .time_us = ls->sensors.time_us, .esc_pulse_us = ls->esc_pulse_us, .esc_pulse_third_us = ls->esc_pulse_third_us, .spindle_moving_speed_raw = ls->spindle_moving_speed_raw,
    };
    uint8_t frame[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_sil_actuators_encode(&msg, ls->tx_seq++, frame, sizeof frame);
    sendto(ls->fd, frame, len, 0, (const struct sockaddr *)&ls->plant, sizeof ls->plant);
}

static rw_encoder_sample encoder_read(void *ctx)
{
    const sil_lockstep *ls = ctx;
    rw_encoder_sample s = { .counts = ls->sensors.encoder_counts, .last_edge_us = ls->sensors.encoder_last_edge_us };
    return s;
}

static uint16_t battery_read_mv(void *ctx)
{
    const sil_lockstep *ls = ctx;
    return ls->sensors.battery_mv;
}

static void esc_write_pulse_us(void *ctx, uint16_t pulse_us)
{
    sil_lockstep *ls = ctx;
    ls->esc_staged_third_us = (uint16_t)(3u * pulse_us);
}

static void esc_write_pulse_third_us(void *ctx, uint16_t pulse_third_us)
{
    sil_lockstep *ls = ctx;
    ls->esc_staged_third_us = pulse_third_us;
}

void sil_lockstep_apply_esc(sil_lockstep *ls)
{
    ls->esc_pulse_third_us = ls->esc_staged_third_us;
    ls->esc_pulse_us = rw_throttle_map_third_us_to_us(ls->esc_staged_third_us);
}

rw_hal_encoder sil_lockstep_encoder(sil_lockstep *ls)
{
    rw_hal_encoder hal = { .ctx = ls, .read = encoder_read };
    return hal;
}

rw_hal_battery sil_lockstep_battery(sil_lockstep *ls)
{
    rw_hal_battery hal = { .ctx = ls, .read_mv = battery_read_mv };
    return hal;
}

rw_hal_esc_output sil_lockstep_esc(sil_lockstep *ls)
{
    rw_hal_esc_output hal = { .ctx = ls, .write_pulse_us = esc_write_pulse_us, .write_pulse_third_us = esc_write_pulse_third_us };
    return hal;
}
