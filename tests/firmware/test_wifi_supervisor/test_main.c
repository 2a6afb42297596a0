/*
 * Unity tests of rw_wifi_supervisor, the board's WiFi connection policy: no call while the module's ready line
 * is busy, NO_MODULE after module_hung_ms of it; a loss closes the socket at once; connection steps wait for
 * the rope to be down (counted once); polls every status_poll_ms. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <unity.h>

#include "rw_wifi_supervisor.h"

static rw_wifi_supervisor s;

void setUp(void) {}

void tearDown(void) {}

static void start(rw_wifi_state state)
{
    rw_wifi_supervisor_config cfg;
    rw_wifi_supervisor_config_defaults(&cfg);
    rw_wifi_supervisor_init(&s, &cfg, state, 0u);
}

/* Passes every ms from t0 to t1; polls answered with connected; returns how often `wanted` was asked. */
static unsigned run(uint32_t t0, uint32_t t1, bool ready, bool rope_down, bool connected, rw_wifi_action wanted)
{
    unsigned n = 0u;
    for (uint32_t t = t0; t != t1; ++t) {
        rw_wifi_action a = rw_wifi_supervisor_step(&s, t, ready, rope_down);
        if (a == RW_WIFI_DO_POLL_STATUS) {
            rw_wifi_supervisor_status(&s, t, connected);
        } else if (a == RW_WIFI_DO_OPEN_SOCKET) {
            rw_wifi_supervisor_socket(&s, true);
        }
        n += a == wanted ? 1u : 0u;
    }
    return n;
}

static void test_polls_every_period(void)
{
    start(RW_WIFI_UP);
    TEST_ASSERT_EQUAL_UINT(4u, run(1u, 2001u, true, false, true, RW_WIFI_DO_POLL_STATUS));
    TEST_ASSERT_EQUAL(RW_WIFI_UP, s.state);
}

static void test_loss_in_flight_defers_the_reconnect(void)
{
    start(RW_WIFI_UP);
    TEST_ASSERT_EQUAL_UINT(0u, run(0u, 3100u, true, false, false, RW_WIFI_DO_START_CONNECT));
    TEST_ASSERT_EQUAL(RW_WIFI_CONNECTING, s.state);
    TEST_ASSERT_EQUAL_UINT32(1u, s.counters.losses);
    TEST_ASSERT_EQUAL_UINT32(1u, s.counters.deferred);
    TEST_ASSERT_EQUAL_UINT(1u, run(3100u, 3110u, true, true, false, RW_WIFI_DO_START_CONNECT));
}

static void test_association_in_flight_waits_for_the_rope(void)
{
    start(RW_WIFI_CONNECTING);
    TEST_ASSERT_EQUAL_UINT(0u, run(0u, 2100u, true, false, true, RW_WIFI_DO_OPEN_SOCKET));
    TEST_ASSERT_EQUAL_UINT(1u, run(2100u, 2102u, true, true, true, RW_WIFI_DO_OPEN_SOCKET));
    TEST_ASSERT_EQUAL(RW_WIFI_UP, s.state);
}

static void test_busy_line_then_no_module(void)
{
    start(RW_WIFI_UP);
    TEST_ASSERT_EQUAL_UINT(999u, run(0u, 999u, false, true, true, RW_WIFI_DO_NOTHING));
    TEST_ASSERT_EQUAL(RW_WIFI_UP, s.state);
    (void)run(999u, 1001u, false, true, true, RW_WIFI_DO_NOTHING);
    TEST_ASSERT_EQUAL(RW_WIFI_NO_MODULE, s.state);
    TEST_ASSERT_EQUAL_UINT32(1u, s.counters.module_hangs);
    TEST_ASSERT_EQUAL_UINT(0u, run(2000u, 12000u, true, true, true, RW_WIFI_DO_POLL_STATUS));
}

static void test_reconnect_interval(void)
{
    start(RW_WIFI_CONNECTING);
    TEST_ASSERT_EQUAL_UINT(2u, run(0u, 12001u, true, true, false, RW_WIFI_DO_START_CONNECT));
}

static void test_wraps_around(void)
{
    rw_wifi_supervisor_config cfg;
    rw_wifi_supervisor_config_defaults(&cfg);
    rw_wifi_supervisor_init(&s, &cfg, RW_WIFI_UP, 0xFFFFFFFFu - 700u);
    TEST_ASSERT_EQUAL_UINT(2u, run(0xFFFFFFFFu - 700u, 500u, true, true, true, RW_WIFI_DO_POLL_STATUS));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_polls_every_period);
    RUN_TEST(test_loss_in_flight_defers_the_reconnect);
    RUN_TEST(test_association_in_flight_waits_for_the_rope);
    RUN_TEST(test_busy_line_then_no_module);
    RUN_TEST(test_reconnect_interval);
    RUN_TEST(test_wraps_around);
    return UNITY_END();
}
